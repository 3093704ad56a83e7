//! An eight-wide view of the binary [`Bvh`](crate::accel::Bvh) for the ray-casting traversal:
//! each wide node holds up to eight children's boxes by coordinate, so that one slab test
//! over eight lanes (one AVX2 vector; compiled per instruction set through `crate::simd`, see
//! `kernels`) replaces up to three levels of binary nodes. Embree's BVH8 on AVX2 is the model;
//! against four wide, eight took the bunny's incoherent queries from 2,115 / 3,146 / 1,638
//! instructions per ray (`cast_rays` / `count_intersections` / `test_occlusions`) to
//! 1,834 / 2,655 / 1,350, with more rays per second (measured: docs/benchmarks.md, «Design
//! measurements», `accel::wide::node`, eight wide).
//!
//! The wide tree is collapsed from the binary one (an interior child with the largest
//! surface area is replaced by its two children until there are eight, as in Wald et al.,
//! "Getting Rid of Packets", 2008), except that children of at most two leaves' worth of
//! triangles are opened first: left alone, each would become a wide node of two leaves, a
//! node load for little culling (opening them took less time on incoherent rays on the bunny
//! at four wide; measured: docs/benchmarks.md, «Design measurements», `accel::wide::node`,
//! small subtrees opened).
//! The children's boxes are the binary nodes' padded boxes, bit for bit, and each leaf is the
//! leaf-slot range of a binary subtree, so the wide box test is exactly as conservative as
//! the binary one (see `tree`) and every query visits a superset of the triangles it must
//! see.

use super::margins::raised;
use crate::accel::BvhNode;
use crate::simd::{max, min, Isa};

/// Children per wide node.
pub(crate) const WIDTH: usize = 8;

/// A wide node: up to [`WIDTH`] children, each an interior wide node, a leaf (a range of
/// leaf slots) or unused. Unused lanes come last.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct WideNode {
    /// Smallest corner of each child's box: `min[axis][child]`.
    min: [[f32; WIDTH]; 3],
    /// Largest corner of each child's box: `max[axis][child]`.
    max: [[f32; WIDTH]; 3],
    /// An interior child's wide-node index, or a leaf's index given by `collapse`'s caller.
    child: [u32; WIDTH],
    /// A leaf's number of triangles; 0 for an interior child and [`UNUSED`] for no child.
    count: [u32; WIDTH],
}

/// The `count` of an unused lane.
const UNUSED: u32 = u32::MAX;

impl WideNode {
    /// A node with no children.
    const EMPTY: WideNode = WideNode {
        min: [[0.0; WIDTH]; 3],
        max: [[0.0; WIDTH]; 3],
        child: [0; WIDTH],
        count: [UNUSED; WIDTH],
    };

    /// Child `lane`: its index (wide node or first leaf slot) and its triangle count (0 for
    /// an interior child).
    #[inline(always)]
    pub fn child(&self, lane: usize) -> (u32, u32) {
        (self.child[lane], self.count[lane])
    }

    /// Whether lane `lane` holds a child.
    #[inline(always)]
    pub fn used(&self, lane: usize) -> bool {
        self.count[lane] != UNUSED
    }

    /// The lanes holding a child (bit `i` for lane `i`).
    #[inline(always)]
    pub fn used_mask(&self) -> u32 {
        (0..WIDTH)
            .filter(|&c| self.used(c))
            .fold(0, |m, c| m | 1 << c)
    }

    /// The box of child `lane` as its smallest and largest corners.
    #[inline(always)]
    pub fn bounds(&self, lane: usize) -> ([f32; 3], [f32; 3]) {
        (
            [0, 1, 2].map(|a| self.min[a][lane]),
            [0, 1, 2].map(|a| self.max[a][lane]),
        )
    }

