//! One render's fixed parts and the work on a row of pixels: camera rays of a few neighbouring
//! pixels traced together (a pinhole's rays share their origin), then every hit shaded.

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::{Vec2, Vec3};

use super::aov::{AovContext, AovPixel};
use super::RenderSettings;
use crate::camera::FilmCamera;
use crate::geometry::Hit;
use crate::integrator::{BatchScratch, Integrator, CAMERA_T_MIN};
use crate::light::{EnvironmentLight, Light};
use crate::math::{Ray, Rgb};
use crate::sampling::{jittered_offset, Rng};
use crate::world::World;

/// Salts the seed of the thin lens's samples (see [`Job::pixels`]).
const LENS_STREAM: u64 = 0x6c65_6e73_2d73_6d70;

/// Camera rays traced together: a packet of the widest SIMD path, four pixels of the usual
/// 4 samples. More pixels per batch only when they have fewer samples.
const BATCH_RAYS: u32 = 16;

/// One render's fixed parts, shared by its workers.
pub(super) struct Job<'a> {
    pub(super) world: &'a World,
    pub(super) settings: &'a RenderSettings,
    pub(super) camera: FilmCamera,
    pub(super) integrator: Integrator<'a>,
    /// The pixel offsets of a deterministic sampler; `None` for jittered.
    pub(super) offsets: Option<Vec<Vec2>>,
    /// Present when the render computes AOVs.
    pub(super) aovs: Option<AovContext>,
    /// Checked before every sample is shaded.
    pub(super) cancel: Option<&'a AtomicBool>,
    /// The environments camera rays that miss see (see [`visible_environments`]).
    pub(super) sky: Vec<&'a EnvironmentLight>,
}

/// The environment lights of `world` marked visible, found once per render rather than per
/// missed camera ray.
pub(super) fn visible_environments(world: &World) -> Vec<&EnvironmentLight> {
    let lights = world.lights().iter();
    lights
        .filter_map(|l| match l {
            Light::Environment(e) if e.visible => Some(e),
            _ => None,
        })
        .collect()
}

/// Buffers one worker reuses from one batch of pixels to the next.
#[derive(Default)]
pub(super) struct Buffers {
    scratch: BatchScratch,
    /// Each camera ray's film point, direction, its sample's generator (after the pixel
    /// jitter, ready for the light jitter) and its hit.
    film: Vec<(f32, f32)>,
    dirs: Vec<Vec3>,
    rngs: Vec<Rng>,
    hits: Vec<Option<Hit>>,
    /// The hits of the rays that hit.
    found: Vec<Hit>,
    /// The directions of the rays that hit, and their generators, and what shading them
    /// gave.
    hit_dirs: Vec<Vec3>,
    hit_rngs: Vec<Rng>,
    shaded: Vec<(Rgb, u64)>,
    /// A thin lens's sample of each camera ray (empty without an aperture).
    lens: Vec<Vec2>,
    lens_rays: LensRays,
}

/// What [`Job::trace_lens`] reuses: each ray's origin, and the rays the lens sees.
#[derive(Default)]
struct LensRays {
    origins: Vec<Vec3>,
    seen: Vec<usize>,
    seen_dirs: Vec<Vec3>,
    seen_hits: Vec<Option<Hit>>,
}

