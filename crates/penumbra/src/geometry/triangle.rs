//! What a ray–triangle test finds: [`TriangleHit`] (the test itself is
//! `accel::prim::moller_trumbore`) and the closest hit of a ray, [`Hit`].

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
