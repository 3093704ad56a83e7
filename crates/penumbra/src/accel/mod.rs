//! Bounding volume hierarchy over all triangles of a scene: a binned-SAH build (Wald, "On fast
//! Construction of SAH-based Bounding Volume Hierarchies", 2007) into a flat array of 32-byte
//! nodes, closest-hit traversal for camera rays and any-hit traversal for shadow rays.
//!
//! The hot loop touches only [`BvhNode`]s and a copy of the triangles in leaf order, stored as
//! `v0, e1, e2` ready for Möller–Trumbore; shading data stays in [`Geometry`] and is read once
//! per hit through the primitive permutation.

use glam::{Vec3, Vec3A};

use crate::geometry::{intersect_triangle, Geometry, Hit};
use crate::math::{Aabb, Ray};

/// A node of the flat BVH. Interior nodes have `count == 0` and their two children at
/// `first` and `first + 1`; leaves hold the triangles `first .. first + count` of the leaf-order
/// arrays.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub struct BvhNode {
    min: [f32; 3],
    first: u32,
    max: [f32; 3],
    count: u32,
}

impl BvhNode {
    fn bounds(&self) -> Aabb {
        Aabb {
            min: Vec3::from(self.min),
            max: Vec3::from(self.max),
        }
    }

    fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

/// A triangle ready for intersection: `v0` and the two edges from it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct TriAccel {
    v0: Vec3,
    e1: Vec3,
    e2: Vec3,
}

/// The BVH: nodes, triangles in leaf order, and the permutation back to scene triangle indices.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Vec<BvhNode>,
    tris: Vec<TriAccel>,
    prim_ids: Vec<u32>,
}

const BINS: usize = 16;
const MAX_LEAF: usize = 8;
/// Subtrees with more triangles than this are built on separate threads.
const PARALLEL_MIN: usize = 32 * 1024;
const STACK_SIZE: usize = 64;
/// Deepest leaf: the any-hit traversal holds at most `depth + 1` entries on its stack.
const MAX_DEPTH: usize = STACK_SIZE - 2;

#[derive(Clone, Copy)]
struct BuildPrim {
    bounds: Aabb,
    centroid: Vec3,
    index: u32,
}

fn accel(corners: [Vec3; 3]) -> TriAccel {
    TriAccel {
        v0: corners[0],
        e1: corners[1] - corners[0],
        e2: corners[2] - corners[0],
    }
}

impl Bvh {
    /// Builds the hierarchy over every triangle of `geometry` on the calling thread.
    pub fn build(geometry: &Geometry) -> Bvh {
        Self::build_with(geometry, None)
    }

    /// Builds the hierarchy, splitting large subtrees across the threads of `pool`. The result
    /// is the same as [`Bvh::build`]'s.
    pub fn build_parallel(geometry: &Geometry, pool: &rayon::ThreadPool) -> Bvh {
        Self::build_with(geometry, Some(pool))
    }

