//! Materials: what penumbra reads of each glTF material (base colour factor and texture with
//! its sampler and `KHR_texture_transform`, metallic and roughness factors, alpha mode)
//! and the images of the base-colour textures of the materials the placed
//! meshes use: only those images are looked for.

use glam::{Vec2, Vec4};
use gltf::material::AlphaMode as Mode;
use gltf::texture::{MagFilter, WrappingMode};

use super::container::READ_EXTENSIONS;
use super::{AlphaMode, GltfMaterial, GltfModel, Reader, Result, TextureRef};
use crate::texture::{Filter, Wrap};

impl Reader<'_> {
    /// Every material of the file into `model`; the images of those the meshes use.
    pub(super) fn materials(&mut self, model: &mut GltfModel) -> Result<()> {
        let doc = self.doc;
        let mut used = vec![false; doc.materials().len()];
        for m in &model.meshes {
            for &k in m.materials.iter().flatten() {
                if let Some(u) = used.get_mut(k) {
                    *u = true;
                }
            }
        }
        model.images = vec![None; doc.images().len()];
        for material in doc.materials() {
            let i = material.index().unwrap_or_default();
            let used = used.get(i).copied().unwrap_or(false);
            let m = self.material(&material, i);
            if used {
                self.note_ignored(&material);
                if m.alpha == AlphaMode::Blend {
                    self.ignored.note(
                        "{n} material(s) with alphaMode BLEND are read as cut-outs at alpha 0.5 \
                         (no partial transparency)",
                    );
                }
                if let Some(t) = &m.texture {
                    if model.images.get(t.image).is_some_and(Option::is_none) {
                        model.images[t.image] = Some(self.buffers.image(doc, t.image)?);
                    }
                }
            }
            model.materials.push(m);
        }
        for ext in &model.extensions {
            if !READ_EXTENSIONS.contains(&ext.as_str()) {
                self.ignored.note(extension_note(ext));
            }
        }
        Ok(())
    }

    /// What penumbra reads of `material` (glTF index `i`).
    fn material(&mut self, material: &gltf::Material, i: usize) -> GltfMaterial {
        let pbr = material.pbr_metallic_roughness();
        let texture = pbr.base_color_texture().map(|info| self.texture(&info));
        GltfMaterial {
            name: material
                .name()
                .map_or_else(|| format!("materials[{i}]"), str::to_owned),
            base_color: Vec4::from(pbr.base_color_factor()),
            texture,
            metallic: pbr.metallic_factor().clamp(0.0, 1.0),
            roughness: pbr.roughness_factor().clamp(0.0, 1.0),
            alpha: match material.alpha_mode() {
                Mode::Opaque => AlphaMode::Opaque,
                Mode::Mask => AlphaMode::Mask(material.alpha_cutoff().unwrap_or(0.5)),
                Mode::Blend => AlphaMode::Blend,
            },
        }
    }

    /// A base-colour texture reference: its image, sampler and uv transform.
    fn texture(&mut self, info: &gltf::texture::Info) -> TextureRef {
        let texture = info.texture();
        let sampler = texture.sampler();
        let wrap = |w: WrappingMode| match w {
            WrappingMode::ClampToEdge => Wrap::Clamp,
            WrappingMode::Repeat | WrappingMode::MirroredRepeat => Wrap::Repeat,
        };
        if sampler.wrap_s() == WrappingMode::MirroredRepeat
            || sampler.wrap_t() == WrappingMode::MirroredRepeat
        {
            self.ignored
                .note("{n} texture(s) wrap MIRRORED_REPEAT, read as REPEAT");
        }
        if wrap(sampler.wrap_s()) != wrap(sampler.wrap_t()) {
            self.ignored
                .note("{n} texture(s) wrap s and t differently; both take wrapS");
        }
        let (mut scale, mut offset, mut tex_coord) = (Vec2::ONE, Vec2::ZERO, info.tex_coord());
        if let Some(t) = info.texture_transform() {
            scale = Vec2::from(t.scale());
            offset = Vec2::from(t.offset());
            tex_coord = t.tex_coord().unwrap_or(tex_coord);
            if t.rotation() != 0.0 {
                self.ignored.note(
                    "{n} KHR_texture_transform rotation(s) are ignored (offset and scale are read)",
                );
            }
        }
        // glTF: v' = s·v + o with v down the image; penumbra's t = 1 − v, so
        // t' = 1 − v' = s·t + (1 − s − o).
        TextureRef {
            image: texture.source().index(),
            filter: match sampler.mag_filter() {
                Some(MagFilter::Nearest) => Filter::Nearest,
                _ => Filter::Bilinear,
            },
            wrap: wrap(sampler.wrap_s()),
            uv_scale: scale,
            uv_offset: Vec2::new(offset.x, 1.0 - scale.y - offset.y),
            tex_coord,
        }
    }

    /// Counts the parts of a used material penumbra does not render.
    fn note_ignored(&mut self, material: &gltf::Material) {
        let pbr = material.pbr_metallic_roughness();
        if pbr.metallic_roughness_texture().is_some() {
            self.ignored
                .note("{n} metallic-roughness texture(s) are ignored (their factors are read)");
        }
        if material.normal_texture().is_some() {
            self.ignored.note("{n} normal map(s) are ignored");
        }
        if material.occlusion_texture().is_some() {
            self.ignored.note("{n} occlusion map(s) are ignored");
        }
        if material.emissive_texture().is_some() || material.emissive_factor() != [0.0; 3] {
            self.ignored
                .note("{n} emissive material(s) are ignored (surfaces do not emit light)");
        }
    }
}

/// The warning for an extension the file uses that penumbra does not read. Known names get
/// a sentence of their own; others share one.
fn extension_note(ext: &str) -> &'static str {
    match ext {
        "KHR_materials_emissive_strength" => "extension KHR_materials_emissive_strength is ignored",
        "KHR_materials_unlit" => "extension KHR_materials_unlit is ignored (lit as any material)",
        "KHR_materials_transmission" => "extension KHR_materials_transmission is ignored",
        "KHR_materials_volume" => "extension KHR_materials_volume is ignored",
        "KHR_materials_ior" => "extension KHR_materials_ior is ignored",
        "KHR_materials_specular" => "extension KHR_materials_specular is ignored",
        "KHR_materials_clearcoat" => "extension KHR_materials_clearcoat is ignored",
        "KHR_materials_sheen" => "extension KHR_materials_sheen is ignored",
        "KHR_materials_variants" => "extension KHR_materials_variants is ignored (the default variant is used)",
        "KHR_materials_pbrSpecularGlossiness" => {
            "extension KHR_materials_pbrSpecularGlossiness is ignored (the metallic-roughness values are read)"
        }
        _ => "{n} other extension(s) the file uses are ignored (see `extensions`)",
    }
}
