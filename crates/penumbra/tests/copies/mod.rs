//! Comparing a world with its copies: the same scene built with instances (meshes placed by
//! transforms) and with every instance copied into world space. The two are the same surfaces
//! in two float roundings, so a ray through a triangle's edge or a texel's border, or a segment
//! that ends on a surface, may get either answer in either world. A different answer is
//! accepted only when the copies give it for the query moved by a hair ([`HAIR`] of the
//! scene's scale): what a user could tell apart is still caught.
//!
//! Used as `mod copies;` by the tests that compare instances with copies.

// Each test crate uses its own part of this module.
#![allow(dead_code)]

use glam::Vec3;
use penumbra::{Hit, Ray, World};

/// How far a query may move, against the scene's scale, to find the other world's answer.
pub const HAIR: f32 = 1e-4;

/// The object and the triangle's index within it, for a world with instances or copies: a
/// copy's triangle index counts from its object's first triangle.
pub fn ids(world: &World, hit: &Hit) -> (u32, u32) {
    let s = world.surface(hit);
    if hit.instance.is_some() {
        return (s.object, s.triangle);
    }
    let first = world
        .geometry()
        .triangles
        .iter()
        .position(|t| t.object == s.object)
        .unwrap() as u32;
    (s.object, s.triangle - first)
}

/// The moves of a query from `start` toward `end` by a hair: sideways along each axis, and
/// its far end nearer and farther.
fn nudges(start: Vec3, end: Vec3) -> impl Iterator<Item = (Vec3, Vec3)> {
    let hair = HAIR * start.length().max(end.length()).max(1.0);
    let sideways = [Vec3::X, Vec3::Y, Vec3::Z]
        .into_iter()
        .flat_map(move |axis| [axis * hair, -axis * hair])
        .map(move |step| (start + step, end + step));
    let along = (end - start).normalize_or_zero() * hair;
    sideways.chain([(start, end + along), (start, end - along)])
}

/// True when `copies` says `blocked` for the segment from `start` to `end`, or for the segment
/// moved by a hair.
pub fn occluded_near(copies: &World, start: Vec3, end: Vec3, blocked: bool) -> bool {
    let occluded = |(s, e): (Vec3, Vec3)| copies.accel().occluded(&Ray::new(s, e - s), 0.0, 1.0);
    occluded((start, end)) == blocked || nudges(start, end).any(|q| occluded(q) == blocked)
}

/// True when `copies`' closest hit along `ray` is the object and triangle `hit` names (or a
/// miss for none), or is for the ray moved by a hair.
pub fn hit_near(copies: &World, ray: &Ray, hit: Option<(u32, u32)>) -> bool {
    let found = |r: &Ray| {
        copies
            .intersect(r, 0.0, f32::INFINITY)
            .map(|h| ids(copies, &h))
    };
    let end = ray.origin + ray.direction;
    found(ray) == hit
        || nudges(ray.origin, end)
            .take(6)
            .any(|(s, e)| found(&Ray::new(s, e - s)) == hit)
}

/// Checks occlusion answers of a world with instances against its copies, one by one: each
/// segment `(start, end)` with `blocked` must be the copies' answer up to a hair.
pub fn occlusions_near(
    copies: &World,
    segments: impl IntoIterator<Item = (Vec3, Vec3)>,
    blocked: &[bool],
) -> Result<(), String> {
    for ((start, end), &b) in segments.into_iter().zip(blocked) {
        if !occluded_near(copies, start, end, b) {
            return Err(format!("{start} to {end}: blocked {b} in one world only"));
        }
    }
    Ok(())
}
