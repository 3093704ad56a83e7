//! Textures of SPEC §6 (docs/spec.md): decoded images sampled with nearest or bilinear filtering and repeat or
//! clamp wrapping, and the procedural checker. A texture also has an alpha at every uv, which
//! cut-outs test (SPEC §5.1): an image's alpha channel, or its luminance when it has none.

use std::ops::{Add, Mul};
use std::sync::Arc;

use glam::Vec2;

use crate::math::Rgb;

/// How texels are blended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Filter {
    /// The texel the point falls in.
    Nearest,
    /// A blend of the four texels around the point.
    Bilinear,
}

/// How texel indices outside the image are mapped back in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Wrap {
    /// Euclidean modulo: the image tiles the plane.
    Repeat,
    /// The nearest edge texel.
    Clamp,
}

/// A decoded image in linear RGB, row 0 at the top, with its alpha channel when the file
/// has one.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in texels (≥ 1).
    pub width: u32,
    /// Height in texels (≥ 1).
    pub height: u32,
    /// Linear RGB texels, row-major from the top row.
    pub texels: Vec<Rgb>,
    /// Alpha of each texel in the order of `texels` (as stored: never sRGB-decoded), for
    /// an image whose file has an alpha channel; `None` otherwise, so that opaque images
    /// cost nothing more.
    pub alpha: Option<Vec<f32>>,
}

impl Image {
    /// An image without alpha.
    pub fn rgb(width: u32, height: u32, texels: Vec<Rgb>) -> Image {
        Image {
            width,
            height,
            texels,
            alpha: None,
        }
    }

    /// An image of straight (not premultiplied) RGBA texels, row-major from the top row;
    /// `None` unless there are `width × height` of them and both are at least 1. RGB is
    /// decoded through the sRGB curve when `srgb`, else taken as linear; alpha is always
    /// taken as it is. For readers that decode images themselves (glTF's, say).
    pub fn from_rgba(width: u32, height: u32, rgba: &[[f32; 4]], srgb: bool) -> Option<Image> {
        if width == 0 || height == 0 || rgba.len() as u64 != u64::from(width) * u64::from(height) {
            return None;
        }
        let decode = |c: f32| if srgb { srgb_to_linear(c) } else { c };
        Some(Image {
            width,
            height,
            texels: rgba
                .iter()
                .map(|p| Rgb::new(decode(p[0]), decode(p[1]), decode(p[2])))
                .collect(),
            alpha: Some(rgba.iter().map(|p| p[3]).collect()),
        })
    }
}

/// An image texture: shared decoded texels plus sampling parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageTexture {
    /// The texels, shared by every texture made from the same file.
    pub image: Arc<Image>,
    /// Filtering.
    pub filter: Filter,
    /// Wrapping.
    pub wrap: Wrap,
}

/// A texture: a color for every uv.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// What the color comes from.
    pub kind: TextureKind,
    /// uv is mapped to `uv·uv_scale + uv_offset` before lookup.
    pub uv_scale: Vec2,
    /// See `uv_scale`.
    pub uv_offset: Vec2,
}

/// Where a texture's colors come from.
#[derive(Clone, Debug, PartialEq)]
pub enum TextureKind {
    /// An image file.
    Image(ImageTexture),
    /// A checkerboard of `checks` squares per unit of uv along each axis.
    Checker {
        /// Color where floor(s·checks) + floor(t·checks) is even.
        even: Rgb,
        /// Color elsewhere.
        odd: Rgb,
        /// Squares per unit of uv.
        checks: f32,
    },
}

impl Texture {
    /// The linear color at texture coordinates `uv` (before `uv_scale`/`uv_offset`).
    pub fn eval(&self, uv: Vec2) -> Rgb {
        let st = uv * self.uv_scale + self.uv_offset;
        match &self.kind {
            TextureKind::Image(tex) => tex.eval(st),
            TextureKind::Checker { even, odd, checks } => {
                let sum = (st.x * checks).floor() + (st.y * checks).floor();
                if sum.rem_euclid(2.0) == 0.0 {
                    *even
                } else {
                    *odd
                }
            }
        }
    }

    /// The alpha at texture coordinates `uv` (before `uv_scale`/`uv_offset`), with the same
    /// filtering and wrapping as the color: an image's alpha channel, or the luminance of
    /// its linear color (Rec. 709 weights) when it has none, as for a checker.
    pub fn alpha(&self, uv: Vec2) -> f32 {
        match &self.kind {
            TextureKind::Image(tex) => tex.alpha(uv * self.uv_scale + self.uv_offset),
            TextureKind::Checker { .. } => luminance(self.eval(uv)),
        }
    }
}

/// Rec. 709 luminance of linear RGB: the alpha of a texture without an alpha channel.
pub fn luminance(c: Rgb) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

