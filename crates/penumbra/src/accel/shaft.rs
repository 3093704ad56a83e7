//! Shaft culling (Haines and Wallace, "Shaft Culling for Efficient Ray-Cast Radiosity", 1991):
//! the few triangles that could stop any of a batch's shadow rays, found once per batch.
//!
//! The segments between a few neighbouring shading points and the samples of a light all lie
//! in the convex hull of those points and samples: the shaft. A triangle that lies wholly
//! outside the shaft cannot meet any of them. The shaft is described by its extent along a few
//! axes (the coordinate axes, and three across the shaft's direction), and a box or a triangle
//! whose extent along one of them is apart from the shaft's is outside it. One walk of the BVH
//! gathers the triangles left (in a room of large triangles, usually the points' own surface
//! alone); the batch's packets then test those alone, and a batch whose shaft holds too many
//! goes back to walking the tree packet by packet.
//!
//! Exactness: the gathering only prunes, with a margin far above the rounding of the
//! projections. A packet tests every candidate for every pair with the same lane test as the
//! walk, and keeps a hit only when the pair's segment enters the triangle's leaf, the one box
//! test the walk would have needed to test that triangle. Without it, a segment lying in a
//! candidate's plane could be reported hit far outside the triangle (Möller–Trumbore divides
//! two rounding errors there; `tests/verdict.rs`), and a render's answer would depend on which
//! points share its batch. With it, a segment is occluded exactly when [`Bvh::occluded`] says
//! so.

use glam::Vec3;

use super::lanes::{self, lane};
use super::prim::moller_trumbore::{determinant_bounds, origin_terms, solve};
use super::{Bvh, BvhNode, Pairs, TriAccel, STACK_SIZE};
use crate::simd::{max, min, Isa};

/// Most triangles a shaft may hold for its batch to test them alone; beyond, the batch walks
/// the tree.
pub(super) const MAX_CANDIDATES: usize = 32;

/// Fewest ends for which a batch's segments are worth a shaft. One walk of the tree gathers
/// a shaft's triangles for every segment, where the packets walk it once per end: with few
/// ends the gathering costs about what it saves, and a shaft too wide to use (over
/// [`MAX_CANDIDATES`]) is pure cost. Without a shaft, renders took less time under three
/// point lights (3 ends), under one 3×3 light (scenes/bench/small_light.toml) and in the
/// seed's room at 2×2, about as long at 3×3; at 5×5 (25 ends) the shaft saves time there
/// (measured: docs/benchmarks.md, «Design measurements», `MIN_ENDS`).
pub const MIN_ENDS: usize = 16;

/// Fewest ends for which a batch too small for [`MIN_ENDS`] still finds its [`Roots`]: with
/// fewer (point lights), the descent costs more than the walks save.
pub(super) const ROOTS_MIN_ENDS: usize = 4;

/// Most subtrees a shaft's descent leaves for the walks to start from. 4 and 8 gave the same
/// time under a 3×3 light (scenes/bench/small_light.toml), less than the walks from the
/// tree's root; 16 was slower, 1 and 2 saved little (measured: docs/benchmarks.md, «Design
/// measurements», `MAX_ROOTS`).
pub(super) const MAX_ROOTS: usize = 4;

/// Axes the shaft is measured along: x, y, z, and three across its direction.
const AXES: usize = 6;

/// A batch's shaft: its extent along each axis, widened by a margin.
pub(super) struct Shaft {
    axes: [Vec3; AXES],
    lo: [f32; AXES],
    hi: [f32; AXES],
}

/// The triangles a shaft holds: each one's leaf-order index and the index of its leaf.
pub(super) struct Candidates {
    index: [(u32, u32); MAX_CANDIDATES],
    len: usize,
}

impl Candidates {
    /// The candidates: each one's leaf-order index and its leaf's node index.
    pub(super) fn as_slice(&self) -> &[(u32, u32)] {
        &self.index[..self.len]
    }
}

/// The subtrees a shaft meets: node indices, at most [`MAX_ROOTS`] of them.
pub(super) struct Roots {
    index: [u32; MAX_ROOTS],
    len: usize,
}