    /// The children (bit `i` for child `i`) whose box the ray `origin + t/inv_dir` enters
    /// with `t` in `[t_min, t_max]`, and each child's entry distance (at least `t_min`).
    ///
    /// Per lane this is the conservative slab test of Ize (2013), on padded boxes: the exit
    /// distance is raised by the margin `exit_scale` (`1 + 2γ₃`, [`raised`]). The lanes are plain loops over
    /// `[f32; 8]`, which the compiler turns into one AVX2 vector per coordinate when inlined
    /// into a kernel compiled for AVX2 (`min`/`max` below are `vminps`/`vmaxps` exactly).
    #[inline(always)]
    pub fn enter<I: Isa>(
        &self,
        origin: &[f32; 3],
        inv_dir: &[f32; 3],
        t_min: f32,
        t_max: f32,
        exit_scale: f32,
    ) -> (u32, [f32; WIDTH]) {
        // The ray enters each slab through the plane its direction faces first: the smallest
        // corner's where `1/d ≥ +0`, the largest's where the sign bit is set (`−0` too, whose
        // `1/d` is `−∞`). Where `(lo − o)·(1/d)` and `(hi − o)·(1/d)` are numbers, rounding is
        // monotonic, so this is the slab test's `min`/`max` of the two, bit for bit, without
        // the six `min`/`max` per node; it differs only where one is NaN (`0·∞`, a ray in the
        // plane of a padded face, which never touches the true box: see `tree`).
        let faces = |a: usize| {
            if inv_dir[a].is_sign_negative() {
                (&self.max[a], &self.min[a])
            } else {
                (&self.min[a], &self.max[a])
            }
        };
        let planes = [faces(0), faces(1), faces(2)];
        let mut inside = [0i32; WIDTH];
        let mut entry = [0.0f32; WIDTH];
        for i in 0..WIDTH {
            let near = [0, 1, 2].map(|a| (planes[a].0[i] - origin[a]) * inv_dir[a]);
            let far = [0, 1, 2].map(|a| (planes[a].1[i] - origin[a]) * inv_dir[a]);
            let near = max(max(max(near[0], near[1]), near[2]), t_min);
            let far = min(raised(min(min(far[0], far[1]), far[2]), exit_scale), t_max);
            // One vector compare folds the unused lanes into the mask.
            inside[i] = -i32::from((near <= far) & (self.count[i] != UNUSED));
            entry[i] = near;
        }
        (I::mask(&inside), entry)
    }

    /// The children (bit `i` for child `i`) that some ray of a packet may enter with `t` in
    /// `[t_min, t_max]`: the rays' origins lie in the box `origin` (smallest and largest
    /// corners), their reciprocal directions in `inv_dir` (per axis one sign, finite).
    ///
    /// Interval arithmetic on the slab test (Boulos et al. 2006, "Geometric and arithmetic
    /// culling methods for entire ray packets"): per axis, the entry distance `(p − o)·(1/d)`
    /// is smallest at the origin's far end and at one end of `1/d`, the exit distance largest
    /// at the near end. Rounding is monotonic, so the bounds computed in `f32` bound every
    /// ray's own `f32` distances: a child missed here is missed by each ray's test
    /// ([`crate::accel::lanes::slab`], with `t_max` at least each ray's bound), and culling
    /// with it only saves the rays' tests.
    #[inline(always)]
    pub fn enter_interval<I: Isa>(
        &self,
        origin: &([f32; 3], [f32; 3]),
        inv_dir: &([f32; 3], [f32; 3]),
        t_min: f32,
        t_max: f32,
        exit_scale: f32,
    ) -> u32 {
        // Per axis: the entry and exit planes, the origin's end that gives the smallest
        // entry and the one that gives the largest exit (plain loops: they vectorize).
        let (o, (lo, hi)) = (origin, inv_dir);
        let mut near = [t_min; WIDTH];
        let mut far = [f32::INFINITY; WIDTH];
        for a in 0..3 {
            let (entry, exit, o_entry, o_exit) = if lo[a].is_sign_negative() {
                (&self.max[a], &self.min[a], o.0[a], o.1[a])
            } else {
                (&self.min[a], &self.max[a], o.1[a], o.0[a])
            };
            for i in 0..WIDTH {
                let x = entry[i] - o_entry;
                let y = exit[i] - o_exit;
                near[i] = max(near[i], min(x * lo[a], x * hi[a]));
                far[i] = min(far[i], max(y * lo[a], y * hi[a]));
            }
        }
        let mut inside = [0i32; WIDTH];
        for i in 0..WIDTH {
            let far = min(raised(far[i], exit_scale), t_max);
            inside[i] = -i32::from((near[i] <= far) & (self.count[i] != UNUSED));
        }
        I::mask(&inside)
    }
}

/// `1 − 2⁻²⁰`: scales a squared box distance computed in `f32` (at most a few roundings of
/// `2⁻²⁴` each above the exact one) down to a lower bound of it.
pub(crate) const SHRINK: f32 = 1.0 - 1.0 / 1_048_576.0;

