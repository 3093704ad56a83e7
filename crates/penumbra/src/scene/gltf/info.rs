//! What a glTF file holds, read on its own (no scene): for `penumbra check model.glb` and for
//! framing a bare model. Images are located, not decoded.

use std::path::Path;

use super::{load_gltf, parse_gltf, GltfModel};
use crate::files::Files;
use crate::math::Aabb;

/// A summary of a glTF file's chosen scene, in the file's space (node transforms applied).
#[derive(Clone, Debug, PartialEq)]
pub struct GltfInfo {
    /// Triangles as rays see them: each mesh counted once per node that uses it.
    pub triangles: usize,
    /// Triangles of the distinct meshes (each stored once).
    pub unique_triangles: usize,
    /// Vertices of the distinct meshes.
    pub vertices: usize,
    /// Bounds of every placed triangle, after the node transforms.
    pub bounds: Aabb,
    /// Distinct meshes the scene uses.
    pub meshes: usize,
    /// Nodes that place a mesh.
    pub instances: usize,
    /// Whether any mesh has normals and uvs.
    pub normals: bool,
    /// See `normals`.
    pub uvs: bool,
    /// The file's materials, by name.
    pub materials: Vec<String>,
    /// Images the used materials' base-colour textures need.
    pub textures: usize,
    /// The perspective cameras' names, in scene order.
    pub cameras: Vec<String>,
    /// Lights (point, spot and directional).
    pub lights: usize,
    /// The file's `extensionsUsed`.
    pub extensions: Vec<String>,
    /// What penumbra ignores of the file, one sentence each.
    pub warnings: Vec<String>,
}

/// Reads the glTF or GLB file at `path` and summarizes it. The error names the JSON path.
pub fn inspect_gltf(path: &Path) -> Result<GltfInfo, String> {
    inspect_gltf_in(&Files::disk(), path)
}

/// [`inspect_gltf`] reading through `files` (with the folders it allows besides the file's).
pub fn inspect_gltf_in(files: &Files, path: &Path) -> Result<GltfInfo, String> {
    let model = load_gltf(files, path, crate::memory::available()).map_err(|e| e.to_string())?;
    Ok(summarize(&model))
}

/// [`inspect_gltf`] for the bytes of a glTF or GLB file whose external files are relative to
/// `dir`, its geometry held to `max_bytes` of memory.
pub fn inspect_gltf_bytes(
    bytes: &[u8],
    dir: &Path,
    max_bytes: Option<u64>,
) -> Result<GltfInfo, String> {
    let model = parse_gltf(bytes, dir, &Files::disk(), max_bytes).map_err(|e| e.to_string())?;
    Ok(summarize(&model))
}

/// The summary of a read model.
pub(crate) fn summarize(model: &GltfModel) -> GltfInfo {
    let mut bounds = Aabb::EMPTY;
    let mut triangles = 0;
    for u in &model.uses {
        let mesh = &model.meshes[u.mesh].mesh;
        triangles += mesh.len();
        let used = mesh.indices.iter().flatten();
        bounds = used.fold(bounds, |b, &i| {
            b.grow(u.matrix.transform_point3(mesh.positions[i as usize]))
        });
    }
    GltfInfo {
        triangles,
        unique_triangles: model.meshes.iter().map(|m| m.mesh.len()).sum(),
        vertices: model.meshes.iter().map(|m| m.mesh.positions.len()).sum(),
        bounds,
        meshes: model.meshes.len(),
        instances: model.uses.len(),
        normals: model.meshes.iter().any(|m| !m.mesh.normals.is_empty()),
        uvs: model.meshes.iter().any(|m| !m.mesh.uvs.is_empty()),
        materials: model.materials.iter().map(|m| m.name.clone()).collect(),
        textures: model.images.iter().filter(|i| i.is_some()).count(),
        cameras: model.cameras.iter().map(|c| c.name.clone()).collect(),
        lights: model.lights.len(),
        extensions: model.extensions.clone(),
        warnings: model.warnings.clone(),
    }
}
