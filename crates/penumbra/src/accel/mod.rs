//! The acceleration engine: one bounding volume hierarchy over all triangles of a scene, built
//! once by binned SAH (Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies",
//! 2007), and every query over it: the renderer's (closest hit for camera rays, any hit for
//! shadow rays, single and in SIMD packets, with Möller–Trumbore) and ray casting's (closest,
//! any and every hit on an eight-wide view of the same tree, with the watertight test).
//!
//! # Node layout and leaf format (the contract every traversal reads)
//!
//! Binary tree ([`Bvh`]): a flat array of 32-byte [`BvhNode`]s `{ min: [f32; 3], first: u32,
//! max: [f32; 3], count: u32 }`, root at 0 (empty for an empty scene). An interior node has
//! `count == 0` and its two children at `first` and `first + 1`, always after it in the array;
//! a leaf holds `count` (1 to `MAX_LEAF`) triangles, the leaf slots `first .. first + count`.
//! A subtree's slots are contiguous, the left child's first. Boxes are padded outward (see
//! `build`) so that `bound − origin` is never zero for a ray that touches the true box. Leaf
//! slot `i` holds scene triangle `prim_ids[i]`, stored for Möller–Trumbore as `TriAccel`
//! (`v0`, `e1 = v1 − v0`, `e2 = v2 − v0`); the depth is at most `MAX_DEPTH`, so the fixed
//! stacks of `STACK_SIZE` entries never overflow.
//!
//! Eight-wide view (`wide::node::WideNode`, 256 bytes, 64-aligned), collapsed from the binary
//! tree: `min[axis][child]`, `max[axis][child]` (the binary nodes' padded boxes, bit for bit),
//! `child[8]`, `count[8]`. A lane with `count == 0` is an interior child (`child` is a wide
//! node's index), `count == u32::MAX` is unused (unused lanes come last), else the lane is a
//! leaf of `count` triangles: the leaf slots of one binary subtree, as `TriangleGroup`s of
//! eight by coordinate starting at group `child` (the group's `first` is its lane 0's leaf
//! slot; lanes past the leaf repeat its last triangle and are masked). Ray casting keeps each
//! slot's exact corners (`SoaTriangle`) and its geometry and primitive ids beside them.
//!
//! # Cut-outs
//!
//! Triangles whose material may cut (alpha-tested: see `material::Cutout`) are kept apart
//! (`cutouts`): a world with such materials builds its opaque triangles and instances into
//! the levels above, and its cut-out triangles (the world's own, and the instances whose
//! materials may cut, over the same mesh trees) into a second pair of levels, walked by the
//! generic single-ray walks of `traverse` with a filtered primitive test: one traversal, two
//! primitive tests, as Embree's filter functions and obvhs's closures do. A hit the alpha
//! test refuses does not shorten a closest-hit ray, and an any-hit walk looks on past it. The
//! batched kernels (fans, bundles, shafts, the batches inside instances) are not changed:
//! after them, each ray or segment of a batch still open asks the cut-out levels alone. So a
//! world without cut-outs runs exactly the code of before (same bytes, same speed), and a
//! ray's answer never depends on how it was grouped. Ray casting tests the same alpha after
//! the watertight test, in its wide walk, for a scene made from a world with cut-outs
//! (`WideBvh` holds the tests by triangle); its packets then trace one ray at a time.
//!
//! # Files
//!
//! This file owns the binary layout ([`Bvh`], [`BvhNode`], `TriAccel`), the tuning constants
//! and the renderer's public API, whose methods delegate to the submodules:
//!
//! - `build`: binned-SAH construction, serial and parallel;
//! - `split`: one node's split: binning (in parallel chunks for large nodes), the SAH sweep
//!   and the partition;
//! - `traverse`: single rays on the binary tree: the slab test, the nearest-first walk (generic
//!   over the distance: a ray's closest hit, a point's closest point) and the any-hit walk
//!   (both generic over what a leaf holds), and the closest-hit, any-hit and batch queries;
//! - `tree`: [`Tree`], the one interface of both trees (closest, any and every hit of a
//!   ray, a hit filter after the primitive test, and the rule: interval and tie order),
//!   implemented by [`Bvh`] and `wide::WideBvh`;
//! - `placed`: the second level written once over any [`Tree`]: `Placed<T>` (mesh trees,
//!   the one `Placement` type, the top-level tree, moves in place), the top-level walk into
//!   placed meshes and the closest rule across placements; the renderer's `instances` and
//!   ray casting's `wide::levels` are both a `Placed` of their tree;
//! - `closest_fans`: closest-hit SIMD packets of rays sharing an origin (camera rays);
//! - `shadow_fans`: any-hit SIMD packets of segments sharing an origin (a point and its light
//!   samples), and the any-hit packet walk every packet kind uses;
//! - `lanes`: rays by SIMD lane and the one slab test of a box against `N` of them (fans,
//!   bundles, and ray casting's packets);
//! - `segments`: any-hit packets of segments with origins of their own (bundles of shadow rays
//!   from neighbouring points to one light sample);
//! - `shaft`: shaft culling for those bundles when every point has the same light samples:
//!   the few triangles in the hull of a batch's points and samples, tested without the tree;
//! - `instances` and `levels`: the renderer's queries of its second level (`Placed<Bvh>`)
//!   and the pair of levels a world queries (with `build::join`, the one tree over all its
//!   own triangles that ray casting views); `instance_batches`: the batched shadow queries
//!   inside each instance a batch meets;
//! - `cutouts`: the cut-out levels, the split of a world's parts between opaque and cut-out
//!   levels, and (`cutouts::alpha`) the alpha tests of cut-out hits;
//! - `validate`: the structural check and the brute-force references the BVH must agree with;
//! - `prim`: the triangle tests, each written once for scalar and lane callers:
//!   `moller_trumbore` (the renderer's), `watertight` (ray casting's: Woop, Benthin and Wald
//!   2013; `hit_lane` is its SIMD lane) and `boundary` (which triangle owns a point of the
//!   surface's border, for counting);
//! - `wide`: the ray-casting engine: `node` (the wide node and the collapse), `group` (a
//!   leaf's triangles by eight and the watertight test on them), `tree` ([`wide::WideBvh`]
//!   and the one single-ray walk its closest-, any- and every-hit queries share), `packets` (closest-hit packets of neighbouring rays),
//!   `kernels` (batches of single-ray queries per instruction set), `nearest` (the closest
//!   point of the surface).

