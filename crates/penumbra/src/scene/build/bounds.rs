//! Bounds on radiance, so that finite inputs cannot overflow f32 while rendering (a light of
//! color 3e38 × intensity 10, a diffuse near `f32::MAX`): every light, the lights together,
//! the ambient light and the background emit at most [`MAX_EMISSION`], and what a material
//! can reflect under them is at most [`MAX_REFLECTED`]. A pixel sums at most
//! [`MAX_SPP`](crate::render::MAX_SPP) (65536) samples of that, which stays below `f32::MAX`.
//! Values beyond are refused at their key rather than rendered as infinite or NaN pixels.
//!
//! Not bounded here: the inverse-square falloff of the physical light model, which grows
//! without limit near a light; the image writer refuses a non-finite pixel in a float image.

use super::{Builder, Result};
use crate::integrator::LightModel;
use crate::light::Light;
use crate::material::Material;
use crate::math::Rgb;
use crate::scene::desc::{ColorDesc, LightDesc, MaterialDesc, Num};
use crate::scene::error::KeyPath;
use crate::texture::{Texture, TextureKind};

/// Most radiance a light (color × intensity), all lights together, the ambient light or the
/// background may emit.
pub const MAX_EMISSION: f64 = 1e32;

/// Most radiance a material may reflect under the scene's lights and ambient light.
pub const MAX_REFLECTED: f64 = 1e33;

/// `x` in three significant digits without trailing zeros: "3e39", "1.1e32", "3.4e38".
fn sci(x: f64) -> String {
    let s = format!("{x:.2e}");
    match s.split_once('e') {
        Some((mantissa, exp)) if mantissa.contains('.') => {
            let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
            format!("{mantissa}e{exp}")
        }
        _ => s,
    }
}

/// The largest channel magnitude of `c`, in f64 (where products of f32 cannot overflow).
pub(super) fn peak(c: Rgb) -> f64 {
    c.abs().max_element() as f64
}

/// The largest channel a texture gives: 1 for a decoded image, the larger color for a
/// checker.
pub(super) fn texture_peak(t: &Texture) -> f64 {
    match &t.kind {
        TextureKind::Image(_) => 1.0,
        TextureKind::Checker { even, odd, .. } => peak(*even).max(peak(*odd)),
    }
}

/// The key of a light to blame for its emission: `intensity`, else `file` (an environment
/// map), else `color`.
pub(super) fn light_key(l: &LightDesc) -> &'static str {
    let (intensity, file) = match l {
        LightDesc::Area(a) => (a.intensity.is_some(), false),
        LightDesc::Point(p) => (p.intensity.is_some(), false),
        LightDesc::Environment(e) => (e.intensity.is_some(), e.file.is_some()),
        LightDesc::Directional(d) => (d.intensity.is_some(), false),
        LightDesc::Spot(s) => (s.intensity.is_some(), false),
    };
    match (intensity, file) {
        (true, _) => "intensity",
        (false, true) => "file",
        (false, false) => "color",
    }
}

/// The key of material `m` at `path` to blame for its largest term: the coefficient itself
/// when the file gives it, else what it defaults from (ambient from diffuse), else the
/// texture, else the material.
pub(super) fn material_key(path: &KeyPath, m: &MaterialDesc, term: Term) -> KeyPath {
    let given = |key: &str| match key {
        "diffuse" => m.diffuse.is_some(),
        "ambient" => m.ambient.is_some(),
        "specular" => m.specular.is_some(),
        _ => m.texture.is_some(),
    };
    let candidates: &[&str] = match term {
        Term::Diffuse => &["diffuse", "texture"],
        Term::Specular => &["specular"],
        Term::Ambient => &["ambient", "diffuse", "texture"],
    };
    match candidates.iter().find(|k| given(k)) {
        Some(k) => path.key(k),
        None => path.clone(),
    }
}

/// What light `l` (built as `built`) emits at most, summed over its samples: color ×
/// intensity, times the area for a physical area light (its samples weigh |u × v|/N² each).
/// From the file's numbers, in f64: the f32 product may already be infinite. An environment
/// map's sample weighs radiance / density, at most 64 × 4π times its largest texel (a
/// bilinear value is at most 4 times its cell's mean luminance, and a channel at most 14
/// times the luminance).
pub(super) fn emission(l: &LightDesc, built: &Light, model: LightModel) -> f64 {
    let color_intensity = |c: Option<ColorDesc>, i: Option<Num>| {
        c.map_or(1.0, |c| peak(c.rgb())) * i.map_or(1.0, |i| i.0.abs())
    };
    match l {
        LightDesc::Point(p) => color_intensity(p.color, p.intensity),
        LightDesc::Directional(d) => color_intensity(d.color, d.intensity),
        LightDesc::Spot(s) => color_intensity(s.color, s.intensity),
        LightDesc::Area(a) => {
            let e = color_intensity(a.color, a.intensity);
            match model {
                LightModel::Phong => e,
                LightModel::Physical => {
                    let (u, v) = (a.u.vec3().as_dvec3(), a.v.vec3().as_dvec3());
                    e * u.cross(v).length().max(1.0)
                }
            }
        }
        LightDesc::Environment(e) => {
            let Light::Environment(env) = built else {
                return 0.0;
            };
            let (_, texel) = env.map.mean_and_peak();
            let intensity = e.intensity.map_or(1.0, |i| i.0.abs());
            intensity * peak(texel) * 64.0 * 4.0 * std::f64::consts::PI
        }
    }
}

