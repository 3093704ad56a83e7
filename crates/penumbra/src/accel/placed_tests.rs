//! The second level over both trees: random placements (mirrored, non-uniformly scaled, one
//! placed twice at the same spot, so that ties happen) of two meshes, walked through the top
//! tree by [`placed`](super::placed), against asking every placement's mesh tree on its own and
//! keeping the closest by the tree's rule. The two must agree bit for bit: the top walk may
//! skip a placement only when it cannot hold the answer.

use glam::Vec3;

use super::instances::{inverse, world_box};
use super::placed::{self, Entry, Placements};
use super::test_meshes::{icosphere, random_transform, subdivided_cube, MeshData};
use super::tree::{Rule, Tree};
use super::wide::WideBvh;
use super::{build, Bvh, BvhNode};
use crate::math::Transform;
use crate::sampling::Rng;
use crate::simd::Baseline;

/// Meshes of tree type `T` placed by `placements` (mesh, object-to-world map) under a top tree.
struct Scene<T> {
    meshes: Vec<T>,
    placements: Vec<(usize, glam::Affine3A)>,
    top: (Vec<BvhNode>, Vec<u32>),
}

impl<T: Tree> Placements for Scene<T> {
    type Tree = T;

    fn top(&self) -> (&[BvhNode], &[u32]) {
        (&self.top.0, &self.top.1)
    }

    fn entry(&self, index: u32) -> Entry<'_, T> {
        let (mesh, map) = &self.placements[index as usize];
        Entry {
            object_from_world: map,
            mesh: &self.meshes[*mesh],
            id: 100 + index,
            filter: None,
            border: None,
        }
    }
}

/// The scene of `seed` with each mesh's tree made by `tree`.
fn scene<T>(seed: u64, tree: impl Fn(&MeshData, Bvh) -> T, bvh: impl Fn(&T) -> &Bvh) -> Scene<T> {
    let data = [icosphere(1), subdivided_cube(2, glam::Mat3::IDENTITY)];
    let meshes: Vec<T> = data
        .iter()
        .map(|m| {
            let corners = |i: usize| m.1[i].map(|v| Vec3::from(m.0[v as usize]));
            tree(m, build::build(m.1.len(), corners, None))
        })
        .collect();
    let mut rng = Rng::new(seed, &[]);
    let mut transforms: Vec<(usize, Transform)> = (0..10)
        .map(|i| (i % 2, random_transform(&mut rng)))
        .collect();
    // The same mesh at the same place twice: every hit of one is a tie with the other's.
    transforms.push(transforms[3]);
    let boxes: Vec<_> = transforms
        .iter()
        .map(|(m, t)| world_box(bvh(&meshes[*m]), t))
        .collect();
    Scene {
        top: build::build_tree(boxes.len(), |i| boxes[i], None),
        placements: transforms.iter().map(|(m, t)| (*m, inverse(t))).collect(),
        meshes,
    }
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
fn one_by_one<T: Tree>(s: &Scene<T>, (o, d): (Vec3, Vec3), range: (f32, f32)) -> Option<T::Hit> {
    let mut stack = T::Stack::default();
    let mut best: Option<T::Hit> = None;
    for index in 0..s.placements.len() as u32 {
        let e = s.entry(index);
        let map = e.object_from_world;
        let Some(ray) = T::prepare(map.transform_point3(o), map.transform_vector3(d)) else {
            continue;
        };
        let Some(h) = e.mesh.closest::<Baseline>(&ray, range, None, &mut stack) else {
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
fn check<T: Tree>(s: &Scene<T>, seed: u64) -> usize
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
        let binary = scene(seed, |_, bvh| bvh, |b| b);
        let wide = scene(
            seed,
            |m, bvh| {
                let corners = |i: usize| m.1[i].map(|v| Vec3::from(m.0[v as usize]));
                WideBvh::from_bvh(bvh, corners, |i| [0, i as u32])
            },
            WideBvh::bvh,
        );
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
    let s = scene(7, |_, bvh| bvh, |b| b);
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
