//! Tests of the BVH against the brute-force references [`intersect_brute_force`] and
//! [`occluded_brute_force`]: the shared helpers, and unit tests of the structure (node layout,
//! validation, depth cap, serial against parallel build) and of the queries on empty scenes and
//! batches. Edge cases of the geometry are in `edges`, property tests over random scenes in
//! `props`, and the reference build every build must agree with in `reference`.

use super::*;
use crate::geometry::Mesh;
use crate::math::Transform;
use crate::simd::supported_paths;

mod edges;
mod props;
mod reference;
mod verdict;

use verdict::Verdict;

/// The `t_max` of shadow segments: short of the end point, so a surface there is not a blocker.
const T_MAX: f32 = 1.0 - 1e-4;

#[test]
fn node_is_32_bytes() {
    assert_eq!(std::mem::size_of::<BvhNode>(), 32);
    assert_eq!(std::mem::align_of::<BvhNode>(), 32);
}

/// One single-triangle mesh per entry, so triangle `i` of the geometry is `tris[i]`.
fn soup(tris: &[[[f32; 3]; 3]]) -> Geometry {
    let mut g = Geometry::default();
    for t in tris {
        let mesh = Mesh {
            positions: t.iter().map(|&p| Vec3::from(p)).collect(),
            indices: vec![[0, 1, 2]],
            ..Mesh::default()
        };
        g.append(&mesh, &Transform::IDENTITY, &[0], 0);
    }
    g
}

/// The two triangles of the parallelogram `corner + a·u + b·v`, `a, b ∈ [0, 1]`.
fn parallelogram(corner: Vec3, u: Vec3, v: Vec3) -> [[[f32; 3]; 3]; 2] {
    let [p, pu, pv, puv] = [corner, corner + u, corner + v, corner + u + v].map(<[f32; 3]>::from);
    [[p, pu, puv], [p, puv, pv]]
}

fn pool() -> &'static rayon::ThreadPool {
    crate::pool::test_pool()
}

/// Builds serially and on a pool, validates both, checks they are the reference build's tree,
/// and returns it.
fn build_checked(g: &Geometry) -> Bvh {
    let bvh = Bvh::build(g);
    bvh.validate(g)
        .unwrap_or_else(|e| panic!("serial build: {e}"));
    let parallel = Bvh::build_parallel(g, pool());
    parallel
        .validate(g)
        .unwrap_or_else(|e| panic!("parallel build: {e}"));
    assert_same_tree(&bvh, &parallel);
    assert_same_tree(&bvh, &reference::reference_build(g));
    bvh
}

fn assert_same_tree(a: &Bvh, b: &Bvh) {
    assert_eq!(a.nodes, b.nodes);
    assert_eq!(a.prim_ids, b.prim_ids);
    assert_eq!(a.tris, b.tris);
}

fn assert_agree(g: &Geometry, bvh: &Bvh, ray: &Ray) {
    assert_agree_in(g, bvh, ray, 1e-4, f32::INFINITY);
}

/// Closest hit and occlusion over `(t_min, t_max)` agree with brute force: the same hit (on an
/// exact tie, the triangle with the smallest index), the reported barycentrics are the hit
/// triangle's own, and nothing blocks the ray strictly before its closest hit.
fn assert_agree_in(g: &Geometry, bvh: &Bvh, ray: &Ray, t_min: f32, t_max: f32) {
    let a = bvh.intersect(ray, t_min, t_max);
    let b = intersect_brute_force(g, ray, t_min, t_max);
    match (a, b) {
        (None, None) => {}
        (Some(a), Some(b)) => {
            assert_eq!(a, b, "closest hit differs for {ray:?}");
            let tri = accel(g.corners(a.triangle as usize));
            let own = tri
                .hit(ray, t_min, t_max)
                .expect("the reported triangle is hit");
            assert_eq!((a.t, a.b1, a.b2), (own.t, own.b1, own.b2));
        }
        (a, b) => panic!("bvh {a:?} vs brute force {b:?} for {ray:?} in ({t_min}, {t_max})"),
    }
    let occluded = occluded_brute_force(g, ray, t_min, t_max);
    assert_eq!(occluded, b.is_some(), "the two references disagree");
    assert_eq!(
        bvh.occluded(ray, t_min, t_max),
        occluded,
        "occluded({ray:?})"
    );
    if let Some(b) = b {
        assert!(!bvh.occluded(ray, t_min, b.t));
    }
}

