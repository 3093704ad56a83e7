//! The point queries of [`RaycastingScene`]: closest points, distances, occupancy and the
//! signed distance.

use glam::Vec3;
use rayon::prelude::*;

use crate::accel::wide::kernels::{counts, Nearests};
use crate::accel::wide::nearest::Nearest;
use crate::simd::{dispatch, simd_path};

use super::lazy;
use super::order::{across_order, morton_order};
use super::queries::ALL;
use super::run::{beyond, budget, filled, room, run, QueryOptions, CHUNK};
use super::{RaycastError, RaycastingScene, INVALID_ID};

/// Bytes of [`ClosestPoints`] per point, and of the query's own arrays (the Morton order
/// and its inverse, the sorted points, the answers in that order).
const CLOSEST_BYTES: usize = 12 + 4 + 4 + 8 + 12 + 8 + 16 + 12 + size_of::<Option<Nearest>>();

/// Bytes of an occupancy query's own arrays per point: the cell keys, the order, the odd
/// counts and the result.
const OCCUPANCY_BYTES: usize = 4 + 8 + 1 + 4;

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
        // The points in Morton order, so that neighbours walk the same nodes one after the
        // other and each starts from its neighbour's answer; the answers are put back in
        // the given order at the end.
        let (order, rank) = morton_order(points, &pool);
        let sorted: Vec<[f32; 3]> = pool.install(|| order.par_iter().map(|&i| points[i]).collect());
        let mut found: Vec<Option<Nearest>> = filled(&pool, options, n, None)?;
        let path = simd_path();
        let items = (sorted.par_chunks(CHUNK), found.par_chunks_mut(CHUNK)).into_par_iter();
        run(&pool, options, items, |(points, out)| {
            dispatch(
                path,
                Nearests {
                    accel,
                    options,
                    points,
                    out,
                },
            );
        })?;
        let items = (
            rank.par_chunks(CHUNK),
            out.points.par_chunks_mut(CHUNK),
            out.geometry_ids.par_chunks_mut(CHUNK),
            out.primitive_ids.par_chunks_mut(CHUNK),
            out.primitive_uvs.par_chunks_mut(CHUNK),
            out.primitive_normals.par_chunks_mut(CHUNK),
        )
            .into_par_iter();
        run(&pool, options, items, |(rank, pts, g, p, uv, normal)| {
            for (i, &k) in rank.iter().enumerate() {
                let Some(near) = found[k] else {
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
        let (accel, pool) = self.prepare(options)?;
        let border = &lazy::borders(&accel, &pool, options)?;
        let accel = &*accel;
        let n = points.len();
        budget(&[(n, OCCUPANCY_BYTES)], "the result")?;
        // The points by cells across the rays: the vote directions are all within 0.1 % of
        // (1, 1, 1), so runs of points in this order cast nearly the same line, and go as
        // packets of parallel rays (the counting kernel finds them).
        let order = across_order(points, &pool);
        let dirs = vote_directions(nsamples);
        // Per point (in that order), the rays that cross the surface an odd number of times.
        let mut odd: Vec<u8> = filled(&pool, options, n, 0)?;
        let path = simd_path();
        let items = order.par_chunks(CHUNK).zip(odd.par_chunks_mut(CHUNK));
        run(&pool, options, items, |(order, odd)| {
            let mut rays = [[0.0f32; 6]; CHUNK];
            let mut crossings = [0i32; CHUNK];
            let (rays, crossings) = (&mut rays[..order.len()], &mut crossings[..order.len()]);
            for d in &dirs {
                for (ray, &i) in rays.iter_mut().zip(order) {
                    let p = points[i];
                    *ray = [p[0], p[1], p[2], d[0], d[1], d[2]];
                }
                crossings.fill(0);
                counts(path, (accel, options), (border, ALL), rays, crossings);
                for (odd, count) in odd.iter_mut().zip(&*crossings) {
                    *odd += (count % 2 == 1) as u8;
                }
            }
        })?;
        let mut out: Vec<f32> = filled(&pool, options, n, 0.0)?;
        for (&i, &odd) in order.iter().zip(&odd) {
            if 2 * u32::from(odd) > nsamples {
                out[i] = 1.0;
            }
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
