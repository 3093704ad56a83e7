//! One interface over both of the engine's trees: [`Tree`], the closest, any and every hit of
//! one ray, each with a hit [`Filter`] asked after the primitive test (none, or the cut-outs'
//! alpha test), as Embree's intersection filter and pbrt-v4's `GeometricPrimitive` ask theirs,
//! and under the tree's [`Rule`]: the interval a hit's `t` may take and the order that breaks
//! ties.
//!
//! Two trees implement it, each with its one primitive test:
//! - the binary [`Bvh`] (Möller–Trumbore, the renderer's): `t` in the open interval
//!   `(t_min, t_max)`, ties to the smaller triangle index, so that the renderer's images stay
//!   what they are bit for bit;
//! - the [`WideBvh`] (the watertight test, ray casting's): `t` in the closed interval
//!   `[t_min, t_max]`, edges and vertices inclusive, ties to the smaller (geometry, primitive)
//!   id, as Open3D answers.
//!
//! A filter is asked only about a hit that would count: one that would become the closest so
//! far, end an any-hit walk, or be reported. A hit it refuses does not shorten a closest-hit
//! ray, and an any-hit walk looks on past it. The filter names a triangle by the tree's own
//! triangle index (its `prim_ids`), which is how [`AlphaTests::keeps_flat`] numbers them.
//! A walk takes its filter as a type ([`Keep`]): the alpha tests, asked on each hit, or
//! [`KeepAll`], with no test compiled in, for trees and placements that have none.

use glam::Vec3;

use super::prim::boundary::Boundary;
use super::prim::watertight::PreparedRay;
use super::wide::{SlotHit, Stack, WideBvh, EXIT_SCALE};
use super::{traverse, AlphaTests, Bvh};
use crate::geometry::Hit;
use crate::math::Ray;
use crate::simd::Isa;

/// What a hit must pass after the primitive test: the alpha tests (`Some`) keep a hit unless
/// its triangle's material cuts it out where the ray meets it; `None` keeps every hit.
pub(crate) type Filter<'a> = Option<&'a AlphaTests>;

/// A filter as a walk takes it: [`Filter`], asked on each hit, or [`KeepAll`], which a walk
/// compiles without a test. A set of placements none of which has alpha tests walks with
/// `KeepAll` (see `placed`), so that an opaque placement's walk is the plain one.
pub(crate) trait Keep<'a>: Copy {
    /// The filter of a placement whose alpha tests are `alpha`.
    fn of(alpha: Filter<'a>) -> Self;
    /// Whether the hit at barycentrics `(b1, b2)` of triangle `id` is kept.
    fn keeps(self, id: u32, b1: f32, b2: f32) -> bool;
    /// The alpha tests, for a tree whose walks take them as a [`Filter`].
    fn tests(self) -> Filter<'a>;
}

/// Keeps every hit, with no test.
#[derive(Clone, Copy, Debug)]
pub(crate) struct KeepAll;

impl<'a> Keep<'a> for KeepAll {
    #[inline(always)]
    fn of(alpha: Filter<'a>) -> Self {
        debug_assert!(
            alpha.is_none(),
            "KeepAll walks placements with no alpha tests"
        );
        KeepAll
    }
    #[inline(always)]
    fn keeps(self, _: u32, _: f32, _: f32) -> bool {
        true
    }
    #[inline(always)]
    fn tests(self) -> Filter<'a> {
        None
    }
}

impl<'a> Keep<'a> for Filter<'a> {
    #[inline(always)]
    fn of(alpha: Filter<'a>) -> Self {
        alpha
    }
    #[inline(always)]
    fn keeps(self, id: u32, b1: f32, b2: f32) -> bool {
        self.is_none_or(|alpha| alpha.keeps_flat(id, b1, b2))
    }
    #[inline(always)]
    fn tests(self) -> Filter<'a> {
        self
    }
}

/// The interval of `t` a tree's hits may take.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Rule {
    /// `(t_min, t_max)`, ties to the smaller triangle index: the renderer's.
    Open,
    /// `[t_min, t_max]`, edges and vertices inclusive, ties to the smaller (geometry,
    /// primitive) id: ray casting's.
    Closed,
}

