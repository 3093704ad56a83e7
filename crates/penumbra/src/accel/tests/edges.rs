//! Edge cases, each against the brute-force references: rays in box face planes and through
//! edges and corners on box boundaries, degenerate and duplicate triangles, shadow segments
//! that end exactly on a surface, and one known gap of the slab test (ignored).

use super::*;

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
    // The same with the edge on the box's min x (mirrored), and direction x = +0 and −0:
    // with a tight box one of the slab distances is 0·(±∞) = NaN, and which way a NaN goes
    // through SIMD min/max depends on the operand order, so both faces and both zeros count.
    for g in [
        soup(&[[[-1.0, -1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 1.0, 0.0]]]),
        soup(&[[[1.0, -1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 1.0, 0.0]]]),
    ] {
        let bvh = build_checked(&g);
        for x in [0.0, -0.0] {
            for ray in [
                Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::new(x, 0.0, -1.0)),
                Ray::new(Vec3::new(-0.0, 3.0, 5.0), Vec3::new(x, -0.6, -1.0)),
                Ray::new(Vec3::new(0.0, -3.0, -5.0), Vec3::new(x, 0.6, 1.0)),
            ] {
                assert!(intersect_brute_force(&g, &ray, 1e-4, f32::INFINITY).is_some());
                assert_agree(&g, &bvh, &ray);
            }
        }
    }
}

#[test]
fn axis_aligned_rays_on_box_boundaries_agree() {
    // Unit squares on a lattice, in all three axis planes, so that node boxes (flat ones
    // included) have faces at every lattice coordinate. Axis-aligned rays at lattice and
    // half-lattice coordinates run in those face planes and through edges and corners, with
    // both signs of zero in the direction (1/±0 = ±∞ in the slab test).
    let mut tris = Vec::new();
    for i in -2..2 {
        for j in -2..2 {
            let (a, b) = (i as f32, j as f32);
            tris.extend(parallelogram(Vec3::new(a, 0.0, b), Vec3::X, Vec3::Z));
            tris.extend(parallelogram(Vec3::new(a, b, -1.0), Vec3::X, Vec3::Y));
            tris.extend(parallelogram(Vec3::new(1.0, a, b), Vec3::Y, Vec3::Z));
        }
    }
    let g = soup(&tris);
    let bvh = build_checked(&g);
    let coords: Vec<f32> = (-6..=6).map(|k| k as f32 * 0.5).chain([-0.0]).collect();
    let (mut rays, mut edge_hits) = (0, 0);
    for axis in 0..3 {
        for &a in &coords {
            for &b in &coords {
                for (start, sign) in [(-5.0, 1.0), (5.0, -1.0)] {
                    for zeros in [[0.0, 0.0], [-0.0, 0.0], [0.0, -0.0], [-0.0, -0.0]] {
                        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                        let (mut o, mut d) = ([start; 3], [sign; 3]);
                        (o[u], o[v], d[u], d[v]) = (a, b, zeros[0], zeros[1]);
                        let ray = Ray::new(Vec3::from(o), Vec3::from(d));
                        assert_agree_in(&g, &bvh, &ray, 0.0, f32::INFINITY);
                        assert_agree_in(&g, &bvh, &ray, 1e-4, 5.0);
                        let hit = intersect_brute_force(&g, &ray, 0.0, f32::INFINITY);
                        if hit.is_some_and(|h| h.b1 * h.b2 * (1.0 - h.b1 - h.b2) == 0.0) {
                            edge_hits += 1;
                        }
                        rays += 1;
                    }
                }
            }
        }
    }
    // The scene is built so that many of them meet triangles on an edge or a vertex.
    assert!(
        edge_hits * 4 > rays,
        "{edge_hits} of {rays} rays hit an edge"
    );
}

