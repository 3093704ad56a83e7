//! Direct lighting of SPEC §6 (docs/spec.md): ambient plus, for every light sample, a
//! (Blinn-)Phong or energy-normalized BRDF term, each gated by a shadow ray. Knows nothing of
//! files, cameras or films.
//!
//! An [`Integrator`] is made once per render from the world and the shading settings: it
//! plans every light (its emission weight under the light model and, for fixed grids, its
//! sample points). At a shading point, [`Integrator::shade`] gathers every light sample that
//! could contribute, tests them together with the shared-origin occlusion query, and sums the
//! unoccluded ones in light and sample order.

use std::f32::consts::PI;

use glam::Vec3;

use crate::geometry::Surface;
use crate::light::{AreaLight, Light};
use crate::math::{Ray, Rgb};
use crate::sampling::Rng;
use crate::world::World;

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
pub const CAMERA_T_MIN: f32 = 1e-4;
/// Shadow rays start this far off the surface, relative to the hit point's magnitude (so
/// that scenes far from the origin or at large scale still clear their own surface).
pub const SHADOW_OFFSET: f32 = 1e-4;
/// Shadow rays stop this fraction short of the light sample.
pub const SHADOW_T_MAX: f32 = 1.0 - 1e-4;

/// A light as one render uses it.
struct LightPlan {
    /// Emission of one sample under the light model, before distance and angle terms.
    weight: Rgb,
    /// Unit normal of an emitter that is one-sided under the light model (a physical area
    /// light); `None` for one that shines all ways.
    facing: Option<Vec3>,
    source: Source,
}

enum Source {
    Point(Vec3),
    /// The N² fixed cell centers, computed once per render.
    Grid(Vec<Vec3>),
    /// Drawn afresh at every shading point.
    Jittered(AreaLight),
}

/// A light model: what arrives from a sample, and how the surface reflects it.
struct Model {
    /// Light arriving from a sample along unit `l` at squared distance `d2`; `None` when the
    /// emitter sends nothing that way.
    arrival: fn(&LightPlan, Vec3, f32) -> Option<Rgb>,
    /// The BRDF term times the cosine, from k_d, k_s, the cosine and the specular lobe value.
    reflect: fn(&Lobe, f32, f32) -> Rgb,
}

/// The seed's model: every sample a point light of the plan's weight, both ways, no falloff.
fn seed_arrival(plan: &LightPlan, _l: Vec3, _d2: f32) -> Option<Rgb> {
    Some(plan.weight)
}

/// The seed's BRDF: the plain Phong sum k_d·cos + k_s·lobe.
fn seed_reflect(lobe: &Lobe, cos: f32, spec: f32) -> Rgb {
    lobe.kd * cos + lobe.ks * spec
}

/// Radiometric arrival: inverse-square falloff, and the emitter's cosine for area lights,
/// which emit only on their `u × v` side.
fn physical_arrival(plan: &LightPlan, l: Vec3, d2: f32) -> Option<Rgb> {
    match plan.facing {
        None => Some(plan.weight / d2),
        Some(n_light) => {
            let cos_light = -n_light.dot(l);
            // NaN when the sample sits on the shaded point: no light.
            (cos_light > 0.0).then(|| plan.weight * (cos_light / d2))
        }
    }
}

/// The energy-normalized BRDF: (k_d/π + k_s·(p+2)/2π·lobe)·cos (Blinn-Phong: (p+8)/8π).
fn physical_reflect(lobe: &Lobe, cos: f32, spec: f32) -> Rgb {
    (lobe.kd * (1.0 / PI) + lobe.ks * (lobe.specular_norm * spec)) * cos
}

/// The material at a shading point, seen from `view`.
struct Lobe {
    n: Vec3,
    view: Vec3,
    kd: Rgb,
    ks: Rgb,
    p: f32,
    shading: Shading,
    specular_norm: f32,
}

