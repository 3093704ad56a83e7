//! The film: linear RGB pixel values, row 0 at the top.

use crate::math::Rgb;

/// A rendered image in linear RGB (unclamped floats), row-major from the top row.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height` pixels, row-major, row 0 at the top.
    pub pixels: Vec<Rgb>,
}

impl Film {
    /// The pixel in column `x`, row `y` (from the top).
    pub fn get(&self, x: u32, y: u32) -> Rgb {
        self.pixels[(y as usize) * (self.width as usize) + x as usize]
    }
}
