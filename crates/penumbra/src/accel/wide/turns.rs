//! Rays walked in turns: the single-ray walk ([`WideBvh::walk`]) of a stream of rays, a few
//! at once, one step of each in turn, for the incoherent queries on trees larger than the
//! caches.
//!
//! An incoherent ray's walk through such a tree waits on memory more than it computes: each
//! node and leaf it visits is a cache miss whose address depends on the visit before.
//! [`INTERLEAVED`] independent walks side by side keep as many misses in flight, and a ray
//! whose walk ends gives its place to the next ray of the stream at once, so that none waits
//! for the longest walk of a batch. The visit of each ray is exactly the one it makes alone
//! (its own stack, `t_max` and hits), so every answer is the single-ray query's, bit for bit,
//! whatever `K`; only the order in which the rays' steps run changes.

use glam::Vec3;

use super::group::TriangleGroup;
use super::margins::tie_bound;
use super::tree::{found_hit, Found, Order, SlotHit, Stack, WideBvh};
use crate::accel::prim::boundary::Boundary;
use crate::accel::prim::watertight::{Crossing, EdgeRule, PreparedRay};
use crate::accel::AlphaTests;
use crate::simd::Isa;

/// Rays whose walks go in turn through a tree larger than `INTERLEAVE_BYTES` (`stack`). Eight
/// against four, in batches that waited for their longest walk: faster on the 1M-triangle
/// blob's occlusion and closest hits, about even on counting. In a stream (a walk that ends
/// gives its place to the next ray), six, ten, twelve and sixteen gained nothing over eight
/// (six lost; measured: docs/benchmarks.md, «Design measurements», `INTERLEAVED`).
pub(crate) const INTERLEAVED: usize = 8;

/// A ray walking in one of a stream's `K` places ([`WideBvh::walk_stream`]): its index in
/// the batch, the ray, its closest bound so far, and what its walk has found (`S`).
struct Walker<S> {
    index: usize,
    ray: PreparedRay,
    o: [f32; 3],
    inv: [f32; 3],
    t_max: f32,
    found: S,
}

impl WideBvh {
    /// The next walker of a stream, its walk started on `stack`: the next ray of `rays` that
    /// can hit something, `done(index, start(index))` for each ray before it that cannot.
    #[inline(always)]
    fn next_walker<S>(
        &self,
        rays: &mut impl Iterator<Item = (usize, Option<PreparedRay>)>,
        (t_max, start): (f32, &impl Fn(usize) -> S),
        stack: &mut Stack,
        done: &mut impl FnMut(usize, S),
    ) -> Option<Walker<S>> {
        for (index, ray) in rays {
            let Some(ray) = ray else {
                done(index, start(index));
                continue;
            };
            stack.start(self.wide());
            let [o, inv] = [ray.origin, ray.inv_dir].map(|v| v.to_array());
            return Some(Walker {
                index,
                ray,
                o,
                inv,
                t_max,
                found: start(index),
            });
        }
        None
    }

    /// The one walk of the wide tree for a stream of rays (with their indices), `K` at a
    /// time: each ray's visit is [`WideBvh::walk`]'s, with its own `t_max` and stack,
    /// `hit(found, …)` getting its hits into its `found` (`start(index)` at first), and
    /// `done(index, found)` called when its walk ends (at once for a ray of `None`). As soon
    /// as one walk ends, the next ray takes its place, so that `K` walks are under way until
    /// the rays run out.
    ///
    /// The rays take one step each in turn, so that the loads of one ray's nodes and
    /// triangles overlap the others' tests: a walk through a tree larger than the caches waits
    /// on memory more than it computes. Each ray sees exactly the visit it would see alone.
    #[allow(clippy::type_complexity)]
    #[inline(always)]
    pub(super) fn walk_stream<'a, const K: usize, S, I: Isa>(
        &'a self,
        mut rays: impl Iterator<Item = (usize, Option<PreparedRay>)>,
        (t_max, start): (f32, impl Fn(usize) -> S),
        tests: (f32, &impl Fn(f32) -> f32, Order, (EdgeRule, &[Boundary])),
        mut stacks: [&mut Stack; K],
        mut hit: impl FnMut(&mut S, &'a TriangleGroup, usize, Crossing, &mut f32) -> bool,
        mut done: impl FnMut(usize, S),
    ) {
        let mut walkers: [Option<Walker<S>>; K] = std::array::from_fn(|k| {
            self.next_walker(&mut rays, (t_max, &start), stacks[k], &mut done)
        });
        let mut live = walkers.iter().filter(|w| w.is_some()).count();
        while live != 0 {
            for (place, stack) in walkers.iter_mut().zip(stacks.iter_mut()) {
                let Some(w) = place else { continue };
                let found = &mut w.found;
                let mut hit = |g, lane, c, t: &mut f32| hit(found, g, lane, c, t);
                let ray = (&w.ray, &w.o, &w.inv);
                if !self.step::<I>(ray, &mut w.t_max, tests, stack, &mut hit) {
                    let next = self.next_walker(&mut rays, (t_max, &start), stack, &mut done);
                    let ended = std::mem::replace(place, next);
                    if let Some(w) = ended {
                        done(w.index, w.found);
                    }
                    live -= usize::from(place.is_none());
                }
            }
        }
    }

