//! Ray casting against triangle meshes with Open3D's `RaycastingScene` names and semantics,
//! watertight: a ray aimed exactly at an edge shared by two triangles, or at a vertex, hits
//! the surface; it never slips through and never leaks to the far side.
//!
//! Meshes are added with [`RaycastingScene::add_triangles`] (geometry ids 0, 1, … in order),
//! placed copies of them with [`RaycastingScene::add_instance`] (see `instances`);
//! a BVH over all of them is built on the first query (or by [`RaycastingScene::commit`]).
//! Every batch query takes flat arrays (`[f32; 6]` rays `[ox, oy, oz, dx, dy, dz]`,
//! `[f32; 3]` points) and returns flat arrays in the same order, running on a pool of the
//! scene's own sized by [`QueryOptions::threads`]; results do not depend on the thread
//! count.
//!
//! ```
//! use penumbra::{QueryOptions, RaycastingScene, INVALID_ID};
//!
//! let mut scene = RaycastingScene::new();
//! // A unit square in the z = 0 plane, as two triangles.
//! let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
//! let id = scene.add_triangles(&vertices, &[[0, 1, 2], [0, 2, 3]])?;
//! assert_eq!(id, 0);
//!
//! // Straight down through the shared diagonal, and one ray beside the square.
//! let rays = [[0.5, 0.5, 2.0, 0.0, 0.0, -2.0], [3.0, 0.5, 2.0, 0.0, 0.0, -1.0]];
//! let hits = scene.cast_rays(&rays, &QueryOptions::default())?;
//! assert_eq!(hits.t_hit[0], 1.0); // in units of the direction's length
//! assert_eq!(hits.geometry_ids, [0, INVALID_ID]);
//! assert_eq!(hits.t_hit[1], f32::INFINITY);
//! // The ray through the diagonal crosses the surface once.
//! assert_eq!(scene.count_intersections(&rays, &QueryOptions::default())?, [1, 0]);
//! # Ok::<(), penumbra::RaycastError>(())
//! ```
//!
//! Edges and vertices: the closest-hit and occlusion queries count a ray on a boundary as a
//! hit of every triangle there. Among triangles hit at exactly the same distance, the
//! closest-hit query reports the one with the smallest geometry id, then primitive id, so that
//! no answer depends on the order in which the hierarchy is visited. The counting
//! queries ([`RaycastingScene::count_intersections`],
//! [`RaycastingScene::list_intersections`], and through them occupancy and the sign of the
//! signed distance) count each crossing of the surface once: a ray through an edge shared by
//! two triangles, or through a vertex, crossing from one side to the other, counts one hit
//! (Open3D merges equal distances within a geometry to the same end); where the ray only
//! touches the surface at a fold (a silhouette edge) it counts 0 or 2, so the parity stays
//! right. On the border of an open mesh (an edge that only one triangle has, a vertex of such
//! an edge: all of a lone triangle's) a ray counts once, as in Open3D, so every ray that the
//! closest-hit query finds there is counted and listed too. See `accel::prim::watertight`
//! and `accel::prim::boundary` for the rule.

mod instances;
mod lazy;
mod order;
mod pinhole;
mod points;
mod queries;
mod run;

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_behind;
#[cfg(test)]
mod tests_border;
#[cfg(test)]
mod tests_coincident;
#[cfg(test)]
mod tests_edges;
#[cfg(test)]
mod tests_instances;
#[cfg(test)]
mod tests_levels;
#[cfg(test)]
mod tests_packets;

use std::sync::Arc;

use glam::Vec3;

use crate::memory::human;
use crate::scale::MAX_COORDINATE;
use crate::world::MAX_TRIANGLES;

pub use pinhole::{create_rays_pinhole, create_rays_pinhole_fov};
pub use points::ClosestPoints;
pub use queries::{CastRays, Intersections};
pub use run::QueryOptions;

use crate::accel::wide::levels::WideLevels;
use lazy::{LazyAccel, Triangles};
use run::Pools;

/// The id of nothing: the geometry and primitive id of a miss (Open3D's `INVALID_ID`,
/// 4294967295).
pub const INVALID_ID: u32 = u32::MAX;