    fn build_with(geometry: &Geometry, pool: Option<&rayon::ThreadPool>) -> Bvh {
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

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The closest hit with `t` in `(t_min, t_max)`, if any.
    pub fn intersect(&self, ray: &Ray, t_min: f32, mut t_max: f32) -> Option<Hit> {
        if self.nodes.is_empty() {
            return None;
        }
        let (origin, inv_dir) = (Vec3A::from(ray.origin), Vec3A::from(ray.direction).recip());
        let mut best: Option<(usize, f32, f32)> = None;
        let mut stack = [0u32; STACK_SIZE];
        let mut sp = 0;
        let mut node = &self.nodes[0];
        slab(node, origin, inv_dir, t_min, t_max)?;
        loop {
            if node.is_leaf() {
                let first = node.first as usize;
                for i in first..first + node.count as usize {
                    let tri = &self.tris[i];
                    let hit = intersect_triangle(
                        ray.origin,
                        ray.direction,
                        tri.v0,
                        tri.e1,
                        tri.e2,
                        t_min,
                        t_max,
                    );
                    if let Some(h) = hit {
                        t_max = h.t;
                        best = Some((i, h.b1, h.b2));
                    }
                }
            } else {
                let (l, r) = (node.first as usize, node.first as usize + 1);
                let dl = slab(&self.nodes[l], origin, inv_dir, t_min, t_max);
                let dr = slab(&self.nodes[r], origin, inv_dir, t_min, t_max);
                match (dl, dr) {
                    (Some(a), Some(b)) => {
                        let (near, far) = if a <= b { (l, r) } else { (r, l) };
                        stack[sp] = far as u32;
                        sp += 1;
                        node = &self.nodes[near];
                        continue;
                    }
                    (Some(_), None) => {
                        node = &self.nodes[l];
                        continue;
                    }
                    (None, Some(_)) => {
                        node = &self.nodes[r];
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the next subtree that can still hold a closer hit.
            loop {
                if sp == 0 {
                    return best.map(|(i, b1, b2)| Hit {
                        t: t_max,
                        b1,
                        b2,
                        triangle: self.prim_ids[i],
                    });
                }
                sp -= 1;
                let candidate = &self.nodes[stack[sp] as usize];
                if slab(candidate, origin, inv_dir, t_min, t_max).is_some() {
                    node = candidate;
                    break;
                }
            }
        }
    }

    /// True when any triangle meets the ray with `t` in `(t_min, t_max)`; stops at the first.
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let (origin, inv_dir) = (Vec3A::from(ray.origin), Vec3A::from(ray.direction).recip());
        let mut stack = [0u32; STACK_SIZE];
        let mut sp = 1;
        stack[0] = 0;
        while sp > 0 {
            sp -= 1;
            let node = &self.nodes[stack[sp] as usize];
            if slab(node, origin, inv_dir, t_min, t_max).is_none() {
                continue;
            }
            if node.is_leaf() {
                let first = node.first as usize;
                for tri in &self.tris[first..first + node.count as usize] {
                    let hit = intersect_triangle(
                        ray.origin,
                        ray.direction,
                        tri.v0,
                        tri.e1,
                        tri.e2,
                        t_min,
                        t_max,
                    );
                    if hit.is_some() {
                        return true;
                    }
                }
            } else {
                stack[sp] = node.first;
                stack[sp + 1] = node.first + 1;
                sp += 2;
            }
        }
        false
    }

    /// The closest hit of every ray of `rays` with `t` in `(t_min, t_max)`, written to `hits`
    /// (which must be as long as `rays`). Each result equals [`Bvh::intersect`]'s.
    pub fn intersect_batch(&self, rays: &[Ray], t_min: f32, t_max: f32, hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
        for (ray, hit) in rays.iter().zip(hits) {
            *hit = self.intersect(ray, t_min, t_max);
        }
    }

    /// Occlusion of the segments from `origin` to each point of `ends`: `occluded[i]` is true
    /// when a triangle meets `origin + t·(ends[i] − origin)` for some `t` in `(0, t_max)`, as
    /// [`Bvh::occluded`] on that ray would say. The segments share their origin, like the N×N
    /// samples of an area light seen from one shading point. `occluded` must be as long as
    /// `ends`.
    pub fn occluded_from(&self, origin: Vec3, ends: &[Vec3], t_max: f32, occluded: &mut [bool]) {
        assert_eq!(ends.len(), occluded.len(), "one mask slot per segment");
        for (&end, o) in ends.iter().zip(occluded) {
            *o = self.occluded(&Ray::new(origin, end - origin), 0.0, t_max);
        }
    }

    /// Checks the structure's invariants against the geometry it was built from: every
    /// triangle appears exactly once, children are in range, and every box holds its contents.
    pub fn validate(&self, geometry: &Geometry) -> Result<(), String> {
        if geometry.is_empty() {
            return if self.nodes.is_empty() {
                Ok(())
            } else {
                Err("nodes without triangles".into())
            };
        }
        let mut seen = vec![false; geometry.len()];
        for &id in &self.prim_ids {
            let slot = seen
                .get_mut(id as usize)
                .ok_or(format!("triangle id {id} out of range"))?;
            if std::mem::replace(slot, true) {
                return Err(format!("triangle {id} appears twice"));
            }
        }
        if seen.iter().any(|s| !s) || self.tris.len() != geometry.len() {
            return Err("a triangle is missing from the leaves".into());
        }
        let mut leaf_tris = 0;
        let mut stack = vec![(0usize, 0usize)];
        while let Some((i, depth)) = stack.pop() {
            if depth >= STACK_SIZE {
                return Err(format!("depth {depth} exceeds the traversal stack"));
            }
            let node = self.nodes.get(i).ok_or(format!("node {i} out of range"))?;
            let bounds = node.bounds();
            if node.is_leaf() {
                let first = node.first as usize;
                let end = first + node.count as usize;
                if end > self.tris.len() {
                    return Err(format!("leaf {i} past the triangle array"));
                }
                for k in first..end {
                    for p in geometry.corners(self.prim_ids[k] as usize) {
                        if !bounds.contains(p) {
                            return Err(format!("leaf {i} does not hold triangle {k}"));
                        }
                    }
                }
                leaf_tris += node.count as usize;
            } else {
                for c in [node.first as usize, node.first as usize + 1] {
                    let child = self.nodes.get(c).ok_or(format!("child {c} out of range"))?;
                    if c <= i || bounds.union(child.bounds()) != bounds {
                        return Err(format!("node {i} does not enclose child {c}"));
                    }
                    stack.push((c, depth + 1));
                }
            }
        }
        if leaf_tris != geometry.len() {
            return Err(format!(
                "leaves reach {leaf_tris} of {} triangles",
                geometry.len()
            ));
        }
        Ok(())
    }
}

/// The closest hit by testing every triangle: the reference the BVH must agree with.
pub fn intersect_brute_force(
    geometry: &Geometry,
    ray: &Ray,
    t_min: f32,
    t_max: f32,
) -> Option<Hit> {
    let mut best = None;
    let mut t_max = t_max;
    for i in 0..geometry.len() {
        let tri = accel(geometry.corners(i));
        if let Some(h) = intersect_triangle(
            ray.origin,
            ray.direction,
            tri.v0,
            tri.e1,
            tri.e2,
            t_min,
            t_max,
        ) {
            t_max = h.t;
            best = Some(Hit {
                t: h.t,
                b1: h.b1,
                b2: h.b2,
                triangle: i as u32,
            });
        }
    }
    best
}

/// The entry distance of the ray into the node's box within `(t_min, t_max)`, or `None`.
#[inline(always)]
fn slab(node: &BvhNode, origin: Vec3A, inv_dir: Vec3A, t_min: f32, t_max: f32) -> Option<f32> {
    // With padded boxes (see `node`), `bound − origin` is zero only for rays outside the true
    // box, so a NaN from 0·∞ can only turn a miss into a miss: SIMD min/max need no NaN care.
    let t0 = (Vec3A::from(node.min) - origin) * inv_dir;
    let t1 = (Vec3A::from(node.max) - origin) * inv_dir;
    let near = t0.min(t1).max_element();
    let far = t0.max(t1).min_element();
    let near = if near > t_min { near } else { t_min };
    let far = if far < t_max { far } else { t_max };
    (near <= far).then_some(near)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Mesh;
    use crate::math::Transform;
    use proptest::prelude::*;

    #[test]
    fn node_is_32_bytes() {
        assert_eq!(std::mem::size_of::<BvhNode>(), 32);
        assert_eq!(std::mem::align_of::<BvhNode>(), 32);
    }

    fn soup(tris: &[[[f32; 3]; 3]]) -> Geometry {
        let mut g = Geometry::default();
        for t in tris {
            let mesh = Mesh {
                positions: t.iter().map(|&p| Vec3::from(p)).collect(),
                indices: vec![[0, 1, 2]],
                ..Mesh::default()
            };
            g.append(&mesh, &Transform::IDENTITY, &[0], 0);
        }
        g
    }

    fn assert_agree(g: &Geometry, bvh: &Bvh, ray: &Ray) {
        let a = bvh.intersect(ray, 1e-4, f32::INFINITY);
        let b = intersect_brute_force(g, ray, 1e-4, f32::INFINITY);
        match (a, b) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                // The triangle may differ only on an exact tie in t.
                assert_eq!(a.t, b.t, "closest distance differs");
            }
            (a, b) => panic!("bvh {a:?} vs brute force {b:?}"),
        }
        assert_eq!(bvh.occluded(ray, 1e-4, f32::INFINITY), b.is_some());
        if let Some(b) = b {
            // Nothing blocks the ray strictly before its closest hit.
            assert!(!bvh.occluded(ray, 1e-4, b.t));
        }
    }

    #[test]
    fn empty_and_single_triangle() {
        let g = Geometry::default();
        let bvh = Bvh::build(&g);
        bvh.validate(&g).unwrap();
        let ray = Ray::new(Vec3::ZERO, Vec3::Z);
        assert!(bvh.intersect(&ray, 0.0, f32::INFINITY).is_none());
        assert!(!bvh.occluded(&ray, 0.0, f32::INFINITY));

        let g = soup(&[[[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]]]);
        let bvh = Bvh::build(&g);
        bvh.validate(&g).unwrap();
        let hit = bvh
            .intersect(&Ray::new(Vec3::new(0.2, 0.2, 0.0), Vec3::Z), 0.0, 9.0)
            .unwrap();
        assert_eq!((hit.t, hit.triangle), (1.0, 0));
    }

    #[test]
    fn identical_centroids_still_give_small_leaves() {
        let tris: Vec<_> = (0..100)
            .map(|i| {
                let s = 1.0 + i as f32;
                [[-s, -s, 0.0], [s, -s, 0.0], [0.0, 2.0 * s, 0.0]]
            })
            .map(|t| {
                // Same centroid (0, 0, 0) for every triangle.
                let c = (Vec3::from(t[0]) + Vec3::from(t[1]) + Vec3::from(t[2])) / 3.0;
                t.map(|p| (Vec3::from(p) - c).to_array())
            })
            .collect();
        let g = soup(&tris);
        let bvh = Bvh::build(&g);
        bvh.validate(&g).unwrap();
        assert!(bvh.nodes.iter().all(|n| n.count as usize <= MAX_LEAF));
        assert_agree(&g, &bvh, &Ray::new(Vec3::new(0.1, 0.1, -5.0), Vec3::Z));
    }

    #[test]
    fn rays_in_a_box_face_plane_still_hit_edges() {
        // The triangle's right edge lies on x = 0, the box's max x. A ray with direction x = 0
        // travelling in that plane (the center column of an axis-aligned camera) hits the
        // edge, which counts as inside; the box test must not skip it.
        let g = soup(&[[[-1.0, -1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 1.0, 0.0]]]);
        let bvh = Bvh::build(&g);
        for ray in [
            Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z),
            Ray::new(Vec3::new(0.0, 3.0, 5.0), Vec3::new(0.0, -0.6, -1.0)),
        ] {
            assert!(intersect_brute_force(&g, &ray, 1e-4, f32::INFINITY).is_some());
            assert_agree(&g, &bvh, &ray);
        }
    }

