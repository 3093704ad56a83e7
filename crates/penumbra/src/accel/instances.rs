//! The second level: meshes built once into a BVH of their own (the bottom level, in object
//! space) and placed any number of times by instances, under a top-level BVH over the
//! instances' world boxes.
//!
//! The top-level tree is a [`Bvh`] like any other: the same nodes and build, with instance
//! indices where a mesh's tree has triangle indices, and no triangles. A ray walks it with the
//! same walks (`traverse::walk_closest`, `traverse::walk_any`); at an instance it enters the
//! mesh's tree in object space through the instance's precomputed inverse. The direction is
//! mapped but not renormalized, so `t` means the same in both spaces and a hit needs no
//! conversion: the world point is `origin + t·direction` of the world ray.
//!
//! Which hit is closest follows the one-level rule extended to two: the smallest `t`, then
//! the world's own triangles before any instance, then the smaller instance index, then the
//! smaller triangle index in the mesh, so that the answer never depends on the order of the
//! visit.
//!
//! A world with cut-outs keeps two sets of instances over the same mesh trees (see
//! `cutouts`): the instances whose materials may cut and the others. Each set reports its
//! hits by the world's instance index.

use std::sync::Arc;

use glam::{Affine3A, DMat4, Vec3, Vec3A};

use super::placed::{self, Entry, Placements};
use super::{build, traverse, AlphaTests, Bvh, BvhNode, Tree};
use crate::geometry::{Hit, Mesh};
use crate::math::{Aabb, Ray, Transform};
use crate::simd::Baseline;

/// Meshes built once, the instances that place them, and the top-level tree over those.
#[derive(Clone, Debug, Default)]
pub struct Instances {
    meshes: Arc<Vec<Bvh>>,
    placements: Vec<Placement>,
    top: Bvh,
    /// The world's index of each placement, when the placements are some of the world's
    /// instances (empty: all of them, in order).
    ids: Vec<u32>,
}

/// Where an instance puts its mesh: the mesh's index, the map from world to object space, and
/// the alpha tests of its mesh's triangles under its materials when some may cut.
#[derive(Clone, Debug)]
struct Placement {
    mesh: u32,
    object_from_world: Affine3A,
    alpha: Option<Arc<AlphaTests>>,
}

impl Instances {
    /// Builds each of `meshes` once and the top-level tree over `instances`: for each, the
    /// index of its mesh and its object-to-world transform, which must be invertible. On the
    /// threads of `pool` when there is one.
    pub(crate) fn build(
        meshes: &[Mesh],
        instances: &[(u32, Transform)],
        pool: Option<&rayon::ThreadPool>,
    ) -> Instances {
        if instances.is_empty() {
            return Instances::default();
        }
        let opaque = vec![None; instances.len()];
        Instances::place(
            build_meshes(meshes, pool),
            instances,
            (Vec::new(), opaque),
            pool,
        )
    }

    /// The top-level tree over `instances` (mesh index into `meshes` and transform) placing
    /// the mesh trees `meshes` (kept, and counted by [`Instances::node_count`], even without
    /// instances); `ids` are their world indices (empty: `0, 1, …`), `alphas` their alpha
    /// tests (one for each instance).
    pub(super) fn place(
        meshes: Arc<Vec<Bvh>>,
        instances: &[(u32, Transform)],
        (ids, alphas): (Vec<u32>, Vec<Option<Arc<AlphaTests>>>),
        pool: Option<&rayon::ThreadPool>,
    ) -> Instances {
        let boxes: Vec<Aabb> = instances
            .iter()
            .map(|(mesh, transform)| world_box(&meshes[*mesh as usize], transform))
            .collect();
        let (nodes, prim_ids) = build::build_tree(boxes.len(), |i| boxes[i], pool);
        let placements = instances
            .iter()
            .zip(alphas)
            .map(|((mesh, transform), alpha)| Placement {
                mesh: *mesh,
                object_from_world: inverse(transform),
                alpha,
            })
            .collect();
        Instances {
            meshes,
            placements,
            top: Bvh {
                nodes,
                tris: Vec::new(),
                prim_ids,
            },
            ids,
        }
    }

    /// The world's index of placement `index`.
    #[inline(always)]
    fn id(&self, index: u32) -> u32 {
        self.ids.get(index as usize).copied().unwrap_or(index)
    }

    /// Nodes of the top-level tree alone.
    pub(super) fn top_node_count(&self) -> usize {
        self.top.node_count()
    }

    /// True when there are no instances.
    pub fn is_empty(&self) -> bool {
        self.placements.is_empty()
    }

    /// The tree of each mesh, by mesh index (all of a world's meshes when it has instances,
    /// whichever set places them).
    pub(crate) fn mesh_trees(&self) -> &[Bvh] {
        &self.meshes
    }

    /// Number of instances.
    pub fn len(&self) -> usize {
        self.placements.len()
    }

