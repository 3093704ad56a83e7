//! Textures of SPEC §6 (docs/spec.md): decoded images sampled with nearest or bilinear filtering and repeat or
//! clamp wrapping, and the procedural checker.

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

/// A decoded image in linear RGB, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in texels (≥ 1).
    pub width: u32,
    /// Height in texels (≥ 1).
    pub height: u32,
    /// Linear RGB texels, row-major from the top row.
    pub texels: Vec<Rgb>,
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
}

impl ImageTexture {
    /// The filtered color at `(s, t)`; t = 0 is the bottom row of the image.
    pub fn eval(&self, st: Vec2) -> Rgb {
        let (w, h) = (self.image.width as f32, self.image.height as f32);
        match self.filter {
            Filter::Nearest => {
                let x = (st.x * w).floor();
                let y = ((1.0 - st.y) * h).floor();
                self.texel(x, y)
            }
            Filter::Bilinear => {
                let x = finite(st.x * w - 0.5);
                let y = finite((1.0 - st.y) * h - 0.5);
                let (x0, y0) = (x.floor(), y.floor());
                let (fx, fy) = (x - x0, y - y0);
                let top = self.texel(x0, y0) * (1.0 - fx) + self.texel(x0 + 1.0, y0) * fx;
                let bottom =
                    self.texel(x0, y0 + 1.0) * (1.0 - fx) + self.texel(x0 + 1.0, y0 + 1.0) * fx;
                top * (1.0 - fy) + bottom * fy
            }
        }
    }

    /// The texel at integer coordinates given as floats (possibly outside the image).
    fn texel(&self, x: f32, y: f32) -> Rgb {
        let (w, h) = (self.image.width as i64, self.image.height as i64);
        // Saturating float-to-int casts keep huge or non-finite uvs in range of i64.
        let (x, y) = (x as i64, y as i64);
        let (x, y) = match self.wrap {
            Wrap::Repeat => (x.rem_euclid(w), y.rem_euclid(h)),
            Wrap::Clamp => (x.clamp(0, w - 1), y.clamp(0, h - 1)),
        };
        self.image.texels[(y * w + x) as usize]
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
            image: Arc::new(Image {
                width: 2,
                height: 2,
                texels: vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE],
            }),
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
