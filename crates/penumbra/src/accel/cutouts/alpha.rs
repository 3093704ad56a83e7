//! The alpha test as the engine asks it: for a hit of a cut-out triangle (one of the world's
//! own, or one of an instance's mesh), its material's [`Cutout`] at the hit's uv. The engine
//! keeps copies of what the test reads (the cut-out materials with their textures, the
//! triangles' corner uvs and material slots), so that it answers without the world. Ray
//! casting's scene built from a world asks the same tests of its triangles (see
//! `raycast::instances`).

use glam::Vec2;

use crate::geometry::{Geometry, Mesh};
use crate::material::{interpolate_uv, Cutout, Material};
use crate::texture::Texture;

/// No test: the hit is kept.
const OPAQUE: u32 = u32::MAX;

/// Everything the alpha test of a cut-out hit reads.
#[derive(Clone, Debug, Default)]
pub(crate) struct AlphaTests {
    /// Each cut-out material's cut-out and texture.
    tests: Vec<(Cutout, Option<Texture>)>,
    /// Each material's test, or [`OPAQUE`].
    by_material: Vec<u32>,
    /// Each of the world's own cut-out triangles (in the cut-out tree's numbering): its
    /// corners' uvs and its test.
    flat: Vec<([Vec2; 3], u32)>,
    /// Each mesh's corner uvs by triangle, for the meshes a cut-out instance places (empty
    /// for the others).
    mesh_uvs: Vec<Vec<[Vec2; 3]>>,
    /// Each mesh's material slots (empty: slot 0 for every triangle).
    mesh_slots: Vec<Vec<u32>>,
    /// Each cut-out instance (in the cut-out set's numbering): its mesh, and its materials
    /// by slot as tests (slots past the end take the last; none: the default material).
    instances: Vec<(u32, Vec<u32>)>,
}

impl AlphaTests {
    /// The tests of `materials` (with `textures`): `None` when no material may cut.
    pub(crate) fn of(materials: &[Material], textures: &[Texture]) -> Option<AlphaTests> {
        let mut tests = Vec::new();
        let by_material = materials
            .iter()
            .map(|m| match m.cutout.filter(Cutout::may_cut) {
                Some(cutout) => {
                    let texture = cutout.texture.and_then(|t| textures.get(t as usize));
                    tests.push((cutout, texture.cloned()));
                    tests.len() as u32 - 1
                }
                None => OPAQUE,
            })
            .collect();
        (!tests.is_empty()).then_some(AlphaTests {
            tests,
            by_material,
            ..AlphaTests::default()
        })
    }

    /// True when material `material` may cut.
    pub(super) fn cuts(&self, material: u32) -> bool {
        self.by_material
            .get(material as usize)
            .is_some_and(|&t| t != OPAQUE)
    }

    /// Adds the world's own triangle `triangle` of `geometry` as the next triangle.
    pub(crate) fn push_flat(&mut self, geometry: &Geometry, triangle: usize) {
        let t = &geometry.triangles[triangle];
        let uv = t.vertices.map(|v| geometry.uvs[v as usize]);
        self.push_triangle(uv, t.material);
    }

    /// Adds a triangle with corner uvs `uv` and material `material` as the next one (a
    /// material that is not one of the world's is opaque).
    pub(crate) fn push_triangle(&mut self, uv: [Vec2; 3], material: u32) {
        let test = self.by_material.get(material as usize).copied();
        self.flat.push((uv, test.unwrap_or(OPAQUE)));
    }

    /// The tests of triangles `triangles` (by index), numbered from 0 in that order: a
    /// geometry's own tests for a tree of its own.
    pub(crate) fn subset(&self, triangles: impl Iterator<Item = usize>) -> AlphaTests {
        AlphaTests {
            tests: self.tests.clone(),
            by_material: self.by_material.clone(),
            flat: triangles.map(|i| self.flat[i]).collect(),
            ..AlphaTests::default()
        }
    }

    /// True when some triangle added may be cut.
    pub(crate) fn any_triangle_cuts(&self) -> bool {
        self.flat.iter().any(|&(_, test)| test != OPAQUE)
    }

    /// Adds an instance of `meshes[mesh]` whose slots map to `materials` as the next cut-out
    /// instance, copying its mesh's uvs and slots on first use.
    pub(super) fn push_instance(&mut self, meshes: &[Mesh], mesh: u32, materials: &[u32]) {
        if self.mesh_uvs.is_empty() {
            self.mesh_uvs = vec![Vec::new(); meshes.len()];
            self.mesh_slots = vec![Vec::new(); meshes.len()];
        }
        let m = &meshes[mesh as usize];
        if self.mesh_uvs[mesh as usize].is_empty() {
            self.mesh_uvs[mesh as usize] = m
                .indices
                .iter()
                .map(|t| match m.has_uvs() {
                    true => t.map(|v| m.uvs[v as usize]),
                    false => [Vec2::ZERO; 3],
                })
                .collect();
            self.mesh_slots[mesh as usize] = (0..m.len()).map(|i| m.slot(i)).collect();
        }
        let tests = match materials {
            [] => vec![self.by_material[0]],
            _ => materials
                .iter()
                .map(|&m| self.by_material[m as usize])
                .collect(),
        };
        self.instances.push((mesh, tests));
    }

    /// True when the instance materials `materials` (an instance's, by slot) may cut.
    pub(super) fn instance_cuts(&self, materials: &[u32]) -> bool {
        match materials {
            [] => self.cuts(0),
            _ => materials.iter().any(|&m| self.cuts(m)),
        }
    }

    /// Whether the hit at barycentrics `(b1, b2)` of the world's own cut-out triangle `local`
    /// is kept.
    #[inline]
    pub(crate) fn keeps_flat(&self, local: u32, b1: f32, b2: f32) -> bool {
        let (uv, test) = self.flat[local as usize];
        self.keeps(test, uv, b1, b2)
    }

    /// Whether the hit at barycentrics `(b1, b2)` of triangle `triangle` of cut-out instance
    /// `placement`'s mesh is kept.
    #[inline]
    pub(super) fn keeps_instance(&self, placement: u32, triangle: u32, b1: f32, b2: f32) -> bool {
        let (mesh, tests) = &self.instances[placement as usize];
        let slots = &self.mesh_slots[*mesh as usize];
        let slot = slots.get(triangle as usize).copied().unwrap_or(0) as usize;
        let test = tests[slot.min(tests.len() - 1)];
        let uv = self.mesh_uvs[*mesh as usize][triangle as usize];
        self.keeps(test, uv, b1, b2)
    }

    /// The one alpha test of every query: [`Cutout::keeps`] at the uv the barycentrics
    /// interpolate.
    #[inline]
    fn keeps(&self, test: u32, uv: [Vec2; 3], b1: f32, b2: f32) -> bool {
        match self.tests.get(test as usize) {
            None => true,
            Some((cutout, texture)) => cutout.keeps(texture.as_ref(), interpolate_uv(uv, b1, b2)),
        }
    }
}