    /// [`WideBvh::closest`] of each ray of `rays`, `K` walks at a time
    /// ([`WideBvh::walk_stream`]): `done(index, hit)`.
    #[inline(always)]
    pub fn closest_stream<const K: usize, I: Isa>(
        &self,
        rays: impl Iterator<Item = (usize, Option<PreparedRay>)>,
        range: (f32, f32),
        alpha: Option<&AlphaTests>,
        stacks: [&mut Stack; K],
        mut done: impl FnMut(usize, Option<SlotHit>),
    ) {
        let done = |index, best: Option<Found>| done(index, best.map(found_hit));
        self.first_hits_stream::<K, false, I>(rays, range, alpha, stacks, done);
    }

    /// [`WideBvh::occluded`] of each ray of `rays`, `K` walks at a time
    /// ([`WideBvh::walk_stream`]): `done(index, occluded)`.
    #[inline(always)]
    pub fn occluded_stream<const K: usize, I: Isa>(
        &self,
        rays: impl Iterator<Item = (usize, Option<PreparedRay>)>,
        range: (f32, f32),
        alpha: Option<&AlphaTests>,
        stacks: [&mut Stack; K],
        mut done: impl FnMut(usize, bool),
    ) {
        let done = |index, best: Option<Found>| done(index, best.is_some());
        self.first_hits_stream::<K, true, I>(rays, range, alpha, stacks, done);
    }

    /// For each ray of `rays`, `done(index, hit)` with the hit [`WideBvh::keep`] keeps: the
    /// closest, or when `ANY` the first found.
    #[inline(always)]
    fn first_hits_stream<'a, const K: usize, const ANY: bool, I: Isa>(
        &'a self,
        rays: impl Iterator<Item = (usize, Option<PreparedRay>)>,
        (t_min, t_max): (f32, f32),
        alpha: Option<&AlphaTests>,
        stacks: [&mut Stack; K],
        done: impl FnMut(usize, Option<Found<'a>>),
    ) {
        let bound = |t| if ANY { t } else { tie_bound(t) };
        let order = if ANY { Order::Lanes } else { Order::Nearest };
        let tests = (t_min, &bound, order, (EdgeRule::Inclusive, &[][..]));
        let hit = |best: &mut Option<Found<'a>>, g, lane, c, t: &mut f32| {
            self.keep::<ANY>(best, alpha, (g, lane, c), t)
        };
        self.walk_stream::<K, _, I>(rays, (t_max, |_| None), tests, stacks, hit, done);
    }

    /// [`WideBvh::each_hit`] of each ray of `rays`, `K` walks at a time
    /// ([`WideBvh::walk_stream`]): `f(found, hit)` for each hit of a ray into its `found`
    /// (`start(index)` at first), then `done(index, found)`.
    #[allow(clippy::type_complexity)]
    #[inline(always)]
    pub fn each_hit_stream<const K: usize, S, I: Isa>(
        &self,
        rays: impl Iterator<Item = (usize, Option<PreparedRay>)>,
        (t_min, t_max): (f32, f32),
        (border, alpha): (&[Boundary], Option<&AlphaTests>),
        stacks: [&mut Stack; K],
        (start, mut f, done): (
            impl Fn(usize) -> S,
            impl FnMut(&mut S, SlotHit),
            impl FnMut(usize, S),
        ),
    ) {
        let tests = (t_min, &|t| t, Order::Free, (EdgeRule::Owned, border));
        let hit = |found: &mut S, g, lane, c, _: &mut f32| {
            self.each(alpha, (g, lane, c), &mut |hit| f(found, hit));
            true
        };
        self.walk_stream::<K, S, I>(rays, (t_max, start), tests, stacks, hit, done);
    }
}

/// The ray `[ox, oy, oz, dx, dy, dz]` prepared for traversal; `None` hits nothing.
#[inline(always)]
pub(crate) fn prepare(ray: &[f32; 6]) -> Option<PreparedRay> {
    PreparedRay::new(
        Vec3::new(ray[0], ray[1], ray[2]),
        Vec3::new(ray[3], ray[4], ray[5]),
    )
}

/// The rays of the chunks `chunks` (each `size` rays) of `rays`, with their indices,
/// prepared ([`prepare`]), for a stream of walks ([`WideBvh::walk_stream`]); none past a
/// chunk at whose start `cancelled()` holds.
pub(crate) fn stream<'r>(
    rays: &'r [[f32; 6]],
    (chunks, size): (impl IntoIterator<Item = usize> + 'r, usize),
    cancelled: impl Fn() -> bool + 'r,
) -> impl Iterator<Item = (usize, Option<PreparedRay>)> + 'r {
    (chunks.into_iter())
        .take_while(move |_| !cancelled())
        .flat_map(move |c| c * size..rays.len().min((c + 1) * size))
        .map(|i| (i, prepare(&rays[i])))
}

/// The stacks of a stream's `K` walks ([`WideBvh::walk_stream`]), on the heap: a query
/// makes them only where it streams.
pub(crate) struct Turns<const K: usize>(Vec<Stack>);

impl<const K: usize> Turns<K> {
    pub(crate) fn new() -> Turns<K> {
        const { assert!(K >= 1) };
        Turns((0..K).map(|_| Stack::default()).collect())
    }

    /// The stacks, one per walk.
    pub(crate) fn stacks(&mut self) -> [&mut Stack; K] {
        let stacks: &mut [Stack; K] = (self.0.as_mut_slice().try_into()).expect("K stacks");
        stacks.each_mut()
    }
}
