//! The single-ray queries of a chunk of rays as [`Kernel`]s, so that the traversal (its
//! eight-lane box test above all, `node`) is compiled for each instruction set by
//! `crate::simd` and runs with the best one the CPU has: AVX2's eight lanes test a wide node's
//! children in one pass, where the baseline's SSE needs two.
//!
//! Every path computes the same answers: the lanes do the same operations whatever their
//! width, and Rust never fuses a multiply and an add on its own.
//!
//! A kernel asks the query that runs it ([`Control`]) whether to stop, and for room for
//! results that grow as they are found; the ray-casting API's options answer.

use glam::Vec3;

use super::levels::{Borders, WideLevels};
use super::nearest::Nearest;
use super::tree::{SlotHit, Stack};
use super::turns::{prepare, stream, Turns, INTERLEAVED};

use super::control::Control;
use super::packets::{count_parallel, CastPackets};
use crate::simd::{dispatch, Isa, Kernel, SimdPath};

/// Rays between two looks at the cancel flag: a ray through a dense region can take
/// milliseconds, so a chunk of 1024 could take seconds; a look at every ray slowed the
/// counting query (measured: docs/benchmarks.md, «Design measurements», `CHECK`).
const CHECK: usize = 8;

/// Lanes of a packet of parallel rays (four vectors with AVX2, two with AVX-512).
const PARALLEL: usize = 32;

/// Whether a triangle meets each ray of `rays` with `t` in `range`, written to `out`: the
/// own tree's ([`WideLevels::occluded_own`]), or with `PLACED` the placements' for each ray
/// not yet occluded ([`WideLevels::occluded_placed`]). The two are kernels of their own, so
/// that the own tree's walk compiles as it does alone.
pub(crate) struct Occlusions<'a, C, const PLACED: bool> {
    pub accel: &'a WideLevels,
    /// Checked every [`CHECK`] rays: a cancelled query stops there.
    pub options: &'a C,
    pub rays: &'a [[f32; 6]],
    pub range: (f32, f32),
    pub out: &'a mut [bool],
}

impl<C: Control, const PLACED: bool> Kernel for Occlusions<'_, C, PLACED> {
    type Output = ();

    #[inline(always)]
    fn run<const N: usize, I: Isa>(self) {
        let (accel, range) = (self.accel, self.range);
        let mut stack = Stack::default();
        let interleave = accel.own().interleaves();
        if !PLACED && interleave {
            let mut turns = Turns::<INTERLEAVED>::new();
            let stacks = turns.stacks();
            let (options, chunks) = (self.options, 0..self.rays.len().div_ceil(CHECK));
            let rays = stream(self.rays, (chunks, CHECK), || options.cancelled());
            let out = &mut *self.out;
            accel.occluded_own_stream::<INTERLEAVED, I>(rays, range, stacks, |i, o| out[i] = o);
            return;
        }
        for (rays, out) in self.rays.chunks(CHECK).zip(self.out.chunks_mut(CHECK)) {
            if self.options.cancelled() {
                return;
            }
            if PLACED {
                for (ray, o) in rays.iter().zip(out) {
                    *o = *o || accel.occluded_placed::<I>(ray, range, &mut stack);
                }
            } else {
                for (ray, o) in rays.iter().zip(out) {
                    *o = prepare(ray)
                        .is_some_and(|r| accel.occluded_own::<I>(&r, range, &mut stack));
                }
            }
        }
    }
}

/// The closest of each hit of `hits` (the own tree's, from `packets::CastPackets`) and the
/// placements' hits of its ray of `rays` ([`WideLevels::closest_placed`]), `t` in `[0, ∞]`.
pub(crate) struct ClosestPlaced<'a, C> {
    pub accel: &'a WideLevels,
    /// Hits with `t` in this range count.
    pub range: (f32, f32),
    /// Checked every [`CHECK`] rays.
    pub options: &'a C,
    pub rays: &'a [[f32; 6]],
    pub hits: &'a mut [Option<SlotHit>],
}

