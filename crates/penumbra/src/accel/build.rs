//! Binned-SAH construction of the [`Bvh`], on the calling thread or with large subtrees built
//! in parallel on a rayon pool; both give the same nodes. Also owns the box padding that keeps
//! the slab test conservative (see `node`).

use glam::Vec3;

use super::{accel, Bvh, BvhNode, BINS, MAX_DEPTH, MAX_LEAF, PARALLEL_MIN};
use crate::geometry::Geometry;
use crate::math::Aabb;

#[derive(Clone, Copy)]
struct BuildPrim {
    bounds: Aabb,
    centroid: Vec3,
    index: u32,
}

/// Builds the hierarchy over every triangle of `geometry`, splitting large subtrees across the
/// threads of `pool` when there is one.
pub(super) fn build(geometry: &Geometry, pool: Option<&rayon::ThreadPool>) -> Bvh {
    let mut prims: Vec<BuildPrim> = (0..geometry.len())
        .map(|i| {
            let bounds = geometry
                .corners(i)
                .into_iter()
                .fold(Aabb::EMPTY, Aabb::grow);
            BuildPrim {
                bounds,
                centroid: bounds.center(),
                index: i as u32,
            }
        })
        .collect();
    if prims.is_empty() {
        return Bvh::default();
    }
    let nodes = match pool {
        Some(pool) if prims.len() >= 2 * PARALLEL_MIN => {
            pool.install(|| build_subtree(&mut prims, 0, 0, true))
        }
        _ => build_subtree(&mut prims, 0, 0, false),
    };
    let prim_ids: Vec<u32> = prims.iter().map(|p| p.index).collect();
    let tris = prim_ids
        .iter()
        .map(|&i| accel(geometry.corners(i as usize)))
        .collect();
    Bvh {
        nodes,
        tris,
        prim_ids,
    }
}

fn bounds_of(prims: &[BuildPrim]) -> (Aabb, Aabb) {
    prims.iter().fold((Aabb::EMPTY, Aabb::EMPTY), |(b, c), p| {
        (b.union(p.bounds), c.grow(p.centroid))
    })
}

/// A node whose box is `bounds` grown outward by a relative 2⁻²⁰ (and at least the smallest
/// normal float). A ray lying exactly in a face plane of a tight box computes 0·∞ = NaN in the
/// slab test and would skip the box; with the padding, `bound − origin` is never zero for
/// a ray that touches the true box, and the box test stays conservative.
fn node(bounds: Aabb, first: usize, count: usize) -> BvhNode {
    let pad = |v: Vec3| v.abs() * (1.0 / (1 << 20) as f32) + Vec3::splat(f32::MIN_POSITIVE);
    BvhNode {
        min: (bounds.min - pad(bounds.min)).into(),
        first: first as u32,
        max: (bounds.max + pad(bounds.max)).into(),
        count: count as u32,
    }
}

/// Builds the subtree over `prims` (which sit at `offset` in the final permutation), reordering
/// them in place, with large halves built in parallel when `parallel` (on the current rayon
/// pool). The returned nodes have the subtree's root at index 0.
fn build_subtree(
    prims: &mut [BuildPrim],
    offset: usize,
    depth: usize,
    parallel: bool,
) -> Vec<BvhNode> {
    let (bounds, centroids) = bounds_of(prims);
    let Some(mid) = split(prims, bounds, centroids, depth) else {
        return vec![node(bounds, offset, prims.len())];
    };
    let root = node(bounds, 1, 0);
    let n = prims.len();
    let (left, right) = prims.split_at_mut(mid);
    if parallel && left.len().min(right.len()) >= PARALLEL_MIN {
        let (l, r) = rayon::join(
            || build_subtree(left, offset, depth + 1, true),
            || build_subtree(right, offset + mid, depth + 1, true),
        );
        join_subtrees(root, l, r)
    } else {
        let mut nodes = Vec::with_capacity(n);
        nodes.push(root);
        nodes.push(BvhNode { count: 0, ..root });
        nodes.push(BvhNode { count: 0, ..root });
        build_into(&mut nodes, 1, left, offset, depth + 1);
        build_into(&mut nodes, 2, right, offset + mid, depth + 1);
        nodes
    }
}

