//! Single-ray queries on a built [`Bvh`]: the slab test, and the two walks every single-ray
//! query is made of, generic over what a leaf holds (triangles in a mesh's tree, instances in
//! the top-level tree; see `instances`): the closest-first walk (`walk_closest`) and the
//! any-hit walk (`walk_any`). `intersect`, `occluded` and `intersect_batch` are those walks
//! over triangles; `intersect_kept` and `occluded_kept` are the same walks with a filter on
//! each hit (the cut-outs' alpha test, see `cutouts`): one traversal, two primitive tests.

use std::ops::Range;

use glam::Vec3A;

use super::wide::{raised, tie_bound};
use super::{Bvh, BvhNode, STACK_SIZE};
use crate::geometry::Hit;
use crate::math::Ray;

/// The closest-first walk over `nodes` (root at 0, not empty) for the ray `origin` with
/// reciprocal direction `inv_dir`: visits every leaf the ray enters within `(t_min, t)`, the
/// nearer child first, and skips each waiting subtree the ray no longer enters before `t`.
/// `leaf(slots, t)` tests the leaf's slots and lowers `t` to the closest hit it finds (or
/// keeps it). Boxes entered at exactly `t` are still visited, so a leaf can take a tie.
#[inline(always)]
pub(super) fn walk_closest(
    nodes: &[BvhNode],
    origin: Vec3A,
    inv_dir: Vec3A,
    t_min: f32,
    t: &mut f32,
    leaf: impl FnMut(Range<usize>, &mut f32),
) {
    let enter = |node: &BvhNode, t: f32| slab(node, origin, inv_dir, t_min, t);
    walk_nearest(nodes, t, enter, leaf);
}

/// The nearest-first walk over `nodes` (root at 0, not empty) that every closest query of
/// the binary tree is made of (a ray's closest hit, a point's closest point): `enter(node,
/// bound)` is the node's distance when it may still hold something within `bound`, else
/// `None`; the walk visits the leaves entered, the nearer child first, and skips each waiting
/// subtree no longer entered under the bound, which `leaf(slots, bound)` may lower.
#[inline(always)]
pub(super) fn walk_nearest<K: Copy + PartialOrd>(
    nodes: &[BvhNode],
    bound: &mut K,
    enter: impl Fn(&BvhNode, K) -> Option<K>,
    mut leaf: impl FnMut(Range<usize>, &mut K),
) {
    let mut stack = [0u32; STACK_SIZE];
    let mut sp = 0;
    let mut node = &nodes[0];
    if enter(node, *bound).is_none() {
        return;
    }
    loop {
        if node.is_leaf() {
            let first = node.first as usize;
            leaf(first..first + node.count as usize, bound);
        } else {
            let (l, r) = (node.first as usize, node.first as usize + 1);
            let dl = enter(&nodes[l], *bound);
            let dr = enter(&nodes[r], *bound);
            match (dl, dr) {
                (Some(a), Some(b)) => {
                    let (near, far) = if a <= b { (l, r) } else { (r, l) };
                    stack[sp] = far as u32;
                    sp += 1;
                    node = &nodes[near];
                    continue;
                }
                (Some(_), None) => {
                    node = &nodes[l];
                    continue;
                }
                (None, Some(_)) => {
                    node = &nodes[r];
                    continue;
                }
                (None, None) => {}
            }
        }
        // Pop the next subtree that can still hold something nearer.
        loop {
            if sp == 0 {
                return;
            }
            sp -= 1;
            let candidate = &nodes[stack[sp] as usize];
            if enter(candidate, *bound).is_some() {
                node = candidate;
                break;
            }
        }
    }
}

