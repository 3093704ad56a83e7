//! Lights as one render uses them: each light's emission weight under the light model and its
//! sample points, fixed grids computed once per render, stored by coordinate so that the
//! per-sample directions of a shading point are computed many lanes at a time.

use glam::Vec3;

use super::ShadingSettings;
use crate::accel::SharedEnds;
use crate::light::{AreaLight, DirectionalLight, EnvironmentLight, Light, SpotLight};
use crate::math::Rgb;
use crate::sampling::Rng;

/// A light as one render uses it.
pub(super) struct LightPlan {
    /// Emission of one sample under the light model, before distance and angle terms.
    pub(super) weight: Rgb,
    /// Unit normal of an emitter that is one-sided under the light model (a physical area
    /// light); `None` for one that shines all ways.
    pub(super) facing: Option<Vec3>,
    pub(super) source: Source,
}

pub(super) enum Source {
    /// A point light or a fixed grid: points computed once per render.
    Fixed(Points),
    /// A jittered area light, drawn afresh at every shading point.
    Jittered(AreaLight),
    /// An environment, its directions drawn afresh at every shading point, each with its own
    /// weight (radiance / density / N²).
    Environment(EnvironmentLight),
    /// A sun: N² directions over its cone (drawn afresh at every shading point when it has
    /// one), each bringing irradiance / N².
    Sun(DirectionalLight),
    /// A spot: one sample at its position, weighed by the cone's falloff toward the point
    /// (and 1/d² under the physical model).
    Spot { light: SpotLight, physical: bool },
}

/// Points, as they are and by coordinate.
#[derive(Default)]
pub(super) struct Points {
    pub(super) all: Vec<Vec3>,
    pub(super) x: Vec<f32>,
    pub(super) y: Vec<f32>,
    pub(super) z: Vec<f32>,
}

impl Points {
    /// Replaces the points with those `fill` appends, and their coordinates.
    pub(super) fn fill(&mut self, fill: impl FnOnce(&mut Vec<Vec3>)) {
        self.all.clear();
        fill(&mut self.all);
        self.x.clear();
        self.y.clear();
        self.z.clear();
        self.x.extend(self.all.iter().map(|p| p.x));
        self.y.extend(self.all.iter().map(|p| p.y));
        self.z.extend(self.all.iter().map(|p| p.z));
    }

    pub(super) fn len(&self) -> usize {
        self.x.len()
    }
}

/// The directions from a shading point to a light's points, by coordinate.
#[derive(Default)]
pub(super) struct Directions {
    /// Unit direction toward each point.
    pub(super) lx: Vec<f32>,
    pub(super) ly: Vec<f32>,
    pub(super) lz: Vec<f32>,
    /// Squared distance to each point.
    pub(super) d2: Vec<f32>,
    /// `n·l` for the shading normal `n`.
    pub(super) cos: Vec<f32>,
}

impl Directions {
    /// Every field set to `count` lanes, as slices: `[lx, ly, lz, d2, cos]`. Inlined, and
    /// without an array `map` (whose `try_map` was not): called per point and light, the call
    /// and the map took a visible share of the seed room's time (measured: docs/benchmarks.md,
    /// «Design measurements», `Directions::lanes`).
    #[inline(always)]
    pub(super) fn lanes(&mut self, count: usize) -> [&mut [f32]; 5] {
        for v in [
            &mut self.lx,
            &mut self.ly,
            &mut self.lz,
            &mut self.d2,
            &mut self.cos,
        ] {
            v.resize(count, 0.0);
        }
        [
            &mut self.lx[..count],
            &mut self.ly[..count],
            &mut self.lz[..count],
            &mut self.d2[..count],
            &mut self.cos[..count],
        ]
    }

    /// The directions from `x` to every point of `points`, and their cosines with `n`
    /// ([`toward`] each). The lanes are independent, so the loop vectorizes.
    #[inline(always)]
    pub(super) fn compute(&mut self, x: Vec3, n: Vec3, points: &Points) {
        let count = points.len();
        let [lx, ly, lz, d2s, coss] = self.lanes(count);
        let (px, py, pz) = (&points.x[..count], &points.y[..count], &points.z[..count]);
        for i in 0..count {
            let (l, d2, cos) = toward(x, n, [px[i], py[i], pz[i]]);
            (lx[i], ly[i], lz[i]) = (l.x, l.y, l.z);
            (d2s[i], coss[i]) = (d2, cos);
        }
    }
}