impl Roots {
    /// The whole tree: its root alone.
    pub(super) fn whole() -> Roots {
        Roots {
            index: [0; MAX_ROOTS],
            len: 1,
        }
    }

    /// The subtrees' node indices.
    pub(super) fn as_slice(&self) -> &[u32] {
        &self.index[..self.len]
    }
}

impl Shaft {
    /// The hull of `origins` and `ends` (each by axis, neither empty) in the scene of `bvh`
    /// (not empty).
    #[inline(always)]
    pub(super) fn new(bvh: &Bvh, origins: [&[f32]; 3], ends: [&[f32]; 3]) -> Shaft {
        // The hull of the two sets lies in the hull of their boxes (Haines and Wallace's shaft
        // between two boxes), whose extent along an axis is the union of the boxes'.
        let (from, to) = (bounds(origins), bounds(ends));
        let along = (to.0 + to.1) - (from.0 + from.1);
        let mut axes = [
            Vec3::X,
            Vec3::Y,
            Vec3::Z,
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::ZERO,
        ];
        for k in 0..3 {
            // A degenerate cross axis stays zero: every extent along it is 0, so it prunes
            // nothing.
            axes[3 + k] = along.cross(axes[k]).normalize_or_zero();
        }
        // The root box bounds every coordinate a node or triangle has.
        let root = &bvh.nodes[0];
        let scale = [from.0, from.1, to.0, to.1, root.min.into(), root.max.into()]
            .iter()
            .fold(0.0f32, |s, c| s.max(c.abs().max_element()));
        // The projections round by a few units of 2⁻²⁴ of the largest coordinate; a
        // triangle's test reports hits a rounding away from its true edges. 2⁻¹⁴ is far
        // above both. A NaN coordinate (a degenerate point) makes the shaft prune nothing.
        let margin = scale * (1.0 / (1 << 14) as f32) + f32::MIN_POSITIVE;
        let (mut lo, mut hi) = ([f32::NEG_INFINITY; AXES], [f32::INFINITY; AXES]);
        for (k, &axis) in axes.iter().enumerate() {
            let ((a, b), (c, d)) = (extent(axis, from), extent(axis, to));
            let (l, h) = (a.min(c) - margin, b.max(d) + margin);
            if l <= h {
                (lo[k], hi[k]) = (l, h);
            }
        }
        Shaft { axes, lo, hi }
    }

    /// Whether the node's box lies outside the shaft.
    #[inline(always)]
    fn misses_box(&self, node: &BvhNode) -> bool {
        let (min, max) = (Vec3::from(node.min), Vec3::from(node.max));
        for k in 0..3 {
            if max[k] < self.lo[k] || min[k] > self.hi[k] {
                return true;
            }
        }
        (3..AXES).any(|k| {
            let (l, h) = extent(self.axes[k], (min, max));
            h < self.lo[k] || l > self.hi[k]
        })
    }

    /// Whether the triangle lies outside the shaft.
    #[inline(always)]
    fn misses_triangle(&self, tri: &TriAccel) -> bool {
        let corners = [tri.v0, tri.v0 + tri.e1, tri.v0 + tri.e2];
        (0..AXES).any(|k| {
            let d = corners.map(|c| self.axes[k].dot(c));
            d[0].max(d[1]).max(d[2]) < self.lo[k] || d[0].min(d[1]).min(d[2]) > self.hi[k]
        })
    }

    /// At most [`MAX_ROOTS`] subtrees of `bvh` (not empty) whose boxes meet the shaft and
    /// hold every triangle it does: the tree's root, split into the children that meet the
    /// shaft, level by level, while there is room. Every segment of the batch lies in the
    /// shaft, so the boxes it enters lie in these subtrees (or above them), and walks that
    /// start from them test the triangles a walk from the root would.
    #[inline(always)]
    pub(super) fn roots(&self, bvh: &Bvh) -> Roots {
        let mut roots = Roots {
            index: [0; MAX_ROOTS],
            len: 0,
        };
        if self.misses_box(&bvh.nodes[0]) {
            return roots;
        }
        roots.len = 1;
        let mut split = true;
        while split {
            split = false;
            let mut i = 0;
            while i < roots.len {
                let node = &bvh.nodes[roots.index[i] as usize];
                i += 1;
                if node.is_leaf() {
                    continue;
                }
                let (l, r) = (node.first, node.first + 1);
                let meets = |k: u32| !self.misses_box(&bvh.nodes[k as usize]);
                match (meets(l), meets(r)) {
                    (true, true) if roots.len < MAX_ROOTS => {
                        roots.index[i - 1] = l;
                        roots.index[roots.len] = r;
                        roots.len += 1;
                    }
                    (true, true) => continue,
                    (true, false) => roots.index[i - 1] = l,
                    (false, true) => roots.index[i - 1] = r,
                    (false, false) => {
                        roots.len -= 1;
                        roots.index[i - 1] = roots.index[roots.len];
                        i -= 1;
                    }
                }
                split = true;
            }
        }
        roots
    }