/// The any-hit walk over `nodes` (root at 0, not empty): visits the leaves the ray enters
/// within `(t_min, t_max)` until `leaf(slots)` says it found a hit; true when one did. Each
/// box's exit distance is raised by `exit_scale` (see [`slab_scaled`]; 1 for the renderer).
#[inline(always)]
pub(super) fn walk_any(
    nodes: &[BvhNode],
    (origin, inv_dir): (Vec3A, Vec3A),
    (t_min, t_max): (f32, f32),
    exit_scale: f32,
    mut leaf: impl FnMut(Range<usize>) -> bool,
) -> bool {
    let mut stack = [0u32; STACK_SIZE];
    let mut sp = 1;
    stack[0] = 0;
    while sp > 0 {
        sp -= 1;
        let node = &nodes[stack[sp] as usize];
        if slab_scaled(node, origin, inv_dir, (t_min, t_max), exit_scale).is_none() {
            continue;
        }
        if node.is_leaf() {
            let first = node.first as usize;
            if leaf(first..first + node.count as usize) {
                return true;
            }
        } else {
            stack[sp] = node.first;
            stack[sp + 1] = node.first + 1;
            sp += 2;
        }
    }
    false
}

/// The closest hit with `t` in `(t_min, t_max)`, if any.
pub(super) fn intersect(bvh: &Bvh, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
    intersect_kept(bvh, ray, t_min, t_max, |_, _, _| true)
}

/// The closest hit with `t` in `(t_min, t_max)` that `keep(prim_id, b1, b2)` keeps, if any:
/// a hit it refuses does not shorten the ray. `keep` is asked only about a hit that would
/// become the closest so far.
#[inline(always)]
pub(super) fn intersect_kept(
    bvh: &Bvh,
    ray: &Ray,
    t_min: f32,
    mut t_max: f32,
    keep: impl Fn(u32, f32, f32) -> bool,
) -> Option<Hit> {
    if bvh.nodes.is_empty() {
        return None;
    }
    let (origin, inv_dir) = (Vec3A::from(ray.origin), Vec3A::from(ray.direction).recip());
    // The best hit so far: its leaf-order index, barycentrics and scene index (`u32::MAX`
    // before the first). A later triangle at exactly `t_max` wins when its scene index is
    // smaller, so the answer does not depend on the order of the visit.
    let mut best: Option<(usize, f32, f32)> = None;
    let mut best_id = u32::MAX;
    let mut limit = t_max;
    walk_closest(
        &bvh.nodes,
        origin,
        inv_dir,
        t_min,
        &mut t_max,
        |slots, t_max| {
            for i in slots {
                let tri = &bvh.tris[i];
                let hit = tri.hit(ray, t_min, limit);
                if let Some(h) = hit {
                    let id = bvh.prim_ids[i];
                    if (h.t < *t_max || id < best_id) && keep(id, h.b1, h.b2) {
                        *t_max = h.t;
                        limit = h.t.next_up();
                        best_id = id;
                        best = Some((i, h.b1, h.b2));
                    }
                }
            }
        },
    );
    best.map(|(i, b1, b2)| Hit {
        t: t_max,
        b1,
        b2,
        triangle: bvh.prim_ids[i],
        instance: None,
    })
}

/// True when any triangle meets the ray with `t` in `(t_min, t_max)`; stops at the first:
/// [`occluded_kept`] keeping every hit.
#[inline(always)]
pub(super) fn occluded(bvh: &Bvh, ray: &Ray, t_min: f32, t_max: f32) -> bool {
    occluded_kept(bvh, ray, t_min, t_max, |_, _, _| true)
}

/// True when a triangle meets the ray with `t` in `(t_min, t_max)` at a hit that
/// `keep(prim_id, b1, b2)` keeps; stops at the first.
#[inline(always)]
pub(super) fn occluded_kept(
    bvh: &Bvh,
    ray: &Ray,
    t_min: f32,
    t_max: f32,
    keep: impl Fn(u32, f32, f32) -> bool,
) -> bool {
    walk_kept(bvh, ray, (t_min, t_max), keep, |_| true)
}

