//! The Möller–Trumbore ray–triangle test (Möller & Trumbore, "Fast, Minimum Storage
//! Ray/Triangle Intersection", 1997), written once: the scalar test ([`intersect_triangle`])
//! and every SIMD lane of the renderer's packets (fans, bundles, shafts) are made of the
//! functions here, so a lane computes the scalar test's products, sums and comparisons in
//! its order (glam's `cross` and `dot`, written out; no fused multiply-add) and answers
//! exactly as it does.
//!
//! The test solves `[−d, e1, e2]·(t, b1, b2) = o − v0` by Cramer's rule with scalar triple
//! products: `pvec = d × e2`, `det = e1 · pvec`, `tvec = o − v0`, `qvec = tvec × e1`, then
//! `b1 = tvec · pvec / det`, `b2 = d · qvec / det`, `t = e2 · qvec / det`. The terms of the
//! origin alone (`tvec`, `qvec` and the numerator `e2 · qvec`) are shared by rays from one
//! point, and those of the direction alone (`pvec`, `det`) by rays along one direction.

use glam::Vec3;

use crate::geometry::TriangleHit;

/// `a − b`.
#[inline(always)]
fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `a × b` as glam's `Vec3::cross` computes it.
#[inline(always)]
fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - b[1] * a[2],
        a[2] * b[0] - b[2] * a[0],
        a[0] * b[1] - b[0] * a[1],
    ]
}

/// `a · b` as glam's `Vec3::dot` computes it.
#[inline(always)]
fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The terms of the origin `o` alone: `tvec = o − v0`, `qvec = tvec × e1` and the `t`
/// numerator `e2 · qvec`.
#[inline(always)]
pub(crate) fn origin_terms(
    o: [f32; 3],
    v0: [f32; 3],
    e1: [f32; 3],
    e2: [f32; 3],
) -> ([f32; 3], [f32; 3], f32) {
    let tvec = sub(o, v0);
    let qvec = cross(tvec, e1);
    (tvec, qvec, dot(e2, qvec))
}

/// The terms of the direction `d` alone: `pvec = d × e2` and the determinant `e1 · pvec`.
#[inline(always)]
pub(crate) fn determinant(d: [f32; 3], e1: [f32; 3], e2: [f32; 3]) -> ([f32; 3], f32) {
    let pvec = cross(d, e2);
    (pvec, dot(e1, pvec))
}

/// Bounds `(lo, hi)` on [`determinant`]`(d, e1, e2).1` over every direction `d` with
/// `d[a]` in `[lo[a], hi[a]]`, as computed in `f32`: the same operations on the interval's
/// ends. Rounding is monotonic, so each product and difference of the test stays between
/// those of the ends that bound it, and so does every direction's determinant. `None` when a
/// bound is not finite (no conclusion then).
#[inline(always)]
pub(crate) fn determinant_bounds(
    (lo, hi): ([f32; 3], [f32; 3]),
    e1: [f32; 3],
    e2: [f32; 3],
) -> Option<(f32, f32)> {
    // c·x for x in [l, h]: the smaller and larger of the ends' products.
    let scale = |c: f32, (l, h): (f32, f32)| {
        let (a, b) = (l * c, h * c);
        if a <= b {
            (a, b)
        } else {
            (b, a)
        }
    };
    let d = |a: usize| (lo[a], hi[a]);
    // pvec = d × e2 (`cross`: a[1]·b[2] − b[1]·a[2], …), each term a difference of products.
    let minus = |(a, b): (f32, f32), (c, e): (f32, f32)| (a - e, b - c);
    let pvec = [
        minus(scale(e2[2], d(1)), scale(e2[1], d(2))),
        minus(scale(e2[0], d(2)), scale(e2[2], d(0))),
        minus(scale(e2[1], d(0)), scale(e2[0], d(1))),
    ];
    // det = e1 · pvec, summed in `dot`'s order.
    let [x, y, z] = [0, 1, 2].map(|a| scale(e1[a], pvec[a]));
    let det = ((x.0 + y.0) + z.0, (x.1 + y.1) + z.1);
    let terms = [pvec[0], pvec[1], pvec[2], x, y, z, det];
    terms
        .iter()
        .all(|&(l, h)| l.is_finite() && h.is_finite())
        .then_some(det)
}

