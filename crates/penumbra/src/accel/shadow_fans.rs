//! Shadow-ray packets: segments that share their origin (a shading point and the N×N samples
//! of its lights) traced together through the BVH, `N` lanes at a time.
//!
//! Each node is fetched once per packet and its slab test runs for all lanes in one loop, which
//! the compiler turns into vector instructions (`crate::simd` compiles this file's code once
//! per instruction set and picks one at run time). A lane leaves the packet at its first occluder;
//! the packet stops when no lane is left. That walk ([`walk`]) also serves the bundles of
//! `segments`, whose lanes have origins of their own.
//!
//! Exactness: every lane runs the Möller–Trumbore test of `prim::moller_trumbore`, the scalar
//! test's own functions, operation for operation (the same products, sums and comparisons in
//! the same order, no fused multiply-add), and the slab test the scalar walk runs, and a lane
//! meets the triangles of the leaves its own segment enters and no others ([`walk`]). So a
//! lane is occluded exactly when [`Bvh::occluded`] says so, whatever the packet's width.

use std::marker::PhantomData;

use glam::Vec3;

use super::lanes::{self, lane};
use super::prim::moller_trumbore::{determinant, origin_terms, solve};
use super::{traverse, Bvh, BvhNode, TriAccel, STACK_SIZE};
use crate::math::Ray;
use crate::simd::{Isa, Kernel};

/// Trees of at least this many nodes (2 MiB of them: more than a core's L2 cache) have the
/// packets prefetch what lies below the children they test. On smaller trees the nodes stay
/// cached and the prefetches are pure cost (the seed's room); on the 1M-triangle room they
/// save time (measured: docs/benchmarks.md, «Design measurements», `PREFETCH_MIN_NODES`).
const PREFETCH_MIN_NODES: usize = 64 * 1024;

/// [`Bvh::occlude_from`] as a [`Kernel`]: the segments in packets of `N` lanes.
pub(super) struct Occlude<'a> {
    pub(super) bvh: &'a Bvh,
    pub(super) origin: Vec3,
    pub(super) ends: &'a [Vec3],
    pub(super) t_max: f32,
    pub(super) blocked: &'a mut [bool],
}

impl Kernel for Occlude<'_> {
    type Output = ();

    /// A packet with a quarter of its lanes or fewer to trace goes one ray at a time.
    #[inline(always)]
    fn run<const N: usize, I: Isa>(self) {
        let Occlude {
            bvh,
            origin,
            ends,
            t_max,
            blocked,
        } = self;
        assert_eq!(ends.len(), blocked.len(), "one mask slot per segment");
        if bvh.nodes.is_empty() {
            return;
        }
        let deep = bvh.nodes.len() >= PREFETCH_MIN_NODES;
        for (ends, blocked) in ends.chunks(N).zip(blocked.chunks_mut(N)) {
            let live = blocked.iter().filter(|&&b| !b).count();
            if live == 0 {
                continue;
            }
            if live * 4 <= N {
                for (&end, b) in ends.iter().zip(blocked) {
                    if !*b {
                        *b = traverse::occluded(bvh, &Ray::new(origin, end - origin), 0.0, t_max);
                    }
                }
            } else if deep {
                occlude_packet::<N, I, true>(bvh, origin, ends, t_max, blocked);
            } else {
                occlude_packet::<N, I, false>(bvh, origin, ends, t_max, blocked);
            }
        }
    }
}

/// Marks `blocked[i]` for each segment from `origin` to `ends[i]` (`ends.len() <= N`) that is
/// not blocked yet and that a triangle meets for `t` in `(0, t_max)`.
#[inline(always)]
pub(super) fn occlude_packet<const N: usize, I: Isa, const PREFETCH: bool>(
    bvh: &Bvh,
    origin: Vec3,
    ends: &[Vec3],
    t_max: f32,
    blocked: &mut [bool],
) {
    debug_assert!(N <= 32 && !ends.is_empty() && ends.len() <= N && ends.len() == blocked.len());
    let count = ends.len();
    // Lanes past `count` repeat the last segment and start inactive, as do blocked lanes.
    let mut dir = [[0.0f32; N]; 3];
    // Lane i is bit i.
    let mut active: u32 = 0;
    for i in 0..N {
        let d = ends[i.min(count - 1)] - origin;
        for a in 0..3 {
            dir[a][i] = d[a];
        }
        active |= ((i < count && !blocked[i]) as u32) << i;
    }
    let mut inv = [[0.0f32; N]; 3];
    for a in 0..3 {
        for i in 0..N {
            inv[a][i] = 1.0 / dir[a][i];
        }
    }
    let fan = Fan::<N, I> {
        origin,
        o: origin.to_array(),
        dir,
        inv,
        far: [t_max; N],
        t_max,
        isa: PhantomData,
    };
    let active = walk::<N, PREFETCH>(bvh, &fan, active);
    for (i, b) in blocked.iter_mut().enumerate() {
        *b |= active & (1 << i) == 0;
    }
}

