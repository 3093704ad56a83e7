//! The second level, written once over any [`Tree`]: meshes built once (in object space) and
//! placed any number of times ([`Placement`]), under a top-level binary tree over the
//! placements' world boxes ([`Placed`]). Placements move in place
//! ([`Placed::set_transforms`]): their maps are replaced and the top-level tree is built
//! again; the mesh trees are untouched.
//!
//! A closest- or every-hit query walks the top tree nearest first, an any-hit query as
//! [`Tree::ANY_NEAREST_FIRST`] says; at a placement the ray enters the mesh's tree
//! through the placement's world-to-object map. The direction is mapped but not renormalized,
//! so `t` means the same in both spaces and a hit needs no conversion.
//!
//! The closest hit across placements follows the tree's [`Rule`]: the smallest `t`, then the
//! smaller [`Tree::tie_key`] of the hit stamped with its placement ([`Tree::placed`]), so that
//! the answer never depends on the order of the visit. Under the open rule a placement is
//! asked up to just past the best `t` so far (a tie there may still win); under the closed
//! rule up to that `t`, included. The top-level boxes are tested with the exit margin of the
//! rule ([`Tree::EXIT_SCALE`]): Ize's conservative exit for the watertight tree, so that a
//! placement is never skipped by a ray that meets it.

use std::sync::Arc;

use glam::{Affine3A, DMat4, Vec3, Vec3A};

use super::traverse::{slab_scaled, walk_any, walk_nearest};
use super::tree::{Filter, Keep, KeepAll, Rule, Tree};
use super::{build, AlphaTests, Bvh, BvhNode};
use crate::accel::prim::boundary::Boundary;
use crate::math::{Aabb, Transform};
use crate::simd::Isa;

/// Where a mesh is placed.
#[derive(Clone, Debug)]
pub(crate) struct Placement {
    /// The index of its mesh.
    pub mesh: u32,
    /// The id its hits report ([`Tree::placed`]): the world's instance index in the renderer,
    /// the geometry id in ray casting.
    pub id: u32,
    /// Object to world; invertible.
    pub transform: Transform,
    /// The alpha tests of its mesh's triangles under its materials, when some may cut. Set
    /// before [`Placed::new`] and never after: whether a set's walks test hits at all is
    /// decided there, from these.
    pub(crate) alpha: Option<Arc<AlphaTests>>,
}

/// Meshes built once, their placements, and the top-level tree over the placements.
#[derive(Clone, Debug)]
pub(crate) struct Placed<T> {
    meshes: Vec<Arc<T>>,
    placements: Vec<Placement>,
    /// Each placement's world-to-object map.
    maps: Vec<Affine3A>,
    /// The top-level tree over the placements' world boxes: its nodes, and the placement in
    /// each leaf slot.
    top: Vec<BvhNode>,
    top_ids: Vec<u32>,
    /// True when some placement has alpha tests: the walks then ask each placement's filter;
    /// else they walk with [`KeepAll`], the plain walk.
    filtered: bool,
}

impl<T> Default for Placed<T> {
    fn default() -> Self {
        Placed {
            meshes: Vec::new(),
            placements: Vec::new(),
            maps: Vec::new(),
            top: Vec::new(),
            top_ids: Vec::new(),
            filtered: false,
        }
    }
}

impl<T: Tree> Placed<T> {
    /// `placements` (in increasing id order) of `meshes` (kept, even when nothing places
    /// them), under a top-level tree built on `pool` when given.
    pub(crate) fn new(
        meshes: Vec<Arc<T>>,
        placements: Vec<Placement>,
        pool: Option<&rayon::ThreadPool>,
    ) -> Placed<T> {
        debug_assert!(placements.windows(2).all(|w| w[0].id < w[1].id));
        let maps = placements.iter().map(|p| inverse(&p.transform)).collect();
        let filtered = placements.iter().any(|p| p.alpha.is_some());
        let mut placed = Placed {
            meshes,
            placements,
            maps,
            filtered,
            ..Placed::default()
        };
        placed.build_top(pool);
        placed
    }

    /// Builds the top-level tree over the placements' world boxes.
    fn build_top(&mut self, pool: Option<&rayon::ThreadPool>) {
        let boxes: Vec<Aabb> = (self.placements.iter())
            .map(|p| world_box(self.meshes[p.mesh as usize].bvh(), &p.transform))
            .collect();
        (self.top, self.top_ids) = build::build_tree(boxes.len(), |i| boxes[i], pool);
    }

    /// Replaces the transform of each placement `index` of `moves` with its new one
    /// (invertible) and builds the top-level tree again, once, on `pool` when given; the mesh
    /// trees are untouched.
    pub(crate) fn set_transforms(
        &mut self,
        moves: &[(usize, Transform)],
        pool: Option<&rayon::ThreadPool>,
    ) {
        for &(index, transform) in moves {
            self.placements[index].transform = transform;
            self.maps[index] = inverse(&transform);
        }
        self.build_top(pool);
    }

    /// The index of the placement whose hits report `id` (placements are kept in increasing
    /// id order).
    pub(crate) fn position(&self, id: u32) -> Option<usize> {
        self.placements.binary_search_by_key(&id, |p| p.id).ok()
    }

