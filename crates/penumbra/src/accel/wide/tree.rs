//! The ray-casting engine's tree, [`WideBvh`], and its single-ray walks: closest hit, any hit
//! and every hit, with the watertight triangle test and a conservative box test, on the
//! eight-wide view of the binary [`Bvh`] (`node`); the closest-point query (`nearest`) walks
//! the binary tree. The ray queries are generic over the instruction set
//! (`crate::simd::Isa`) and inlined into the kernels of `kernels` and `packets`, which are
//! compiled once per instruction set.
//!
//! The tree keeps its own copy of the triangles in leaf order with their exact corners (the
//! renderer's leaves store `v0` and two edges, and `v0 + e1` is not always `v1` in `f32`,
//! which would break watertightness).
//!
//! The box test is Ize's, with the margins of `margins`. The build pads boxes so that
//! `bound − origin` is never zero for a ray touching the true box, hence no `0·∞` NaN there.

use glam::{Vec3, Vec3A};

use std::sync::OnceLock;

use super::group::{TriangleGroup, GROUP};
use super::margins::{tie_bound, EXIT_SCALE};
use super::node::{collapse, WideNode};
use super::stack::INTERLEAVE_BYTES;
pub(crate) use super::stack::{Order, Stack};
use crate::accel::prim::boundary::{boundaries, Boundary};
use crate::accel::prim::watertight::{unit_normal, Crossing, EdgeRule, PreparedRay, SoaTriangle};
use crate::accel::{AlphaTests, Bvh};
use crate::geometry::Geometry;
use crate::simd::{prefetch, Isa};

/// The `level` of a hit on the scene's own triangles.
pub(crate) const OWN: u32 = u32::MAX;

/// Triangles of the largest binary subtree that the wide tree holds as one leaf (one group).
/// With four, half of the bunny's four-wide nodes had only two children, both leaves: a
/// whole node load for two groups. At eight those subtrees are leaves, and the incoherent
/// queries took less CPU time, the more the busier the caches (twelve gained nothing more;
/// measured: docs/benchmarks.md, «Design measurements», `LEAF_MAX`).
const LEAF_MAX: u32 = GROUP as u32;

/// The BVH over every triangle of a scene with the triangles' exact corners and ids in the
/// BVH's leaf order.
#[derive(Debug, Default)]
pub(crate) struct WideBvh {
    bvh: Bvh,
    /// The eight-wide view of `bvh` that the ray queries traverse; a leaf child's index is
    /// its first group in `groups` and its count its number of triangles.
    wide: Vec<WideNode>,
    /// The triangles of each leaf as one group of up to eight.
    groups: Vec<TriangleGroup>,
    /// Corners of the triangle in each leaf slot.
    tris: Vec<SoaTriangle>,
    /// Geometry id and primitive id of the triangle in each leaf slot.
    ids: Vec<[u32; 2]>,
    /// Unit normal of the triangle in each leaf slot ([`unit_normal`]): made once here, where
    /// `cast_rays` computed one per hit (from the hit's group, a square root and a division
    /// each, a visible share of coherent rays' time; measured: docs/benchmarks.md, «Design
    /// measurements», `WideBvh::normals`).
    normals: Vec<[f32; 3]>,
    /// Each leaf slot's part of the surface's border, for the counting rule: made by the
    /// first counting query ([`WideBvh::border`]), which the others do not need.
    border: OnceLock<Vec<Boundary>>,
    /// Whether the single-ray walks go in turn ([`WideBvh::interleaves`]).
    interleave: bool,
}

/// A hit of the closest-hit or every-hit traversal: where, and which triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct SlotHit {
    pub crossing: Crossing,
    /// Geometry id.
    pub geometry: u32,
    /// Primitive id within the geometry.
    pub primitive: u32,
    /// Leaf slot, for [`WideBvh::normal`].
    pub slot: u32,
    /// The placement of the triangle hit ([`OWN`]: the scene's own).
    pub level: u32,
}

