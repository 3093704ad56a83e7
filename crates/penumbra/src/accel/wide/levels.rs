//! Ray casting's two levels, as the renderer's `accel::levels` has them: a scene's own
//! triangles in one [`WideBvh`], and meshes built once into a [`WideBvh`] each (in object
//! space) and placed any number of times, under a top-level tree over the placements' world
//! boxes, the same binary [`BvhNode`]s the renderer's instances use (`accel::instances`).
//!
//! A ray enters a placement through its inverse, as in the renderer: the direction is mapped
//! but not renormalized, so `t` means the same in both spaces. The top-level boxes are tested
//! with Ize's conservative exit distance, as the wide nodes are, so a placement is never
//! skipped by a ray that meets it; inside, the watertight test runs on the mapped ray, so a
//! placed mesh is as watertight as the mesh (two placements that only meet along a seam share
//! no edge: each is exact alone).
//!
//! Every query asks the own level, then the placements the ray enters, with the same rule for
//! the closest hit: the smallest `t`, then the smallest geometry id, then primitive id. Hits
//! in a placement carry its geometry id and its index (`level`), from which its normal and
//! closest points are made with the placement's corners mapped to world space exactly as
//! `Geometry::append` maps a copy's: they are the copy's, bit for bit.
//!
//! Closest points: a placement's mesh tree is walked in object space with a box's distance
//! scaled by a lower bound of the map's smallest stretch (`1 / ‖M⁻¹‖_F`), so that no box
//! holding a nearer point is skipped, and each triangle is tested in world space.

use std::sync::Arc;

use glam::{Affine3A, DAffine3, Vec3, Vec3A};

use super::nearest::{Frame, Nearest};
use super::tree::{SlotHit, Stack, WideBvh};
use crate::accel::instances::{inverse, inverse_f64, world_box};
use crate::accel::placed::{self, Entry, Placements};
use crate::accel::prim::boundary::Boundary;
use crate::accel::prim::watertight::{unit_normal, PreparedRay};
use crate::accel::traverse::walk_nearest;
use crate::accel::{build, AlphaTests, BvhNode};
use crate::math::Transform;
use crate::simd::Isa;

/// The `level` of a hit on the scene's own triangles.
pub(crate) const OWN: u32 = u32::MAX;

/// One placement of a mesh, as given to [`WideLevels::new`].
#[derive(Clone, Debug)]
pub(crate) struct Placement {
    /// Index of its mesh tree.
    pub mesh: u32,
    /// The geometry id its hits report.
    pub geometry: u32,
    /// Object to world; invertible.
    pub transform: Transform,
    /// The alpha tests of the mesh's triangles under this placement's materials, if any may
    /// cut.
    pub alpha: Option<Arc<AlphaTests>>,
}

/// A placement ready for queries.
#[derive(Debug)]
struct Placed {
    placement: Placement,
    object_from_world: Affine3A,
    /// The same map in `f64`, for closest points.
    object_from_world_f64: DAffine3,
    /// A lower bound of the squared smallest stretch of the object-to-world map.
    shrink_sq: f64,
    /// How far, in object units, the placed corners (rounded to `f32` by the map) may be
    /// from the exact images of the mesh's: closest-point bounds in object space allow it.
    pad: f32,
}

/// The two levels of a ray-casting scene.
#[derive(Debug, Default)]
pub(crate) struct WideLevels {
    own: WideBvh,
    own_alpha: Option<Arc<AlphaTests>>,
    meshes: Vec<Arc<WideBvh>>,
    placed: Vec<Placed>,
    /// The top-level tree over the placements' world boxes, and the placement in each leaf
    /// slot.
    top: Vec<BvhNode>,
    top_ids: Vec<u32>,
}

/// A bound of how far `transform` puts a corner of `mesh` (whose placed box is `world`) from
/// its exact image: each coordinate of `M·c + t` in `f32` is off by less than `2⁻²⁰` of the
/// sum of the magnitudes it is made of.
fn rounding_pad(transform: &Transform, mesh: &crate::accel::Bvh, world: &crate::math::Aabb) -> f64 {
    let m = transform.world_from_object;
    let object = mesh.nodes().first().map_or(0.0, |root| {
        let b = root.bounds();
        b.max.abs().max(b.min.abs()).max_element()
    });
    let linear = [m.x_axis, m.y_axis, m.z_axis]
        .iter()
        .map(|c| c.truncate().length_squared())
        .sum::<f32>()
        .sqrt();
    let sizes = world.max.abs().max(world.min.abs()).max_element()
        + linear * object
        + m.w_axis.truncate().abs().max_element();
    sizes as f64 / 1_048_576.0
}

/// Each tree's part of the surface's border ([`WideBvh::border`]): the own tree's, and each
/// mesh's by index.
pub(crate) struct Borders<'a> {
    pub own: &'a [Boundary],
    pub meshes: Vec<&'a [Boundary]>,
}

