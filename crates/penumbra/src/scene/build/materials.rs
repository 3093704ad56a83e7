//! Textures, materials and lights. Scene materials and MTL materials go through one
//! conversion ([`material`]), so both get the same defaults: those of [`Material::default`].

use std::path::PathBuf;
use std::sync::Arc;

use glam::Vec2;

use super::{list, Builder, Result};
use crate::light::{
    AreaLight, DirectionalLight, EnvironmentLight, EnvironmentMap, Light, PointLight, SpotLight,
};
use crate::material::{Cutout, Material};
use crate::math::Rgb;
use crate::scene::desc::{
    ColorSpace, EnvironmentLightDesc, LightDesc, MaterialDesc, Num, TextureDesc, TextureKindDesc,
};
use crate::scene::error::{AssetKind, ErrorKind, KeyPath};
use crate::texture::{Filter, Image, ImageTexture, Texture, TextureKind, Wrap};
use crate::texture_file::load_texture_image;

/// The (Blinn-)Phong coefficients as a scene file or an MTL file gives them; what is absent
/// takes the default material's value (k_a defaults to k_d).
pub(super) struct Phong {
    pub(super) diffuse: Option<Rgb>,
    pub(super) ambient: Option<Rgb>,
    pub(super) specular: Option<Rgb>,
    pub(super) shininess: Option<f32>,
    pub(super) texture: Option<u32>,
    pub(super) cutout: Option<Cutout>,
}

/// The material `p` describes.
pub(super) fn material(p: Phong) -> Material {
    let defaults = Material::default();
    let diffuse = p.diffuse.unwrap_or(defaults.diffuse);
    Material {
        ambient: p.ambient.unwrap_or(diffuse),
        diffuse,
        specular: p.specular.unwrap_or(defaults.specular),
        shininess: p.shininess.unwrap_or(defaults.shininess),
        texture: p.texture,
        cutout: p.cutout,
    }
}

