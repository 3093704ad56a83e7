//! Progressive rendering: a pixel's samples taken in passes over the whole film. A pixel's
//! sum carries over from pass to pass, its samples added in the same order as in one pass, so
//! the final image is the same bit for bit.

use std::ops::Range;
use std::sync::Mutex;

use super::{Film, PixelBounds, Pixels};
use crate::math::Rgb;

/// A finished pass of a progressive render (see [`RenderOptions::passes`]).
#[derive(Clone, Copy, Debug)]
pub struct Pass<'f> {
    /// 0 for the first pass.
    pub index: usize,
    /// Samples per pixel so far: the image is each pixel's mean over its first `samples`
    /// samples (in the sampler's order for the full count; not the image of a render with
    /// `samples` samples, whose pattern differs).
    pub samples: u32,
    /// The image so far, of the region's size.
    pub film: &'f Film,
}

/// What receives the passes of a progressive render.
pub type PassSink<'a> = dyn Fn(&Pass) + Sync + 'a;

/// The samples of each pass of a progressive render of `spp` samples per pixel: the first
/// pass takes sample 0, each next one doubles the samples done, the last ends at `spp`
/// (1, 2, 4, … samples in all).
pub(super) fn pass_samples(spp: u32) -> Vec<Range<u32>> {
    let mut passes = Vec::new();
    let mut done = 0;
    while done < spp {
        let next = (done * 2).clamp(1, spp);
        passes.push(done..next);
        done = next;
    }
    passes
}

/// Fills `values` with the sums so far of `tile`'s pixels (`from_film`), or zeros in the
/// first pass.
pub(super) fn load(
    film: &Mutex<Pixels>,
    region: PixelBounds,
    tile: &PixelBounds,
    from_film: bool,
    values: &mut Vec<Rgb>,
) {
    let (tw, th) = ((tile.x1 - tile.x0) as usize, (tile.y1 - tile.y0) as usize);
    values.clear();
    if !from_film {
        values.resize(tw * th, Rgb::ZERO);
        return;
    }
    let rw = (region.x1 - region.x0) as usize;
    let film = film.lock().unwrap_or_else(|e| e.into_inner());
    for row in 0..th {
        let at = ((tile.y0 - region.y0) as usize + row) * rw + (tile.x0 - region.x0) as usize;
        values.extend_from_slice(&film.0[at..at + tw]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passes_double_the_samples_and_end_at_all_of_them() {
        assert_eq!(pass_samples(1).len(), 1);
        assert_eq!(pass_samples(1)[0], 0..1);
        assert_eq!(pass_samples(4), [0..1, 1..2, 2..4]);
        assert_eq!(pass_samples(9), [0..1, 1..2, 2..4, 4..8, 8..9]);
        assert_eq!(pass_samples(16).last(), Some(&(8..16)));
    }
}
