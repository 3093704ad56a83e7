//! Packets: `N` neighbouring rays traced together through the wide tree, one lane each,
//! compiled per instruction set by `crate::simd` (32 lanes: four vectors of 8 with AVX2 and
//! the baseline, two of 16 with AVX-512). One walk serves two
//! queries ([`Hits`]): the closest hits of `cast_rays` (the pixels of a pinhole image come
//! in row order) and the crossing counts of parallel rays (`count_parallel`: occupancy's
//! votes, all along one direction, children in any order).
//!
//! A batch is cut into runs of `N` rays; a run goes as a packet when all its rays are valid
//! and share the watertight test's axis permutation (then every lane runs the same
//! operations), else one ray at a time; a run of closest hits whose bounds enter none of the
//! root's children is answered "no hit" before any lane is prepared (`cull::misses`). Each
//! wide node is fetched once per packet and its boxes tested for all lanes, each lane bounded
//! by its own closest hit so far. For closest hits, the children no lane can enter are first
//! culled by one interval test for the whole packet (`cull`); of the rest, only the leaves are
//! tested lane by lane, and an inner child keeps the lanes that reached its node.
//!
//! Exactness: per lane the box test is the single-ray test (conservative, so it only
//! prunes), the triangle test is `PreparedRay::hit` operation for operation (a lane whose
//! edge function rounds to zero goes to `hit` itself, for its `f64` re-test), and the rule for
//! the closest hit is the same total order (the smallest `t`, then the smallest geometry and
//! primitive id). So a lane's answer is the single-ray query's, whatever the order of the
//! visit. A count packet tests under the single-ray count's rule ([`EdgeRule::Owned`], with
//! the tree's border), and every leaf a lane's ray enters is visited once for it: the same
//! crossings, counted once each.
//!
//! A scene with cut-out triangles (ray casting from a world with cut-out materials) traces
//! every ray alone: the single-ray walk applies the alpha test. Placed meshes are asked after
//! the own tree, one ray at a time (`kernels::ClosestPlaced`, `kernels::Counts`).

use super::control::Control;
use super::cull::{bounds, furthest, misses, Bounds};
use super::levels::WideLevels;
use super::margins::EXIT_SCALE;
use super::node::WIDTH;
use super::rays::{lanes, Lanes};
use super::tree::{SlotHit, Stack, WideBvh};
use super::turns::{prepare, stream, Turns, INTERLEAVED};
use crate::accel::lanes::lane;
use crate::accel::prim::boundary::Boundary;
use crate::accel::prim::watertight::{hit_lane, Crossing, EdgeRule, T_LIMIT};
use crate::accel::prim::Corners;
use crate::simd::{Isa, Kernel};

/// The closest hit of a ray.
pub(crate) type ClosestHit = Option<SlotHit>;

/// Rays per packet of closest hits (four vectors of 8 lanes, or two of 16 with AVX-512): 8 × 4
/// rays of an image in tile order. With the whole packet's culling (`walk`), 4 × 4 tiles beat
/// 4 × 2, and 8 × 4 then beat 4 × 4 with AVX2 (measured: docs/benchmarks.md, «Design
/// measurements», `PACKET`).
const PACKET: usize = 32;

/// The closest hit in the own tree of [`WideLevels`] with `t` in `[0, ∞]` for every ray of
/// `rays` (`None`: a ray that hits nothing), written to `hits`, as a [`Kernel`] (the
/// placements are asked after, by `kernels::ClosestPlaced`).
pub(crate) struct CastPackets<'a, C> {
    pub accel: &'a WideLevels,
    /// Hits with `t` in this range count: packets for `[0, ∞]`, single rays otherwise.
    pub range: (f32, f32),
    /// Checked before each packet: a cancelled query stops there.
    pub options: &'a C,
    /// `[ox, oy, oz, dx, dy, dz]`, in the packets' order.
    pub rays: &'a [[f32; 6]],
    pub hits: &'a mut [ClosestHit],
}

