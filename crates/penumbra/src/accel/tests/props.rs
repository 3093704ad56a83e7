//! Property tests: every query of the BVH against the brute-force references, on random
//! soups of small triangles and on lattice scenes whose coordinates are small integers (where
//! rays run through edges, vertices and box faces exactly, and many triangles are degenerate
//! or coincide). Every tree is validated, serial and parallel builds are compared.

use proptest::prelude::*;

use super::*;

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

/// Rays between two random points, skipping near-zero directions.
fn arb_rays(len: std::ops::Range<usize>) -> impl Strategy<Value = Vec<Ray>> {
    prop::collection::vec((arb_point(), arb_point()), len).prop_map(|v| {
        v.into_iter()
            .map(|(o, target)| Ray::new(Vec3::from(o), Vec3::from(target) - Vec3::from(o)))
            .filter(|r| r.direction.length() >= 1e-3)
            .collect()
    })
}

fn arb_t_min() -> impl Strategy<Value = f32> {
    prop_oneof![Just(0.0f32), Just(1e-4), 0.0f32..2.0]
}

fn arb_t_max() -> impl Strategy<Value = f32> {
    prop_oneof![Just(f32::INFINITY), 0.05f32..40.0]
}

/// A lattice point with coordinates in `-r..=r`.
fn arb_lattice_point(r: i32) -> impl Strategy<Value = Vec3> {
    prop::array::uniform3(-r..=r).prop_map(|p| Vec3::from(p.map(|c| c as f32)))
}

