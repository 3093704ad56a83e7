//! Piecewise-constant distributions for importance sampling (Pharr, Jakob and Humphreys,
//! "Physically Based Rendering", 4th ed., §A.1 and §A.5): a 1D one over `n` equal cells of
//! `[0, 1)`, and a 2D one over a grid, sampled by inverting the marginal CDF over rows and then
//! the row's conditional CDF. Inversion keeps stratification: strata of `[0, 1)²` map to
//! disjoint regions. The CDFs are kept in f64, so that a faint cell beside a sun millions of
//! times brighter keeps its probability (only a cell below about 1e-16 of the total would
//! not).

use glam::Vec2;

use crate::simd::prefetch;

/// A distribution over `n` equal cells of `[0, 1)` with probabilities proportional to
/// non-negative weights.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Distribution1D {
    /// `cdf[i]` = P(cell < i), `n + 1` entries from 0 to 1.
    cdf: Vec<f64>,
    /// Sum of the weights (0 for an all-zero distribution, which samples uniformly).
    total: f64,
    /// `guide[k]` (k in `0..=n`) is the cell `u = k/n` falls in: a search for `u` only reads
    /// the CDF between the guides of its neighbouring fractions, a few entries where a binary
    /// search over all `n` would touch about log₂ n cache lines (Chen and Asau's guide table).
    guide: Vec<u32>,
}

impl Distribution1D {
    /// The distribution of `weights` (finite, ≥ 0). All zero (or empty) samples uniformly.
    pub(crate) fn new(weights: &[f32]) -> Distribution1D {
        let total: f64 = weights.iter().map(|&w| f64::from(w.max(0.0))).sum();
        let n = weights.len();
        let mut cdf = Vec::with_capacity(n + 1);
        cdf.push(0.0);
        let mut sum = 0.0f64;
        if total > 0.0 {
            let scale = 1.0 / total;
            cdf.extend(weights.iter().map(|&w| {
                sum += f64::from(w.max(0.0));
                sum * scale
            }));
        } else {
            let scale = 1.0 / n as f64;
            cdf.extend((1..=n).map(|i| i as f64 * scale));
        }
        // Exactly 1 at the end, whatever the rounding of the sums.
        if let Some(last) = cdf.last_mut().filter(|_| n > 0) {
            *last = 1.0;
        }
        let guide = guide(&cdf);
        Distribution1D { cdf, total, guide }
    }

    /// Number of cells.
    pub(crate) fn len(&self) -> usize {
        self.cdf.len() - 1
    }

    /// Sum of the weights it was made from.
    pub(crate) fn total(&self) -> f64 {
        self.total
    }

    /// Probability of cell `i`.
    pub(crate) fn probability(&self, i: usize) -> f64 {
        self.cdf[i + 1] - self.cdf[i]
    }

    /// The cell `u` in `[0, 1)` falls in and `u`'s position inside it, in `[0, 1)`. Cells of
    /// probability 0 are never chosen.
    pub(crate) fn sample(&self, u: f32) -> (usize, f32) {
        let (n, u) = (self.len(), f64::from(u));
        // The last i with cdf[i] <= u among cells 0..n: the guides of the fractions k/n around
        // u bound it (one fraction of slack each side absorbs the rounding of u·n).
        let k = ((u * n as f64) as usize).min(n);
        let (lo, hi) = (self.guide[k.saturating_sub(1)], self.guide[(k + 2).min(n)]);
        let (lo, hi) = (lo as usize, hi as usize);
        let i = lo + self.cdf[lo + 1..=hi].partition_point(|&c| c <= u);
        let (lo, hi) = (self.cdf[i], self.cdf[i + 1]);
        let inside = match hi > lo {
            true => (((u - lo) / (hi - lo)) as f32).clamp(0.0, ONE_BELOW),
            false => 0.5,
        };
        (i, inside)
    }
}

impl Distribution1D {
    /// The guide entries [`sample`](Self::sample) of `u` reads first.
    #[inline(always)]
    fn guides(&self, u: f32) -> (usize, usize) {
        let n = self.len();
        let k = ((f64::from(u) * n as f64) as usize).min(n);
        (k.saturating_sub(1), (k + 2).min(n))
    }

    /// Asks the CPU to start loading what [`sample`](Self::sample) of `u` reads first, its
    /// guide entries: a hint that changes no result.
    #[inline(always)]
    fn prefetch_guides(&self, u: f32) {
        let (lo, hi) = self.guides(u);
        prefetch(&self.guide[lo]);
        prefetch(&self.guide[hi]);
    }

