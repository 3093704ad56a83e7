//! Phong materials of SPEC §6 (docs/spec.md).

use crate::math::Rgb;

/// The coefficients of the (Blinn-)Phong model, with an optional texture that multiplies the
/// ambient and diffuse colors.
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
}

impl Default for Material {
    /// The format's default: diffuse 0.8 grey, ambient equal to diffuse, no specular, p = 16.
    fn default() -> Self {
        Self {
            ambient: Rgb::splat(0.8),
            diffuse: Rgb::splat(0.8),
            specular: Rgb::ZERO,
            shininess: 16.0,
            texture: None,
        }
    }
}
