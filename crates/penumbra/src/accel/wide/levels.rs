//! Ray casting's two levels, as the renderer's `accel::levels` has them: a scene's own
//! triangles in one [`WideBvh`], and meshes built once into a [`WideBvh`] each (in object
//! space) and placed any number of times: the engine's one second level,
//! [`Placed`]`<WideBvh>` (`accel::placed`), as the renderer's instances are `Placed<Bvh>`.
//! Beside it, each placement's reach for closest points (its map in `f64`). Moving
//! placements ([`WideLevels::replaced`]) keeps every tree but the top one.
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

use glam::{DAffine3, Vec3, Vec3A};

use super::nearest::{Frame, Nearest};
use super::tree::{SlotHit, Stack, WideBvh};
use crate::accel::placed::{self, inverse_f64, world_box, Placed, Placement};
use crate::accel::prim::boundary::Boundary;
use crate::accel::prim::watertight::{unit_normal, PreparedRay};
use crate::accel::traverse::walk_nearest;
use crate::accel::{AlphaTests, BvhNode};
use crate::math::Transform;
use crate::simd::Isa;

/// What the closest-point walk needs of a placement beyond its map.
#[derive(Debug)]
struct Reach {
    /// The world-to-object map in `f64`.
    object_from_world: DAffine3,
    /// A lower bound of the squared smallest stretch of the object-to-world map.
    shrink_sq: f64,
    /// How far, in object units, the placed corners (rounded to `f32` by the map) may be
    /// from the exact images of the mesh's: closest-point bounds in object space allow it.
    pad: f32,
}

/// The two levels of a ray-casting scene.
#[derive(Debug, Default)]
pub(crate) struct WideLevels {
    own: Arc<WideBvh>,
    own_alpha: Option<Arc<AlphaTests>>,
    placed: Placed<WideBvh>,
    /// Each placement's [`Reach`].
    reaches: Vec<Reach>,
}

/// The [`Reach`] of `placement` of `mesh`.
fn reach(placement: &Placement, mesh: &WideBvh) -> Reach {
    let exact = inverse_f64(&placement.transform);
    let linear = glam::DMat3::from_mat4(exact);
    let frobenius_sq = [linear.x_axis, linear.y_axis, linear.z_axis]
        .iter()
        .map(|c| c.length_squared())
        .sum::<f64>();
    let world = world_box(mesh.bvh(), &placement.transform);
    let pad = rounding_pad(&placement.transform, mesh.bvh(), &world) * frobenius_sq.sqrt();
    Reach {
        object_from_world: DAffine3::from_mat4(exact),
        shrink_sq: (1.0 - 1e-6) / frobenius_sq,
        pad: (pad * 1.001) as f32,
    }
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
        own: Arc<WideBvh>,
        own_alpha: Option<Arc<AlphaTests>>,
        meshes: Vec<Arc<WideBvh>>,
        placements: Vec<Placement>,
        pool: Option<&rayon::ThreadPool>,
    ) -> WideLevels {
        let reaches = (placements.iter())
            .map(|p| reach(p, &meshes[p.mesh as usize]))
            .collect();
        WideLevels {
            own,
            own_alpha,
            placed: Placed::new(meshes, placements, pool),
            reaches,
        }
    }

    /// These levels with `placements` (of the same meshes) in place of theirs: the own tree
    /// and the mesh trees shared, the top level built again on `pool` when given.
    pub fn replaced(&self, placements: Vec<Placement>, pool: Option<&rayon::ThreadPool>) -> Self {
        let meshes = self.placed.meshes().to_vec();
        WideLevels::new(
            self.own.clone(),
            self.own_alpha.clone(),
            meshes,
            placements,
            pool,
        )
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
        !self.placed.placements().is_empty()
    }

    /// Triangles of the own tree and of each mesh tree, each counted once.
    pub fn unique_triangles(&self) -> usize {
        let meshes = self.placed.meshes().iter();
        self.own.tris().len() + meshes.map(|m| m.tris().len()).sum::<usize>()
    }

    /// Each tree's border, made on `pool` where it is not yet ([`WideBvh::border`]).
    pub fn borders(&self, pool: &rayon::ThreadPool) -> Borders<'_> {
        Borders {
            own: self.own.border(pool),
            meshes: self
                .placed
                .meshes()
                .iter()
                .map(|m| m.border(pool))
                .collect(),
        }
    }

    /// The borders when every tree's is made.
    pub fn made_borders(&self) -> Option<Borders<'_>> {
        Some(Borders {
            own: self.own.made_border()?,
            meshes: (self.placed.meshes().iter())
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
        placed::closest::<_, I>(&self.placed, world_ray(ray), range, best, stack)
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
        placed::any::<_, I>(&self.placed, world_ray(ray), range, stack)
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
        debug_assert_eq!(borders.meshes.len(), self.placed.meshes().len());
        placed::each::<_, I>(&self.placed, world_ray(ray), range, stack, f);
    }

    /// The unit normal of the triangle of a hit or closest point: leaf slot `slot` of the own
    /// tree (`level` `OWN`) or of placement `level`'s mesh, mapped as a copy's corners are.
    pub fn normal(&self, level: u32, slot: u32) -> [f32; 3] {
        let Some(p) = self.placed.placements().get(level as usize) else {
            return self.own.normal(slot);
        };
        let mesh = &self.placed.meshes()[p.mesh as usize];
        let t = &p.transform;
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
        let (top, ids) = self.placed.top();
        if top.is_empty() {
            return best;
        }
        let enter = |node: &BvhNode, bound: f64| {
            let d = super::nearest::box_distance_sq(node, pa);
            (d <= bound).then_some(d)
        };
        walk_nearest(top, &mut best_d, enter, |slots, best_d| {
            for &index in &ids[slots] {
                let p = &self.placed.placements()[index as usize];
                let r = &self.reaches[index as usize];
                let frame = Frame {
                    level: index,
                    geometry: p.id,
                    to_object: &r.object_from_world,
                    to_world: &p.transform,
                    shrink_sq: r.shrink_sq,
                    pad: r.pad,
                };
                let mesh = &self.placed.meshes()[p.mesh as usize];
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