impl ImageTexture {
    /// The filtered color at `(s, t)`; t = 0 is the bottom row of the image.
    pub fn eval(&self, st: Vec2) -> Rgb {
        self.sample(st, |i| self.image.texels[i])
    }

    /// The filtered alpha at `(s, t)`: the alpha channel's, or without one the luminance of
    /// the filtered color. Nearest filtering gives a cut-out's edge along texel borders;
    /// bilinear blends the four texels around the point, so the edge runs smoothly between
    /// texel centres where the blend crosses the cutoff.
    pub fn alpha(&self, st: Vec2) -> f32 {
        match &self.image.alpha {
            Some(alpha) => self.sample(st, |i| alpha[i]),
            None => luminance(self.eval(st)),
        }
    }

    /// The value at `(s, t)` filtered and wrapped from `texel(index)` (`y · width + x`):
    /// the one sampling rule of colors and alphas.
    #[inline(always)]
    fn sample<T>(&self, st: Vec2, texel: impl Fn(usize) -> T) -> T
    where
        T: Copy + Add<Output = T> + Mul<f32, Output = T>,
    {
        let (w, h) = (self.image.width as f32, self.image.height as f32);
        let at = |x: f32, y: f32| texel(self.index(x, y));
        match self.filter {
            Filter::Nearest => {
                let x = (st.x * w).floor();
                let y = ((1.0 - st.y) * h).floor();
                at(x, y)
            }
            Filter::Bilinear => {
                let x = finite(st.x * w - 0.5);
                let y = finite((1.0 - st.y) * h - 0.5);
                let (x0, y0) = (x.floor(), y.floor());
                let (fx, fy) = (x - x0, y - y0);
                let top = at(x0, y0) * (1.0 - fx) + at(x0 + 1.0, y0) * fx;
                let bottom = at(x0, y0 + 1.0) * (1.0 - fx) + at(x0 + 1.0, y0 + 1.0) * fx;
                top * (1.0 - fy) + bottom * fy
            }
        }
    }

    /// The index of the texel at integer coordinates given as floats (possibly outside the
    /// image), wrapped.
    #[inline(always)]
    fn index(&self, x: f32, y: f32) -> usize {
        let (w, h) = (self.image.width as i64, self.image.height as i64);
        // Saturating float-to-int casts keep huge or non-finite uvs in range of i64.
        let (x, y) = (x as i64, y as i64);
        let (x, y) = match self.wrap {
            Wrap::Repeat => (x.rem_euclid(w), y.rem_euclid(h)),
            Wrap::Clamp => (x.clamp(0, w - 1), y.clamp(0, h - 1)),
        };
        (y * w + x) as usize
    }
}

/// `x`, or for an infinite `x` (uv·uv_scale can overflow) the largest float of its sign, and 0
/// for NaN: then x − floor(x) is 0 rather than NaN, and the lookup a texel, not NaN.
fn finite(x: f32) -> f32 {
    if x.is_nan() {
        0.0
    } else {
        x.clamp(-f32::MAX, f32::MAX)
    }
}

