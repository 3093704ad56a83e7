//! The light samples of a batch of points whose lights are all fixed (point lights and fixed
//! grids: the same samples at every point), computed sample by sample across the points.
//!
//! Gathering point by point (`Integrator::gather`) runs one short loop per light at each
//! point: with a few point lights those loops hold one sample each, and a point's shading
//! becomes a chain of dependent square roots and divisions with bookkeeping between them.
//! Across the points, the directions to each sample are one vector loop over the batch's
//! points (kept by axis), the rest of each sample's terms a loop whose points' chains
//! overlap, and the answers land where the bundled shadow rays read and write them: slot
//! `j · points + i` is point `i`'s sample `j`.
//!
//! Each slot holds exactly what gathering at its point gives (the same functions,
//! [`toward`], `Lobe::specular` and [`Model::sample`], on the same values), so the image does
//! not depend on which way the samples were gathered.

use glam::Vec3;

use super::model::{Model, Physical, Seed};
use super::plan::{toward, Directions, Source};
use super::{Integrator, LightModel, Point, Seen};
use crate::geometry::Surface;
use crate::math::Rgb;

/// Lights with fewer samples than this on average gather across points. Gathering point by
/// point runs each light's loop over its samples as vectors, which pays once a light has a
/// vector's worth of them; across points each sample is a scalar loop over the points.
/// Gathered across points, three point lights took 0.85× the time (1024², 2 threads), and the
/// seed's room (one light of 25 samples) 1.42×.
const MAX_MEAN_SAMPLES: u64 = 8;

/// Whether a render whose `lights` have `samples` fixed samples in all gathers them across
/// points.
pub(super) fn pays(samples: u64, lights: usize) -> bool {
    samples < MAX_MEAN_SAMPLES * lights as u64
}

/// Every sample of a batch's points, slot `j · points + i` for point `i`'s sample `j`, in
/// light and sample order.
#[derive(Default)]
pub(super) struct Across {
    pub(super) seen: Vec<Seen>,
    pub(super) points: Vec<Point>,
    /// The light each sample sends toward the viewer if visible, by channel.
    r: Vec<f32>,
    g: Vec<f32>,
    b: Vec<f32>,
    /// Whether a sample cannot contribute (below the surface, behind a one-sided emitter,
    /// sending nothing): no shadow ray.
    pub(super) dark: Vec<bool>,
    /// Whether a sample lies behind the surface: its shadow ray leaves from the other side.
    pub(super) behind: Vec<bool>,
    /// Each point's position, shading normal and geometric normal, by axis, and the
    /// directions from every point toward one sample.
    frames: Frames,
    row: Directions,
}

/// Points' positions, shading normals and geometric normals, by axis.
#[derive(Default)]
struct Frames {
    x: [Vec<f32>; 3],
    n: [Vec<f32>; 3],
    n_geom: [Vec<f32>; 3],
}

impl Across {
    /// Gathers every sample of `integrator`'s lights (all fixed) at the surfaces hit by
    /// camera rays along `directions`: each point's ambient term and shadow-ray origins in
    /// `points`, its samples' terms in the slots.
    #[inline(always)]
    pub(super) fn gather(
        &mut self,
        integrator: &Integrator,
        directions: &[Vec3],
        surfaces: &[Surface],
    ) {
        self.seen.clear();
        self.points.clear();
        for (&direction, surface) in directions.iter().zip(surfaces) {
            let (seen, point) = integrator.look(direction, surface);
            self.seen.push(seen);
            self.points.push(point);
        }
        let frames = &mut self.frames;
        for a in 0..3 {
            let seen = &self.seen;
            let axis = |v: &mut Vec<f32>, of: fn(&Seen) -> Vec3| {
                v.clear();
                v.extend(seen.iter().map(|s| of(s)[a]));
            };
            axis(&mut frames.x[a], |s| s.x);
            axis(&mut frames.n[a], |s| s.lobe.n);
            axis(&mut frames.n_geom[a], |s| s.n_geom);
        }
        match integrator.settings.light_model {
            LightModel::Phong => self.samples::<Seed>(integrator),
            LightModel::Physical => self.samples::<Physical>(integrator),
        }
        let count = self.points.len();
        for (i, point) in self.points.iter_mut().enumerate() {
            point.traced = self
                .dark
                .iter()
                .skip(i)
                .step_by(count)
                .filter(|&&d| !d)
                .count() as u64;
        }
    }

