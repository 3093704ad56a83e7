//! The second level over both trees: random placements (mirrored, non-uniformly scaled, one
//! placed twice at the same spot, so that ties happen) of two meshes, walked through the top
//! tree by [`placed`](super::placed), against asking every placement's mesh tree on its own and
//! keeping the closest by the tree's rule. The two must agree bit for bit: the top walk may
//! skip a placement only when it cannot hold the answer.

use std::sync::Arc;

use glam::Vec3;

use super::placed::{self, Placed, Placement};
use super::test_meshes::{icosphere, random_transform, subdivided_cube, MeshData};
use super::tree::{KeepAll, Rule, Tree};
use super::wide::WideBvh;
use super::{build, Bvh};
use crate::sampling::Rng;
use crate::simd::Baseline;

/// Two meshes of tree type `T` (each made by `tree` from its binary tree) placed eleven times
/// by `seed`'s random transforms, placement `i` reporting id `100 + i`; placement 10 is
/// placement 3 again.
fn scene<T: Tree>(seed: u64, tree: impl Fn(&MeshData, Bvh) -> T) -> Placed<T> {
    let data = [icosphere(1), subdivided_cube(2, glam::Mat3::IDENTITY)];
    let meshes: Vec<Arc<T>> = data
        .iter()
        .map(|m| {
            let corners = |i: usize| m.1[i].map(|v| Vec3::from(m.0[v as usize]));
            Arc::new(tree(m, build::build(m.1.len(), corners, None)))
        })
        .collect();
    let mut rng = Rng::new(seed, &[]);
    let mut placements: Vec<Placement> = (0..10)
        .map(|i| Placement {
            mesh: i % 2,
            id: 100 + i,
            transform: random_transform(&mut rng),
            alpha: None,
        })
        .collect();
    // The same mesh at the same place twice: every hit of one is a tie with the other's.
    placements.push(Placement {
        id: 110,
        ..placements[3].clone()
    });
    Placed::new(meshes, placements, None)
}

/// `bvh` as the wide tree of mesh `m`.
fn wide(m: &MeshData, bvh: Bvh) -> WideBvh {
    let corners = |i: usize| m.1[i].map(|v| Vec3::from(m.0[v as usize]));
    WideBvh::from_bvh(bvh, corners, |i| [0, i as u32])
}

/// Random rays from within ±5 in random directions.
fn rays(seed: u64, n: usize) -> Vec<(Vec3, Vec3)> {
    let mut rng = Rng::new(seed, &[1]);
    let mut f = |lo: f32, hi: f32| lo + (hi - lo) * rng.uniform();
    (0..n)
        .map(|_| {
            let o = Vec3::new(f(-5.0, 5.0), f(-5.0, 5.0), f(-5.0, 5.0));
            let target = Vec3::new(f(-3.0, 3.0), f(-3.0, 3.0), f(-3.0, 3.0));
            (o, target - o)
        })
        .collect()
}

/// Every placement asked on its own, the closest kept by the rule.
fn one_by_one<T: Tree>(s: &Placed<T>, (o, d): (Vec3, Vec3), range: (f32, f32)) -> Option<T::Hit> {
    let mut stack = T::Stack::default();
    let mut best: Option<T::Hit> = None;
    for index in 0..s.placements().len() as u32 {
        let e = s.entry(index);
        let map = e.object_from_world;
        let Some(ray) = T::prepare(map.transform_point3(o), map.transform_vector3(d)) else {
            continue;
        };
        let Some(h) = e
            .mesh
            .closest::<Baseline, KeepAll>(&ray, range, KeepAll, &mut stack)
        else {
            continue;
        };
        let h = T::placed(h, e.id, index);
        if best
            .as_ref()
            .is_none_or(|b| (T::t(&h), T::tie_key(&h)) < (T::t(b), T::tie_key(b)))
        {
            best = Some(h);
        }
    }
    best
}

