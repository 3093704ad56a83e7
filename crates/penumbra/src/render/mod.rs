//! Renders a [`World`] with per-call [`RenderSettings`] into a [`Film`]: tiles over a local
//! rayon pool, each pixel the box-filtered mean of its samples. A pixel's value depends only on
//! its coordinates in the full film, so any thread count, scheduling or region gives the same
//! bits. [`render_with_aovs`] also returns per-pixel AOVs (see [`AovPixel`]); [`render`] computes
//! none of them.

mod aov;
mod job;
mod settings;

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use rayon::prelude::*;
use thiserror::Error;

use crate::camera::PinholeCamera;
use crate::film::Film;
use crate::integrator::Integrator;
use crate::math::Rgb;
use crate::pool::thread_pool;
use crate::sampling::fixed_offsets;
use crate::world::World;
use aov::AovContext;
use job::{Buffers, Job};

pub use aov::{AovFilm, AovPixel, NO_ID};
pub use settings::{RenderSettings, SettingsError, View, MAX_LIGHT_SAMPLES, MAX_PIXELS, MAX_SPP};

/// A half-open pixel rectangle `[x0, x1) × [y0, y1)` of the full film (pbrt's
/// `--pixelbounds`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelBounds {
    /// First column.
    pub x0: u32,
    /// One past the last column.
    pub x1: u32,
    /// First row (from the top).
    pub y0: u32,
    /// One past the last row.
    pub y1: u32,
}

/// How to run a render: threads, region, cancellation and progress (what it shows is in the
/// [`RenderSettings`]).
#[derive(Clone, Copy, Default)]
pub struct RenderOptions<'a> {
    /// Worker threads; 0 means all available cores.
    pub threads: usize,
    /// Render only this region of the film (default: all of it).
    pub region: Option<PixelBounds>,
    /// Checked before every sample: when set, rendering stops with [`RenderError::Cancelled`]
    /// within one sample's work.
    pub cancel: Option<&'a AtomicBool>,
    /// Called from worker threads after each tile with (pixels done, pixels in all).
    pub progress: Option<&'a (dyn Fn(u64, u64) + Sync)>,
}

/// Counts and timings of a render.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Camera rays traced.
    pub camera_rays: u64,
    /// Shadow rays traced.
    pub shadow_rays: u64,
    /// Wall-clock time of the render.
    pub time: Duration,
    /// Threads used.
    pub threads: usize,
}

impl RenderStats {
    /// All rays per second of wall-clock time.
    pub fn rays_per_second(&self) -> f64 {
        (self.camera_rays + self.shadow_rays) as f64 / self.time.as_secs_f64().max(1e-9)
    }
}

/// Why a render did not finish.
#[derive(Debug, Error)]
pub enum RenderError {
    /// The settings cannot be rendered.
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// The cancel flag was set.
    #[error("interrupted")]
    Cancelled,
    /// The region is empty or reaches past the film.
    #[error(
        "pixel bounds {x0},{x1},{y0},{y1} are not a non-empty region of the {width}x{height} film"
    )]
    BadRegion {
        /// Requested bounds.
        x0: u32,
        /// See x0.
        x1: u32,
        /// See x0.
        y0: u32,
        /// See x0.
        y1: u32,
        /// Film width.
        width: u32,
        /// Film height.
        height: u32,
    },
    /// The image does not fit in memory.
    #[error("not enough memory for a {width}x{height} image")]
    OutOfMemory {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
    },
    /// The worker threads could not be started.
    #[error("cannot start {threads} render threads: {message}")]
    Threads {
        /// Requested count.
        threads: usize,
        /// The system's reason.
        message: String,
    },
}

const TILE: u32 = 16;

/// Renders `world` (or a region of its film) as `settings` say, run as `options` say.
pub fn render(
    world: &World,
    settings: &RenderSettings,
    options: &RenderOptions,
) -> Result<(Film, RenderStats), RenderError> {
    let (film, _, stats) = render_impl(world, settings, options, false)?;
    Ok((film, stats))
}

/// Renders like [`render`] and also returns the AOVs of every pixel of the film (or region):
/// the colour is the same, bit for bit. Costs one more camera ray per pixel and the albedo of
/// every sample.
pub fn render_with_aovs(
    world: &World,
    settings: &RenderSettings,
    options: &RenderOptions,
) -> Result<(Film, AovFilm, RenderStats), RenderError> {
    let (film, aovs, stats) = render_impl(world, settings, options, true)?;
    let aovs = AovFilm {
        width: film.width,
        height: film.height,
        pixels: aovs,
    };
    Ok((film, aovs, stats))
}

/// A buffer of `len` values, or the error that the image does not fit in memory.
fn buffer<T: Clone>(
    len: usize,
    value: T,
    (width, height): (u32, u32),
) -> Result<Vec<T>, RenderError> {
    let mut v: Vec<T> = Vec::new();
    v.try_reserve_exact(len)
        .map_err(|_| RenderError::OutOfMemory { width, height })?;
    v.resize(len, value);
    Ok(v)
}