/// A tree of triangles and its single-ray queries (see the module's docs).
pub(crate) trait Tree {
    /// A ray as the tree's primitive test takes it.
    type Ray;
    /// A hit as the tree reports it.
    type Hit: Copy;
    /// The scratch a walk needs (a stack), made once per thread and reused.
    type Stack: Default;
    /// The interval of `t` and the order of ties.
    const RULE: Rule;
    /// The margin a top-level box's exit distance is raised by ([`raised`]): 1 for the
    /// binary tree, Ize's conservative scale for the watertight one, as its own nodes use.
    const EXIT_SCALE: f32;
    /// True when an any-hit query walks the top level nearest first (the wide tree: ray
    /// casting's occlusion walked so before the level was shared); false for tree order,
    /// depth first (the binary tree: the renderer's single shadow rays walked so). Each tree
    /// keeps its walk; the other order has not been measured on it.
    const ANY_NEAREST_FIRST: bool;

    /// The binary tree it is made of (itself, or the wide tree's source), whose root box
    /// bounds the mesh.
    fn bvh(&self) -> &Bvh;

    /// Its part of the surface's border for [`Tree::each`], when made ([`WideBvh::border`]);
    /// the binary tree has none.
    fn border(&self) -> Option<&[Boundary]>;

    /// `origin + t·direction` prepared for [`Tree::closest`] and the others; `None` for a ray
    /// that can hit nothing (a component not finite, a zero direction).
    fn prepare(origin: Vec3, direction: Vec3) -> Option<Self::Ray>;

    /// The closest hit with `t` in `range` under [`Tree::RULE`] that `filter` keeps, if any.
    fn closest<'f, I: Isa, K: Keep<'f>>(
        &self,
        ray: &Self::Ray,
        range: (f32, f32),
        filter: K,
        stack: &mut Self::Stack,
    ) -> Option<Self::Hit>;

    /// True when some hit with `t` in `range` passes `filter`; stops at the first.
    fn any<'f, I: Isa, K: Keep<'f>>(
        &self,
        ray: &Self::Ray,
        range: (f32, f32),
        filter: K,
        stack: &mut Self::Stack,
    ) -> bool;

    /// Calls `f` with every hit with `t` in `range` that `filter` keeps, in the walk's order.
    /// `border` (the wide tree's [`WideBvh::border`]) counts each crossing of the surface
    /// once: a ray through an edge or vertex is reported by the one triangle that owns it;
    /// without it, every triangle the ray meets is reported. The binary tree takes no border.
    fn each<'f, I: Isa, K: Keep<'f>>(
        &self,
        ray: &Self::Ray,
        range: (f32, f32),
        filters: (K, Option<&[Boundary]>),
        stack: &mut Self::Stack,
        f: &mut impl FnMut(Self::Hit),
    );

    /// The `t` of `hit`.
    fn t(hit: &Self::Hit) -> f32;

    /// The key that breaks a tie of `hit` with another at the same `t`: the smaller wins.
    fn tie_key(hit: &Self::Hit) -> u64;

    /// `hit`, found in placement `index` (whose hits report `id`), as the placement's.
    fn placed(hit: Self::Hit, id: u32, index: u32) -> Self::Hit;
}

impl Tree for Bvh {
    type Ray = Ray;
    type Hit = Hit;
    type Stack = ();
    const RULE: Rule = Rule::Open;
    const EXIT_SCALE: f32 = 1.0;
    const ANY_NEAREST_FIRST: bool = false;

    fn bvh(&self) -> &Bvh {
        self
    }

    fn border(&self) -> Option<&[Boundary]> {
        None
    }

    fn prepare(origin: Vec3, direction: Vec3) -> Option<Ray> {
        Some(Ray::new(origin, direction))
    }

