//! The memory a scene may take, checked as it is built: a scene whose triangles (with their
//! BVH) or decoded textures would not fit is refused at the object or texture that does not
//! fit, with exit code 2, rather than aborting the process on a failed allocation.

use std::path::Path;

use super::{Builder, Result};
use crate::scene::error::KeyPath;
use crate::scene::error::{AssetKind, ErrorKind};

/// Memory a triangle takes at the peak of building the world: its share of the vertex and
/// index buffers, the BVH and the BVH build's temporaries (measured: about 175 bytes).
pub(super) const BYTES_PER_TRIANGLE: u64 = 200;

/// Memory an instance takes at the peak of building the world: its transform twice (for
/// shading and for the walk), its share of the top-level tree and of that tree's build.
pub(super) const BYTES_PER_INSTANCE: u64 = 512;

/// Memory a decoded texel keeps: linear float RGB.
pub(super) const BYTES_PER_TEXEL: u64 = 12;

/// Memory reading an OBJ file takes per byte of it, at most: the text itself and what it is
/// parsed into (a `v` or `f` line of 8 bytes becomes 12 bytes of vertex or indices and more).
pub(super) const OBJ_BYTES_PER_FILE_BYTE: u64 = 6;

/// What the scene may take and what it takes so far.
pub(super) struct Budget {
    /// Bytes the process could allocate when building began; `None` when unknown.
    pub(super) available: Option<u64>,
    /// Triangles added so far.
    pub(super) triangles: u64,
    /// Instances added so far.
    pub(super) instances: u64,
    /// Bytes of the textures decoded so far.
    pub(super) texture_bytes: u64,
}

impl Budget {
    pub(super) fn new(available: Option<u64>) -> Budget {
        Budget {
            available,
            triangles: 0,
            instances: 0,
            texture_bytes: 0,
        }
    }

    /// Bytes the scene takes so far.
    fn used(&self) -> u64 {
        self.triangles * BYTES_PER_TRIANGLE
            + self.instances * BYTES_PER_INSTANCE
            + self.texture_bytes
    }

    /// Bytes still free for a texture's decoding, if known.
    pub(super) fn left(&self) -> Option<u64> {
        let used = self.used();
        self.available.map(|a| a.saturating_sub(used))
    }
}

impl Builder<'_> {
    /// Counts the `triangles` of the object at `path`, refusing it when the scene's
    /// triangles would no longer fit in memory.
    pub(super) fn take_triangles(&mut self, path: &KeyPath, triangles: usize) -> Result<()> {
        let budget = &mut self.budget;
        let total = budget.triangles + triangles as u64;
        let need = budget.used() + triangles as u64 * BYTES_PER_TRIANGLE;
        if let Some(available) = budget.available.filter(|&a| need > a) {
            return Err(self.bad(
                path,
                format!(
                    "this object brings the scene to {total} triangles, which need about {} of \
                     memory with their BVH, more than the {} available",
                    crate::memory::human(need),
                    crate::memory::human(available)
                ),
            ));
        }
        budget.triangles = total;
        Ok(())
    }

    /// Counts one instance of the object at `path`, refusing it when it would no longer fit
    /// in memory.
    pub(super) fn take_instance(&mut self, path: &KeyPath) -> Result<()> {
        let need = self.budget.used() + BYTES_PER_INSTANCE;
        if let Some(available) = self.budget.available.filter(|&a| need > a) {
            return Err(self.bad(
                path,
                format!(
                    "this instance brings the scene to {} instances, which need about {} of \
                     memory, more than the {} available",
                    self.budget.instances + 1,
                    crate::memory::human(need),
                    crate::memory::human(available)
                ),
            ));
        }
        self.budget.instances += 1;
        Ok(())
    }

    /// Refuses the OBJ `file` (named at `path`) when reading it would not fit in memory; a
    /// file that cannot be examined is left for the reader to report.
    pub(super) fn check_obj_size(&self, path: &KeyPath, file: &Path) -> Result<()> {
        let Some(size) = self.file.files().size(file) else {
            return Ok(());
        };
        let need = size.saturating_mul(OBJ_BYTES_PER_FILE_BYTE);
        match self.budget.left().filter(|&left| need > left) {
            None => Ok(()),
            Some(left) => Err(self.err(
                ErrorKind::Asset(AssetKind::Mesh),
                path,
                format!(
                    "cannot load mesh \"{}\": reading this {} file needs about {} of memory, \
                     more than the {} available",
                    file.display(),
                    crate::memory::human(size),
                    crate::memory::human(need),
                    crate::memory::human(left)
                ),
            )),
        }
    }
}