/// The whole test from the origin's terms ([`origin_terms`]) and the direction `d`: whether
/// the ray meets the triangle's inside (edges included), and `t`, `b1`, `b2`. The caller
/// bounds `t`.
#[inline(always)]
pub(crate) fn solve(
    (tvec, qvec, t_num): ([f32; 3], [f32; 3], f32),
    d: [f32; 3],
    e1: [f32; 3],
    e2: [f32; 3],
) -> (bool, f32, f32, f32) {
    let (pvec, det) = determinant(d, e1, e2);
    let inv_det = 1.0 / det;
    let b1 = dot(tvec, pvec) * inv_det;
    let b2 = dot(d, qvec) * inv_det;
    let t = t_num * inv_det;
    (inside(det, b1, b2), t, b1, b2)
}

/// The verdict from the determinant and barycentrics: the ray meets the triangle's inside,
/// edges included. Every test ends here, so that all of them answer alike.
// The comparisons are written out, negations included, so that NaN values answer as the
// scalar test's early exits do (a NaN `b2` passes both of its tests).
#[allow(clippy::neg_cmp_op_on_partial_ord, clippy::manual_range_contains)]
#[inline(always)]
pub(crate) fn inside(det: f32, b1: f32, b2: f32) -> bool {
    (det != 0.0) & det.is_finite() & (0.0 <= b1) & (b1 <= 1.0) & !(b2 < 0.0) & !(b1 + b2 > 1.0)
}

