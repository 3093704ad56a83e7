//! The two light models of SPEC §6, each a pair of small functions: what arrives from a light
//! sample, and how the surface reflects it. [`Lobe`] is the material at a shading point.

use std::f32::consts::PI;

use glam::Vec3;

use super::plan::{Directions, LightPlan};
use super::pow::pow;
use super::Shading;

/// Samples whose specular powers are computed together: a vector of 16 on AVX-512.
const LANES: usize = 16;
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
    /// `cos = n·l` (0 where `cos ≤ 0`; 0⁰ = 1).
    #[inline(always)]
    pub(super) fn specular(&self, l: Vec3, cos: f32) -> f32 {
        if self.ks == Vec3::ZERO {
            return 0.0;
        }
        self.power(self.base(l, cos), cos)
    }

    /// [`Lobe::specular`] toward each direction of `dirs`, into `out` (as long as the
    /// directions used). The bases are computed first, then their powers a whole vector of
    /// [`LANES`] at a time, the last few padded to a whole vector: a vector loop's scalar
    /// remainder would run the power's chain of dependent operations once per sample.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    pub(super) fn speculars(&self, dirs: &Directions, out: &mut [f32]) {
        let n = out.len();
        if self.ks == Vec3::ZERO {
            out.fill(0.0);
            return;
        }
        let (cos, lx, ly, lz) = (&dirs.cos[..n], &dirs.lx[..n], &dirs.ly[..n], &dirs.lz[..n]);
        for start in (0..n).step_by(LANES) {
            let count = LANES.min(n - start);
            // Padding lanes: a base of 1 and a cosine of 0, whose power is discarded.
            let (mut base, mut c) = ([1.0f32; LANES], [0.0f32; LANES]);
            // Indexed loops (an iterator's `for_each` was compiled outside the SIMD kernels).
            for i in 0..count {
                let (l, k) = (
                    Vec3::new(lx[start + i], ly[start + i], lz[start + i]),
                    start + i,
                );
                (base[i], c[i]) = (self.base(l, cos[k]), cos[k]);
            }
            let mut power = [0.0f32; LANES];
            for i in 0..LANES {
                power[i] = self.power(base[i], c[i]);
            }
            out[start..start + count].copy_from_slice(&power[..count]);
        }
    }

    /// The lobe's base toward unit direction `l` with `cos = n·l`: r·v with r the mirrored
    /// light direction (Phong), or n·h with h the half vector (Blinn-Phong).
    #[inline(always)]
    fn base(&self, l: Vec3, cos: f32) -> f32 {
        match self.shading {
            Shading::Phong => (2.0 * cos * self.n - l).dot(self.view),
            Shading::BlinnPhong => self.n.dot((l + self.view).normalize()),
        }
    }

    /// max(0, base)^p where `cos > 0`, else 0: a base ≤ 0 (or NaN, from l = −v) counts as 0,
    /// and 0⁰ = 1. Branch-free: the power of every lane is computed and the answer selected.
    #[inline(always)]
    fn power(&self, base: f32, cos: f32) -> f32 {
        let lit = base > 0.0;
        let power = pow(if lit { base } else { 1.0 }, self.p);
        let unlit = if self.p == 0.0 { 1.0 } else { 0.0 };
        let value = if lit { power } else { unlit };
        if cos > 0.0 {
            value
        } else {
            0.0
        }
    }
}

/// The light each sample of a light sends back toward the viewer if nothing blocks it, by
/// channel, and which samples cannot contribute at all.
pub(super) struct Lanes<'a> {
    pub(super) r: &'a mut [f32],
    pub(super) g: &'a mut [f32],
    pub(super) b: &'a mut [f32],
    /// True for a sample below the surface, behind a one-sided emitter or sending nothing.
    pub(super) blocked: &'a mut [bool],
}

/// A light model: what arrives from a light sample, and how the surface reflects it. Each
/// model writes every sample of a light in one loop over independent lanes, which the compiler
/// vectorizes; each lane computes exactly `e · reflect(cos, spec)` with glam's scalar `Vec3`
/// arithmetic (the same products and sums in the same order).
pub(super) trait Model {
    /// What [`Model::sample`] needs of a light and a material, the same for all their samples.
    type Terms;

