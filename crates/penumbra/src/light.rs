//! Lights of SPEC §6 (docs/spec.md): parallelogram area lights sampled on an N×N grid, and point lights.
//! Lights are not geometry: camera rays do not see them and they cast no shadows.

use glam::{Vec2, Vec3};

use crate::math::{unit_cross, Rgb};
use crate::sampling::{jittered_offset, Rng};

/// A light source.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// A parallelogram `center ± u/2 ± v/2`.
    Area(AreaLight),
    /// A point emitting equally in all directions.
    Point(PointLight),
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