/// Zero direction components of either sign (1/±0 = ±∞ in the slab test).
fn signed_zeros(d: Vec3, negative: [bool; 3]) -> Vec3 {
    let mut d = d.to_array();
    for (c, neg) in d.iter_mut().zip(negative) {
        if *c == 0.0 && neg {
            *c = -0.0;
        }
    }
    Vec3::from(d)
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

    /// Two trees over the two parts of a soup, joined under one root (as a world's opaque and
    /// cut-out trees are for ray casting), are a valid tree over all of it that answers as
    /// brute force does.
    #[test]
    fn two_trees_joined_answer_as_one(
        tris in arb_soup(),
        parts in prop::collection::vec(any::<bool>(), 300),
        rays in arb_rays(1..40),
    ) {
        let g = soup(&tris);
        let (a, b): (Vec<u32>, Vec<u32>) = (0..g.len() as u32).partition(|&i| parts[i as usize]);
        let part = |ids: &[u32]| {
            let mut bvh = build::build(ids.len(), |j| g.corners(ids[j] as usize), None);
            bvh.prim_ids.iter_mut().for_each(|id| *id = ids[*id as usize]);
            bvh
        };
        let joined = build::join(part(&a), part(&b)).expect("shallow trees join");
        prop_assert!(joined.validate(&g).is_ok(), "{:?}", joined.validate(&g));
        for ray in &rays {
            assert_agree(&g, &joined, ray);
        }
    }

    /// Closest hit and occlusion over any interval, empty ones (`t_max ≤ t_min`) included.
    #[test]
    fn queries_agree_with_brute_force_in_any_interval(
        tris in arb_soup(),
        rays in arb_rays(1..40),
        t_min in arb_t_min(),
        t_max in arb_t_max(),
    ) {
        let g = soup(&tris);
        let bvh = build_checked(&g);
        for ray in &rays {
            assert_agree_in(&g, &bvh, ray, t_min, t_max);
        }
    }

    #[test]
    fn intersect_batch_equals_single_queries_and_brute_force(
        tris in arb_soup(),
        rays in arb_rays(0..60),
        t_min in arb_t_min(),
        t_max in arb_t_max(),
    ) {
        let g = soup(&tris);
        let bvh = build_checked(&g);
        // Stale contents must be overwritten, misses included.
        let stale = Hit { t: -1.0, b1: 0.5, b2: 0.5, triangle: u32::MAX, instance: None };
        let mut hits = vec![Some(stale); rays.len()];
        bvh.intersect_batch(&rays, t_min, t_max, &mut hits);
        for (ray, hit) in rays.iter().zip(&hits) {
            prop_assert_eq!(*hit, bvh.intersect(ray, t_min, t_max));
            prop_assert_eq!(*hit, intersect_brute_force(&g, ray, t_min, t_max));
        }
    }

    /// Shadow segments from one point to samples on a parallelogram, like an area light,
    /// optionally part of the scene itself (the segments then end on its triangles).
    #[test]
    fn occluded_from_equals_brute_force_occlusion(
        tris in arb_soup(),
        origin in arb_point(),
        corner in arb_point(),
        edges in prop::array::uniform2(prop::array::uniform3(-3.0f32..3.0)),
        light_in_scene in any::<bool>(),
        samples in prop::collection::vec((0.0f32..=1.0, 0.0f32..=1.0), 0..40),
    ) {
        let (corner, u, v) = (Vec3::from(corner), Vec3::from(edges[0]), Vec3::from(edges[1]));
        let mut tris = tris;
        if light_in_scene {
            tris.extend(parallelogram(corner, u, v));
        }
        let g = soup(&tris);
        let bvh = build_checked(&g);
        let ends: Vec<Vec3> = samples.iter().map(|&(a, b)| corner + a * u + b * v).collect();
        assert_segments_agree(&g, &bvh, Vec3::from(origin), &ends, T_MAX);
    }

    /// A renderer's bundles: neighbouring points on a floor (some exactly on it, some a
    /// hair above) to the N×N samples of a light, among a room's large triangles and a few
    /// small ones, so that the batch's shaft holds few candidates, or many when the soup is
    /// dense. Up to 81 samples: more than one pass of ends.
    #[test]
    fn bundles_to_a_light_grid_equal_brute_force_occlusion(
        tris in prop::collection::vec(
            (arb_point(), prop::array::uniform3(prop::array::uniform3(-1.5f32..1.5))),
            0..60,
        ),
        center in prop::array::uniform2(-5.0f32..5.0),
        spread in prop_oneof![Just(0.0f32), 1e-3f32..0.5],
        lifts in prop::collection::vec((0.0f32..=1.0, 0.0f32..=1.0, 0u8..4), 1..20),
        light in (arb_point(), -3.0f32..3.0, -3.0f32..3.0),
        n in 1usize..10,
    ) {
        // A floor at y = −6 and a ceiling at y = 6 that the light may lie in or below.
        let mut soup_tris: Vec<[[f32; 3]; 3]> = tris
            .into_iter()
            .map(|(c, offs)| offs.map(|o| [c[0] + o[0], c[1] + o[1], c[2] + o[2]]))
            .collect();
        let (x, z) = (Vec3::X * 20.0, Vec3::Z * 20.0);
        soup_tris.extend(parallelogram(Vec3::new(-10.0, -6.0, -10.0), x, z));
        soup_tris.extend(parallelogram(Vec3::new(-10.0, 6.0, -10.0), z, x));
        let g = soup(&soup_tris);
        let bvh = build_checked(&g);
        let origins: Vec<Vec3> = lifts
            .iter()
            .map(|&(a, b, lift)| {
                let lift = [0.0, 1e-6, 1e-4, 0.3][usize::from(lift)];
                Vec3::new(center[0] + a * spread, -6.0 + lift, center[1] + b * spread)
            })
            .collect();
        let (corner, a, b) = light;
        let corner = Vec3::new(corner[0], corner[1].abs().min(6.0), corner[2]);
        let (u, v) = (Vec3::new(a, 0.0, 0.0), Vec3::new(0.0, 0.0, b));
        let step = 1.0 / n as f32;
        let ends: Vec<Vec3> = (0..n * n)
            .map(|k| {
                let (i, j) = ((k % n) as f32 + 0.5, (k / n) as f32 + 0.5);
                corner + (i * step) * u + (j * step) * v
            })
            .collect();
        assert_pairs_agree(&g, &bvh, &origins, &ends, T_MAX);
    }

    /// Rays sharing an origin, as a pinhole camera's, in packets of every width.
    #[test]
    fn intersect_from_equals_brute_force(
        tris in arb_soup(),
        origin in arb_point(),
        targets in prop::collection::vec(arb_point(), 0..40),
        t_min in arb_t_min(),
        t_max in arb_t_max(),
    ) {
        let g = soup(&tris);
        let bvh = build_checked(&g);
        let origin = Vec3::from(origin);
        let dirs: Vec<Vec3> = targets.iter().map(|&p| Vec3::from(p) - origin).collect();
        assert_from_agrees(&g, &bvh, origin, &dirs, t_min, t_max);
        assert_from_agrees(&g, &bvh, origin, &dirs, 1e-4, f32::INFINITY);
    }

    /// Integer coordinates: rays and segments between lattice points meet triangles exactly on
    /// edges and vertices, run in box face planes, and cross degenerate and duplicate triangles.
    #[test]
    fn lattice_scenes_agree_with_brute_force(
        tris in prop::collection::vec(prop::array::uniform3(arb_lattice_point(3)), 0..80),
        origin in arb_lattice_point(4),
        ends in prop::collection::vec((arb_lattice_point(4), any::<[bool; 3]>()), 0..40),
    ) {
        let tris: Vec<_> = tris.iter().map(|t| t.map(<[f32; 3]>::from)).collect();
        let g = soup(&tris);
        let bvh = build_checked(&g);
        let mut rays = Vec::new();
        for &(end, negative) in &ends {
            let ray = Ray::new(origin, signed_zeros(end - origin, negative));
            if ray.direction == Vec3::ZERO {
                continue;
            }
            assert_agree_in(&g, &bvh, &ray, 0.0, f32::INFINITY);
            assert_agree_in(&g, &bvh, &ray, 1e-4, 1.0);
            rays.push(ray);
        }
        let mut hits = vec![None; rays.len()];
        bvh.intersect_batch(&rays, 0.0, f32::INFINITY, &mut hits);
        for (ray, hit) in rays.iter().zip(&hits) {
            prop_assert_eq!(*hit, bvh.intersect(ray, 0.0, f32::INFINITY));
        }
        let dirs: Vec<Vec3> = rays.iter().map(|r| r.direction).collect();
        assert_from_agrees(&g, &bvh, origin, &dirs, 0.0, f32::INFINITY);
        assert_from_agrees(&g, &bvh, origin, &dirs, 1e-4, 1.0);
        let ends: Vec<Vec3> = ends.iter().map(|&(e, _)| e).collect();
        assert_segments_agree(&g, &bvh, origin, &ends, T_MAX);
    }
}