    /// Nodes of the top-level tree and of every mesh's tree.
    pub fn node_count(&self) -> usize {
        self.top.node_count() + self.meshes.iter().map(Bvh::node_count).sum::<usize>()
    }

    /// Triangles of the meshes, each counted once however many instances place it.
    pub fn unique_triangles(&self) -> usize {
        self.meshes.iter().map(|m| m.tris.len()).sum()
    }

    /// Instance `index`'s map from world to object space, and its mesh's tree.
    pub(super) fn placement(&self, index: u32) -> (&Affine3A, &Bvh) {
        let p = &self.placements[index as usize];
        (&p.object_from_world, &self.meshes[p.mesh as usize])
    }

    /// Appends to `out` every instance whose (padded) box meets `bounds`, in the tree's order.
    pub(super) fn overlapping(&self, bounds: &Aabb, out: &mut Vec<u32>) {
        if self.top.nodes.is_empty() || bounds.is_empty() {
            return;
        }
        let mut stack = vec![0u32];
        while let Some(index) = stack.pop() {
            let node = &self.top.nodes[index as usize];
            let b = node.bounds();
            if b.min.cmpgt(bounds.max).any() || b.max.cmplt(bounds.min).any() {
                continue;
            }
            if node.is_leaf() {
                let first = node.first as usize;
                out.extend_from_slice(&self.top.prim_ids[first..first + node.count as usize]);
            } else {
                stack.extend([node.first + 1, node.first]);
            }
        }
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
}

impl Placements for Instances {
    type Tree = Bvh;

    #[inline(always)]
    fn top(&self) -> (&[BvhNode], &[u32]) {
        (&self.top.nodes, &self.top.prim_ids)
    }

    #[inline(always)]
    fn entry(&self, index: u32) -> Entry<'_, Bvh> {
        let p = &self.placements[index as usize];
        Entry {
            object_from_world: &p.object_from_world,
            mesh: &self.meshes[p.mesh as usize],
            id: self.id(index),
            filter: p.alpha.as_deref(),
            border: None,
        }
    }
}

impl Instances {
    /// True when an instance meets the segment from `origin` to `end` for some `t` in
    /// `(0, t_max)`, as the renderer's shadow queries define it. Each instance maps the two end
    /// points into its space and traces the segment between them there, exactly as the batched
    /// queries of `instance_batches` do, so a shadow ray gets the same answer whichever way it
    /// was grouped.
    #[inline]
    pub(super) fn occludes_segment(&self, origin: Vec3, end: Vec3, t_max: f32) -> bool {
        if self.top.nodes.is_empty() {
            return false;
        }
        let world = Vec3A::from(end - origin);
        let (o, inv_dir) = (Vec3A::from(origin), world.recip());
        traverse::walk_any(&self.top.nodes, (o, inv_dir), (0.0, t_max), 1.0, |slots| {
            self.top.prim_ids[slots].iter().any(|&index| {
                let e = self.entry(index);
                let map = e.object_from_world;
                let (a, b) = (map.transform_point3(origin), map.transform_point3(end));
                let ray = Ray::new(a, b - a);
                e.mesh
                    .any::<Baseline>(&ray, (0.0, t_max), e.filter, &mut ())
            })
        })
    }
}

/// Each of `meshes` built once into a tree of its own, on the threads of `pool` when there is
/// one.
pub(super) fn build_meshes(meshes: &[Mesh], pool: Option<&rayon::ThreadPool>) -> Arc<Vec<Bvh>> {
    let trees = meshes
        .iter()
        .map(|m| {
            let corners = |i: usize| m.indices[i].map(|v| m.positions[v as usize]);
            build::build(m.len(), corners, pool)
        })
        .collect();
    Arc::new(trees)
}

/// The world-space box of `mesh` placed by `transform`: its root box placed, grown by a
/// relative 2⁻¹⁶ of its size and position for the rounding of the map, so that it holds every
/// point a ray can hit on the placed mesh.
pub(super) fn world_box(mesh: &Bvh, transform: &Transform) -> Aabb {
    let Some(root) = mesh.nodes.first() else {
        return Aabb::EMPTY;
    };
    let world = root.bounds().transformed(transform);
    let pad = (world.max - world.min + world.max.abs().max(world.min.abs())) * (1.0 / 65536.0);
    Aabb {
        min: world.min - pad,
        max: world.max + pad,
    }
}

/// The world-to-object map of `transform`, inverted in double precision.
pub(super) fn inverse(transform: &Transform) -> Affine3A {
    Affine3A::from_mat4(DMat4::as_mat4(&inverse_f64(transform)))
}

/// The world-to-object map of `transform` in double precision, of which [`inverse`] is the
/// `f32` form.
pub(super) fn inverse_f64(transform: &Transform) -> DMat4 {
    transform.world_from_object.as_dmat4().inverse()
}
