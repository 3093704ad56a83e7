//! The split of one node in the binned-SAH build: bin the primitives' centroids along all three
//! axes in one pass, choose the cheapest plane, and partition the primitives by it while
//! collecting the two children's bounds, so that a child never re-reads its primitives just to
//! bound them.
//!
//! Large nodes bin in parallel: each chunk of primitives fills bins of its own and the bins are
//! merged. Merging is exact (boxes are unions, counts are integers), so the chosen split is the
//! one a single pass would choose. The partition stays serial and in place: its element order
//! decides the tree, and Lomuto's partition keeps the left part's order but not the right's,
//! which a parallel partition could reproduce only with a scratch copy and several more passes
//! over memory. The serial partitions of the few nodes above a million triangles are a small
//! part of the build (measured: docs/benchmarks.md, «Design measurements», `accel::split`).

use glam::{Vec3, Vec3A};
use rayon::prelude::*;

use super::{BINS, MAX_DEPTH, MAX_LEAF};
use crate::math::Aabb;

/// A primitive as the build sees it: its box, the box's center and its triangle index.
#[derive(Clone, Copy)]
pub(super) struct BuildPrim {
    pub bounds: Aabb,
    pub centroid: Vec3,
    pub index: u32,
}

/// Primitives binned per task when binning in parallel.
const BIN_CHUNK: usize = 16 * 1024;

/// A chosen split: the left part's size, and each part's bounds and centroid bounds.
pub(super) struct Split {
    pub mid: usize,
    pub left: (Aabb, Aabb),
    pub right: (Aabb, Aabb),
}

/// The bounds of `prims`' boxes and of their centroids.
pub(super) fn bounds_of(prims: &[BuildPrim]) -> (Aabb, Aabb) {
    prims.iter().fold((Aabb::EMPTY, Aabb::EMPTY), |(b, c), p| {
        (b.union(p.bounds), c.grow(p.centroid))
    })
}

/// A bin's box with SIMD corners: a union is two instructions, where [`Aabb`]'s `Vec3`
/// corners take six (binning was half of a large mesh's build). Minima and maxima are exact,
/// so the boxes are [`Aabb`]'s, bit for bit.
#[derive(Clone, Copy)]
struct BinBox {
    min: Vec3A,
    max: Vec3A,
}

impl BinBox {
    const EMPTY: BinBox = BinBox {
        min: Vec3A::INFINITY,
        max: Vec3A::NEG_INFINITY,
    };

    #[inline(always)]
    fn union(self, other: BinBox) -> BinBox {
        BinBox {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    fn aabb(self) -> Aabb {
        Aabb {
            min: self.min.into(),
            max: self.max.into(),
        }
    }

    /// [`Aabb::half_area`] of a box that is not empty (a union of occupied bins), without
    /// the emptiness test: the same arithmetic, so the same bits.
    #[inline(always)]
    fn half_area(self) -> f32 {
        let e = self.max - self.min;
        e.x * e.y + e.y * e.z + e.z * e.x
    }
}

/// Per axis, the bounds and number of the primitives whose centroid falls in each bin, and
/// which bins hold any. Bins that hold none are always empty boxes with a zero count, so that
/// one `Bins` serves every split of a subtree: [`Bins::clear`] empties only the bins used.
#[derive(Clone, Copy)]
pub(super) struct Bins {
    bounds: [[BinBox; BINS]; 3],
    counts: [[u32; BINS]; 3],
    /// Bit `b` of `occupied[axis]` is set when bin `b` of `axis` holds a primitive.
    occupied: [u16; 3],
}

impl Bins {
    pub(super) const EMPTY: Bins = Bins {
        bounds: [[BinBox::EMPTY; BINS]; 3],
        counts: [[0; BINS]; 3],
        occupied: [0; 3],
    };

    /// Adds `prims` on every axis, for centroids starting at `min` with `scale` bins per unit.
    fn add(&mut self, prims: &[BuildPrim], min: Vec3, scale: Vec3) {
        for p in prims {
            let at = bin_position(p.centroid, min, scale);
            let bounds = BinBox {
                min: p.bounds.min.into(),
                max: p.bounds.max.into(),
            };
            for axis in 0..3 {
                let b = bin_at(at[axis]);
                self.bounds[axis][b] = self.bounds[axis][b].union(bounds);
                self.counts[axis][b] += 1;
            }
        }
    }

    /// Marks the bins that hold a primitive, once binning is done (per bin, not per
    /// primitive: a primitive is binned at every level of the tree, a bin once per node).
    fn mark_occupied(&mut self) {
        for axis in 0..3 {
            let counts = &self.counts[axis];
            self.occupied[axis] = (0..BINS).fold(0, |m, b| m | u16::from(counts[b] > 0) << b);
        }
    }

    fn merge(mut self, other: Bins) -> Bins {
        for axis in 0..3 {
            for b in 0..BINS {
                self.bounds[axis][b] = self.bounds[axis][b].union(other.bounds[axis][b]);
                self.counts[axis][b] += other.counts[axis][b];
            }
        }
        self
    }

    /// Empties the bins in use, leaving `Bins::EMPTY`.
    fn clear(&mut self) {
        for axis in 0..3 {
            for b in occupied(self.occupied[axis]) {
                self.bounds[axis][b] = BinBox::EMPTY;
                self.counts[axis][b] = 0;
            }
            self.occupied[axis] = 0;
        }
    }
}

// Occupied bins are bits of a `u16`.
const _: () = assert!(BINS <= 16);

/// The bins set in `mask`, in increasing order.
fn occupied(mut mask: u16) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let b = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            b
        })
    })
}