    /// The triangles of `bvh` (not empty) the shaft holds, or `None` when there are more
    /// than [`MAX_CANDIDATES`].
    #[inline(always)]
    pub(super) fn gather(&self, bvh: &Bvh) -> Option<Candidates> {
        let mut found = Candidates {
            index: [(0, 0); MAX_CANDIDATES],
            len: 0,
        };
        let mut stack = [0u32; STACK_SIZE];
        let mut sp = 0usize;
        let mut next = Some(0u32);
        while let Some(index) = next.take().or_else(|| {
            sp = sp.checked_sub(1)?;
            Some(stack[sp])
        }) {
            let node = &bvh.nodes[index as usize];
            if self.misses_box(node) {
                continue;
            }
            if node.is_leaf() {
                let first = node.first as usize;
                for k in first..first + node.count as usize {
                    if !self.misses_triangle(&bvh.tris[k]) {
                        if found.len == MAX_CANDIDATES {
                            return None;
                        }
                        found.index[found.len] = (k as u32, index);
                        found.len += 1;
                    }
                }
            } else {
                next = Some(node.first);
                stack[sp] = node.first + 1;
                sp += 1;
            }
        }
        Some(found)
    }
}

/// The extent along `axis` of the box with corners `(min, max)`: its center's projection
/// minus and plus its half-size's.
#[inline(always)]
fn extent(axis: Vec3, (min, max): (Vec3, Vec3)) -> (f32, f32) {
    let (c, r) = (
        axis.dot((min + max) * 0.5),
        axis.abs().dot((max - min) * 0.5),
    );
    (c - r, c + r)
}

/// The smallest and largest coordinates of `points` (by axis, not empty), as corners. NaN
/// coordinates are left out: a segment with one meets no triangle in the lane test.
#[inline(always)]
fn bounds(points: [&[f32]; 3]) -> (Vec3, Vec3) {
    // Not `points.map(range)`, nor `range` a closure: neither was inlined, and compiled
    // outside the SIMD kernels these loops took a visible share of the seed room's time
    // (measured: docs/benchmarks.md, «Design measurements», `shaft::bounds`).
    let [(x0, x1), (y0, y1), (z0, z1)] = [range(points[0]), range(points[1]), range(points[2])];
    (Vec3::new(x0, y0, z0), Vec3::new(x1, y1, z1))
}

/// The smallest and largest of `c` (not empty), NaNs left out.
// Eight running minima and maxima, so that the loops vectorize.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn range(c: &[f32]) -> (f32, f32) {
    let (mut lo, mut hi) = ([f32::INFINITY; 8], [f32::NEG_INFINITY; 8]);
    let chunks = c.chunks_exact(8);
    for (i, &x) in chunks.remainder().iter().enumerate() {
        (lo[i], hi[i]) = (min(x, lo[i]), max(x, hi[i]));
    }
    for chunk in chunks {
        for i in 0..8 {
            (lo[i], hi[i]) = (min(chunk[i], lo[i]), max(chunk[i], hi[i]));
        }
    }
    (
        lo.into_iter().fold(f32::INFINITY, min),
        hi.into_iter().fold(f32::NEG_INFINITY, max),
    )
}

/// Ends tested together against one candidate: their lanes' masks fit on the stack.
const ENDS_PER_PASS: usize = 64;