impl Job<'_> {
    /// What a camera ray in direction `d` that hits nothing sees: the environments marked
    /// visible, summed, or the background when there is none (or no direction: the lens
    /// sees nothing there); nothing with alpha, where a miss is transparent.
    fn miss(&self, d: Vec3) -> Rgb {
        if self.settings.alpha {
            return Rgb::ZERO;
        }
        let Some((first, rest)) = self.sky.split_first().filter(|_| d != Vec3::ZERO) else {
            return self.settings.background;
        };
        let d = d.normalize();
        rest.iter()
            .fold(first.radiance(d), |sum, e| sum + e.radiance(d))
    }

    /// The camera rays of a lens other than the plain pinhole: each film point's ray by the
    /// lens model, its direction written to `dirs` (zero where the model sees nothing: never
    /// traced, a miss) and its hit to `hits`. Rays from the eye are traced as
    /// packets; rays from an aperture or an orthographic film one by one.
    fn trace_lens(
        &self,
        film: &[(f32, f32)],
        lens: &[Vec2],
        dirs: &mut Vec<Vec3>,
        hits: &mut Vec<Option<Hit>>,
        rays: &mut LensRays,
    ) {
        let camera = &self.camera;
        let accel = self.world.accel();
        let LensRays {
            origins,
            seen,
            seen_dirs,
            seen_hits,
        } = rays;
        origins.clear();
        for (i, &(x, y)) in film.iter().enumerate() {
            let on_lens = lens.get(i).copied().unwrap_or(Vec2::splat(0.5));
            let ray = camera.sample_ray(x, y, on_lens);
            origins.push(ray.map_or(camera.eye(), |r| r.origin));
            dirs.push(ray.map_or(Vec3::ZERO, |r| r.direction));
        }
        hits.clear();
        hits.resize(dirs.len(), None);
        let traced = (0..dirs.len()).filter(|&i| dirs[i] != Vec3::ZERO);
        if !camera.shares_origin() {
            for i in traced {
                let ray = Ray::new(origins[i], dirs[i]);
                hits[i] = accel.intersect(&ray, CAMERA_T_MIN, f32::INFINITY);
            }
            return;
        }
        seen.clear();
        seen.extend(traced);
        seen_dirs.clear();
        seen_dirs.extend(seen.iter().map(|&i| dirs[i]));
        seen_hits.clear();
        seen_hits.resize(seen.len(), None);
        accel.intersect_from(
            camera.eye(),
            seen_dirs,
            CAMERA_T_MIN,
            f32::INFINITY,
            seen_hits,
        );
        for (&i, &hit) in seen.iter().zip(seen_hits.iter()) {
            hits[i] = hit;
        }
    }

    /// Adds to `sums` (colours and counts of hits, one per pixel of `xs`, in order) the
    /// samples `samples` of the pixels `xs` of row `y` of the full film, each pixel's in
    /// sample order (and appends their AOVs to `aovs` when the render computes them), and
    /// returns the shadow rays they took; `None` once the render is cancelled. A pixel's
    /// value is its sum over all its samples divided by their number; summing the samples in
    /// passes gives the same sums.
    pub(super) fn row(
        &self,
        y: u32,
        xs: Range<u32>,
        samples: Range<u32>,
        buffers: &mut Buffers,
        (colors, hits): (&mut [Rgb], &mut [f32]),
        aovs: &mut Vec<AovPixel>,
    ) -> Option<u64> {
        let spp = samples.len() as u32;
        let per_batch = (BATCH_RAYS / spp.max(1)).max(1);
        let mut shadow = 0;
        let mut x0 = xs.start;
        while x0 < xs.end {
            let x1 = (x0 + per_batch).min(xs.end);
            let at = (x0 - xs.start) as usize..(x1 - xs.start) as usize;
            let sums = (&mut colors[at.clone()], &mut hits[at]);
            shadow += self.pixels(y, x0..x1, samples.clone(), buffers, sums, aovs)?;
            x0 = x1;
        }
        Some(shadow)
    }

    /// [`Job::row`] for a few pixels: every sample's camera ray first, traced in one call,
    /// then each pixel's sum in sample order.
    fn pixels(
        &self,
        y: u32,
        xs: Range<u32>,
        samples: Range<u32>,
        buffers: &mut Buffers,
        (sums, hit_counts): (&mut [Rgb], &mut [f32]),
        aovs: &mut Vec<AovPixel>,
    ) -> Option<u64> {
        let settings = self.settings;
        let n = settings.samples_per_axis();
        let spp = samples.len();
        let Buffers {
            scratch,
            film,
            dirs,
            rngs,
            hits,
            found,
            hit_dirs,
            hit_rngs,
            shaded,
            lens,
            lens_rays,
        } = buffers;
        film.clear();
        rngs.clear();
        lens.clear();
        let camera = &self.camera;
        // A sample's generator is hashed from its pixel and index, and kept, only when
        // something draws from it (3 % of the instructions under three point lights).
        let draws = self.offsets.is_none() || self.integrator.draws();
        let unread = Rng::new(settings.seed, &[]);
        for x in xs.clone() {
            let pixel_index = y as u64 * settings.width as u64 + x as u64;
            for s in samples.clone() {
                let mut rng = match draws {
                    true => Rng::new(settings.seed, &[pixel_index, s as u64]),
                    false => unread.clone(),
                };
                let offset = match &self.offsets {
                    Some(o) => o[s as usize],
                    None => jittered_offset(n, s / n, s % n, rng.uniform2()),
                };
                film.push((x as f32 + 0.5 + offset.x, y as f32 + 0.5 + offset.y));
                if camera.has_aperture() {
                    // A stream of its own, so that the rest of the sample draws as a
                    // pinhole's would.
                    let mut on_lens =
                        Rng::new(settings.seed ^ LENS_STREAM, &[pixel_index, s as u64]);
                    lens.push(on_lens.uniform2());
                }
                if draws {
                    rngs.push(rng);
                }
            }
        }
        dirs.clear();
        match camera.is_pinhole() {
            // The directions in a loop of their own, which vectorizes, then traced as
            // packets from the shared eye.
            true => {
                camera.extend_directions(film, dirs);
                hits.resize(dirs.len(), None);
                let accel = self.world.accel();
                accel.intersect_from(camera.eye(), dirs, CAMERA_T_MIN, f32::INFINITY, hits);
            }
            false => self.trace_lens(film, lens, dirs, hits, lens_rays),
        }
        hit_dirs.clear();
        found.clear();
        for (hit, &dir) in hits.iter().zip(dirs.iter()) {
            if let Some(hit) = hit {
                hit_dirs.push(dir);
                found.push(*hit);
            }
        }
        hit_rngs.clear();
        match draws {
            true => hit_rngs.extend(
                hits.iter()
                    .zip(rngs.iter())
                    .filter(|(hit, _)| hit.is_some())
                    .map(|(_, rng)| rng.clone()),
            ),
            false => hit_rngs.resize(found.len(), unread),
        }
        // One pixel can hold hours of work (65536 samples of a million shadow rays each): a
        // cancelled render stops before the next few points are shaded, within milliseconds.
        shaded.clear();
        let step = self.integrator.batch_points();
        for start in (0..hit_dirs.len()).step_by(step) {
            if self.cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
                return None;
            }
            let end = (start + step).min(hit_dirs.len());
            self.integrator.shade_batch(
                &hit_dirs[start..end],
                &found[start..end],
                &mut hit_rngs[start..end],
                scratch,
                shaded,
            );
        }

        let mut shadow = 0;
        let mut next = 0;
        for (pixel, x) in xs.enumerate() {
            let mut sum = sums[pixel];
            let mut albedo = Rgb::ZERO;
            let mut count = 0;
            for (i, hit) in hits.iter().enumerate().skip(pixel * spp).take(spp) {
                if hit.is_some() {
                    count += 1;
                    if self.aovs.is_some() {
                        albedo += self.world.albedo(&self.world.surface(&found[next]));
                    }
                    let (c, rays) = shaded[next];
                    sum += c;
                    shadow += rays;
                    next += 1;
                } else {
                    sum += self.miss(dirs[i]);
                }
            }
            sums[pixel] = sum;
            hit_counts[pixel] += count as f32;
            if let Some(ctx) = &self.aovs {
                let mut px = ctx.center(self.world, &self.camera, x, y);
                px.albedo = albedo / spp as f32;
                aovs.push(px);
            }
        }
        Some(shadow)
    }
}