    /// Asks the CPU to start loading the CDF entries [`sample`](Self::sample) of `u` searches
    /// (once its guide entries are in: it reads them).
    #[inline(always)]
    fn prefetch_cdf(&self, u: f32) {
        let (lo, hi) = self.guides(u);
        let (lo, hi) = (self.guide[lo] as usize, self.guide[hi] as usize);
        prefetch(&self.cdf[lo]);
        prefetch(&self.cdf[(lo + hi) / 2 + 1]);
        prefetch(&self.cdf[hi + 1]);
    }
}

/// The guide table of a CDF of `n + 1` entries: for each k in `0..=n`, the last cell i in
/// `0..n` with `cdf[i] <= k/n`, found in one forward pass.
fn guide(cdf: &[f64]) -> Vec<u32> {
    let n = cdf.len() - 1;
    let mut i = 0;
    (0..=n)
        .map(|k| {
            let v = k as f64 / n.max(1) as f64;
            while i + 1 < n && cdf[i + 1] <= v {
                i += 1;
            }
            i as u32
        })
        .collect()
}

/// The largest f32 below 1.
pub(crate) const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

/// A distribution over a `width × height` grid of cells (row-major, row 0 first) with
/// probabilities proportional to non-negative weights.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Distribution2D {
    /// One per row: the row's cells.
    rows: Vec<Distribution1D>,
    /// Over the rows, by their sums.
    marginal: Distribution1D,
}

impl Distribution2D {
    /// The distribution of `weights`, `width × height` of them row by row.
    #[cfg(test)]
    pub(crate) fn new(weights: &[f32], width: usize, height: usize) -> Distribution2D {
        assert_eq!(weights.len(), width * height, "one weight per cell");
        Distribution2D::from_rows(
            weights
                .chunks_exact(width.max(1))
                .map(Distribution1D::new)
                .collect(),
        )
    }

    /// The distribution whose rows are `rows` (each over the same number of cells), weighing
    /// each row by its total.
    pub(crate) fn from_rows(rows: Vec<Distribution1D>) -> Distribution2D {
        let sums: Vec<f32> = rows.iter().map(|r| r.total() as f32).collect();
        Distribution2D {
            marginal: Distribution1D::new(&sums),
            rows,
        }
    }

    /// Probability of cell `(x, y)`.
    pub(crate) fn probability(&self, x: usize, y: usize) -> f64 {
        self.marginal.probability(y) * self.rows[y].probability(x)
    }

    /// The cell `u` in `[0, 1)²` maps to, and `u`'s position inside it in `[0, 1)²`.
    pub(crate) fn sample(&self, u: Vec2) -> ((usize, usize), Vec2) {
        let (y, fy) = self.marginal.sample(u.y);
        let (x, fx) = self.rows[y].sample(u.x);
        ((x, y), Vec2::new(fx, fy))
    }

