//! Directional (sun) lights, with an optional angular size, and spot lights with glTF's smooth
//! cone falloff (`KHR_lights_punctual`).

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use crate::math::{unit_cross, Rgb};
use crate::sampling::Rng;

/// Light arriving from one direction (or a small cone of them) at infinity, like the sun.
#[derive(Clone, Debug, PartialEq)]
pub struct DirectionalLight {
    /// Unit direction the light travels (from the light toward the scene), as Mitsuba's
    /// `directional` and glTF's −z of the light's node.
    pub direction: Vec3,
    /// color · intensity: the irradiance on a surface facing the light.
    pub irradiance: Rgb,
    /// Cosine of the cone's half-angle (half the angular diameter); 1 for a point-like sun.
    pub cos_half_angle: f32,
    /// N: N×N samples over the cone (1 when it is point-like).
    pub n: u32,
}

impl DirectionalLight {
    /// Number of samples, N².
    pub fn sample_count(&self) -> u32 {
        self.n * self.n
    }

    /// Appends the N² unit directions toward the light of one shading point, in stratum order,
    /// uniform in solid angle over the cone (stratified, jittered from `rng`); the single
    /// direction toward it, drawing nothing, when it is point-like.
    pub fn sample_directions(&self, rng: &mut Rng, out: &mut Vec<Vec3>) {
        let axis = -self.direction;
        if self.cos_half_angle >= 1.0 {
            out.extend(std::iter::repeat_n(axis, self.sample_count() as usize));
            return;
        }
        let (t, b) = frame(axis);
        let n = self.n as f32;
        for k in 0..self.n {
            for l in 0..self.n {
                let xi = rng.uniform2();
                let u = Vec2::new((k as f32 + xi.x) / n, (l as f32 + xi.y) / n);
                let cos = 1.0 - u.x * (1.0 - self.cos_half_angle);
                let sin = (1.0 - cos * cos).max(0.0).sqrt();
                let (s, c) = (2.0 * PI * u.y).sin_cos();
                out.push((axis * cos + t * (sin * c) + b * (sin * s)).normalize());
            }
        }
    }
}

/// Two unit vectors completing `axis` to an orthonormal frame.
fn frame(axis: Vec3) -> (Vec3, Vec3) {
    let helper = if axis.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let t = unit_cross(helper, axis);
    (t, axis.cross(t))
}

/// A point light shining into a cone, with glTF's smooth falloff between its inner and outer
/// angles.
#[derive(Clone, Debug, PartialEq)]
pub struct SpotLight {
    /// Where it is.
    pub position: Vec3,
    /// Unit direction of the cone's axis (where it points).
    pub direction: Vec3,
    /// color · intensity on the axis, in the units of a point light's.
    pub intensity: Rgb,
    /// Cosine of the inner half-angle: full intensity inside it.
    pub cos_inner: f32,
    /// Cosine of the outer half-angle: nothing outside it.
    pub cos_outer: f32,
}

impl SpotLight {
    /// The fraction of the intensity sent along the unit direction `d` (from the light):
    /// glTF's `clamp((cos θ − cos outer) / max(0.001, cos inner − cos outer), 0, 1)²`.
    pub fn falloff(&self, d: Vec3) -> f32 {
        let scale = 1.0 / (self.cos_inner - self.cos_outer).max(0.001);
        let t = ((self.direction.dot(d) - self.cos_outer) * scale).clamp(0.0, 1.0);
        t * t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_point_like_sun_gives_its_one_direction() {
        let sun = DirectionalLight {
            direction: Vec3::new(0.0, -1.0, 0.0),
            irradiance: Vec3::ONE,
            cos_half_angle: 1.0,
            n: 1,
        };
        let mut out = Vec::new();
        sun.sample_directions(&mut Rng::new(0, &[]), &mut out);
        assert_eq!(out, vec![Vec3::Y]);
    }

    #[test]
    fn a_wide_sun_fills_its_cone() {
        let half = 10f32.to_radians();
        let sun = DirectionalLight {
            direction: Vec3::new(1.0, -1.0, 0.0).normalize(),
            irradiance: Vec3::ONE,
            cos_half_angle: half.cos(),
            n: 8,
        };
        let mut out = Vec::new();
        sun.sample_directions(&mut Rng::new(3, &[1]), &mut out);
        assert_eq!(out.len(), 64);
        let axis = -sun.direction;
        let mean = out.iter().sum::<Vec3>().normalize();
        assert!(mean.dot(axis) > 0.9999);
        for d in &out {
            assert!((d.length() - 1.0).abs() < 1e-5);
            assert!(d.dot(axis) >= half.cos() - 1e-5);
        }
        // Uniform in solid angle: about half the samples beyond the median cosine.
        let median = 1.0 - 0.5 * (1.0 - half.cos());
        let beyond = out.iter().filter(|d| d.dot(axis) < median).count();
        assert!((24..=40).contains(&beyond), "{beyond}");
    }

    #[test]
    fn spots_fall_off_as_gltf_says() {
        let spot = SpotLight {
            position: Vec3::ZERO,
            direction: -Vec3::Y,
            intensity: Vec3::ONE,
            cos_inner: 20f32.to_radians().cos(),
            cos_outer: 40f32.to_radians().cos(),
        };
        let at = |deg: f32| {
            let r = deg.to_radians();
            spot.falloff(Vec3::new(r.sin(), -r.cos(), 0.0))
        };
        assert_eq!(at(0.0), 1.0);
        assert_eq!(at(19.0), 1.0);
        assert_eq!(at(41.0), 0.0);
        let mid = (30f32.to_radians().cos() - spot.cos_outer) / (spot.cos_inner - spot.cos_outer);
        assert!((at(30.0) - mid * mid).abs() < 1e-6);
    }
}
