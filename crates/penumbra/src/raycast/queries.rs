//! The ray queries of [`RaycastingScene`]: closest hits, occlusion, counting and listing
//! intersections (the point queries are in `points`).

use std::borrow::Cow;

use rayon::prelude::*;

use super::lazy;
use super::run::{budget, filled, room, run, FarOrigins, QueryOptions, CHUNK};
use super::{RaycastError, RaycastingScene, INVALID_ID};
use crate::accel::wide::kernels::{closest_hits, counts, occlusions, Listing};
use crate::simd::{dispatch, simd_path};

/// The range of `t` of Open3D's `cast_rays` and `count_intersections`.
pub(super) const ALL: (f32, f32) = (0.0, f32::INFINITY);

/// Rows per band of [`RaycastingScene::cast_rays_rows`], and columns per tile: the packets
/// (32 rays) are then 8 × 4 neighbouring rays.
const TILE: usize = 4;

/// Bytes of [`CastRays`] per ray: `t_hit`, two ids, uv and normal.
const RESULT_BYTES: usize = 4 + 4 + 4 + 8 + 12;

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

impl RaycastingScene {
    /// The closest hit of each ray `[ox, oy, oz, dx, dy, dz]` with `t ≥ 0`. The direction
    /// need not be normalized; `t_hit` is in units of its length. Rays with a non-finite
    /// component or a zero direction miss.
    pub fn cast_rays(
        &self,
        rays: &[[f32; 6]],
        options: &QueryOptions,
    ) -> Result<CastRays, RaycastError> {
        self.cast(rays, None, ALL, options)
    }

    /// [`RaycastingScene::cast_rays`] on the rays of an image stored row after row,
    /// `row_length` rays per row, as [`create_rays_pinhole`](super::create_rays_pinhole)
    /// makes them: the same results, bit for bit, found faster. Neighbouring rays go through
    /// the hierarchy together as packets, and packets of 8 × 4 rays meet fewer boxes and
    /// triangles than runs of one row, the more so on a large mesh (measured:
    /// docs/benchmarks.md, «Design measurements», `RaycastingScene::cast_rays_rows`). A
    /// `row_length` of 0, or one longer than 4096, is the plain query.
    pub fn cast_rays_rows(
        &self,
        rays: &[[f32; 6]],
        row_length: usize,
        options: &QueryOptions,
    ) -> Result<CastRays, RaycastError> {
        self.cast_rays_between(rays, row_length, ALL, options)
    }

    /// [`RaycastingScene::cast_rays_rows`] with only the hits of `t` in `[tnear, tfar]`
    /// (`range`), as [`RaycastingScene::test_occlusions`] bounds its rays: penumbra's
    /// extension of Open3D's `cast_rays`, which always takes `[0, ∞]` (Open3D#5870). Bounds
    /// other than `[0, ∞]` trace the rays one at a time; an empty range hits nothing.
    pub fn cast_rays_between(
        &self,
        rays: &[[f32; 6]],
        row_length: usize,
        range: (f32, f32),
        options: &QueryOptions,
    ) -> Result<CastRays, RaycastError> {
        let tiled = (1..=MAX_TILED_ROW).contains(&row_length);
        self.cast(rays, tiled.then_some(row_length), range, options)
    }

    /// The closest hits of `rays` with `t` in `range`, in bands of [`TILE`] rows of
    /// `row_length` rays when given.
    fn cast(
        &self,
        rays: &[[f32; 6]],
        row_length: Option<usize>,
        range: (f32, f32),
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
            let ordered: Cow<[[f32; 6]]> = match &order {
                Some(o) => o.iter().map(|&i| rays[i]).collect(),
                None => Cow::from(rays),
            };
            let mut hits = vec![None; rays.len()];
            closest_hits(simd_path(), (accel, options), (&ordered, range), &mut hits);
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
            occlusions(simd_path(), (accel, options), rays, (tnear, tfar), out);
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
        self.count_intersections_between(rays, ALL, options)
    }

    /// [`RaycastingScene::count_intersections`] of the crossings with `t` in `[tnear, tfar]`
    /// (`range`): penumbra's extension of Open3D's query (Open3D#5870); an empty range
    /// counts nothing.
    pub fn count_intersections_between(
        &self,
        rays: &[[f32; 6]],
        range: (f32, f32),
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
            counts(simd_path(), (accel, options), (border, range), rays, out);
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
            ray_ids: filled(&pool, options, total, 0)?,
            t_hit: filled(&pool, options, total, 0.0)?,
            geometry_ids: filled(&pool, options, total, 0)?,
            primitive_ids: filled(&pool, options, total, 0)?,
            primitive_uvs: filled(&pool, options, total, [0.0; 2])?,
        };
        out.ray_splits.push(0);
        let mut last = 0;
        for &count in chunks.iter().flat_map(|(counts, _)| counts) {
            last += count;
            out.ray_splits.push(last);
        }
        // Each chunk's hits into its own part of the arrays, the chunks in parallel.
        let sizes: Vec<usize> = chunks.iter().map(|(_, hits)| hits.len()).collect();
        let items = (
            chunks.par_iter(),
            parts(&mut out.ray_ids, &sizes),
            parts(&mut out.t_hit, &sizes),
            parts(&mut out.geometry_ids, &sizes),
            parts(&mut out.primitive_ids, &sizes),
            parts(&mut out.primitive_uvs, &sizes),
        );
        let items = items.into_par_iter().enumerate();
        run(
            &pool,
            options,
            items,
            |(k, ((counts, hits), ray_ids, t, g, p, uv))| {
                let rays = counts.iter().enumerate().flat_map(|(i, &count)| {
                    std::iter::repeat_n((k * CHUNK + i) as u32, count as usize)
                });
                for (j, (h, ray)) in hits.iter().zip(rays).enumerate() {
                    ray_ids[j] = ray;
                    t[j] = h.crossing.t;
                    (g[j], p[j]) = (h.geometry, h.primitive);
                    uv[j] = [h.crossing.b1, h.crossing.b2];
                }
            },
        )?;
        Ok(out)
    }
}

/// `v` cut into consecutive parts of the lengths `sizes` (which sum to at most its length).
fn parts<'a, T>(mut v: &'a mut [T], sizes: &[usize]) -> Vec<&'a mut [T]> {
    sizes
        .iter()
        .map(|&n| {
            let (part, rest) = std::mem::take(&mut v).split_at_mut(n);
            v = rest;
            part
        })
        .collect()
}
