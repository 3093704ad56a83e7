//! An instance as the world keeps it for shading: which shared mesh, where, as which object,
//! with which materials.

use crate::math::Transform;

/// A shared mesh placed in the world.
#[derive(Clone, Debug)]
pub(crate) struct Placed {
    /// Index of the shared mesh.
    pub mesh: u32,
    /// Object-to-world transform.
    pub transform: Transform,
    /// The object id its hits report.
    pub object: u32,
    /// Its material slots' materials: `(first, count)` in the world's instance material list.
    pub materials: (u32, u32),
}
