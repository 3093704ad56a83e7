//! The closest point of a triangle to a point, by Voronoi regions (Ericson, "Real-Time
//! Collision Detection", 2005, §5.1.5), and of the whole surface, by the wide tree's
//! nearest-first walk: the nearest child first, boxes and triangles whose lower bound of the
//! distance exceeds the best point so far skipped.
//!
//! Both compute in `f64`: the region tests multiply four lengths (`d1·d4` is a product of
//! dot products), which overflow `f32` from coordinates of about 1e9 on, where every point
//! fell in a corner's region. In `f64` any finite `f32` point and triangle are fine.

use glam::{DAffine3, DVec3, Vec3};

use super::tree::{Order, Stack, WideBvh, OWN};
use crate::accel::BvhNode;
use crate::math::Transform;
use crate::simd::Isa;

/// The point of the triangle `tri` closest to `p` and its barycentric weights of the second
/// and third corners. Degenerate triangles give a point of their segment or corner.
#[cfg(test)]
pub(crate) fn closest_on_triangle(p: Vec3, tri: [Vec3; 3]) -> (Vec3, f32, f32) {
    let (point, b1, b2) = closest_f64(p.as_dvec3(), tri.map(|c| c.as_dvec3()));
    (point.as_vec3(), b1 as f32, b2 as f32)
}

/// `closest_on_triangle` in `f64`.
pub(crate) fn closest_f64(p: DVec3, tri: [DVec3; 3]) -> (DVec3, f64, f64) {
    let [a, b, c] = tri;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    // Vertex region of a.
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, 0.0, 0.0);
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (b, 1.0, 0.0);
    }
    // Edge region of ab (`d1 − d3 = |ab|²`: a zero-length edge has no region of its own, and
    // would give 0/0 here).
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 && d1 - d3 > 0.0 {
        let s = d1 / (d1 - d3);
        return (a + s * ab, s, 0.0);
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (c, 0.0, 1.0);
    }
    // Edge region of ac.
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 && d2 - d6 > 0.0 {
        let s = d2 / (d2 - d6);
        return (a + s * ac, 0.0, s);
    }
    // Edge region of bc.
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 && (d4 - d3) + (d5 - d6) > 0.0 {
        let s = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + s * (c - b), 1.0 - s, s);
    }
    // Inside the face.
    let denom = va + vb + vc;
    if denom.is_finite() && denom != 0.0 {
        let (v, w) = (vb / denom, vc / denom);
        return (a + v * ab + w * ac, v, w);
    }
    // A degenerate triangle whose regions all failed (NaN input): its first corner.
    (a, 0.0, 0.0)
}

/// The closest point on the surface to a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Nearest {
    pub point: Vec3,
    pub b1: f32,
    pub b2: f32,
    pub geometry: u32,
    pub primitive: u32,
    pub slot: u32,
    /// The placement of its triangle, `tree::OWN` for the scene's own triangles.
    pub level: u32,
}

/// Where a placed mesh's tree is: its maps between world and object space, and a lower bound
/// of the squared smallest stretch of the object-to-world map (a box at object distance `d`
/// is at least `d·√shrink_sq` away in the world).
pub(crate) struct Frame<'a> {
    pub level: u32,
    pub geometry: u32,
    pub to_object: &'a DAffine3,
    pub to_world: &'a Transform,
    pub shrink_sq: f64,
    /// How far the placed corners may be from the exact images of the mesh's, in object
    /// units: the bounds of the walk in object space are lowered by it.
    pub pad: f32,
}

impl WideBvh {
    /// Lowers `best` to the closest point to `p` of this tree's triangles, placed by `frame`
    /// when given, if one is as near as `√best_d` (nearer, or as near with smaller ids, when
    /// `best` is set); then `best_d` is its squared distance.
    ///
    /// The walk takes the wide tree nearest box first, skips a box, and then a triangle,
    /// whose lower bound of the squared distance ([`WideNode::nearer`],
    /// [`TriangleGroup::nearer`], in `f32` over eight lanes) exceeds the best so far, and
    /// computes the closest point of the triangles left in `f64`. The bounds only ever err
    /// low, so every triangle as near as the best is computed, and the answer is that of
    /// testing every triangle.
    ///
    /// [`WideNode::nearer`]: super::node::WideNode::nearer
    /// [`TriangleGroup::nearer`]: super::group::TriangleGroup::nearer
    #[inline(always)]
    pub(crate) fn nearest_within<I: Isa>(
        &self,
        p: DVec3,
        frame: Option<&Frame>,
        (best_d, best): (&mut f64, &mut Option<Nearest>),
        stack: &mut Stack,
    ) {
        let (q, scale) = frame.map_or((p, 1.0), |f| (f.to_object.transform_point3(p), f.shrink_sq));
        // In object space `q` is rounded to `f32`, and the placed corners are the map's
        // rounded images: the bounds allow both.
        let pad = match frame {
            None => 0.0,
            Some(f) => (q.abs().max_element() * PAD) as f32 + f.pad,
        };
        let q32 = q.as_vec3().to_array();
        // The squared distance in the tree's space past which nothing is nearer than the
        // best so far, rounded up to `f32` (∞ when it is beyond `f32`'s range).
        let limit = |best_d: f64| ((best_d / scale) * (1.0 + 1e-6)) as f32;
        stack.start(self.wide());
        while let Some((first, count, near)) = stack.pop() {
            let bound = limit(*best_d);
            if near > bound {
                continue;
            }
            if count == 0 {
                let node = &self.wide()[first as usize];
                let (mask, near) = node.nearer::<I>(&q32, pad, bound);
                stack.push_children(
                    |i, c| self.prefetch_child(i, c),
                    node,
                    mask,
                    &near,
                    Order::Nearest,
                );
                continue;
            }
            for (group, valid) in self.leaf(first, count) {
                let (mask, near) = group.nearer::<I>(&q32, pad, limit(*best_d));
                let mut mask = mask & valid;
                while mask != 0 {
                    let lane = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    // The best may have come nearer since the group's test.
                    if near[lane] > limit(*best_d) {
                        continue;
                    }
                    let corners = group.corners(lane).map(|c| {
                        let c = Vec3::from(c);
                        frame.map_or(c, |f| f.to_world.point(c)).as_dvec3()
                    });
                    let (point, b1, b2) = closest_f64(p, corners);
                    let d = (point - p).length_squared();
                    let [geometry, primitive] = group.ids(lane);
                    let geometry = frame.map_or(geometry, |f| f.geometry);
                    // Among equally near triangles the smallest ids, whatever the order of
                    // the visit (boxes at exactly the best distance are still entered).
                    let tie = |b: &Nearest| (geometry, primitive) < (b.geometry, b.primitive);
                    if d < *best_d || (d == *best_d && best.as_ref().is_none_or(tie)) {
                        *best_d = d;
                        *best = Some(Nearest {
                            point: point.as_vec3(),
                            b1: b1 as f32,
                            b2: b2 as f32,
                            geometry,
                            primitive,
                            slot: group.first + lane as u32,
                            level: frame.map_or(OWN, |f| f.level),
                        });
                    }
                }
            }
        }
    }
}

