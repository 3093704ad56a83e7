//! The ray–triangle tests, each written once for every caller (the scalar test and the SIMD
//! lanes of rays or of triangles): `moller_trumbore`, the renderer's; `watertight`, the test
//! of Woop, Benthin and Wald that ray casting uses (no ray slips between two triangles that
//! share an edge), with `boundary`, the part of the surface's border each triangle owns for
//! its counting rule.

use glam::Vec3A;

pub(crate) mod boundary;
pub(crate) mod moller_trumbore;
pub(crate) mod watertight;

/// The three corners of a triangle.
pub(crate) type Corners = [Vec3A; 3];
