//! A world's whole acceleration structure: the tree over its own triangles (every mesh used
//! once, copied into world space) and the [`Instances`] of meshes built once and placed many
//! times. Every query asks the first, then the second with what the first found.
//!
//! A world without instances is exactly the one-level [`Bvh`]: the same queries on the same
//! tree, so the same answers, bit for bit. After the first level's kernels have run, the
//! instances answer the renderer's batched shadow queries (fans, bundles of segments, shafts)
//! with the same kernels inside each instance the batch may meet (see `instance_batches`),
//! and its camera-ray packets one ray at a time, lane by lane.

use glam::Vec3;

use super::instance_batches;
use super::instances::Instances;
use super::{Bvh, Pairs, Segments};
use crate::geometry::{Geometry, Hit};
use crate::math::Ray;
use crate::simd::SimdPath;

/// The two levels of a world's acceleration structure.
#[derive(Clone, Debug, Default)]
pub struct Levels {
    flat: Bvh,
    instances: Instances,
}

impl Levels {
    /// The world's own triangles' tree and the instances.
    pub(crate) fn new(flat: Bvh, instances: Instances) -> Levels {
        Levels { flat, instances }
    }

    /// The tree over the world's own triangles.
    pub fn flat(&self) -> &Bvh {
        &self.flat
    }

    /// The meshes placed by instances.
    pub fn instances(&self) -> &Instances {
        &self.instances
    }

    /// Nodes of every tree.
    pub fn node_count(&self) -> usize {
        self.flat.node_count() + self.instances.node_count()
    }

    /// Checks the world's own tree against `geometry` (see [`Bvh::validate`]).
    pub fn validate(&self, geometry: &Geometry) -> Result<(), String> {
        self.flat.validate(geometry)
    }

    /// The closest hit with `t` in `(t_min, t_max)`, if any (see [`Bvh::intersect`]; ties
    /// across instances are broken as `instances` says).
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        let hit = self.flat.intersect(ray, t_min, t_max);
        self.instances.intersect(ray, t_min, t_max, hit)
    }

    /// True when any triangle meets the ray with `t` in `(t_min, t_max)`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.flat.occluded(ray, t_min, t_max) || self.instances.occluded(ray, t_min, t_max)
    }

    /// [`Bvh::intersect_from_on`] over both levels.
    pub fn intersect_from_on(
        &self,
        path: SimdPath,
        origin: Vec3,
        dirs: &[Vec3],
        t_min: f32,
        t_max: f32,
        hits: &mut [Option<Hit>],
    ) {
        self.flat
            .intersect_from_on(path, origin, dirs, t_min, t_max, hits);
        if !self.instances.is_empty() {
            for (&dir, hit) in dirs.iter().zip(hits) {
                let ray = Ray::new(origin, dir);
                *hit = self.instances.intersect(&ray, t_min, t_max, *hit);
            }
        }
    }

    /// [`Bvh::intersect_from`] over both levels, on this process's SIMD path.
    pub fn intersect_from(
        &self,
        origin: Vec3,
        dirs: &[Vec3],
        t_min: f32,
        t_max: f32,
        hits: &mut [Option<Hit>],
    ) {
        self.intersect_from_on(crate::simd::simd_path(), origin, dirs, t_min, t_max, hits);
    }

    /// [`Bvh::occlude_from_on`] over both levels.
    pub fn occlude_from_on(
        &self,
        path: SimdPath,
        origin: Vec3,
        ends: &[Vec3],
        t_max: f32,
        blocked: &mut [bool],
    ) {
        self.flat
            .occlude_from_on(path, origin, ends, t_max, blocked);
        if !self.instances.is_empty() {
            instance_batches::occlude_from(&self.instances, path, origin, ends, t_max, blocked);
        }
    }

    /// [`Bvh::occlude_from`] over both levels, on this process's SIMD path.
    pub fn occlude_from(&self, origin: Vec3, ends: &[Vec3], t_max: f32, blocked: &mut [bool]) {
        self.occlude_from_on(crate::simd::simd_path(), origin, ends, t_max, blocked);
    }

    /// [`Bvh::occluded_from`] over both levels.
    pub fn occluded_from(&self, origin: Vec3, ends: &[Vec3], t_max: f32, occluded: &mut [bool]) {
        occluded.fill(false);
        self.occlude_from(origin, ends, t_max, occluded);
    }

    /// [`Bvh::occlude_segments_on`] over both levels.
    pub fn occlude_segments_on(
        &self,
        path: SimdPath,
        segments: Segments,
        t_max: f32,
        blocked: &mut [bool],
    ) {
        self.flat
            .occlude_segments_on(path, segments, t_max, blocked);
        if !self.instances.is_empty() {
            instance_batches::occlude_segments(&self.instances, path, segments, t_max, blocked);
        }
    }

    /// [`Bvh::occlude_pairs_on`] over both levels.
    pub fn occlude_pairs_on(&self, path: SimdPath, pairs: Pairs, t_max: f32, blocked: &mut [bool]) {
        self.flat.occlude_pairs_on(path, pairs, t_max, blocked);
        if !self.instances.is_empty() {
            instance_batches::occlude_pairs(&self.instances, path, pairs, t_max, blocked);
        }
    }
}