/// Checks the walk's closest, any and every hit against [`one_by_one`] on `seed`'s scene.
fn check<T: Tree>(s: &Placed<T>, seed: u64) -> usize
where
    T::Hit: std::fmt::Debug,
{
    let mut stack = T::Stack::default();
    let mut hits = 0;
    for (i, ray) in rays(seed, 400).into_iter().enumerate() {
        let range = (0.0, if i % 3 == 0 { 0.5 } else { f32::INFINITY });
        let want = one_by_one(s, ray, range);
        let got = placed::closest::<_, Baseline>(s, ray, range, None, &mut stack);
        let key = |h: &Option<T::Hit>| h.as_ref().map(|h| (T::t(h).to_bits(), T::tie_key(h)));
        assert_eq!(
            key(&got),
            key(&want),
            "ray {i} {ray:?}: {got:?} vs {want:?}"
        );
        assert_eq!(
            placed::any::<_, Baseline>(s, ray, range, &mut stack),
            want.is_some(),
            "ray {i}"
        );
        let mut every = Vec::new();
        placed::each::<_, Baseline>(s, ray, range, &mut stack, &mut |h| every.push(h));
        let nearest = every
            .iter()
            .map(|h| (T::t(h), T::tie_key(h)))
            .min_by(|a, b| a.partial_cmp(b).unwrap());
        assert_eq!(
            nearest.map(|(t, k)| (t.to_bits(), k)),
            key(&want),
            "ray {i}: every hit"
        );
        hits += usize::from(want.is_some());
    }
    hits
}

#[test]
fn both_trees_find_what_each_placement_finds_alone() {
    for seed in 0..4 {
        let binary = scene(seed, |_, bvh| bvh);
        let wide = scene(seed, wide);
        assert_eq!(Bvh::RULE, Rule::Open);
        assert_eq!(WideBvh::RULE, Rule::Closed);
        let (a, b) = (check(&binary, seed), check(&wide, seed));
        // Most rays hit something, and the two trees agree on which do (up to a ray or two
        // through an edge: only the watertight test is sure to count those).
        assert!(
            a > 150 && a.abs_diff(b) <= 2,
            "seed {seed}: {a} and {b} hits"
        );
    }
}

#[test]
fn a_tie_between_placements_goes_to_the_smaller_key() {
    // Placements 3 and 10 are the same mesh at the same place: a ray that hits one hits the
    // other at the same `t`, and the answer is placement 3's.
    let s = scene(7, |_, bvh| bvh);
    let mut stack = ();
    let mut ties = 0;
    for ray in rays(11, 2000) {
        let Some(h) =
            placed::closest::<_, Baseline>(&s, ray, (0.0, f32::INFINITY), None, &mut stack)
        else {
            continue;
        };
        let mut at_t = Vec::new();
        placed::each::<_, Baseline>(&s, ray, (0.0, f32::INFINITY), &mut stack, &mut |e| {
            if e.t == h.t {
                at_t.push(e.instance)
            }
        });
        if at_t.contains(&Some(110)) {
            ties += 1;
            assert_eq!(h.instance, Some(103), "{ray:?}: {at_t:?}");
        }
    }
    assert!(ties > 0, "no ray met the doubled placement first");
}

/// The answers of `s` to `seed`'s rays: each closest hit's `t` and key, and whether any.
fn answers<T: Tree>(s: &Placed<T>, seed: u64) -> Vec<(Option<(u32, u64)>, bool)> {
    let mut stack = T::Stack::default();
    let range = (0.0, f32::INFINITY);
    (rays(seed, 300).into_iter())
        .map(|ray| {
            let hit = placed::closest::<_, Baseline>(s, ray, range, None, &mut stack);
            let any = placed::any::<_, Baseline>(s, ray, range, &mut stack);
            (hit.map(|h| (T::t(&h).to_bits(), T::tie_key(&h))), any)
        })
        .collect()
}

/// Moves random placements of `s` to random transforms, one after another, checking after
/// each move that the walk still finds what each placement finds alone, and at the end that
/// it answers as the same placements placed afresh.
fn moved_as_fresh<T: Tree>(mut s: Placed<T>, seed: u64)
where
    T::Hit: std::fmt::Debug,
{
    let mut rng = Rng::new(seed, &[2]);
    for step in 0..6 {
        let index = (rng.uniform() * s.placements().len() as f32) as usize;
        s.set_transforms(&[(index, random_transform(&mut rng))], None);
        check(&s, seed + step);
    }
    let meshes = s.meshes().to_vec();
    let fresh = Placed::new(meshes, s.placements().to_vec(), None);
    assert_eq!(answers(&s, seed), answers(&fresh, seed));
}

#[test]
fn moved_placements_answer_as_placed_afresh() {
    for seed in 0..3 {
        moved_as_fresh(scene(seed, |_, bvh| bvh), seed);
        moved_as_fresh(scene(seed, wide), seed);
    }
}