    /// The mesh trees, by index.
    pub(crate) fn meshes(&self) -> &[Arc<T>] {
        &self.meshes
    }

    /// The placements, in order.
    pub(crate) fn placements(&self) -> &[Placement] {
        &self.placements
    }

    /// True when some placement has alpha tests.
    #[inline(always)]
    pub(crate) fn filtered(&self) -> bool {
        self.filtered
    }

    /// The top-level tree's nodes and the placement in each leaf slot.
    #[inline(always)]
    pub(crate) fn top(&self) -> (&[BvhNode], &[u32]) {
        (&self.top, &self.top_ids)
    }

    /// Placement `index` as a ray enters it.
    #[inline(always)]
    pub(crate) fn entry(&self, index: u32) -> Entry<'_, T> {
        let p = &self.placements[index as usize];
        let mesh = &*self.meshes[p.mesh as usize];
        Entry {
            object_from_world: &self.maps[index as usize],
            mesh,
            id: p.id,
            filter: p.alpha.as_deref(),
            border: mesh.border(),
        }
    }

    /// Appends to `out` every placement whose (padded) box meets `bounds`, in the tree's
    /// order.
    pub(crate) fn overlapping(&self, bounds: &Aabb, out: &mut Vec<u32>) {
        if self.top.is_empty() || bounds.is_empty() {
            return;
        }
        let mut stack = vec![0u32];
        while let Some(index) = stack.pop() {
            let node = &self.top[index as usize];
            let b = node.bounds();
            if b.min.cmpgt(bounds.max).any() || b.max.cmplt(bounds.min).any() {
                continue;
            }
            if node.is_leaf() {
                let first = node.first as usize;
                out.extend_from_slice(&self.top_ids[first..first + node.count as usize]);
            } else {
                stack.extend([node.first + 1, node.first]);
            }
        }
    }
}

impl Placed<Bvh> {
    /// True when there are no placements.
    pub(crate) fn is_empty(&self) -> bool {
        self.placements.is_empty()
    }

    /// Nodes of the top-level tree and of every mesh's tree.
    pub(crate) fn node_count(&self) -> usize {
        self.top.len() + self.meshes.iter().map(|m| m.node_count()).sum::<usize>()
    }

    /// Nodes of the top-level tree alone.
    pub(crate) fn top_node_count(&self) -> usize {
        self.top.len()
    }
}

