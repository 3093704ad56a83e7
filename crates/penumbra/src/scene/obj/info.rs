//! What a Wavefront OBJ file holds, read on its own (no scene): its size, bounds, materials
//! and textures, and whether it is closed. For `penumbra check model.obj`.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use crate::geometry::Mesh;
use crate::math::Aabb;

use super::{load_obj, mtl, parse_obj, Library, ObjModel};
use crate::files::Files;

/// A summary of an OBJ (or PLY) file, in its own (object) space.
#[derive(Clone, Debug)]
pub struct ObjInfo {
    /// Triangles after fan triangulation of its faces.
    pub triangles: usize,
    /// Distinct vertices (position, normal, uv triples) of the mesh.
    pub vertices: usize,
    /// Bounds of every vertex a triangle uses.
    pub bounds: Aabb,
    /// Whether it has vertex normals (`vn`) and texture coordinates (`vt`).
    pub normals: bool,
    /// See `normals`.
    pub uvs: bool,
    /// Whether every vertex has a colour (OBJ `v x y z r g b`; PLY `red`, `green`, `blue`).
    pub colors: bool,
    /// The materials of its MTL libraries, in order, each with its `map_Kd` texture.
    pub materials: Vec<(String, Option<PathBuf>)>,
    /// True when every edge is shared by exactly two triangles (vertices matched by position):
    /// a closed surface, such as a watertight model.
    pub closed: bool,
    /// What the file holds that penumbra reads but ignores, each named once (PLY files).
    pub warnings: Vec<String>,
}

/// Reads the OBJ file at `path` (and its MTL libraries, not its textures) and summarizes it.
/// The error says what is wrong, with the line.
pub fn inspect_obj(path: &Path) -> Result<ObjInfo, String> {
    inspect_obj_in(&Files::disk(), path)
}

/// [`inspect_obj`] reading through `files` (with the folders it allows besides the file's).
pub fn inspect_obj_in(files: &Files, path: &Path) -> Result<ObjInfo, String> {
    Ok(summarize(&load_obj(files, path, None)?))
}

/// [`inspect_obj`] for the bytes of an OBJ file, whose `mtllib` names are relative to `dir`.
pub fn inspect_obj_bytes(bytes: &[u8], dir: &Path) -> Result<ObjInfo, String> {
    let library = Library::new(Files::disk(), dir, dir);
    Ok(summarize(&parse_obj(bytes, dir, library, None)?))
}

/// The materials the bytes of an MTL file define, in order, each with its `map_Kd` texture
/// resolved against the folder of `path` (which names the file in messages). The textures are
/// not read.
pub fn inspect_mtl(bytes: &[u8], path: &Path) -> Result<Vec<(String, Option<PathBuf>)>, String> {
    Ok(mtl::parse_bytes(bytes, path)?
        .materials()
        .iter()
        .map(|m| (m.name.clone(), m.diffuse_texture.clone()))
        .collect())
}

/// The bounds of the OBJ file at `path` (read as [`inspect_obj`] reads it): all a model's
/// scene needs, without the rest of the summary (closedness costs a sort of every edge).
pub(in crate::scene) fn obj_bounds(files: &Files, path: &Path) -> Result<Aabb, String> {
    Ok(mesh_bounds(&load_obj(files, path, None)?.mesh))
}

/// Bounds of every vertex a triangle of `mesh` uses.
pub(in crate::scene) fn mesh_bounds(mesh: &Mesh) -> Aabb {
    mesh.indices
        .iter()
        .flatten()
        .fold(Aabb::EMPTY, |b, &i| b.grow(mesh.positions[i as usize]))
}