/// Marks slot `j · m + i` of `blocked` (for `m` origins) when segment `(j, i)` of `pairs` is
/// not blocked yet and one of the triangles `candidates` (a shaft's) meets it for `t` in
/// `(0, t_max)` and the segment enters the triangle's leaf, `N` origins at a time.
///
/// Each lane runs `geometry::intersect_triangle`'s operations in its order (see
/// [`segments`](super::segments)' `triangle`); the terms that do not depend on the segment's
/// end (`tvec`, `qvec` and the `t` numerator) are computed once per triangle and origin, not
/// once per end: the same values, so the same answers. A lane hit is kept only when the
/// segment enters the leaf's box (the walk's slab test, run only when some lane is hit), as the
/// walk tests a triangle only for such segments.
// Lane loops index several arrays by lane; that is what vectorizes.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
pub(super) fn occlude_pairs<const N: usize, I: Isa>(
    bvh: &Bvh,
    candidates: &[(u32, u32)],
    Pairs { origins, ends }: Pairs,
    t_max: f32,
    blocked: &mut [bool],
) {
    let (m, n) = (origins[0].len(), ends[0].len());
    debug_assert!(N <= 32 && blocked.len() == m * n);
    for start in (0..m).step_by(N) {
        let count = N.min(m - start);
        // Lanes past the origins repeat the last one; their masks keep them out.
        let mut o = [[0.0f32; N]; 3];
        for a in 0..3 {
            for i in 0..N {
                o[a][i] = origins[a][start + i.min(count - 1)];
            }
        }
        let from = bounds(origins.map(|axis| &axis[start..start + count]));
        for first in (0..n).step_by(ENDS_PER_PASS) {
            let ends_here = first..n.min(first + ENDS_PER_PASS);
            let mut active = [0u32; ENDS_PER_PASS];
            let mut live = false;
            for (mask, j) in active.iter_mut().zip(ends_here.clone()) {
                for (i, &b) in blocked[j * m + start..][..count].iter().enumerate() {
                    *mask |= u32::from(!b) << i;
                }
                live |= *mask != 0;
            }
            if !live {
                continue;
            }
            // The box of every direction `end − origin` the pass traces (rounding is
            // monotonic): ends some lane still traces (a sample behind a point's surface is
            // traced from its other side, in a pass of its own).
            let mut to = (Vec3::INFINITY, Vec3::NEG_INFINITY);
            for (mask, j) in active.iter().zip(ends_here.clone()) {
                if *mask != 0 {
                    let end = Vec3::new(ends[0][j], ends[1][j], ends[2][j]);
                    to = (to.0.min(end), to.1.max(end));
                }
            }
            let directions = ((to.0 - from.1).to_array(), (to.1 - from.0).to_array());
            for &(k, leaf) in candidates {
                let (tri, leaf) = (&bvh.tris[k as usize], &bvh.nodes[leaf as usize]);
                let fixed = Fixed::new(tri, &o);
                if fixed.misses::<I>(tri, directions, t_max) {
                    continue;
                }
                for (mask, j) in active.iter_mut().zip(ends_here.clone()) {
                    if *mask != 0 {
                        let end = [ends[0][j], ends[1][j], ends[2][j]];
                        let hit = fixed.hits::<I>(tri, &o, end, t_max, *mask);
                        if hit != 0 {
                            *mask &= !entering::<N, I>(leaf, &o, end, t_max, hit);
                        }
                    }
                }
            }
            for (mask, j) in active.iter().zip(ends_here) {
                for (i, b) in blocked[j * m + start..][..count].iter_mut().enumerate() {
                    *b |= mask & (1 << i) == 0;
                }
            }
        }
    }
}

/// The lanes of `lanes` whose segment from `o` to `end` enters `leaf`'s box within
/// `(0, t_max)`: the walk's slab test ([`lanes::slab`]), which answers as the scalar walk's.
// Lane loops index several arrays by lane; that is what vectorizes.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn entering<const N: usize, I: Isa>(
    leaf: &BvhNode,
    o: &[[f32; N]; 3],
    end: [f32; 3],
    t_max: f32,
    lanes: u32,
) -> u32 {
    let mut inv = [[0.0f32; N]; 3];
    for a in 0..3 {
        for i in 0..N {
            inv[a][i] = 1.0 / (end[a] - o[a][i]);
        }
    }
    let rel = |a: usize, i: usize| (leaf.min[a] - o[a][i], leaf.max[a] - o[a][i]);
    lanes::slab::<N, I>(rel, &inv, 0.0, &[t_max; N], 1.0).0 & lanes
}