use glam::Vec3;

use crate::geometry::{Geometry, Hit, TriangleHit};
use crate::math::{Aabb, Ray};
use crate::simd::{dispatch, simd_path, SimdPath};
use prim::moller_trumbore::intersect_triangle;

mod build;
mod closest_fans;
mod cutouts;
mod instance_batches;
mod instances;
mod lanes;
mod levels;
pub(crate) mod placed;
pub(crate) mod prim;
mod segments;
mod shadow_fans;
mod shadows;
mod shaft;
mod split;
mod traverse;
mod tree;
mod validate;
pub(crate) mod wide;

#[cfg(test)]
mod placed_tests;
#[cfg(test)]
pub(crate) mod test_meshes;
#[cfg(test)]
mod tests;

pub(crate) use cutouts::{AlphaTests, Parts};
pub use levels::Levels;
pub use segments::{Pairs, Segments};
pub(crate) use shadows::{Grouping, SharedEnds};
pub use shaft::MIN_ENDS as SHAFT_MIN_ENDS;
pub(crate) use tree::Tree;
pub use validate::{intersect_brute_force, occluded_brute_force};

/// A node of the flat BVH. Interior nodes have `count == 0` and their two children at
/// `first` and `first + 1`; leaves hold the triangles `first .. first + count` of the leaf-order
/// arrays.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub struct BvhNode {
    min: [f32; 3],
    first: u32,
    max: [f32; 3],
    count: u32,
}

impl BvhNode {
    fn bounds(&self) -> Aabb {
        Aabb {
            min: Vec3::from(self.min),
            max: Vec3::from(self.max),
        }
    }

    fn is_leaf(&self) -> bool {
        self.count > 0
    }

    /// Smallest corner of the (padded) box, for traversals outside this module.
    pub(crate) fn min_corner(&self) -> [f32; 3] {
        self.min
    }

    /// Largest corner of the (padded) box.
    pub(crate) fn max_corner(&self) -> [f32; 3] {
        self.max
    }

    /// For an interior node (`count == 0`) the index of the first child (the second follows
    /// it); for a leaf the first of its `count` leaf-order triangles.
    pub(crate) fn first(&self) -> u32 {
        self.first
    }

    /// Number of leaf-order triangles of a leaf; 0 for an interior node.
    pub(crate) fn count(&self) -> u32 {
        self.count
    }
}

/// A triangle ready for intersection: `v0` and the two edges from it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct TriAccel {
    v0: Vec3,
    e1: Vec3,
    e2: Vec3,
}

