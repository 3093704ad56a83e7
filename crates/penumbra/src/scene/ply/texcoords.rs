//! Per-face texture coordinates (MeshLab's and VCGlib's `texcoord` lists) as per-vertex uvs:
//! a vertex whose faces give it different coordinates is split into one vertex per
//! coordinate, as an OBJ file's `v/vt` pairs are.

use std::collections::HashMap;

use glam::Vec2;

use crate::geometry::Mesh;

/// Gives `mesh` one uv per vertex from `texcoords` (each triangle's corner coordinates,
/// parallel to its triangles): each distinct (vertex, uv) pair becomes a vertex, numbered in
/// the order the triangles first use it, with the original vertex's other attributes.
/// Vertices no triangle uses are dropped.
pub(super) fn split_vertices(mesh: &mut Mesh, texcoords: &[[Vec2; 3]]) {
    let mut index: HashMap<(u32, [u32; 2]), u32> = HashMap::with_capacity(mesh.positions.len());
    let mut from: Vec<u32> = Vec::with_capacity(mesh.positions.len());
    let mut uvs: Vec<Vec2> = Vec::with_capacity(mesh.positions.len());
    for (tri, corner_uvs) in mesh.indices.iter_mut().zip(texcoords) {
        for (v, uv) in tri.iter_mut().zip(corner_uvs) {
            let key = (*v, uv.to_array().map(f32::to_bits));
            *v = *index.entry(key).or_insert_with(|| {
                from.push(*v);
                uvs.push(*uv);
                from.len() as u32 - 1
            });
        }
    }
    mesh.positions = gather(&from, &mesh.positions);
    if !mesh.normals.is_empty() {
        mesh.normals = gather(&from, &mesh.normals);
    }
    if !mesh.colors.is_empty() {
        mesh.colors = gather(&from, &mesh.colors);
    }
    mesh.uvs = uvs;
}

/// `values[i]` for each `i` of `from`.
fn gather<T: Copy>(from: &[u32], values: &[T]) -> Vec<T> {
    from.iter().map(|&v| values[v as usize]).collect()
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn a_vertex_with_two_coordinates_becomes_two_vertices() {
        // Two triangles share the edge 0–2; vertex 2 has one uv, vertex 0 two; no triangle
        // uses vertex 4.
        let mut mesh = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE],
            colors: vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE, Vec3::ZERO],
            indices: vec![[0, 1, 2], [0, 2, 3]],
            ..Mesh::default()
        };
        let (a, b, c, d) = (Vec2::ZERO, Vec2::X, Vec2::Y, Vec2::ONE);
        split_vertices(&mut mesh, &[[a, b, c], [d, c, a]]);
        assert_eq!(mesh.indices, [[0, 1, 2], [3, 2, 4]]);
        assert_eq!(mesh.uvs, [a, b, c, d, a]);
        assert_eq!(
            mesh.positions,
            [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ZERO, Vec3::Z]
        );
        assert_eq!(mesh.colors, [Vec3::X, Vec3::Y, Vec3::Z, Vec3::X, Vec3::ONE]);
    }
}
