//! Renders a [`World`] with per-call [`RenderSettings`] into a [`Film`]: tiles over a local
//! rayon pool, each pixel the box-filtered mean of its samples. A pixel's value depends only on
//! its coordinates in the full film, so any thread count, scheduling or region gives the same
//! bits. [`render_with_aovs`] also returns per-pixel AOVs (see [`AovPixel`]); [`render`] computes
//! none of them.

mod aov;
mod job;
mod passes;
mod patch;
mod settings;
mod sums;

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use rayon::prelude::*;
use thiserror::Error;

use crate::camera::FilmCamera;
use crate::film::Film;
use crate::integrator::Integrator;
use crate::math::Rgb;
use crate::pool::thread_pool;
use crate::sampling::fixed_offsets;
use crate::world::World;
use aov::AovContext;
use job::{Buffers, Job};
use passes::{plan, Rows};
use sums::{image, Sums};

pub use aov::{Aov, AovFilm, AovPixel, AovValues, NO_ID};
pub use passes::{Pass, PassSink};
pub(crate) use patch::implied_spp;
pub use patch::SettingsPatch;
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

/// A finished tile of a render (see [`RenderOptions::tiles`]).
#[derive(Clone, Copy, Debug)]
pub struct Tile<'a> {
    /// Its bounds, in pixels of the full film.
    pub bounds: PixelBounds,
    /// Its linear RGB pixels, row by row (premultiplied with alpha).
    pub pixels: &'a [Rgb],
    /// Their coverage with [`RenderSettings::alpha`]; empty without.
    pub alpha: &'a [f32],
    /// Their AOVs; empty unless the render computes them.
    pub aovs: &'a [AovPixel],
}