impl TriAccel {
    /// Möller–Trumbore of the ray against this triangle, `t` in `(t_min, t_max)`.
    #[inline(always)]
    fn hit(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<TriangleHit> {
        intersect_triangle(
            ray.origin,
            ray.direction,
            self.v0,
            self.e1,
            self.e2,
            t_min,
            t_max,
        )
    }
}

/// The triangle with corners `corners` in the form the intersection test takes. The BVH and
/// the brute-force references both go through here, so they test bit-identical edges.
fn accel(corners: [Vec3; 3]) -> TriAccel {
    TriAccel {
        v0: corners[0],
        e1: corners[1] - corners[0],
        e2: corners[2] - corners[0],
    }
}

/// The BVH: nodes, triangles in leaf order, and the permutation back to scene triangle indices.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Vec<BvhNode>,
    tris: Vec<TriAccel>,
    prim_ids: Vec<u32>,
}

/// Number of SAH bins per axis.
const BINS: usize = 16;
/// Largest leaf the SAH may keep when a split would be cheaper.
const MAX_LEAF: usize = 8;
/// Subtrees with at least this many triangles are built on separate threads. At 32k, the
/// suite's 17,590-triangle scenes were built on one thread while the other waited (measured:
/// docs/benchmarks.md, «Design measurements», `PARALLEL_MIN`); a `rayon::join` costs
/// microseconds, a 4k-triangle subtree about a millisecond.
const PARALLEL_MIN: usize = 4 * 1024;
/// Entries of the fixed stacks of every walk of the binary tree (single rays, packets, closest
/// points), and the depth from which the wide walks' stack is sized: the one bound of both
/// engines.
const STACK_SIZE: usize = 64;
/// Deepest leaf: the any-hit traversal holds at most `depth + 1` entries on its stack.
const MAX_DEPTH: usize = STACK_SIZE - 2;

impl Bvh {
    /// Builds the hierarchy over every triangle of `geometry` on the calling thread.
    pub fn build(geometry: &Geometry) -> Bvh {
        build::build(geometry.len(), |i| geometry.corners(i), None)
    }

    /// Builds the hierarchy on the threads of `pool`: the per-triangle steps and the binning of
    /// the top splits run in parallel chunks, and large subtrees are built on separate
    /// threads. The result is the same as [`Bvh::build`]'s, node for node.
    pub fn build_parallel(geometry: &Geometry, pool: &rayon::ThreadPool) -> Bvh {
        build::build(geometry.len(), |i| geometry.corners(i), Some(pool))
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The flat node array (root at 0; empty for an empty scene), for traversals outside this
    /// module.
    pub(crate) fn nodes(&self) -> &[BvhNode] {
        &self.nodes
    }

    /// For each leaf-order triangle slot, the index of the scene triangle it holds.
    pub(crate) fn prim_ids(&self) -> &[u32] {
        &self.prim_ids
    }

    /// The closest hit with `t` in `(t_min, t_max)`, if any. Among triangles hit at exactly the
    /// same `t` (a ray through an edge two triangles share) the one with the smallest index
    /// wins, whatever the tree's shape, so that every query and the brute-force reference
    /// agree.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        traverse::intersect(self, ray, t_min, t_max)
    }

