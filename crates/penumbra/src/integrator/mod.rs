//! Direct lighting of SPEC §6 (docs/spec.md): ambient plus, for every light sample, a
//! (Blinn-)Phong or energy-normalized BRDF term, each gated by a shadow ray. Knows nothing of
//! files, cameras or films.
//!
//! An [`Integrator`] is made once per render from the world and the shading settings: it
//! plans every light (its emission weight under the light model and, for fixed grids, its
//! sample points). [`Integrator::shade_batch`] shades a few neighbouring points: at each it
//! gathers every light sample that could contribute, traces the shadow rays of all of them
//! (see `batch` for how they are grouped), and sums each point's unoccluded samples in light
//! and sample order.

mod across;
mod batch;
mod model;
mod plan;
mod pow;

use std::f32::consts::PI;

use glam::Vec3;

use crate::accel::{Grouping, SharedEnds};
use crate::geometry::Surface;
use crate::math::Rgb;
use crate::sampling::Rng;
use crate::simd::{simd_path, SimdPath};
use crate::world::World;
pub(crate) use batch::BatchScratch;
use model::{Lanes, Lobe, Model, Physical, Seed};
use plan::{fixed_ends, plan, Directions, LightPlan, Points, Source};

/// The specular lobe.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Shading {
    /// max(0, r·v)^p with r the mirrored light direction.
    Phong,
    /// max(0, n·h)^p with h the half vector.
    BlinnPhong,
}

/// How much light reaches a point and how the BRDF is normalized.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LightModel {
    /// The seed's: each area-light sample is a point light of color·intensity/N² shining
    /// both ways, no falloff; the BRDF is the plain Phong sum.
    Phong,
    /// Radiometric: one-sided area emitters with cosine and inverse-square falloff, and an
    /// energy-normalized BRDF.
    Physical,
}

/// What the integrator needs of a render's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingSettings {
    /// Specular lobe.
    pub shading: Shading,
    /// Light model.
    pub light_model: LightModel,
    /// Ambient light I_a.
    pub ambient: Rgb,
    /// N of every area light, replacing each light's own; `None` keeps them.
    pub light_samples: Option<u32>,
}

/// Smallest camera-ray distance that counts as a hit, in scene units.
pub const CAMERA_T_MIN: f32 = 0.0;
/// Shadow rays start this many times the bound on the hit point's rounding error off the
/// surface (see [`Surface::error`]): enough to clear it whatever the scene's scale and distance
/// from the origin, and no more.
pub const SHADOW_OFFSET: f32 = 1.0;
/// Shadow rays stop this fraction short of the light sample.
pub const SHADOW_T_MAX: f32 = 1.0 - 1e-4;

/// Points shaded together when they bundle: the 4 samples of 4 pixels, a vector of 16 lanes
/// per light sample (two of 8 on AVX2).
const BUNDLE_POINTS: usize = 16;

/// Buffers one worker reuses from one shading point to the next.
#[derive(Default)]
pub(crate) struct Scratch {
    /// Jittered sample points.
    points: Points,
    /// The samples of a light whose samples each bring their own light (an environment, a
    /// sun, a spot): the unit direction toward each and what it brings.
    directional: Vec<(Vec3, Rgb)>,
    /// A sun's directions.
    toward: Vec<Vec3>,
    directions: Directions,
    spec: Vec<f32>,
    /// Every sample of every light, in light and sample order: its point, the light it sends
    /// toward the viewer if visible (by channel), whether it is blocked (cannot contribute,
    /// then: occluded), and whether it lies behind the surface (its shadow ray leaves from the
    /// other side). The points are left out when bundles take them from the plan (pairs).
    ends: Vec<Vec3>,
    r: Vec<f32>,
    g: Vec<f32>,
    b: Vec<f32>,
    blocked: Vec<bool>,
    behind: Vec<bool>,
    /// The two sides' masks when samples lie on both sides (see `Levels::occlude_sides`).
    sides: (Vec<bool>, Vec<bool>),
}

/// A shading point as its lights see it.
struct Seen {
    /// The point.
    x: Vec3,
    /// The geometric normal, on the viewer's side.
    n_geom: Vec3,
    lobe: Lobe,
}

/// A shading point between [`Integrator::prepare`] and its shadow rays.
struct Point {
    /// The ambient term.
    ambient: Rgb,
    /// Where shadow rays toward samples on the viewer's side of the surface start, and where
    /// those toward the other side start.
    front: Vec3,
    back: Vec3,
    /// The number of shadow rays the point needs.
    traced: u64,
}

impl Point {
    /// The ambient term plus every unblocked sample's light, in light and sample order.
    #[inline(always)]
    fn radiance(&self, s: &Scratch) -> Rgb {
        self.radiance_where(s, |i| s.blocked[i])
    }