#[test]
fn degenerate_triangles_agree_with_brute_force() {
    let p = |x: f32, y: f32, z: f32| [x, y, z];
    let mut tris = vec![
        [p(1.0, 1.0, 1.0); 3],                                     // a point
        [p(0.0, 0.0, 0.0), p(2.0, 0.0, 0.0), p(1.0, 0.0, 0.0)],    // a segment on the x axis
        [p(0.0, 0.0, 2.0), p(0.0, 0.0, 2.0), p(0.0, 3.0, 2.0)],    // a segment, repeated vertex
        [p(-1.0, -1.0, -1.0), p(1.0, 1.0, 1.0), p(3.0, 3.0, 3.0)], // a diagonal segment
    ];
    tris.extend(parallelogram(
        Vec3::new(-2.0, -2.0, 4.0),
        Vec3::X * 4.0,
        Vec3::Y * 4.0,
    ));
    // Enough copies of the point that one leaf cannot hold them all.
    tris.extend(std::iter::repeat_n([p(-1.0, 2.0, 0.5); 3], 2 * MAX_LEAF));
    let g = soup(&tris);
    let bvh = build_checked(&g);
    let targets = [
        Vec3::ONE,
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.5, 0.0, 0.0),
        Vec3::new(0.0, 1.5, 2.0),
        Vec3::new(2.0, 2.0, 2.0),
        Vec3::new(-1.0, 2.0, 0.5),
    ];
    let origins = [
        Vec3::new(0.3, -4.0, 0.2),
        Vec3::new(-5.0, 0.0, 0.0), // along the x-axis segment
        Vec3::new(0.0, -3.0, 2.0), // along the repeated-vertex segment
        Vec3::splat(-4.0),         // along the diagonal segment
        Vec3::new(-1.0, 2.0, -6.0),
    ];
    for o in origins {
        for t in targets {
            let ray = Ray::new(o, t - o);
            assert_agree_in(&g, &bvh, &ray, 0.0, f32::INFINITY);
            // A zero-area triangle has no hits: only the parallelogram (the last two
            // triangles before the copies) can be hit.
            if let Some(h) = bvh.intersect(&ray, 0.0, f32::INFINITY) {
                assert!([4, 5].contains(&h.triangle), "{h:?}");
            }
        }
        assert_segments_agree(&g, &bvh, o, &targets, T_MAX);
    }
    // A scene of nothing but degenerate triangles builds, validates and is never hit.
    let g = soup(&tris[..4]);
    let bvh = build_checked(&g);
    for o in origins {
        for t in targets {
            assert_agree_in(&g, &bvh, &Ray::new(o, t - o), 0.0, f32::INFINITY);
        }
    }
}

#[test]
fn duplicate_triangles_report_one_of_the_copies() {
    let t = [[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]];
    let mut tris = vec![t; 20]; // 0..20: exact copies
    tris.push([t[1], t[2], t[0]]); // 20, 21: the same triangle with rotated and reversed corners
    tris.push([t[2], t[1], t[0]]);
    tris.extend(parallelogram(
        Vec3::new(-3.0, -3.0, 3.0),
        Vec3::X * 6.0,
        Vec3::Y * 6.0,
    ));
    let g = soup(&tris);
    let bvh = build_checked(&g);
    let origin = Vec3::new(0.1, 0.2, -1.0);
    let ends: Vec<Vec3> = [(0.1, 0.1), (0.25, 0.25), (0.5, 0.5), (0.0, 0.9), (2.0, 2.0)]
        .map(|(x, y)| Vec3::new(x, y, 5.0))
        .to_vec();
    let rays: Vec<Ray> = ends.iter().map(|&e| Ray::new(origin, e - origin)).collect();
    let mut hits = vec![None; rays.len()];
    bvh.intersect_batch(&rays, 0.0, f32::INFINITY, &mut hits);
    for (ray, hit) in rays.iter().zip(&hits) {
        assert_agree_in(&g, &bvh, ray, 0.0, f32::INFINITY);
        assert_eq!(*hit, bvh.intersect(ray, 0.0, f32::INFINITY));
    }
    // Every ray but the last crosses the copies, which are all closer than the big quad.
    assert!(hits[..4].iter().all(|h| h.unwrap().triangle < 22));
    assert_eq!(hits[4].unwrap().triangle / 2, 11);
    assert_segments_agree(&g, &bvh, origin, &ends, T_MAX);
}