/// Calls `f` with every hit with `t` in `(t_min, t_max)` that `keep(prim_id, b1, b2)` keeps,
/// in the walk's order.
pub(super) fn each_kept(
    bvh: &Bvh,
    ray: &Ray,
    range: (f32, f32),
    keep: impl Fn(u32, f32, f32) -> bool,
    f: &mut impl FnMut(Hit),
) {
    walk_kept(bvh, ray, range, keep, |hit| {
        f(hit);
        false
    });
}

/// The any-hit walk over the tree's triangles: `found(hit)` for each hit with `t` in `(t_min,
/// t_max)` that `keep(prim_id, b1, b2)` keeps, in the walk's order, until it returns true;
/// true when it did.
#[inline(always)]
fn walk_kept(
    bvh: &Bvh,
    ray: &Ray,
    (t_min, t_max): (f32, f32),
    keep: impl Fn(u32, f32, f32) -> bool,
    mut found: impl FnMut(Hit) -> bool,
) -> bool {
    if bvh.nodes.is_empty() {
        return false;
    }
    let (origin, inv_dir) = (Vec3A::from(ray.origin), Vec3A::from(ray.direction).recip());
    walk_any(
        &bvh.nodes,
        (origin, inv_dir),
        (t_min, t_max),
        1.0,
        |slots| {
            let (tris, ids) = (&bvh.tris[slots.clone()], &bvh.prim_ids[slots]);
            tris.iter().zip(ids).any(|(tri, &id)| {
                let hit = tri.hit(ray, t_min, t_max).filter(|h| keep(id, h.b1, h.b2));
                hit.is_some_and(|h| {
                    found(Hit {
                        t: h.t,
                        b1: h.b1,
                        b2: h.b2,
                        triangle: id,
                        instance: None,
                    })
                })
            })
        },
    )
}

/// The closest hit of every ray of `rays`, written to `hits`; see [`Bvh::intersect_batch`].
pub(super) fn intersect_batch(
    bvh: &Bvh,
    rays: &[Ray],
    t_min: f32,
    t_max: f32,
    hits: &mut [Option<Hit>],
) {
    assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
    for (ray, hit) in rays.iter().zip(hits) {
        *hit = intersect(bvh, ray, t_min, t_max);
    }
}

/// The entry distance of the ray into the node's box within `(t_min, t_max)`, or `None`.
#[inline(always)]
pub(super) fn slab(
    node: &BvhNode,
    origin: Vec3A,
    inv_dir: Vec3A,
    t_min: f32,
    t_max: f32,
) -> Option<f32> {
    slab_scaled(node, origin, inv_dir, (t_min, t_max), 1.0)
}

/// [`slab`] with the box's exit distance raised by the margin `exit_scale` ([`raised`]): ray
/// casting's top level passes `wide::EXIT_SCALE` (Ize's conservative test, as its wide nodes
/// do), the renderer 1.
#[inline(always)]
pub(super) fn slab_scaled(
    node: &BvhNode,
    origin: Vec3A,
    inv_dir: Vec3A,
    (t_min, t_max): (f32, f32),
    exit_scale: f32,
) -> Option<f32> {
    // With padded boxes (see `build::node`), `bound − origin` is zero only for rays outside the
    // true box, so a NaN from 0·∞ can only turn a miss into a miss: SIMD min/max need no NaN
    // care.
    let t0 = (Vec3A::from(node.min) - origin) * inv_dir;
    let t1 = (Vec3A::from(node.max) - origin) * inv_dir;
    let near = t0.min(t1).max_element();
    let far = raised(t0.max(t1).min_element(), exit_scale);
    let near = if near > t_min { near } else { t_min };
    // Widened as `lanes::slab` widens it, so that a box holding a tie is visited in any order.
    let t_max = tie_bound(t_max);
    let far = if far < t_max { far } else { t_max };
    (near <= far).then_some(near)
}
