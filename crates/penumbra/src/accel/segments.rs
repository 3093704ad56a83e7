//! Shadow-ray packets whose lanes have origins of their own: the segments from neighbouring
//! shading points (the samples of a few adjacent pixels) to one light sample, traced together
//! through the BVH, `N` lanes at a time.
//!
//! This is the other way to find coherence among shadow rays (Embree's renderers bundle
//! them so): where [`super::shadow_fans`] fan out from one shading point toward the N×N samples
//! of a light, these rays start a pixel apart and meet at a light point, so the finer the
//! image, the closer they run. On deep trees (fine meshes) the bundles visit far fewer nodes
//! than the fans, whose rays spread over the light's whole extent.
//!
//! Exactness: every lane runs the Möller–Trumbore test of `prim::moller_trumbore`, the scalar
//! test's own functions, operation for operation, its own `tvec`, `qvec` and `t` numerator
//! included, on the triangles of the leaves its own segment enters (the walk of
//! [`super::shadow_fans`]), so a lane is occluded exactly when [`Bvh::occluded`] says so; as
//! is a segment of a batch with a shaft (see [`super::shaft`]).

use std::marker::PhantomData;

use glam::Vec3;

use super::lanes::{self, lane};
use super::prim::moller_trumbore::{origin_terms, solve};
use super::shadow_fans::{walk_from, ShadowLanes};
use super::shaft::{self, Roots, Shaft};
use super::{traverse, Bvh, BvhNode, TriAccel};
use crate::math::Ray;
use crate::simd::{Isa, Kernel};

/// Segments by coordinate: segment `i` runs from `(origin[0][i], origin[1][i], origin[2][i])`
/// to `(end[0][i], end[1][i], end[2][i])`. All six slices have the same length.
#[derive(Clone, Copy, Debug)]
pub struct Segments<'a> {
    /// The starting points' coordinates, by axis.
    pub origin: [&'a [f32]; 3],
    /// The end points' coordinates, by axis.
    pub end: [&'a [f32]; 3],
}

impl<'a> Segments<'a> {
    /// The number of segments.
    pub fn len(&self) -> usize {
        self.origin[0].len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Segment `i`'s origin and end.
    fn get(&self, i: usize) -> (Vec3, Vec3) {
        let point = |c: &[&[f32]; 3]| Vec3::new(c[0][i], c[1][i], c[2][i]);
        (point(&self.origin), point(&self.end))
    }

    /// Segments `start .. start + len`.
    fn range(&self, start: usize, len: usize) -> Segments<'a> {
        let cut = |c: [&'a [f32]; 3]| c.map(|axis| &axis[start..start + len]);
        Segments {
            origin: cut(self.origin),
            end: cut(self.end),
        }
    }
}

/// Every segment between a few origins and some ends, by coordinate: segment `(j, i)` runs
/// from origin `i` to end `j`. The three origin slices have the same length, as do the three
/// end slices.
///
/// The segments from a few neighbouring shading points to each of the fixed samples of a
/// light are such a set: they need the points and the samples once each, not once per
/// segment.
#[derive(Clone, Copy, Debug)]
pub struct Pairs<'a> {
    /// The starting points' coordinates, by axis.
    pub origins: [&'a [f32]; 3],
    /// The end points' coordinates, by axis.
    pub ends: [&'a [f32]; 3],
}

/// [`Bvh::occlude_segments`] as a [`Kernel`]: consecutive segments in packets of `N` lanes.
pub(super) struct OccludeSegments<'a> {
    pub(super) bvh: &'a Bvh,
    pub(super) segments: Segments<'a>,
    pub(super) t_max: f32,
    pub(super) blocked: &'a mut [bool],
}

impl Kernel for OccludeSegments<'_> {
    type Output = ();

    #[inline(always)]
    fn run<const N: usize, I: Isa>(self) {
        let OccludeSegments {
            bvh,
            segments,
            t_max,
            blocked,
        } = self;
        let n = segments.len();
        assert!(
            segments
                .origin
                .iter()
                .chain(&segments.end)
                .all(|c| c.len() == n)
                && blocked.len() == n,
            "one origin, end and mask slot per segment"
        );
        if bvh.nodes.is_empty() {
            return;
        }
        let mut bundle = Bundle::<N, I>::new(t_max);
        for (chunk, blocked) in blocked.chunks_mut(N).enumerate() {
            let segments = segments.range(chunk * N, blocked.len());
            occlude_lanes(
                bvh,
                &[0],
                &mut bundle,
                blocked,
                |i| segments.get(i),
                |rays| rays.set(segments.origin, |a, i| segments.end[a][i]),
            );
        }
    }
}

/// [`Bvh::occlude_pairs`] as a [`Kernel`]: for each end, the segments from consecutive
/// origins in packets of `N` lanes.
pub(super) struct OccludePairs<'a> {
    pub(super) bvh: &'a Bvh,
    pub(super) pairs: Pairs<'a>,
    pub(super) t_max: f32,
    pub(super) blocked: &'a mut [bool],
}