/// Intersects the ray `origin + t·dir` with the triangle `v0 + b1·e1 + b2·e2`
/// (`e1 = v1 − v0`, `e2 = v2 − v0`), two-sided, for `t` strictly inside `(t_min, t_max)`.
///
/// Returns `None` for a miss, a ray parallel to the triangle's plane, or a degenerate
/// (zero-area) triangle. Edges and vertices count as inside (`b ≥ 0`, `b1 + b2 ≤ 1`).
#[inline(always)]
pub fn intersect_triangle(
    origin: Vec3,
    dir: Vec3,
    v0: Vec3,
    e1: Vec3,
    e2: Vec3,
    t_min: f32,
    t_max: f32,
) -> Option<TriangleHit> {
    let (d, e1, e2) = (dir.to_array(), e1.to_array(), e2.to_array());
    let (pvec, det) = determinant(d, e1, e2);
    // The determinant is zero exactly when the ray is parallel or the triangle degenerate;
    // tiny values give huge barycentrics, which the range tests below reject. The early
    // exits give `inside`'s verdict, a term at a time.
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv_det = 1.0 / det;
    let tvec = sub(origin.to_array(), v0.to_array());
    let b1 = dot(tvec, pvec) * inv_det;
    if !(0.0..=1.0).contains(&b1) {
        return None;
    }
    let qvec = cross(tvec, e1);
    let b2 = dot(d, qvec) * inv_det;
    if b2 < 0.0 || b1 + b2 > 1.0 {
        return None;
    }
    let t = dot(e2, qvec) * inv_det;
    if t > t_min && t < t_max {
        Some(TriangleHit { t, b1, b2 })
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // The triangle (0,0,0), (1,0,0), (0,1,0) in the z = 0 plane.
    const V0: Vec3 = Vec3::ZERO;
    const E1: Vec3 = Vec3::X;
    const E2: Vec3 = Vec3::Y;

    fn hit(origin: Vec3, dir: Vec3) -> Option<TriangleHit> {
        intersect_triangle(origin, dir, V0, E1, E2, 1e-4, f32::INFINITY)
    }

    #[test]
    fn hits_the_inside_with_barycentrics_and_distance() {
        let h = hit(Vec3::new(0.25, 0.5, 2.0), -Vec3::Z).unwrap();
        assert!((h.t - 2.0).abs() < 1e-6);
        assert!((h.b1 - 0.25).abs() < 1e-6 && (h.b2 - 0.5).abs() < 1e-6);
        // t is in units of the direction's length.
        let h = hit(Vec3::new(0.25, 0.5, 2.0), -2.0 * Vec3::Z).unwrap();
        assert!((h.t - 1.0).abs() < 1e-6);
    }

    #[test]
    fn misses_outside_the_edges() {
        assert!(hit(Vec3::new(0.6, 0.6, 1.0), -Vec3::Z).is_none());
        assert!(hit(Vec3::new(-0.01, 0.5, 1.0), -Vec3::Z).is_none());
        assert!(hit(Vec3::new(0.5, -0.01, 1.0), -Vec3::Z).is_none());
    }

    #[test]
    fn edges_and_vertices_count_as_inside() {
        assert!(hit(Vec3::new(0.5, 0.0, 1.0), -Vec3::Z).is_some());
        assert!(hit(Vec3::new(0.0, 0.5, 1.0), -Vec3::Z).is_some());
        assert!(hit(Vec3::new(0.5, 0.5, 1.0), -Vec3::Z).is_some());
        assert!(hit(Vec3::new(0.0, 0.0, 1.0), -Vec3::Z).is_some());
        assert!(hit(Vec3::new(1.0, 0.0, 1.0), -Vec3::Z).is_some());
    }

    #[test]
    fn is_two_sided() {
        let h = hit(Vec3::new(0.2, 0.2, -3.0), Vec3::Z).unwrap();
        assert!((h.t - 3.0).abs() < 1e-6);
    }

    #[test]
    fn parallel_ray_misses() {
        assert!(hit(Vec3::new(0.2, 0.2, 0.0), Vec3::X).is_none());
        assert!(hit(Vec3::new(0.2, 0.2, 1.0), Vec3::new(1.0, 1.0, 0.0)).is_none());
    }

    #[test]
    fn triangle_behind_the_origin_is_not_hit() {
        assert!(hit(Vec3::new(0.2, 0.2, -1.0), -Vec3::Z).is_none());
    }

    #[test]
    fn respects_the_t_interval() {
        let o = Vec3::new(0.2, 0.2, 1.0);
        assert!(intersect_triangle(o, -Vec3::Z, V0, E1, E2, 1e-4, 0.5).is_none());
        assert!(intersect_triangle(o, -Vec3::Z, V0, E1, E2, 1.5, 9.0).is_none());
        assert!(intersect_triangle(o, -Vec3::Z, V0, E1, E2, 0.5, 1.5).is_some());
    }

    #[test]
    fn degenerate_triangle_is_never_hit() {
        let o = Vec3::new(0.5, 0.0, 1.0);
        assert!(intersect_triangle(o, -Vec3::Z, V0, E1, 2.0 * E1, 0.0, 9.0).is_none());
        assert!(intersect_triangle(o, -Vec3::Z, V0, Vec3::ZERO, Vec3::ZERO, 0.0, 9.0).is_none());
    }

    /// Every direction in a box has its determinant within `determinant_bounds`: the box's
    /// corners, its inside, and boxes a few ulps wide (where rounding is all there is).
    #[test]
    fn the_determinant_of_every_direction_in_a_box_is_within_its_bounds() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut tight = 0;
        for k in 0..2000 {
            let mut v = || [next() * 8.0 - 4.0, next() * 8.0 - 4.0, next() * 8.0 - 4.0];
            let (e1, e2, centre) = (v(), v(), v());
            // Widths from a few ulps to a few units.
            let width = [1e-6, 1e-3, 0.5, 3.0][k % 4];
            let half = [0, 1, 2].map(|_| width * next());
            let lo = [0, 1, 2].map(|a| centre[a] - half[a]);
            let hi = [0, 1, 2].map(|a| centre[a] + half[a]);
            let (det_lo, det_hi) = determinant_bounds((lo, hi), e1, e2).expect("finite");
            tight += usize::from(det_lo > 0.0 || det_hi < 0.0);
            for j in 0..64 {
                let d = match j {
                    // The eight corners.
                    0..8 => [0, 1, 2].map(|a| if j >> a & 1 == 0 { lo[a] } else { hi[a] }),
                    _ => [0, 1, 2].map(|a| lo[a] + (hi[a] - lo[a]) * next()),
                };
                let d = [0, 1, 2].map(|a| d[a].clamp(lo[a], hi[a]));
                let det = determinant(d, e1, e2).1;
                assert!(
                    det_lo <= det && det <= det_hi,
                    "{det} outside [{det_lo}, {det_hi}] for {d:?} in {lo:?}..{hi:?}"
                );
            }
        }
        // The bounds decide the sign often enough to be of use.
        assert!(tight > 500, "{tight} of 2000 boxes of one sign");
        let inf = [f32::INFINITY, 0.0, 0.0];
        assert_eq!(
            determinant_bounds(([0.0; 3], inf), [1.0; 3], [0.0, 1.0, 2.0]),
            None
        );
    }
}
