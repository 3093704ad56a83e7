//! Progressive rendering: a pixel's samples taken in passes over the whole film. A pixel's
//! sum carries over from pass to pass, its samples added in the same order as in one pass, so
//! the final image is the same bit for bit.
//!
//! The first sample is taken in two passes, of the even rows and then of the odd ones, so
//! that a whole frame (each even row shown on the odd row below it too: the preview) comes
//! after half the work of a sample; the second pass completes the first sample. No work is
//! done twice.

use std::ops::Range;

use super::Film;

/// A finished pass of a progressive render (see [`RenderOptions::passes`]).
#[derive(Clone, Copy, Debug)]
pub struct Pass<'f> {
    /// 0 for the first pass.
    pub index: usize,
    /// Samples per pixel so far: the image is each pixel's mean over its first `samples`
    /// samples (in the sampler's order for the full count; not the image of a render with
    /// `samples` samples, whose pattern differs). 0 for the preview, the first pass of a
    /// film of two rows or more: the first sample of every even row (counted from the full
    /// film's top), each odd row showing the row above it (the row below for a region that
    /// starts on an odd row).
    pub samples: u32,
    /// The image so far, of the region's size.
    pub film: &'f Film,
}

/// What receives the passes of a progressive render.
pub type PassSink<'a> = dyn Fn(&Pass) + Sync + 'a;

/// Which rows of the film a pass renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Rows {
    All,
    Even,
    Odd,
}

impl Rows {
    /// True when the pass renders row `y` of the full film.
    pub fn has(self, y: u32) -> bool {
        match self {
            Rows::All => true,
            Rows::Even => y.is_multiple_of(2),
            Rows::Odd => y % 2 == 1,
        }
    }
}

/// The passes of a progressive render of `spp` samples per pixel on a film of `height`
/// rows: sample 0 of the even rows then of the odd ones (one pass of all rows for a film of
/// one row), then each pass doubles the samples done, the last ends at `spp` (1, 2, 4, …
/// samples in all).
pub(super) fn plan(spp: u32, height: u32) -> Vec<(Rows, Range<u32>)> {
    let mut passes = match height > 1 {
        true => vec![(Rows::Even, 0..1), (Rows::Odd, 0..1)],
        false => vec![(Rows::All, 0..1)],
    };
    let mut done = 1;
    while done < spp {
        let next = (done * 2).min(spp);
        passes.push((Rows::All, done..next));
        done = next;
    }
    passes
}

/// The rows of the preview of a region `y0..y1` whose even rows are rendered: for each row,
/// the row it shows (itself when even, else its neighbour above, or below at the top).
pub(super) fn preview_row(y: u32, (y0, y1): (u32, u32)) -> u32 {
    match (y.is_multiple_of(2), y > y0) {
        (true, _) => y,
        (false, true) => y - 1,
        (false, false) => (y + 1).min(y1 - 1),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passes_split_the_first_sample_by_rows_then_double_and_end_at_all_samples() {
        let samples = |spp, h| plan(spp, h).into_iter().map(|(_, s)| s).collect::<Vec<_>>();
        assert_eq!(plan(1, 1), [(Rows::All, 0..1)]);
        assert_eq!(plan(1, 8), [(Rows::Even, 0..1), (Rows::Odd, 0..1)]);
        assert_eq!(samples(4, 8), [0..1, 0..1, 1..2, 2..4]);
        assert_eq!(samples(9, 2), [0..1, 0..1, 1..2, 2..4, 4..8, 8..9]);
        assert_eq!(plan(16, 3).last(), Some(&(Rows::All, 8..16)));
        // Every row gets sample 0 once.
        for y in 0..5 {
            let passes = plan(4, 5);
            let first = passes.iter().filter(|(r, s)| s.start == 0 && r.has(y));
            assert_eq!(first.count(), 1, "row {y}");
        }
    }

    #[test]
    fn a_preview_row_shows_a_rendered_row_next_to_it() {
        for (y0, y1) in [(0, 7), (3, 9), (5, 6), (1, 3)] {
            for y in y0..y1 {
                let shown = preview_row(y, (y0, y1));
                assert!((y0..y1).contains(&shown), "{y} in {y0}..{y1}: {shown}");
                assert!(shown.abs_diff(y) <= 1);
                assert!(
                    shown.is_multiple_of(2) || y1 - y0 == 1,
                    "{y} in {y0}..{y1}: {shown}"
                );
            }
        }
    }
}