/// A packet's lanes as the any-hit walk sees them.
pub(super) trait ShadowLanes<const N: usize> {
    /// The lanes (bit i for lane i) that enter `node`'s box within `(0, t_max)`, and each
    /// lane's entry distance.
    fn enter(&self, node: &BvhNode) -> (u32, [f32; N]);
    /// The lanes of `lanes` that `tri` blocks.
    fn blocks(&self, tri: &TriAccel, lanes: u32) -> u32;
}

/// The lanes of `active` that no triangle blocks: the packet's any-hit walk of the BVH.
///
/// Children are tested at their parent and the one the first live lane enters first is
/// visited first, so that occluders near the rays' start end the walk early; the other waits
/// on the stack with the lanes that entered it. A lane leaves at its first occluder; the walk
/// stops when no lane is left. With `PREFETCH` (deep trees), each visit starts loading what
/// lies below the two children it tests.
///
/// Each node is visited with the lanes that entered it and every box above it, and a leaf's
/// triangles are tested for those lanes only: a lane meets exactly the triangles that
/// [`Bvh::occluded`] tests for its ray, whatever the other lanes of its packet. That matters
/// for a segment lying in a triangle's plane, which Möller–Trumbore may report hit at a point
/// far outside the triangle's box: a lane tested for every active lane would find that hit
/// when a neighbour brought it into the leaf, and packets of 4, 8 or 16 lanes would disagree.
#[inline(always)]
pub(super) fn walk<const N: usize, const PREFETCH: bool>(
    bvh: &Bvh,
    rays: &impl ShadowLanes<N>,
    active: u32,
) -> u32 {
    walk_from::<N, PREFETCH>(bvh, rays, active, 0)
}

/// [`walk`] below node `root` alone: the lanes of `active` that no triangle of its subtree
/// blocks. A lane enters a box only if it enters every box above it (a child's box lies in
/// its parent's, and the slab test's rounding is monotonic), so a lane meets here exactly the
/// triangles of the subtree that [`walk`] would test for it.
#[inline(always)]
pub(super) fn walk_from<const N: usize, const PREFETCH: bool>(
    bvh: &Bvh,
    rays: &impl ShadowLanes<N>,
    mut active: u32,
    root: u32,
) -> u32 {
    let mut stack = [(0u32, 0u32); STACK_SIZE];
    let mut sp = 0;
    let mut node = &bvh.nodes[root as usize];
    // The lanes that entered `node` and every box above it.
    let mut entered = rays.enter(node).0 & active;
    if entered == 0 {
        return active;
    }
    'nodes: loop {
        if node.is_leaf() {
            let first = node.first as usize;
            for tri in &bvh.tris[first..first + node.count as usize] {
                active &= !rays.blocks(tri, active & entered);
                if active & entered == 0 {
                    break;
                }
            }
            if active == 0 {
                break 'nodes;
            }
        } else {
            let (l, r) = (
                &bvh.nodes[node.first as usize],
                &bvh.nodes[node.first as usize + 1],
            );
            if PREFETCH {
                prefetch_below(bvh, l);
                prefetch_below(bvh, r);
            }
            let ((ml, nl), (mr, nr)) = (rays.enter(l), rays.enter(r));
            let live = active & entered;
            let (ml, mr) = (ml & live, mr & live);
            if ml != 0 && mr != 0 {
                let lane = live.trailing_zeros() as usize;
                let (near, near_mask, far, far_mask) = if nl[lane] <= nr[lane] {
                    (l, ml, node.first + 1, mr)
                } else {
                    (r, mr, node.first, ml)
                };
                stack[sp] = (far, far_mask);
                sp += 1;
                (node, entered) = (near, near_mask);
                continue;
            } else if ml != 0 {
                (node, entered) = (l, ml);
                continue;
            } else if mr != 0 {
                (node, entered) = (r, mr);
                continue;
            }
        }
        // The next waiting subtree that a lane still live entered.
        loop {
            if sp == 0 {
                break 'nodes;
            }
            sp -= 1;
            let (index, mask) = stack[sp];
            if mask & active != 0 {
                (node, entered) = (&bvh.nodes[index as usize], mask);
                break;
            }
        }
    }
    active
}