/// What can go wrong when adding meshes or running a query.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum RaycastError {
    /// A triangle names a vertex past the end of the vertex array.
    #[error("triangle {triangle} uses vertex {index}, but there are only {vertices} vertices")]
    IndexOutOfRange {
        /// Index of the triangle in the array passed.
        triangle: usize,
        /// The vertex index it holds.
        index: u32,
        /// Number of vertices passed.
        vertices: usize,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {vertex} has a coordinate that is not finite")]
    NotFinite {
        /// Index of the vertex in the array passed.
        vertex: usize,
    },
    /// The scene would hold more triangles than the library supports.
    #[error("the scene would have more than {MAX_TRIANGLES} triangles")]
    TooManyTriangles,
    /// The worker pool could not be made.
    #[error("cannot start worker threads: {0}")]
    Threads(String),
    /// The query was stopped through [`QueryOptions::cancel`].
    #[error("the query was cancelled")]
    Cancelled,
    /// A pinhole camera's parameters are invalid.
    #[error("invalid camera: {0}")]
    InvalidCamera(String),
    /// The number of rays per point of an inside/outside vote is not odd.
    #[error("nsamples must be an odd number from 1 to 255, not {0}")]
    InvalidSamples(u32),
    /// A vertex, a ray's origin or a query point of an occupancy vote has a coordinate
    /// beyond ±[`MAX_COORDINATE`], where the 32-bit products of the watertight ray test
    /// overflow and rays would silently miss.
    #[error(
        "{what} {index} has a coordinate beyond ±{MAX_COORDINATE:e}, the largest ray casting \
         handles exactly (its 32-bit ray-triangle products would overflow): scale the scene \
         down"
    )]
    Beyond {
        /// `"vertex"`, `"ray"` or `"query point"`.
        what: &'static str,
        /// Its index in the array passed.
        index: usize,
    },
    /// A result (or the rays of [`create_rays_pinhole`]) needs more memory than the process
    /// may take.
    #[error(
        "not enough memory for {what}: {} more is more than this process can take",
        human(*.bytes)
    )]
    OutOfMemory {
        /// What was being made: "the result", "the rays"…
        what: &'static str,
        /// The bytes asked for when memory ran out.
        bytes: u64,
    },
    /// [`RaycastingScene::add_instance`] names a geometry that was not added.
    #[error("geometry {id} does not exist (the scene has {geometries} geometries)")]
    UnknownGeometry {
        /// The id given.
        id: u32,
        /// How many geometries the scene has.
        geometries: u32,
    },
    /// [`RaycastingScene::set_transform`] names a geometry that is not a placement.
    #[error("geometry {id} is not a placement (only geometries add_instance returned, or a world's instances, move; the scene has {geometries} geometries)")]
    NotAPlacement {
        /// The id given.
        id: u32,
        /// How many geometries the scene has.
        geometries: u32,
    },
    /// An entry of an instance's transform is NaN or infinite.
    #[error("the matrix entry [{row}][{column}] is not a finite 32-bit float")]
    TransformNotFinite {
        /// Its row.
        row: usize,
        /// Its column.
        column: usize,
    },
    /// An instance's transform is not affine: its last row is not `[0, 0, 0, 1]`.
    #[error("the matrix's last row must be [0, 0, 0, 1] (an affine map)")]
    TransformNotAffine,
    /// An instance's transform cannot be inverted.
    #[error("the matrix cannot be inverted (a zero scale, or factors beyond about 1e±38)")]
    SingularTransform,
    /// A [`RaycastingScene::list_intersections`] result would hold more than 2³² − 1 hits.
    #[error("more than 2^32 - 1 intersections to list; pass fewer rays at a time")]
    TooManyIntersections,
}

/// `Err(TooManyTriangles)` unless a scene of `vertices` vertices and `triangles` triangles
/// fits: at most [`MAX_TRIANGLES`] triangles, and vertices numbered by `u32`.
fn fits(vertices: usize, triangles: usize) -> Result<(), RaycastError> {
    if triangles > MAX_TRIANGLES || vertices > u32::MAX as usize {
        return Err(RaycastError::TooManyTriangles);
    }
    Ok(())
}

