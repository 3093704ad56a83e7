//! Tests of the BVH against the brute-force references: unit tests for edge cases and
//! property tests over random triangle soups.

use super::*;
use crate::geometry::Mesh;
use crate::math::Transform;
use proptest::prelude::*;

#[test]
fn node_is_32_bytes() {
    assert_eq!(std::mem::size_of::<BvhNode>(), 32);
    assert_eq!(std::mem::align_of::<BvhNode>(), 32);
}

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

fn assert_agree(g: &Geometry, bvh: &Bvh, ray: &Ray) {
    let a = bvh.intersect(ray, 1e-4, f32::INFINITY);
    let b = intersect_brute_force(g, ray, 1e-4, f32::INFINITY);
    match (a, b) {
        (None, None) => {}
        (Some(a), Some(b)) => {
            // The triangle may differ only on an exact tie in t.
            assert_eq!(a.t, b.t, "closest distance differs");
        }
        (a, b) => panic!("bvh {a:?} vs brute force {b:?}"),
    }
    assert_eq!(bvh.occluded(ray, 1e-4, f32::INFINITY), b.is_some());
    if let Some(b) = b {
        // Nothing blocks the ray strictly before its closest hit.
        assert!(!bvh.occluded(ray, 1e-4, b.t));
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
fn rays_in_a_box_face_plane_still_hit_edges() {
    // The triangle's right edge lies on x = 0, the box's max x. A ray with direction x = 0
    // travelling in that plane (the center column of an axis-aligned camera) hits the
    // edge, which counts as inside; the box test must not skip it.
    let g = soup(&[[[-1.0, -1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 1.0, 0.0]]]);
    let bvh = Bvh::build(&g);
    for ray in [
        Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z),
        Ray::new(Vec3::new(0.0, 3.0, 5.0), Vec3::new(0.0, -0.6, -1.0)),
    ] {
        assert!(intersect_brute_force(&g, &ray, 1e-4, f32::INFINITY).is_some());
        assert_agree(&g, &bvh, &ray);
    }
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
}

fn arb_point() -> impl Strategy<Value = [f32; 3]> {
    prop::array::uniform3(-10.0f32..10.0)
}

fn arb_soup() -> impl Strategy<Value = Vec<[[f32; 3]; 3]>> {
    // Small triangles scattered in a box, so that rays hit some and miss others.
    prop::collection::vec(
        (
            arb_point(),
            prop::array::uniform3(prop::array::uniform3(-1.5f32..1.5)),
        ),
        0..300,
    )
    .prop_map(|v| {
        v.into_iter()
            .map(|(c, offs)| offs.map(|o| [c[0] + o[0], c[1] + o[1], c[2] + o[2]]))
            .collect()
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn bvh_agrees_with_brute_force(
        tris in arb_soup(),
        rays in prop::collection::vec((arb_point(), arb_point()), 50),
    ) {
        let g = soup(&tris);
        let bvh = Bvh::build(&g);
        prop_assert!(bvh.validate(&g).is_ok(), "{:?}", bvh.validate(&g));
        for (o, target) in rays {
            let dir = Vec3::from(target) - Vec3::from(o);
            if dir.length() < 1e-3 { continue; }
            assert_agree(&g, &bvh, &Ray::new(Vec3::from(o), dir));
        }
    }
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
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let bvh = Bvh::build_parallel(&g, &pool);
    bvh.validate(&g).unwrap();
    let serial = Bvh::build(&g);
    assert_eq!(bvh.nodes, serial.nodes);
    assert_eq!(bvh.prim_ids, serial.prim_ids);
    for _ in 0..300 {
        let o = Vec3::new(rnd(), rnd(), rnd()) * 2.0;
        let d = Vec3::new(rnd(), rnd(), rnd());
        assert_agree(&g, &bvh, &Ray::new(o, d));
    }
}