/// [`Bvh::intersect_from`] on every SIMD path gives each ray's brute-force closest hit.
fn assert_from_agrees(
    g: &Geometry,
    bvh: &Bvh,
    origin: Vec3,
    dirs: &[Vec3],
    t_min: f32,
    t_max: f32,
) {
    let expected: Vec<Option<Hit>> = dirs
        .iter()
        .map(|&d| intersect_brute_force(g, &Ray::new(origin, d), t_min, t_max))
        .collect();
    for path in supported_paths() {
        // Stale contents must be overwritten, misses included.
        let stale = Hit {
            t: -1.0,
            b1: 0.5,
            b2: 0.5,
            triangle: 7,
            instance: None,
        };
        let mut hits = vec![Some(stale); dirs.len()];
        bvh.intersect_from_on(path, origin, dirs, t_min, t_max, &mut hits);
        for (i, (hit, want)) in hits.iter().zip(&expected).enumerate() {
            assert_eq!(
                hit, want,
                "{path:?}: ray {i} from {origin} along {}",
                dirs[i]
            );
        }
    }
}

/// The coordinates of `points`, by axis.
fn by_axis(points: &[Vec3]) -> [Vec<f32>; 3] {
    [0, 1, 2].map(|a| points.iter().map(|p| p[a]).collect())
}

/// The segments from `o` to `e`, given by axis.
fn segments<'a>(o: &'a [Vec<f32>; 3], e: &'a [Vec<f32>; 3]) -> Segments<'a> {
    Segments {
        origin: [0, 1, 2].map(|a| &o[a][..]),
        end: [0, 1, 2].map(|a| &e[a][..]),
    }
}

/// [`Bvh::occluded`] on the segment from `from` to `to`, checked against brute force's
/// [`Verdict`].
fn occluded_as_verdict_allows(g: &Geometry, bvh: &Bvh, from: Vec3, to: Vec3, t_max: f32) -> bool {
    let ray = Ray::new(from, to - from);
    let occluded = bvh.occluded(&ray, 0.0, t_max);
    let verdict = Verdict::of(g, &ray, 0.0, t_max);
    assert!(
        verdict.admits(occluded),
        "{ray:?}: {occluded}, brute force {verdict:?}"
    );
    occluded
}

/// `occluded_from` gives [`Bvh::occluded`]'s answer for every segment, overwriting the mask;
/// `occlude_from` on every SIMD path this machine supports leaves blocked segments blocked and
/// blocks exactly the others that [`Bvh::occluded`] finds occluded (packets of every fill, with
/// some lanes blocked from the start); so do `occlude_segments` on the same segments and on
/// them reversed, and `occlude_pairs` from the origin to the ends and from the ends to a few
/// points. [`Bvh::occluded`] itself agrees with brute force's [`Verdict`].
fn assert_segments_agree(g: &Geometry, bvh: &Bvh, origin: Vec3, ends: &[Vec3], t_max: f32) {
    let occluded = |from: Vec3, to: Vec3| occluded_as_verdict_allows(g, bvh, from, to, t_max);
    let expected: Vec<bool> = ends.iter().map(|&end| occluded(origin, end)).collect();
    // The same segments reversed: origins of their own, one shared end.
    let reversed: Vec<bool> = ends.iter().map(|&end| occluded(end, origin)).collect();
    let shared = vec![origin; ends.len()];
    let mut mask: Vec<bool> = (0..ends.len()).map(|i| i % 2 == 0).collect();
    bvh.occluded_from(origin, ends, t_max, &mut mask);
    assert_eq!(mask, expected, "occluded_from from {origin}");
    for path in supported_paths() {
        for pre_blocked in [0, 3, 7] {
            // Every `pre_blocked`-th segment starts blocked (none for 0).
            let start: Vec<bool> = (0..ends.len())
                .map(|i| pre_blocked != 0 && i % pre_blocked == 1)
                .collect();
            let mut blocked = start.clone();
            bvh.occlude_from_on(path, origin, ends, t_max, &mut blocked);
            let (mut forward, mut backward) = (start.clone(), start.clone());
            let (from, to) = (by_axis(&shared), by_axis(ends));
            bvh.occlude_segments_on(path, segments(&from, &to), t_max, &mut forward);
            bvh.occlude_segments_on(path, segments(&to, &from), t_max, &mut backward);
            for i in 0..ends.len() {
                let why = format!(
                    "{path:?}: segment {origin} → {} (blocked from the start: {})",
                    ends[i], start[i]
                );
                assert_eq!(blocked[i], start[i] || expected[i], "{why}");
                assert_eq!(forward[i], start[i] || expected[i], "segments, {why}");
                assert_eq!(backward[i], start[i] || reversed[i], "reversed, {why}");
            }
        }
    }
    if let (Some(&first), Some(&last)) = (ends.first(), ends.last()) {
        assert_pairs_agree(g, bvh, &[origin], ends, t_max);
        assert_pairs_agree(g, bvh, ends, &[origin, first, last], t_max);
    }
}

