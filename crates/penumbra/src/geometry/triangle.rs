//! The Möller–Trumbore ray–triangle test (Möller & Trumbore, "Fast, Minimum Storage
//! Ray/Triangle Intersection", 1997).

use glam::Vec3;

/// Where a ray meets a triangle: the ray parameter and the barycentrics of `v1` and `v2`
/// (the hit point is `(1 − b1 − b2)·v0 + b1·v1 + b2·v2`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Ray parameter of the hit, in units of the direction's length.
    pub t: f32,
    /// Barycentric weight of `v1`.
    pub b1: f32,
    /// Barycentric weight of `v2`.
    pub b2: f32,
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
    // Solve [-d, e1, e2]·(t, b1, b2) = o − v0 by Cramer's rule with scalar triple products.
    let pvec = dir.cross(e2);
    let det = e1.dot(pvec);
    // The determinant is zero exactly when the ray is parallel or the triangle degenerate;
    // tiny values give huge barycentrics, which the range tests below reject.
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv_det = 1.0 / det;
    let tvec = origin - v0;
    let b1 = tvec.dot(pvec) * inv_det;
    if !(0.0..=1.0).contains(&b1) {
        return None;
    }
    let qvec = tvec.cross(e1);
    let b2 = dir.dot(qvec) * inv_det;
    if b2 < 0.0 || b1 + b2 > 1.0 {
        return None;
    }
    let t = e2.dot(qvec) * inv_det;
    if t > t_min && t < t_max {
        Some(TriangleHit { t, b1, b2 })
    } else {
        None
    }
}

/// The closest hit of a ray: distance, barycentrics, the triangle and, for a mesh placed by
/// an instance, which instance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Barycentric weight of the triangle's second vertex.
    pub b1: f32,
    /// Barycentric weight of the triangle's third vertex.
    pub b2: f32,
    /// Index of the triangle hit: in [`Geometry::triangles`](super::Geometry::triangles)
    /// without an instance, else in the instance's mesh.
    pub triangle: u32,
    /// The instance whose mesh holds the triangle, or `None` for the world's own triangles.
    pub instance: Option<u32>,
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
}