impl<C: Control> Kernel for CastPackets<'_, C> {
    type Output = ();

    #[inline(always)]
    fn run<const N: usize, I: Isa>(self) {
        let CastPackets {
            accel: levels,
            range,
            options,
            rays,
            hits,
        } = self;
        let (accel, alpha) = (levels.own(), levels.own_alpha());
        assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
        let mut stack = Stack::default();
        let interleave = accel.interleaves();
        let mut packet_stack = Vec::new();
        // On a tree larger than the caches, the packets' rays left to single rays go after,
        // as one stream of walks in turn.
        let mut streamed = Vec::new();
        let all = (rays.chunks(PACKET).zip(hits.chunks_mut(PACKET))).enumerate();
        for (c, (rays, hits)) in all {
            if options.cancelled() {
                return;
            }
            // Cut-out triangles are tested one ray at a time, by the filtered single-ray walk,
            // and so are rays with other bounds than `[0, ∞]`.
            let packets = alpha.is_none() && range == (0.0, f32::INFINITY);
            let wide = &mut packet_stack;
            if packets && misses::<PACKET, I>(accel, rays) {
                hits.fill(None);
                continue;
            }
            let traced = packets
                && lanes::<PACKET>(rays)
                    .map(|l| trace::<PACKET, I>(accel, &l, wide, hits))
                    .is_some();
            if !traced && interleave {
                streamed.push(c);
            } else if !traced {
                for (ray, hit) in rays.iter().zip(hits) {
                    let ray = prepare(ray);
                    *hit = ray.and_then(|r| accel.closest::<I>(&r, range, alpha, &mut stack));
                }
            }
        }
        if streamed.is_empty() {
            return;
        }
        let mut turns = Turns::<INTERLEAVED>::new();
        let stacks = turns.stacks();
        let stream = stream(rays, (streamed.iter().copied(), PACKET), || {
            options.cancelled()
        });
        let done = |i, hit| hits[i] = hit;
        accel.closest_stream::<INTERLEAVED, I>(stream, range, alpha, stacks, done);
    }
}

/// Counts the crossings of `rays` with `t` in `range` as one packet, as
/// `WideBvh::each_hit` counts them (`border`: the tree's), into `out`, when the rays are `N`
/// valid rays with one direction (an occupancy vote's rays: parallel lines, neighbours when
/// their origins are sorted across them); false, and `out` untouched, otherwise. The caller
/// tests cut-out triangles alone.
#[inline(always)]
pub(crate) fn count_parallel<const N: usize, I: Isa, C: Control>(
    accel: &WideBvh,
    rays: &[[f32; 6]],
    (range, border): ((f32, f32), &[Boundary]),
    options: &C,
    stack: &mut Vec<(u32, u32, u32)>,
    out: &mut [i32],
) -> bool {
    let direction = |r: &[f32; 6]| [r[3], r[4], r[5]].map(f32::to_bits);
    if rays.len() != N || rays.iter().any(|r| direction(r) != direction(&rays[0])) {
        return false;
    }
    let Some(lanes) = lanes::<N>(rays) else {
        return false;
    };
    let mut tally = Tally {
        t_min: range.0,
        t_max: [range.1; N],
        border,
        options,
        count: [0; N],
    };
    // Origins spread along the rays make the packet's bounds as large as the tree's box:
    // no culling for the whole packet.
    walk::<N, I, _>(accel, &lanes, None, stack, &mut tally);
    out.copy_from_slice(&tally.count);
    true
}

/// What a packet walk does with its lanes' hits: keeps each lane's closest ([`Best`]) or
/// counts every crossing ([`Tally`]). One walk and one triangle test serve both.
trait Hits<const N: usize> {
    /// Whether children are visited nearest first (for the first lane).
    const SORTED: bool;
    /// Hits with `t` in `[t_min, t_max[i]]` count for lane `i`.
    fn t_min(&self) -> f32;
    fn t_max(&self) -> &[f32; N];
    /// The rule for rays on an edge or vertex, and the border [`EdgeRule::Owned`] needs.
    fn rule(&self) -> (EdgeRule, &[Boundary]);
    /// Takes lane `i`'s hit `c` of leaf slot `slot`.
    fn keep(&mut self, accel: &WideBvh, i: usize, c: Crossing, slot: u32);
    /// Whether the walk stops before its next leaf, unfinished (a cancelled query).
    fn stopped(&self) -> bool {
        false
    }
}

