//! The point queries of [`RaycastingScene`]: closest points, distances, occupancy and the
//! signed distance.

use glam::Vec3;
use rayon::prelude::*;

use crate::accel::wide::kernels::Nearests;
use crate::accel::wide::nearest::Nearest;
use crate::simd::{dispatch, simd_path};

use super::run::{beyond, budget, filled, room, run, QueryOptions, CHUNK};
use super::{RaycastError, RaycastingScene, INVALID_ID};

/// Bytes of [`ClosestPoints`] per point, and of the query's own arrays (the Morton order
/// and its inverse, the sorted points, the answers in that order).
const CLOSEST_BYTES: usize = 12 + 4 + 4 + 8 + 12 + 8 + 16 + 12 + size_of::<Option<Nearest>>();

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

/// The indices of `points` along a Morton curve through their box (10 bits per axis; the
/// non-finite ones last), and the inverse: `rank[order[k]] = k`. More than 2³² points keep
/// their order.
fn morton_order(points: &[[f32; 3]], pool: &rayon::ThreadPool) -> (Vec<usize>, Vec<usize>) {
    let (lo, hi) = points
        .iter()
        .map(|&p| Vec3::from(p))
        .filter(|p| p.is_finite())
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        });
    // Cells per unit along each axis (0 for a flat extent or no finite point).
    let scale = (hi - lo).to_array().map(|e| {
        if e > 0.0 && e.is_finite() {
            1023.0 / e
        } else {
            0.0
        }
    });
    let scale = Vec3::from(scale);
    // Each axis' 10 bits spread to every third bit.
    let spread = |x: u32| (0..10).fold(0u64, |code, b| code | (((x as u64 >> b) & 1) << (3 * b)));
    let key = |(i, p): (usize, &[f32; 3])| {
        let p = Vec3::from(*p);
        let code = if p.is_finite() {
            let c = ((p - lo) * scale)
                .clamp(Vec3::ZERO, Vec3::splat(1023.0))
                .as_uvec3();
            spread(c.x) | spread(c.y) << 1 | spread(c.z) << 2
        } else {
            1 << 30
        };
        (code << 32) | i as u64
    };
    let order: Vec<usize> = if u32::try_from(points.len()).is_ok() {
        let mut keys: Vec<u64> = pool.install(|| points.par_iter().enumerate().map(key).collect());
        pool.install(|| keys.par_sort_unstable());
        keys.iter().map(|&k| k as u32 as usize).collect()
    } else {
        (0..points.len()).collect()
    };
    let mut rank = vec![0; order.len()];
    for (k, &i) in order.iter().enumerate() {
        rank[i] = k;
    }
    (order, rank)
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