/// `occlude_pairs` on every SIMD path leaves blocked pairs blocked and blocks the others
/// exactly as [`Bvh::occluded`] does, with a shaft (from [`SHAFT_MIN_ENDS`] ends), with walks
/// from the subtrees a shaft meets (from `shaft::ROOTS_MIN_ENDS`), or from the tree's root;
/// [`Bvh::occluded`] agrees with brute force's [`Verdict`].
fn assert_pairs_agree(g: &Geometry, bvh: &Bvh, origins: &[Vec3], ends: &[Vec3], t_max: f32) {
    let (from, to) = (by_axis(origins), by_axis(ends));
    let pairs = Pairs {
        origins: from.each_ref().map(|axis| &axis[..]),
        ends: to.each_ref().map(|axis| &axis[..]),
    };
    let m = origins.len();
    let pair = |k: usize| (origins[k % m], ends[k / m]);
    let expected: Vec<bool> = (0..m * ends.len())
        .map(|k| {
            let (o, e) = pair(k);
            occluded_as_verdict_allows(g, bvh, o, e, t_max)
        })
        .collect();
    for path in supported_paths() {
        let start: Vec<bool> = (0..m * ends.len()).map(|k| k % 5 == 3).collect();
        let mut blocked = start.clone();
        bvh.occlude_pairs_on(path, pairs, t_max, &mut blocked);
        for (k, &b) in blocked.iter().enumerate() {
            assert_eq!(b, start[k] || expected[k], "{path:?}: pair {:?}", pair(k));
        }
    }
}

#[test]
fn empty_and_single_triangle() {
    let g = Geometry::default();
    let bvh = Bvh::build(&g);
    bvh.validate(&g).unwrap();
    let ray = Ray::new(Vec3::ZERO, Vec3::Z);
    assert!(bvh.intersect(&ray, 0.0, f32::INFINITY).is_none());
    assert!(!bvh.occluded(&ray, 0.0, f32::INFINITY));

    let g = soup(&[[[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]]]);
    let bvh = Bvh::build(&g);
    bvh.validate(&g).unwrap();
    let hit = bvh
        .intersect(&Ray::new(Vec3::new(0.2, 0.2, 0.0), Vec3::Z), 0.0, 9.0)
        .unwrap();
    assert_eq!((hit.t, hit.triangle), (1.0, 0));
}