    /// True when any triangle meets the ray with `t` in `(t_min, t_max)`; stops at the first.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        traverse::occluded(self, ray, t_min, t_max)
    }

    /// The closest hit of every ray of `rays` with `t` in `(t_min, t_max)`, written to `hits`
    /// (which must be as long as `rays`). Each result equals [`Bvh::intersect`]'s.
    pub fn intersect_batch(&self, rays: &[Ray], t_min: f32, t_max: f32, hits: &mut [Option<Hit>]) {
        traverse::intersect_batch(self, rays, t_min, t_max, hits);
    }

    /// The closest hit of each ray from `origin` along `dirs[i]` with `t` in `(t_min, t_max)`,
    /// written to `hits[i]` (which must be as long as `dirs`): the camera rays of a pinhole
    /// camera share their origin. Each result equals [`Bvh::intersect`]'s.
    ///
    /// The rays are traced as SIMD packets on this process's [`simd_path`]; every path gives
    /// the same answers.
    pub fn intersect_from(
        &self,
        origin: Vec3,
        dirs: &[Vec3],
        t_min: f32,
        t_max: f32,
        hits: &mut [Option<Hit>],
    ) {
        self.intersect_from_on(simd_path(), origin, dirs, t_min, t_max, hits);
    }

    /// [`Bvh::intersect_from`] on a given SIMD path (the portable one when `path` is not
    /// supported), so that tests can run every path the machine has.
    #[doc(hidden)]
    pub fn intersect_from_on(
        &self,
        path: SimdPath,
        origin: Vec3,
        dirs: &[Vec3],
        t_min: f32,
        t_max: f32,
        hits: &mut [Option<Hit>],
    ) {
        let kernel = closest_fans::Closest {
            bvh: self,
            origin,
            dirs,
            t_min,
            t_max,
            hits,
        };
        dispatch(path, kernel);
    }

    /// Occlusion of the segments from `origin` to each point of `ends`: `occluded[i]` is true
    /// when a triangle meets `origin + t·(ends[i] − origin)` for some `t` in `(0, t_max)`, as
    /// [`Bvh::occluded`] on that ray would say. The segments share their origin, like the N×N
    /// samples of an area light seen from one shading point. `occluded` must be as long as
    /// `ends`.
    ///
    /// The segments are traced as SIMD packets on this process's [`simd_path`]; every path
    /// gives the same answers.
    pub fn occluded_from(&self, origin: Vec3, ends: &[Vec3], t_max: f32, occluded: &mut [bool]) {
        occluded.fill(false);
        self.occlude_from(origin, ends, t_max, occluded);
    }

    /// Like [`Bvh::occluded_from`] for the segments not yet `blocked`: each of them that a
    /// triangle meets becomes blocked; blocked ones are not traced. A caller marks the samples
    /// that cannot contribute (below the surface, facing away) as blocked and traces the rest
    /// in one call.
    pub fn occlude_from(&self, origin: Vec3, ends: &[Vec3], t_max: f32, blocked: &mut [bool]) {
        self.occlude_from_on(simd_path(), origin, ends, t_max, blocked);
    }

    /// [`Bvh::occlude_from`] on a given SIMD path (the portable one when `path` is not
    /// supported), so that tests can run every path the machine has.
    #[doc(hidden)]
    pub fn occlude_from_on(
        &self,
        path: SimdPath,
        origin: Vec3,
        ends: &[Vec3],
        t_max: f32,
        blocked: &mut [bool],
    ) {
        let kernel = shadow_fans::Occlude {
            bvh: self,
            origin,
            ends,
            t_max,
            blocked,
        };
        dispatch(path, kernel);
    }

    /// Like [`Bvh::occlude_from`] for segments with origins of their own: each segment `i`
    /// of `segments` not yet `blocked` becomes blocked when a triangle meets it for
    /// some `t` in `(0, t_max)`, as [`Bvh::occluded`] on that ray would say. Consecutive
    /// segments are traced together, a SIMD vector's width at a time, so they should run
    /// close to each other: the segments from a few neighbouring shading points to one light
    /// sample, say.
    pub fn occlude_segments(&self, segments: Segments, t_max: f32, blocked: &mut [bool]) {
        self.occlude_segments_on(simd_path(), segments, t_max, blocked);
    }

    /// [`Bvh::occlude_segments`] on a given SIMD path (the portable one when `path` is not
    /// supported), so that tests can run every path the machine has.
    #[doc(hidden)]
    pub fn occlude_segments_on(
        &self,
        path: SimdPath,
        segments: Segments,
        t_max: f32,
        blocked: &mut [bool],
    ) {
        let kernel = segments::OccludeSegments {
            bvh: self,
            segments,
            t_max,
            blocked,
        };
        dispatch(path, kernel);
    }

    /// Like [`Bvh::occlude_segments`] for every segment between `pairs`' origins and ends:
    /// slot `j · m + i` of `blocked` (for `m` origins) is segment `(j, i)`, from origin `i` to
    /// end `j`. Each not yet blocked becomes blocked when a triangle meets it for some `t` in
    /// `(0, t_max)`, as [`Bvh::occluded`] on that ray would say. The segments toward one end
    /// are traced together, a SIMD vector's width at a time, so consecutive origins should lie
    /// close to each other: a few neighbouring shading points, say, with the fixed samples of
    /// a light for ends.
    ///
    /// The triangles that lie in the hull of all the origins and ends (the shaft) are gathered
    /// first; when there are few, each packet tests those alone instead of walking the tree.
    pub fn occlude_pairs(&self, pairs: Pairs, t_max: f32, blocked: &mut [bool]) {
        self.occlude_pairs_on(simd_path(), pairs, t_max, blocked);
    }

    /// [`Bvh::occlude_pairs`] on a given SIMD path (the portable one when `path` is not
    /// supported), so that tests can run every path the machine has.
    #[doc(hidden)]
    pub fn occlude_pairs_on(&self, path: SimdPath, pairs: Pairs, t_max: f32, blocked: &mut [bool]) {
        let kernel = segments::OccludePairs {
            bvh: self,
            pairs,
            t_max,
            blocked,
        };
        dispatch(path, kernel);
    }

    /// Checks the structure's invariants against the geometry it was built from: every
    /// triangle appears exactly once, children are in range, and every box holds its contents.
    pub fn validate(&self, geometry: &Geometry) -> Result<(), String> {
        validate::validate(self, geometry)
    }
}