/// A hit found by a walk: the group, the lane and the crossing.
pub(super) type Found<'a> = (&'a TriangleGroup, usize, Crossing);

/// The hit record of a hit found by a walk, its ids read from its group (still in the caches).
#[inline(always)]
pub(super) fn found_hit((group, lane, crossing): Found) -> SlotHit {
    let [geometry, primitive] = group.ids(lane);
    SlotHit {
        crossing,
        geometry,
        primitive,
        slot: group.first + lane as u32,
        level: OWN,
    }
}

impl WideBvh {
    /// Builds the hierarchy over `geometry`, on `pool` when given. A triangle's geometry id
    /// is its `object`, its primitive id `local_ids[triangle]`.
    pub fn build(
        geometry: &Geometry,
        local_ids: &[u32],
        pool: Option<&rayon::ThreadPool>,
    ) -> WideBvh {
        let bvh = match pool {
            Some(pool) => Bvh::build_parallel(geometry, pool),
            None => Bvh::build(geometry),
        };
        let ids = |i: usize| [geometry.triangles[i].object, local_ids[i]];
        WideBvh::from_bvh(bvh, |i| geometry.corners(i), ids)
    }

    /// The wide view of `bvh`, a tree already built over triangles whose corners are
    /// `corners(triangle)` and whose geometry and primitive ids are `ids(triangle)`: a world's
    /// own tree or a mesh's, so that ray casting never builds a world's trees again.
    pub fn from_bvh(
        bvh: Bvh,
        corners: impl Fn(usize) -> [Vec3; 3],
        ids: impl Fn(usize) -> [u32; 2],
    ) -> WideBvh {
        let slots = bvh.prim_ids();
        let tris: Vec<SoaTriangle> = slots
            .iter()
            .map(|&i| SoaTriangle::new(&corners(i as usize).map(Vec3A::from)))
            .collect();
        let normals = tris
            .iter()
            .map(|t| unit_normal(&t.corners()).to_array())
            .collect();
        let ids: Vec<[u32; 2]> = slots.iter().map(|&i| ids(i as usize)).collect();
        // Each leaf's triangles as groups (one, at most eight triangles), the leaf child's
        // index its first group.
        let mut groups = Vec::new();
        let wide = collapse(bvh.nodes(), LEAF_MAX, &mut |first, count| {
            let index = groups.len() as u32;
            for start in (first..first + count).step_by(GROUP) {
                let n = (first + count - start).min(GROUP as u32);
                groups.push(TriangleGroup::new(&tris, &ids, start as usize, n as usize));
            }
            index
        });
        let mut tree = WideBvh {
            bvh,
            wide,
            groups,
            tris,
            ids,
            normals,
            border: OnceLock::new(),
            interleave: false,
        };
        tree.interleave = tree.walked_bytes() > INTERLEAVE_BYTES;
        tree
    }

    /// True unless the triangle in leaf slot `slot` is cut out where `crossing` meets it by
    /// `alpha`, the alpha tests of the tree's triangles (by triangle index), if any.
    #[inline(always)]
    pub(super) fn keeps(
        &self,
        alpha: Option<&AlphaTests>,
        slot: usize,
        crossing: &Crossing,
    ) -> bool {
        match alpha {
            None => true,
            Some(alpha) => {
                let triangle = self.bvh.prim_ids()[slot];
                alpha.keeps_flat(triangle, crossing.b1, crossing.b2)
            }
        }
    }

    /// The hit record of `crossing` on leaf slot `slot`.
    pub(crate) fn slot_hit(&self, slot: usize, crossing: Crossing) -> SlotHit {
        let [geometry, primitive] = self.ids[slot];
        SlotHit {
            crossing,
            geometry,
            primitive,
            slot: slot as u32,
            level: OWN,
        }
    }

    /// The unit normal `(v1 − v0) × (v2 − v0)` of the triangle in leaf slot `slot`.
    #[inline(always)]
    pub fn normal(&self, slot: u32) -> [f32; 3] {
        self.normals[slot as usize]
    }