/// The bins set in `mask`, in decreasing order.
fn occupied_descending(mut mask: u16) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let b = 15 - mask.leading_zeros() as usize;
            mask &= !(1 << b);
            b
        })
    })
}

/// Where `centroid` falls in bin units along each axis; [`bin_at`] turns a coordinate into a bin.
/// Component by component this is `(c − min) · (BINS / extent)`, the same arithmetic for the
/// binning and the partition, so that both put every primitive in the same bin.
fn bin_position(centroid: Vec3, min: Vec3, scale: Vec3) -> Vec3 {
    (centroid - min) * scale
}

fn bin_at(position: f32) -> usize {
    // Clamped as a float, then cut: the saturating `as usize` of the position (NaN, from a
    // centroid on an axis without extent, and negatives to bin 0) took a third of the
    // binning's instructions; this gives the same bin for every `f32`.
    let clamped = if position > 0.0 { position } else { 0.0 };
    clamped.min((BINS - 1) as f32) as i32 as usize
}

/// Chooses a split by binned SAH over all three axes (binning in parallel chunks on the current
/// rayon pool when `parallel`) and partitions `prims` by it. `bounds` and `centroids` bound
/// `prims`' boxes and centroids; `bins` is scratch space, empty on entry and on return.
/// Returns `None` when a leaf is cheaper.
pub(super) fn split(
    prims: &mut [BuildPrim],
    (bounds, centroids): (Aabb, Aabb),
    depth: usize,
    parallel: bool,
    bins: &mut Bins,
) -> Option<Split> {
    let split = choose(prims, bounds, centroids, depth, parallel, bins);
    bins.clear();
    split
}

