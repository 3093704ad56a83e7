//! The alpha test as the engine asks it: for a hit of a cut-out triangle (one of the world's
//! own, or one of an instance's mesh), its material's [`Cutout`] at the hit's uv. A set of
//! tests belongs to one tree's triangles, in its numbering: the world's own cut-out
//! triangles, or a mesh's triangles under one placement's materials
//! ([`AlphaTests::of_placement`]). It keeps copies of what the test reads (the cut-out
//! materials with their textures, the triangles' corner uvs and tests), so that it answers
//! without the world. Ray casting's scene built from a world asks the same tests (see
//! `raycast::instances`).

use glam::Vec2;

use crate::geometry::{material_of, Geometry, Mesh};
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
    /// Each triangle of the tree the tests are for, in its numbering: its corners' uvs and
    /// its test (the world's own cut-out triangles, or a placed mesh's triangles under one
    /// placement's materials).
    flat: Vec<([Vec2; 3], u32)>,
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
        }
    }

    /// True when some triangle added may be cut.
    pub(crate) fn any_triangle_cuts(&self) -> bool {
        self.flat.iter().any(|&(_, test)| test != OPAQUE)
    }

    /// The tests of `mesh`'s triangles placed with `materials` (an instance's, by slot; see
    /// `material_of`), numbered as the mesh's: `None` when none may cut.
    pub(crate) fn of_placement(&self, mesh: &Mesh, materials: &[u32]) -> Option<AlphaTests> {
        let mut alpha = self.subset(std::iter::empty());
        for (i, t) in mesh.indices.iter().enumerate() {
            let uv = match mesh.has_uvs() {
                true => t.map(|v| mesh.uvs[v as usize]),
                false => Default::default(),
            };
            alpha.push_triangle(uv, material_of(mesh.slot(i), materials));
        }
        alpha.any_triangle_cuts().then_some(alpha)
    }

    /// True when the instance materials `materials` (an instance's, by slot) may cut.
    pub(super) fn instance_cuts(&self, materials: &[u32]) -> bool {
        match materials {
            [] => self.cuts(0),
            _ => materials.iter().any(|&m| self.cuts(m)),
        }
    }

    /// Whether the hit at barycentrics `(b1, b2)` of triangle `local` (in the tests'
    /// numbering) is kept. Out of line: it is asked only of a hit, and the walks it is
    /// passed to stay smaller without it.
    #[inline(never)]
    pub(crate) fn keeps_flat(&self, local: u32, b1: f32, b2: f32) -> bool {
        let (uv, test) = self.flat[local as usize];
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