/// Places `[root, l[0], r[0], l[1..], r[1..]]`, renumbering the children links.
fn join_subtrees(mut root: BvhNode, l: Vec<BvhNode>, r: Vec<BvhNode>) -> Vec<BvhNode> {
    // In `l`, node k ≥ 1 moves to k + 2; in `r`, node k ≥ 1 moves to k + l.len() + 1.
    let relink = |mut n: BvhNode, shift: u32| {
        if !n.is_leaf() {
            n.first += shift;
        }
        n
    };
    let (l_shift, r_shift) = (2, l.len() as u32 + 1);
    root.first = 1;
    let mut nodes = Vec::with_capacity(1 + l.len() + r.len());
    nodes.push(root);
    nodes.push(relink(l[0], l_shift));
    nodes.push(relink(r[0], r_shift));
    nodes.extend(l[1..].iter().map(|&n| relink(n, l_shift)));
    nodes.extend(r[1..].iter().map(|&n| relink(n, r_shift)));
    nodes
}

/// Builds the subtree over `prims` into `nodes[index]`, appending its descendants.
fn build_into(
    nodes: &mut Vec<BvhNode>,
    index: usize,
    prims: &mut [BuildPrim],
    offset: usize,
    depth: usize,
) {
    let (bounds, centroids) = bounds_of(prims);
    let Some(mid) = split(prims, bounds, centroids, depth) else {
        nodes[index] = node(bounds, offset, prims.len());
        return;
    };
    let first = nodes.len();
    nodes[index] = node(bounds, first, 0);
    nodes.push(nodes[index]);
    nodes.push(nodes[index]);
    let (left, right) = prims.split_at_mut(mid);
    build_into(nodes, first, left, offset, depth + 1);
    build_into(nodes, first + 1, right, offset + mid, depth + 1);
}

/// Chooses a split by binned SAH over all three axes and partitions `prims` by it. Returns the
/// size of the left part, or `None` when a leaf is cheaper.
fn split(prims: &mut [BuildPrim], bounds: Aabb, centroids: Aabb, depth: usize) -> Option<usize> {
    let n = prims.len();
    // Past MAX_DEPTH (only reached by adversarial inputs, such as triangles spread over
    // hundreds of orders of magnitude) a leaf, however large, keeps traversal in its stack.
    if n <= 2 || depth >= MAX_DEPTH {
        return None;
    }
    let extent = centroids.extent();
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, bin)
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let bin_of = |p: &BuildPrim| bin_index(p, axis, centroids.min[axis], extent[axis]);
        let mut bin_bounds = [Aabb::EMPTY; BINS];
        let mut bin_counts = [0usize; BINS];
        for p in prims.iter() {
            let b = bin_of(p);
            bin_bounds[b] = bin_bounds[b].union(p.bounds);
            bin_counts[b] += 1;
        }
        // Sweep from the right to get the cost of every split plane's right side.
        let mut right_cost = [0.0f32; BINS];
        let (mut acc, mut count) = (Aabb::EMPTY, 0);
        for b in (1..BINS).rev() {
            acc = acc.union(bin_bounds[b]);
            count += bin_counts[b];
            right_cost[b] = acc.half_area() * count as f32;
        }
        let (mut acc, mut count) = (Aabb::EMPTY, 0);
        for b in 0..BINS - 1 {
            acc = acc.union(bin_bounds[b]);
            count += bin_counts[b];
            if count == 0 || count == n {
                continue;
            }
            let cost = acc.half_area() * count as f32 + right_cost[b + 1];
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b));
            }
        }
    }
    // SAH with traversal cost 1 and intersection cost 1, relative to the parent's area.
    let leaf_cost = n as f32;
    let area = bounds.half_area().max(f32::MIN_POSITIVE);
    match best {
        Some((cost, axis, bin)) if n > MAX_LEAF || 1.0 + cost / area < leaf_cost => {
            let (min, extent) = (centroids.min[axis], extent[axis]);
            let mid = partition(prims, |p| bin_index(p, axis, min, extent) <= bin);
            Some(mid)
        }
        Some(_) => None,
        // Every centroid coincides: SAH cannot separate them, so split by count to keep
        // leaves small.
        None if n > MAX_LEAF => Some(n / 2),
        None => None,
    }
}

/// The SAH bin of `p`'s centroid along `axis`, for centroids starting at `min` over `extent`.
fn bin_index(p: &BuildPrim, axis: usize, min: f32, extent: f32) -> usize {
    (((p.centroid[axis] - min) * (BINS as f32 / extent)) as usize).min(BINS - 1)
}

/// Moves the elements satisfying `pred` to the front; returns how many there are.
fn partition(prims: &mut [BuildPrim], pred: impl Fn(&BuildPrim) -> bool) -> usize {
    let mut i = 0;
    for j in 0..prims.len() {
        if pred(&prims[j]) {
            prims.swap(i, j);
            i += 1;
        }
    }
    i
}