impl Kernel for OccludePairs<'_> {
    type Output = ();

    #[inline(always)]
    fn run<const N: usize, I: Isa>(self) {
        let OccludePairs {
            bvh,
            pairs: Pairs { origins, ends },
            t_max,
            blocked,
        } = self;
        let (m, n) = (origins[0].len(), ends[0].len());
        assert!(
            origins.iter().all(|c| c.len() == m)
                && ends.iter().all(|c| c.len() == n)
                && blocked.len() == m * n,
            "one mask slot per origin and end"
        );
        if bvh.nodes.is_empty() || m == 0 || n == 0 {
            return;
        }
        let shaft = (n >= shaft::ROOTS_MIN_ENDS).then(|| Shaft::new(bvh, origins, ends));
        let gathered = match &shaft {
            Some(shaft) if n >= shaft::MIN_ENDS => shaft.gather(bvh),
            _ => None,
        };
        match gathered {
            Some(candidates) if candidates.as_slice().is_empty() => return,
            Some(candidates) => {
                let pairs = Pairs { origins, ends };
                shaft::occlude_pairs::<N, I>(bvh, candidates.as_slice(), pairs, t_max, blocked);
                return;
            }
            None => {}
        }
        let roots = shaft.map_or_else(Roots::whole, |shaft| shaft.roots(bvh));
        let roots = roots.as_slice();
        if roots.is_empty() {
            return;
        }
        let mut bundle = Bundle::<N, I>::new(t_max);
        for (j, row) in blocked.chunks_mut(m).enumerate() {
            let end = [ends[0][j], ends[1][j], ends[2][j]];
            for (chunk, blocked) in row.chunks_mut(N).enumerate() {
                let lanes = chunk * N..chunk * N + blocked.len();
                let origin = origins.map(|axis| &axis[lanes.clone()]);
                let point = |i: usize| Vec3::new(origin[0][i], origin[1][i], origin[2][i]);
                occlude_lanes(
                    bvh,
                    roots,
                    &mut bundle,
                    blocked,
                    |i| (point(i), end.into()),
                    |rays| rays.set(origin, |a, _| end[a]),
                );
            }
        }
    }
}

/// Traces the segments of one packet (at most `N`, `blocked` one slot each) whose origin and
/// end `segment(i)` gives, and whose lanes `fill` writes into `bundle`'s (in place: a packet's
/// lanes are a few hundred bytes, and copies of them were a visible share of the seed room's
/// shadow rays; measured: docs/benchmarks.md, «Design measurements», `occlude_lanes`).
/// A packet with a quarter of its lanes or fewer to trace goes one ray at a time.
#[inline(always)]
fn occlude_lanes<const N: usize, I: Isa>(
    bvh: &Bvh,
    roots: &[u32],
    bundle: &mut Bundle<N, I>,
    blocked: &mut [bool],
    segment: impl Fn(usize) -> (Vec3, Vec3),
    fill: impl FnOnce(&mut Lanes<N>),
) {
    let t_max = bundle.t_max;
    let live = blocked.iter().filter(|&&b| !b).count();
    if live == 0 {
        return;
    }
    if live * 4 <= N {
        for (i, b) in blocked.iter_mut().enumerate() {
            if !*b {
                let (o, end) = segment(i);
                *b = traverse::occluded(bvh, &Ray::new(o, end - o), 0.0, t_max);
            }
        }
    } else {
        fill(&mut bundle.rays);
        occlude_packet(bvh, roots, bundle, blocked);
    }
}

/// A packet's rays by lane: origins, directions and inverse directions by axis.
struct Lanes<const N: usize> {
    origin: [[f32; N]; 3],
    dir: [[f32; N]; 3],
    inv: [[f32; N]; 3],
}

impl<const N: usize> Lanes<N> {
    /// Sets the lanes to the segments from `origin` (at most `N` of them, by axis) to the
    /// points whose coordinate along axis `a` is `end(a, i)`. Lanes past the segments repeat
    /// the last one. Each direction is `end − origin`.
    #[inline(always)]
    fn set(&mut self, origin: [&[f32]; 3], end: impl Fn(usize, usize) -> f32) {
        let count = origin[0].len();
        debug_assert!(N <= 32 && count > 0 && count <= N);
        let last = count - 1;
        for (a, &from) in origin.iter().enumerate() {
            let axis = (&mut self.origin[a], &mut self.dir[a], &mut self.inv[a]);
            // A full packet reads fixed-size arrays, so that the loop needs no bounds checks.
            match <&[f32; N]>::try_from(from) {
                Ok(full) => set_axis(axis, |i| full[i], |i| end(a, i)),
                Err(_) => set_axis(axis, |i| from[i.min(last)], |i| end(a, i.min(last))),
            }
        }
    }
}