/// The closest hits so far, by lane: `slot` is the leaf slot (valid where `hit`).
struct Best<const N: usize> {
    t: [f32; N],
    b1: [f32; N],
    b2: [f32; N],
    slot: [u32; N],
    hit: u32,
}

/// Every crossing with `t` in `range`, counted by lane, one per crossing of the surface
/// ([`EdgeRule::Owned`] with the tree's border): `WideBvh::each_hit`'s count. The walk stops
/// once `options` is cancelled: 32 rays through a dense region can take longer than a Ctrl-C
/// should wait (measured: docs/benchmarks.md, «Design measurements», `Tally`).
struct Tally<'a, const N: usize, C> {
    t_min: f32,
    t_max: [f32; N],
    border: &'a [Boundary],
    options: &'a C,
    count: [i32; N],
}

/// Traces the packet and writes each lane's closest hit to `hits`.
#[inline(always)]
fn trace<const N: usize, I: Isa>(
    accel: &WideBvh,
    lanes: &Lanes<N>,
    stack: &mut Vec<(u32, u32, u32)>,
    hits: &mut [ClosestHit],
) {
    let mut best = Best {
        t: [T_LIMIT; N],
        b1: [0.0; N],
        b2: [0.0; N],
        slot: [0; N],
        hit: 0,
    };
    let bounds = bounds(&lanes.origin, &lanes.inv_dir);
    walk::<N, I, _>(accel, lanes, bounds.as_ref(), stack, &mut best);
    for (i, hit) in hits.iter_mut().enumerate() {
        *hit = (best.hit >> i & 1 == 1).then(|| {
            let crossing = Crossing {
                t: best.t[i],
                b1: best.b1[i],
                b2: best.b2[i],
            };
            accel.slot_hit(best.slot[i] as usize, crossing)
        });
    }
}

/// The packet walk: visits the leaves each lane's ray enters (the lanes that enter a node
/// go on with it), and gives every hit of a lane to `hits`. With the packet's `bounds`, a
/// node's children are first culled for the whole packet, one test for all lanes.
#[inline(always)]
fn walk<const N: usize, I: Isa, H: Hits<N>>(
    accel: &WideBvh,
    lanes: &Lanes<N>,
    bounds: Option<&Bounds>,
    stack: &mut Vec<(u32, u32, u32)>,
    hits: &mut H,
) {
    let all = if N == 32 { u32::MAX } else { (1 << N) - 1 };
    stack.clear();
    if !accel.wide().is_empty() {
        stack.push((0, 0, all));
    }
    while let Some((index, count, mask)) = stack.pop() {
        if count == 0 {
            let node = &accel.wide()[index as usize];
            // The children some lane may enter, culled for the whole packet first.
            let mut maybe = match bounds {
                Some((o, inv)) => {
                    let t_max = furthest(hits.t_max(), mask);
                    node.enter_interval::<I>(o, inv, hits.t_min(), t_max, EXIT_SCALE)
                }
                None => node.used_mask(),
            };
            // Children the packet enters, the nearest to its first lane on top. With the
            // packet's bounds, an inner child the interval test let through keeps all the
            // lanes (the lanes are tested at the leaves: 2.2-2.5 % fewer instructions for an
            // image, bunny and Spot), and "nearest" is by the child's centre along the first
            // lane's ray; without, by the first lane's entry distance.
            let first = mask.trailing_zeros() as usize;
            let mut kids = [(0u32, 0u32, 0u32, 0.0f32); WIDTH];
            let mut n = 0;
            while maybe != 0 {
                let c = maybe.trailing_zeros() as usize;
                maybe &= maybe - 1;
                let (child, child_count) = node.child(c);
                let b = node.bounds(c);
                let (m, near) = match bounds {
                    Some(_) if child_count == 0 => (mask, ahead(b, lanes, first)),
                    Some(_) => {
                        let (m, _) = slab::<N, I>(b, lanes, hits.t_min(), hits.t_max());
                        (m & mask, ahead(b, lanes, first))
                    }
                    None => {
                        let (m, near) = slab::<N, I>(b, lanes, hits.t_min(), hits.t_max());
                        (m & mask, near[first])
                    }
                };
                if m != 0 {
                    kids[n] = (child, child_count, m, near);
                    n += 1;
                }
            }
            let kids = &mut kids[..n];
            if H::SORTED {
                kids.sort_unstable_by(|a, b| b.3.total_cmp(&a.3));
            }
            for &(i, c, m, _) in kids.iter() {
                accel.prefetch_child(i, c);
                stack.push((i, c, m));
            }
            continue;
        }
        if hits.stopped() {
            return;
        }
        // With half the lanes or fewer, lane by lane: it pays most where a triangle is about
        // one pixel (the 1M-triangle blob's image), and on the bunny too, where always lane by
        // lane was slower (measured: docs/benchmarks.md, «Design measurements», leaves lane
        // by lane).
        if mask.count_ones() as usize <= N / 2 {
            leaf_by_lane::<N, I>(accel, lanes, (index, count), mask, hits);
            continue;
        }
        for (group, valid) in accel.leaf(index, count) {
            let mut tris = valid;
            while tris != 0 {
                let lane = tris.trailing_zeros() as usize;
                tris &= tris - 1;
                let corners = group.corners(lane);
                let slot = group.first + lane as u32;
                triangle::<N, I>(accel, lanes, &corners, slot, mask, hits);
            }
        }
    }
}

