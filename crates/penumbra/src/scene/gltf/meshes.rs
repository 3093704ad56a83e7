//! Meshes: a glTF mesh's primitives merged into one object-space [`Mesh`], each primitive's
//! triangles in the material slot of its material.

use glam::{Vec2, Vec3};
use gltf::json::accessor::ComponentType;
use gltf::mesh::{Mode, Semantic};

use super::{GltfError, GltfMesh, Reader, Result};
use crate::geometry::Mesh;

/// Component types a float attribute may have: float, or normalized integers (checked by
/// the accessor's `normalized` flag where it matters).
fn any_type(_: ComponentType) -> bool {
    true
}

fn index_type(c: ComponentType) -> bool {
    matches!(
        c,
        ComponentType::U8 | ComponentType::U16 | ComponentType::U32
    )
}

impl Reader<'_> {
    /// The mesh `index`, its primitives merged.
    pub(super) fn mesh(&mut self, index: usize) -> Result<GltfMesh> {
        let doc = self.doc;
        let mesh = doc
            .meshes()
            .nth(index)
            .ok_or_else(|| GltfError::new(format!("meshes[{index}]"), "no such mesh"))?;
        let mut out = GltfMesh {
            mesh: Mesh::default(),
            materials: Vec::new(),
            name: mesh
                .name()
                .map_or_else(|| format!("meshes[{index}]"), str::to_owned),
        };
        let mut smooth = false;
        let mut colored = false;
        let mut normals = Vec::new();
        let mut colors: Vec<Vec3> = Vec::new();
        for (p, primitive) in mesh.primitives().enumerate() {
            let at = format!("meshes[{index}].primitives[{p}]");
            if !matches!(
                primitive.mode(),
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                self.ignored.note(
                    "{n} primitive(s) of points or lines are skipped (only triangles are rendered)",
                );
                continue;
            }
            if primitive.morph_targets().len() > 0 {
                self.ignored
                    .note("{n} primitive(s) have morph targets, ignored (the base shape is used)");
            }
            let slot = slot_of(&mut out.materials, primitive.material().index());
            let part = self.primitive(&primitive, &at)?;
            let base = out.mesh.positions.len();
            if base + part.positions.len() > u32::MAX as usize {
                return Err(GltfError::new(at, "the mesh has more than 2^32 vertices"));
            }
            smooth |= part.normals.is_some();
            colored |= part.colors.is_some();
            let nv = part.positions.len();
            normals.push((base, part.normals));
            out.mesh.positions.extend(part.positions);
            out.mesh
                .uvs
                .extend(part.uvs.unwrap_or_else(|| vec![Vec2::ZERO; nv]));
            if let Some(c) = part.colors {
                colors.resize(base, Vec3::ONE);
                colors.extend(c);
            }
            let b = base as u32;
            out.mesh
                .indices
                .extend(part.triangles.iter().map(|t| t.map(|i| i + b)));
            out.mesh
                .material_slots
                .extend(std::iter::repeat_n(slot, part.triangles.len()));
        }
        let nv = out.mesh.positions.len();
        if smooth {
            // A primitive without normals gets zeros: shaded with its geometric normal.
            out.mesh.normals = vec![Vec3::ZERO; nv];
            for (base, n) in normals {
                if let Some(n) = n {
                    out.mesh.normals[base..base + n.len()].copy_from_slice(&n);
                }
            }
        }
        if colored {
            // A primitive without COLOR_0 is white.
            colors.resize(nv, Vec3::ONE);
            out.mesh.colors = colors;
        }
        if !out.mesh.uvs.iter().any(|&uv| uv != Vec2::ZERO) {
            out.mesh.uvs.clear();
        }
        Ok(out)
    }

    /// One primitive's vertices and triangles.
    fn primitive(&mut self, primitive: &gltf::Primitive, at: &str) -> Result<Part> {
        let attr = |s: &str| format!("{at}.attributes.{s}");
        let position = primitive
            .get(&Semantic::Positions)
            .ok_or_else(|| GltfError::new(format!("{at}.attributes"), "no POSITION attribute"))?;
        let (p, _) = self.read::<f32>(position.index(), &attr("POSITION"), &[3], any_type)?;
        let positions: Vec<Vec3> = p.chunks_exact(3).map(Vec3::from_slice).collect();
        if let Some(k) = positions.iter().position(|p| !p.is_finite()) {
            return Err(GltfError::new(
                attr("POSITION"),
                format!("vertex {k} is not finite: {}", positions[k]),
            ));
        }
        let nv = positions.len();
        let same_count = |name: &str, len: usize| -> Result<()> {
            match len == nv {
                true => Ok(()),
                false => Err(GltfError::new(
                    attr(name),
                    format!("{len} values for {nv} vertices (POSITION's count)"),
                )),
            }
        };
        let normals = match primitive.get(&Semantic::Normals) {
            None => None,
            Some(a) => {
                let (n, _) = self.read::<f32>(a.index(), &attr("NORMAL"), &[3], any_type)?;
                same_count("NORMAL", n.len() / 3)?;
                // A normal that is not finite is read as none (zero): the geometric normal.
                let n = n.chunks_exact(3).map(Vec3::from_slice);
                Some(
                    n.map(|n| if n.is_finite() { n } else { Vec3::ZERO })
                        .collect(),
                )
            }
        };
        let set = self.tex_coord(primitive);
        let uvs = match primitive.get(&Semantic::TexCoords(set)) {
            None => None,
            Some(a) => {
                let name = format!("TEXCOORD_{set}");
                let (t, _) = self.read::<f32>(a.index(), &attr(&name), &[2], any_type)?;
                same_count(&name, t.len() / 2)?;
                // glTF's v runs down the image; penumbra's t runs up.
                let uv = |c: &[f32]| Vec2::new(c[0], 1.0 - c[1]);
                Some(t.chunks_exact(2).map(uv).collect())
            }
        };
        let extra_sets = primitive
            .attributes()
            .filter(|(s, _)| matches!(s, Semantic::TexCoords(k) if *k != set))
            .count();
        self.ignored.add(
            "{n} extra uv set(s) (TEXCOORD_n that no base-colour texture reads) are ignored",
            extra_sets,
        );
        let colors = match primitive.get(&Semantic::Colors(0)) {
            None => None,
            Some(a) => {
                let (c, n) = self.read::<f32>(a.index(), &attr("COLOR_0"), &[3, 4], any_type)?;
                same_count("COLOR_0", c.len() / n)?;
                // The colour multiplies the base colour; its alpha is not read. A value
                // that is not finite is read as white.
                let rgb = |c: &[f32]| Vec3::new(c[0], c[1], c[2]);
                let finite = |c: Vec3| if c.is_finite() { c } else { Vec3::ONE };
                Some(c.chunks_exact(n).map(|c| finite(rgb(c))).collect())
            }
        };
        let corners: Vec<u32> = match primitive.indices() {
            None => (0..nv as u32).collect(),
            Some(a) => {
                let (idx, _) =
                    self.read::<u32>(a.index(), &format!("{at}.indices"), &[1], index_type)?;
                if let Some(k) = idx.iter().position(|&i| i as usize >= nv) {
                    return Err(GltfError::new(
                        format!("{at}.indices"),
                        format!("index {k} is {}, past the {nv} vertices", idx[k]),
                    ));
                }
                idx
            }
        };
        Ok(Part {
            triangles: triangles(primitive.mode(), &corners),
            positions,
            normals,
            uvs,
            colors,
        })
    }

    /// The uv set the primitive's base-colour texture reads (0 without one).
    fn tex_coord(&self, primitive: &gltf::Primitive) -> u32 {
        let info = primitive
            .material()
            .pbr_metallic_roughness()
            .base_color_texture();
        info.map_or(0, |info| {
            info.texture_transform()
                .and_then(|t| t.tex_coord())
                .unwrap_or(info.tex_coord())
        })
    }
}