impl Builder<'_> {
    /// The decoded image `file`, loaded once per scene and color space.
    pub(super) fn image(
        &mut self,
        path: &KeyPath,
        file: PathBuf,
        srgb: bool,
        what: &str,
    ) -> Result<Arc<Image>> {
        let key = (self.file.files().identity(&file), srgb);
        if let Some(img) = self.images.get(&key) {
            return Ok(img.clone());
        }
        let img = load_texture_image(self.file.files(), &file, srgb, self.budget.left()).map_err(
            |e| {
                self.err(
                    ErrorKind::Asset(AssetKind::Image),
                    path,
                    format!("cannot load {what} \"{}\": {e}", file.display()),
                )
            },
        )?;
        self.read.insert(file);
        let alpha_bytes = img.alpha.as_ref().map_or(0, |a| a.len() as u64 * 4);
        self.budget.texture_bytes +=
            img.width as u64 * img.height as u64 * super::budget::BYTES_PER_TEXEL + alpha_bytes;
        let img = Arc::new(img);
        self.images.insert(key, img.clone());
        Ok(img)
    }

    pub(super) fn texture(&mut self, path: &KeyPath, t: &TextureDesc) -> Result<Texture> {
        let kind = match &t.kind {
            TextureKindDesc::Image(i) => {
                let srgb = i.colorspace.unwrap_or(ColorSpace::Srgb) == ColorSpace::Srgb;
                let at = path.key("file");
                let file = self.reference(&at, &i.file, ErrorKind::Asset(AssetKind::Image))?;
                let image = self.image(&at, file, srgb, "texture")?;
                TextureKind::Image(ImageTexture {
                    image,
                    filter: i.filter.unwrap_or(Filter::Bilinear),
                    wrap: i.wrap.unwrap_or(Wrap::Repeat),
                })
            }
            TextureKindDesc::Checker(c) => TextureKind::Checker {
                even: c.even.map_or(Rgb::ONE, |c| c.rgb()),
                odd: c.odd.map_or(Rgb::ZERO, |c| c.rgb()),
                checks: c.checks.map_or(8.0, Num::f32),
            },
        };
        Ok(Texture {
            kind,
            uv_scale: t.uv_scale.map_or(Vec2::ONE, |v| v.vec2()),
            uv_offset: t.uv_offset.map_or(Vec2::ZERO, |v| v.vec2()),
        })
    }

    pub(super) fn material(&self, path: &KeyPath, m: &MaterialDesc) -> Result<Material> {
        if let Some(Num(p)) = m.shininess {
            if p < 0.0 {
                return Err(self.bad(
                    &path.key("shininess"),
                    format!("shininess must be at least 0, not {p}"),
                ));
            }
        }
        let texture = self.texture_index(&path.key("texture"), m.texture.as_deref())?;
        Ok(material(Phong {
            diffuse: m.diffuse.map(|c| c.rgb()),
            ambient: m.ambient.map(|c| c.rgb()),
            specular: m.specular.map(|c| c.rgb()),
            shininess: m.shininess.map(Num::f32),
            texture,
            cutout: self.cutout(path, m)?,
        }))
    }

    /// The index of the texture called `name`, if one is named.
    fn texture_index(&self, path: &KeyPath, name: Option<&str>) -> Result<Option<u32>> {
        let Some(name) = name else {
            return Ok(None);
        };
        let textures = &self.file.desc.textures;
        let index = textures.get(name).map(|(i, _)| i as u32).ok_or_else(|| {
            let known: Vec<&str> = textures.names().collect();
            self.err(
                ErrorKind::UnknownName,
                path,
                format!("unknown texture \"{name}\"{}", list(&known)),
            )
        })?;
        Ok(Some(index))
    }

    /// The cut-out of `m`'s `alpha`, `alpha_texture` and `alpha_cutoff` keys: none without
    /// any of them.
    fn cutout(&self, path: &KeyPath, m: &MaterialDesc) -> Result<Option<Cutout>> {
        if m.alpha.is_none() && m.alpha_texture.is_none() && m.alpha_cutoff.is_none() {
            return Ok(None);
        }
        let defaults = Cutout::default();
        let unit = |key: &str, v: Option<Num>, default: f32| match v.map(Num::f32) {
            None => Ok(default),
            Some(x) if (0.0..=1.0).contains(&x) => Ok(x),
            Some(x) => Err(self.bad(
                &path.key(key),
                format!("{key} must be within [0, 1], not {x}"),
            )),
        };
        let factor = unit("alpha", m.alpha, defaults.factor)?;
        let cutoff = unit("alpha_cutoff", m.alpha_cutoff, defaults.cutoff)?;
        let texture = self.texture_index(&path.key("alpha_texture"), m.alpha_texture.as_deref())?;
        Ok(Some(Cutout {
            texture,
            factor,
            cutoff,
        }))
    }

    pub(super) fn light(&mut self, path: &KeyPath, l: &LightDesc, default_n: u32) -> Result<Light> {
        let color = |c: Option<crate::scene::desc::ColorDesc>, i: Option<Num>| {
            c.map_or(Rgb::ONE, |c| c.rgb()) * i.map_or(1.0, Num::f32)
        };
        Ok(match l {
            LightDesc::Area(a) => Light::Area(AreaLight {
                center: a.center.vec3(),
                u: a.u.vec3(),
                v: a.v.vec3(),
                radiance: color(a.color, a.intensity),
                n: match a.samples {
                    Some(n) => self.light_n(&path.key("samples"), n)?,
                    None => default_n,
                },
                jitter: a.jitter.unwrap_or(false),
            }),
            LightDesc::Point(p) => Light::Point(PointLight {
                position: p.position.vec3(),
                intensity: color(p.color, p.intensity),
            }),
            LightDesc::Environment(e) => Light::Environment(EnvironmentLight {
                map: self.environment_map(path, e)?,
                intensity: e.intensity.map_or(1.0, Num::f32),
                rotation: e.rotation.map_or(0.0, Num::f32),
                n: match e.samples {
                    Some(n) => self.light_n(&path.key("samples"), n)?,
                    None => default_n,
                },
                visible: e.visible.unwrap_or(true),
            }),
            LightDesc::Directional(d) => {
                let angle = self.angle(&path.key("angle"), d.angle, 0.0, 0.0, 90.0)?;
                Light::Directional(DirectionalLight {
                    direction: self.direction(&path.key("direction"), d.direction.vec3())?,
                    irradiance: color(d.color, d.intensity),
                    cos_half_angle: (0.5 * angle).to_radians().cos(),
                    n: match (angle > 0.0, d.samples) {
                        (false, _) => 1,
                        (true, Some(n)) => self.light_n(&path.key("samples"), n)?,
                        (true, None) => default_n,
                    },
                })
            }
            LightDesc::Spot(s) => {
                let inner = self.angle(&path.key("inner_angle"), s.inner_angle, 0.0, 0.0, 90.0)?;
                let outer = self.angle(&path.key("outer_angle"), s.outer_angle, 45.0, 0.0, 90.0)?;
                if outer < inner {
                    let message = format!(
                        "outer_angle ({outer}°) must not be smaller than inner_angle ({inner}°)"
                    );
                    return Err(self.bad(&path.key("outer_angle"), message));
                }
                Light::Spot(SpotLight {
                    position: s.position.vec3(),
                    direction: self.direction(&path.key("direction"), s.direction.vec3())?,
                    intensity: color(s.color, s.intensity),
                    cos_inner: inner.to_radians().cos(),
                    cos_outer: outer.to_radians().cos(),
                })
            }
        })
    }

    /// The unit vector along `v` at `path`; a zero (or unnormalizable) vector is an error.
    fn direction(&self, path: &KeyPath, v: glam::Vec3) -> Result<glam::Vec3> {
        v.try_normalize()
            .ok_or_else(|| self.bad(path, "the direction must not be zero"))
    }

    /// The angle in degrees at `path` (or `default`), which must lie in `[lo, hi]`.
    fn angle(
        &self,
        path: &KeyPath,
        angle: Option<Num>,
        default: f32,
        lo: f32,
        hi: f32,
    ) -> Result<f32> {
        let a = angle.map_or(default, Num::f32);
        if !(lo..=hi).contains(&a) {
            let message = format!("the angle must be between {lo} and {hi} degrees, not {a}");
            return Err(self.bad(path, message));
        }
        Ok(a)
    }

    /// The map of environment light `e` at `path`: its `file` (Radiance HDR and OpenEXR
    /// content linear, PNG and JPEG content through the sRGB curve, whatever the extension)
    /// or its uniform `color`.
    fn environment_map(
        &mut self,
        path: &KeyPath,
        e: &EnvironmentLightDesc,
    ) -> Result<Arc<EnvironmentMap>> {
        if let Some(i) = e.intensity.filter(|i| i.0 < 0.0) {
            let message = format!("intensity must not be negative, not {}", i.0);
            return Err(self.bad(&path.key("intensity"), message));
        }
        let map = match (&e.file, e.color) {
            (Some(_), Some(_)) => {
                let message = "give `file` or `color`, not both";
                return Err(self.bad(&path.key("color"), message));
            }
            (None, None) => {
                let message = "an environment light needs `file` (an equirectangular map) or \
                               `color` (a uniform sky)";
                return Err(self.bad(path, message));
            }
            (None, Some(c)) => {
                let c = c.rgb();
                if c.cmplt(Rgb::ZERO).any() {
                    return Err(self.bad(&path.key("color"), "color must not be negative"));
                }
                EnvironmentMap::uniform(c)
            }
            (Some(file), None) => {
                let at = path.key("file");
                let resolved = self.reference(&at, file, ErrorKind::Asset(AssetKind::Image))?;
                // The content picks the curve, not the extension: see `load_texture_image`.
                let image = self.image(&at, resolved, true, "environment map")?;
                EnvironmentMap::new(image.width, image.height, image.texels.clone())
            }
        };
        let key = if e.file.is_some() { "file" } else { "color" };
        let map = map.map_err(|err| {
            self.err(
                ErrorKind::Asset(AssetKind::Image),
                &path.key(key),
                err.to_string(),
            )
        })?;
        // The sampling distribution: about 8 bytes per texel beside the texels.
        self.budget.texture_bytes += u64::from(map.size().0) * u64::from(map.size().1) * 8;
        Ok(Arc::new(map))
    }

    /// The index of the material called `name`.
    pub(super) fn material_index(&self, path: &KeyPath, name: &str) -> Result<u32> {
        let materials = &self.file.desc.materials;
        materials
            .get(name)
            .map(|(i, _)| i as u32 + 1)
            .ok_or_else(|| {
                let known: Vec<&str> = materials.names().collect();
                self.err(
                    ErrorKind::UnknownName,
                    path,
                    format!("unknown material \"{name}\"{}", list(&known)),
                )
            })
    }
}
