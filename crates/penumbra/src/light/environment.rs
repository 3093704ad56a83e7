//! Environment maps: an equirectangular (latitude-longitude) image of the radiance arriving
//! from every direction at infinity, oriented, looked up and importance-sampled.
//!
//! # Orientation (normative, SPEC §6)
//!
//! The same as Mitsuba 3's `envmap` emitter with `to_world = rotate(axis=[0, 1, 0],
//! angle=rotation)`. In the map's own frame a unit direction `d` has texture coordinates
//! `u = atan2(d.x, −d.z) / 2π` (wrapped into `[0, 1)`) and `v = acos(d.y) / π`: the top row
//! (`v = 0`) is +y, the centre column (`u = ½`) faces +z, `u = ¼` faces +x and `u = ¾` faces −x.
//! A world direction is rotated into the map's frame by the inverse of the rotation about +y.
//!
//! # Lookup
//!
//! As Mitsuba reads the map: texel `(i, j)` of a `W × H` image sits at `u = (i + ½) / W`,
//! `v = j / (H − 1)` (the top row at the +y pole, the bottom row at the −y pole), and radiance
//! between texels is bilinear, wrapping across `u = 0`.
//!
//! # Sampling
//!
//! The bilinear cells between neighbouring texels (`W` columns, wrapping, by `H − 1` rows) are
//! chosen in proportion to the mean luminance of their four corners times their solid angle,
//! then a direction uniformly in the cell's solid angle (uniform in φ and in cos θ). So the
//! density of a direction is `P(cell) / Ω(cell)`: finite everywhere, with no 1/sin θ spike at
//! the poles, and positive wherever the radiance is.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::distribution::{Distribution1D, Distribution2D};
use crate::math::Rgb;

/// Luminance of linear Rec. 709 RGB (the weights Mitsuba's `luminance` uses).
pub(crate) fn luminance(c: Rgb) -> f32 {
    0.212_671 * c.x + 0.715_160 * c.y + 0.072_169 * c.z
}

/// Why texels cannot make an environment map.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EnvironmentError {
    /// Fewer than 2 × 2 texels (or a texel count that does not match).
    #[error("an environment map needs at least 2×2 texels, not {width}×{height}")]
    TooSmall {
        /// Width given.
        width: u32,
        /// Height given.
        height: u32,
    },
    /// A texel is NaN, infinite or negative.
    #[error("texel ({x}, {y}) is {value}: radiance must be finite and not negative")]
    BadTexel {
        /// Column.
        x: u32,
        /// Row (0 at the top).
        y: u32,
        /// The offending channel's value.
        value: f32,
    },
}

/// An equirectangular radiance map with its sampling distribution, built once per scene.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentMap {
    width: u32,
    height: u32,
    /// Linear RGB radiance, row-major from the top row (+y).
    texels: Vec<Rgb>,
    /// Over the `width × (height − 1)` bilinear cells.
    cells: Distribution2D,
    /// cos θ of each texel row, `height` of them, from 1 at the top to −1 at the bottom.
    cos_rows: Vec<f32>,
    /// Mean radiance over the sphere and the largest texel (see [`Self::mean_and_peak`]).
    mean: Rgb,
    peak: Rgb,
}

/// A direction drawn from a map, with where in the map it was drawn.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Drawn {
    /// Unit direction in the map's frame.
    pub direction: Vec3,
    /// The bilinear cell (column, row band) and the position across its columns.
    cell: (usize, usize),
    fx: f32,
}

/// The most draws [`EnvironmentMap::draw_all`] takes at once.
pub(crate) const DRAWN_AT_ONCE: usize = 64;

/// A direction drawn from a map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnvironmentSample {
    /// Unit direction in the map's frame.
    pub direction: Vec3,
    /// Radiance arriving from it.
    pub radiance: Rgb,
    /// Density over solid angle, > 0.
    pub pdf: f32,
}

