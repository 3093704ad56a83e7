//! The second level: meshes built once into a BVH of their own (the bottom level, in object
//! space) and placed any number of times by instances, under a top-level BVH over the
//! instances' world boxes.
//!
//! The top-level tree is made of the same nodes by the same build as a [`Bvh`], with instance
//! indices where a mesh's tree has triangle indices, and no triangles. A ray walks it with the
//! same walks (`traverse::walk_nearest`, `traverse::walk_any`); at an instance it enters the
//! mesh's tree in object space through the instance's precomputed inverse. The direction is
//! mapped but not renormalized, so `t` means the same in both spaces and a hit needs no
//! conversion: the world point is `origin + t·direction` of the world ray.
//!
//! Which hit is closest follows the one-level rule extended to two: the smallest `t`, then
//! the world's own triangles before any instance, then the smaller instance index, then the
//! smaller triangle index in the mesh, so that the answer never depends on the order of the
//! visit.
//!
//! It is the engine's one second level ([`Placed`]) over binary trees, with the renderer's
//! queries. A world with cut-outs keeps two sets of instances over the same mesh trees (see
//! `cutouts`): the instances whose materials may cut and the others. Each set reports its
//! hits by the world's instance index.

use std::sync::Arc;

use glam::{Affine3A, Vec3, Vec3A};

use super::placed::{self, Placed};
use super::tree::{Filter, Keep, KeepAll};
use super::{build, traverse, Bvh, Tree};
use crate::geometry::{Hit, Mesh};
use crate::math::Ray;
use crate::simd::Baseline;

/// The renderer's second level: meshes built once, the instances that place them (each
/// placement's id is the world's instance index) and the top-level tree over those.
pub(crate) type Instances = Placed<Bvh>;

impl Instances {
    /// Instance `index`'s map from world to object space, and its mesh's tree.
    pub(super) fn placement(&self, index: u32) -> (&Affine3A, &Bvh) {
        let e = self.entry(index);
        (e.object_from_world, e.mesh)
    }

    /// The closest of `best` (a hit of the world's own triangles, or `None`) and every
    /// instance's hits with `t` in `(t_min, t_max)` that its alpha tests keep.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32, best: Option<Hit>) -> Option<Hit> {
        let world = (ray.origin, ray.direction);
        placed::closest::<_, Baseline>(self, world, (t_min, t_max), best, &mut ())
    }

    /// True when an instance meets the ray with `t` in `(t_min, t_max)` at a hit its alpha
    /// tests keep; stops at the first.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        placed::any::<_, Baseline>(self, (ray.origin, ray.direction), (t_min, t_max), &mut ())
    }

    /// True when an instance meets the segment from `origin` to `end` for some `t` in
    /// `(0, t_max)`, as the renderer's shadow queries define it. Each instance maps the two end
    /// points into its space and traces the segment between them there, exactly as the batched
    /// queries of `instance_batches` do, so a shadow ray gets the same answer whichever way it
    /// was grouped.
    #[inline]
    pub(super) fn occludes_segment(&self, origin: Vec3, end: Vec3, t_max: f32) -> bool {
        match self.filtered() {
            false => self.occludes_segment_with::<KeepAll>(origin, end, t_max),
            true => self.occludes_segment_with::<Filter>(origin, end, t_max),
        }
    }

    /// [`Instances::occludes_segment`] with each instance's filter as `K`.
    #[inline(always)]
    fn occludes_segment_with<'p, K: Keep<'p>>(
        &'p self,
        origin: Vec3,
        end: Vec3,
        t_max: f32,
    ) -> bool {
        let (top, ids) = self.top();
        if top.is_empty() {
            return false;
        }
        let world = Vec3A::from(end - origin);
        let (o, inv_dir) = (Vec3A::from(origin), world.recip());
        traverse::walk_any(top, (o, inv_dir), (0.0, t_max), 1.0, |slots| {
            ids[slots].iter().any(|&index| {
                let e = self.entry(index);
                let map = e.object_from_world;
                let (a, b) = (map.transform_point3(origin), map.transform_point3(end));
                let ray = Ray::new(a, b - a);
                (e.mesh).any::<Baseline, K>(&ray, (0.0, t_max), K::of(e.filter), &mut ())
            })
        })
    }
}

/// Each of `meshes` built once into a tree of its own, on the threads of `pool` when there is
/// one.
pub(super) fn build_meshes(meshes: &[Mesh], pool: Option<&rayon::ThreadPool>) -> Vec<Arc<Bvh>> {
    meshes
        .iter()
        .map(|m| {
            let corners = |i: usize| m.indices[i].map(|v| m.positions[v as usize]);
            Arc::new(build::build(m.len(), corners, pool))
        })
        .collect()
}