impl WideLevels {
    /// The levels of `own` (its triangles' alpha tests `own_alpha`) and `placements` of
    /// `meshes`; the top-level tree is built on `pool` when given.
    pub fn new(
        own: WideBvh,
        own_alpha: Option<Arc<AlphaTests>>,
        meshes: Vec<Arc<WideBvh>>,
        placements: Vec<Placement>,
        pool: Option<&rayon::ThreadPool>,
    ) -> WideLevels {
        let boxes: Vec<_> = placements
            .iter()
            .map(|p| world_box(meshes[p.mesh as usize].bvh(), &p.transform))
            .collect();
        let (top, top_ids) = build::build_tree(boxes.len(), |i| boxes[i], pool);
        let placed = placements
            .into_iter()
            .zip(&boxes)
            .map(|(placement, world)| {
                let exact = inverse_f64(&placement.transform);
                let linear = glam::DMat3::from_mat4(exact);
                let frobenius_sq = [linear.x_axis, linear.y_axis, linear.z_axis]
                    .iter()
                    .map(|c| c.length_squared())
                    .sum::<f64>();
                let mesh = meshes[placement.mesh as usize].bvh();
                let pad = rounding_pad(&placement.transform, mesh, world) * frobenius_sq.sqrt();
                Placed {
                    object_from_world: inverse(&placement.transform),
                    object_from_world_f64: DAffine3::from_mat4(exact),
                    shrink_sq: (1.0 - 1e-6) / frobenius_sq,
                    pad: (pad * 1.001) as f32,
                    placement,
                }
            })
            .collect();
        WideLevels {
            own,
            own_alpha,
            meshes,
            placed,
            top,
            top_ids,
        }
    }

    /// The tree of the scene's own triangles.
    pub fn own(&self) -> &WideBvh {
        &self.own
    }

    /// The alpha tests of the own tree's triangles, when some may be cut out.
    pub fn own_alpha(&self) -> Option<&AlphaTests> {
        self.own_alpha.as_deref()
    }

    /// True when there are placements.
    pub fn has_placements(&self) -> bool {
        !self.placed.is_empty()
    }

    /// Triangles of the own tree and of each mesh tree, each counted once.
    pub fn unique_triangles(&self) -> usize {
        self.own.tris().len() + self.meshes.iter().map(|m| m.tris().len()).sum::<usize>()
    }

