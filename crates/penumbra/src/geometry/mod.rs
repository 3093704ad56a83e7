//! Triangles and the meshes they live in. Every object of a scene becomes triangles here:
//! the [`Hit`] record of a ray–triangle test (the tests are in `accel::prim`), indexed mesh
//! storage, the built-in shapes (quad, cube, sphere), and the [`Surface`] at a hit.

mod mesh;
mod shapes;
mod surface;
mod triangle;

pub(crate) use mesh::material_of;
pub use mesh::{Geometry, Mesh, Triangle};
pub use shapes::{cube, quad, sphere, triangle, SPHERE_RINGS, SPHERE_SEGMENTS};
pub(crate) use surface::Facet;
pub use surface::Surface;
pub use triangle::{Hit, TriangleHit};