impl Lobe {
    /// cos θ and the specular lobe value for a unit direction `l` toward the light, or `None`
    /// below the surface.
    fn eval(&self, l: Vec3) -> Option<(f32, f32)> {
        let cos = self.n.dot(l);
        // NaN when the light sample sits exactly on the shaded point (l = 0/0): no light.
        if cos.is_nan() || cos <= 0.0 {
            return None;
        }
        if self.ks == Vec3::ZERO {
            return Some((cos, 0.0));
        }
        let base = match self.shading {
            Shading::Phong => (2.0 * cos * self.n - l).dot(self.view),
            Shading::BlinnPhong => self.n.dot((l + self.view).normalize()),
        };
        // max(0, base)^p without a powf call for the half of directions where base ≤ 0
        // (a NaN base, from l = −v, counts as 0); 0⁰ = 1.
        let spec = if base > 0.0 {
            base.powf(self.p)
        } else if self.p == 0.0 {
            1.0
        } else {
            0.0
        };
        Some((cos, spec))
    }
}

/// Buffers one worker reuses from one shading point to the next.
#[derive(Default)]
pub(crate) struct Scratch {
    points: Vec<Vec3>,
    /// Light samples that would contribute if visible: end point, contribution, and whether
    /// the sample lies behind the surface (its shadow ray leaves from the other side).
    ends: Vec<Vec3>,
    values: Vec<Rgb>,
    behind: Vec<bool>,
    occluded: Vec<bool>,
    group: Vec<Vec3>,
    group_occluded: Vec<bool>,
}

/// Direct lighting for one render: the world, the shading settings and the planned lights.
pub(crate) struct Integrator<'w> {
    world: &'w World,
    settings: ShadingSettings,
    model: Model,
    lights: Vec<LightPlan>,
}

impl<'w> Integrator<'w> {
    /// Plans every light of `world` for `settings`.
    pub(crate) fn new(world: &'w World, settings: ShadingSettings) -> Self {
        let physical = settings.light_model == LightModel::Physical;
        let model = if physical {
            Model {
                arrival: physical_arrival,
                reflect: physical_reflect,
            }
        } else {
            Model {
                arrival: seed_arrival,
                reflect: seed_reflect,
            }
        };
        let lights = world
            .lights()
            .iter()
            .map(|light| plan(light, &settings, physical))
            .collect();
        Self {
            world,
            settings,
            model,
            lights,
        }
    }

    /// The radiance leaving `surface` back along `ray`, and the number of shadow rays traced.
    /// `rng` supplies the jitter of jittered area lights.
    pub(crate) fn shade(
        &self,
        ray: &Ray,
        surface: &Surface,
        rng: &mut Rng,
        scratch: &mut Scratch,
    ) -> (Rgb, u64) {
        let world = self.world;
        let x = surface.position;
        let mut n_geom = surface.geometric_normal;
        let mut n = surface.shading_normal;
        if n_geom.dot(ray.direction) > 0.0 {
            n_geom = -n_geom;
            n = -n;
        }
        // A mirroring transform (negative scale) reverses the winding, so e1 × e2 flips while
        // the inverse-transpose vertex normals do not; OBJ files can also carry normals that
        // disagree with their winding. Either way the shading normal belongs on the viewer's
        // side, as pbrt does by face-forwarding one normal to the other.
        if n.dot(n_geom) < 0.0 {
            n = -n;
        }
        let material = &world.materials()[surface.material as usize];
        let tex = match material.texture {
            Some(t) => world.textures()[t as usize].eval(surface.uv),
            None => Vec3::ONE,
        };
        let p = material.shininess;
        let lobe = Lobe {
            n,
            view: -ray.direction.normalize(),
            kd: tex * material.diffuse,
            ks: material.specular,
            p,
            shading: self.settings.shading,
            specular_norm: match self.settings.shading {
                Shading::Phong => (p + 2.0) / (2.0 * PI),
                Shading::BlinnPhong => (p + 8.0) / (8.0 * PI),
            },
        };

        self.gather(x, n_geom, &lobe, rng, scratch);
        let offset = SHADOW_OFFSET * (1.0 + x.abs().max_element());
        self.occlude(x + offset * n_geom, x + offset * (-n_geom), scratch);

        let mut radiance = tex * material.ambient * self.settings.ambient;
        for (value, occluded) in scratch.values.iter().zip(&scratch.occluded) {
            if !occluded {
                radiance += *value;
            }
        }
        (radiance, scratch.ends.len() as u64)
    }