#[test]
fn a_segment_ending_on_a_triangle_is_not_blocked_by_it() {
    // A unit square at z = 1, like an area light, seen from points below it: every end point
    // lies on the square (inside, on the shared diagonal, on its outer edges and corners).
    let light = parallelogram(Vec3::new(0.0, 0.0, 1.0), Vec3::X, Vec3::Y);
    let g = soup(&light);
    let bvh = build_checked(&g);
    let inner = [
        (0.5, 0.5),
        (0.25, 0.25),
        (0.25, 0.75),
        (0.75, 0.25),
        (0.25, 0.5),
    ];
    let outer = [(0.0, 0.0), (1.0, 1.0), (0.5, 0.0), (1.0, 0.5), (0.0, 1.0)];
    let on_light = |pts: &[(f32, f32)]| -> Vec<Vec3> {
        pts.iter().map(|&(x, y)| Vec3::new(x, y, 1.0)).collect()
    };
    let (inner, all) = (on_light(&inner), on_light(&[&inner[..], &outer].concat()));
    for origin in [Vec3::new(0.5, 0.5, 0.0), Vec3::new(0.25, 0.25, 0.0)] {
        for &end in &all {
            let ray = Ray::new(origin, end - origin);
            let hit = intersect_brute_force(&g, &ray, 0.0, f32::INFINITY).expect("ends on it");
            assert!((hit.t - 1.0).abs() <= 1e-6, "t = {}", hit.t);
        }
        let mut mask = vec![true; all.len()];
        bvh.occluded_from(origin, &all, T_MAX, &mut mask);
        assert!(mask.iter().all(|&m| !m), "{mask:?}");
        assert_segments_agree(&g, &bvh, origin, &all, T_MAX);
        // Past the end, the square does block: for ends strictly inside it (edges on a flat
        // box's boundary are the known gap, see `oblique_hits_on_a_flat_box_boundary_edge`).
        let mut mask = vec![false; inner.len()];
        bvh.occluded_from(origin, &inner, 1.0 + 1e-4, &mut mask);
        assert!(mask.iter().all(|&m| m), "{mask:?}");
        assert_segments_agree(&g, &bvh, origin, &inner, 1.0 + 1e-4);
    }
    // A blocker halfway does count.
    let mut tris = light.to_vec();
    tris.extend(parallelogram(Vec3::new(0.0, 0.0, 0.5), Vec3::X, Vec3::Y));
    let g = soup(&tris);
    let bvh = build_checked(&g);
    let mut mask = vec![false; all.len()];
    let origin = Vec3::new(0.5, 0.5, 0.0);
    bvh.occluded_from(origin, &all, T_MAX, &mut mask);
    assert!(mask.iter().all(|&m| m), "{mask:?}");
    assert_segments_agree(&g, &bvh, origin, &all, T_MAX);
}

/// Known gap, left as found: a ray crossing a flat node box (a triangle in an axis plane) that
/// meets the triangle exactly on an edge lying on the box's boundary can be culled by the slab
/// test, while Möller–Trumbore counts the edge as inside. The padding of `build::node` is
/// relative to the coordinate (so about `f32::MIN_POSITIVE` at 0), while the rounding of the
/// slab distances is relative to `t`; at the edge the slabs' intervals can miss each other by
/// an ulp. Run with `cargo test -p penumbra -- --ignored`.
#[test]
#[ignore = "known traversal gap on edges of flat boxes; see the doc comment"]
fn oblique_hits_on_a_flat_box_boundary_edge() {
    let g = soup(&[[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]]);
    let bvh = build_checked(&g);
    let mut missed = Vec::new();
    for i in 1..40 {
        for j in 1..40 {
            let (a, b) = (i as f32 * 0.37, j as f32 * 1.13);
            // Meets the triangle's edge y = 0 at (0.25, 0, 0), where t = 1.
            let ray = Ray::new(Vec3::new(0.25, -a, -b), Vec3::new(0.0, a, b));
            let reference = intersect_brute_force(&g, &ray, 0.0, f32::INFINITY);
            if reference.is_some() != bvh.intersect(&ray, 0.0, f32::INFINITY).is_some() {
                missed.push((a, b, reference));
            }
        }
    }
    assert!(
        missed.is_empty(),
        "{} missed, e.g. {:?}",
        missed.len(),
        missed[0]
    );
}