    /// What a light brings to [`Model::terms`], the same at every point.
    type Light;

    /// The light terms of `plan`, found once per light (and hoisted out of loops over
    /// points: an `Option` of the plan read in such a loop was compiled to vector gathers).
    fn light(plan: &LightPlan) -> Self::Light;

    /// The terms of the samples of a light with terms `light` seen from a point with
    /// material `lobe`.
    fn terms(light: &Self::Light, lobe: &Lobe) -> Self::Terms;

    /// One sample with terms `t`: unit direction `l` toward it, squared distance `d2`, cosine
    /// `c = n·l` and specular lobe value `s`. Returns the light it sends toward the viewer if
    /// nothing blocks it, by channel, and whether it cannot contribute at all.
    fn sample(t: &Self::Terms, l: Vec3, d2: f32, c: f32, s: f32) -> (Rgb, bool);

    /// Fills `out` for the samples of `plan` in the directions `dirs`, with specular lobe
    /// values `spec`: [`Model::sample`] for each.
    #[inline(always)]
    fn contribute(plan: &LightPlan, lobe: &Lobe, dirs: &Directions, spec: &[f32], out: Lanes) {
        let n = out.r.len();
        let (cos, spec, d2) = (&dirs.cos[..n], &spec[..n], &dirs.d2[..n]);
        let (lx, ly, lz) = (&dirs.lx[..n], &dirs.ly[..n], &dirs.lz[..n]);
        let (r, g, b, blocked) = (
            out.r,
            &mut out.g[..n],
            &mut out.b[..n],
            &mut out.blocked[..n],
        );
        let terms = Self::terms(&Self::light(plan), lobe);
        for i in 0..n {
            let l = Vec3::new(lx[i], ly[i], lz[i]);
            let (e, dark) = Self::sample(&terms, l, d2[i], cos[i], spec[i]);
            (r[i], g[i], b[i], blocked[i]) = (e.x, e.y, e.z, dark);
        }
    }

    /// Fills `out` for directional samples: each `(direction, e)` of `samples` brings the
    /// plan's weight × `e` (for an environment: 1/N² × radiance / density) from its direction,
    /// with no falloff.
    fn contribute_directional(
        plan: &LightPlan,
        lobe: &Lobe,
        dirs: &Directions,
        spec: &[f32],
        samples: &[(Vec3, Rgb)],
        out: Lanes,
    );
}

/// The seed's model: every sample a point light of the plan's weight, both ways, no falloff;
/// the plain Phong sum k_d·cos + k_s·lobe.
pub(super) struct Seed;

impl Model for Seed {
    /// The weight, k_d, k_s and whether the light sends nothing.
    type Terms = (Rgb, Rgb, Rgb, bool);
    /// The weight and whether the light sends nothing.
    type Light = (Rgb, bool);

    #[inline(always)]
    fn light(plan: &LightPlan) -> (Rgb, bool) {
        (plan.weight, plan.weight == Vec3::ZERO)
    }

    #[inline(always)]
    fn terms(&(w, dark): &(Rgb, bool), lobe: &Lobe) -> Self::Terms {
        (w, lobe.kd, lobe.ks, dark)
    }

    #[inline(always)]
    fn sample(&(w, kd, ks, dark): &Self::Terms, _: Vec3, _: f32, c: f32, s: f32) -> (Rgb, bool) {
        let e = Vec3::new(
            w.x * (kd.x * c + ks.x * s),
            w.y * (kd.y * c + ks.y * s),
            w.z * (kd.z * c + ks.z * s),
        );
        // Below the surface, or NaN for a sample on the shaded point: no light.
        let lit = c > 0.0;
        (e, !lit | dark)
    }

    #[inline(always)]
    fn contribute_directional(
        plan: &LightPlan,
        lobe: &Lobe,
        dirs: &Directions,
        spec: &[f32],
        samples: &[(Vec3, Rgb)],
        out: Lanes,
    ) {
        let n = out.r.len();
        let (kd, ks) = (lobe.kd, lobe.ks);
        let (cos, spec, samples) = (&dirs.cos[..n], &spec[..n], &samples[..n]);
        for i in 0..n {
            let (c, s, e) = (cos[i], spec[i], plan.weight * samples[i].1);
            out.r[i] = e.x * (kd.x * c + ks.x * s);
            out.g[i] = e.y * (kd.y * c + ks.y * s);
            out.b[i] = e.z * (kd.z * c + ks.z * s);
            // Below the surface (or a NaN cosine), or bringing nothing: no light.
            let lit = c > 0.0;
            out.blocked[i] = !lit | (e == Vec3::ZERO);
        }
    }
}

