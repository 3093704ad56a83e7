//! The film while it renders: each pixel's sums over its samples so far (colour, the count of
//! samples that hit, AOVs), filled in tile by tile by the workers, and the image they make.

use std::sync::Mutex;

use super::{AovPixel, PixelBounds};
use crate::math::Rgb;

/// Sums, row-major: of a region of the film (its hit counts empty unless the render computes
/// alpha, its AOVs unless asked for), or of one tile as a worker adds to them (hit counts
/// always counted, kept in the film only with alpha; the AOVs of the rows done).
#[derive(Default)]
pub(super) struct Sums {
    pub(super) colors: Vec<Rgb>,
    pub(super) hits: Vec<f32>,
    pub(super) aovs: Vec<AovPixel>,
}

/// Which pixels of `region` belong to row `row` of `tile`.
fn row_at(region: PixelBounds, tile: &PixelBounds, row: usize) -> std::ops::Range<usize> {
    let rw = (region.x1 - region.x0) as usize;
    let tw = (tile.x1 - tile.x0) as usize;
    let at = ((tile.y0 - region.y0) as usize + row) * rw + (tile.x0 - region.x0) as usize;
    at..at + tw
}

impl Sums {
    /// Fills the tile's colours and hit counts with their sums so far in `film`
    /// (`from_film`), or zeros in the first pass; clears its AOVs.
    pub(super) fn load(
        &mut self,
        film: &Mutex<Sums>,
        region: PixelBounds,
        tile: &PixelBounds,
        from_film: bool,
    ) {
        let len = ((tile.x1 - tile.x0) * (tile.y1 - tile.y0)) as usize;
        self.colors.clear();
        self.hits.clear();
        self.aovs.clear();
        if !from_film {
            self.colors.resize(len, Rgb::ZERO);
            self.hits.resize(len, 0.0);
            return;
        }
        let film = film.lock().unwrap_or_else(|e| e.into_inner());
        for row in 0..(tile.y1 - tile.y0) as usize {
            let at = row_at(region, tile, row);
            self.colors.extend_from_slice(&film.colors[at.clone()]);
            match film.hits.is_empty() {
                true => self.hits.resize(self.hits.len() + at.len(), 0.0),
                false => self.hits.extend_from_slice(&film.hits[at]),
            }
        }
    }

    /// Divides the sums by `count` samples: the tile's finished values.
    pub(super) fn divide(&mut self, count: f32) {
        self.colors.iter_mut().for_each(|v| *v /= count);
        self.hits.iter_mut().for_each(|v| *v /= count);
    }

    /// Copies the tile's values into `film`, of `region`: hit counts only when the film keeps
    /// them, AOVs when computed.
    pub(super) fn store(&self, film: &Mutex<Sums>, region: PixelBounds, tile: &PixelBounds) {
        let tw = (tile.x1 - tile.x0) as usize;
        // A worker that panicked while holding the lock left whole tiles: the film is still
        // good.
        let mut film = film.lock().unwrap_or_else(|e| e.into_inner());
        let Sums { colors, hits, aovs } = &mut *film;
        for (row, chunk) in self.colors.chunks(tw).enumerate() {
            colors[row_at(region, tile, row)].copy_from_slice(chunk);
        }
        if !hits.is_empty() {
            for (row, chunk) in self.hits.chunks(tw).enumerate() {
                hits[row_at(region, tile, row)].copy_from_slice(chunk);
            }
        }
        for (row, chunk) in self.aovs.chunks(tw).enumerate() {
            aovs[row_at(region, tile, row)].copy_from_slice(chunk);
        }
    }
}

/// The image of `sums` (rows `y0..y1` of `width` values) after `count` samples; with
/// `preview`, after the even rows' first sample, each odd row showing its
/// [`preview_row`](super::passes::preview_row).
pub(super) fn image<T: Copy + std::ops::Div<f32, Output = T>>(
    sums: &[T],
    width: usize,
    (y0, y1): (u32, u32),
    preview: bool,
    count: f32,
) -> Vec<T> {
    if !preview {
        return sums.iter().map(|&v| v / count).collect();
    }
    (y0..y1)
        .flat_map(|y| {
            let from = (super::passes::preview_row(y, (y0, y1)) - y0) as usize * width;
            sums[from..from + width].iter().map(move |&v| v / count)
        })
        .collect()
}