/// The unit direction from `x` toward `y`, the squared distance and the cosine with `n`:
/// exactly what `to = y − x; d2 = to·to; l = to / √d2; cos = n·l` gives with glam's scalar
/// `Vec3`, written by coordinate so that loops over many points vectorize.
#[inline(always)]
pub(super) fn toward(x: Vec3, n: Vec3, y: [f32; 3]) -> (Vec3, f32, f32) {
    let (tx, ty, tz) = (y[0] - x.x, y[1] - x.y, y[2] - x.z);
    let d2 = tx * tx + ty * ty + tz * tz;
    let s = d2.sqrt();
    let (ux, uy, uz) = (tx / s, ty / s, tz / s);
    (Vec3::new(ux, uy, uz), d2, n.x * ux + n.y * uy + n.z * uz)
}

/// How `light` is sampled and weighted in a render with `settings`.
impl LightPlan {
    /// The number of samples (shadow rays) per shading point.
    pub(super) fn sample_count(&self) -> u64 {
        match &self.source {
            Source::Fixed(points) => points.len() as u64,
            Source::Jittered(light) => u64::from(light.sample_count()),
            Source::Environment(light) => u64::from(light.sample_count()),
            Source::Sun(light) => u64::from(light.sample_count()),
            Source::Spot { .. } => 1,
        }
    }
}

pub(super) fn plan(light: &Light, settings: &ShadingSettings, physical: bool) -> LightPlan {
    match light {
        Light::Point(pl) => {
            let mut points = Points::default();
            points.fill(|all| all.push(pl.position));
            LightPlan {
                weight: pl.intensity,
                facing: None,
                source: Source::Fixed(points),
            }
        }
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
                let mut points = Points::default();
                // A fixed grid draws nothing from the generator.
                points.fill(|all| al.sample_points(&mut Rng::new(0, &[]), all));
                Source::Fixed(points)
            };
            LightPlan {
                weight,
                facing,
                source,
            }
        }
        Light::Environment(el) => {
            let el = EnvironmentLight {
                n: settings.light_samples.unwrap_or(el.n),
                ..el.clone()
            };
            LightPlan {
                // Each sample carries its own weight.
                weight: Rgb::ONE / el.sample_count() as f32,
                facing: None,
                source: Source::Environment(el),
            }
        }
        Light::Directional(dl) => {
            let n = match dl.cos_half_angle < 1.0 {
                true => settings.light_samples.unwrap_or(dl.n),
                false => 1,
            };
            let dl = DirectionalLight { n, ..dl.clone() };
            LightPlan {
                weight: Rgb::ONE / dl.sample_count() as f32,
                facing: None,
                source: Source::Sun(dl),
            }
        }
        Light::Spot(sl) => LightPlan {
            weight: Rgb::ONE,
            facing: None,
            source: Source::Spot {
                light: sl.clone(),
                physical,
            },
        },
    }
}

/// Every sample of `lights` ([`SharedEnds`]: the accel groups them in runs), if none is
/// jittered.
pub(super) fn fixed_ends(lights: &[LightPlan]) -> Option<SharedEnds> {
    let mut ends = SharedEnds::default();
    for light in lights {
        let Source::Fixed(points) = &light.source else {
            return None;
        };
        ends.push_light([&points.x, &points.y, &points.z]);
    }
    Some(ends)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::{LightModel, Shading};
    use crate::light::PointLight;

    /// A point light, or a fixed `n`×`n` grid.
    fn light(n: u32) -> Light {
        match n {
            0 => Light::Point(PointLight {
                position: Vec3::Y,
                intensity: Vec3::ONE,
            }),
            _ => Light::Area(AreaLight {
                center: Vec3::Y,
                u: Vec3::X,
                v: Vec3::Z,
                radiance: Vec3::ONE,
                n,
                jitter: false,
            }),
        }
    }

    #[test]
    fn lights_with_a_shaft_of_their_own_are_traced_apart_and_the_others_together() {
        let settings = ShadingSettings {
            shading: Shading::Phong,
            light_model: LightModel::Phong,
            ambient: Vec3::ZERO,
            light_samples: None,
        };
        let runs = |grids: &[u32]| {
            let plans: Vec<_> = grids
                .iter()
                .map(|&n| plan(&light(n), &settings, false))
                .collect();
            fixed_ends(&plans).unwrap().runs().to_vec()
        };
        assert_eq!(runs(&[0, 0, 0]), vec![(0..3)]);
        assert_eq!(runs(&[5]), vec![(0..25)]);
        // A point, a 4×4 grid (a shaft), a point and a 3×3 grid together, then a 3×3 grid
        // that would make that run 19 long.
        assert_eq!(runs(&[0, 4, 0, 3, 3]), [0..1, 1..17, 17..27, 27..36]);
        // Jittered lights have no fixed samples.
        let Light::Area(grid) = light(2) else {
            unreachable!()
        };
        let jittered = Light::Area(AreaLight {
            jitter: true,
            ..grid
        });
        assert!(fixed_ends(&[plan(&jittered, &settings, false)]).is_none());
    }
}
