//! Shaft culling (Haines and Wallace, "Shaft Culling for Efficient Ray-Cast Radiosity", 1991):
//! the few triangles that could stop any of a batch's shadow rays, found once per batch.
//!
//! The segments between a few neighbouring shading points and the samples of a light all lie
//! in the convex hull of those points and samples: the shaft. A triangle that lies wholly
//! outside the shaft cannot meet any of them. The shaft is described by its extent along a few
//! axes (the coordinate axes, and three across the shaft's direction), and a box or a triangle
//! whose extent along one of them is apart from the shaft's is outside it. One walk of the BVH
//! gathers the triangles left (a room of large triangles leaves a handful, often none); the
//! batch's packets then test those alone, and a batch whose shaft holds too many goes back to
//! walking the tree packet by packet.
//!
//! Exactness: the gathering only prunes, with a margin far above the rounding of the
//! projections. A packet tests every candidate with the same lane test as the walk, which
//! itself tests a leaf's triangles for every live lane, entered or not: a lane is occluded
//! exactly when some triangle's test says so, whichever triangles are tested besides the ones
//! its segment passes through.

use glam::Vec3;

use super::{Bvh, BvhNode, TriAccel, STACK_SIZE};

/// Most triangles a shaft may hold for its batch to test them alone; beyond, the batch walks
/// the tree.
pub(super) const MAX_CANDIDATES: usize = 32;

/// Axes the shaft is measured along: x, y, z, and three across its direction.
const AXES: usize = 6;

/// A batch's shaft: its extent along each axis, widened by a margin.
pub(super) struct Shaft {
    axes: [Vec3; AXES],
    lo: [f32; AXES],
    hi: [f32; AXES],
}

/// The triangles (leaf-order indices) a shaft holds.
pub(super) struct Candidates {
    index: [u32; MAX_CANDIDATES],
    len: usize,
}

impl Candidates {
    /// The candidates' leaf-order indices.
    pub(super) fn as_slice(&self) -> &[u32] {
        &self.index[..self.len]
    }
}

impl Shaft {
    /// The hull of `origins` and `ends` (each by axis, neither empty) in the scene of `bvh`
    /// (not empty).
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
        for (k, axis) in axes.iter().enumerate() {
            let extent = |(min, max): (Vec3, Vec3)| {
                let (c, r) = (
                    axis.dot((min + max) * 0.5),
                    axis.abs().dot((max - min) * 0.5),
                );
                (c - r, c + r)
            };
            let ((a, b), (c, d)) = (extent(from), extent(to));
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
        let (center, half) = ((min + max) * 0.5, (max - min) * 0.5);
        for k in 3..AXES {
            let axis = self.axes[k];
            let (c, r) = (axis.dot(center), axis.abs().dot(half));
            if c + r < self.lo[k] || c - r > self.hi[k] {
                return true;
            }
        }
        false
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

    /// The triangles of `bvh` (not empty) the shaft holds, or `None` when there are more
    /// than [`MAX_CANDIDATES`].
    pub(super) fn gather(&self, bvh: &Bvh) -> Option<Candidates> {
        let mut found = Candidates {
            index: [0; MAX_CANDIDATES],
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
                        found.index[found.len] = k as u32;
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

/// The smallest and largest coordinates of `points` (by axis, not empty), as corners.
#[inline(always)]
fn bounds(points: [&[f32]; 3]) -> (Vec3, Vec3) {
    let range = |c: &[f32]| {
        c.iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &x| {
                (lo.min(x), hi.max(x))
            })
    };
    let [(x0, x1), (y0, y1), (z0, z1)] = points.map(range);
    (Vec3::new(x0, y0, z0), Vec3::new(x1, y1, z1))
}
