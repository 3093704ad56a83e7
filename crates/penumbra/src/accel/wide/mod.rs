//! The ray-casting engine: the binary [`Bvh`](super::Bvh) seen eight children at a time, with
//! its triangles' exact corners, and the queries that walk it with the watertight test.
//!
//! - `node`: the wide node and its collapse from the binary tree;
//! - `group`: a leaf's triangles, eight by coordinate, and the watertight test on all eight;
//! - `tree`: [`WideBvh`] (the binary tree, the wide view, triangles and ids in leaf order) and
//!   its one single-ray walk, which the closest-, any- and every-hit queries share;
//! - `packets`: packets of neighbouring rays through one walk: closest hits (`cast_rays` on
//!   pinhole images) and crossing counts of parallel rays (occupancy's votes);
//! - `rays`: a packet's rays by lane, prepared side by side;
//! - `cull`: a packet's bounds, for culling a node's children for all its rays at once;
//! - `turns`: a few rays' single-ray walks side by side, one step each in turn, so that
//!   their cache misses overlap on trees larger than the caches;
//! - `kernels`: the single-ray queries of a batch, compiled per instruction set;
//! - `control`: what a batch kernel asks of the query that runs it (stop, room for results);
//! - `nearest`: the closest point of the surface, by the binary tree's nearest-first walk;
//! - `levels`: the scene's own tree and placed meshes' trees under a top-level tree, which
//!   every query of the ray-casting API asks.

pub(crate) mod control;
mod cull;
mod group;
pub(crate) mod kernels;
pub(crate) mod levels;
mod margins;
pub(crate) mod nearest;
pub(crate) mod node;
pub(crate) mod packets;
pub(crate) mod rays;
mod stack;
mod tree;
pub(crate) mod turns;
#[cfg(test)]
mod turns_tests;

pub(crate) use margins::{raised, tie_bound, EXIT_SCALE};
pub(crate) use tree::{SlotHit, Stack, WideBvh};