/// One triangle's Möller–Trumbore terms that depend on the origin alone, by lane: `tvec =
/// origin − v0`, `qvec = tvec × e1` and the `t` numerator `e2 · qvec`.
struct Fixed<const N: usize> {
    tvec: [[f32; N]; 3],
    qvec: [[f32; N]; 3],
    t_num: [f32; N],
}

// Lane loops index several arrays by lane; that is what vectorizes.
#[allow(clippy::needless_range_loop)]
impl<const N: usize> Fixed<N> {
    #[inline(always)]
    fn new(tri: &TriAccel, o: &[[f32; N]; 3]) -> Self {
        let (v0, e1, e2) = (tri.v0.to_array(), tri.e1.to_array(), tri.e2.to_array());
        let mut f = Fixed {
            tvec: [[0.0; N]; 3],
            qvec: [[0.0; N]; 3],
            t_num: [0.0; N],
        };
        for i in 0..N {
            let (tvec, qvec, t_num) = origin_terms(lane(o, i), v0, e1, e2);
            for a in 0..3 {
                (f.tvec[a][i], f.qvec[a][i]) = (tvec[a], qvec[a]);
            }
            f.t_num[i] = t_num;
        }
        f
    }

    /// Whether the test gives no lane a `t` in `(0, t_max)` toward any end whose direction
    /// from the lane's origin lies in `directions` (a box by axis): every such determinant has
    /// one sign ([`determinant_bounds`]), and each lane's `t = t_num · (1 / det)` is then
    /// either never positive (its `t` numerator has the other sign, or is zero) or never below
    /// `t_max` (bounded by the same operations on the bound of `1 / det` that makes it
    /// smallest: rounding is monotonic). Triangles under the batch's points (their own surface,
    /// which a shaft usually holds: the rays leave it) and beyond its light samples (the
    /// ceiling around a light: the rays stop short of it) are so. Exactly what the lanes' tests
    /// would say, at about the cost of one.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn misses<I: Isa>(&self, tri: &TriAccel, directions: ([f32; 3], [f32; 3]), t_max: f32) -> bool {
        let (e1, e2) = (tri.e1.to_array(), tri.e2.to_array());
        let Some((lo, hi)) = determinant_bounds(directions, e1, e2) else {
            return false;
        };
        // The sign of every determinant, and the bound of 1/det that gives each `t` of that
        // sign's numerators its smallest value.
        let (sign, inv) = match (lo > 0.0, hi < 0.0) {
            (true, _) => (1.0, 1.0 / hi),
            (_, true) => (-1.0, 1.0 / lo),
            _ => return false,
        };
        let mut missed = [0i32; N];
        for i in 0..N {
            let t_num = self.t_num[i];
            let behind = t_num * sign <= 0.0;
            let beyond = t_num * sign > 0.0 && t_num * inv >= t_max;
            missed[i] = -((behind | beyond) as i32);
        }
        I::mask(&missed).count_ones() as usize == N
    }

    /// The lanes of `lanes` whose segment from `o` to `end` the triangle meets with `t` in
    /// `(0, t_max)`: the rest of the lane test, `prim::moller_trumbore::solve`.
    #[inline(always)]
    fn hits<I: Isa>(
        &self,
        tri: &TriAccel,
        o: &[[f32; N]; 3],
        end: [f32; 3],
        t_max: f32,
        lanes: u32,
    ) -> u32 {
        let mut dir = [[0.0f32; N]; 3];
        for a in 0..3 {
            for i in 0..N {
                dir[a][i] = end[a] - o[a][i];
            }
        }
        let (e1, e2) = (tri.e1.to_array(), tri.e2.to_array());
        let mut hit = [0i32; N];
        for i in 0..N {
            let terms = (lane(&self.tvec, i), lane(&self.qvec, i), self.t_num[i]);
            let (inside, t, _, _) = solve(terms, lane(&dir, i), e1, e2);
            hit[i] = -((inside & (t > 0.0) & (t < t_max)) as i32);
        }
        I::mask(&hit) & lanes
    }
}
