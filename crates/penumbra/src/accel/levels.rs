//! A world's whole acceleration structure: the tree over its own triangles (every mesh used
//! once, copied into world space) and the [`Instances`] of meshes built once and placed many
//! times. Every query asks the first, then the second with what the first found.
//!
//! A world without instances is exactly the one-level [`Bvh`]: the same queries on the same
//! tree, so the same answers, bit for bit. After the first level's kernels have run, the
//! instances answer the renderer's batched shadow queries (fans, bundles of segments, shafts)
//! with the same kernels inside each instance the batch may meet (see `instance_batches`),
//! and its camera-ray packets one ray at a time, lane by lane.
//!
//! A world with cut-out materials has cut-out levels too (see `cutouts`): every query asks
//! them last, and a batched query asks them for each of its rays still open, one at a time.

use std::borrow::Cow;
use std::sync::Arc;

use glam::Vec3;

use super::cutouts::{self, Cutouts, Parts};
use super::instance_batches;
use super::instances::Instances;
use super::{build, Bvh, Pairs, Segments};
use crate::geometry::{Geometry, Hit};
use crate::math::{Ray, Transform};
use crate::simd::SimdPath;

/// The two levels of a world's acceleration structure.
#[derive(Clone, Debug, Default)]
pub struct Levels {
    /// Shared by `Arc`: a world with moved instances shares it.
    flat: Arc<Bvh>,
    instances: Instances,
    /// The levels of the triangles whose material may cut; `None` in a world without.
    cutouts: Option<Box<Cutouts>>,
}

impl Levels {
    /// The levels of a world's `parts`, built on the threads of `pool` when there is one.
    pub(crate) fn build(parts: &Parts, pool: Option<&rayon::ThreadPool>) -> Levels {
        let (flat, instances, cutouts) = cutouts::split(parts, pool);
        Levels {
            flat: Arc::new(flat),
            instances,
            cutouts: cutouts.map(Box::new),
        }
    }

    /// True when some triangle's material may cut (then [`Levels::flat`] and
    /// [`Levels::instances`] hold the opaque ones only).
    pub fn has_cutouts(&self) -> bool {
        self.cutouts.is_some()
    }

    /// The tree over the world's own triangles (their opaque ones, with cut-outs).
    pub fn flat(&self) -> &Bvh {
        &self.flat
    }

    /// The tree over all of the world's own triangles (`geometry`), naming each by its index
    /// there: [`Levels::flat`], or with cut-outs the opaque and the cut-out trees under one
    /// new root, nothing built (unless that root would make the tree deeper than a build
    /// makes one: then it is built).
    pub(crate) fn own_tree(&self, geometry: &Geometry) -> Cow<'_, Bvh> {
        let Some(cut) = &self.cutouts else {
            return Cow::Borrowed(&self.flat);
        };
        let joined = build::join(Bvh::clone(&self.flat), cut.flat_in_world());
        Cow::Owned(joined.unwrap_or_else(|| Bvh::build(geometry)))
    }

    /// The meshes placed by instances.
    pub(crate) fn instances(&self) -> &Instances {
        &self.instances
    }

    /// Moves instances: the transform of each instance (by its world index) of `moves` is
    /// replaced by its new one (invertible), and the top level of each set of instances that
    /// holds one is built again; the mesh trees are untouched.
    pub(crate) fn set_transforms(&mut self, moves: &[(usize, Transform)]) {
        let sets = [
            Some(&mut self.instances),
            self.cutouts.as_mut().map(|c| c.instances_mut()),
        ];
        for set in sets.into_iter().flatten() {
            let mine: Vec<(usize, Transform)> = (moves.iter())
                .filter_map(|&(id, t)| Some((set.position(id as u32)?, t)))
                .collect();
            if !mine.is_empty() {
                set.set_transforms(&mine, None);
            }
        }
    }

    /// Nodes of every tree.
    pub fn node_count(&self) -> usize {
        let cut = self.cutouts.as_ref().map_or(0, |c| c.node_count());
        self.flat.node_count() + self.instances.node_count() + cut
    }

    /// Checks the trees of the world's own triangles against `geometry` (see
    /// [`Bvh::validate`]): with cut-outs, the opaque tree and the cut-out tree each hold
    /// their part, and together every triangle once.
    pub fn validate(&self, geometry: &Geometry) -> Result<(), String> {
        let Some(cut) = &self.cutouts else {
            return self.flat.validate(geometry);
        };
        let ids = cut.triangles();
        let opaque: Vec<u32> = (0..geometry.len() as u32)
            .filter(|i| ids.binary_search(i).is_err())
            .collect();
        super::validate::validate_subset(&self.flat, geometry, &opaque, false)?;
        super::validate::validate_subset(cut.flat(), geometry, ids, true)
    }

    /// The closest hit with `t` in `(t_min, t_max)`, if any (see [`Bvh::intersect`]; ties
    /// across instances are broken as `instances` says).
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        let hit = self.flat.intersect(ray, t_min, t_max);
        let hit = self.instances.intersect(ray, t_min, t_max, hit);
        match &self.cutouts {
            None => hit,
            Some(cut) => cut.intersect(ray, t_min, t_max, hit),
        }
    }

    /// True when any triangle meets the ray with `t` in `(t_min, t_max)`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.flat.occluded(ray, t_min, t_max)
            || self.instances.occluded(ray, t_min, t_max)
            || self
                .cutouts
                .as_ref()
                .is_some_and(|c| c.occluded(ray, t_min, t_max))
    }

    /// [`Bvh::intersect_from_on`] over both levels.
    #[doc(hidden)]
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
            for (&dir, hit) in dirs.iter().zip(hits.iter_mut()) {
                let ray = Ray::new(origin, dir);
                *hit = self.instances.intersect(&ray, t_min, t_max, *hit);
            }
        }
        if let Some(cut) = &self.cutouts {
            for (&dir, hit) in dirs.iter().zip(hits) {
                *hit = cut.intersect(&Ray::new(origin, dir), t_min, t_max, *hit);
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
    #[doc(hidden)]
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
        if let Some(cut) = &self.cutouts {
            for (&end, b) in ends.iter().zip(blocked) {
                *b = *b || cut.occludes_segment(origin, end, t_max);
            }
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
    #[doc(hidden)]
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
        if let Some(cut) = &self.cutouts {
            let (o, e) = (segments.origin, segments.end);
            for (i, b) in blocked.iter_mut().enumerate() {
                *b = *b || cut.occludes_segment(point(o, i), point(e, i), t_max);
            }
        }
    }

    /// [`Bvh::occlude_pairs_on`] over both levels.
    #[doc(hidden)]
    pub fn occlude_pairs_on(&self, path: SimdPath, pairs: Pairs, t_max: f32, blocked: &mut [bool]) {
        self.flat.occlude_pairs_on(path, pairs, t_max, blocked);
        if !self.instances.is_empty() {
            instance_batches::occlude_pairs(&self.instances, path, pairs, t_max, blocked);
        }
        if let Some(cut) = &self.cutouts {
            let (o, e) = (pairs.origins, pairs.ends);
            let m = o[0].len().max(1);
            for (k, b) in blocked.iter_mut().enumerate() {
                *b = *b || cut.occludes_segment(point(o, k % m), point(e, k / m), t_max);
            }
        }
    }
}

/// Point `i` of coordinate slices `c`.
fn point(c: [&[f32]; 3], i: usize) -> Vec3 {
    Vec3::new(c[0][i], c[1][i], c[2][i])
}
