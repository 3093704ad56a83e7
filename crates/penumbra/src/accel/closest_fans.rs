//! Closest-hit packets: rays that share their origin (the camera rays of a few neighbouring
//! pixels, seen from a pinhole) traced together through the BVH, `N` lanes at a time.
//!
//! Each node is fetched once per packet and its slab test runs for all lanes, each lane bounded
//! by its own closest hit so far. Leaves test every triangle for all lanes.
//!
//! Exactness: a lane's answer is the one [`Bvh::intersect`] gives for that ray, whatever the
//! order in which the packet visits nodes, because both follow one rule for what "closest"
//! means: the smallest `t`, and among triangles at exactly that `t` the one with the smallest
//! index in the scene (as the brute-force reference finds it). Every lane runs the scalar
//! Möller–Trumbore test operation for operation (see `prim::moller_trumbore`), and the box
//! tests only prune, conservatively.

use glam::Vec3;

use super::lanes::lane;
use super::prim::moller_trumbore::{origin_terms, solve};
use super::shadow_fans::slab;
use super::{Bvh, STACK_SIZE};
use crate::geometry::Hit;
use crate::simd::{Isa, Kernel};

/// [`Bvh::intersect_from`] as a [`Kernel`]: the rays in packets of `N` lanes.
pub(super) struct Closest<'a> {
    pub(super) bvh: &'a Bvh,
    pub(super) origin: Vec3,
    pub(super) dirs: &'a [Vec3],
    pub(super) t_min: f32,
    pub(super) t_max: f32,
    pub(super) hits: &'a mut [Option<Hit>],
}

impl Kernel for Closest<'_> {
    type Output = ();

    #[inline(always)]
    fn run<const N: usize, I: Isa>(self) {
        let Closest {
            bvh,
            origin,
            dirs,
            t_min,
            t_max,
            hits,
        } = self;
        assert_eq!(dirs.len(), hits.len(), "one hit slot per ray");
        for (dirs, hits) in dirs.chunks(N).zip(hits.chunks_mut(N)) {
            closest_packet::<N, I>(bvh, origin, dirs, t_min, t_max, hits);
        }
    }
}

/// The closest hits so far, one per lane. `id` is the scene index of the triangle plus one,
/// and 0 while the lane has no hit, so that no tie is taken at the exclusive `t_max`.
struct Best<const N: usize> {
    t: [f32; N],
    id: [u32; N],
    b1: [f32; N],
    b2: [f32; N],
}

/// Writes to `hits[i]` the closest hit of the ray `origin + t·dirs[i]` with `t` in
/// `(t_min, t_max)` (`dirs.len() <= N`).
#[inline(always)]
fn closest_packet<const N: usize, I: Isa>(
    bvh: &Bvh,
    origin: Vec3,
    dirs: &[Vec3],
    t_min: f32,
    t_max: f32,
    hits: &mut [Option<Hit>],
) {
    debug_assert!(N <= 32 && dirs.len() <= N && dirs.len() == hits.len());
    let count = dirs.len();
    hits.fill(None);
    if count == 0 || bvh.nodes.is_empty() {
        return;
    }
    // Lanes past `count` repeat the last ray and stay out of every mask.
    let mut dir = [[0.0f32; N]; 3];
    for i in 0..N {
        let d = dirs[i.min(count - 1)];
        for a in 0..3 {
            dir[a][i] = d[a];
        }
    }
    let mut inv = [[0.0f32; N]; 3];
    for a in 0..3 {
        for i in 0..N {
            inv[a][i] = 1.0 / dir[a][i];
        }
    }
    let lanes: u32 = if count == 32 {
        u32::MAX
    } else {
        (1 << count) - 1
    };
    let o = origin.to_array();
    let mut best = Best {
        t: [t_max; N],
        id: [0; N],
        b1: [0.0; N],
        b2: [0.0; N],
    };

    let mut stack = [(0u32, 0u32); STACK_SIZE];
    let mut sp = 0;
    let mut node = &bvh.nodes[0];
    let mut mask = slab::<N, I>(node, &o, &inv, t_min, &best.t).0 & lanes;
    if mask == 0 {
        return;
    }
    loop {
        if node.is_leaf() {
            let first = node.first as usize;
            let range = first..first + node.count as usize;
            for (tri, &id) in bvh.tris[range.clone()].iter().zip(&bvh.prim_ids[range]) {
                triangle(tri, id, origin, &dir, t_min, &mut best);
            }
        } else {
            let (l, r) = (
                &bvh.nodes[node.first as usize],
                &bvh.nodes[node.first as usize + 1],
            );
            let (ml, nl) = slab::<N, I>(l, &o, &inv, t_min, &best.t);
            let (mr, nr) = slab::<N, I>(r, &o, &inv, t_min, &best.t);
            let (ml, mr) = (ml & mask, mr & mask);
            if ml != 0 && mr != 0 {
                let lane = mask.trailing_zeros() as usize;
                let (near, far, near_mask, far_mask) = if nl[lane] <= nr[lane] {
                    (l, node.first + 1, ml, mr)
                } else {
                    (r, node.first, mr, ml)
                };
                stack[sp] = (far, far_mask);
                sp += 1;
                node = near;
                mask = near_mask;
                continue;
            } else if ml != 0 {
                node = l;
                mask = ml;
                continue;
            } else if mr != 0 {
                node = r;
                mask = mr;
                continue;
            }
        }
        // The next waiting subtree that a lane can still find a closer hit in.
        loop {
            if sp == 0 {
                for (i, hit) in hits.iter_mut().enumerate() {
                    if best.id[i] != 0 {
                        *hit = Some(Hit {
                            t: best.t[i],
                            b1: best.b1[i],
                            b2: best.b2[i],
                            triangle: best.id[i] - 1,
                            instance: None,
                        });
                    }
                }
                return;
            }
            sp -= 1;
            let (index, entered) = stack[sp];
            let candidate = &bvh.nodes[index as usize];
            let m = slab::<N, I>(candidate, &o, &inv, t_min, &best.t).0 & entered;
            if m != 0 {
                node = candidate;
                mask = m;
                break;
            }
        }
    }
}

/// Tests the triangle (scene index `id`) on every lane and keeps it where it is closer than
/// the lane's best hit, or as close with a smaller index.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn triangle<const N: usize>(
    tri: &super::TriAccel,
    id: u32,
    origin: Vec3,
    dir: &[[f32; N]; 3],
    t_min: f32,
    best: &mut Best<N>,
) {
    let (e1, e2) = (tri.e1.to_array(), tri.e2.to_array());
    let terms = origin_terms(origin.to_array(), tri.v0.to_array(), e1, e2);
    let key = id + 1;
    for i in 0..N {
        let (inside, t, b1, b2) = solve(terms, lane(dir, i), e1, e2);
        let closer = (t < best.t[i]) | ((t == best.t[i]) & (key < best.id[i]));
        let take = inside & (t > t_min) & closer;
        best.t[i] = if take { t } else { best.t[i] };
        best.id[i] = if take { key } else { best.id[i] };
        best.b1[i] = if take { b1 } else { best.b1[i] };
        best.b2[i] = if take { b2 } else { best.b2[i] };
    }
}