/// The sRGB transfer curve's inverse: an encoded value in [0, 1] to linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The sRGB transfer curve: linear [0, 1] to encoded.
pub fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A 2×2 image: top row red, green; bottom row blue, white.
    fn tex(filter: Filter, wrap: Wrap) -> ImageTexture {
        ImageTexture {
            image: Arc::new(Image::rgb(2, 2, vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE])),
            filter,
            wrap,
        }
    }

    #[test]
    fn nearest_uses_the_bottom_row_at_t_zero() {
        let t = tex(Filter::Nearest, Wrap::Repeat);
        assert_eq!(t.eval(Vec2::new(0.25, 0.25)), Vec3::Z); // bottom left
        assert_eq!(t.eval(Vec2::new(0.75, 0.25)), Vec3::ONE); // bottom right
        assert_eq!(t.eval(Vec2::new(0.25, 0.75)), Vec3::X); // top left
        assert_eq!(t.eval(Vec2::new(0.75, 0.75)), Vec3::Y); // top right
    }

    #[test]
    fn bilinear_at_texel_centers_and_between() {
        let t = tex(Filter::Bilinear, Wrap::Clamp);
        assert_eq!(t.eval(Vec2::new(0.25, 0.75)), Vec3::X);
        // Midway between the two top texels.
        let mid = t.eval(Vec2::new(0.5, 0.75));
        assert!((mid - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-6);
        // The image center blends all four equally.
        let c = t.eval(Vec2::new(0.5, 0.5));
        assert!((c - Vec3::splat(0.5)).length() < 1e-6);
        // Clamp: the corner stays the corner texel.
        assert_eq!(t.eval(Vec2::new(0.0, 1.0)), Vec3::X);
    }

    #[test]
    fn bilinear_repeat_blends_across_the_edge() {
        let t = tex(Filter::Bilinear, Wrap::Repeat);
        // At s = 0 the left texel column blends half with the right column (wrapped).
        let c = t.eval(Vec2::new(0.0, 0.75));
        assert!((c - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-6);
    }

    #[test]
    fn repeat_handles_negative_uvs() {
        let t = tex(Filter::Nearest, Wrap::Repeat);
        assert_eq!(t.eval(Vec2::new(-0.75, 0.25)), Vec3::Z);
        assert_eq!(t.eval(Vec2::new(-0.25, -0.25)), Vec3::Y);
        assert_eq!(t.eval(Vec2::new(1.25, 1.25)), Vec3::Z);
    }

    #[test]
    fn clamp_holds_the_edge() {
        let t = tex(Filter::Nearest, Wrap::Clamp);
        assert_eq!(t.eval(Vec2::new(5.0, -3.0)), Vec3::ONE);
        assert_eq!(t.eval(Vec2::new(-5.0, 3.0)), Vec3::X);
    }

    #[test]
    fn checker_and_uv_transform() {
        let t = Texture {
            kind: TextureKind::Checker {
                even: Vec3::ONE,
                odd: Vec3::ZERO,
                checks: 2.0,
            },
            uv_scale: Vec2::ONE,
            uv_offset: Vec2::ZERO,
        };
        assert_eq!(t.eval(Vec2::new(0.1, 0.1)), Vec3::ONE);
        assert_eq!(t.eval(Vec2::new(0.6, 0.1)), Vec3::ZERO);
        assert_eq!(t.eval(Vec2::new(0.6, 0.6)), Vec3::ONE);
        assert_eq!(t.eval(Vec2::new(-0.1, 0.1)), Vec3::ZERO);
        let shifted = Texture {
            uv_offset: Vec2::new(0.5, 0.0),
            ..t.clone()
        };
        assert_eq!(shifted.eval(Vec2::new(0.1, 0.1)), Vec3::ZERO);
        let scaled = Texture {
            uv_scale: Vec2::splat(2.0),
            ..t
        };
        assert_eq!(scaled.eval(Vec2::new(0.3, 0.1)), Vec3::ZERO);
    }

    #[test]
    fn alpha_is_the_alpha_plane_filtered_like_the_color_or_the_luminance() {
        // Alpha 1, 0 on the top row, 0.5, 0.25 on the bottom row; never sRGB-decoded.
        let rgba = [
            [1.0, 0.0, 0.0, 1.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.5],
            [1.0, 1.0, 1.0, 0.25],
        ];
        let image = Arc::new(Image::from_rgba(2, 2, &rgba, true).unwrap());
        let nearest = ImageTexture {
            image: image.clone(),
            filter: Filter::Nearest,
            wrap: Wrap::Repeat,
        };
        assert_eq!(nearest.alpha(Vec2::new(0.25, 0.75)), 1.0);
        assert_eq!(nearest.alpha(Vec2::new(0.75, 0.75)), 0.0);
        assert_eq!(nearest.alpha(Vec2::new(0.25, 0.25)), 0.5);
        assert_eq!(nearest.alpha(Vec2::new(1.75, -0.75)), 0.25); // wrapped
        let bilinear = ImageTexture {
            filter: Filter::Bilinear,
            wrap: Wrap::Clamp,
            ..nearest
        };
        // Midway between the two top texels, and the centre of all four.
        assert!((bilinear.alpha(Vec2::new(0.5, 0.75)) - 0.5).abs() < 1e-6);
        assert!((bilinear.alpha(Vec2::new(0.5, 0.5)) - 0.4375).abs() < 1e-6);
        // Without an alpha plane: the luminance, white 1 and black 0.
        let opaque = tex(Filter::Nearest, Wrap::Repeat);
        assert!((opaque.alpha(Vec2::new(0.75, 0.25)) - 1.0).abs() < 1e-6);
        assert!((opaque.alpha(Vec2::new(0.25, 0.75)) - 0.2126).abs() < 1e-6);
        assert!(Image::from_rgba(2, 1, &rgba, false).is_none());
    }

    #[test]
    fn srgb_curve_round_trips_and_hits_known_values() {
        assert_eq!(linear_to_srgb(0.0), 0.0);
        assert!((linear_to_srgb(1.0) - 1.0).abs() < 1e-6);
        assert!((linear_to_srgb(0.18) - 0.4614).abs() < 1e-3);
        assert!((srgb_to_linear(0.5) - 0.2140).abs() < 1e-3);
        for i in 0..=255 {
            let c = i as f32 / 255.0;
            assert!((linear_to_srgb(srgb_to_linear(c)) - c).abs() < 1e-5);
        }
    }
}