    /// Fills `scratch` with every light sample that contributes if visible, in light and
    /// sample order.
    fn gather(&self, x: Vec3, n_geom: Vec3, lobe: &Lobe, rng: &mut Rng, scratch: &mut Scratch) {
        scratch.ends.clear();
        scratch.values.clear();
        scratch.behind.clear();
        for plan in &self.lights {
            let points: &[Vec3] = match &plan.source {
                Source::Point(p) => std::slice::from_ref(p),
                Source::Grid(points) => points,
                Source::Jittered(light) => {
                    scratch.points.clear();
                    light.sample_points(rng, &mut scratch.points);
                    &scratch.points
                }
            };
            for &y in points {
                let to = y - x;
                let d2 = to.length_squared();
                let l = to / d2.sqrt();
                let Some((cos, spec)) = lobe.eval(l) else {
                    continue;
                };
                let Some(e) = (self.model.arrival)(plan, l, d2) else {
                    continue;
                };
                if e == Vec3::ZERO {
                    continue;
                }
                scratch.ends.push(y);
                scratch
                    .values
                    .push(e * (self.model.reflect)(lobe, cos, spec));
                // `l` is finite here (a NaN `l` failed the cosine test), so the dot product is too.
                scratch.behind.push(n_geom.dot(l) < 0.0);
            }
        }
    }

    /// Sets `scratch.occluded` for the gathered samples: shadow rays leave from `front` toward
    /// samples on the viewer's side of the surface, from `back` toward the others.
    fn occlude(&self, front: Vec3, back: Vec3, scratch: &mut Scratch) {
        let accel = self.world.accel();
        let count = scratch.ends.len();
        scratch.occluded.clear();
        scratch.occluded.resize(count, false);
        if !scratch.behind.contains(&true) {
            accel.occluded_from(front, &scratch.ends, SHADOW_T_MAX, &mut scratch.occluded);
            return;
        }
        for (origin, behind) in [(front, false), (back, true)] {
            scratch.group.clear();
            scratch.group.extend(
                (0..count)
                    .filter(|&i| scratch.behind[i] == behind)
                    .map(|i| scratch.ends[i]),
            );
            scratch.group_occluded.clear();
            scratch.group_occluded.resize(scratch.group.len(), false);
            accel.occluded_from(
                origin,
                &scratch.group,
                SHADOW_T_MAX,
                &mut scratch.group_occluded,
            );
            let mut results = scratch.group_occluded.iter();
            for i in (0..count).filter(|&i| scratch.behind[i] == behind) {
                scratch.occluded[i] = *results.next().unwrap_or(&false);
            }
        }
    }
}

/// How `light` is sampled and weighted in a render with `settings`.
fn plan(light: &Light, settings: &ShadingSettings, physical: bool) -> LightPlan {
    match light {
        Light::Point(pl) => LightPlan {
            weight: pl.intensity,
            facing: None,
            source: Source::Point(pl.position),
        },
        Light::Area(al) => {
            let al = AreaLight {
                n: settings.light_samples.unwrap_or(al.n),
                ..al.clone()
            };
            let count = al.sample_count() as f32;
            let (weight, facing) = if physical {
                (al.radiance * (al.area() / count), Some(al.normal()))
            } else {
                (al.radiance / count, None)
            };
            let source = if al.jitter {
                Source::Jittered(al)
            } else {
                let mut points = Vec::with_capacity(al.sample_count() as usize);
                // A fixed grid draws nothing from the generator.
                al.sample_points(&mut Rng::new(0, &[]), &mut points);
                Source::Grid(points)
            };
            LightPlan {
                weight,
                facing,
                source,
            }
        }
    }
}
