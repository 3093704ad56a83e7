//! What brute force says of a shadow segment, and how firmly.
//!
//! On a ray lying (nearly) in a triangle's plane, Möller–Trumbore divides two rounding errors:
//! it can report a hit at a `t` where the ray is nowhere near the triangle. A segment between
//! two samples of a light lies in the light's own plane and meets this: one found by the
//! property tests is reported hit at a point 1.1 units outside the triangle's box, while in exact
//! arithmetic both ends, and so the whole segment, lie in the other triangle of the light.
//! A query that culls by boxes or shafts can never find such a hit, and may or may not test
//! that triangle at all, so the reference leaves the segment's answer open. A hit at a point
//! inside the triangle's (padded) box is firm, and every query must report it.

use super::*;

/// Brute force's occlusion of one segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Verdict {
    /// Some triangle is hit at a point inside its box.
    Blocked,
    /// No triangle is hit.
    Clear,
    /// Triangles are hit, but each at a point outside its box: either answer is right.
    Open,
}

impl Verdict {
    /// The verdict on `ray` over `(t_min, t_max)` from every triangle of `g`.
    pub(super) fn of(g: &Geometry, ray: &Ray, t_min: f32, t_max: f32) -> Verdict {
        let mut verdict = Verdict::Clear;
        for i in 0..g.len() {
            let corners = g.corners(i);
            if let Some(h) = accel(corners).hit(ray, t_min, t_max) {
                let tight = corners.into_iter().fold(Aabb::EMPTY, Aabb::grow);
                let padded = build::node(tight, 0, 1).bounds();
                if padded.contains(ray.at(h.t)) {
                    return Verdict::Blocked;
                }
                verdict = Verdict::Open;
            }
        }
        verdict
    }

    /// True when a query answering `blocked` agrees with this verdict.
    pub(super) fn admits(self, blocked: bool) -> bool {
        match self {
            Verdict::Blocked => blocked,
            Verdict::Clear => !blocked,
            Verdict::Open => true,
        }
    }
}

/// The second triangle of the light the property test failed on, its tree, and the point at
/// `(a, b)` of the light's parallelogram (the triangle covers `b ≥ a`).
fn light_triangle() -> (Geometry, Bvh, impl Fn(f32, f32) -> Vec3) {
    let (corner, u, v) = (
        Vec3::new(-3.9226649, -2.4733906, 5.6919756),
        Vec3::new(-0.36001608, -0.60710675, -2.9584782),
        Vec3::new(0.700488, 1.4405535, 2.3873572),
    );
    let g = soup(&parallelogram(corner, u, v)[1..]);
    let bvh = build_checked(&g);
    (g, bvh, move |a: f32, b: f32| corner + a * u + b * v)
}

/// The segment of the property test's failure: between two samples of a light, it lies in the
/// light's plane, inside one of its triangles, and Möller–Trumbore reports a hit on the other
/// far outside that triangle's box. Brute force calls it blocked, the BVH clear.
#[test]
fn a_hit_outside_the_triangles_box_leaves_the_verdict_open() {
    let (g, bvh, at) = light_triangle();
    let (o, e) = (at(0.83423954, 0.07173311), at(0.70886075, 0.6030608));
    let ray = Ray::new(o, e - o);
    assert!(occluded_brute_force(&g, &ray, 0.0, T_MAX));
    assert_eq!(Verdict::of(&g, &ray, 0.0, T_MAX), Verdict::Open);
    assert!(!bvh.occluded(&ray, 0.0, T_MAX));
    // A segment through the light's plane, across it, is firmly blocked.
    let n = (at(1.0, 0.0) - at(0.0, 0.0)).cross(at(0.0, 1.0) - at(0.0, 0.0));
    let through = Ray::new(at(0.25, 0.5) + n, -2.0 * n);
    assert_eq!(Verdict::of(&g, &through, 0.0, T_MAX), Verdict::Blocked);
    assert_eq!(
        Verdict::of(&g, &Ray::new(o + n, n), 0.0, T_MAX),
        Verdict::Clear
    );
}

/// The same segment among 16 from one point to samples across the whole light: the batch
/// takes a shaft, which holds the light's other triangle, and its lanes test that triangle for
/// every segment. Each answer is still [`Bvh::occluded`]'s, the one above included.
#[test]
fn a_shaft_keeps_only_the_hits_the_walk_would_find() {
    let (g, bvh, at) = light_triangle();
    let origin = at(0.83423954, 0.07173311);
    let mut ends = vec![at(0.70886075, 0.6030608)];
    ends.extend((0..15).map(|k| at((k % 4) as f32 / 4.0 + 0.1, (k / 4) as f32 / 4.0 + 0.1)));
    assert!(ends.len() >= SHAFT_MIN_ENDS);
    let expected: Vec<bool> = ends
        .iter()
        .map(|&e| bvh.occluded(&Ray::new(origin, e - origin), 0.0, T_MAX))
        .collect();
    let first = Ray::new(origin, ends[0] - origin);
    assert_eq!(Verdict::of(&g, &first, 0.0, T_MAX), Verdict::Open);
    assert!(!expected[0]);
    let (from, to) = (by_axis(&[origin]), by_axis(&ends));
    let pairs = Pairs {
        origins: from.each_ref().map(|axis| &axis[..]),
        ends: to.each_ref().map(|axis| &axis[..]),
    };
    for path in supported_paths() {
        let mut blocked = vec![false; ends.len()];
        bvh.occlude_pairs_on(path, pairs, T_MAX, &mut blocked);
        assert_eq!(blocked, expected, "{path:?}");
    }
}