/// One primitive read: vertices and triangles over them.
struct Part {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    uvs: Option<Vec<Vec2>>,
    colors: Option<Vec<Vec3>>,
    triangles: Vec<[u32; 3]>,
}

/// The slot of glTF material `material` in a mesh's `materials`, added when new.
fn slot_of(materials: &mut Vec<Option<usize>>, material: Option<usize>) -> u32 {
    match materials.iter().position(|&m| m == material) {
        Some(k) => k as u32,
        None => {
            materials.push(material);
            materials.len() as u32 - 1
        }
    }
}

/// The triangles of `corners` (vertex indices) in primitive mode `mode`, as the glTF spec
/// assembles them (§3.7.2.1); a trailing partial triangle is dropped.
pub(super) fn triangles(mode: Mode, corners: &[u32]) -> Vec<[u32; 3]> {
    let n = corners.len();
    match mode {
        Mode::Triangles => corners
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect(),
        // p_i = {v_i, v_{i+(1+i%2)}, v_{i+(2−i%2)}}: every other triangle swaps two corners
        // so that all keep one winding.
        Mode::TriangleStrip => (0..n.saturating_sub(2))
            .map(|i| {
                let odd = i % 2;
                [corners[i], corners[i + 1 + odd], corners[i + 2 - odd]]
            })
            .collect(),
        // p_i = {v_{i+1}, v_{i+2}, v_0}.
        Mode::TriangleFan => (0..n.saturating_sub(2))
            .map(|i| [corners[i + 1], corners[i + 2], corners[0]])
            .collect(),
        _ => Vec::new(),
    }
}