impl<C: Control> Kernel for ClosestPlaced<'_, C> {
    type Output = ();

    #[inline(always)]
    fn run<const N: usize, I: Isa>(self) {
        let mut stack = Stack::default();
        for (rays, hits) in self.rays.chunks(CHECK).zip(self.hits.chunks_mut(CHECK)) {
            if self.options.cancelled() {
                return;
            }
            for (ray, hit) in rays.iter().zip(hits) {
                *hit = self
                    .accel
                    .closest_placed::<I>(ray, self.range, *hit, &mut stack);
            }
        }
    }
}

/// The closest point of the surface to each finite point of `points`
/// ([`WideLevels::nearest`]), written to `out` (left alone for the others).
pub(crate) struct Nearests<'a, C> {
    pub accel: &'a WideLevels,
    /// Checked every [`CHECK`] points.
    pub options: &'a C,
    pub points: &'a [[f32; 3]],
    pub out: &'a mut [Option<Nearest>],
}

impl<C: Control> Kernel for Nearests<'_, C> {
    type Output = ();

    #[inline(always)]
    fn run<const N: usize, I: Isa>(self) {
        let mut stack = Stack::default();
        // The previous point's answer: no surface point is farther than it (see `seed`).
        let mut last: Option<Vec3> = None;
        for (points, out) in self.points.chunks(CHECK).zip(self.out.chunks_mut(CHECK)) {
            if self.options.cancelled() {
                return;
            }
            for (p, near) in points.iter().zip(out) {
                let p = Vec3::from(*p);
                if !p.is_finite() {
                    continue;
                }
                let accel = self.accel;
                let bound = last.map_or(f64::INFINITY, |q| seed(p, q));
                *near = accel
                    .nearest::<I>(p, bound, &mut stack)
                    .or_else(|| accel.nearest::<I>(p, f64::INFINITY, &mut stack));
                last = near.map(|n| n.point);
            }
        }
    }
}

/// A squared distance from `p` within which some triangle lies, when `q` is the closest point
/// of a triangle to another point (rounded to `f32`: within `2⁻²⁴` of its largest coordinate
/// per coordinate, and `2⁻²²` covers that and the `f64` arithmetic).
fn seed(p: Vec3, q: Vec3) -> f64 {
    let slack = q.abs().max_element() as f64 / 4_194_304.0;
    let d = (p.as_dvec3() - q.as_dvec3()).length() * (1.0 + 1e-12) + slack;
    d * d
}

/// The number of crossings from `t = 0` on of each ray of `rays`: the own tree's
/// ([`WideLevels::each_hit_own`]) written to `out` (left alone for a ray that hits nothing),
/// or with `PLACED` the placements' ([`WideLevels::each_hit_placed`]) added to it (two
/// kernels, as for [`Occlusions`]).
pub(crate) struct Counts<'a, C, const PLACED: bool> {
    pub accel: &'a WideLevels,
    /// Crossings with `t` in this range count.
    pub range: (f32, f32),
    /// [`WideLevels::borders`].
    pub border: &'a Borders<'a>,
    /// Checked every [`CHECK`] rays, and by a packet's walk before each leaf.
    pub options: &'a C,
    pub rays: &'a [[f32; 6]],
    pub out: &'a mut [i32],
}

