//! The batch queries of [`RaycastingScene`]: closest hits, occlusion, counting and listing
//! intersections, closest points, distances, occupancy.

use std::borrow::Cow;

use glam::Vec3;
use rayon::prelude::*;

use super::lazy;
use super::run::{beyond, budget, filled, room, run, FarOrigins, QueryOptions, CHUNK};
use super::{RaycastError, RaycastingScene, INVALID_ID};
use crate::accel::prim::watertight::PreparedRay;
use crate::accel::wide::kernels::{prepare, ClosestPlaced, Counts, Listing, Occlusions};
use crate::accel::wide::packets::CastPackets;
use crate::simd::{dispatch, simd_path};

/// Rows per band of [`RaycastingScene::cast_rays_rows`], and columns per tile: the packets
/// (16 rays with AVX-512, 8 without) are then 4 × 4 or 4 × 2 neighbouring rays.
const TILE: usize = 4;

/// Bytes of [`CastRays`] per ray: `t_hit`, two ids, uv and normal.
const RESULT_BYTES: usize = 4 + 4 + 4 + 8 + 12;

/// Bytes of [`ClosestPoints`] per point.
const CLOSEST_BYTES: usize = 12 + 4 + 4 + 8 + 12;

/// Rays of one round of an occupancy vote: the points' rays are made a round at a time,
/// never all at once (`nsamples` rays of 24 bytes per point).
const VOTE_RAYS: usize = 64 * CHUNK;

/// The longest row that [`RaycastingScene::cast_rays_rows`] traces in tiles: a band is one
/// work item, and this keeps it within 16 chunks.
const MAX_TILED_ROW: usize = 4096;

/// The indices `0..len` of a band of at most [`TILE`] rows of `row_length` rays in tile
/// order: [`TILE`] columns of every row of the band, then the next [`TILE`] columns.
pub(super) fn tile_order(len: usize, row_length: usize) -> Vec<usize> {
    let rows = len.div_ceil(row_length);
    let mut order = Vec::with_capacity(len);
    for x0 in (0..row_length).step_by(TILE) {
        for y in 0..rows {
            let row = y * row_length;
            let end = (row + (x0 + TILE).min(row_length)).min(len);
            order.extend(row + x0..end);
        }
    }
    order
}

/// The closest hit of each ray ([`RaycastingScene::cast_rays`]); entry `i` of every array
/// belongs to ray `i`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CastRays {
    /// Ray parameter of the hit, in units of the direction's length (the direction is not
    /// normalized); `f32::INFINITY` on a miss.
    pub t_hit: Vec<f32>,
    /// Geometry id of the triangle hit; [`INVALID_ID`] on a miss.
    pub geometry_ids: Vec<u32>,
    /// Index of the triangle hit within its geometry; [`INVALID_ID`] on a miss.
    pub primitive_ids: Vec<u32>,
    /// Barycentric weights of the hit triangle's second and third vertices (the hit point is
    /// `(1 − u − v)·v0 + u·v1 + v·v2`); `[0, 0]` on a miss.
    pub primitive_uvs: Vec<[f32; 2]>,
    /// Unit geometric normal `(v1 − v0) × (v2 − v0)` of the hit triangle, whichever side the
    /// ray came from; `[0, 0, 0]` on a miss.
    pub primitive_normals: Vec<[f32; 3]>,
}