/// What a tile's worker returns: its colours, its AOVs (empty unless asked for) and the shadow
/// rays it traced.
type TileOut = (Vec<Rgb>, Vec<AovPixel>, u64);

/// [`render`], with the AOVs of every pixel when `with_aovs` (else an empty vector).
fn render_impl(
    world: &World,
    settings: &RenderSettings,
    options: &RenderOptions,
    with_aovs: bool,
) -> Result<(Film, Vec<AovPixel>, RenderStats), RenderError> {
    let camera = settings.check(world)?;
    let (width, height) = (settings.width, settings.height);
    let region = options.region.unwrap_or(PixelBounds {
        x0: 0,
        x1: width,
        y0: 0,
        y1: height,
    });
    if region.x0 >= region.x1 || region.y0 >= region.y1 || region.x1 > width || region.y1 > height {
        let PixelBounds { x0, x1, y0, y1 } = region;
        return Err(RenderError::BadRegion {
            x0,
            x1,
            y0,
            y1,
            width,
            height,
        });
    }
    let (rw, rh) = (region.x1 - region.x0, region.y1 - region.y0);
    let len = rw as usize * rh as usize;
    let mut pixels = buffer(len, Rgb::ZERO, (rw, rh))?;
    let mut aov_pixels = buffer(if with_aovs { len } else { 0 }, AovPixel::MISS, (rw, rh))?;

    let (pool, threads) = thread_pool(options.threads).map_err(|e| RenderError::Threads {
        threads: options.threads,
        message: e,
    })?;
    let job = Job {
        camera: PinholeCamera::new(&camera, width, height),
        integrator: Integrator::new(world, settings.shading_settings()),
        world,
        settings,
        offsets: fixed_offsets(settings.sampler, settings.samples_per_axis()),
        aovs: with_aovs.then(|| AovContext::new(world)),
        cancel: options.cancel,
    };

    let tiles: Vec<PixelBounds> = (region.y0..region.y1)
        .step_by(TILE as usize)
        .flat_map(|y0| {
            (region.x0..region.x1)
                .step_by(TILE as usize)
                .map(move |x0| PixelBounds {
                    x0,
                    x1: (x0 + TILE).min(region.x1),
                    y0,
                    y1: (y0 + TILE).min(region.y1),
                })
        })
        .collect();
    let total = rw as u64 * rh as u64;
    let done = AtomicU64::new(0);
    let start = Instant::now();
    let cancelled = || options.cancel.is_some_and(|c| c.load(Ordering::Relaxed));

    let results: Vec<Option<TileOut>> = pool.install(|| {
        // Scratch buffers are made once per rayon job, not per tile: a tile's worth of
        // work is small, and filling fresh buffers cost allocations and page faults.
        tiles
            .par_iter()
            .map_init(Buffers::default, |buffers, tile| {
                if cancelled() {
                    return None;
                }
                let n = ((tile.x1 - tile.x0) * (tile.y1 - tile.y0)) as usize;
                let mut out = Vec::with_capacity(n);
                let mut aovs = Vec::with_capacity(if with_aovs { n } else { 0 });
                let mut shadow = 0;
                for y in tile.y0..tile.y1 {
                    shadow += job.row(y, tile.x0..tile.x1, buffers, &mut out, &mut aovs)?;
                }
                let n = out.len() as u64;
                let d = done.fetch_add(n, Ordering::Relaxed) + n;
                if let Some(progress) = options.progress {
                    progress(d, total);
                }
                Some((out, aovs, shadow))
            })
            .collect()
    });
    if cancelled() {
        return Err(RenderError::Cancelled);
    }

    let mut shadow_rays = 0;
    for (tile, result) in tiles.iter().zip(results) {
        let (values, aovs, shadow) = result.ok_or(RenderError::Cancelled)?;
        shadow_rays += shadow;
        let tw = (tile.x1 - tile.x0) as usize;
        for (row, chunk) in values.chunks(tw).enumerate() {
            let y = (tile.y0 - region.y0) as usize + row;
            let x = (tile.x0 - region.x0) as usize;
            let at = y * rw as usize + x;
            pixels[at..at + tw].copy_from_slice(chunk);
        }
        for (row, chunk) in aovs.chunks(tw).enumerate() {
            let y = (tile.y0 - region.y0) as usize + row;
            let at = y * rw as usize + (tile.x0 - region.x0) as usize;
            aov_pixels[at..at + tw].copy_from_slice(chunk);
        }
    }
    let stats = RenderStats {
        camera_rays: total * settings.spp as u64,
        shadow_rays,
        time: start.elapsed(),
        threads,
    };
    let film = Film {
        width: rw,
        height: rh,
        pixels,
    };
    Ok((film, aov_pixels, stats))
}