/// `2⁻²³`: a bound of the relative rounding of an `f64` coordinate to `f32`, twice over.
const PAD: f64 = 1.0 / 8_388_608.0;

/// Squared distance from `p` to the node's box (0 inside).
#[inline(always)]
pub(super) fn box_distance_sq(node: &BvhNode, p: DVec3) -> f64 {
    let lo = Vec3::from(node.min_corner()).as_dvec3();
    let hi = Vec3::from(node.max_corner()).as_dvec3();
    let d = (lo - p).max(p - hi).max(DVec3::ZERO);
    d.length_squared()
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRI: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

    #[test]
    fn each_region_gives_the_expected_point_and_weights() {
        let cases = [
            // (query, closest, b1, b2)
            ([0.25, 0.25, 2.0], [0.25, 0.25, 0.0], 0.25, 0.25),
            ([-1.0, -1.0, 0.5], [0.0, 0.0, 0.0], 0.0, 0.0),
            ([2.0, -0.5, 0.0], [1.0, 0.0, 0.0], 1.0, 0.0),
            ([-0.5, 3.0, 0.0], [0.0, 1.0, 0.0], 0.0, 1.0),
            ([0.5, -2.0, 1.0], [0.5, 0.0, 0.0], 0.5, 0.0),
            ([-2.0, 0.25, -1.0], [0.0, 0.25, 0.0], 0.0, 0.25),
            ([1.0, 1.0, 0.0], [0.5, 0.5, 0.0], 0.5, 0.5),
        ];
        for (q, want, b1, b2) in cases {
            let (p, u, v) = closest_on_triangle(Vec3::from(q), TRI.map(Vec3::from));
            assert!(p.distance(Vec3::from(want)) < 1e-6, "{q:?} → {p}");
            assert!(
                (u - b1).abs() < 1e-6 && (v - b2).abs() < 1e-6,
                "{q:?} → {u} {v}"
            );
            // The weights reproduce the point.
            let [a, b, c] = TRI.map(Vec3::from);
            assert!(((1.0 - u - v) * a + u * b + v * c).distance(p) < 1e-6);
        }
    }

    #[test]
    fn degenerate_triangles_give_a_point_on_them() {
        let seg = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        let (p, _, _) = closest_on_triangle(Vec3::new(1.5, 1.0, 0.0), seg.map(Vec3::from));
        assert!(p.distance(Vec3::new(1.5, 0.0, 0.0)) < 1e-6, "{p}");
        let dot = [[1.0, 1.0, 1.0]; 3];
        let (p, _, _) = closest_on_triangle(Vec3::ZERO, dot.map(Vec3::from));
        assert_eq!(p, Vec3::ONE);
        // Two equal corners (a segment from a to c), in every order: the segment's point, not
        // the 0/0 of the zero-length edge (found by proptest).
        let (a, c) = (Vec3::new(1.0, 2.0, 0.0), Vec3::new(3.0, 2.0, 0.0));
        let q = Vec3::new(2.5, 0.0, 1.0);
        for tri in [
            [a, a, c],
            [a, c, a],
            [c, a, a],
            [c, c, a],
            [c, a, c],
            [a, c, c],
        ] {
            let (p, b1, b2) = closest_on_triangle(q, tri);
            assert!(p.distance(Vec3::new(2.5, 2.0, 0.0)) < 1e-6, "{tri:?}: {p}");
            let [t0, t1, t2] = tri;
            let back = t0 + b1 * (t1 - t0) + b2 * (t2 - t0);
            assert!(back.distance(p) < 1e-6, "{tri:?}: weights {b1}, {b2}");
        }
    }
}