impl EnvironmentMap {
    /// A map of `width × height` linear RGB texels, row 0 at the top (+y).
    pub fn new(width: u32, height: u32, texels: Vec<Rgb>) -> Result<Self, EnvironmentError> {
        if width < 2 || height < 2 || texels.len() != width as usize * height as usize {
            return Err(EnvironmentError::TooSmall { width, height });
        }
        let (w, h) = (width as usize, height as usize);
        // One parallel pass over the texel rows checks them and sums them; every figure is
        // per row, and rows are combined in order, so nothing depends on the thread count.
        let rows: Vec<RowStats> = texels.par_chunks_exact(w).map(RowStats::of).collect();
        if let Some((y, x)) = rows
            .iter()
            .enumerate()
            .find_map(|(y, r)| r.bad.map(|x| (y, x)))
        {
            let t = texels[y * w + x];
            let value = [t.x, t.y, t.z]
                .into_iter()
                .find(|v| !v.is_finite() || *v < 0.0)
                .unwrap_or(f32::NAN);
            let (x, y) = (x as u32, y as u32);
            return Err(EnvironmentError::BadTexel { x, y, value });
        }
        let cos_rows: Vec<f32> = (0..h)
            .map(|j| match j {
                0 => 1.0,
                j if j == h - 1 => -1.0,
                j => (PI * j as f32 / (h - 1) as f32).cos(),
            })
            .collect();
        let peak = rows.iter().fold(Rgb::ZERO, |m, r| m.max(r.peak));
        let scale = weight_scale(peak.max_element());
        // The bilinear cells row by row, in parallel: a row's weights and distribution depend
        // on its two texel rows alone.
        let cells = (0..h - 1).into_par_iter().map(|j| {
            // Every cell of a row spans the same solid angle: weigh by the band's height.
            let band = cos_rows[j] - cos_rows[j + 1];
            let lum = |j: usize| {
                let row = texels[j * w..(j + 1) * w].iter();
                row.map(move |&t| luminance(t * scale))
            };
            let pairs: Vec<f32> = lum(j).zip(lum(j + 1)).map(|(a, b)| a + b).collect();
            let weights: Vec<f32> = (0..w)
                .map(|i| {
                    let k = if i + 1 == w { 0 } else { i + 1 };
                    0.25 * (pairs[i] + pairs[k]) * band
                })
                .collect();
            Distribution1D::new(&weights)
        });
        let cells = Distribution2D::from_rows(cells.collect());
        // The mean over the bilinear cells: a cell's four corners each weigh ¼ of its band,
        // and across a row every texel is the corner of two cells.
        let (mut sum, mut total) = (glam::DVec3::ZERO, 0.0f64);
        for j in 0..h - 1 {
            let band = f64::from(cos_rows[j] - cos_rows[j + 1]);
            sum += (rows[j].sum + rows[j + 1].sum) * (0.5 * band);
            total += band * w as f64;
        }
        Ok(EnvironmentMap {
            width,
            height,
            texels,
            cells,
            cos_rows,
            mean: (sum / total).as_vec3(),
            peak,
        })
    }

    /// A map of one radiance in every direction.
    pub fn uniform(radiance: Rgb) -> Result<Self, EnvironmentError> {
        EnvironmentMap::new(2, 2, vec![radiance; 4])
    }

    /// `(width, height)` in texels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Radiance arriving from the unit direction `d` of the map's frame (see the module docs).
    pub fn radiance(&self, d: Vec3) -> Rgb {
        let w = self.width as f32;
        let u = d.x.atan2(-d.z) * (0.5 / PI) - 0.5 / w;
        let u = u - u.floor();
        let (x, y) = (u * w, self.row_position(d.y));
        let i = (x as usize).min(self.width as usize - 1);
        self.bilinear(i, x - i as f32, y)
    }

