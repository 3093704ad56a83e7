//! Cut-outs in the engine: the triangles whose material may cut (see [`Cutout`]) kept apart
//! from the opaque ones, and walked with an alpha test on each hit.
//!
//! A world with cut-out materials splits its triangles in two when it is built. The opaque
//! ones (the world's own, and the instances whose materials cannot cut) form the levels every
//! kernel already walks: single rays, fans, bundles, shafts, the batches inside instances.
//! The cut-out ones form a second pair of levels of the same kind ([`Cutouts`]): a tree over
//! the world's own cut-out triangles, with their alpha tests, and the instances whose
//! materials may cut, over the same mesh trees, each with the alpha tests of its mesh under
//! its materials (one set for each mesh and materials, shared; ray casting makes the same
//! sets with the same function, [`AlphaTests::of_placement`]). Those are walked by the
//! single-ray queries of [`Tree`](super::Tree) and [`placed`](super::placed) with the tests
//! as their hit filter: a hit the alpha test refuses does not shorten a closest-hit ray, and
//! an any-hit walk looks on past it. The batched kernels are not changed: after them, each of
//! a batch's rays or segments not yet blocked (or its closest hit, for a camera fan) asks the
//! cut-out levels on its own.
//!
//! So a world without cut-out materials has no cut-out levels, and its queries are exactly
//! those of before; and each ray gets the same answer whichever way it was grouped, since the
//! opaque kernels agree with the single-ray walks and the cut-out part is asked one ray at a
//! time. The alpha test is one function ([`Cutout::keeps`] at the uv the hit's barycentrics
//! interpolate, `alpha::AlphaTests::keeps`) on every path.

mod alpha;

use std::collections::HashMap;
use std::sync::Arc;

use glam::Vec3;

use super::instances::{build_meshes, Instances};
use super::placed::{closer, Placed, Placement};
use super::tree::Filter;
use super::{build, Bvh, Tree};
use crate::geometry::{Geometry, Hit, Mesh};
use crate::material::Material;
use crate::math::{Ray, Transform};
use crate::simd::Baseline;
use crate::texture::Texture;
pub(crate) use alpha::AlphaTests;

/// A world's parts, as the engine is built from them.
pub(crate) struct Parts<'a> {
    /// The world's own triangles.
    pub geometry: &'a Geometry,
    /// The meshes placed by instances.
    pub meshes: &'a [Mesh],
    /// Each instance: its mesh, its object-to-world transform (invertible), and the
    /// materials its mesh's slots map to.
    pub instances: Vec<(u32, Transform, &'a [u32])>,
    /// The world's materials.
    pub materials: &'a [Material],
    /// The world's textures.
    pub textures: &'a [Texture],
}

/// The cut-out levels: the world's own cut-out triangles and the instances whose materials
/// may cut, with the alpha tests of their hits.
#[derive(Clone, Debug)]
pub(crate) struct Cutouts {
    /// The tree over the world's own cut-out triangles, numbered in the order of the world's
    /// (shared by `Arc`, as the ids and tests are: a world with moved instances shares them).
    flat: Arc<Bvh>,
    /// The world's index of each of those.
    flat_ids: Arc<[u32]>,
    /// The instances whose materials may cut.
    instances: Instances,
    alpha: Arc<AlphaTests>,
}