/// What receives finished tiles (see [`RenderOptions::tiles`]).
pub type TileSink<'a> = dyn Fn(&Tile) + Sync + 'a;

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
    /// Called from worker threads as each tile is finished, with its values (see [`Tile`]):
    /// what a live preview shows. Tiles finish in any order; the film gets the same values.
    pub tiles: Option<&'a TileSink<'a>>,
    /// Progressive rendering: the samples of every pixel are taken in passes over the whole
    /// film (a preview of every second row, then 1, 2, 4, … samples in all, see [`Pass`])
    /// and this is called on the calling thread after each pass but the last with the image
    /// so far. The final film is the same, bit for bit, as without passes. Ignored by
    /// [`render_with_aovs`] (one pass).
    pub passes: Option<&'a PassSink<'a>>,
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
    /// The image (with its AOVs) does not fit in memory.
    #[error("not enough memory for a {width}x{height} image{}", memory_detail(*need))]
    OutOfMemory {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
        /// The bytes it needs and the bytes available, when the refusal came from comparing
        /// them (`None`: an allocation failed).
        need: Option<(u64, u64)>,
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

/// How much memory [`RenderError::OutOfMemory`] says was needed, when known.
fn memory_detail(need: Option<(u64, u64)>) -> String {
    need.map_or_else(String::new, |(need, available)| {
        format!(
            ": it needs about {}, more than the {} available",
            crate::memory::human(need),
            crate::memory::human(available)
        )
    })
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

/// Memory a pixel of the film takes while it renders: its colour and coverage, and its AOVs
/// when asked for.
fn bytes_per_pixel(with_aovs: bool) -> u64 {
    let aovs = if with_aovs {
        std::mem::size_of::<AovPixel>()
    } else {
        0
    };
    (std::mem::size_of::<Rgb>() + std::mem::size_of::<f32>() + aovs) as u64
}

/// Refuses a `width × height` film (with its AOVs) that would not fit in the memory the
/// process may still take, before anything is allocated.
fn check_memory(
    (width, height): (u32, u32),
    with_aovs: bool,
    available: Option<u64>,
) -> Result<(), RenderError> {
    let need = width as u64 * height as u64 * bytes_per_pixel(with_aovs);
    match available {
        Some(available) if need > available => Err(RenderError::OutOfMemory {
            width,
            height,
            need: Some((need, available)),
        }),
        _ => Ok(()),
    }
}

/// A buffer of `len` values, or the error that the image does not fit in memory; filled on
/// `pool`. The first write to each page of a fresh buffer faults it in: a 1024² film is
/// about 3,000 faults, which one thread took while the others waited (measured:
/// docs/benchmarks.md, «Design measurements», `render::buffer`).
fn buffer<T: Copy + Send + Sync>(
    len: usize,
    value: T,
    (width, height): (u32, u32),
    pool: &rayon::ThreadPool,
) -> Result<Vec<T>, RenderError> {
    let mut v: Vec<T> = Vec::new();
    v.try_reserve_exact(len)
        .map_err(|_| RenderError::OutOfMemory {
            width,
            height,
            need: None,
        })?;
    pool.install(|| v.par_extend(rayon::iter::repeat_n(value, len)));
    Ok(v)
}

/// What one worker keeps from one tile to the next: its scratch buffers and the sums of the
/// tile it is working on.
#[derive(Default)]
struct Worker {
    buffers: Buffers,
    sums: Sums,
}

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
    check_memory((rw, rh), with_aovs, crate::memory::available())?;
    let len = rw as usize * rh as usize;
    let (pool, threads) = thread_pool(options.threads).map_err(|e| RenderError::Threads {
        threads: options.threads,
        message: e,
    })?;
    let colors = buffer(len, Rgb::ZERO, (rw, rh), &pool)?;
    let hits = buffer(if settings.alpha { len } else { 0 }, 0.0, (rw, rh), &pool)?;
    let aovs = buffer(
        if with_aovs { len } else { 0 },
        AovPixel::MISS,
        (rw, rh),
        &pool,
    )?;
    let job = Job {
        camera: FilmCamera::new(&camera, width, height),
        integrator: Integrator::new(world, settings.shading_settings()),
        world,
        settings,
        offsets: fixed_offsets(settings.sampler, settings.samples_per_axis()),
        aovs: with_aovs.then(|| AovContext::new(world)),
        cancel: options.cancel,
        sky: job::visible_environments(world),
    };

    // Tiles are numbered row by row; none is stored, so the render's memory is the film's.
    let columns = rw.div_ceil(TILE) as u64;
    let tile_count = columns * rh.div_ceil(TILE) as u64;
    let tile = |i: u64| {
        let x0 = region.x0 + (i % columns) as u32 * TILE;
        let y0 = region.y0 + (i / columns) as u32 * TILE;
        PixelBounds {
            x0,
            x1: (x0 + TILE).min(region.x1),
            y0,
            y1: (y0 + TILE).min(region.y1),
        }
    };
    let spp = settings.samples_per_axis().pow(2);
    // Progress counts pixel samples and reports them as pixels (whole ones when one pass).
    let (pixels_in_all, spp64) = (rw as u64 * rh as u64, spp as u64);
    let total = pixels_in_all * spp64;
    let done = AtomicU64::new(0);
    let shadow_rays = AtomicU64::new(0);
    let start = Instant::now();
    let cancelled = || options.cancel.is_some_and(|c| c.load(Ordering::Relaxed));
    // The film holds each pixel's sum over the samples so far; it is divided at the end.
    let film = Mutex::new(Sums { colors, hits, aovs });
    let passes = match (options.passes, with_aovs) {
        (Some(_), false) => plan(spp, rh),
        _ => vec![(Rows::All, 0..spp)],
    };

    // One pass leaves every pixel's sum final as its tile ends: the tile divides it then,
    // while it is in the caches (a pass over the film afterwards read 12 MB at 1024²).
    let divided = passes.len() == 1;
    for (index, (rows, samples)) in passes.iter().enumerate() {
        let rows = *rows;
        let count = if divided { 1.0 } else { samples.end as f32 };
        pool.install(|| {
            // Scratch buffers are made once per rayon job, not per tile: a tile's worth of
            // work is small, and filling fresh buffers cost allocations and page faults.
            (0..tile_count)
                .into_par_iter()
                .for_each_init(Worker::default, |worker, i| {
                    if cancelled() {
                        return;
                    }
                    let tile = tile(i);
                    let Worker { buffers, sums } = worker;
                    let carried = samples.start > 0 || rows == Rows::Odd;
                    sums.load(&film, region, &tile, carried);
                    let (tw, mut shadow) = ((tile.x1 - tile.x0) as usize, 0);
                    let Sums { colors, hits, aovs } = sums;
                    for ((y, colors), hits) in (tile.y0..tile.y1)
                        .zip(colors.chunks_mut(tw))
                        .zip(hits.chunks_mut(tw))
                    {
                        if !rows.has(y) {
                            continue;
                        }
                        let xs = tile.x0..tile.x1;
                        let row = (colors, hits);
                        match job.row(y, xs, samples.clone(), buffers, row, aovs) {
                            Some(s) => shadow += s,
                            None => return,
                        }
                    }
                    shadow_rays.fetch_add(shadow, Ordering::Relaxed);
                    if divided {
                        sums.divide(spp as f32);
                    }
                    sums.store(&film, region, &tile);
                    if let Some(show) = options.tiles {
                        let (bounds, first) = ((tile.y0, tile.y1), rows == Rows::Even);
                        let alpha = match settings.alpha {
                            true => image(&sums.hits, tw, bounds, first, count),
                            false => Vec::new(),
                        };
                        show(&Tile {
                            bounds: tile,
                            pixels: &image(&sums.colors, tw, bounds, first, count),
                            alpha: &alpha,
                            aovs: &sums.aovs,
                        });
                    }
                    let done_rows = (tile.y0..tile.y1).filter(|&y| rows.has(y)).count();
                    let n = (done_rows * tw) as u64 * samples.len() as u64;
                    let d = done.fetch_add(n, Ordering::Relaxed) + n;
                    if let Some(progress) = options.progress {
                        progress(d / spp64, pixels_in_all);
                    }
                })
        });
        if cancelled() {
            return Err(RenderError::Cancelled);
        }
        if let (Some(show), true) = (options.passes, index + 1 < passes.len()) {
            let sums = film.lock().unwrap_or_else(|e| e.into_inner());
            let (bounds, first) = ((region.y0, region.y1), rows == Rows::Even);
            let image = Film {
                width: rw,
                height: rh,
                pixels: image(&sums.colors, rw as usize, bounds, first, count),
                alpha: (settings.alpha)
                    .then(|| image(&sums.hits, rw as usize, bounds, first, count)),
            };
            show(&Pass {
                index,
                samples: if first { 0 } else { samples.end },
                film: &image,
            });
        }
    }
    if done.load(Ordering::Relaxed) != total {
        return Err(RenderError::Cancelled);
    }
    let Sums {
        mut colors,
        mut hits,
        aovs,
    } = film.into_inner().unwrap_or_else(|e| e.into_inner());
    if !divided {
        pool.install(|| colors.par_iter_mut().for_each(|v| *v /= spp as f32));
        pool.install(|| hits.par_iter_mut().for_each(|v| *v /= spp as f32));
    }
    let stats = RenderStats {
        camera_rays: rw as u64 * rh as u64 * spp as u64,
        shadow_rays: shadow_rays.into_inner(),
        time: start.elapsed(),
        threads,
    };
    let film = Film {
        width: rw,
        height: rh,
        pixels: colors,
        alpha: settings.alpha.then_some(hits),
    };
    Ok((film, aovs, stats))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A film is refused before anything is allocated when it (with its AOVs) needs more than
    /// the memory available.
    #[test]
    fn films_beyond_the_memory_available_are_refused() {
        const GIB: u64 = 1 << 30;
        let cases = [
            ((9000, 9000), false, Some(900 << 20), false),
            ((7000, 7000), false, Some(GIB / 2), false),
            ((7000, 7000), false, Some(GIB), true),
            ((6000, 6000), false, Some(GIB), true),
            ((6000, 6000), true, Some(GIB), false),
            ((16384, 16384), true, None, true),
        ];
        for (size, with_aovs, available, fits) in cases {
            let got = check_memory(size, with_aovs, available);
            assert_eq!(got.is_ok(), fits, "{size:?} {with_aovs}: {got:?}");
            if let Err(e) = got {
                let text = e.to_string();
                let name = format!("{}x{}", size.0, size.1);
                assert!(text.contains(&name) && text.contains("more than"), "{text}");
            }
        }
    }
}
