//! The two light models of SPEC §6, each a pair of small functions: what arrives from a light
//! sample, and how the surface reflects it. [`Lobe`] is the material at a shading point.

use std::f32::consts::PI;

use glam::Vec3;

use super::plan::LightPlan;
use super::Shading;
use crate::math::Rgb;

/// The material at a shading point, seen from `view`.
pub(super) struct Lobe {
    /// Unit shading normal, on the viewer's side.
    pub(super) n: Vec3,
    /// Unit direction toward the viewer.
    pub(super) view: Vec3,
    pub(super) kd: Rgb,
    pub(super) ks: Rgb,
    /// Phong exponent.
    pub(super) p: f32,
    pub(super) shading: Shading,
    /// The energy normalization of the specular lobe (physical model).
    pub(super) specular_norm: f32,
}

impl Lobe {
    /// The specular lobe value max(0, base)^p for a unit direction `l` toward the light with
    /// `cos = n·l > 0` (0⁰ = 1).
    #[inline]
    pub(super) fn specular(&self, l: Vec3, cos: f32) -> f32 {
        if self.ks == Vec3::ZERO {
            return 0.0;
        }
        let base = match self.shading {
            Shading::Phong => (2.0 * cos * self.n - l).dot(self.view),
            Shading::BlinnPhong => self.n.dot((l + self.view).normalize()),
        };
        // max(0, base)^p without a powf call for the half of directions where base ≤ 0
        // (a NaN base, from l = −v, counts as 0); 0⁰ = 1.
        if base > 0.0 {
            base.powf(self.p)
        } else if self.p == 0.0 {
            1.0
        } else {
            0.0
        }
    }
}

/// A light model.
pub(super) trait Model {
    /// Light arriving from a sample of `plan` along unit `l` at squared distance `d2`; `None`
    /// when the emitter sends nothing that way.
    fn arrival(plan: &LightPlan, l: Vec3, d2: f32) -> Option<Rgb>;
    /// The BRDF times the cosine, from the cosine and the specular lobe value.
    fn reflect(lobe: &Lobe, cos: f32, spec: f32) -> Rgb;
}

/// The seed's model: every sample a point light of the plan's weight, both ways, no falloff;
/// the plain Phong sum k_d·cos + k_s·lobe.
pub(super) struct Seed;

impl Model for Seed {
    #[inline]
    fn arrival(plan: &LightPlan, _l: Vec3, _d2: f32) -> Option<Rgb> {
        Some(plan.weight)
    }

    #[inline]
    fn reflect(lobe: &Lobe, cos: f32, spec: f32) -> Rgb {
        lobe.kd * cos + lobe.ks * spec
    }
}

/// Radiometric: inverse-square falloff and, for area lights, the emitter's cosine (they emit
/// only on their `u × v` side); the energy-normalized BRDF (k_d/π + k_s·(p+2)/2π·lobe)·cos
/// (Blinn-Phong: (p+8)/8π).
pub(super) struct Physical;

impl Model for Physical {
    #[inline]
    fn arrival(plan: &LightPlan, l: Vec3, d2: f32) -> Option<Rgb> {
        match plan.facing {
            None => Some(plan.weight / d2),
            Some(n_light) => {
                let cos_light = -n_light.dot(l);
                // NaN when the sample sits on the shaded point: no light.
                (cos_light > 0.0).then(|| plan.weight * (cos_light / d2))
            }
        }
    }

    #[inline]
    fn reflect(lobe: &Lobe, cos: f32, spec: f32) -> Rgb {
        (lobe.kd * (1.0 / PI) + lobe.ks * (lobe.specular_norm * spec)) * cos
    }
}