/// Radiometric: inverse-square falloff and, for area lights, the emitter's cosine (they emit
/// only on their `u × v` side); the energy-normalized BRDF (k_d/π + k_s·(p+2)/2π·lobe)·cos
/// (Blinn-Phong: (p+8)/8π).
pub(super) struct Physical;

/// [`Physical`]'s terms of a light and a material.
pub(super) struct PhysicalTerms {
    w: Rgb,
    ks: Rgb,
    norm: f32,
    kd_pi: Rgb,
    /// Whether the light is one-sided, and its normal.
    facing: bool,
    nl: Vec3,
}

impl Model for Physical {
    type Terms = PhysicalTerms;
    /// The weight, whether the light is one-sided, and its normal.
    type Light = (Rgb, bool, Vec3);

    #[inline(always)]
    fn light(plan: &LightPlan) -> (Rgb, bool, Vec3) {
        // One-sided area lights: the emitter's cosine; point lights: none (1, always lit).
        match plan.facing {
            Some(nl) => (plan.weight, true, nl),
            None => (plan.weight, false, Vec3::ZERO),
        }
    }

    #[inline(always)]
    fn terms(&(w, facing, nl): &(Rgb, bool, Vec3), lobe: &Lobe) -> PhysicalTerms {
        PhysicalTerms {
            w,
            ks: lobe.ks,
            norm: lobe.specular_norm,
            kd_pi: lobe.kd * (1.0 / PI),
            facing,
            nl,
        }
    }

    #[inline(always)]
    fn sample(t: &PhysicalTerms, l: Vec3, d2: f32, c: f32, s: f32) -> (Rgb, bool) {
        let PhysicalTerms {
            w,
            ks,
            norm,
            kd_pi,
            facing,
            nl,
        } = *t;
        // e = weight·(cos_light / d²), or weight / d² for a point light.
        let cos_light = -(nl.x * l.x + nl.y * l.y + nl.z * l.z);
        let q = cos_light / d2;
        let (ex, ey, ez) = if facing {
            (w.x * q, w.y * q, w.z * q)
        } else {
            (w.x / d2, w.y / d2, w.z / d2)
        };
        let sn = norm * s;
        let e = Vec3::new(
            ex * ((kd_pi.x + ks.x * sn) * c),
            ey * ((kd_pi.y + ks.y * sn) * c),
            ez * ((kd_pi.z + ks.z * sn) * c),
        );
        let emits = !facing | (cos_light > 0.0);
        let dark = (ex == 0.0) & (ey == 0.0) & (ez == 0.0);
        // NaN cosines (a sample on the shaded point) count as no light.
        let lit = c > 0.0;
        (e, !lit | !emits | dark)
    }

    #[inline(always)]
    fn contribute_directional(
        plan: &LightPlan,
        lobe: &Lobe,
        dirs: &Directions,
        spec: &[f32],
        samples: &[(Vec3, Rgb)],
        out: Lanes,
    ) {
        let n = out.r.len();
        let (ks, norm) = (lobe.ks, lobe.specular_norm);
        let kd_pi = lobe.kd * (1.0 / PI);
        let (cos, spec, samples) = (&dirs.cos[..n], &spec[..n], &samples[..n]);
        for i in 0..n {
            let (c, sn, e) = (cos[i], norm * spec[i], plan.weight * samples[i].1);
            out.r[i] = e.x * ((kd_pi.x + ks.x * sn) * c);
            out.g[i] = e.y * ((kd_pi.y + ks.y * sn) * c);
            out.b[i] = e.z * ((kd_pi.z + ks.z * sn) * c);
            // Below the surface (or a NaN cosine), or bringing nothing: no light.
            let lit = c > 0.0;
            out.blocked[i] = !lit | (e == Vec3::ZERO);
        }
    }
}