    /// The slots of every sample, light by light.
    #[inline(always)]
    fn samples<M: Model>(&mut self, integrator: &Integrator) {
        let count = self.seen.len();
        let slots = integrator.samples as usize * count;
        for v in [&mut self.r, &mut self.g, &mut self.b] {
            v.resize(slots, 0.0);
        }
        self.dark.resize(slots, true);
        self.behind.resize(slots, false);
        let mut slot = 0;
        for plan in &integrator.lights {
            let Source::Fixed(points) = &plan.source else {
                unreachable!("every light of a render gathered across points is fixed");
            };
            for k in 0..points.len() {
                let y = [points.x[k], points.y[k], points.z[k]];
                let row = slot..slot + count;
                let (r, g, b) = (
                    &mut self.r[row.clone()],
                    &mut self.g[row.clone()],
                    &mut self.b[row.clone()],
                );
                let (dark, behind) = (&mut self.dark[row.clone()], &mut self.behind[row]);
                self.frames.toward(y, &mut self.row, behind);
                let dirs = &self.row;
                for (i, seen) in self.seen.iter().enumerate() {
                    let lobe = &seen.lobe;
                    let l = Vec3::new(dirs.lx[i], dirs.ly[i], dirs.lz[i]);
                    let (d2, cos) = (dirs.d2[i], dirs.cos[i]);
                    // powf only where the sample can contribute.
                    let spec = if cos > 0.0 {
                        lobe.specular(l, cos)
                    } else {
                        0.0
                    };
                    let (e, off) = M::sample(&M::terms(plan, lobe), l, d2, cos, spec);
                    (r[i], g[i], b[i], dark[i]) = (e.x, e.y, e.z, off);
                }
                slot += count;
            }
        }
    }

    /// Point `i`'s ambient term plus every sample's light that `blocked` (by slot) lets
    /// through, in light and sample order.
    #[inline(always)]
    pub(super) fn radiance(&self, i: usize, blocked: &[bool]) -> Rgb {
        let count = self.points.len();
        let slots = blocked.len();
        let (r, g, b) = (&self.r[..slots], &self.g[..slots], &self.b[..slots]);
        self.points[i].sum(slots / count, |j| {
            let slot = j * count + i;
            (!blocked[slot]).then(|| Rgb::new(r[slot], g[slot], b[slot]))
        })
    }
}

impl Frames {
    /// The directions from every point toward `y` ([`toward`] each) in `dirs`, and whether
    /// `y` lies behind each point's surface in `behind`. Whole chunks of [`LANES`] points are
    /// computed into arrays of their own, in one loop that vectorizes (the square roots and
    /// divisions of many points at once), and then copied out; the last few points one at a
    /// time. Written in place over the slices, the loop stayed scalar, a bounds check per
    /// store.
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn toward(&self, y: [f32; 3], dirs: &mut Directions, behind: &mut [bool]) {
        let count = behind.len();
        let [lx, ly, lz, d2s, coss] = dirs.lanes(count);
        let whole = count - count % LANES;
        for start in (0..whole).step_by(LANES) {
            let (x, n, g) = (
                whole_chunk(&self.x, start),
                whole_chunk(&self.n, start),
                whole_chunk(&self.n_geom, start),
            );
            let (mut l, mut d2, mut cos, mut back) = (
                [[0.0f32; LANES]; 3],
                [0.0f32; LANES],
                [0.0f32; LANES],
                [false; LANES],
            );
            for i in 0..LANES {
                let v = |c: &[&[f32; LANES]; 3]| Vec3::new(c[0][i], c[1][i], c[2][i]);
                let (u, d, c, b) = frame(v(&x), v(&n), v(&g), y);
                (l[0][i], l[1][i], l[2][i], d2[i], cos[i], back[i]) = (u.x, u.y, u.z, d, c, b);
            }
            let out = start..start + LANES;
            for (to, from) in [&mut *lx, &mut *ly, &mut *lz, &mut *d2s, &mut *coss]
                .into_iter()
                .zip([l[0], l[1], l[2], d2, cos])
            {
                to[out.clone()].copy_from_slice(&from);
            }
            behind[out].copy_from_slice(&back);
        }
        for i in whole..count {
            let v = |c: &[Vec<f32>; 3]| Vec3::new(c[0][i], c[1][i], c[2][i]);
            let (u, d, c, b) = frame(v(&self.x), v(&self.n), v(&self.n_geom), y);
            (lx[i], ly[i], lz[i], d2s[i], coss[i], behind[i]) = (u.x, u.y, u.z, d, c, b);
        }
    }
}

/// Points computed together by [`Frames::toward`]: a vector of 16 on AVX-512, two on AVX2.
const LANES: usize = 16;

/// The [`LANES`] values of each axis of `v` from `start` (which are there).
#[inline(always)]
fn whole_chunk(v: &[Vec<f32>; 3], start: usize) -> [&[f32; LANES]; 3] {
    v.each_ref()
        .map(|axis| axis[start..].first_chunk().expect("a whole chunk"))
}

/// The direction from a point at `x` with shading normal `n` and geometric normal `g` toward
/// `y`, its squared distance and cosine ([`toward`]), and whether `y` lies behind the surface.
#[inline(always)]
fn frame(x: Vec3, n: Vec3, g: Vec3, y: [f32; 3]) -> (Vec3, f32, f32, bool) {
    let (l, d2, cos) = toward(x, n, y);
    (l, d2, cos, g.x * l.x + g.y * l.y + g.z * l.z < 0.0)
}
