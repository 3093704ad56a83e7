//! Checks on the [`Bvh`]: the structural invariants (`validate`) and the brute-force
//! references every query must agree with ([`intersect_brute_force`],
//! [`occluded_brute_force`]), which test each triangle of the scene in turn.

use super::{accel, Bvh, STACK_SIZE};
use crate::geometry::{Geometry, Hit};
use crate::math::Ray;

/// Checks `bvh` against the geometry it was built from; see [`Bvh::validate`].
pub(super) fn validate(bvh: &Bvh, geometry: &Geometry) -> Result<(), String> {
    if geometry.is_empty() {
        return if bvh.nodes.is_empty() {
            Ok(())
        } else {
            Err("nodes without triangles".into())
        };
    }
    let mut seen = vec![false; geometry.len()];
    for &id in &bvh.prim_ids {
        let slot = seen
            .get_mut(id as usize)
            .ok_or(format!("triangle id {id} out of range"))?;
        if std::mem::replace(slot, true) {
            return Err(format!("triangle {id} appears twice"));
        }
    }
    if seen.iter().any(|s| !s) || bvh.tris.len() != geometry.len() {
        return Err("a triangle is missing from the leaves".into());
    }
    let mut leaf_tris = 0;
    let mut stack = vec![(0usize, 0usize)];
    while let Some((i, depth)) = stack.pop() {
        if depth >= STACK_SIZE {
            return Err(format!("depth {depth} exceeds the traversal stack"));
        }
        let node = bvh.nodes.get(i).ok_or(format!("node {i} out of range"))?;
        let bounds = node.bounds();
        if node.is_leaf() {
            let first = node.first as usize;
            let end = first + node.count as usize;
            if end > bvh.tris.len() {
                return Err(format!("leaf {i} past the triangle array"));
            }
            for k in first..end {
                for p in geometry.corners(bvh.prim_ids[k] as usize) {
                    if !bounds.contains(p) {
                        return Err(format!("leaf {i} does not hold triangle {k}"));
                    }
                }
            }
            leaf_tris += node.count as usize;
        } else {
            for c in [node.first as usize, node.first as usize + 1] {
                let child = bvh.nodes.get(c).ok_or(format!("child {c} out of range"))?;
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
        if let Some(h) = tri.hit(ray, t_min, t_max) {
            t_max = h.t;
            best = Some(Hit {
                t: h.t,
                b1: h.b1,
                b2: h.b2,
                triangle: i as u32,
                instance: None,
            });
        }
    }
    best
}

/// True when any triangle of `geometry` meets the ray with `t` in `(t_min, t_max)`, found by
/// testing every triangle: the reference for [`Bvh::occluded`] and [`Bvh::occluded_from`].
pub fn occluded_brute_force(geometry: &Geometry, ray: &Ray, t_min: f32, t_max: f32) -> bool {
    (0..geometry.len()).any(|i| {
        let tri = accel(geometry.corners(i));
        tri.hit(ray, t_min, t_max).is_some()
    })
}