/// One term of what a material reflects.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Term {
    Diffuse,
    Specular,
    Ambient,
}

/// What `m` reflects at most under lights emitting `lights` in all and an ambient light
/// `ambient`, with its texture's largest channel `texture`; and the largest of its terms.
pub(super) fn reflected(
    m: &Material,
    texture: f64,
    lights: f64,
    ambient: f64,
    model: LightModel,
) -> (f64, Term) {
    let pi = std::f64::consts::PI;
    let p = m.shininess as f64;
    // The physical model's energy normalization; Phong's (p + 2)/(2π) is the larger lobe.
    let (kd_norm, ks_norm) = match model {
        LightModel::Phong => (1.0, 1.0),
        LightModel::Physical => (1.0 / pi, (p + 2.0) / (2.0 * pi)),
    };
    let terms = [
        (texture * peak(m.diffuse) * kd_norm * lights, Term::Diffuse),
        (peak(m.specular) * ks_norm * lights, Term::Specular),
        (texture * peak(m.ambient) * ambient, Term::Ambient),
    ];
    let total = terms.iter().map(|t| t.0).sum();
    let largest = terms
        .iter()
        .fold(terms[0], |a, &b| if b.0 > a.0 { b } else { a });
    (total, largest.1)
}

impl Builder<'_> {
    /// What `material`, with a texture whose largest channel is `texture`, reflects at most
    /// under the scene's lighting, and its largest term.
    pub(super) fn reflected(&self, material: &Material, texture: f64) -> (f64, Term) {
        let l = self.lighting;
        reflected(material, texture, l.emission, l.ambient, l.model)
    }

    /// Checks that the light at `path`, emitting `emitted`, keeps the lights' sum `total`
    /// (this light included) within [`MAX_EMISSION`]. `key` is the key to blame.
    pub(super) fn check_emission(
        &self,
        path: &KeyPath,
        key: &str,
        emitted: f64,
        total: f64,
    ) -> Result<()> {
        let path = path.key(key);
        if emitted > MAX_EMISSION {
            return Err(self.bad(
                &path,
                format!(
                    "this light emits {} (color × intensity), but at most {} can be rendered",
                    sci(emitted),
                    sci(MAX_EMISSION)
                ),
            ));
        }
        if total > MAX_EMISSION {
            return Err(self.bad(
                &path,
                format!(
                    "the lights together emit {} (color × intensity), but at most {} can be rendered",
                    sci(total),
                    sci(MAX_EMISSION)
                ),
            ));
        }
        Ok(())
    }

    /// Checks a color of `[render]` (the ambient light or the background) at `path`.
    pub(super) fn check_render_color(&self, path: &KeyPath, c: Rgb) -> Result<()> {
        if peak(c) <= MAX_EMISSION {
            return Ok(());
        }
        Err(self.bad(
            path,
            format!(
                "{} is brighter than can be rendered (at most {})",
                sci(peak(c)),
                sci(MAX_EMISSION)
            ),
        ))
    }

    /// Checks that a material (`what`) reflecting `reflected` at most stays within
    /// [`MAX_REFLECTED`]; `path` is the key to blame.
    pub(super) fn check_reflected(&self, path: &KeyPath, what: &str, reflected: f64) -> Result<()> {
        if reflected <= MAX_REFLECTED {
            return Ok(());
        }
        Err(self.bad(
            path,
            format!(
                "{what} can reflect up to {} under the scene's lights, but at most {} can be rendered",
                sci(reflected),
                sci(MAX_REFLECTED)
            ),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_short() {
        assert_eq!(sci(3e39), "3e39");
        assert_eq!(sci(1.1e32), "1.1e32");
        assert_eq!(sci(3.4e38_f32 as f64), "3.4e38");
        assert_eq!(sci(1e32), "1e32");
    }

    #[test]
    fn a_pixel_of_the_most_samples_of_the_most_reflected_light_is_finite() {
        let most = MAX_REFLECTED * crate::render::MAX_SPP as f64;
        assert!(most < f32::MAX as f64);
        // The default material under the brightest lights and ambient light.
        let (r, _) = reflected(
            &Material::default(),
            1.0,
            MAX_EMISSION,
            MAX_EMISSION,
            LightModel::Phong,
        );
        assert!(r <= MAX_REFLECTED, "{r}");
    }
}
