//! Indexed triangle storage: per-object meshes as shapes and OBJ files produce them, and the
//! scene-wide [`Geometry`] they are transformed into.

use glam::{Vec2, Vec3};

use crate::math::{Aabb, Rgb, Transform};

/// An indexed triangle mesh in its own (object) space, as a shape or an OBJ file makes it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals, or empty for flat (geometric-normal) shading.
    pub normals: Vec<Vec3>,
    /// Per-vertex texture coordinates; empty means (0, 0) everywhere.
    pub uvs: Vec<Vec2>,
    /// Per-vertex colours, linear RGB (finite; 1 is white), which multiply the material's
    /// diffuse and ambient colours; empty (or not one per vertex) means none, white.
    pub colors: Vec<Rgb>,
    /// Vertex index triples, one per triangle.
    pub indices: Vec<[u32; 3]>,
    /// Per-triangle material slot, local to the mesh (an index into the object's material
    /// list); empty means slot 0 for every triangle.
    pub material_slots: Vec<u32>,
}

impl Mesh {
    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    /// True when the mesh has no triangles.
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// True when every vertex has a shading normal to interpolate.
    pub fn is_smooth(&self) -> bool {
        !self.normals.is_empty() && self.normals.len() == self.positions.len()
    }

    /// True when every vertex has texture coordinates (else they are (0, 0) everywhere).
    pub fn has_uvs(&self) -> bool {
        self.uvs.len() == self.positions.len()
    }

    /// True when every vertex has a colour (else the mesh is uncoloured: white).
    pub fn has_colors(&self) -> bool {
        !self.colors.is_empty() && self.colors.len() == self.positions.len()
    }

    /// The material slot of triangle `i`.
    pub fn slot(&self, i: usize) -> u32 {
        self.material_slots.get(i).copied().unwrap_or(0)
    }
}

/// The material of slot `slot` for an object whose slots map to `materials`: slots past the
/// end take the last entry, and no entries means the default material, 0.
pub(crate) fn material_of(slot: u32, materials: &[u32]) -> u32 {
    let fallback = materials.last().copied().unwrap_or(0);
    materials.get(slot as usize).copied().unwrap_or(fallback)
}

/// One triangle of the built scene: three indices into [`Geometry`]'s vertex buffers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Triangle {
    /// Indices of the three vertices.
    pub vertices: [u32; 3],
    /// Index into the scene's material table.
    pub material: u32,
    /// Index of the object (scene-file entry or mesh added to a world) it came from.
    pub object: u32,
    /// True when the vertices carry shading normals to interpolate.
    pub smooth: bool,
}

/// Every triangle of a scene, in world space, with shared vertex buffers. Immutable once built.
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    /// World-space vertex positions.
    pub positions: Vec<Vec3>,
    /// World-space unit normals, one per vertex (zero where a vertex has none).
    pub normals: Vec<Vec3>,
    /// Texture coordinates, one per vertex.
    pub uvs: Vec<Vec2>,
    /// Linear RGB colours, one per vertex (white where a mesh has none), or empty when no
    /// mesh appended so far has colours: scenes without them pay no memory for them.
    pub colors: Vec<Rgb>,
    /// The triangles.
    pub triangles: Vec<Triangle>,
}

impl Geometry {
    /// Appends `mesh` transformed to world space as object `object`. Its material slot `k`
    /// becomes the scene material `materials[k]` (slots past the end use the last entry).
    pub fn append(&mut self, mesh: &Mesh, world: &Transform, materials: &[u32], object: u32) {
        let base = self.positions.len() as u32;
        let smooth = mesh.is_smooth();
        self.positions
            .extend(mesh.positions.iter().map(|&p| world.point(p)));
        if smooth {
            self.normals
                .extend(mesh.normals.iter().map(|&n| world.normal(n)));
        } else {
            self.normals
                .extend(std::iter::repeat_n(Vec3::ZERO, mesh.positions.len()));
        }
        if mesh.has_uvs() {
            self.uvs.extend_from_slice(&mesh.uvs);
        } else {
            self.uvs
                .extend(std::iter::repeat_n(Vec2::ZERO, mesh.positions.len()));
        }
        self.append_colors(mesh, base as usize);
        for (i, idx) in mesh.indices.iter().enumerate() {
            self.triangles.push(Triangle {
                vertices: idx.map(|v| base + v),
                material: material_of(mesh.slot(i), materials),
                object,
                smooth,
            });
        }
    }

    /// Appends `mesh`'s vertex colours, whose first vertex is `base`: white for an uncoloured
    /// mesh once some mesh has colours, and white for every earlier vertex when the first
    /// coloured mesh arrives.
    fn append_colors(&mut self, mesh: &Mesh, base: usize) {
        if mesh.has_colors() {
            self.colors.resize(base, Rgb::ONE);
            self.colors.extend_from_slice(&mesh.colors);
        } else if !self.colors.is_empty() {
            self.colors
                .extend(std::iter::repeat_n(Rgb::ONE, mesh.positions.len()));
        }
    }

    /// Drops every vertex from `vertices` on and every triangle from `triangles` on.
    pub(crate) fn truncate(&mut self, vertices: usize, triangles: usize) {
        self.positions.truncate(vertices);
        self.normals.truncate(vertices);
        self.uvs.truncate(vertices);
        self.colors.truncate(vertices);
        self.triangles.truncate(triangles);
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// True when there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The three corner positions of triangle `i`.
    pub fn corners(&self, i: usize) -> [Vec3; 3] {
        self.triangles[i]
            .vertices
            .map(|v| self.positions[v as usize])
    }

    /// Bounds of every vertex used by a triangle.
    pub fn bounds(&self) -> Aabb {
        (0..self.len())
            .flat_map(|i| self.corners(i))
            .fold(Aabb::EMPTY, Aabb::grow)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle(colors: Vec<Rgb>) -> Mesh {
        Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            colors,
            indices: vec![[0, 1, 2]],
            ..Mesh::default()
        }
    }

    #[test]
    fn colours_take_memory_only_once_a_mesh_has_them() {
        let mut g = Geometry::default();
        g.append(&triangle(Vec::new()), &Transform::IDENTITY, &[0], 0);
        // Colours not one per vertex are no colours.
        g.append(&triangle(vec![Rgb::X]), &Transform::IDENTITY, &[0], 1);
        assert!(g.colors.is_empty());
        let red = vec![Rgb::X; 3];
        g.append(&triangle(red.clone()), &Transform::IDENTITY, &[0], 2);
        g.append(&triangle(Vec::new()), &Transform::IDENTITY, &[0], 3);
        let white = vec![Rgb::ONE; 6];
        assert_eq!(g.colors, [white.clone(), red, white[..3].to_vec()].concat());
        g.truncate(6, 2);
        assert_eq!(g.colors, white);
    }
}