/// A lower bound of the squared distance from `q` to each of eight boxes given by their
/// corners `lo[axis][lane]` and `hi[axis][lane]` (0 inside), for the closest-point walks;
/// `pad` covers how far `q` may be from the true query point (0 when `q` is it). The lanes
/// are plain loops over `[f32; 8]`, one vector each when inlined into a kernel.
#[inline(always)]
pub(crate) fn box_distances(
    lo: &[[f32; WIDTH]; 3],
    hi: &[[f32; WIDTH]; 3],
    q: &[f32; 3],
    pad: f32,
) -> [f32; WIDTH] {
    let mut d = [0.0f32; WIDTH];
    for i in 0..WIDTH {
        let gap = [0, 1, 2].map(|a| max(max(lo[a][i] - q[a], q[a] - hi[a][i]) - pad, 0.0));
        d[i] = (gap[0] * gap[0] + gap[1] * gap[1] + gap[2] * gap[2]) * SHRINK;
    }
    d
}

impl WideNode {
    /// The children whose box may hold a point within squared distance `limit` of `q` (bit
    /// `i` for child `i`), and a lower bound of each child's squared distance
    /// ([`box_distances`]).
    #[inline(always)]
    pub fn nearer<I: Isa>(&self, q: &[f32; 3], pad: f32, limit: f32) -> (u32, [f32; WIDTH]) {
        let d = box_distances(&self.min, &self.max, q, pad);
        let mut inside = [0i32; WIDTH];
        for i in 0..WIDTH {
            inside[i] = -i32::from((d[i] <= limit) & (self.count[i] != UNUSED));
        }
        (I::mask(&inside), d)
    }
}

/// Surface area (half of it: enough to compare) of a binary node's box.
fn half_area(node: &BvhNode) -> f32 {
    let (lo, hi) = (node.min_corner(), node.max_corner());
    let d = [0, 1, 2].map(|a| hi[a] - lo[a]);
    d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
}

/// For each binary node, the leaf slots of its subtree as `(first, count)`: a subtree's
/// slots are contiguous, the left child's before the right child's.
fn subtree_slots(nodes: &[BvhNode]) -> Vec<(u32, u32)> {
    let mut slots = vec![(0, 0); nodes.len()];
    // Children come after their parent in the array, so a backward pass sees them first.
    for (i, n) in nodes.iter().enumerate().rev() {
        slots[i] = if n.count() > 0 {
            (n.first(), n.count())
        } else {
            let c = n.first() as usize;
            assert!(c > i, "children follow their parent");
            let ((l0, ln), (r0, rn)) = (slots[c], slots[c + 1]);
            assert_eq!(l0 + ln, r0, "a subtree's slots are contiguous");
            (l0, ln + rn)
        };
    }
    slots
}