/// One axis of [`Lanes::set`]: lane `i` starts at `origin(i)` and ends at `end(i)`. The lanes
/// are computed in registers and stored once, never read back from the stores: reading the
/// origins back right after copying them in slowed the seed room's render (measured:
/// docs/benchmarks.md, «Design measurements», `set_axis`).
// Lane loops index several arrays by lane; that is what vectorizes.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn set_axis<const N: usize>(
    (origins, dirs, invs): (&mut [f32; N], &mut [f32; N], &mut [f32; N]),
    origin: impl Fn(usize) -> f32,
    end: impl Fn(usize) -> f32,
) {
    let (mut o, mut d, mut inv) = ([0.0; N], [0.0; N], [0.0; N]);
    for i in 0..N {
        o[i] = origin(i);
        d[i] = end(i) - o[i];
        inv[i] = 1.0 / d[i];
    }
    (*origins, *dirs, *invs) = (o, d, inv);
}

/// Marks `blocked[i]` for each lane `i` of `bundle` (`blocked` has one slot per segment, at
/// most `N`) that is not blocked yet and that a triangle meets for `t` in `(0, t_max)`.
#[inline(always)]
fn occlude_packet<const N: usize, I: Isa>(
    bvh: &Bvh,
    roots: &[u32],
    bundle: &Bundle<N, I>,
    blocked: &mut [bool],
) {
    let mut active: u32 = 0;
    for (i, &b) in blocked.iter().enumerate() {
        active |= u32::from(!b) << i;
    }
    for &root in roots {
        active = walk_from::<N, false>(bvh, bundle, active, root);
        if active == 0 {
            break;
        }
    }
    for (i, b) in blocked.iter_mut().enumerate() {
        *b |= active & (1 << i) == 0;
    }
}

/// A bundle's lanes for the any-hit walk.
struct Bundle<const N: usize, I> {
    rays: Lanes<N>,
    far: [f32; N],
    t_max: f32,
    isa: PhantomData<I>,
}

impl<const N: usize, I> Bundle<N, I> {
    /// A bundle of segments traced for `t` in `(0, t_max)`, its lanes to be set.
    fn new(t_max: f32) -> Self {
        Bundle {
            rays: Lanes {
                origin: [[0.0; N]; 3],
                dir: [[0.0; N]; 3],
                inv: [[0.0; N]; 3],
            },
            far: [t_max; N],
            t_max,
            isa: PhantomData,
        }
    }
}

impl<const N: usize, I: Isa> ShadowLanes<N> for Bundle<N, I> {
    #[inline(always)]
    fn enter(&self, node: &BvhNode) -> (u32, [f32; N]) {
        slab::<N, I>(node, &self.rays, &self.far)
    }

    #[inline(always)]
    fn blocks(&self, tri: &TriAccel, lanes: u32) -> u32 {
        triangle::<N, I>(tri, &self.rays, self.t_max, lanes)
    }
}

/// The lanes (bit i for lane i) that enter the node's box within `(0, t_max[i])`, and each
/// lane's entry distance ([`lanes::slab`], each lane from its own origin).
#[inline(always)]
fn slab<const N: usize, I: Isa>(
    node: &BvhNode,
    rays: &Lanes<N>,
    t_max: &[f32; N],
) -> (u32, [f32; N]) {
    let o = &rays.origin;
    let rel = |a: usize, i: usize| (node.min[a] - o[a][i], node.max[a] - o[a][i]);
    lanes::slab::<N, I>(rel, &rays.inv, 0.0, t_max, 1.0)
}

/// The lanes of `lanes` (bit i for lane i) that hit the triangle with `t` in `(0, t_max)`:
/// per lane, the whole Möller–Trumbore test from the lane's origin and direction.
// Lane loops index several arrays by lane; that is what vectorizes.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn triangle<const N: usize, I: Isa>(
    tri: &TriAccel,
    rays: &Lanes<N>,
    t_max: f32,
    lanes: u32,
) -> u32 {
    let (v0, e1, e2) = (tri.v0.to_array(), tri.e1.to_array(), tri.e2.to_array());
    let mut hit = [0i32; N];
    for i in 0..N {
        let terms = origin_terms(lane(&rays.origin, i), v0, e1, e2);
        let (inside, t, _, _) = solve(terms, lane(&rays.dir, i), e1, e2);
        hit[i] = -((inside & (t > 0.0) & (t < t_max)) as i32);
    }
    I::mask(&hit) & lanes
}
