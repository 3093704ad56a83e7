//! Triangles and the meshes they live in. Every object of a scene becomes triangles here:
//! the ray–triangle test, indexed mesh storage, and the built-in shapes (quad, cube, sphere).

mod mesh;
mod shapes;
mod triangle;

pub use mesh::{Geometry, Mesh, Triangle};
pub use shapes::{cube, quad, sphere, triangle, SPHERE_RINGS, SPHERE_SEGMENTS};
pub use triangle::{intersect_triangle, Hit, TriangleHit};