    /// Each leaf slot's part of the surface's border (a vertex of the border owned by its
    /// first triangle added), made on first use, sorting the edges on `pool`.
    pub fn border(&self, pool: &rayon::ThreadPool) -> &[Boundary] {
        self.border.get_or_init(|| {
            let slots = self.bvh.prim_ids();
            // The corners by triangle, in the order they were added.
            let mut corners = vec![[Vec3A::ZERO; 3]; slots.len()];
            for (slot, &i) in slots.iter().enumerate() {
                corners[i as usize] = self.tris[slot].corners();
            }
            let by_triangle = boundaries(&corners, Some(pool));
            slots.iter().map(|&i| by_triangle[i as usize]).collect()
        })
    }

    /// [`WideBvh::border`] when it is made.
    pub fn made_border(&self) -> Option<&[Boundary]> {
        self.border.get().map(Vec::as_slice)
    }

    /// The binary tree.
    pub(crate) fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// The corners of every triangle by leaf slot.
    #[inline(always)]
    pub(crate) fn tris(&self) -> &[SoaTriangle] {
        &self.tris
    }

    /// The corners of scene triangle slot `slot` (leaf order).
    pub(crate) fn slot(&self, slot: usize) -> &SoaTriangle {
        &self.tris[slot]
    }

    /// The closest hit with `t` in `[t_min, t_max]`, edges and vertices inclusive. Its ids
    /// come from the hit's group, still in the caches when the ray is done: read from the
    /// array indexed by slot, they were a cache miss at the end of each incoherent ray.
    #[inline(always)]
    pub fn closest<I: Isa>(
        &self,
        ray: &PreparedRay,
        (t_min, t_max): (f32, f32),
        alpha: Option<&AlphaTests>,
        stack: &mut Stack,
    ) -> Option<SlotHit> {
        let mut best = None;
        // A box entered past the closest hit so far cannot hold a closer hit nor a tie.
        let tests = (
            t_min,
            &tie_bound,
            Order::Nearest,
            (EdgeRule::Inclusive, &[][..]),
        );
        self.walk::<I>(ray, &mut t_max.clone(), tests, stack, |g, lane, c, t| {
            self.keep::<false>(&mut best, alpha, (g, lane, c), t)
        });
        best.map(found_hit)
    }

    /// True when some triangle meets the ray with `t` in `[t_min, t_max]`, edges and vertices
    /// inclusive; stops at the first.
    #[inline(always)]
    pub fn occluded<I: Isa>(
        &self,
        ray: &PreparedRay,
        (t_min, t_max): (f32, f32),
        alpha: Option<&AlphaTests>,
        stack: &mut Stack,
    ) -> bool {
        // The any-hit rule of `keep`, with a flag for the hit: keeping the hit itself cost
        // the one-ray occlusion walk 1.5 % more instructions.
        let mut found = false;
        let tests = (t_min, &|t| t, Order::Lanes, (EdgeRule::Inclusive, &[][..]));
        self.walk::<I>(ray, &mut t_max.clone(), tests, stack, |g, lane, c, _| {
            found = self.keeps(alpha, g.first as usize + lane, &c);
            !found
        });
        found
    }