#[test]
fn empty_scene_misses_everything() {
    let g = Geometry::default();
    let bvh = build_checked(&g);
    assert_eq!(bvh.node_count(), 0);
    let rays = [
        Ray::new(Vec3::ZERO, Vec3::Z),
        Ray::new(Vec3::ONE, -Vec3::ONE),
    ];
    for ray in &rays {
        assert_agree_in(&g, &bvh, ray, 0.0, f32::INFINITY);
    }
    let stale = Hit {
        t: 1.0,
        b1: 0.0,
        b2: 0.0,
        triangle: 7,
        instance: None,
    };
    let mut hits = [Some(stale); 2];
    bvh.intersect_batch(&rays, 0.0, f32::INFINITY, &mut hits);
    assert_eq!(hits, [None, None]);
    let mut mask = [true; 3];
    bvh.occluded_from(
        Vec3::ZERO,
        &[Vec3::X, Vec3::Y, Vec3::ZERO],
        T_MAX,
        &mut mask,
    );
    assert_eq!(mask, [false; 3]);
    bvh.intersect_batch(&[], 0.0, f32::INFINITY, &mut []);
    bvh.occluded_from(Vec3::ZERO, &[], T_MAX, &mut []);
}

#[test]
fn empty_batches_are_no_ops() {
    let g = soup(&parallelogram(
        Vec3::new(-1.0, -1.0, 1.0),
        2.0 * Vec3::X,
        2.0 * Vec3::Y,
    ));
    let bvh = build_checked(&g);
    bvh.intersect_batch(&[], 1e-4, f32::INFINITY, &mut []);
    bvh.occluded_from(Vec3::ZERO, &[], T_MAX, &mut []);
    // The same scene does block a segment, so the empty answers are not for want of geometry.
    let mut mask = [false];
    bvh.occluded_from(Vec3::ZERO, &[2.0 * Vec3::Z], T_MAX, &mut mask);
    assert_eq!(mask, [true]);
}

#[test]
#[should_panic(expected = "one hit slot per ray")]
fn intersect_batch_needs_one_slot_per_ray() {
    let bvh = Bvh::default();
    bvh.intersect_batch(&[Ray::new(Vec3::ZERO, Vec3::Z)], 0.0, 1.0, &mut []);
}

#[test]
#[should_panic(expected = "one mask slot per segment")]
fn occluded_from_needs_one_slot_per_end() {
    let bvh = Bvh::default();
    bvh.occluded_from(Vec3::ZERO, &[Vec3::Z], 1.0, &mut [false, false]);
}

#[test]
fn identical_centroids_still_give_small_leaves() {
    let tris: Vec<_> = (0..100)
        .map(|i| {
            let s = 1.0 + i as f32;
            [[-s, -s, 0.0], [s, -s, 0.0], [0.0, 2.0 * s, 0.0]]
        })
        .map(|t| {
            // Same centroid (0, 0, 0) for every triangle.
            let c = (Vec3::from(t[0]) + Vec3::from(t[1]) + Vec3::from(t[2])) / 3.0;
            t.map(|p| (Vec3::from(p) - c).to_array())
        })
        .collect();
    let g = soup(&tris);
    let bvh = Bvh::build(&g);
    bvh.validate(&g).unwrap();
    assert!(bvh.nodes.iter().all(|n| n.count as usize <= MAX_LEAF));
    assert_agree(&g, &bvh, &Ray::new(Vec3::new(0.1, 0.1, -5.0), Vec3::Z));
}

#[test]
fn validate_rejects_broken_trees() {
    let tris: Vec<_> = (0..40)
        .map(|i| {
            let x = i as f32;
            [[x, 0.0, 0.0], [x + 0.5, 0.0, 0.0], [x, 0.5, 1.0]]
        })
        .collect();
    let g = soup(&tris);
    let bvh = build_checked(&g);
    assert!(bvh.node_count() > 3);
    let broken = |f: &dyn Fn(&mut Bvh)| {
        let mut b = bvh.clone();
        f(&mut b);
        b.validate(&g)
    };
    assert!(broken(&|b| b.prim_ids[0] = b.prim_ids[1]).is_err());
    assert!(broken(&|b| b.prim_ids[0] = 40).is_err());
    assert!(broken(&|b| b.nodes[0].first = 1000).is_err());
    assert!(broken(&|b| b.nodes[0].max[0] = 0.0).is_err());
    assert!(broken(&|b| {
        let leaf = b.nodes.iter_mut().find(|n| n.is_leaf()).unwrap();
        leaf.max = leaf.min;
    })
    .is_err());
    assert!(broken(&|b| {
        let leaf = b.nodes.iter_mut().find(|n| n.is_leaf()).unwrap();
        leaf.count += 1;
    })
    .is_err());
    assert!(bvh.validate(&soup(&tris[..39])).is_err());
    assert!(bvh.validate(&Geometry::default()).is_err());
}

