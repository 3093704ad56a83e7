//! The point queries of [`RaycastingScene`]: closest points, distances, occupancy and the
//! signed distance.

use glam::Vec3;
use rayon::prelude::*;

use super::run::{beyond, budget, filled, room, run, QueryOptions, CHUNK};
use super::{RaycastError, RaycastingScene, INVALID_ID};

/// Bytes of [`ClosestPoints`] per point.
const CLOSEST_BYTES: usize = 12 + 4 + 4 + 8 + 12;

/// Rays of one round of an occupancy vote: the points' rays are made a round at a time,
/// never all at once (`nsamples` rays of 24 bytes per point).
const VOTE_RAYS: usize = 64 * CHUNK;

/// The closest surface point to each query point
/// ([`RaycastingScene::compute_closest_points`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClosestPoints {
    /// The closest point; NaN when there is none (empty scene, non-finite query).
    pub points: Vec<[f32; 3]>,
    /// Geometry id of its triangle; [`INVALID_ID`] when there is none.
    pub geometry_ids: Vec<u32>,
    /// Index of its triangle within the geometry; [`INVALID_ID`] when there is none.
    pub primitive_ids: Vec<u32>,
    /// Its barycentric weights of the triangle's second and third vertices.
    pub primitive_uvs: Vec<[f32; 2]>,
    /// Unit normal `(v1 − v0) × (v2 − v0)` of its triangle.
    pub primitive_normals: Vec<[f32; 3]>,
}

impl RaycastingScene {
    /// The closest surface point to each query point, with its triangle, barycentrics and
    /// normal. Among equally close triangles, the smallest geometry id, then primitive id.
    pub fn compute_closest_points(
        &self,
        points: &[[f32; 3]],
        options: &QueryOptions,
    ) -> Result<ClosestPoints, RaycastError> {
        let (accel, pool) = self.prepare(options)?;
        let accel = &*accel;
        let n = points.len();
        budget(&[(n, CLOSEST_BYTES)], "the result")?;
        let mut out = ClosestPoints {
            points: filled(&pool, options, n, [f32::NAN; 3])?,
            geometry_ids: filled(&pool, options, n, INVALID_ID)?,
            primitive_ids: filled(&pool, options, n, INVALID_ID)?,
            primitive_uvs: filled(&pool, options, n, [0.0; 2])?,
            primitive_normals: filled(&pool, options, n, [0.0; 3])?,
        };
        let items = (
            points.par_chunks(CHUNK),
            out.points.par_chunks_mut(CHUNK),
            out.geometry_ids.par_chunks_mut(CHUNK),
            out.primitive_ids.par_chunks_mut(CHUNK),
            out.primitive_uvs.par_chunks_mut(CHUNK),
            out.primitive_normals.par_chunks_mut(CHUNK),
        )
            .into_par_iter();
        run(&pool, options, items, |(queries, pts, g, p, uv, normal)| {
            for (i, q) in queries.iter().enumerate() {
                let q = Vec3::from(*q);
                if !q.is_finite() {
                    continue;
                }
                let Some(near) = accel.nearest(q) else {
                    continue;
                };
                pts[i] = near.point.to_array();
                (g[i], p[i]) = (near.geometry, near.primitive);
                uv[i] = [near.b1, near.b2];
                normal[i] = accel.normal(near.level, near.slot);
            }
        })?;
        Ok(out)
    }

    /// The distance from each query point to the surface: `∞` for an empty scene, NaN for a
    /// non-finite point.
    pub fn compute_distance(
        &self,
        points: &[[f32; 3]],
        options: &QueryOptions,
    ) -> Result<Vec<f32>, RaycastError> {
        let closest = self.compute_closest_points(points, options)?;
        let mut out = room(points.len(), "the result")?;
        out.extend(
            points
                .iter()
                .zip(&closest.points)
                .map(|(q, p)| distance(q, p)),
        );
        Ok(out)
    }

    /// The distance to the surface, negative inside: a point is inside when most of
    /// `nsamples` (odd) rays from it cross the surface an odd number of times, as in
    /// [`compute_occupancy`](Self::compute_occupancy). Meaningful for closed meshes.
    pub fn compute_signed_distance(
        &self,
        points: &[[f32; 3]],
        nsamples: u32,
        options: &QueryOptions,
    ) -> Result<Vec<f32>, RaycastError> {
        let inside = self.compute_occupancy(points, nsamples, options)?;
        let mut d = self.compute_distance(points, options)?;
        for (d, inside) in d.iter_mut().zip(inside) {
            if inside > 0.5 {
                *d = -*d;
            }
        }
        Ok(d)
    }

    /// 1 for points inside the closed surface and 0 outside (as `f32`, like Open3D): the
    /// majority vote of `nsamples` (odd, 1 to 255) rays from the point, each inside when it
    /// crosses the surface an odd number of times. The first ray goes along `(1, 1, 1)`, the
    /// others along fixed directions within 0.1 % of it. The crossing count is exact (see the
    /// module docs), so one sample is enough for a closed mesh. Non-finite points are outside.
    pub fn compute_occupancy(
        &self,
        points: &[[f32; 3]],
        nsamples: u32,
        options: &QueryOptions,
    ) -> Result<Vec<f32>, RaycastError> {
        if nsamples.is_multiple_of(2) || nsamples > 255 {
            return Err(RaycastError::InvalidSamples(nsamples));
        }
        if let Some(index) = points.iter().position(|p| beyond(p)) {
            let what = "query point";
            return Err(RaycastError::Beyond { what, index });
        }
        let dirs = vote_directions(nsamples);
        let mut out = room(points.len(), "the result")?;
        let mut rays = Vec::new();
        for points in points.chunks((VOTE_RAYS / dirs.len()).max(1)) {
            rays.clear();
            rays.extend(
                points
                    .iter()
                    .flat_map(|p| dirs.iter().map(|d| [p[0], p[1], p[2], d[0], d[1], d[2]])),
            );
            let counts = self.count_intersections(&rays, options)?;
            out.extend(counts.chunks(dirs.len()).map(|c| {
                let odd = c.iter().filter(|&&n| n % 2 == 1).count();
                if 2 * odd > c.len() {
                    1.0
                } else {
                    0.0
                }
            }));
        }
        Ok(out)
    }
}

/// `|q − p|`, ∞ when there is no closest point for a finite query, NaN for a non-finite one.
fn distance(q: &[f32; 3], p: &[f32; 3]) -> f32 {
    let q = Vec3::from(*q);
    if !q.is_finite() {
        return f32::NAN;
    }
    let p = Vec3::from(*p);
    if p.is_nan() {
        return f32::INFINITY;
    }
    // In f64: the square of a difference of 1e20 overflows f32.
    (p.as_dvec3() - q.as_dvec3()).length() as f32
}

/// The `n` directions of an inside/outside vote: `(1, 1, 1)` and fixed offsets of at most
/// 0.001 per component (a low-discrepancy sequence, no RNG).
fn vote_directions(n: u32) -> Vec<[f32; 3]> {
    (0..n)
        .map(|j| {
            if j == 0 {
                return [1.0; 3];
            }
            let offset = |k: f64| {
                let x = (j as f64 * k).fract();
                (1.0 + (x - 0.5) * 0.002) as f32
            };
            [
                offset(0.618_033_988_75),
                offset(0.414_213_562_37),
                offset(0.732_050_807_57),
            ]
        })
        .collect()
}