    /// `v·(H − 1)` for a direction whose y (cos θ) is `cos_theta`: the position between rows.
    fn row_position(&self, cos_theta: f32) -> f32 {
        let v = (cos_theta.clamp(-1.0, 1.0).acos() / PI).clamp(0.0, 1.0);
        v * (self.height - 1) as f32
    }

    /// The bilinear blend of columns `i` and `i + 1` (wrapping) at weight `fx`, at row
    /// position `y`.
    fn bilinear(&self, i: usize, fx: f32, y: f32) -> Rgb {
        let j = (y as usize).min(self.height as usize - 2);
        let fy = y - j as f32;
        let w = self.width as usize;
        // Column i + 1 wraps to 0 (i < w: no division needed).
        let k = if i + 1 == w { 0 } else { i + 1 };
        let (above, below) = (&self.texels[j * w..], &self.texels[(j + 1) * w..]);
        let top = above[i] * (1.0 - fx) + above[k] * fx;
        let bottom = below[i] * (1.0 - fx) + below[k] * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// The direction `u` in `[0, 1)²` maps to, its radiance and density. Strata of `u` map to
    /// disjoint sets of directions. The radiance is looked up from the cell and position
    /// drawn (no trigonometry back from the direction): the same as
    /// [`radiance`](Self::radiance) of the direction up to rounding.
    pub fn sample(&self, u: Vec2) -> EnvironmentSample {
        let drawn = self.draw(u);
        EnvironmentSample {
            direction: drawn.direction,
            radiance: self.radiance_drawn(&drawn),
            pdf: self.pdf_drawn(&drawn),
        }
    }

    /// The direction `u` maps to, without its radiance and density: [`Self::sample`] in
    /// parts, for callers that need those only for some directions.
    pub(crate) fn draw(&self, u: Vec2) -> Drawn {
        let (cell, f) = self.cells.sample(u);
        self.drawn(cell, f)
    }

    /// [`draw`](Self::draw) of each of `us` (at most [`DRAWN_AT_ONCE`]), into `out` (as
    /// long), with the loads of every draw (its cells, then the texels of its radiance)
    /// asked for before any is read: a large map's cells and texels lie far apart in memory,
    /// and one draw at a time waits on each of its cache misses in turn. The same answers.
    #[inline(always)]
    pub(crate) fn draw_all(&self, us: &[Vec2], out: &mut [Drawn]) {
        let mut cells = [((0, 0), Vec2::ZERO); DRAWN_AT_ONCE];
        let cells = &mut cells[..us.len()];
        self.cells.sample_all(us, cells);
        for (o, &(cell, f)) in out.iter_mut().zip(cells.iter()) {
            *o = self.drawn(cell, f);
            let (i, j) = o.cell;
            let w = self.width as usize;
            crate::simd::prefetch(&self.texels[j * w + i]);
            crate::simd::prefetch(&self.texels[(j + 1).min(self.height as usize - 1) * w + i]);
        }
    }

    /// The direction of cell `(i, j)` at position `f` in it.
    #[inline(always)]
    fn drawn(&self, (i, j): (usize, usize), f: Vec2) -> Drawn {
        let w = self.width as f32;
        let phi = 2.0 * PI * ((i as f32 + 0.5 + f.x) / w);
        let (c0, c1) = (self.cos_rows[j], self.cos_rows[j + 1]);
        let cos_theta = (c0 + (c1 - c0) * f.y).clamp(-1.0, 1.0);
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let direction = Vec3::new(phi.sin() * sin_theta, cos_theta, -phi.cos() * sin_theta);
        Drawn {
            direction,
            cell: (i, j),
            fx: f.x,
        }
    }

    /// The radiance of a drawn direction. Texel columns sit at u = (i + ½)/W: the cell spans
    /// columns i and i + 1.
    pub(crate) fn radiance_drawn(&self, drawn: &Drawn) -> Rgb {
        let y = self.row_position(drawn.direction.y);
        self.bilinear(drawn.cell.0, drawn.fx, y)
    }

    /// The density over solid angle of a drawn direction.
    pub(crate) fn pdf_drawn(&self, drawn: &Drawn) -> f32 {
        self.cell_pdf(drawn.cell.0, drawn.cell.1)
    }

    /// Density over solid angle of the directions in cell `(i, j)`.
    fn cell_pdf(&self, i: usize, j: usize) -> f32 {
        let solid_angle = 2.0 * PI / self.width as f32 * (self.cos_rows[j] - self.cos_rows[j + 1]);
        (self.cells.probability(i, j) / f64::from(solid_angle)) as f32
    }

    /// Density over solid angle with which [`sample`](Self::sample) draws the unit direction
    /// `d` of the map's frame.
    pub fn pdf(&self, d: Vec3) -> f32 {
        let w = self.width as f32;
        let u = d.x.atan2(-d.z) * (0.5 / PI);
        let x = (u - u.floor()) * w - 0.5;
        let i = (x.floor() as i64).rem_euclid(i64::from(self.width)) as usize;
        let cos_theta = d.y.clamp(-1.0, 1.0);
        // The band whose cos θ range holds d's (rows run from cos 1 down to −1).
        let j = self.cos_rows[1..self.height as usize - 1].partition_point(|&c| c > cos_theta);
        self.cell_pdf(i, j)
    }

    /// Mean radiance over the sphere (weighted by solid angle) and the largest texel, measured
    /// once when the map is made.
    pub fn mean_and_peak(&self) -> (Rgb, Rgb) {
        (self.mean, self.peak)
    }
}

/// The power of two the sampling weights of a map whose largest channel is `peak` are
/// computed at: 1 up to 2^64, else what brings it to 2^64, so that the f32 sums of a cell's
/// four corners cannot overflow (a map of the largest RGBE texels, 1.7e38, summed to
/// infinity and sampled NaN). A power of two scales every weight exactly, so the
/// distribution is the one the unscaled weights would give; only texels under 2^-190 of the
/// peak (subnormal once scaled) lose precision.
fn weight_scale(peak: f32) -> f32 {
    const MOST: i32 = 64;
    match peak > 2f32.powi(MOST) {
        true => 2f32.powi(MOST - peak.log2().ceil() as i32),
        false => 1.0,
    }
}

/// What one pass learns of a row of texels.
struct RowStats {
    /// The first texel that is NaN, infinite or negative.
    bad: Option<usize>,
    /// Sum of the texels.
    sum: glam::DVec3,
    /// Per channel, the largest texel.
    peak: Rgb,
}

impl RowStats {
    fn of(row: &[Rgb]) -> RowStats {
        let bad = row
            .iter()
            .position(|t| !t.is_finite() || t.cmplt(Vec3::ZERO).any());
        let sum = row.iter().fold(glam::DVec3::ZERO, |s, t| s + t.as_dvec3());
        let peak = row.iter().fold(Rgb::ZERO, |m, &t| m.max(t));
        RowStats { bad, sum, peak }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A map dark everywhere but one texel.
    fn spot(w: u32, h: u32, at: (u32, u32)) -> EnvironmentMap {
        let mut texels = vec![Vec3::ZERO; (w * h) as usize];
        texels[(at.1 * w + at.0) as usize] = Vec3::ONE;
        EnvironmentMap::new(w, h, texels).unwrap()
    }

    #[test]
    fn orientation_is_mitsubas() {
        // 8 columns: texel i is centred at u = (i + ½)/8. Column 2 (u = 0.3125) is near +x
        // (u = ¼), column 4 (u = 0.5625) near +z, column 6 near −x, column 0 near −z.
        let (w, h) = (8, 5);
        for (column, toward) in [(2, Vec3::X), (4, Vec3::Z), (6, -Vec3::X), (0, -Vec3::Z)] {
            let map = spot(w, h, (column, 2));
            // The texel's own direction: u = (column + ½)/8, v = ½ (the horizon).
            let phi = 2.0 * PI * (column as f32 + 0.5) / w as f32;
            let d = Vec3::new(phi.sin(), 0.0, -phi.cos());
            assert!(
                (map.radiance(d) - Vec3::ONE).length() < 1e-5,
                "column {column}"
            );
            assert!(d.dot(toward) > 0.9, "column {column} faces {toward}");
        }
        // The top row is +y, the bottom row −y.
        let row = |j: u32| {
            let texels = (0..w * h)
                .map(|k| Vec3::splat(f32::from(k / w == j)))
                .collect();
            EnvironmentMap::new(w, h, texels).unwrap()
        };
        assert_eq!(row(0).radiance(Vec3::Y), Vec3::ONE);
        assert_eq!(row(4).radiance(-Vec3::Y), Vec3::ONE);
        assert_eq!(row(0).radiance(-Vec3::Y), Vec3::ZERO);
        assert_eq!(row(2).radiance(Vec3::Y), Vec3::ZERO);
    }

    #[test]
    fn lookup_agrees_with_mitsuba() {
        // Mitsuba 3.9.1 (`scalar_rgb`), an `envmap` of a 4×3 bitmap whose red channel is
        // 0..12 row by row: `emitter.eval` with `si.wi = −d` for these directions d.
        let texels = (0..12).map(|k| Vec3::new(k as f32, 1.0, 2.0)).collect();
        let map = EnvironmentMap::new(4, 3, texels).unwrap();
        let cases = [
            ([0.0, 0.0, -1.0], 5.5),
            ([1.0, 0.0, 0.0], 4.5),
            ([0.0, 0.0, 1.0], 5.5),
            ([-1.0, 0.0, 0.0], 6.5),
            ([0.0, 1.0, 0.0], 1.5),
            ([0.0, -1.0, 0.0], 9.5),
            ([0.3, 0.5, -0.2], 1.71659),
        ];
        for (d, red) in cases {
            let got = map.radiance(Vec3::from(d).normalize());
            assert!((got.x - red).abs() < 1e-4, "{d:?}: {} vs {red}", got.x);
            assert_eq!((got.y, got.z), (1.0, 2.0));
        }
    }

    #[test]
    fn lookup_is_bilinear_and_wraps() {
        let (w, h) = (4, 3);
        let texels = (0..w * h).map(|k| Vec3::splat(k as f32)).collect();
        let map = EnvironmentMap::new(w, h, texels).unwrap();
        // Halfway between columns 3 and 0 (u = 0 exactly) on the horizon row: (7 + 4) / 2.
        let d = Vec3::new(0.0, 0.0, -1.0);
        assert!((map.radiance(d).x - 5.5).abs() < 1e-5);
    }

    #[test]
    fn samples_carry_their_density_and_radiance() {
        let texels = (0..16 * 9)
            .map(|k| Vec3::new(1.0 + (k % 7) as f32, 2.0, (k % 5) as f32))
            .collect();
        let map = EnvironmentMap::new(16, 9, texels).unwrap();
        for a in 0..20 {
            for b in 0..20 {
                let u = Vec2::new((a as f32 + 0.3) / 20.0, (b as f32 + 0.7) / 20.0);
                let s = map.sample(u);
                assert!((s.direction.length() - 1.0).abs() < 1e-5);
                assert!(s.pdf > 0.0);
                assert!((map.pdf(s.direction) / s.pdf - 1.0).abs() < 1e-3, "{u}");
                let lookup = map.radiance(s.direction);
                assert!((s.radiance - lookup).abs().max_element() < 1e-4 * lookup.max_element());
            }
        }
    }

    #[test]
    fn the_estimator_integrates_the_map() {
        // ∫ L(ω) cos⁺θ_y dω over the sphere, by stratified importance sampling, against a
        // fine uniform quadrature: the irradiance on an upward-facing plane.
        let (w, h) = (32, 17);
        let texels = (0..w * h)
            .map(|k| {
                let (i, j) = (k % w, k / w);
                Vec3::splat(if (3..6).contains(&i) && (2..5).contains(&j) {
                    50.0
                } else {
                    0.2
                })
            })
            .collect();
        let map = EnvironmentMap::new(w, h, texels).unwrap();
        // A fine grid of strata: its midpoints cover every cell in proportion.
        let n = 512;
        let mut estimate = 0.0f64;
        for a in 0..n {
            for b in 0..n {
                let s = map.sample(Vec2::new(
                    (a as f32 + 0.5) / n as f32,
                    (b as f32 + 0.5) / n as f32,
                ));
                estimate += f64::from(s.radiance.x * s.direction.y.max(0.0) / s.pdf);
            }
        }
        estimate /= (n * n) as f64;
        let m = 1000;
        let mut reference = 0.0f64;
        for a in 0..m {
            for b in 0..m {
                // Uniform in φ and cos θ: dω = 4π / m².
                let phi = 2.0 * PI * (a as f32 + 0.5) / m as f32;
                let c = 1.0 - 2.0 * (b as f32 + 0.5) / m as f32;
                let s = (1.0 - c * c).sqrt();
                let d = Vec3::new(phi.sin() * s, c, -phi.cos() * s);
                reference += f64::from(map.radiance(d).x * c.max(0.0));
            }
        }
        reference *= 4.0 * std::f64::consts::PI / (m * m) as f64;
        assert!(
            (estimate / reference - 1.0).abs() < 0.01,
            "{estimate} vs {reference}"
        );
    }

    #[test]
    fn uniform_sky_has_its_radiance_everywhere() {
        let map = EnvironmentMap::uniform(Vec3::new(0.5, 1.0, 2.0)).unwrap();
        let d = Vec3::new(0.3, -0.4, 0.5).normalize();
        assert!((map.radiance(d) - Vec3::new(0.5, 1.0, 2.0)).length() < 1e-6);
        // Uniform over the sphere: 1 / 4π.
        let s = map.sample(Vec2::new(0.3, 0.8));
        assert!((s.pdf * 4.0 * PI - 1.0).abs() < 1e-5);
        let (mean, peak) = map.mean_and_peak();
        assert!((mean - Vec3::new(0.5, 1.0, 2.0)).length() < 1e-6);
        assert_eq!(peak, Vec3::new(0.5, 1.0, 2.0));
    }

    #[test]
    fn the_map_is_the_same_for_any_thread_count() {
        // Rows are built in parallel: distribution, mean and peak must not depend on it.
        let (w, h) = (64, 33);
        let texels: Vec<Rgb> = (0..w * h)
            .map(|k| Vec3::new((k % 13) as f32 * 0.1, (k % 7) as f32 * 3.0, 1e-3 * k as f32))
            .collect();
        let build = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build();
            pool.unwrap()
                .install(|| EnvironmentMap::new(w, h, texels.clone()).unwrap())
        };
        let one = build(1);
        assert_eq!(one, build(3));
        assert_eq!(
            one.mean_and_peak().1,
            Vec3::new(1.2, 18.0, 1e-3 * (w * h - 1) as f32)
        );
    }

    #[test]
    fn bad_maps_are_refused() {
        assert_eq!(
            EnvironmentMap::new(1, 4, vec![Vec3::ONE; 4]),
            Err(EnvironmentError::TooSmall {
                width: 1,
                height: 4
            })
        );
        let mut texels = vec![Vec3::ONE; 6];
        texels[4] = Vec3::new(0.0, -1.0, 0.0);
        assert_eq!(
            EnvironmentMap::new(3, 2, texels),
            Err(EnvironmentError::BadTexel {
                x: 1,
                y: 1,
                value: -1.0
            })
        );
    }
}