    /// [`Point::radiance`] with sample `i` blocked when `blocked(i)`.
    #[inline(always)]
    fn radiance_where(&self, s: &Scratch, blocked: impl Fn(usize) -> bool) -> Rgb {
        self.sum(s.r.len(), |i| {
            (!blocked(i)).then(|| Vec3::new(s.r[i], s.g[i], s.b[i]))
        })
    }

    /// The ambient term plus the light of each of `samples` samples that `light(j)` lets
    /// through, in light and sample order: the one order every way of shading sums in. A
    /// blocked sample adds 0, so that summing many points side by side is a select and an add
    /// per lane (the sum is the same as skipping it, but for a radiance of −0, which becomes
    /// +0).
    #[inline(always)]
    fn sum(&self, samples: usize, light: impl Fn(usize) -> Option<Rgb>) -> Rgb {
        let mut radiance = self.ambient;
        for j in 0..samples {
            radiance += light(j).unwrap_or(Rgb::ZERO);
        }
        radiance
    }
}

/// Direct lighting for one render: the world, the shading settings and the planned lights.
pub(crate) struct Integrator<'w> {
    world: &'w World,
    settings: ShadingSettings,
    lights: Vec<LightPlan>,
    /// The number of light samples (shadow rays) per point.
    samples: u64,
    /// How the points' shadow rays are grouped, as the tree chose (see `batch`).
    grouping: Grouping,
    /// Every light sample, when every point has the same ones (no jittered light).
    fixed_ends: Option<SharedEnds>,
    /// The centre and radius of a sphere around the scene's geometry: shadow rays toward an
    /// environment end outside it.
    sphere: (Vec3, f32),
    path: SimdPath,
}

impl<'w> Integrator<'w> {
    /// Plans every light of `world` for `settings`.
    pub(crate) fn new(world: &'w World, settings: ShadingSettings) -> Self {
        let physical = settings.light_model == LightModel::Physical;
        let lights: Vec<LightPlan> = world
            .lights()
            .iter()
            .map(|light| plan(light, &settings, physical))
            .collect();
        let samples: u64 = lights.iter().map(LightPlan::sample_count).sum();
        let fixed_ends = fixed_ends(&lights);
        let grouping = world.accel().grouping(samples, fixed_ends.is_some());
        let bounds = world.bounds();
        let sphere = match bounds.is_empty() {
            true => (Vec3::ZERO, 1.0),
            false => {
                let center = 0.5 * (bounds.min + bounds.max);
                (center, (0.5 * (bounds.max - bounds.min).length()).max(1e-3))
            }
        };
        Self {
            sphere,
            world,
            settings,
            grouping,
            fixed_ends,
            lights,
            samples,
            path: simd_path(),
        }
    }

    /// Whether shading draws random numbers: false when every light's samples are fixed
    /// (point lights, grid area lights), and then the generators given to
    /// [`Integrator::shade_batch`] are never read.
    pub(crate) fn draws(&self) -> bool {
        self.fixed_ends.is_none()
    }

    /// How many points [`Integrator::shade_batch`] should be given at a time: a few pixels'
    /// worth when they bundle their shadow rays or have few samples each (one call, one
    /// dispatch to the SIMD kernel, for all of them), else one (each may trace many
    /// thousands, and a cancelled render stops between calls).
    pub(crate) fn batch_points(&self) -> usize {
        if self.grouping != Grouping::Fans || self.samples <= batch::FEW_SAMPLES {
            BUNDLE_POINTS
        } else {
            1
        }
    }

    /// Everything of shading a point seen along `direction` but its shadow rays: the light
    /// samples gathered in `scratch` (those that cannot contribute already blocked), the
    /// origins of the shadow rays and the ambient term.
    #[inline(always)]
    fn prepare(
        &self,
        direction: Vec3,
        surface: &Surface,
        rng: &mut Rng,
        scratch: &mut Scratch,
    ) -> Point {
        let (seen, mut point) = self.look(direction, surface);
        match self.settings.light_model {
            LightModel::Phong => self.gather::<Seed>(&seen, rng, scratch),
            LightModel::Physical => self.gather::<Physical>(&seen, rng, scratch),
        }
        point.traced = scratch.blocked.iter().filter(|&&b| !b).count() as u64;
        point
    }

    /// What shading a point seen along `direction` needs of its surface and material, and the
    /// point's ambient term and shadow-ray origins (no shadow rays counted yet).
    #[inline(always)]
    fn look(&self, direction: Vec3, surface: &Surface) -> (Seen, Point) {
        let world = self.world;
        let (n_geom, n) = surface.facing(direction);
        let material = &world.materials()[surface.material as usize];
        let tex = match material.texture {
            Some(t) => world.textures()[t as usize].eval(surface.uv),
            None => Vec3::ONE,
        };
        // The texture times the vertex colour scales k_d and k_a. Without vertex colours the
        // colour is exactly 1 and x·1 = x, so such scenes shade exactly as before.
        let tex = tex * surface.color;
        let p = material.shininess;
        let lobe = Lobe {
            n,
            view: -direction.normalize(),
            kd: tex * material.diffuse,
            ks: material.specular,
            p,
            shading: self.settings.shading,
            specular_norm: match self.settings.shading {
                Shading::Phong => (p + 2.0) / (2.0 * PI),
                Shading::BlinnPhong => (p + 8.0) / (8.0 * PI),
            },
        };
        let x = surface.position;
        let offset = SHADOW_OFFSET * n_geom.abs().dot(surface.error);
        let point = Point {
            ambient: tex * material.ambient * self.settings.ambient,
            front: x + offset * n_geom,
            back: x + offset * (-n_geom),
            traced: 0,
        };
        (Seen { x, n_geom, lobe }, point)
    }