    /// [`sample`](Self::sample) of each of `us`, into `out` (as long): the same answers, found
    /// in passes over all of them. The rows of a large map lie far apart in memory, and a
    /// sample waits on each of its loads in turn (a row's guide entries, then the CDF entries
    /// they point to); in passes, the loads of every sample are asked for before any is read,
    /// and they overlap. (The marginal distribution is small and stays cached.)
    #[inline(always)]
    pub(crate) fn sample_all(&self, us: &[Vec2], out: &mut [((usize, usize), Vec2)]) {
        for (o, &u) in out.iter_mut().zip(us) {
            let (y, fy) = self.marginal.sample(u.y);
            self.rows[y].prefetch_guides(u.x);
            *o = ((0, y), Vec2::new(0.0, fy));
        }
        for (&((_, y), _), &u) in out.iter().zip(us) {
            self.rows[y].prefetch_cdf(u.x);
        }
        for (((x, y), f), &u) in out.iter_mut().zip(us) {
            (*x, f.x) = self.rows[*y].sample(u.x);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_dimension_follows_the_weights() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0]);
        assert_eq!(d.probability(0), 0.25);
        assert_eq!(d.probability(1), 0.0);
        assert_eq!(d.probability(2), 0.75);
        assert_eq!(d.sample(0.0), (0, 0.0));
        assert_eq!(d.sample(0.125), (0, 0.5));
        // The empty cell is skipped: 0.25 is the start of cell 2.
        assert_eq!(d.sample(0.25), (2, 0.0));
        assert_eq!(d.sample(0.625), (2, 0.5));
        let (i, f) = d.sample(ONE_BELOW);
        assert_eq!(i, 2);
        assert!(f < 1.0);
    }

    #[test]
    fn the_guided_search_finds_what_a_binary_search_finds() {
        // Weights with runs of empty cells and a few huge ones, and u on and beside the CDF's
        // own values and the guides' fractions.
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 40) as u32
        };
        for n in [1usize, 2, 3, 7, 64, 1000] {
            let weights: Vec<f32> = (0..n)
                .map(|_| match next() % 4 {
                    0 => 0.0,
                    1 => 1e6,
                    _ => (next() % 100) as f32,
                })
                .collect();
            let d = Distribution1D::new(&weights);
            let mut us: Vec<f32> = d.cdf.iter().map(|&c| c as f32).collect();
            us.extend((0..=n).map(|k| k as f32 / n as f32));
            us.extend((0..2000).map(|_| next() as f32 / (1u32 << 24) as f32));
            for u in us {
                let u = u.clamp(0.0, ONE_BELOW);
                let wide = f64::from(u);
                let i = d.cdf[1..n].partition_point(|&c| c <= wide);
                assert_eq!(d.sample(u).0, i, "n {n}, u {u}");
            }
        }
    }

    #[test]
    fn sampling_in_passes_answers_as_one_at_a_time() {
        // A map with a bright spot, empty runs and faint cells, and u on cell boundaries.
        let (w, h) = (37, 11);
        let weights: Vec<f32> = (0..w * h)
            .map(|k| match k % 7 {
                0 => 0.0,
                3 if k / w == 4 => 1e6,
                _ => (k % 13) as f32 * 1e-3,
            })
            .collect();
        let d = Distribution2D::new(&weights, w, h);
        let us: Vec<Vec2> = (0..64)
            .map(|k| Vec2::new((k % 8) as f32 / 8.0, ((k * 5) % 64) as f32 / 64.0))
            .map(|u| u.min(Vec2::splat(ONE_BELOW)))
            .collect();
        let mut all = vec![((0, 0), Vec2::ZERO); us.len()];
        d.sample_all(&us, &mut all);
        for (u, got) in us.iter().zip(&all) {
            assert_eq!(*got, d.sample(*u), "u {u}");
        }
    }

    #[test]
    fn all_zero_is_uniform() {
        let d = Distribution1D::new(&[0.0; 4]);
        assert_eq!(d.probability(3), 0.25);
        let (i, f) = d.sample(0.6);
        assert_eq!(i, 2);
        assert!((f - 0.4).abs() < 1e-6);
    }

    #[test]
    fn strata_map_to_cells_in_proportion() {
        // Counting where a fine grid of u lands recovers the probabilities.
        let weights = [0.0, 2.0, 1.0, 1.0, 0.0, 4.0];
        let d = Distribution2D::new(&weights, 3, 2);
        let total: f32 = weights.iter().sum();
        let n = 400;
        let mut counts = [0u32; 6];
        for i in 0..n {
            for j in 0..n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let ((x, y), f) = d.sample(u);
                assert!(f.cmpge(Vec2::ZERO).all() && f.cmplt(Vec2::ONE).all());
                counts[y * 3 + x] += 1;
            }
        }
        for (c, (&count, &w)) in counts.iter().zip(&weights).enumerate() {
            let expected = w / total;
            let got = count as f32 / (n * n) as f32;
            assert!(
                (got - expected).abs() < 2e-3,
                "cell {c}: {got} vs {expected}"
            );
            assert!((d.probability(c % 3, c / 3) as f32 - expected).abs() < 1e-6);
        }
    }

    #[test]
    fn a_tiny_cell_among_large_ones_keeps_its_probability() {
        // A sun of one bright texel in a 4096 × 2048 map of faint sky still gets sampled.
        let (w, h) = (4096, 2048);
        let mut weights = vec![1e-3f32; w * h];
        weights[1000 * w + 3000] = 1e6;
        let d = Distribution2D::new(&weights, w, h);
        let p = d.probability(3000, 1000);
        let expected = 1e6 / (1e6 + 1e-3 * (w * h - 1) as f64);
        assert!((p - expected).abs() < 1e-4);
        assert!(d.probability(0, 0) > 0.0);
    }
}