/// Twice the dot product of lane `i`'s direction and the offset of the centre of the box
/// `(lo, hi)` from its origin: boxes ordered along the lane's ray.
#[inline(always)]
fn ahead<const N: usize>((lo, hi): ([f32; 3], [f32; 3]), lanes: &Lanes<N>, i: usize) -> f32 {
    let (o, inv) = (&lanes.origin, &lanes.inv_dir);
    (0..3)
        .map(|a| (lo[a] + hi[a] - 2.0 * o[a][i]) / inv[a][i])
        .sum()
}

/// The lanes (bit `i` for lane `i`) whose ray enters the box `(lo, hi)` with `t` in
/// `[t_min, tie_bound(t_max[i])]` (`lanes::slab` widens it), and each lane's entry distance:
/// the conservative test of `node`, per lane ([`crate::accel::lanes::slab`]).
#[inline(always)]
fn slab<const N: usize, I: Isa>(
    (lo, hi): ([f32; 3], [f32; 3]),
    lanes: &Lanes<N>,
    t_min: f32,
    t_max: &[f32; N],
) -> (u32, [f32; N]) {
    let o = &lanes.origin;
    let rel = |a: usize, i: usize| (lo[a] - o[a][i], hi[a] - o[a][i]);
    crate::accel::lanes::slab::<N, I>(rel, &lanes.inv_dir, t_min, t_max, EXIT_SCALE)
}

/// Tests the triangle `corners` (leaf slot `slot`) on the lanes of `mask` and gives the
/// hits to `hits`: per lane, [`PreparedRay::hit`]'s answer under `hits`' rule and bounds.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn triangle<const N: usize, I: Isa>(
    accel: &WideBvh,
    lanes: &Lanes<N>,
    corners: &Corners,
    slot: u32,
    mask: u32,
    hits: &mut impl Hits<N>,
) {
    let [kx, ky, kz] = lanes.k;
    let v = corners.map(|c| [c[kx], c[ky], c[kz]]);
    let (mut hit, mut zero) = ([0i32; N], [0i32; N]);
    let (mut t, mut b1, mut b2) = ([0.0f32; N], [0.0f32; N], [0.0f32; N]);
    let (t_min, t_max) = (hits.t_min(), hits.t_max());
    for i in 0..N {
        let shear = (lanes.shear[0][i], lanes.shear[1][i]);
        let (exact, inside, ti, b1i, b2i) =
            hit_lane(v, lane(&lanes.permuted, i), shear, lanes.inv_dz[i]);
        hit[i] = -i32::from(inside & (ti >= t_min) & (ti <= t_max[i].min(T_LIMIT)));
        zero[i] = -i32::from(exact);
        (t[i], b1[i], b2[i]) = (ti, b1i, b2i);
    }
    let exact = I::mask(&zero) & mask;
    let mut found = I::mask(&hit) & mask & !exact;
    // Lanes on an edge function's zero: the one-triangle test itself.
    let (rule, border) = hits.rule();
    let boundary = border.get(slot as usize).copied().unwrap_or_default();
    let mut rest = exact;
    while rest != 0 {
        let i = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        let ray = lanes.ray(i);
        let tri = accel.slot(slot as usize);
        if let Some(c) = ray.hit(tri, boundary, t_min, t_max[i], rule) {
            (t[i], b1[i], b2[i]) = (c.t, c.b1, c.b2);
            found |= 1 << i;
        }
    }
    while found != 0 {
        let i = found.trailing_zeros() as usize;
        found &= found - 1;
        let c = Crossing {
            t: t[i],
            b1: b1[i],
            b2: b2[i],
        };
        hits.keep(accel, i, c, slot);
    }
}