/// The summary of a mesh file's model (also a PLY file's, without materials).
pub(in crate::scene) fn summarize(model: &ObjModel) -> ObjInfo {
    let mesh = &model.mesh;
    let bounds = mesh_bounds(mesh);
    ObjInfo {
        triangles: mesh.indices.len(),
        vertices: mesh.positions.len(),
        bounds,
        normals: !mesh.normals.is_empty(),
        uvs: !mesh.uvs.is_empty(),
        colors: mesh.has_colors(),
        materials: model
            .materials
            .iter()
            .map(|m| (m.name.clone(), m.diffuse_texture.clone()))
            .collect(),
        closed: is_closed(mesh),
        warnings: Vec::new(),
    }
}

/// Every edge shared by exactly two triangles, vertices compared by position (an OBJ splits a
/// position into several vertices where normals or uvs differ). Each distinct position gets
/// an id, each edge a sorted pair of ids packed in a `u64`; sorted, every run has length 2.
fn is_closed(mesh: &Mesh) -> bool {
    if mesh.indices.is_empty() {
        return false;
    }
    let mut ids: HashMap<[u32; 3], u32> = HashMap::with_capacity(mesh.positions.len());
    let id: Vec<u32> = mesh
        .positions
        .iter()
        .map(|p| {
            let next = ids.len() as u32;
            *ids.entry(p.to_array().map(f32::to_bits)).or_insert(next)
        })
        .collect();
    let mut edges: Vec<u64> = Vec::with_capacity(3 * mesh.indices.len());
    for tri in &mesh.indices {
        for k in 0..3 {
            let (a, b) = (id[tri[k] as usize], id[tri[(k + 1) % 3] as usize]);
            edges.push(u64::from(a.min(b)) << 32 | u64::from(a.max(b)));
        }
    }
    edges.sort_unstable();
    edges.chunk_by(|a, b| a == b).all(|run| run.len() == 2)
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    fn mesh(positions: &[[f32; 3]], indices: &[[u32; 3]]) -> Mesh {
        Mesh {
            positions: positions.iter().map(|&p| Vec3::from(p)).collect(),
            indices: indices.to_vec(),
            ..Mesh::default()
        }
    }

    #[test]
    fn a_tetrahedron_is_closed_and_a_triangle_is_not() {
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let tetra = mesh(&p, &[[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]);
        assert!(is_closed(&tetra));
        assert!(!is_closed(&mesh(&p, &[[0, 1, 2]])));
        assert!(!is_closed(&mesh(&p, &[])));
        // The same position under two indices (split by uvs) still closes the surface.
        let mut split = p.to_vec();
        split.push([0.0, 0.0, 0.0]);
        let tetra = mesh(&split, &[[4, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]);
        assert!(is_closed(&tetra));
    }

    #[test]
    fn obj_and_mtl_bytes_are_read_as_their_files_are() {
        let obj =
            b"mtllib missing.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 2\nvt 0 0\nf 1 3 2\nf 1/1 2 4\n";
        let e = inspect_obj_bytes(obj, Path::new("/nonexistent")).unwrap_err();
        assert!(e.contains("missing.mtl"), "{e}");
        let info = inspect_obj_bytes(&obj[19..], Path::new("")).unwrap();
        assert_eq!((info.triangles, info.uvs, info.normals), (2, true, false));
        assert_eq!(info.bounds.max, Vec3::new(1.0, 1.0, 2.0));
        let e = inspect_obj_bytes(b"v 0 0 0\n", Path::new("")).unwrap_err();
        assert!(e.contains("no faces"), "{e}");

        let mtl = b"newmtl a\nKd 1 0 0\nnewmtl b\nmap_Kd -s 2 2 1 t.png\n";
        let materials = inspect_mtl(mtl, Path::new("lib/x.mtl")).unwrap();
        assert_eq!(
            materials,
            [
                ("a".to_owned(), None),
                ("b".to_owned(), Some(PathBuf::from("lib/t.png")))
            ]
        );
        let e = inspect_mtl(b"newmtl a\nKd red\n", Path::new("x.mtl")).unwrap_err();
        assert!(e.contains("x.mtl") && e.contains("line 2"), "{e}");
    }
}