impl<C: Control, const PLACED: bool> Kernel for Counts<'_, C, PLACED> {
    type Output = ();

    #[inline(always)]
    fn run<const N: usize, I: Isa>(self) {
        let (accel, border, range) = (self.accel, self.border, self.range);
        let mut stack = Stack::default();
        let interleave = accel.own().interleaves();
        let mut packet_stack = Vec::new();
        // Runs of parallel rays go as packets of 32 through the own tree (without cut-outs):
        // such rays share most of their walk, and occupancy took less time with 32 lanes than
        // with 16 (measured: docs/benchmarks.md, «Design measurements», parallel-ray packets).
        let packets = !PLACED && accel.own_alpha().is_none();
        // On a tree larger than the caches, the runs left to single rays go after, as one
        // stream of walks in turn.
        let mut streamed = Vec::new();
        for (c, (rays, out)) in (self.rays.chunks(PARALLEL))
            .zip(self.out.chunks_mut(PARALLEL))
            .enumerate()
        {
            if packets {
                if self.options.cancelled() {
                    return;
                }
                let (tree, parallel) = (accel.own(), (range, border.own));
                let stack = &mut packet_stack;
                let options = self.options;
                let done =
                    count_parallel::<PARALLEL, I, _>(tree, rays, parallel, options, stack, out);
                if done {
                    continue;
                }
            }
            if !PLACED && interleave {
                streamed.push(c);
                continue;
            }
            for (rays, out) in rays.chunks(CHECK).zip(out.chunks_mut(CHECK)) {
                if self.options.cancelled() {
                    return;
                }
                if PLACED {
                    for (ray, count) in rays.iter().zip(out) {
                        let mut n = 0i32;
                        let tally = &mut |_| n = n.saturating_add(1);
                        accel.each_hit_placed::<I>(ray, range, border, &mut stack, tally);
                        *count = count.saturating_add(n);
                    }
                } else {
                    for (ray, count) in rays.iter().zip(out) {
                        let Some(r) = prepare(ray) else { continue };
                        let mut n = 0i32;
                        let tally = &mut |_| n = n.saturating_add(1);
                        accel.each_hit_own::<I>(&r, range, border, &mut stack, tally);
                        *count = n;
                    }
                }
            }
        }
        if streamed.is_empty() {
            return;
        }
        let mut turns = Turns::<INTERLEAVED>::new();
        let (stacks, options) = (turns.stacks(), self.options);
        let rays = stream(self.rays, (streamed.iter().copied(), PARALLEL), || {
            options.cancelled()
        });
        let tally = |n: &mut i32, _| *n = n.saturating_add(1);
        let out = &mut *self.out;
        let calls = (|_| 0, tally, |i, n| out[i] = n);
        accel.each_hit_own_stream::<INTERLEAVED, i32, I>(rays, range, border, stacks, calls);
    }
}

/// The hits of each ray of `rays` from `t = 0` on, one per crossing, sorted by `t` then ids:
/// the number of each ray's hits, and all the hits one ray after the other; `Err` when the
/// query is cancelled (checked before each ray) or the hits do not fit in memory.
pub(crate) struct Listing<'a, C> {
    pub accel: &'a WideLevels,
    /// [`WideLevels::borders`].
    pub border: &'a Borders<'a>,
    pub rays: &'a [[f32; 6]],
    pub options: &'a C,
}

/// What [`Listing`] finds.
pub(crate) type Listed<E> = Result<(Vec<u32>, Vec<SlotHit>), E>;

impl<C: Control> Kernel for Listing<'_, C> {
    type Output = Listed<C::Error>;

    #[inline(always)]
    fn run<const N: usize, I: Isa>(self) -> Listed<C::Error> {
        match self.accel.own().interleaves() {
            true => self.list::<INTERLEAVED, I>(),
            false => self.list::<1, I>(),
        }
    }
}

impl<C: Control> Listing<'_, C> {
    /// [`Listing`] with the own tree's walks one ray at a time (`K` of 1) or `K` in turn
    /// (see `turns`).
    #[inline(always)]
    pub(super) fn list<const K: usize, I: Isa>(self) -> Listed<C::Error> {
        let (accel, border, options, rays) = (self.accel, self.border, self.options, self.rays);
        let what = "the intersections";
        let mut counts = Vec::new();
        options.grow(&mut counts, rays.len(), what)?;
        counts.resize(rays.len(), 0u32);
        // Every crossing with its ray, in the order the walks find them; a ray may cross
        // millions of triangles, so grown fallibly.
        let mut found: Vec<(u32, SlotHit)> = Vec::new();
        let mut full = Ok(());
        let mut push = |i: u32, h| {
            if full.is_ok() {
                full = options.grow(&mut found, 1, what);
            }
            if full.is_ok() {
                found.push((i, h));
                counts[i as usize] += 1;
            }
        };
        let range = (0.0, f32::INFINITY);
        let mut stack = Stack::default();
        match K {
            1 => {
                for (i, ray) in rays.iter().enumerate() {
                    if i.is_multiple_of(CHECK) && options.cancelled() {
                        break;
                    }
                    if let Some(r) = prepare(ray) {
                        let f = &mut |h| push(i as u32, h);
                        accel.each_hit_own::<I>(&r, range, border, &mut stack, f);
                    }
                }
            }
            _ => {
                let mut turns = Turns::<K>::new();
                let stacks = turns.stacks();
                let chunks = 0..rays.len().div_ceil(CHECK);
                let stream = stream(rays, (chunks, CHECK), || options.cancelled());
                let calls = (|i| i as u32, |i: &mut u32, h| push(*i, h), |_, _| {});
                accel.each_hit_own_stream::<K, u32, I>(stream, range, border, stacks, calls);
            }
        }
        if options.cancelled() {
            return Err(options.cancel_error());
        }
        if accel.has_placements() {
            for (i, ray) in rays.iter().enumerate() {
                if prepare(ray).is_some() {
                    let f = &mut |h| push(i as u32, h);
                    accel.each_hit_placed::<I>(ray, range, border, &mut stack, f);
                }
            }
        }
        full?;
        let all = by_ray(&counts, found, options)?;
        Ok((counts, all))
    }
}

