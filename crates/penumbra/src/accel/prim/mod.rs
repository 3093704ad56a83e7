//! The ray–triangle tests: `watertight`, the test of Woop, Benthin and Wald that ray casting
//! uses (no ray slips between two triangles that share an edge), with `boundary`, the part of
//! the surface's border each triangle owns for its counting rule.

pub(crate) mod boundary;
pub(crate) mod watertight;