    /// The closest-hit rule, for a hit `found` of a walk with the closest hit so far `best` at
    /// `t_max`: the smallest `t`, and among hits at exactly that `t` the smallest geometry
    /// id, then primitive id, whatever the order of the visit; or, when `ANY`, the first hit
    /// found. Keeps `found` in `best` (lowering `t_max`) when it wins and `alpha` does not cut
    /// it out; false when the walk may stop.
    #[inline(always)]
    pub(super) fn keep<'a, const ANY: bool>(
        &self,
        best: &mut Option<Found<'a>>,
        alpha: Option<&AlphaTests>,
        (group, lane, c): Found<'a>,
        t_max: &mut f32,
    ) -> bool {
        let slot = group.first as usize + lane;
        if ANY {
            if !self.keeps(alpha, slot, &c) {
                return true;
            }
            *best = Some((group, lane, c));
            return false;
        }
        // Lanes of one group are tested against the same `t_max`: a later lane may be farther
        // than an earlier one's hit. Ids are read only for a tie.
        let closer = match best {
            None => true,
            Some((g, l, _)) => {
                let other = g.first as usize + *l;
                c.t < *t_max || (c.t == *t_max && self.key(slot) < self.key(other))
            }
        };
        if closer && self.keeps(alpha, slot, &c) {
            *t_max = c.t;
            *best = Some((group, lane, c));
        }
        true
    }

    /// The one walk of the wide tree every single-ray query is made of: visits the leaves the
    /// ray enters with `t` in `[t_min, bound(t_max)]` (children in `order`), tests
    /// their groups under `rule` (with the border of [`WideBvh::border`] for
    /// [`EdgeRule::Owned`]) for `t` in `[t_min, t_max]`, and calls `hit(group, lane,
    /// crossing, t_max)` for each hit, which may lower `t_max` and returns false to stop:
    /// [`WideBvh::step`] until the ray is done.
    #[allow(clippy::type_complexity)]
    #[inline(always)]
    fn walk<'a, I: Isa>(
        &'a self,
        ray: &PreparedRay,
        t_max: &mut f32,
        tests: (f32, &impl Fn(f32) -> f32, Order, (EdgeRule, &[Boundary])),
        stack: &mut Stack,
        mut hit: impl FnMut(&'a TriangleGroup, usize, Crossing, &mut f32) -> bool,
    ) {
        let (o, inv) = (ray.origin.to_array(), ray.inv_dir.to_array());
        stack.start(&self.wide);
        while self.step::<I>((ray, &o, &inv), t_max, tests, stack, &mut hit) {}
    }

    /// One step of a ray's walk ([`WideBvh::walk`]): the next entry of its stack that
    /// it enters before `bound(t_max)`, a wide node's children pushed or a leaf's groups
    /// tested. False when the ray is done: its stack is empty or `hit` said stop.
    #[allow(clippy::type_complexity)]
    #[inline(always)]
    pub(super) fn step<'a, I: Isa>(
        &'a self,
        (ray, o, inv): (&PreparedRay, &[f32; 3], &[f32; 3]),
        t_max: &mut f32,
        (t_min, bound, order, (rule, border)): (
            f32,
            &impl Fn(f32) -> f32,
            Order,
            (EdgeRule, &[Boundary]),
        ),
        stack: &mut Stack,
        hit: &mut impl FnMut(&'a TriangleGroup, usize, Crossing, &mut f32) -> bool,
    ) -> bool {
        let limit = bound(*t_max);
        let next = loop {
            match stack.pop() {
                Some((_, _, near)) if near > limit => continue,
                entry => break entry,
            }
        };
        let Some((first, count, _)) = next else {
            return false;
        };
        if count == 0 {
            let node = &self.wide[first as usize];
            let (mask, near) = node.enter::<I>(o, inv, t_min, limit, EXIT_SCALE);
            stack.push_children(|i, c| self.prefetch_child(i, c), node, mask, &near, order);
            return true;
        }
        for (group, valid) in self.leaf(first, count) {
            let hits = ray.hit_group::<I>(group, valid, &self.tris, border, t_min, *t_max, rule);
            let mut mask = hits.mask;
            while mask != 0 {
                let lane = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                if !hit(group, lane, hits.crossing(lane), t_max) {
                    return false;
                }
            }
        }
        true
    }

    /// Starts loading the child `(index, count)` of a wide node (a wide node when `count` is
    /// 0, else a leaf's first group) into the caches: its visit comes a little later.
    #[inline(always)]
    pub(crate) fn prefetch_child(&self, index: u32, count: u32) {
        if count == 0 {
            prefetch(&self.wide[index as usize]);
        } else {
            prefetch(&self.groups[index as usize]);
        }
    }

    /// The bytes of the wide nodes and triangle groups that the walks read.
    pub(super) fn walked_bytes(&self) -> usize {
        self.wide.len() * size_of::<WideNode>() + self.groups.len() * size_of::<TriangleGroup>()
    }

    /// True when the single-ray walks of this tree go in turn ([`WideBvh::walk_stream`]):
    /// when its nodes and triangles take more than [`INTERLEAVE_BYTES`].
    pub(crate) fn interleaves(&self) -> bool {
        self.interleave
    }

    /// This tree with its single-ray walks in turn whatever its size, for tests of the
    /// queries that walk so on large trees only.
    #[cfg(test)]
    pub(crate) fn interleaved(self) -> WideBvh {
        WideBvh {
            interleave: true,
            ..self
        }
    }

    /// The wide tree.
    pub(crate) fn wide(&self) -> &[WideNode] {
        &self.wide
    }

    /// The groups of the leaf whose first group is `first` and which holds `count`
    /// triangles, each with its mask of valid lanes.
    #[inline(always)]
    pub(crate) fn leaf(
        &self,
        first: u32,
        count: u32,
    ) -> impl Iterator<Item = (&TriangleGroup, u32)> {
        let groups = count.div_ceil(GROUP as u32) as usize;
        let first = first as usize;
        self.groups[first..first + groups]
            .iter()
            .enumerate()
            .map(move |(k, group)| {
                let lanes = (count as usize - k * GROUP).min(GROUP);
                (group, (1u32 << lanes) - 1)
            })
    }

    /// The order of the closest-hit rule among hits at the same `t`: geometry id, then
    /// primitive id, of leaf slot `slot`.
    #[inline(always)]
    pub(crate) fn key(&self, slot: usize) -> u64 {
        let [geometry, primitive] = self.ids[slot];
        ((geometry as u64) << 32) | primitive as u64
    }

    /// Calls `f` with every hit with `t` in `[t_min, t_max]` under the [`EdgeRule::Owned`] rule
    /// (one hit per crossing of the surface), in traversal order; `border` is
    /// [`WideBvh::border`].
    #[inline(always)]
    pub fn each_hit<I: Isa>(
        &self,
        ray: &PreparedRay,
        (t_min, t_max): (f32, f32),
        (border, alpha): (&[Boundary], Option<&AlphaTests>),
        stack: &mut Stack,
        f: &mut impl FnMut(SlotHit),
    ) {
        let tests = (t_min, &|t| t, Order::Free, (EdgeRule::Owned, border));
        self.walk::<I>(ray, &mut t_max.clone(), tests, stack, |g, lane, c, _| {
            self.each(alpha, (g, lane, c), f);
            true
        });
    }

    /// Calls `f` with every hit with `t` in `[t_min, t_max]` under the
    /// [`EdgeRule::Inclusive`] rule (each triangle the ray meets, edges and vertices
    /// inclusive), in traversal order.
    pub fn each_met<I: Isa>(
        &self,
        ray: &PreparedRay,
        (t_min, t_max): (f32, f32),
        alpha: Option<&AlphaTests>,
        stack: &mut Stack,
        f: &mut impl FnMut(SlotHit),
    ) {
        let tests = (t_min, &|t| t, Order::Free, (EdgeRule::Inclusive, &[][..]));
        self.walk::<I>(ray, &mut t_max.clone(), tests, stack, |g, lane, c, _| {
            self.each(alpha, (g, lane, c), f);
            true
        });
    }

    /// Calls `f` with the hit record of `found` unless `alpha` cuts it out.
    #[inline(always)]
    pub(super) fn each(
        &self,
        alpha: Option<&AlphaTests>,
        (g, lane, c): Found,
        f: &mut impl FnMut(SlotHit),
    ) {
        // The ids from the group, in the caches: from the array by slot, they were a cache
        // miss a crossing on trees larger than the caches.
        if self.keeps(alpha, g.first as usize + lane, &c) {
            f(found_hit((g, lane, c)));
        }
    }
}