/// The wide tree of the binary tree `nodes` (root at 0 in both; empty for an empty tree).
/// Every binary subtree of at most `leaf_max` triangles becomes one leaf (its box is the
/// subtree root's); a leaf child's index is what `leaf(first, count)` returns for the leaf
/// slots `first .. first + count` it holds.
pub(crate) fn collapse(
    nodes: &[BvhNode],
    leaf_max: u32,
    leaf: &mut impl FnMut(u32, u32) -> u32,
) -> Vec<WideNode> {
    if nodes.is_empty() {
        return Vec::new();
    }
    let slots = subtree_slots(nodes);
    let splits = |k: u32| nodes[k as usize].count() == 0 && slots[k as usize].1 > leaf_max;
    // Each wide node holds at least one binary node that splits: reserving that many never
    // grows the vector (a copy of it all) and costs only address space, as untouched pages
    // are never made resident; the excess is returned at the end.
    let bound = (0..nodes.len() as u32)
        .filter(|&k| splits(k))
        .count()
        .max(1);
    let mut wide = Vec::with_capacity(bound);
    wide.push(WideNode::EMPTY);
    // Wide nodes to fill: (wide index, the binary node whose subtree it holds).
    let mut todo = vec![(0usize, 0u32)];
    while let Some((w, b)) = todo.pop() {
        let mut kids = [b; WIDTH];
        let mut len = 1;
        while len < WIDTH {
            let small = |k: u32| slots[k as usize].1 <= 2 * leaf_max;
            let widest = (0..len).filter(|&k| splits(kids[k])).max_by(|&x, &y| {
                let (a, b) = (kids[x], kids[y]);
                small(a)
                    .cmp(&small(b))
                    .then(half_area(&nodes[a as usize]).total_cmp(&half_area(&nodes[b as usize])))
            });
            let Some(k) = widest else { break };
            let first = nodes[kids[k] as usize].first();
            kids[k] = first;
            kids[len] = first + 1;
            len += 1;
        }
        let mut node = WideNode::EMPTY;
        for (lane, &k) in kids[..len].iter().enumerate() {
            let n = &nodes[k as usize];
            let (lo, hi) = (n.min_corner(), n.max_corner());
            for a in 0..3 {
                node.min[a][lane] = lo[a];
                node.max[a][lane] = hi[a];
            }
            if splits(k) {
                wide.push(WideNode::EMPTY);
                todo.push((wide.len() - 1, k));
                node.child[lane] = (wide.len() - 1) as u32;
                node.count[lane] = 0;
            } else {
                let (first, count) = slots[k as usize];
                node.child[lane] = leaf(first, count);
                node.count[lane] = count;
            }
        }
        wide[w] = node;
    }
    wide.shrink_to_fit();
    wide
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::Bvh;
    use crate::geometry::{Geometry, Triangle};
    use glam::Vec3;

    /// A strip of `n` small triangles along x.
    fn strip(n: usize) -> Geometry {
        let mut g = Geometry::default();
        for i in 0..n {
            let x = i as f32;
            let base = g.positions.len() as u32;
            g.positions.extend([
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + 0.5, 0.0, 0.0),
                Vec3::new(x, 0.5, (i % 7) as f32),
            ]);
            g.triangles.push(Triangle {
                vertices: [base, base + 1, base + 2],
                material: 0,
                object: 0,
                smooth: false,
            });
        }
        g
    }

    #[test]
    fn small_subtrees_are_opened_rather_than_left_as_two_leaf_nodes() {
        // A wide node of just two leaves costs a node load for little culling: the collapse
        // opens such subtrees (of at most 2 · leaf_max triangles) first. On this sphere of
        // 20,480 triangles that leaves 55 of 660 eight-wide nodes (8 %); at four wide it left
        // 224 of 1,419 (16 %), and opening the largest child alone 298 of 1,479 (20 %).
        let (positions, triangles) = crate::accel::test_meshes::icosphere(5);
        let sphere = Geometry {
            positions: positions.into_iter().map(Vec3::from).collect(),
            triangles: triangles
                .into_iter()
                .map(|vertices| Triangle {
                    vertices,
                    material: 0,
                    object: 0,
                    smooth: false,
                })
                .collect(),
            ..Geometry::default()
        };
        let bvh = Bvh::build(&sphere);
        let wide = collapse(bvh.nodes(), 8, &mut |first, _| first);
        let two_leaves = wide
            .iter()
            .filter(|w| {
                let used = (0..WIDTH).filter(|&l| w.used(l)).count();
                used == 2 && (0..2).all(|l| w.child(l).1 > 0)
            })
            .count();
        assert!(
            two_leaves * 6 < wide.len(),
            "{two_leaves} of {} wide nodes hold just two leaves",
            wide.len()
        );
    }

    #[test]
    fn a_wide_node_is_four_cache_lines() {
        assert_eq!(std::mem::size_of::<WideNode>(), 256);
        assert_eq!(std::mem::align_of::<WideNode>(), 64);
    }

    #[test]
    fn the_wide_tree_holds_every_slot_once_in_a_binary_subtree_box() {
        for (n, leaf_max) in [1, 2, 3, 9, 100, 1000]
            .into_iter()
            .flat_map(|n| [(n, 4), (n, 8)])
        {
            let bvh = Bvh::build(&strip(n));
            let slots = subtree_slots(bvh.nodes());
            let wide = collapse(bvh.nodes(), leaf_max, &mut |first, _| first);
            let mut seen = vec![0; n];
            let mut reached = vec![false; wide.len()];
            reached[0] = true;
            for node in &wide {
                for lane in 0..WIDTH {
                    let (child, count) = node.child(lane);
                    if count == UNUSED {
                        continue;
                    }
                    if count == 0 {
                        assert!(!reached[child as usize], "a wide node has one parent");
                        reached[child as usize] = true;
                        continue;
                    }
                    // A leaf: the slots of a binary subtree, in that subtree's box.
                    let (lo, hi) = (
                        [0, 1, 2].map(|a| node.min[a][lane]),
                        [0, 1, 2].map(|a| node.max[a][lane]),
                    );
                    assert!(bvh.nodes().iter().zip(&slots).any(|(b, &s)| {
                        s == (child, count) && b.min_corner() == lo && b.max_corner() == hi
                    }));
                    assert!(
                        count <= leaf_max
                            || bvh
                                .nodes()
                                .iter()
                                .any(|b| b.first() == child && b.count() == count)
                    );
                    for s in child..child + count {
                        seen[s as usize] += 1;
                    }
                }
                // Unused lanes come last.
                let used = node.count.iter().take_while(|&&c| c != UNUSED).count();
                assert!(node.count[used..].iter().all(|&c| c == UNUSED));
                assert!(used >= 1);
            }
            assert!(reached.iter().all(|&r| r), "every wide node is reachable");
            assert!(
                seen.iter().all(|&k| k == 1),
                "each slot once, {n} triangles"
            );
        }
    }
}
