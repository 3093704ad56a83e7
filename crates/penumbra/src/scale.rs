//! The scales penumbra renders exactly, and how a world is checked against them.
//!
//! Möller–Trumbore multiplies three lengths: a ray from `o` toward a triangle with edges `e1`,
//! `e2` forms `e2 · ((o − v0) × e1)`, up to |o − v0|·|e1|·|e2| (and a shadow ray's determinant
//! likewise, with the segment's length). In 32-bit floats such a product overflows above
//! about 3.4e38, and then rays silently miss; far below 1, it sinks toward the subnormal range
//! and loses the precision that decides hits. So a world keeps
//! - its vertices within ±[`MAX_COORDINATE`] (then any triangle's products among its own
//!   points stay near 1e37 at the most),
//! - every ray origin (a camera, a light's points) within [`MAX_REACH`] of the triangles, as
//!   distance × (longest edge)², and
//! - an extent (triangles and cameras) of at least [`MIN_EXTENT`].
//!
//! Measured on a room scaled by powers of ten: from 1e-9 to 1e12 every pixel equals the
//! unscaled image to 3e-7; at 1e13 camera rays miss everything, at 1e-12 pixels differ by up
//! to 0.03 and at 1e-15 by 0.8.

use glam::Vec3;

use crate::geometry::Geometry;
use crate::light::Light;
use crate::math::Aabb;

/// The largest coordinate magnitude of a world's vertices.
pub const MAX_COORDINATE: f32 = 1e12;

/// The largest distance × (longest edge)² between a ray origin and the world's triangles.
pub const MAX_REACH: f32 = 1e38;

/// The smallest extent of a scene's triangles and cameras together.
pub const MIN_EXTENT: f32 = 1e-9;

/// What leaves the exact scales, for a message at its key.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Problem {
    /// The camera of that name, with its distance × (longest edge)².
    Camera(String, f32),
    /// The light of that index, likewise.
    Light(usize, f32),
    /// The extent of the triangles and cameras.
    Tiny(f32),
}

impl std::fmt::Display for Problem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Problem::Camera(_, product) | Problem::Light(_, product) => write!(
                f,
                "too far from the scene for the size of its triangles: distance × (longest \
                 edge)² is {product:e}, beyond {MAX_REACH:e}, where 32-bit ray-triangle \
                 products overflow and rays would miss: bring it closer, or scale the scene \
                 down"
            ),
            Problem::Tiny(extent) => write!(
                f,
                "the scene is {extent:e} units across (its objects and cameras); penumbra \
                 renders scenes at least {MIN_EXTENT:e} across (below, its 32-bit \
                 ray-triangle products lose their precision): scale the scene up"
            ),
        }
    }
}

/// The largest coordinate magnitude of `points` (NaN counts as nothing).
pub(crate) fn largest_coordinate(points: &[Vec3]) -> f32 {
    points
        .iter()
        .map(|p| p.abs().max_element())
        .fold(0.0, f32::max)
}

/// The longest edge of `triangles` (0 for none).
pub(crate) fn longest_edge(triangles: impl Iterator<Item = [Vec3; 3]>) -> f32 {
    triangles
        .map(|[a, b, c]| (b - a).length().max((c - a).length()).max((c - b).length()))
        .fold(0.0, f32::max)
}

/// The points a light's shadow rays end at: an area light's corners (the hull of its
/// samples), a point or spot light's position; none for an environment or a sun.
pub(crate) fn light_points(light: &Light) -> impl Iterator<Item = Vec3> {
    let points = match light {
        Light::Area(a) => Some([a.u + a.v, a.u - a.v, a.v - a.u, -a.u - a.v].map(|d| a.center + d)),
        Light::Point(p) => Some([p.position; 4]),
        // Shadow rays toward an environment or a sun end outside the scene's bounds (see the
        // integrator), never at a point of the file.
        Light::Environment(_) | Light::Directional(_) => None,
        Light::Spot(s) => Some([s.position; 4]),
    };
    points.into_iter().flatten()
}

/// The bounds and longest edge of a world's triangles.
pub(crate) struct Reach {
    pub(crate) bounds: Aabb,
    longest_edge: f32,
}

impl Reach {
    pub(crate) fn of(geometry: &Geometry) -> Reach {
        Reach {
            bounds: geometry.bounds(),
            longest_edge: longest_edge((0..geometry.len()).map(|i| geometry.corners(i))),
        }
    }

    /// The reach of these triangles and more within `bounds` whose edges are at most
    /// `longest_edge` long.
    pub(crate) fn with(self, bounds: Aabb, longest_edge: f32) -> Reach {
        Reach {
            bounds: self.bounds.union(bounds),
            longest_edge: self.longest_edge.max(longest_edge),
        }
    }

    /// The distance from `origin` to the farthest corner of the triangles' bounds, times the
    /// longest edge squared (in f64, so that the product itself cannot overflow).
    pub(crate) fn product(&self, origin: Vec3) -> f32 {
        let far = (origin - self.bounds.min)
            .abs()
            .max((origin - self.bounds.max).abs());
        let edge = self.longest_edge as f64;
        (far.as_dvec3().length() * edge * edge) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Mesh;
    use crate::math::Transform;

    fn unit_triangle_at(scale: f32) -> Geometry {
        let mesh = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X * scale, Vec3::Y * scale],
            indices: vec![[0, 1, 2]],
            ..Mesh::default()
        };
        let mut g = Geometry::default();
        g.append(&mesh, &Transform::IDENTITY, &[0], 0);
        g
    }

    #[test]
    fn reach_is_distance_times_the_longest_edge_squared() {
        let reach = Reach::of(&unit_triangle_at(2.0));
        // Longest edge: the hypotenuse, 2√2; farthest corner from (0, 0, 10): (2, 2, 0).
        let expected = (4.0f32 + 4.0 + 100.0).sqrt() * 8.0;
        assert!((reach.product(Vec3::new(0.0, 0.0, 10.0)) - expected).abs() < 1e-3);
        // A camera 1e20 away from a small triangle is fine; one 1e15 away from a 1e12 one is not.
        assert!(reach.product(Vec3::splat(1e20)) < MAX_REACH);
        let big = Reach::of(&unit_triangle_at(1e12));
        assert!(big.product(Vec3::splat(1e15)) > MAX_REACH);
        assert!(big.product(Vec3::splat(1e12)) < MAX_REACH);
    }
}
