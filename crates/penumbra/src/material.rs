//! Phong materials of SPEC §6 (docs/spec.md), and their cut-outs (SPEC §5.1): the texels
//! where a surface is cut away, for foliage drawn on cards.

use glam::Vec2;

use crate::math::Rgb;
use crate::texture::Texture;

/// The coefficients of the (Blinn-)Phong model, with an optional texture that multiplies the
/// ambient and diffuse colors, and an optional cut-out.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// k_a.
    pub ambient: Rgb,
    /// k_d.
    pub diffuse: Rgb,
    /// k_s.
    pub specular: Rgb,
    /// Phong exponent p ≥ 0.
    pub shininess: f32,
    /// Index into the scene's textures.
    pub texture: Option<u32>,
    /// Where the surface is cut away (rays pass through it there); `None`: nowhere.
    pub cutout: Option<Cutout>,
}

impl Default for Material {
    /// The format's default: diffuse 0.8 grey, ambient equal to diffuse, no specular, p = 16,
    /// no cut-out.
    fn default() -> Self {
        Self {
            ambient: Rgb::splat(0.8),
            diffuse: Rgb::splat(0.8),
            specular: Rgb::ZERO,
            shininess: 16.0,
            texture: None,
            cutout: None,
        }
    }
}

/// An alpha test: a hit of a surface is kept when its alpha, `factor` times the alpha of
/// `texture` at the hit's uv (1 without a texture), is at least `cutoff`; elsewhere the
/// surface is cut away, for camera rays and shadow rays alike (glTF's `alphaMode` MASK).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cutout {
    /// Index into the scene's textures: its alpha channel, or its luminance when it has none
    /// (see [`Texture::alpha`]).
    pub texture: Option<u32>,
    /// Multiplies the texture's alpha.
    pub factor: f32,
    /// The least alpha that is kept.
    pub cutoff: f32,
}

impl Default for Cutout {
    /// No texture, factor 1, cutoff 0.5 (glTF's default `alphaCutoff`): keeps everything
    /// until a texture is given.
    fn default() -> Self {
        Cutout {
            texture: None,
            factor: 1.0,
            cutoff: 0.5,
        }
    }
}

impl Cutout {
    /// The cut-out of `texture`'s alpha (or luminance) with `cutoff`, factor 1.
    pub fn with_texture(texture: u32, cutoff: f32) -> Cutout {
        Cutout {
            texture: Some(texture),
            factor: 1.0,
            cutoff,
        }
    }

    /// True when it may cut something away: it has a texture, or its factor is below the
    /// cutoff (then it cuts everything). A cut-out that keeps every hit is no cut-out, and
    /// the world builds it as an opaque surface.
    pub fn may_cut(&self) -> bool {
        self.texture.is_some() || !self.keeps(None, Vec2::ZERO)
    }

    /// The alpha at texture coordinates `uv`: `factor` times `texture`'s alpha there (the
    /// texture this cut-out names; `None` counts as alpha 1).
    #[inline]
    pub fn alpha(&self, texture: Option<&Texture>, uv: Vec2) -> f32 {
        self.factor * texture.map_or(1.0, |t| t.alpha(uv))
    }

    /// True when a hit at `uv` is kept: its [`Cutout::alpha`] is at least `cutoff` (a NaN
    /// alpha is cut away). Every query of the engine and of ray casting asks this one test.
    #[inline]
    pub fn keeps(&self, texture: Option<&Texture>, uv: Vec2) -> bool {
        self.alpha(texture, uv) >= self.cutoff
    }
}

/// The texture coordinates at barycentrics `(b1, b2)` of a triangle whose corners have
/// `uv`: the same sum, in the same order, as the shading point's (`Surface`), so that a
/// kept hit is shaded with the alpha it was tested with.
#[inline]
pub(crate) fn interpolate_uv(uv: [Vec2; 3], b1: f32, b2: f32) -> Vec2 {
    let b0 = 1.0 - b1 - b2;
    b0 * uv[0] + b1 * uv[1] + b2 * uv[2]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::texture::TextureKind;

    fn checker() -> Texture {
        Texture {
            kind: TextureKind::Checker {
                even: Rgb::ONE,
                odd: Rgb::ZERO,
                checks: 2.0,
            },
            uv_scale: Vec2::ONE,
            uv_offset: Vec2::ZERO,
        }
    }

    #[test]
    fn a_hit_is_kept_where_factor_times_alpha_reaches_the_cutoff() {
        let t = checker();
        let c = Cutout::with_texture(0, 0.5);
        assert!(c.keeps(Some(&t), Vec2::new(0.1, 0.1)));
        assert!(!c.keeps(Some(&t), Vec2::new(0.6, 0.1)));
        let faded = Cutout { factor: 0.4, ..c };
        assert!(!faded.keeps(Some(&t), Vec2::new(0.1, 0.1)));
        // Exactly at the cutoff is kept.
        let at = Cutout {
            texture: None,
            factor: 0.5,
            cutoff: 0.5,
        };
        assert!(at.keeps(None, Vec2::ZERO));
        assert!(!Cutout { factor: 0.49, ..at }.keeps(None, Vec2::ZERO));
    }

    #[test]
    fn only_cutouts_that_can_cut_are_cutouts() {
        assert!(!Cutout::default().may_cut());
        assert!(Cutout::with_texture(0, 0.5).may_cut());
        let none = Cutout {
            factor: 0.2,
            ..Cutout::default()
        };
        assert!(none.may_cut());
        assert!(!none.keeps(None, Vec2::ZERO));
    }

    #[test]
    fn uv_interpolation_weights_the_corners() {
        let uv = [Vec2::ZERO, Vec2::X, Vec2::Y];
        assert_eq!(interpolate_uv(uv, 0.25, 0.5), Vec2::new(0.25, 0.5));
        assert_eq!(interpolate_uv(uv, 0.0, 0.0), Vec2::ZERO);
    }
}