    /// Fills `scratch` with every sample of every light, in light and sample order.
    #[inline(always)]
    fn gather<M: Model>(&self, seen: &Seen, rng: &mut Rng, scratch: &mut Scratch) {
        let Seen { x, n_geom, lobe } = seen;
        let (x, n_geom) = (*x, *n_geom);
        scratch.ends.clear();
        let mut base = 0;
        for plan in &self.lights {
            let points = match &plan.source {
                Source::Fixed(points) => points,
                Source::Jittered(light) => {
                    scratch.points.fill(|all| light.sample_points(rng, all));
                    &scratch.points
                }
                Source::Environment(light) => {
                    scratch.directional.clear();
                    light.sample_directions(lobe.n, rng, &mut scratch.directional);
                    self.far_points(x, scratch);
                    &scratch.points
                }
                Source::Sun(light) => {
                    scratch.toward.clear();
                    light.sample_directions(rng, &mut scratch.toward);
                    scratch.directional.clear();
                    let e = light.irradiance;
                    scratch
                        .directional
                        .extend(scratch.toward.iter().map(|&d| (d, e)));
                    self.far_points(x, scratch);
                    &scratch.points
                }
                Source::Spot { light, physical } => {
                    let to = light.position - x;
                    let d2 = to.length_squared();
                    let l = to / d2.sqrt();
                    let e = light.intensity * light.falloff(-l);
                    let e = if *physical { e / d2 } else { e };
                    scratch.directional.clear();
                    scratch.directional.push((l, e));
                    scratch.points.fill(|all| all.push(light.position));
                    &scratch.points
                }
            };
            let n = points.len();
            scratch.ends.extend_from_slice(&points.all);
            let end = base + n;
            for v in [&mut scratch.r, &mut scratch.g, &mut scratch.b] {
                v.resize(end, 0.0);
            }
            scratch.blocked.resize(end, false);
            scratch.behind.resize(end, false);
            let dirs = &mut scratch.directions;
            dirs.compute(x, lobe.n, points);
            scratch.spec.resize(n, 0.0);
            lobe.speculars(dirs, &mut scratch.spec);
            let lanes = Lanes {
                r: &mut scratch.r[base..end],
                g: &mut scratch.g[base..end],
                b: &mut scratch.b[base..end],
                blocked: &mut scratch.blocked[base..end],
            };
            match plan.source {
                Source::Environment(_) | Source::Sun(_) | Source::Spot { .. } => {
                    M::contribute_directional(
                        plan,
                        lobe,
                        dirs,
                        &scratch.spec,
                        &scratch.directional,
                        lanes,
                    )
                }
                _ => M::contribute(plan, lobe, dirs, &scratch.spec, lanes),
            }
            let behind = &mut scratch.behind[base..end];
            let (lx, ly, lz) = (&dirs.lx[..n], &dirs.ly[..n], &dirs.lz[..n]);
            for i in 0..n {
                behind[i] = n_geom.x * lx[i] + n_geom.y * ly[i] + n_geom.z * lz[i] < 0.0;
            }
            base = end;
        }
        let count = base;
        for v in [&mut scratch.r, &mut scratch.g, &mut scratch.b] {
            v.truncate(count);
        }
        scratch.blocked.truncate(count);
        scratch.behind.truncate(count);
    }

    /// Fills `scratch.points` with the end points of shadow rays from `x` along each of
    /// `scratch.directional`'s directions: twice the way out of the scene's bounding sphere,
    /// so that every segment leaves it.
    #[inline(always)]
    fn far_points(&self, x: Vec3, scratch: &mut Scratch) {
        let (center, radius) = self.sphere;
        let far = 2.0 * ((x - center).length() + radius);
        let directional = &scratch.directional;
        scratch
            .points
            .fill(|all| all.extend(directional.iter().map(|&(d, _)| x + far * d)));
    }

    /// Blocks the gathered samples that something occludes: shadow rays leave from `front`
    /// toward samples on the viewer's side of the surface, from `back` toward the others.
    fn occlude(&self, front: Vec3, back: Vec3, s: &mut Scratch) {
        let (ends, behind, blocked) = (&s.ends, &s.behind, &mut s.blocked);
        (self.world.accel()).occlude_sides(
            (front, back),
            ends,
            behind,
            SHADOW_T_MAX,
            blocked,
            &mut s.sides,
        );
    }
}