/// Every intersection of every ray ([`RaycastingScene::list_intersections`]), in Open3D's
/// layout: the hits of ray `i` are entries `ray_splits[i] .. ray_splits[i + 1]` of the other
/// arrays, sorted by increasing `t_hit`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Intersections {
    /// `rays + 1` offsets: `ray_splits[0] = 0`, and the last is the number of hits.
    pub ray_splits: Vec<u32>,
    /// The ray of each hit.
    pub ray_ids: Vec<u32>,
    /// Ray parameter of each hit, in units of the direction's length.
    pub t_hit: Vec<f32>,
    /// Geometry id of each hit.
    pub geometry_ids: Vec<u32>,
    /// Triangle index within its geometry of each hit.
    pub primitive_ids: Vec<u32>,
    /// Barycentric weights of the second and third vertices of each hit.
    pub primitive_uvs: Vec<[f32; 2]>,
}

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
    /// The closest hit of each ray `[ox, oy, oz, dx, dy, dz]` with `t ≥ 0`. The direction
    /// need not be normalized; `t_hit` is in units of its length. Rays with a non-finite
    /// component or a zero direction miss.
    pub fn cast_rays(
        &self,
        rays: &[[f32; 6]],
        options: &QueryOptions,
    ) -> Result<CastRays, RaycastError> {
        self.cast(rays, None, options)
    }

    /// [`RaycastingScene::cast_rays`] on the rays of an image stored row after row,
    /// `row_length` rays per row, as [`create_rays_pinhole`](super::create_rays_pinhole)
    /// makes them: the same results, bit for bit, found faster. Neighbouring rays go through
    /// the hierarchy together as packets, and packets of 4 × 4 rays (4 × 2 without AVX-512)
    /// meet fewer boxes and triangles than runs of 16 rays of one row (a 724² image of the
    /// Stanford bunny on one thread: 1.17× the rays per second; through Python on two
    /// threads, 1024² images gain less, within the calls' spread). A `row_length` of 0, or one
    /// longer than 4096, is the plain query.
    pub fn cast_rays_rows(
        &self,
        rays: &[[f32; 6]],
        row_length: usize,
        options: &QueryOptions,
    ) -> Result<CastRays, RaycastError> {
        let tiled = (1..=MAX_TILED_ROW).contains(&row_length);
        self.cast(rays, tiled.then_some(row_length), options)
    }

    /// The closest hits of `rays`, in bands of [`TILE`] rows of `row_length` rays when given.
    fn cast(
        &self,
        rays: &[[f32; 6]],
        row_length: Option<usize>,
        options: &QueryOptions,
    ) -> Result<CastRays, RaycastError> {
        let (accel, pool) = self.prepare(options)?;
        let accel = &*accel;
        let n = rays.len();
        budget(&[(n, RESULT_BYTES)], "the result")?;
        let mut out = CastRays {
            t_hit: filled(&pool, options, n, f32::INFINITY)?,
            geometry_ids: filled(&pool, options, n, INVALID_ID)?,
            primitive_ids: filled(&pool, options, n, INVALID_ID)?,
            primitive_uvs: filled(&pool, options, n, [0.0; 2])?,
            primitive_normals: filled(&pool, options, n, [0.0; 3])?,
        };
        let chunk = row_length.map_or(CHUNK, |w| TILE * w);
        let items = (
            rays.par_chunks(chunk),
            out.t_hit.par_chunks_mut(chunk),
            out.geometry_ids.par_chunks_mut(chunk),
            out.primitive_ids.par_chunks_mut(chunk),
            out.primitive_uvs.par_chunks_mut(chunk),
            out.primitive_normals.par_chunks_mut(chunk),
        )
            .into_par_iter()
            .enumerate();
        let far = FarOrigins::new();
        run(&pool, options, items, |(k, (rays, t, g, p, uv, normal))| {
            far.check(k * chunk, rays);
            // The rays in the order of the packets: tile by tile across a band, or as given.
            let order: Option<Vec<usize>> = row_length.map(|w| tile_order(rays.len(), w));
            let index = |j: usize| order.as_ref().map_or(j, |o| o[j]);
            let prepared: Vec<Option<PreparedRay>> =
                (0..rays.len()).map(|j| prepare(&rays[index(j)])).collect();
            let mut hits = vec![None; rays.len()];
            let kernel = CastPackets {
                accel,
                options,
                rays: &prepared,
                hits: &mut hits,
            };
            dispatch(simd_path(), kernel);
            if accel.has_placements() {
                // The rays as given, in the packets' order.
                let rays: Cow<[[f32; 6]]> = match &order {
                    Some(o) => o.iter().map(|&i| rays[i]).collect(),
                    None => rays.into(),
                };
                let hits = &mut hits;
                let rays = &rays;
                dispatch(
                    simd_path(),
                    ClosestPlaced {
                        accel,
                        options,
                        rays,
                        hits,
                    },
                );
            }
            for (j, hit) in hits.into_iter().enumerate() {
                let Some(hit) = hit else { continue };
                let i = index(j);
                let c = hit.crossing;
                t[i] = c.t;
                (g[i], p[i]) = (hit.geometry, hit.primitive);
                uv[i] = [c.b1, c.b2];
                normal[i] = accel.normal(hit.level, hit.slot);
            }
        })?;
        far.result()?;
        Ok(out)
    }

    /// For each ray, whether a triangle meets it with `t` in `[tnear, tfar]` (Open3D's
    /// defaults are `tnear = 0`, `tfar = ∞`). Rays on an edge or vertex are occluded.
    pub fn test_occlusions(
        &self,
        rays: &[[f32; 6]],
        tnear: f32,
        tfar: f32,
        options: &QueryOptions,
    ) -> Result<Vec<bool>, RaycastError> {
        let (accel, pool) = self.prepare(options)?;
        let accel = &*accel;
        let mut out = filled(&pool, options, rays.len(), false)?;
        let items = rays.par_chunks(CHUNK).zip(out.par_chunks_mut(CHUNK));
        let far = FarOrigins::new();
        run(&pool, options, items.enumerate(), |(k, (rays, out))| {
            far.check(k * CHUNK, rays);
            let range = (tnear, tfar);
            let out = &mut *out;
            dispatch(
                simd_path(),
                Occlusions::<_, false> {
                    accel,
                    options,
                    rays,
                    range,
                    out,
                },
            );
            if accel.has_placements() {
                dispatch(
                    simd_path(),
                    Occlusions::<_, true> {
                        accel,
                        options,
                        rays,
                        range,
                        out,
                    },
                );
            }
        })?;
        far.result()?;
        Ok(out)
    }

    /// The number of times each ray crosses the surface with `t ≥ 0`: a ray through an edge
    /// or vertex where the surface crosses it counts once (see the module docs). From a point
    /// outside a closed mesh the count is even.
    pub fn count_intersections(
        &self,
        rays: &[[f32; 6]],
        options: &QueryOptions,
    ) -> Result<Vec<i32>, RaycastError> {
        let (accel, pool) = self.prepare(options)?;
        let border = &lazy::borders(&accel, &pool, options)?;
        let accel = &*accel;
        let mut out = filled(&pool, options, rays.len(), 0i32)?;
        let items = rays.par_chunks(CHUNK).zip(out.par_chunks_mut(CHUNK));
        let far = FarOrigins::new();
        run(&pool, options, items.enumerate(), |(k, (rays, out))| {
            far.check(k * CHUNK, rays);
            let out = &mut *out;
            dispatch(
                simd_path(),
                Counts::<_, false> {
                    accel,
                    border,
                    options,
                    rays,
                    out,
                },
            );
            if accel.has_placements() {
                dispatch(
                    simd_path(),
                    Counts::<_, true> {
                        accel,
                        border,
                        options,
                        rays,
                        out,
                    },
                );
            }
        })?;
        far.result()?;
        Ok(out)
    }

    /// Every crossing of every ray with `t ≥ 0`, as [`count_intersections`] counts them,
    /// sorted by `t` within each ray.
    ///
    /// [`count_intersections`]: Self::count_intersections
    pub fn list_intersections(
        &self,
        rays: &[[f32; 6]],
        options: &QueryOptions,
    ) -> Result<Intersections, RaycastError> {
        let (accel, pool) = self.prepare(options)?;
        let border = &lazy::borders(&accel, &pool, options)?;
        let accel = &*accel;
        let far = FarOrigins::new();
        // The first error (memory, cancel) stops the other chunks, and what they hold is
        // freed.
        let chunks: Result<Vec<_>, RaycastError> = pool.install(|| {
            rays.par_chunks(CHUNK)
                .enumerate()
                .map(|(k, rays)| {
                    far.check(k * CHUNK, rays);
                    dispatch(
                        simd_path(),
                        Listing {
                            accel,
                            border,
                            rays,
                            options,
                        },
                    )
                })
                .collect()
        });
        if options.cancelled() {
            return Err(RaycastError::Cancelled);
        }
        far.result()?;
        let chunks = chunks?;
        let total: usize = chunks.iter().map(|(_, h)| h.len()).sum();
        if total > u32::MAX as usize {
            return Err(RaycastError::TooManyIntersections);
        }
        // Each hit's record (ray id, t, ids, uv: 24 bytes) and the ray splits.
        let what = "the intersections";
        budget(&[(total, 24), (rays.len() + 1, 4)], what)?;
        let mut out = Intersections {
            ray_splits: room(rays.len() + 1, what)?,
            ray_ids: room(total, what)?,
            t_hit: room(total, what)?,
            geometry_ids: room(total, what)?,
            primitive_ids: room(total, what)?,
            primitive_uvs: room(total, what)?,
        };
        out.ray_splits.push(0);
        let mut ray = 0u32;
        for (counts, hits) in chunks {
            let mut hits = hits.iter();
            for count in counts {
                let last = *out.ray_splits.last().unwrap_or(&0);
                out.ray_splits.push(last + count);
                for h in hits.by_ref().take(count as usize) {
                    out.ray_ids.push(ray);
                    out.t_hit.push(h.crossing.t);
                    out.geometry_ids.push(h.geometry);
                    out.primitive_ids.push(h.primitive);
                    out.primitive_uvs.push([h.crossing.b1, h.crossing.b2]);
                }
                ray += 1;
            }
        }
        Ok(out)
    }

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
