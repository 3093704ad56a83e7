//! Checks on the [`Bvh`]: the structural invariants (`validate`) and the brute-force
//! references every query must agree with ([`intersect_brute_force`],
//! [`occluded_brute_force`]), which test each triangle of the scene in turn.

use super::{accel, Bvh, STACK_SIZE};
use crate::geometry::{Geometry, Hit};
use crate::math::Ray;

/// Checks `bvh` against the geometry it was built from; see [`Bvh::validate`].
pub(super) fn validate(bvh: &Bvh, geometry: &Geometry) -> Result<(), String> {
    let all: Vec<u32> = (0..geometry.len() as u32).collect();
    validate_subset(bvh, geometry, &all, false)
}

/// Checks `bvh` against the triangles `ids` of `geometry` (increasing) that it was built
/// over: each appears exactly once, and every box holds its contents. The tree names them
/// by their index in `geometry`, or when `local` by their position in `ids`.
pub(super) fn validate_subset(
    bvh: &Bvh,
    geometry: &Geometry,
    ids: &[u32],
    local: bool,
) -> Result<(), String> {
    if ids.is_empty() {
        return if bvh.nodes.is_empty() {
            Ok(())
        } else {
            Err("nodes without triangles".into())
        };
    }
    // The triangle of `geometry` that prim id `id` names, if it is one of `ids`.
    let triangle = |id: u32| -> Option<usize> {
        match local {
            true => ids.get(id as usize).map(|&i| i as usize),
            false => ids.binary_search(&id).ok().map(|_| id as usize),
        }
    };
    let mut seen = vec![false; geometry.len()];
    for &id in &bvh.prim_ids {
        let slot = triangle(id)
            .and_then(|i| seen.get_mut(i))
            .ok_or(format!("triangle id {id} out of range"))?;
        if std::mem::replace(slot, true) {
            return Err(format!("triangle {id} appears twice"));
        }
    }
    if bvh.prim_ids.len() != ids.len() || bvh.tris.len() != ids.len() {
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
                let i = triangle(bvh.prim_ids[k]).ok_or("a leaf past the triangles")?;
                for p in geometry.corners(i) {
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
    if leaf_tris != ids.len() {
        return Err(format!(
            "leaves reach {leaf_tris} of {} triangles",
            ids.len()
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