    #[test]
    fn depth_stays_within_the_traversal_stack() {
        // Tiny triangles at x = 2^k for k over f32's whole range: binned SAH peels off a few
        // per level, which without a depth cap would overflow the traversal stack.
        let tris: Vec<_> = (-120..120)
            .map(|k| {
                let x = 2f32.powi(k);
                let e = x * 1e-3;
                [[x, 0.0, 0.0], [x + e, 0.0, 0.0], [x, e, 0.0]]
            })
            .collect();
        let g = soup(&tris);
        let bvh = Bvh::build(&g);
        bvh.validate(&g).unwrap();
        let ray = Ray::new(Vec3::new(-1.0, 1e-30, 0.0), Vec3::X);
        let _ = bvh.intersect(&ray, 0.0, f32::INFINITY);
        let _ = bvh.occluded(&ray, 0.0, f32::INFINITY);
    }

    fn arb_point() -> impl Strategy<Value = [f32; 3]> {
        prop::array::uniform3(-10.0f32..10.0)
    }

    fn arb_soup() -> impl Strategy<Value = Vec<[[f32; 3]; 3]>> {
        // Small triangles scattered in a box, so that rays hit some and miss others.
        prop::collection::vec(
            (
                arb_point(),
                prop::array::uniform3(prop::array::uniform3(-1.5f32..1.5)),
            ),
            0..300,
        )
        .prop_map(|v| {
            v.into_iter()
                .map(|(c, offs)| offs.map(|o| [c[0] + o[0], c[1] + o[1], c[2] + o[2]]))
                .collect()
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn bvh_agrees_with_brute_force(
            tris in arb_soup(),
            rays in prop::collection::vec((arb_point(), arb_point()), 50),
        ) {
            let g = soup(&tris);
            let bvh = Bvh::build(&g);
            prop_assert!(bvh.validate(&g).is_ok(), "{:?}", bvh.validate(&g));
            for (o, target) in rays {
                let dir = Vec3::from(target) - Vec3::from(o);
                if dir.length() < 1e-3 { continue; }
                assert_agree(&g, &bvh, &Ray::new(Vec3::from(o), dir));
            }
        }
    }

    #[test]
    fn large_soup_takes_the_parallel_path_and_agrees() {
        // Enough triangles that both halves of the root exceed PARALLEL_MIN.
        let n = 2 * PARALLEL_MIN + 1000;
        let mut state = 12345u64;
        let mut rnd = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 40) as f32 / (1u64 << 24) as f32) * 20.0 - 10.0
        };
        let tris: Vec<_> = (0..n)
            .map(|_| {
                let c = [rnd(), rnd(), rnd()];
                [0, 1, 2].map(|_| {
                    [
                        c[0] + rnd() * 0.02,
                        c[1] + rnd() * 0.02,
                        c[2] + rnd() * 0.02,
                    ]
                })
            })
            .collect();
        let g = soup(&tris);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let bvh = Bvh::build_parallel(&g, &pool);
        bvh.validate(&g).unwrap();
        let serial = Bvh::build(&g);
        assert_eq!(bvh.nodes, serial.nodes);
        assert_eq!(bvh.prim_ids, serial.prim_ids);
        for _ in 0..300 {
            let o = Vec3::new(rnd(), rnd(), rnd()) * 2.0;
            let d = Vec3::new(rnd(), rnd(), rnd());
            assert_agree(&g, &bvh, &Ray::new(o, d));
        }
    }
}
