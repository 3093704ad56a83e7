//! Lights of SPEC §6 (docs/spec.md): parallelogram area lights sampled on an N×N grid, point
//! and spot lights, directional (sun) lights, and environment maps sampled N×N by importance.
//! Lights are not geometry: they cast no shadows, and camera rays see only an environment
//! marked visible.

mod environment;
mod punctual;

use std::sync::Arc;

use glam::{Vec2, Vec3};

use crate::distribution::ONE_BELOW;
use crate::math::{unit_cross, Rgb};
use crate::sampling::{jittered_offset, Rng};
use environment::{Drawn, DRAWN_AT_ONCE};
pub use environment::{EnvironmentError, EnvironmentMap, EnvironmentSample};
pub use punctual::{DirectionalLight, SpotLight};

/// A light source.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// A parallelogram `center ± u/2 ± v/2`.
    Area(AreaLight),
    /// A point emitting equally in all directions.
    Point(PointLight),
    /// Radiance arriving from every direction at infinity.
    Environment(EnvironmentLight),
    /// Light from one direction (or a small cone) at infinity: the sun.
    Directional(DirectionalLight),
    /// A point shining into a cone.
    Spot(SpotLight),
}

/// An environment map as a light: the map, oriented about +y and scaled.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentLight {
    /// The radiance map (shared: a scene's views reuse one).
    pub map: Arc<EnvironmentMap>,
    /// Scale on the map's radiance.
    pub intensity: f32,
    /// Rotation about +y in degrees (Mitsuba's `to_world = rotate([0, 1, 0], rotation)`).
    pub rotation: f32,
    /// N: N×N samples per shading point, one in each stratum.
    pub n: u32,
    /// Whether camera rays that miss see the map (else the background).
    pub visible: bool,
}

impl EnvironmentLight {
    /// (sin, cos) of the rotation.
    fn sin_cos(&self) -> (f32, f32) {
        self.rotation.to_radians().sin_cos()
    }

    /// A world direction in the map's frame: the inverse rotation about +y.
    pub fn to_map(&self, d: Vec3) -> Vec3 {
        let (s, c) = self.sin_cos();
        Vec3::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z)
    }

    /// A direction of the map's frame in the world: the rotation about +y.
    pub fn to_world(&self, d: Vec3) -> Vec3 {
        rotate_y(self.sin_cos(), d)
    }

    /// Radiance arriving from the world direction `d` (unit), scaled.
    pub fn radiance(&self, d: Vec3) -> Rgb {
        self.map.radiance(self.to_map(d)) * self.intensity
    }

    /// Number of samples, N².
    pub fn sample_count(&self) -> u32 {
        self.n * self.n
    }

    /// Appends the N² samples of one shading point in stratum order (stratum `(k, l)` at
    /// index `k·N + l`), each a world direction with its scaled radiance divided by its
    /// density, drawing two numbers per stratum from `rng`. A direction clearly below the
    /// plane of `normal` (cosine under −10⁻³) brings no light to it, so it is given zero
    /// radiance without looking the map up; shading finds the same (a cosine ≤ 0 lights
    /// nothing) whatever the radiance.
    #[inline(always)]
    pub fn sample_directions(&self, normal: Vec3, rng: &mut Rng, out: &mut Vec<(Vec3, Rgb)>) {
        let n = self.n as f32;
        let rotation = self.sin_cos();
        // The strata in order, drawn a few at a time (`EnvironmentMap::draw_all`).
        let strata = (0..self.n).flat_map(|k| (0..self.n).map(move |l| (k, l)));
        let mut us = [Vec2::ZERO; DRAWN_AT_ONCE];
        let mut drawn = [Drawn::default(); DRAWN_AT_ONCE];
        let mut strata = strata.peekable();
        while strata.peek().is_some() {
            let mut count = 0;
            for (u, (k, l)) in us.iter_mut().zip(strata.by_ref()) {
                let xi = rng.uniform2();
                let v = Vec2::new((k as f32 + xi.x) / n, (l as f32 + xi.y) / n);
                *u = v.min(Vec2::splat(ONE_BELOW));
                count += 1;
            }
            let drawn = &mut drawn[..count];
            self.map.draw_all(&us[..count], drawn);
            for drawn in drawn.iter() {
                let direction = rotate_y(rotation, drawn.direction);
                let radiance = match direction.dot(normal) < -1e-3 {
                    true => Rgb::ZERO,
                    false => {
                        let pdf = self.map.pdf_drawn(drawn);
                        self.map.radiance_drawn(drawn) * (self.intensity / pdf)
                    }
                };
                out.push((direction, radiance));
            }
        }
    }
}

/// `d` rotated about +y by the angle of `(sin, cos)`.
fn rotate_y((s, c): (f32, f32), d: Vec3) -> Vec3 {
    Vec3::new(c * d.x + s * d.z, d.y, -s * d.x + c * d.z)
}

