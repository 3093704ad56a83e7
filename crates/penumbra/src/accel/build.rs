//! Binned-SAH construction of the [`Bvh`], on the calling thread or on a rayon pool; both give
//! the same nodes. On a pool, the steps over all primitives run in parallel chunks, the top
//! splits bin in parallel (see `split`), and large subtrees are built on separate threads.
//! Also owns the box padding that keeps the slab test conservative (see `node`).

use glam::Vec3;
use rayon::prelude::*;

use super::split::{bounds_of, split, Bins, BuildPrim};
use super::{accel, Bvh, BvhNode, MAX_DEPTH, PARALLEL_MIN};
use crate::math::Aabb;

/// Nodes with at least this many primitives bin them in parallel (when building on a pool).
const PARALLEL_BINNING_MIN: usize = 128 * 1024;

/// Builds the hierarchy over the `n` triangles whose corners `corners(i)` gives, on the
/// threads of `pool` when there is one and the mesh is large enough to gain from it.
pub(super) fn build(
    n: usize,
    corners: impl Fn(usize) -> [Vec3; 3] + Sync,
    pool: Option<&rayon::ThreadPool>,
) -> Bvh {
    let bounds = |i: usize| corners(i).into_iter().fold(Aabb::EMPTY, Aabb::grow);
    let (nodes, prim_ids) = build_tree(n, bounds, pool);
    let tri = |&i: &u32| accel(corners(i as usize));
    let tris = if n >= 2 * PARALLEL_MIN && pool.is_some() {
        prim_ids.par_iter().map(tri).collect()
    } else {
        prim_ids.iter().map(tri).collect()
    };
    Bvh {
        nodes,
        tris,
        prim_ids,
    }
}

/// The nodes over the `n` primitives whose boxes `bounds(i)` gives, and the permutation from
/// leaf order to primitive index; on the threads of `pool` when there is one and there are
/// enough primitives to gain from it.
pub(super) fn build_tree(
    n: usize,
    bounds: impl Fn(usize) -> Aabb + Sync,
    pool: Option<&rayon::ThreadPool>,
) -> (Vec<BvhNode>, Vec<u32>) {
    if n == 0 {
        return (Vec::new(), Vec::new());
    }
    match pool {
        Some(pool) if n >= 2 * PARALLEL_MIN => pool.install(|| build_with(n, &bounds, true)),
        _ => build_with(n, bounds, false),
    }
}

/// The build, either all on the calling thread or, when `parallel`, with every step over all
/// primitives (their boxes, the top splits' binning, the final arrays) and every pair of large
/// subtrees spread over the current rayon pool. Both give the same nodes.
fn build_with(
    n: usize,
    bounds: impl Fn(usize) -> Aabb + Sync,
    parallel: bool,
) -> (Vec<BvhNode>, Vec<u32>) {
    let prim = |i: usize| {
        let bounds = bounds(i);
        BuildPrim {
            bounds,
            centroid: bounds.center(),
            index: i as u32,
        }
    };
    let mut prims: Vec<BuildPrim>;
    let (bounds, centroids);
    if parallel {
        prims = (0..n).into_par_iter().map(prim).collect();
        (bounds, centroids) = prims.par_chunks(PARALLEL_MIN).map(bounds_of).reduce(
            || (Aabb::EMPTY, Aabb::EMPTY),
            |(b0, c0), (b1, c1)| (b0.union(b1), c0.union(c1)),
        );
    } else {
        prims = (0..n).map(prim).collect();
        (bounds, centroids) = bounds_of(&prims);
    }
    let nodes = build_subtree(&mut prims, 0, 0, (bounds, centroids), parallel);
    let prim_ids = if parallel {
        prims.par_iter().map(|p| p.index).collect()
    } else {
        prims.iter().map(|p| p.index).collect()
    };
    (nodes, prim_ids)
}

/// A node whose box is `bounds` grown outward by a relative 2⁻²⁰ (and at least the smallest
/// normal float). A ray lying exactly in a face plane of a tight box computes 0·∞ = NaN in the
/// slab test and would skip the box; with the padding, `bound − origin` is never zero for
/// a ray that touches the true box, and the box test stays conservative.
pub(super) fn node(bounds: Aabb, first: usize, count: usize) -> BvhNode {
    let pad = |v: Vec3| v.abs() * (1.0 / (1 << 20) as f32) + Vec3::splat(f32::MIN_POSITIVE);
    BvhNode {
        min: (bounds.min - pad(bounds.min)).into(),
        first: first as u32,
        max: (bounds.max + pad(bounds.max)).into(),
        count: count as u32,
    }
}