#[test]
fn depth_stays_within_the_traversal_stack() {
    // Tiny triangles at x = 2^k for k over f32's whole range: binned SAH peels off a few
    // per level, which without a depth cap would overflow the traversal stack.
    let tris: Vec<_> = (-120..120)
        .map(|k| {
            let x = 2f32.powi(k);
            let e = x * 1e-3;
            [[x, 0.0, 0.0], [x + e, 0.0, 0.0], [x, e, 0.0]]
        })
        .collect();
    let g = soup(&tris);
    let bvh = Bvh::build(&g);
    bvh.validate(&g).unwrap();
    let ray = Ray::new(Vec3::new(-1.0, 1e-30, 0.0), Vec3::X);
    let _ = bvh.intersect(&ray, 0.0, f32::INFINITY);
    let _ = bvh.occluded(&ray, 0.0, f32::INFINITY);
    // At the cap, a root above it (`build::join`) would be too deep: it is refused.
    assert!(build::join(bvh.clone(), build_checked(&soup(&tris[..2]))).is_none());
}

/// Triangles under `node`, counted over its leaves.
fn triangles_under(bvh: &Bvh, node: usize) -> usize {
    let n = &bvh.nodes[node];
    if n.is_leaf() {
        return n.count as usize;
    }
    let first = n.first as usize;
    triangles_under(bvh, first) + triangles_under(bvh, first + 1)
}

#[test]
fn large_soup_takes_the_parallel_path_and_agrees() {
    // Enough triangles that both halves of the root exceed PARALLEL_MIN.
    let n = 2 * PARALLEL_MIN + 1000;
    let mut state = 12345u64;
    let mut rnd = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 40) as f32 / (1u64 << 24) as f32) * 20.0 - 10.0
    };
    let tris: Vec<_> = (0..n)
        .map(|_| {
            let c = [rnd(), rnd(), rnd()];
            [0, 1, 2].map(|_| {
                [
                    c[0] + rnd() * 0.02,
                    c[1] + rnd() * 0.02,
                    c[2] + rnd() * 0.02,
                ]
            })
        })
        .collect();
    let g = soup(&tris);
    let bvh = Bvh::build_parallel(&g, pool());
    bvh.validate(&g).unwrap();
    let serial = Bvh::build(&g);
    assert_same_tree(&bvh, &serial);
    assert_same_tree(&bvh, &reference::reference_build(&g));
    // The root's halves are both big enough to have been built on separate threads.
    let first = bvh.nodes[0].first as usize;
    let halves = [
        triangles_under(&bvh, first),
        triangles_under(&bvh, first + 1),
    ];
    assert!(halves.iter().all(|&h| h >= PARALLEL_MIN), "{halves:?}");
    let mut rays = Vec::new();
    for _ in 0..300 {
        let o = Vec3::new(rnd(), rnd(), rnd()) * 2.0;
        let d = Vec3::new(rnd(), rnd(), rnd());
        assert_agree(&g, &bvh, &Ray::new(o, d));
        rays.push(Ray::new(o, d));
    }
    let mut hits = vec![None; rays.len()];
    bvh.intersect_batch(&rays, 1e-4, f32::INFINITY, &mut hits);
    for (ray, hit) in rays.iter().zip(&hits) {
        assert_eq!(*hit, bvh.intersect(ray, 1e-4, f32::INFINITY));
    }
    for _ in 0..4 {
        let origin = Vec3::new(rnd(), rnd(), rnd());
        let (corner, u, v) = (Vec3::new(rnd(), rnd(), rnd()), Vec3::X * 0.3, Vec3::Z * 0.2);
        let ends: Vec<Vec3> = (0..36)
            .map(|i| corner + (i % 6) as f32 / 5.0 * u + (i / 6) as f32 / 5.0 * v)
            .collect();
        assert_segments_agree(&g, &bvh, origin, &ends, T_MAX);
    }
}