/// The crossings `found` (each with its ray) one ray after the other, `counts[i]` of ray `i`,
/// each ray's sorted by `t` then ids.
fn by_ray<C: Control>(
    counts: &[u32],
    found: Vec<(u32, SlotHit)>,
    options: &C,
) -> Result<Vec<SlotHit>, C::Error> {
    let mut all = Vec::new();
    options.grow(&mut all, found.len(), "the intersections")?;
    all.extend(found.iter().map(|&(_, h)| h));
    let mut next: Vec<usize> = (counts.iter())
        .scan(0, |start, &n| {
            let here = *start;
            *start += n as usize;
            Some(here)
        })
        .collect();
    for (i, h) in found {
        all[next[i as usize]] = h;
        next[i as usize] += 1;
    }
    let mut start = 0;
    for &n in counts {
        let one = &mut all[start..start + n as usize];
        one.sort_by(|a: &SlotHit, b: &SlotHit| {
            a.crossing
                .t
                .total_cmp(&b.crossing.t)
                .then((a.geometry, a.primitive).cmp(&(b.geometry, b.primitive)))
        });
        start += n as usize;
    }
    Ok(all)
}

/// The closest hits of `rays` with `t` in `range` on `path`, written to `hits`: the own tree
/// by packets (neighbouring rays, so `rays` in the packets' order), then the placements.
pub(crate) fn closest_hits<C: Control>(
    path: SimdPath,
    (accel, options): (&WideLevels, &C),
    (rays, range): (&[[f32; 6]], (f32, f32)),
    hits: &mut [Option<SlotHit>],
) {
    let own = CastPackets {
        accel,
        range,
        options,
        rays,
        hits: &mut *hits,
    };
    dispatch(path, own);
    if accel.has_placements() {
        dispatch(
            path,
            ClosestPlaced {
                accel,
                range,
                options,
                rays,
                hits,
            },
        );
    }
}

/// [`Occlusions`] of `rays` on `path`: the own tree's kernel, then the placements'.
pub(crate) fn occlusions<C: Control>(
    path: SimdPath,
    (accel, options): (&WideLevels, &C),
    rays: &[[f32; 6]],
    range: (f32, f32),
    out: &mut [bool],
) {
    dispatch(
        path,
        Occlusions::<_, false> {
            accel,
            options,
            rays,
            range,
            out: &mut *out,
        },
    );
    if accel.has_placements() {
        dispatch(
            path,
            Occlusions::<_, true> {
                accel,
                options,
                rays,
                range,
                out,
            },
        );
    }
}

/// [`Counts`] of `rays` with `t` in `range` on `path`: the own tree's kernel, then the
/// placements'.
pub(crate) fn counts<C: Control>(
    path: SimdPath,
    (accel, options): (&WideLevels, &C),
    (border, range): (&Borders, (f32, f32)),
    rays: &[[f32; 6]],
    out: &mut [i32],
) {
    let own = Counts::<_, false> {
        accel,
        range,
        border,
        options,
        rays,
        out: &mut *out,
    };
    dispatch(path, own);
    if accel.has_placements() {
        dispatch(
            path,
            Counts::<_, true> {
                accel,
                range,
                border,
                options,
                rays,
                out,
            },
        );
    }
}