/// A set of triangle meshes to cast rays against, with Open3D's `RaycastingScene` queries.
///
/// Add meshes with [`add_triangles`](Self::add_triangles), then query; the acceleration
/// structure is built on the first query after a change, or by [`commit`](Self::commit).
/// Queries take `&self` and may run from several threads at once.
#[derive(Debug, Default)]
pub struct RaycastingScene {
    /// Every triangle with its geometry and primitive ids.
    triangles: Arc<Triangles>,
    /// Number of geometries added.
    geometries: u32,
    /// The BVH, built on demand.
    accel: LazyAccel,
    /// The worker pool of the last query.
    pools: Pools,
}

impl RaycastingScene {
    /// An empty scene: every ray misses.
    pub fn new() -> RaycastingScene {
        RaycastingScene::default()
    }

    /// Adds a mesh: `vertices` are positions, `triangles` index triples into them. Returns
    /// the new geometry's id: 0 for the first mesh, then 1, 2, …. Primitive ids in query
    /// results are indices into `triangles`.
    ///
    /// Nothing is added when an index is out of range ([`RaycastError::IndexOutOfRange`]) or
    /// a used or unused vertex is not finite ([`RaycastError::NotFinite`]) or beyond
    /// ±[`MAX_COORDINATE`] ([`RaycastError::Beyond`]). Degenerate
    /// (zero-area) triangles are kept and never hit by rays (they still have closest points).
    pub fn add_triangles(
        &mut self,
        vertices: &[[f32; 3]],
        triangles: &[[u32; 3]],
    ) -> Result<u32, RaycastError> {
        if let Some(vertex) = vertices
            .iter()
            .position(|v| !v.iter().all(|c| c.is_finite()))
        {
            return Err(RaycastError::NotFinite { vertex });
        }
        if let Some(index) = vertices.iter().position(|v| run::beyond(v)) {
            return Err(RaycastError::Beyond {
                what: "vertex",
                index,
            });
        }
        for (triangle, tri) in triangles.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= vertices.len()) {
                return Err(RaycastError::IndexOutOfRange {
                    triangle,
                    index,
                    vertices: vertices.len(),
                });
            }
        }
        let all = &self.triangles.geometry;
        fits(
            all.positions.len() + vertices.len(),
            all.len() + triangles.len(),
        )?;
        let id = self.geometries;
        // Forget the structure first: a build still running then holds the only other
        // reference, and the triangles are copied once at most.
        self.accel.reset();
        Arc::make_mut(&mut self.triangles).push(
            vertices.iter().map(|&v| Vec3::from(v)),
            triangles.iter().copied(),
            id,
        );
        self.geometries += 1;
        Ok(id)
    }

    /// Number of geometries added.
    pub fn geometry_count(&self) -> u32 {
        self.geometries
    }

    /// Number of triangles of all geometries (a placed geometry's counted for each
    /// placement: the triangles rays see).
    pub fn triangle_count(&self) -> usize {
        self.triangles.seen()
    }

    /// Builds the acceleration structure now (with `threads` workers, 0 for one per core)
    /// rather than on the next query. Does nothing when it is already built.
    pub fn commit(&self, threads: usize) -> Result<(), RaycastError> {
        let pool = self.pools.get(threads)?;
        let options = QueryOptions::default();
        self.accel.get(&self.triangles, &pool, &options).map(|_| ())
    }

    /// The built structure and the pool for a query: built first if need be, on a thread of
    /// its own when large, so that a cancel is answered during the build too.
    fn prepare(
        &self,
        options: &QueryOptions,
    ) -> Result<(Arc<WideLevels>, Arc<rayon::ThreadPool>), RaycastError> {
        let pool = self.pools.get(options.threads)?;
        let accel = self.accel.get(&self.triangles, &pool, options)?;
        Ok((accel, pool))
    }

    /// Geometry id and primitive id of scene triangle `triangle`.
    #[cfg(test)]
    fn ids(&self, triangle: u32) -> (u32, u32) {
        let t = triangle as usize;
        let all = &self.triangles;
        (all.geometry.triangles[t].object, all.local_ids[t])
    }

    /// Corners of scene triangle `triangle`.
    #[cfg(test)]
    fn corners(&self, triangle: u32) -> crate::accel::prim::Corners {
        self.triangles
            .geometry
            .corners(triangle as usize)
            .map(glam::Vec3A::from)
    }
}