fn choose(
    prims: &mut [BuildPrim],
    bounds: Aabb,
    centroids: Aabb,
    depth: usize,
    parallel: bool,
    bins: &mut Bins,
) -> Option<Split> {
    let n = prims.len();
    // Past MAX_DEPTH (only reached by adversarial inputs, such as triangles spread over
    // hundreds of orders of magnitude) a leaf, however large, keeps traversal in its stack.
    if n <= 2 || depth >= MAX_DEPTH {
        return None;
    }
    let extent = centroids.extent();
    let (min, scale) = (centroids.min, Vec3::splat(BINS as f32) / extent);
    // Axes without extent are binned too (every centroid lands in one bin) but never chosen.
    if parallel {
        *bins = prims
            .par_chunks(BIN_CHUNK)
            .map(|chunk| {
                let mut bins = Bins::EMPTY;
                bins.add(chunk, min, scale);
                bins
            })
            .reduce(|| Bins::EMPTY, Bins::merge);
    } else {
        bins.add(prims, min, scale);
    }
    bins.mark_occupied();
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, bin)
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let (bin_bounds, bin_counts) = (&bins.bounds[axis], &bins.counts[axis]);
        // Only the planes just right of an occupied bin need a cost: past an empty bin, a
        // plane splits the primitives as the plane before it does, at the same cost, and the
        // first of equal costs wins. Empty bins change no sum, so skipping them keeps every
        // cost bit for bit what a sweep over all bins computes.
        let used = bins.occupied[axis];
        // Sweep from the right: `right_cost[b]` is the cost of the bins from `b` on.
        let mut right_cost = [0.0f32; BINS];
        let (mut acc, mut count) = (BinBox::EMPTY, 0);
        for b in occupied_descending(used) {
            acc = acc.union(bin_bounds[b]);
            count += bin_counts[b] as usize;
            right_cost[b] = acc.half_area() * count as f32;
        }
        let (mut acc, mut count) = (BinBox::EMPTY, 0);
        let mut bins_used = occupied(used).peekable();
        while let (Some(b), Some(&next)) = (bins_used.next(), bins_used.peek()) {
            acc = acc.union(bin_bounds[b]);
            count += bin_counts[b] as usize;
            // `next` is the first occupied bin right of the plane after `b`.
            let cost = acc.half_area() * count as f32 + right_cost[next];
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b));
            }
        }
    }
    // SAH with traversal cost 1 and intersection cost 1, relative to the parent's area.
    let leaf_cost = n as f32;
    let area = bounds.half_area().max(f32::MIN_POSITIVE);
    match best {
        Some((cost, axis, bin)) if n > MAX_LEAF || 1.0 + cost / area < leaf_cost => {
            let (min, scale) = (min[axis], scale[axis]);
            let (mid, left_centroids, right_centroids) =
                partition(prims, |c| bin_at((c[axis] - min) * scale) <= bin);
            let union = |bins: &[BinBox]| {
                let all = bins.iter().fold(BinBox::EMPTY, |a, &b| a.union(b));
                all.aabb()
            };
            let bin_bounds = &bins.bounds[axis];
            Some(Split {
                mid,
                left: (union(&bin_bounds[..=bin]), left_centroids),
                right: (union(&bin_bounds[bin + 1..]), right_centroids),
            })
        }
        Some(_) => None,
        // Every centroid coincides: SAH cannot separate them, so split by count to keep
        // leaves small.
        None if n > MAX_LEAF => {
            let mid = n / 2;
            Some(Split {
                mid,
                left: bounds_of(&prims[..mid]),
                right: bounds_of(&prims[mid..]),
            })
        }
        None => None,
    }
}

/// Moves the elements whose centroid satisfies `left` to the front (Lomuto's partition: the
/// left part keeps its order, the right part does not); returns how many there are and the
/// bounds of both parts' centroids.
fn partition(prims: &mut [BuildPrim], left: impl Fn(Vec3) -> bool) -> (usize, Aabb, Aabb) {
    let (mut i, mut left_centroids, mut right_centroids) = (0, Aabb::EMPTY, Aabb::EMPTY);
    for j in 0..prims.len() {
        let c = prims[j].centroid;
        if left(c) {
            left_centroids = left_centroids.grow(c);
            prims.swap(i, j);
            i += 1;
        } else {
            right_centroids = right_centroids.grow(c);
        }
    }
    (i, left_centroids, right_centroids)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_position_falls_in_the_bin_the_saturating_cast_gives() {
        let cast = |p: f32| (p as usize).min(BINS - 1);
        let mut positions = vec![
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            -0.0,
            0.0,
            f32::MIN_POSITIVE,
            -1e30,
            1e30,
            (BINS - 1) as f32,
            BINS as f32,
            (BINS as f32).next_down(),
        ];
        positions.extend((-40..=40 * BINS as i32).map(|i| i as f32 / 40.0));
        positions.extend((0..BINS).map(|b| (b as f32).next_down()));
        for p in positions {
            assert_eq!(bin_at(p), cast(p), "{p}");
        }
    }

    #[test]
    fn bin_boxes_are_the_unions_of_aabbs() {
        let a = Aabb {
            min: Vec3::new(-1.0, 2.0, 0.5),
            max: Vec3::new(0.0, 3.0, 4.0),
        };
        let b = Aabb {
            min: Vec3::new(-0.5, -7.0, 1.0),
            max: Vec3::new(2.0, 1.0, 1.5),
        };
        let boxed = |x: Aabb| BinBox {
            min: x.min.into(),
            max: x.max.into(),
        };
        let union = BinBox::EMPTY.union(boxed(a)).union(boxed(b)).aabb();
        assert_eq!(union, Aabb::EMPTY.union(a).union(b));
        assert_eq!(BinBox::EMPTY.aabb(), Aabb::EMPTY);
    }
}