    #[inline(always)]
    fn closest<'f, I: Isa, K: Keep<'f>>(
        &self,
        ray: &Ray,
        range: (f32, f32),
        filter: K,
        _: &mut (),
    ) -> Option<Hit> {
        // One walk for either filter: with alpha tests the test is a branch on a hit (a
        // `match` that made two walks was slower, and the larger code was no longer inlined
        // whole); with [`KeepAll`] it is compiled away.
        let keep = |id, b1, b2| filter.keeps(id, b1, b2);
        traverse::intersect_kept(self, ray, range.0, range.1, keep)
    }

    #[inline(always)]
    fn any<'f, I: Isa, K: Keep<'f>>(
        &self,
        ray: &Ray,
        range: (f32, f32),
        filter: K,
        _: &mut (),
    ) -> bool {
        let keep = |id, b1, b2| filter.keeps(id, b1, b2);
        traverse::occluded_kept(self, ray, range.0, range.1, keep)
    }

    fn each<'f, I: Isa, K: Keep<'f>>(
        &self,
        ray: &Ray,
        range: (f32, f32),
        (filter, border): (K, Option<&[Boundary]>),
        _: &mut (),
        f: &mut impl FnMut(Hit),
    ) {
        debug_assert!(border.is_none(), "Möller–Trumbore owns no border");
        let keep = |id, b1, b2| filter.keeps(id, b1, b2);
        traverse::each_kept(self, ray, range, keep, f);
    }

    #[inline(always)]
    fn t(hit: &Hit) -> f32 {
        hit.t
    }

    /// The world's own triangles first, then by instance, then by triangle.
    #[inline(always)]
    fn tie_key(hit: &Hit) -> u64 {
        (hit.instance.map_or(0, |i| u64::from(i) + 1) << 32) | u64::from(hit.triangle)
    }

    #[inline(always)]
    fn placed(hit: Hit, id: u32, _: u32) -> Hit {
        Hit {
            instance: Some(id),
            ..hit
        }
    }
}

impl Tree for WideBvh {
    type Ray = PreparedRay;
    type Hit = SlotHit;
    type Stack = Stack;
    const RULE: Rule = Rule::Closed;
    const EXIT_SCALE: f32 = EXIT_SCALE;
    const ANY_NEAREST_FIRST: bool = true;

    fn bvh(&self) -> &Bvh {
        WideBvh::bvh(self)
    }

    /// Made by `WideLevels::borders` before any query that counts.
    fn border(&self) -> Option<&[Boundary]> {
        self.made_border()
    }

    fn prepare(origin: Vec3, direction: Vec3) -> Option<PreparedRay> {
        PreparedRay::new(origin, direction)
    }

    #[inline(always)]
    fn closest<'f, I: Isa, K: Keep<'f>>(
        &self,
        ray: &PreparedRay,
        range: (f32, f32),
        filter: K,
        stack: &mut Stack,
    ) -> Option<SlotHit> {
        WideBvh::closest::<I>(self, ray, range, filter.tests(), stack)
    }

    #[inline(always)]
    fn any<'f, I: Isa, K: Keep<'f>>(
        &self,
        ray: &PreparedRay,
        range: (f32, f32),
        filter: K,
        stack: &mut Stack,
    ) -> bool {
        WideBvh::occluded::<I>(self, ray, range, filter.tests(), stack)
    }

    fn each<'f, I: Isa, K: Keep<'f>>(
        &self,
        ray: &PreparedRay,
        range: (f32, f32),
        (filter, border): (K, Option<&[Boundary]>),
        stack: &mut Stack,
        f: &mut impl FnMut(SlotHit),
    ) {
        let filter = filter.tests();
        match border {
            Some(border) => self.each_hit::<I>(ray, range, (border, filter), stack, f),
            None => self.each_met::<I>(ray, range, filter, stack, f),
        }
    }

    #[inline(always)]
    fn t(hit: &SlotHit) -> f32 {
        hit.crossing.t
    }

    /// By geometry id, then primitive id.
    #[inline(always)]
    fn tie_key(hit: &SlotHit) -> u64 {
        (u64::from(hit.geometry) << 32) | u64::from(hit.primitive)
    }

    #[inline(always)]
    fn placed(hit: SlotHit, id: u32, index: u32) -> SlotHit {
        SlotHit {
            geometry: id,
            level: index,
            ..hit
        }
    }
}
