//! The second level, written once over any [`Tree`]: meshes built once (in object space) and
//! placed any number of times, under a top-level binary tree over the placements' world
//! boxes. A closest- or every-hit query walks the top tree nearest first, an any-hit query as
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

use glam::{Affine3A, Vec3, Vec3A};

use super::traverse::{slab_scaled, walk_any, walk_nearest};
use super::tree::{Filter, Rule, Tree};
use super::BvhNode;
use crate::accel::prim::boundary::Boundary;
use crate::simd::Isa;

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

/// Placements of meshes under a top-level tree (see the module's docs).
pub(crate) trait Placements {
    /// The trees of the meshes.
    type Tree: Tree;
    /// The top-level tree's nodes and the placement in each leaf slot.
    fn top(&self) -> (&[BvhNode], &[u32]);
    /// Placement `index`.
    fn entry(&self, index: u32) -> Entry<'_, Self::Tree>;
}

type HitOf<P> = <<P as Placements>::Tree as Tree>::Hit;
type StackOf<P> = <<P as Placements>::Tree as Tree>::Stack;
type RayOf<P> = <<P as Placements>::Tree as Tree>::Ray;

/// The closest of `best` and the placements' hits of the ray `origin + t·direction` with `t`
/// in `range`, under the tree's rule.
#[inline(always)]
pub(crate) fn closest<P: Placements, I: Isa>(
    placements: &P,
    (origin, direction): (Vec3, Vec3),
    (t_min, t_max): (f32, f32),
    mut best: Option<HitOf<P>>,
    stack: &mut StackOf<P>,
) -> Option<HitOf<P>> {
    let mut t = best.as_ref().map_or(t_max, P::Tree::t);
    walk(
        placements,
        (origin, direction),
        t_min,
        &mut t,
        |index, entry, ray, t| {
            let limit = match (P::Tree::RULE, &best) {
                // Ties at the best `t` so far are looked for too: a smaller key may take them.
                (Rule::Open, Some(_)) => t.next_up(),
                (Rule::Open, None) => t_max,
                (Rule::Closed, _) => *t,
            };
            let Some(hit) = entry
                .mesh
                .closest::<I>(ray, (t_min, limit), entry.filter, stack)
            else {
                return;
            };
            let hit = P::Tree::placed(hit, entry.id, index);
            if best.as_ref().is_none_or(|b| closer::<P::Tree>(&hit, b)) {
                *t = P::Tree::t(&hit);
                best = Some(hit);
            }
        },
    );
    best
}

/// True when a placement's hit passes its filter with `t` in `range`; stops at the first.
#[inline(always)]
pub(crate) fn any<P: Placements, I: Isa>(
    placements: &P,
    ray: (Vec3, Vec3),
    range: (f32, f32),
    stack: &mut StackOf<P>,
) -> bool {
    let (o, d) = ray;
    if !P::Tree::ANY_NEAREST_FIRST {
        let (top, ids) = placements.top();
        if top.is_empty() {
            return false;
        }
        let (origin, inv_dir) = (Vec3A::from(o), Vec3A::from(d).recip());
        let scale = P::Tree::EXIT_SCALE;
        return walk_any(top, (origin, inv_dir), range, scale, |slots| {
            ids[slots].iter().any(|&index| {
                entered(placements, index, ray)
                    .is_some_and(|(e, r)| e.mesh.any::<I>(&r, range, e.filter, stack))
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
            if !hit && entry.mesh.any::<I>(ray, range, entry.filter, stack) {
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
pub(crate) fn each<P: Placements, I: Isa>(
    placements: &P,
    ray: (Vec3, Vec3),
    range: (f32, f32),
    stack: &mut StackOf<P>,
    f: &mut impl FnMut(HitOf<P>),
) {
    let mut bound = range.1;
    walk(
        placements,
        ray,
        range.0,
        &mut bound,
        |index, entry, ray, _| {
            let filters = (entry.filter, entry.border);
            entry.mesh.each::<I>(ray, range, filters, stack, &mut |h| {
                f(P::Tree::placed(h, entry.id, index))
            });
        },
    );
}

/// Visits the placements whose boxes the ray enters with `t` in `[t_min, bound]`, nearest
/// first: `visit(index, entry, object-space ray, bound)`, which may lower the bound.
#[inline(always)]
fn walk<'p, P: Placements>(
    placements: &'p P,
    (o, d): (Vec3, Vec3),
    t_min: f32,
    bound: &mut f32,
    mut visit: impl FnMut(u32, Entry<'p, P::Tree>, &RayOf<P>, &mut f32),
) {
    let (top, ids) = placements.top();
    if top.is_empty() {
        return;
    }
    let (origin, inv_dir) = (Vec3A::from(o), Vec3A::from(d).recip());
    let scale = P::Tree::EXIT_SCALE;
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
fn entered<P: Placements>(
    placements: &P,
    index: u32,
    (o, d): (Vec3, Vec3),
) -> Option<(Entry<'_, P::Tree>, RayOf<P>)> {
    let entry = placements.entry(index);
    let map = entry.object_from_world;
    let ray = P::Tree::prepare(map.transform_point3(o), map.transform_vector3(d))?;
    Some((entry, ray))
}