/// A parallelogram light sampled on an `n × n` grid.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaLight {
    /// Center of the parallelogram.
    pub center: Vec3,
    /// First edge.
    pub u: Vec3,
    /// Second edge.
    pub v: Vec3,
    /// color · intensity.
    pub radiance: Rgb,
    /// Grid resolution N (N² samples).
    pub n: u32,
    /// True: one random point per cell; false: the cell centers.
    pub jitter: bool,
}

/// A point light.
#[derive(Clone, Debug, PartialEq)]
pub struct PointLight {
    /// Where it is.
    pub position: Vec3,
    /// color · intensity.
    pub intensity: Rgb,
}

impl AreaLight {
    /// The unit normal `normalize(u × v)`, the side a physical area light emits toward.
    pub fn normal(&self) -> Vec3 {
        unit_cross(self.u, self.v)
    }

    /// The area `|u × v|`.
    pub fn area(&self) -> f32 {
        self.u.cross(self.v).length()
    }

    /// Number of samples, N².
    pub fn sample_count(&self) -> u32 {
        self.n * self.n
    }

    /// The point of cell `(k, l)` at position `xi` in `[0, 1)²` inside the cell
    /// (`(½, ½)` is the cell center).
    pub fn sample_point(&self, k: u32, l: u32, xi: Vec2) -> Vec3 {
        // The same stratification as jittered pixel samples, in the light's (u, v) frame.
        let ab = jittered_offset(self.n, k, l, xi);
        self.center + ab.x * self.u + ab.y * self.v
    }

    /// Appends all N² sample points in cell order (cell `(k, l)` at index `k·N + l`): the cell
    /// centers, or for a jittered light one uniform point per cell, drawn from `rng` in that
    /// order.
    pub fn sample_points(&self, rng: &mut Rng, out: &mut Vec<Vec3>) {
        for k in 0..self.n {
            for l in 0..self.n {
                let xi = if self.jitter {
                    rng.uniform2()
                } else {
                    Vec2::splat(0.5)
                };
                out.push(self.sample_point(k, l, xi));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn light(n: u32) -> AreaLight {
        AreaLight {
            center: Vec3::new(0.0, 5.0, 0.0),
            u: Vec3::new(2.0, 0.0, 0.0),
            v: Vec3::new(0.0, 0.0, 2.0),
            radiance: Vec3::ONE,
            n,
            jitter: false,
        }
    }

    #[test]
    fn grid_points_are_the_cell_centers() {
        let l = light(5);
        let pts: Vec<Vec3> = (0..5)
            .flat_map(|k| (0..5).map(move |m| (k, m)))
            .map(|(k, m)| l.sample_point(k, m, Vec2::splat(0.5)))
            .collect();
        assert_eq!(pts.len(), 25);
        // Cell size 0.4: centers at -0.8, -0.4, 0, 0.4, 0.8 along each edge.
        assert!((pts[0] - Vec3::new(-0.8, 5.0, -0.8)).length() < 1e-6);
        assert!((pts[12] - Vec3::new(0.0, 5.0, 0.0)).length() < 1e-6);
        assert!((pts[24] - Vec3::new(0.8, 5.0, 0.8)).length() < 1e-6);
        let mean = pts.iter().sum::<Vec3>() / 25.0;
        assert!((mean - Vec3::new(0.0, 5.0, 0.0)).length() < 1e-6);
    }

    #[test]
    fn batch_of_points_is_the_grid_in_cell_order() {
        let mut l = light(3);
        let mut rng = Rng::new(0, &[]);
        let mut pts = Vec::new();
        l.sample_points(&mut rng, &mut pts);
        assert_eq!(pts.len(), 9);
        assert_eq!(pts[5], l.sample_point(1, 2, Vec2::splat(0.5)));
        // Jittered: the same draws, in the same order, as point by point.
        l.jitter = true;
        pts.clear();
        l.sample_points(&mut Rng::new(4, &[1]), &mut pts);
        let mut rng = Rng::new(4, &[1]);
        for (i, p) in pts.iter().enumerate() {
            let (k, m) = (i as u32 / 3, i as u32 % 3);
            assert_eq!(*p, l.sample_point(k, m, rng.uniform2()));
        }
    }

    #[test]
    fn jittered_points_stay_in_their_cell() {
        let l = light(2);
        let p = l.sample_point(1, 0, Vec2::new(0.999, 0.0));
        assert!(p.x < 1.0 && p.x > 0.99 && (p.z - -1.0).abs() < 1e-6);
    }

    #[test]
    fn normal_and_area() {
        let l = light(1);
        assert_eq!(l.area(), 4.0);
        // u × v = x × z = −y: this light faces down.
        assert_eq!(l.normal(), -Vec3::Y);
    }
}