/// Builds the subtree over `prims` (which sit at `offset` in the final permutation, and whose
/// boxes and centroids `bounds` bounds), reordering them in place. When `parallel`, the split
/// bins in parallel while the node is large and large children are built on the current rayon
/// pool, both at once when both are large. The returned nodes have the subtree's root at
/// index 0 and are laid out as the serial build lays them out.
fn build_subtree(
    prims: &mut [BuildPrim],
    offset: usize,
    depth: usize,
    bounds: (Aabb, Aabb),
    parallel: bool,
) -> Vec<BvhNode> {
    let n = prims.len();
    let bin_in_parallel = parallel && n >= PARALLEL_BINNING_MIN;
    let mut bins = Box::new(Bins::EMPTY);
    let Some(s) = split(prims, bounds, depth, bin_in_parallel, &mut bins) else {
        return vec![node(bounds.0, offset, n)];
    };
    let root = node(bounds.0, 1, 0);
    let (left, right) = prims.split_at_mut(s.mid);
    let (left_large, right_large) = (
        parallel && left.len() >= PARALLEL_MIN,
        parallel && right.len() >= PARALLEL_MIN,
    );
    let (mid, depth) = (s.mid, depth + 1);
    if left_large && right_large {
        let (l, r) = rayon::join(
            || build_subtree(left, offset, depth, s.left, true),
            || build_subtree(right, offset + mid, depth, s.right, true),
        );
        join_subtrees(root, l, r)
    } else if left_large || right_large {
        // A small side (a few outlying triangles cut off) must not make the large side serial.
        let l = build_subtree(left, offset, depth, s.left, left_large);
        let r = build_subtree(right, offset + mid, depth, s.right, right_large);
        join_subtrees(root, l, r)
    } else {
        let mut nodes = Vec::with_capacity(2 * n);
        nodes.push(root);
        nodes.push(BvhNode { count: 0, ..root });
        nodes.push(BvhNode { count: 0, ..root });
        build_into(&mut nodes, 1, left, offset, depth, s.left, &mut bins);
        build_into(
            &mut nodes,
            2,
            right,
            offset + mid,
            depth,
            s.right,
            &mut bins,
        );
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

/// Builds the subtree over `prims` (bounded by `bounds`) into `nodes[index]`, appending its
/// descendants; `bins` is the splits' scratch space.
fn build_into(
    nodes: &mut Vec<BvhNode>,
    index: usize,
    prims: &mut [BuildPrim],
    offset: usize,
    depth: usize,
    bounds: (Aabb, Aabb),
    bins: &mut Bins,
) {
    let Some(s) = split(prims, bounds, depth, false, bins) else {
        nodes[index] = node(bounds.0, offset, prims.len());
        return;
    };
    let first = nodes.len();
    nodes[index] = node(bounds.0, first, 0);
    nodes.push(nodes[index]);
    nodes.push(nodes[index]);
    let (left, right) = prims.split_at_mut(s.mid);
    build_into(nodes, first, left, offset, depth + 1, s.left, bins);
    build_into(
        nodes,
        first + 1,
        right,
        offset + s.mid,
        depth + 1,
        s.right,
        bins,
    );
}

/// One tree over the triangles of `a`, then those of `b` (each keeping its prim ids): a root
/// over the two roots, nothing built. `None` when the result would be deeper than a build
/// makes a tree (`MAX_DEPTH`), which the walks' fixed stacks are sized for.
pub(super) fn join(a: Bvh, mut b: Bvh) -> Option<Bvh> {
    if a.nodes.is_empty() || b.nodes.is_empty() {
        return Some(if a.nodes.is_empty() { b } else { a });
    }
    if depth(&a.nodes).max(depth(&b.nodes)) + 1 > MAX_DEPTH {
        return None;
    }
    let shift = a.tris.len() as u32;
    for n in b.nodes.iter_mut().filter(|n| n.is_leaf()) {
        n.first += shift;
    }
    let (ra, rb) = (a.nodes[0].bounds(), b.nodes[0].bounds());
    let root = BvhNode {
        min: ra.min.min(rb.min).into(),
        first: 1,
        max: ra.max.max(rb.max).into(),
        count: 0,
    };
    let nodes = join_subtrees(root, a.nodes, b.nodes);
    let (mut tris, mut prim_ids) = (a.tris, a.prim_ids);
    tris.extend(b.tris);
    prim_ids.extend(b.prim_ids);
    Some(Bvh {
        nodes,
        tris,
        prim_ids,
    })
}

/// The depth of the deepest leaf of `nodes` (the root's is 0).
fn depth(nodes: &[BvhNode]) -> usize {
    let mut deepest = 0;
    let mut stack = vec![(0u32, 0usize)];
    while let Some((index, d)) = stack.pop() {
        let n = &nodes[index as usize];
        if n.is_leaf() {
            deepest = deepest.max(d);
        } else {
            stack.extend([(n.first, d + 1), (n.first + 1, d + 1)]);
        }
    }
    deepest
}
