//! The light samples of a batch of points whose lights are all fixed (point lights and fixed
//! grids: the same samples at every point), computed sample by sample across the points.
//!
//! The batch's points sit side by side in [`LANES`] lanes, each of their terms (position,
//! normals, material) kept by lane, and every light sample is one pass of vector loops over
//! the lanes: the directions toward the sample, the specular lobe's powers (`pow`, plain
//! arithmetic that vectorizes), what the sample sends back, and at the end each point's sum.
//! The loops always run over all [`LANES`] lanes, so that none has a scalar remainder: lanes
//! past the batch's points repeat its last point and are never read. The answers land where
//! the bundled shadow rays read and write them: slot `j · points + i` is point `i`'s sample
//! `j`.
//!
//! Each slot holds exactly what gathering at its point gives (the same functions, [`toward`],
//! [`Lobe::specular`]'s terms and [`Model::sample`], on the same values), and each point's
//! light is summed in light and sample order, so the image does not depend on which way the
//! samples were gathered.

use glam::Vec3;

use super::model::{Lobe, Model, Physical, Seed};
use super::plan::{toward, Source};
use super::{Integrator, LightModel, Point, Seen, Shading, BUNDLE_POINTS};
use crate::geometry::Hit;
use crate::math::Rgb;

/// Lanes of the batch's points: a bundle's points, a vector of 16 on AVX-512 (two on AVX2).
const LANES: usize = BUNDLE_POINTS;

/// One value per lane.
type Lane<T = f32> = [T; LANES];

/// Every sample of a batch's points: its light by lane, sample by sample, and its masks in
/// slot `j · points + i` for point `i`'s sample `j`, in light and sample order.
#[derive(Default)]
pub(super) struct Across {
    pub(super) points: Vec<Point>,
    lobes: Lobes,
    /// The light sample `j` sends toward the viewer of each lane's point if visible, by
    /// channel.
    light: Vec<[Lane; 3]>,
    /// Whether a sample cannot contribute (below the surface, behind a one-sided emitter,
    /// sending nothing): no shadow ray.
    pub(super) dark: Vec<bool>,
    /// Whether a sample lies behind the surface: its shadow ray leaves from the other side.
    pub(super) behind: Vec<bool>,
}

/// The points' positions, normals and materials, by lane.
#[derive(Default)]
struct Lobes {
    x: [Lane; 3],
    /// The geometric normal, on the viewer's side.
    n_geom: [Lane; 3],
    /// [`Lobe`]'s fields.
    n: [Lane; 3],
    view: [Lane; 3],
    kd: [Lane; 3],
    ks: [Lane; 3],
    p: Lane,
    specular_norm: Lane,
    /// Whether any point's material is specular.
    specular: bool,
}

impl Across {
    /// Gathers every sample of `integrator`'s lights (all fixed) at the surfaces hit by
    /// camera rays along `directions` (at most [`LANES`], at least one): each point's ambient
    /// term, shadow-ray origins and shadow-ray count in `points`, its samples' terms in the
    /// slots.
    #[inline(always)]
    pub(super) fn gather(&mut self, integrator: &Integrator, directions: &[Vec3], hits: &[Hit]) {
        let count = directions.len();
        assert!((1..=LANES).contains(&count), "{count} points");
        self.points.clear();
        let mut facet = None;
        for (i, (&direction, hit)) in directions.iter().zip(hits).enumerate() {
            let surface = integrator.world.surface_after(hit, &mut facet);
            let (seen, point) = integrator.look(direction, &surface);
            self.lobes.set(i, &seen);
            self.points.push(point);
        }
        self.lobes.pad(count);
        let traced = match integrator.settings.light_model {
            LightModel::Phong => self.samples::<Seed>(integrator),
            LightModel::Physical => self.samples::<Physical>(integrator),
        };
        for (point, t) in self.points.iter_mut().zip(traced) {
            point.traced = t.into();
        }
    }