/// The opaque levels (the world's own opaque triangles' tree and the other instances) and,
/// when some triangle's material may cut, the cut-out levels.
pub(crate) fn split(
    parts: &Parts,
    pool: Option<&rayon::ThreadPool>,
) -> (Bvh, Instances, Option<Cutouts>) {
    let placement = |index: usize, alpha: Option<Arc<AlphaTests>>| {
        let (mesh, transform, _) = parts.instances[index];
        Placement {
            mesh,
            id: index as u32,
            transform,
            alpha,
        }
    };
    let meshes = match parts.instances.is_empty() {
        true => Vec::new(),
        false => build_meshes(parts.meshes, pool),
    };
    let geometry = parts.geometry;
    let used = |a: &AlphaTests| {
        geometry.triangles.iter().any(|t| a.cuts(t.material))
            || parts.instances.iter().any(|i| a.instance_cuts(i.2))
    };
    let Some(mut alpha) = AlphaTests::of(parts.materials, parts.textures).filter(used) else {
        // Nothing is cut out: the levels of a world without cut-outs.
        let flat = build::build(geometry.len(), |i| geometry.corners(i), pool);
        let all = (0..parts.instances.len()).map(|i| placement(i, None));
        let instances = Placed::new(meshes, all.collect(), pool);
        return (flat, instances, None);
    };
    let (cut, opaque): (Vec<u32>, Vec<u32>) = (0..geometry.len() as u32)
        .partition(|&i| alpha.cuts(geometry.triangles[i as usize].material));
    let flat = subset(geometry, &opaque, pool);
    let cut_flat = build::build(cut.len(), |j| geometry.corners(cut[j] as usize), pool);
    for &i in &cut {
        alpha.push_flat(geometry, i as usize);
    }
    // `cut` is in the world's order (a partition keeps it), so the cut-out tree's tie rule
    // (the smaller number) agrees with the world's.
    let (mut cut_list, mut opaque_list) = (Vec::new(), Vec::new());
    // One set of tests for each mesh and materials, shared by the instances that have them.
    let mut tests = HashMap::new();
    for (index, &(mesh, _, materials)) in parts.instances.iter().enumerate() {
        let of = || {
            alpha
                .of_placement(&parts.meshes[mesh as usize], materials)
                .map(Arc::new)
        };
        match tests.entry((mesh, materials)).or_insert_with(of).clone() {
            Some(tests) => cut_list.push(placement(index, Some(tests))),
            None => opaque_list.push(placement(index, None)),
        }
    }
    let instances = Placed::new(meshes.clone(), opaque_list, pool);
    let cut_instances = Placed::new(meshes, cut_list, pool);
    let cutouts = Cutouts {
        flat: Arc::new(cut_flat),
        flat_ids: cut.into(),
        instances: cut_instances,
        alpha: Arc::new(alpha),
    };
    (flat, instances, Some(cutouts))
}

/// The tree over the triangles `ids` of `geometry`, reporting their indices in `geometry`.
fn subset(geometry: &Geometry, ids: &[u32], pool: Option<&rayon::ThreadPool>) -> Bvh {
    let mut bvh = build::build(ids.len(), |j| geometry.corners(ids[j] as usize), pool);
    for id in &mut bvh.prim_ids {
        *id = ids[*id as usize];
    }
    bvh
}

impl Cutouts {
    /// Nodes of the cut-out trees (the mesh trees are counted with the opaque instances').
    pub(crate) fn node_count(&self) -> usize {
        self.flat.node_count() + self.instances.top_node_count()
    }

    /// The world's own cut-out triangles, by their index in the world's geometry.
    pub(crate) fn triangles(&self) -> &[u32] {
        &self.flat_ids
    }

    /// The tree over the world's own cut-out triangles.
    pub(crate) fn flat(&self) -> &Bvh {
        &self.flat
    }

    /// The instances whose materials may cut.
    pub(crate) fn instances_mut(&mut self) -> &mut Instances {
        &mut self.instances
    }

    /// [`Cutouts::flat`], naming its triangles by their index in the world's geometry.
    pub(crate) fn flat_in_world(&self) -> Bvh {
        let mut bvh = Bvh::clone(&self.flat);
        for id in &mut bvh.prim_ids {
            *id = self.flat_ids[*id as usize];
        }
        bvh
    }

    /// The closest of `best` and the kept hits of cut-out triangles with `t` in `(t_min,
    /// t_max)`, by the rule of `placed::closer` (ties go to the smaller key).
    pub(crate) fn intersect(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        best: Option<Hit>,
    ) -> Option<Hit> {
        // Ties with `best` are looked for too: a smaller key may take them.
        let limit = best.map_or(t_max, |b| b.t.next_up());
        let own =
            self.flat
                .closest::<Baseline, Filter>(ray, (t_min, limit), Some(&self.alpha), &mut ());
        let own = own.map(|h| Hit {
            triangle: self.flat_ids[h.triangle as usize],
            ..h
        });
        let best = match (best, own) {
            (Some(b), Some(h)) if !closer::<Bvh>(&h, &b) => Some(b),
            (b, h) => h.or(b),
        };
        self.instances.intersect(ray, t_min, t_max, best)
    }

    /// True when a kept hit of a cut-out triangle meets the ray with `t` in `(t_min, t_max)`.
    pub(crate) fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.flat
            .any::<Baseline, Filter>(ray, (t_min, t_max), Some(&self.alpha), &mut ())
            || self.instances.occluded(ray, t_min, t_max)
    }

    /// True when a kept hit of a cut-out triangle meets the segment from `origin` to `end`
    /// for some `t` in `(0, t_max)`, as the renderer's shadow queries define it (an
    /// instance traces the segment between the mapped end points).
    pub(crate) fn occludes_segment(&self, origin: Vec3, end: Vec3, t_max: f32) -> bool {
        let ray = Ray::new(origin, end - origin);
        self.flat
            .any::<Baseline, Filter>(&ray, (0.0, t_max), Some(&self.alpha), &mut ())
            || self.instances.occludes_segment(origin, end, t_max)
    }
}
