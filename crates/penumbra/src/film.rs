//! The film: linear RGB pixel values, row 0 at the top, and their coverage when asked for.

use crate::math::Rgb;

/// A rendered image in linear RGB (unclamped floats), row-major from the top row.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height` pixels, row-major, row 0 at the top; premultiplied by
    /// [`Film::alpha`] when there is one.
    pub pixels: Vec<Rgb>,
    /// Each pixel's coverage, in the order of `pixels`: the fraction of its samples whose
    /// camera ray hit geometry, from a render with
    /// [`RenderSettings::alpha`](crate::RenderSettings::alpha); `None` otherwise.
    pub alpha: Option<Vec<f32>>,
}

impl Film {
    /// The pixel in column `x`, row `y` (from the top).
    pub fn get(&self, x: u32, y: u32) -> Rgb {
        self.pixels[(y as usize) * (self.width as usize) + x as usize]
    }

    /// The coverage of the pixel in column `x`, row `y` (from the top): 1 for a film without
    /// alpha.
    pub fn alpha_at(&self, x: u32, y: u32) -> f32 {
        let at = (y as usize) * (self.width as usize) + x as usize;
        self.alpha.as_ref().map_or(1.0, |a| a[at])
    }
}