    /// The slots of every sample, light by light: each sample one pass over the lanes.
    /// Returns each lane's number of samples that can contribute (its shadow rays).
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn samples<M: Model>(&mut self, integrator: &Integrator) -> Lane<u32> {
        let count = self.points.len();
        let rows = integrator.samples as usize;
        self.light.resize(rows, [[0.0; LANES]; 3]);
        self.dark.resize(rows * count, true);
        self.behind.resize(rows * count, false);
        let shading = integrator.settings.shading;
        let lobes = &self.lobes;
        let mut traced = [0u32; LANES];
        let mut row = 0;
        for plan in &integrator.lights {
            let Source::Fixed(points) = &plan.source else {
                unreachable!("every light of a render gathered across points is fixed");
            };
            let light = M::light(plan);
            for k in 0..points.len() {
                let y = [points.x[k], points.y[k], points.z[k]];
                let (mut l, mut d2, mut cos, mut behind) = (
                    [[0.0f32; LANES]; 3],
                    [0.0f32; LANES],
                    [0.0f32; LANES],
                    [false; LANES],
                );
                for i in 0..LANES {
                    let (x, n) = (lane(&lobes.x, i), lane(&lobes.n, i));
                    let (u, d, c) = toward(x, n, y);
                    let g = lane(&lobes.n_geom, i);
                    (l[0][i], l[1][i], l[2][i], d2[i], cos[i]) = (u.x, u.y, u.z, d, c);
                    behind[i] = g.x * u.x + g.y * u.y + g.z * u.z < 0.0;
                }
                let mut spec = [0.0f32; LANES];
                if lobes.specular {
                    for i in 0..LANES {
                        spec[i] = lobes.lobe(i, shading).specular(lane(&l, i), cos[i]);
                    }
                }
                let (mut e, mut dark) = ([[0.0f32; LANES]; 3], [false; LANES]);
                for i in 0..LANES {
                    let terms = M::terms(&light, &lobes.lobe(i, shading));
                    let (light, off) = M::sample(&terms, lane(&l, i), d2[i], cos[i], spec[i]);
                    (e[0][i], e[1][i], e[2][i], dark[i]) = (light.x, light.y, light.z, off);
                }
                for i in 0..LANES {
                    traced[i] += u32::from(!dark[i]);
                }
                self.light[row] = e;
                let slots = row * count..(row + 1) * count;
                self.dark[slots.clone()].copy_from_slice(&dark[..count]);
                self.behind[slots].copy_from_slice(&behind[..count]);
                row += 1;
            }
        }
        traced
    }

    /// Each point's ambient term plus every sample's light that `blocked` (by slot) lets
    /// through, in light and sample order, with the point's shadow-ray count, appended to
    /// `out`.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    pub(super) fn radiance(&self, blocked: &[bool], out: &mut Vec<(Rgb, u64)>) {
        let count = self.points.len();
        let mut sum = [[0.0f32; LANES]; 3];
        for (i, point) in self.points.iter().enumerate() {
            let a = point.ambient;
            (sum[0][i], sum[1][i], sum[2][i]) = (a.x, a.y, a.z);
        }
        for (light, row) in self.light.iter().zip(blocked.chunks_exact(count)) {
            // Each lane's light masked to +0 where its sample is blocked, as `Point::sum`
            // adds 0 there: bitwise, so that the loop compiles to vector instructions (a
            // select was compiled to a branch per lane).
            let mut keep = [0u32; LANES];
            for (k, &b) in keep.iter_mut().zip(row) {
                *k = u32::from(b).wrapping_sub(1);
            }
            // Over the points, not all lanes: a loop the compiler vectorizes as a loop,
            // with the sums in memory (fully unrolled, its sums in registers were not).
            let keep = &keep[..count];
            for c in 0..3 {
                let (sum, light) = (&mut sum[c][..count], &light[c][..count]);
                for i in 0..count {
                    sum[i] += f32::from_bits(light[i].to_bits() & keep[i]);
                }
            }
        }
        out.extend(
            self.points
                .iter()
                .enumerate()
                .map(|(i, p)| (Rgb::new(sum[0][i], sum[1][i], sum[2][i]), p.traced)),
        );
    }
}

impl Lobes {
    /// Lane `i` takes the point `seen`.
    #[inline(always)]
    fn set(&mut self, i: usize, seen: &Seen) {
        let lobe = &seen.lobe;
        let fields = [
            (&mut self.x, seen.x),
            (&mut self.n_geom, seen.n_geom),
            (&mut self.n, lobe.n),
            (&mut self.view, lobe.view),
            (&mut self.kd, lobe.kd),
            (&mut self.ks, lobe.ks),
        ];
        for (field, v) in fields {
            (field[0][i], field[1][i], field[2][i]) = (v.x, v.y, v.z);
        }
        (self.p[i], self.specular_norm[i]) = (lobe.p, lobe.specular_norm);
    }

    /// Lanes from `count` on repeat lane `count − 1`, and [`Lobes::specular`] is set.
    #[inline(always)]
    fn pad(&mut self, count: usize) {
        let last = count - 1;
        let fields = [
            &mut self.x,
            &mut self.n_geom,
            &mut self.n,
            &mut self.view,
            &mut self.kd,
            &mut self.ks,
        ];
        for field in fields {
            for axis in field.iter_mut() {
                let v = axis[last];
                axis[count..].fill(v);
            }
        }
        for axis in [&mut self.p, &mut self.specular_norm] {
            let v = axis[last];
            axis[count..].fill(v);
        }
        let ks = &self.ks;
        self.specular = (0..LANES).any(|i| lane(ks, i) != Vec3::ZERO);
    }

    /// The lobe of lane `i` under `shading`.
    #[inline(always)]
    fn lobe(&self, i: usize, shading: Shading) -> Lobe {
        Lobe {
            n: lane(&self.n, i),
            view: lane(&self.view, i),
            kd: lane(&self.kd, i),
            ks: lane(&self.ks, i),
            p: self.p[i],
            shading,
            specular_norm: self.specular_norm[i],
        }
    }
}

/// Lane `i` of a vector kept by axis.
#[inline(always)]
fn lane(v: &[Lane; 3], i: usize) -> Vec3 {
    Vec3::new(v[0][i], v[1][i], v[2][i])
}