impl<const N: usize> Hits<N> for Best<N> {
    const SORTED: bool = true;

    #[inline(always)]
    fn t_min(&self) -> f32 {
        0.0
    }

    #[inline(always)]
    fn t_max(&self) -> &[f32; N] {
        &self.t
    }

    #[inline(always)]
    fn rule(&self) -> (EdgeRule, &[Boundary]) {
        (EdgeRule::Inclusive, &[])
    }

    /// Keeps the hit `c` of leaf slot `slot` as lane `i`'s best when it is closer; ids decide
    /// exact ties.
    #[inline(always)]
    fn keep(&mut self, accel: &WideBvh, i: usize, c: Crossing, slot: u32) {
        let closer = self.hit >> i & 1 == 0
            || c.t < self.t[i]
            || (c.t == self.t[i] && accel.key(slot as usize) < accel.key(self.slot[i] as usize));
        if closer {
            self.t[i] = c.t;
            self.b1[i] = c.b1;
            self.b2[i] = c.b2;
            self.slot[i] = slot;
            self.hit |= 1 << i;
        }
    }
}

impl<const N: usize, C: Control> Hits<N> for Tally<'_, N, C> {
    const SORTED: bool = false;

    #[inline(always)]
    fn t_min(&self) -> f32 {
        self.t_min
    }

    #[inline(always)]
    fn t_max(&self) -> &[f32; N] {
        &self.t_max
    }

    #[inline(always)]
    fn rule(&self) -> (EdgeRule, &[Boundary]) {
        (EdgeRule::Owned, self.border)
    }

    #[inline(always)]
    fn keep(&mut self, _: &WideBvh, i: usize, _: Crossing, _: u32) {
        self.count[i] = self.count[i].saturating_add(1);
    }

    #[inline(always)]
    fn stopped(&self) -> bool {
        self.options.cancelled()
    }
}

/// Tests the leaf `(index, count)` on the lanes of `mask` one lane at a time, each lane's ray
/// against all the leaf's triangles at once (the single-ray group test), and gives the hits
/// to `hits`: where few lanes reach a leaf (small triangles), cheaper than testing its
/// triangles one by one on every lane.
#[inline(always)]
fn leaf_by_lane<const N: usize, I: Isa>(
    accel: &WideBvh,
    lanes: &Lanes<N>,
    (index, count): (u32, u32),
    mask: u32,
    hits: &mut impl Hits<N>,
) {
    let mut rest = mask;
    while rest != 0 {
        let i = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        let ray = lanes.ray(i);
        for (group, valid) in accel.leaf(index, count) {
            let (rule, border) = hits.rule();
            let (t_min, t_max) = (hits.t_min(), hits.t_max()[i]);
            let found = ray.hit_group::<I>(group, valid, accel.tris(), border, t_min, t_max, rule);
            let mut lanes_hit = found.mask;
            while lanes_hit != 0 {
                let lane = lanes_hit.trailing_zeros() as usize;
                lanes_hit &= lanes_hit - 1;
                hits.keep(accel, i, found.crossing(lane), group.first + lane as u32);
            }
        }
    }
}