/// The world-space box of the mesh whose tree is `mesh` placed by `transform`: its root box
/// placed, grown by a relative 2⁻¹⁶ of its size and position for the rounding of the map, so
/// that it holds every point a ray can hit on the placed mesh.
pub(crate) fn world_box(mesh: &Bvh, transform: &Transform) -> Aabb {
    let Some(root) = mesh.nodes().first() else {
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
pub(crate) fn inverse(transform: &Transform) -> Affine3A {
    Affine3A::from_mat4(DMat4::as_mat4(&inverse_f64(transform)))
}

/// The world-to-object map of `transform` in double precision, of which [`inverse`] is the
/// `f32` form.
pub(crate) fn inverse_f64(transform: &Transform) -> DMat4 {
    transform.world_from_object.as_dmat4().inverse()
}

/// True when `a` is closer than `b` under the tree's rule: a smaller `t`, or the same `t` and
/// a smaller [`Tree::tie_key`].
#[inline(always)]
pub(crate) fn closer<T: Tree>(a: &T::Hit, b: &T::Hit) -> bool {
    (T::t(a), T::tie_key(a)) < (T::t(b), T::tie_key(b))
}

/// What a placement gives a ray that enters it.
pub(crate) struct Entry<'a, T> {
    /// The world-to-object map.
    pub object_from_world: &'a Affine3A,
    /// The mesh's tree.
    pub mesh: &'a T,
    /// The id its hits report ([`Tree::placed`]).
    pub id: u32,
    /// The filter of its hits.
    pub filter: Filter<'a>,
    /// Its mesh's border, for [`Tree::each`].
    pub border: Option<&'a [Boundary]>,
}

/// The closest of `best` and the placements' hits of the ray `origin + t·direction` with `t`
/// in `range`, under the tree's rule.
#[inline(always)]
pub(crate) fn closest<T: Tree, I: Isa>(
    placements: &Placed<T>,
    ray: (Vec3, Vec3),
    range: (f32, f32),
    best: Option<T::Hit>,
    stack: &mut T::Stack,
) -> Option<T::Hit> {
    match placements.filtered {
        false => closest_with::<T, I, KeepAll>(placements, ray, range, best, stack),
        true => closest_with::<T, I, Filter>(placements, ray, range, best, stack),
    }
}

/// [`closest`] with each placement's filter as `K`.
#[inline(always)]
fn closest_with<'p, T: Tree, I: Isa, K: Keep<'p>>(
    placements: &'p Placed<T>,
    (origin, direction): (Vec3, Vec3),
    (t_min, t_max): (f32, f32),
    mut best: Option<T::Hit>,
    stack: &mut T::Stack,
) -> Option<T::Hit> {
    let mut t = best.as_ref().map_or(t_max, T::t);
    walk(
        placements,
        (origin, direction),
        t_min,
        &mut t,
        |index, entry, ray, t| {
            let limit = match (T::RULE, &best) {
                // Ties at the best `t` so far are looked for too: a smaller key may take them.
                (Rule::Open, Some(_)) => t.next_up(),
                (Rule::Open, None) => t_max,
                (Rule::Closed, _) => *t,
            };
            let filter = K::of(entry.filter);
            let Some(hit) = entry
                .mesh
                .closest::<I, K>(ray, (t_min, limit), filter, stack)
            else {
                return;
            };
            let hit = T::placed(hit, entry.id, index);
            if best.as_ref().is_none_or(|b| closer::<T>(&hit, b)) {
                *t = T::t(&hit);
                best = Some(hit);
            }
        },
    );
    best
}

/// True when a placement's hit passes its filter with `t` in `range`; stops at the first.
#[inline(always)]
pub(crate) fn any<T: Tree, I: Isa>(
    placements: &Placed<T>,
    ray: (Vec3, Vec3),
    range: (f32, f32),
    stack: &mut T::Stack,
) -> bool {
    match placements.filtered {
        false => any_with::<T, I, KeepAll>(placements, ray, range, stack),
        true => any_with::<T, I, Filter>(placements, ray, range, stack),
    }
}

/// [`any`] with each placement's filter as `K`.
#[inline(always)]
fn any_with<'p, T: Tree, I: Isa, K: Keep<'p>>(
    placements: &'p Placed<T>,
    ray: (Vec3, Vec3),
    range: (f32, f32),
    stack: &mut T::Stack,
) -> bool {
    let (o, d) = ray;
    if !T::ANY_NEAREST_FIRST {
        let (top, ids) = placements.top();
        if top.is_empty() {
            return false;
        }
        let (origin, inv_dir) = (Vec3A::from(o), Vec3A::from(d).recip());
        let scale = T::EXIT_SCALE;
        return walk_any(top, (origin, inv_dir), range, scale, |slots| {
            ids[slots].iter().any(|&index| {
                entered(placements, index, ray)
                    .is_some_and(|(e, r)| e.mesh.any::<I, K>(&r, range, K::of(e.filter), stack))
            })
        });
    }
    let mut hit = false;
    let mut bound = range.1;
    walk(
        placements,
        ray,
        range.0,
        &mut bound,
        |_, entry, ray, bound| {
            if !hit
                && entry
                    .mesh
                    .any::<I, K>(ray, range, K::of(entry.filter), stack)
            {
                hit = true;
                // No box is entered before −∞: the walk ends.
                *bound = f32::NEG_INFINITY;
            }
        },
    );
    hit
}

/// Calls `f` with every hit of every placement with `t` in `range` ([`Tree::each`] with the
/// placement's filter and border), stamped with its placement.
#[inline(always)]
pub(crate) fn each<T: Tree, I: Isa>(
    placements: &Placed<T>,
    ray: (Vec3, Vec3),
    range: (f32, f32),
    stack: &mut T::Stack,
    f: &mut impl FnMut(T::Hit),
) {
    let mut bound = range.1;
    walk(
        placements,
        ray,
        range.0,
        &mut bound,
        |index, entry, ray, _| {
            let filters = (entry.filter, entry.border);
            entry
                .mesh
                .each::<I, Filter>(ray, range, filters, stack, &mut |h| {
                    f(T::placed(h, entry.id, index))
                });
        },
    );
}

/// Visits the placements whose boxes the ray enters with `t` in `[t_min, bound]`, nearest
/// first: `visit(index, entry, object-space ray, bound)`, which may lower the bound.
#[inline(always)]
fn walk<'p, T: Tree>(
    placements: &'p Placed<T>,
    (o, d): (Vec3, Vec3),
    t_min: f32,
    bound: &mut f32,
    mut visit: impl FnMut(u32, Entry<'p, T>, &T::Ray, &mut f32),
) {
    let (top, ids) = placements.top();
    if top.is_empty() {
        return;
    }
    let (origin, inv_dir) = (Vec3A::from(o), Vec3A::from(d).recip());
    let scale = T::EXIT_SCALE;
    let enter = |node: &BvhNode, t: f32| slab_scaled(node, origin, inv_dir, (t_min, t), scale);
    walk_nearest(top, bound, enter, |slots, bound| {
        for &index in &ids[slots] {
            if let Some((entry, ray)) = entered(placements, index, (o, d)) {
                visit(index, entry, &ray, bound);
            }
        }
    });
}

/// Placement `index` and the world ray `(o, d)` in its object space (the same `t`), when the
/// mapped ray can hit anything.
#[inline(always)]
fn entered<T: Tree>(
    placements: &Placed<T>,
    index: u32,
    (o, d): (Vec3, Vec3),
) -> Option<(Entry<'_, T>, T::Ray)> {
    let entry = placements.entry(index);
    let map = entry.object_from_world;
    let ray = T::prepare(map.transform_point3(o), map.transform_vector3(d))?;
    Some((entry, ray))
}
