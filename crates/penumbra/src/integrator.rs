//! Direct lighting of SPEC §6: ambient plus, for every light sample, a (Blinn-)Phong or
//! energy-normalized BRDF term, each gated by a shadow ray. Knows nothing of files.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use crate::geometry::Hit;
use crate::light::Light;
use crate::math::{Ray, Rgb};
use crate::sampling::{Rng, Sampler};
use crate::scene::Scene;

/// The specular lobe.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shading {
    /// max(0, r·v)^p with r the mirrored light direction.
    Phong,
    /// max(0, n·h)^p with h the half vector.
    BlinnPhong,
}

/// How much light reaches a point and how the BRDF is normalized.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightModel {
    /// The seed's: each area-light sample is a point light of color·intensity/N² shining
    /// both ways, no falloff; the BRDF is the plain Phong sum.
    Phong,
    /// Radiometric: one-sided area emitters with cosine and inverse-square falloff, and an
    /// energy-normalized BRDF.
    Physical,
}

/// Sampling and shading settings of a built scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// Pixel sample pattern.
    pub sampler: Sampler,
    /// Samples per pixel along each axis (n; n² per pixel).
    pub samples_per_axis: u32,
    /// Specular lobe.
    pub shading: Shading,
    /// Light model.
    pub light_model: LightModel,
    /// Ambient light I_a.
    pub ambient: Rgb,
    /// Radiance of rays that hit nothing.
    pub background: Rgb,
    /// Seed of every random choice.
    pub seed: u64,
}

/// Smallest camera-ray distance that counts as a hit, in scene units.
pub const CAMERA_T_MIN: f32 = 1e-4;
/// Shadow rays start this far off the surface, relative to the hit point's magnitude (so
/// that scenes far from the origin or at large scale still clear their own surface).
pub const SHADOW_OFFSET: f32 = 1e-4;
/// Shadow rays stop this fraction short of the light sample.
pub const SHADOW_T_MAX: f32 = 1.0 - 1e-4;

/// The radiance along a camera ray that hit `hit`, and the number of shadow rays traced.
/// `rng` supplies the jitter of jittered area lights.
pub fn shade(scene: &Scene, ray: &Ray, hit: &Hit, rng: &mut Rng) -> (Rgb, u64) {
    let geometry = &scene.geometry;
    let tri = &geometry.triangles[hit.triangle as usize];
    let [i0, i1, i2] = tri.vertices.map(|v| v as usize);
    let (p0, p1, p2) = (
        geometry.positions[i0],
        geometry.positions[i1],
        geometry.positions[i2],
    );
    let b0 = 1.0 - hit.b1 - hit.b2;
    let x = b0 * p0 + hit.b1 * p1 + hit.b2 * p2;
    // Zero only for a sliver whose cross product underflows: it then reflects only ambient.
    let mut n_geom = (p1 - p0).cross(p2 - p0).normalize_or_zero();
    let mut n = if tri.smooth {
        let ns = b0 * geometry.normals[i0]
            + hit.b1 * geometry.normals[i1]
            + hit.b2 * geometry.normals[i2];
        ns.try_normalize().unwrap_or(n_geom)
    } else {
        n_geom
    };
    if n_geom.dot(ray.direction) > 0.0 {
        n_geom = -n_geom;
        n = -n;
    }
    // A mirroring transform (negative scale) reverses the winding, so e1 × e2 flips while the
    // inverse-transpose vertex normals do not; OBJ files can also carry normals that disagree
    // with their winding. Either way the shading normal belongs on the viewer's side, as pbrt
    // does by face-forwarding one normal to the other.
    if n.dot(n_geom) < 0.0 {
        n = -n;
    }
    let material = &scene.materials[tri.material as usize];
    let tex = match material.texture {
        Some(t) => {
            let uv = b0 * geometry.uvs[i0] + hit.b1 * geometry.uvs[i1] + hit.b2 * geometry.uvs[i2];
            scene.textures[t as usize].eval(uv)
        }
        None => Vec3::ONE,
    };
    let settings = &scene.settings;
    let view = -ray.direction.normalize();
    let kd = tex * material.diffuse;
    let ks = material.specular;
    let p = material.shininess;
    let physical = settings.light_model == LightModel::Physical;
    let diffuse_norm = 1.0 / PI;
    let specular_norm = match settings.shading {
        Shading::Phong => (p + 2.0) / (2.0 * PI),
        Shading::BlinnPhong => (p + 8.0) / (8.0 * PI),
    };
    let offset = SHADOW_OFFSET * (1.0 + x.abs().max_element());
    let mut shadow_rays = 0;

    // The BRDF term B_s for a unit direction `l` toward the light (zero below the surface).
    let brdf = |l: Vec3| -> Option<Rgb> {
        let cos = n.dot(l);
        // NaN when the light sample sits exactly on the shaded point (l = 0/0): no light.
        if cos.is_nan() || cos <= 0.0 {
            return None;
        }
        let spec = if ks == Vec3::ZERO {
            0.0
        } else {
            let base = match settings.shading {
                Shading::Phong => (2.0 * cos * n - l).dot(view),
                Shading::BlinnPhong => n.dot((l + view).normalize()),
            };
            // max(0, base)^p without a powf call for the half of directions where base ≤ 0
            // (a NaN base, from l = −v, counts as 0); 0⁰ = 1.
            if base > 0.0 {
                base.powf(p)
            } else if p == 0.0 {
                1.0
            } else {
                0.0
            }
        };
        Some(if physical {
            (kd * diffuse_norm + ks * (specular_norm * spec)) * cos
        } else {
            kd * cos + ks * spec
        })
    };
    // Whether the segment from `x` to `y` is free, counting the ray.
    let mut visible = |y: Vec3, l: Vec3| -> bool {
        shadow_rays += 1;
        let side = if n_geom.dot(l) >= 0.0 {
            n_geom
        } else {
            -n_geom
        };
        let origin = x + offset * side;
        !scene
            .bvh
            .occluded(&Ray::new(origin, y - origin), 0.0, SHADOW_T_MAX)
    };

    let mut radiance = tex * material.ambient * settings.ambient;
    for light in &scene.lights {
        match light {
            Light::Point(pl) => {
                let to = pl.position - x;
                let d2 = to.length_squared();
                let l = to / d2.sqrt();
                let Some(b) = brdf(l) else { continue };
                let e = if physical {
                    pl.intensity / d2
                } else {
                    pl.intensity
                };
                if e != Vec3::ZERO && visible(pl.position, l) {
                    radiance += e * b;
                }
            }
            Light::Area(al) => {
                let count = al.sample_count() as f32;
                let n_light = al.normal();
                let weight = if physical {
                    al.radiance * (al.area() / count)
                } else {
                    al.radiance / count
                };
                for k in 0..al.n {
                    for l_idx in 0..al.n {
                        let xi = if al.jitter {
                            rng.uniform2()
                        } else {
                            Vec2::splat(0.5)
                        };
                        let y = al.sample_point(k, l_idx, xi);
                        let to = y - x;
                        let d2 = to.length_squared();
                        let l = to / d2.sqrt();
                        let Some(b) = brdf(l) else { continue };
                        let e = if physical {
                            let cos_light = -n_light.dot(l);
                            if cos_light.is_nan() || cos_light <= 0.0 {
                                continue;
                            }
                            weight * (cos_light / d2)
                        } else {
                            weight
                        };
                        if visible(y, l) {
                            radiance += e * b;
                        }
                    }
                }
            }
        }
    }
    (radiance, shadow_rays)
}