/// A fan's lanes: rays from one origin, by lane.
struct Fan<const N: usize, I> {
    origin: Vec3,
    o: [f32; 3],
    dir: [[f32; N]; 3],
    inv: [[f32; N]; 3],
    far: [f32; N],
    t_max: f32,
    isa: PhantomData<I>,
}

impl<const N: usize, I: Isa> ShadowLanes<N> for Fan<N, I> {
    #[inline(always)]
    fn enter(&self, node: &BvhNode) -> (u32, [f32; N]) {
        slab::<N, I>(node, &self.o, &self.inv, 0.0, &self.far)
    }

    #[inline(always)]
    fn blocks(&self, tri: &TriAccel, lanes: u32) -> u32 {
        triangle::<N, I>(tri, self.origin, &self.dir, self.t_max, lanes)
    }
}

/// Starts loading what a visit of `node` reads first (its children, or its first
/// triangles), so that on deep trees the loads overlap the box tests of `node` and its sibling.
#[inline(always)]
fn prefetch_below(bvh: &Bvh, node: &BvhNode) {
    if node.is_leaf() {
        crate::simd::prefetch(&bvh.tris[node.first as usize]);
    } else {
        crate::simd::prefetch(&bvh.nodes[node.first as usize]);
        crate::simd::prefetch(&bvh.nodes[node.first as usize + 1]);
    }
}

/// The lanes (bit i for lane i) that enter the node's box within `(t_min, t_max[i])`, and each
/// lane's entry distance: the box relative to the shared origin once, then [`lanes::slab`].
#[inline(always)]
pub(super) fn slab<const N: usize, I: Isa>(
    node: &BvhNode,
    o: &[f32; 3],
    inv: &[[f32; N]; 3],
    t_min: f32,
    t_max: &[f32; N],
) -> (u32, [f32; N]) {
    let lo = [node.min[0] - o[0], node.min[1] - o[1], node.min[2] - o[2]];
    let hi = [node.max[0] - o[0], node.max[1] - o[1], node.max[2] - o[2]];
    lanes::slab::<N, I>(|a, _| (lo[a], hi[a]), inv, t_min, t_max, 1.0)
}

/// The lanes of `lanes` (bit i for lane i) that hit the triangle with `t` in `(0, t_max)`.
///
/// `t = t_num · (1 / det)` is positive only where `det` is nonzero and has the sign of
/// `t_num` (shared by all lanes), so the lanes' `det` alone (a third of the test) rules out a
/// triangle whose plane lies behind every lane; the rest of the test runs only when some lane
/// is left. Either way the answer is the full test's. This pays on 16-lane vectors (AVX-512)
/// and costs on 8 (AVX2), so only packets of 16 lanes or more take it (measured:
/// docs/benchmarks.md, «Design measurements», the `det` pretest).
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn triangle<const N: usize, I: Isa>(
    tri: &TriAccel,
    origin: Vec3,
    dir: &[[f32; N]; 3],
    t_max: f32,
    lanes: u32,
) -> u32 {
    let (e1, e2) = (tri.e1.to_array(), tri.e2.to_array());
    let terms = origin_terms(origin.to_array(), tri.v0.to_array(), e1, e2);
    let t_num = terms.2;
    // Zero or NaN: every lane's `t` is ±0 or NaN.
    if !(t_num != 0.0) {
        return 0;
    }
    if N >= 16 {
        let positive = t_num > 0.0;
        let mut ahead = [0i32; N];
        for i in 0..N {
            let det = determinant(lane(dir, i), e1, e2).1;
            ahead[i] = -((((det > 0.0) == positive) & (det != 0.0)) as i32);
        }
        if I::mask(&ahead) & lanes == 0 {
            return 0;
        }
    }
    let mut hit = [0i32; N];
    for i in 0..N {
        let (inside, t, _, _) = solve(terms, lane(dir, i), e1, e2);
        hit[i] = -((inside & (t > 0.0) & (t < t_max)) as i32);
    }
    I::mask(&hit) & lanes
}