    /// Each tree's border, made on `pool` where it is not yet ([`WideBvh::border`]).
    pub fn borders(&self, pool: &rayon::ThreadPool) -> Borders<'_> {
        Borders {
            own: self.own.border(pool),
            meshes: self.meshes.iter().map(|m| m.border(pool)).collect(),
        }
    }

    /// The borders when every tree's is made.
    pub fn made_borders(&self) -> Option<Borders<'_>> {
        Some(Borders {
            own: self.own.made_border()?,
            meshes: self
                .meshes
                .iter()
                .map(|m| m.made_border())
                .collect::<Option<_>>()?,
        })
    }

    /// The closest of `best` (the own tree's closest hit) and the placements' hits of `ray`
    /// with `t` in `range`.
    #[inline(always)]
    pub fn closest_placed<I: Isa>(
        &self,
        ray: &[f32; 6],
        range: (f32, f32),
        best: Option<SlotHit>,
        stack: &mut Stack,
    ) -> Option<SlotHit> {
        placed::closest::<_, I>(self, world_ray(ray), range, best, stack)
    }

    /// True when a triangle of the own tree meets `prepared` with `t` in `range`.
    #[inline(always)]
    pub fn occluded_own<I: Isa>(
        &self,
        prepared: &PreparedRay,
        range: (f32, f32),
        stack: &mut Stack,
    ) -> bool {
        let own = self.own_alpha.as_deref();
        self.own.occluded::<I>(prepared, range, own, stack)
    }

    /// [`WideLevels::occluded_own`] of a stream of rays, `K` walks at a time:
    /// `done(index, occluded)`.
    #[inline(always)]
    pub fn occluded_own_stream<const K: usize, I: Isa>(
        &self,
        rays: impl Iterator<Item = (usize, Option<PreparedRay>)>,
        range: (f32, f32),
        stacks: [&mut Stack; K],
        done: impl FnMut(usize, bool),
    ) {
        let own = self.own_alpha.as_deref();
        self.own
            .occluded_stream::<K, I>(rays, range, own, stacks, done);
    }

    /// True when a triangle of a placement meets `ray` with `t` in `range`.
    #[inline(always)]
    pub fn occluded_placed<I: Isa>(
        &self,
        ray: &[f32; 6],
        range: (f32, f32),
        stack: &mut Stack,
    ) -> bool {
        placed::any::<_, I>(self, world_ray(ray), range, stack)
    }

    /// Calls `f` with every crossing of `prepared` with `t` in `range` in the own tree, one per
    /// crossing of its surface (see [`WideBvh::each_hit`]); the placements' are
    /// [`WideLevels::each_hit_placed`]'s.
    #[inline(always)]
    pub fn each_hit_own<I: Isa>(
        &self,
        prepared: &PreparedRay,
        range: (f32, f32),
        borders: &Borders,
        stack: &mut Stack,
        f: &mut impl FnMut(SlotHit),
    ) {
        let own = (borders.own, self.own_alpha.as_deref());
        self.own.each_hit::<I>(prepared, range, own, stack, f);
    }

    /// [`WideLevels::each_hit_own`] of a stream of rays, `K` walks at a time: `f(found, hit)`
    /// for each hit of a ray into its `found` (`start(index)` at first), then
    /// `done(index, found)`.
    #[allow(clippy::type_complexity)]
    #[inline(always)]
    pub fn each_hit_own_stream<const K: usize, S, I: Isa>(
        &self,
        rays: impl Iterator<Item = (usize, Option<PreparedRay>)>,
        range: (f32, f32),
        borders: &Borders,
        stacks: [&mut Stack; K],
        calls: (
            impl Fn(usize) -> S,
            impl FnMut(&mut S, SlotHit),
            impl FnMut(usize, S),
        ),
    ) {
        let own = (borders.own, self.own_alpha.as_deref());
        self.own
            .each_hit_stream::<K, S, I>(rays, range, own, stacks, calls);
    }

    /// [`WideLevels::each_hit_own`] of the placements: every crossing of `ray` with each placed
    /// mesh's surface (`borders` are every tree's, made).
    #[inline(always)]
    pub fn each_hit_placed<I: Isa>(
        &self,
        ray: &[f32; 6],
        range: (f32, f32),
        borders: &Borders,
        stack: &mut Stack,
        f: &mut impl FnMut(SlotHit),
    ) {
        debug_assert_eq!(borders.meshes.len(), self.meshes.len());
        placed::each::<_, I>(self, world_ray(ray), range, stack, f);
    }

    /// The unit normal of the triangle of a hit or closest point: leaf slot `slot` of the own
    /// tree (`level` [`OWN`]) or of placement `level`'s mesh, mapped as a copy's corners are.
    pub fn normal(&self, level: u32, slot: u32) -> [f32; 3] {
        let Some(p) = self.placed.get(level as usize) else {
            return self.own.normal(slot);
        };
        let mesh = &self.meshes[p.placement.mesh as usize];
        let t = &p.placement.transform;
        let corners = mesh
            .slot(slot as usize)
            .corners()
            .map(|c| Vec3A::from(t.point(Vec3::from(c))));
        unit_normal(&corners).to_array()
    }

    /// The closest point of any triangle to `p` (see `nearest`) if one is within squared
    /// distance `bound` (∞: any).
    #[inline(always)]
    pub fn nearest<I: Isa>(&self, p: Vec3, bound: f64, stack: &mut Stack) -> Option<Nearest> {
        let pa = p.as_dvec3();
        let (mut best, mut best_d) = (None, bound);
        self.own
            .nearest_within::<I>(pa, None, (&mut best_d, &mut best), stack);
        if self.top.is_empty() {
            return best;
        }
        let enter = |node: &BvhNode, bound: f64| {
            let d = super::nearest::box_distance_sq(node, pa);
            (d <= bound).then_some(d)
        };
        walk_nearest(&self.top, &mut best_d, enter, |slots, best_d| {
            for &index in &self.top_ids[slots] {
                let p = &self.placed[index as usize];
                let frame = Frame {
                    level: index,
                    geometry: p.placement.geometry,
                    to_object: &p.object_from_world_f64,
                    to_world: &p.placement.transform,
                    shrink_sq: p.shrink_sq,
                    pad: p.pad,
                };
                let mesh = &self.meshes[p.placement.mesh as usize];
                mesh.nearest_within::<I>(pa, Some(&frame), (best_d, &mut best), stack);
            }
        });
        best
    }
}

/// A ray's origin and direction from its six coordinates.
#[inline(always)]
fn world_ray(ray: &[f32; 6]) -> (Vec3, Vec3) {
    (
        Vec3::new(ray[0], ray[1], ray[2]),
        Vec3::new(ray[3], ray[4], ray[5]),
    )
}

impl Placements for WideLevels {
    type Tree = WideBvh;

    #[inline(always)]
    fn top(&self) -> (&[BvhNode], &[u32]) {
        (&self.top, &self.top_ids)
    }

    #[inline(always)]
    fn entry(&self, index: u32) -> Entry<'_, WideBvh> {
        let p = &self.placed[index as usize];
        let mesh = &self.meshes[p.placement.mesh as usize];
        Entry {
            object_from_world: &p.object_from_world,
            mesh,
            id: p.placement.geometry,
            filter: p.placement.alpha.as_deref(),
            // Made by `borders` before any query that counts.
            border: mesh.made_border(),
        }
    }
}
