//! Shading neighbouring points together: the camera samples of a few adjacent pixels, whose
//! shadow rays toward each light sample are traced as one bundle.
//!
//! Which grouping a render's shadow rays take is the tree's choice (`accel::shadows`, from its
//! size and the samples); the integrator gathers the samples in the layout that grouping
//! reads and asks. A point's shadow rays can be traced as a fan, from the point to the
//! samples of its lights (`Bvh::occlude_from`). A fan's rays spread over the light's extent,
//! so on a fine mesh between surface and light they part ways after a few levels of the tree. The rays from a few
//! neighbouring points to one light sample stay within a pixel or so of each other for their
//! whole length, and the finer the image the closer they run: bundled, they share nearly every
//! node they visit. Fans still serve points with many jittered samples (a fan of hundreds of
//! rays is a packet of its own, and a bundle would hold every point's segments in memory at
//! once), and points with more fixed samples than `accel::shadows` bundles.
//!
//! When every point has the same light samples (no jittered light), a bundle is given as
//! [`crate::accel::Pairs`]: the batch's points once and the samples once per render, the
//! segments between them implied. All of a batch's segments then lie in one shaft between its
//! points and the samples, and the BVH finds the few triangles in it once for the batch
//! (in a room of large triangles, usually the points' own surface alone). Such a batch's
//! samples are gathered across its points too, each sample one pass of vector loops over
//! the points (`across`). Jittered samples differ from point to point: each point gathers its
//! own, and their bundles list every segment ([`Segments`]), which costs their writes; those
//! pay only on deep trees.
//!
//! Either way each shadow ray is the same segment and gets the same answer (both packet kinds
//! answer as [`crate::accel::Bvh::occluded`] would), and each point's light is summed in light
//! and sample order: the image does not depend on how the rays were grouped.

use glam::Vec3;

use super::across::Across;
use super::{Integrator, Point, Scratch, SHADOW_T_MAX};
use crate::accel::{Grouping, Segments, SharedEnds};
use crate::geometry::Hit;
use crate::math::Rgb;
use crate::sampling::Rng;
use crate::simd::{dispatch, Isa, Kernel};

/// Points with at most this many light samples are shaded a batch at a time even when each
/// traces its own fans: a batch is then a few thousand shadow rays at most.
pub(super) const FEW_SAMPLES: u64 = 256;

/// Buffers one worker reuses from one batch to the next.
#[derive(Default)]
pub(crate) struct BatchScratch {
    /// Each point's gathered light samples.
    points: Vec<Scratch>,
    prepared: Vec<Point>,
    /// The samples of points whose lights are all fixed.
    across: Across,
    bundle: Bundle,
}

/// The shadow rays of a batch as bundles: one mask slot per light sample and point, sample
/// by sample.
#[derive(Default)]
struct Bundle {
    /// Each segment's origin and end by axis (jittered lights), or the points' shadow-ray
    /// origins toward samples on their viewer's side (`origin`) and on the other side (`end`)
    /// when every point has the same samples.
    origin: [Vec<f32>; 3],
    end: [Vec<f32>; 3],
    blocked: Vec<bool>,
    /// The slots of the samples behind their surface, traced from the other side.
    back: Vec<bool>,
}

/// [`Integrator::shade_batch`] as a [`Kernel`], to be compiled per instruction set.
struct ShadeBatch<'a, 'w> {
    integrator: &'a Integrator<'w>,
    /// The camera rays' directions.
    directions: &'a [Vec3],
    hits: &'a [Hit],
    rngs: &'a mut [Rng],
    scratch: &'a mut BatchScratch,
    out: &'a mut Vec<(Rgb, u64)>,
}

impl Kernel for ShadeBatch<'_, '_> {
    type Output = ();

    #[inline(always)]
    fn run<const N: usize, I: Isa>(self) {
        let ShadeBatch {
            integrator,
            directions,
            hits,
            rngs,
            scratch,
            out,
        } = self;
        let count = directions.len();
        let BatchScratch {
            points,
            prepared,
            across,
            bundle,
        } = scratch;
        if let (Grouping::Pairs, Some(ends)) = (integrator.grouping, &integrator.fixed_ends) {
            across.gather(integrator, directions, hits);
            let masks = (&across.dark[..], &across.behind[..]);
            bundle.pairs(integrator, &across.points, masks, ends);
            across.radiance(&bundle.blocked, out);
            return;
        }
        let mut facet = None;
        if integrator.grouping == Grouping::Fans {
            // Each point traces its own fans, one point after another in one scratch.
            if points.is_empty() {
                points.push(Scratch::default());
            }
            let point = &mut points[0];
            for (i, &d) in directions.iter().enumerate() {
                let surface = integrator.world.surface_after(&hits[i], &mut facet);
                let p = integrator.prepare(d, &surface, &mut rngs[i], point);
                integrator.occlude(p.front, p.back, point);
                out.push((p.radiance(point), p.traced));
            }
            return;
        }
        if points.len() < count {
            points.resize_with(count, Scratch::default);
        }
        let points = &mut points[..count];
        prepared.clear();
        for (i, point) in points.iter_mut().enumerate() {
            let d = directions[i];
            let surface = integrator.world.surface_after(&hits[i], &mut facet);
            prepared.push(integrator.prepare(d, &surface, &mut rngs[i], point));
        }
        // Every point has the same lights, hence as many samples.
        let samples = points.first().map_or(0, |p| p.blocked.len());
        debug_assert!(points.iter().all(|p| p.blocked.len() == samples));
        // Jittered lights: each point's samples are its own.
        let stride = count.next_multiple_of(N);
        bundle.segments(integrator, points, prepared, stride);
        let blocked = &bundle.blocked;
        // Each point's light, its samples' answers read where the bundles left them.
        out.extend(
            points
                .iter()
                .zip(prepared.iter())
                .enumerate()
                .map(|(i, (point, p))| {
                    let light = p.radiance_where(point, |j| blocked[j * stride + i]);
                    (light, p.traced)
                }),
        );
    }
}

impl Bundle {
    /// Traces the shadow rays of `points` toward light samples `ends` that every point
    /// shares, as [`crate::accel::Pairs`]: the points' origins are written once, not once per
    /// sample. Slot `j · points.len() + i` of `blocked`, of `dark` (samples that cannot
    /// contribute) and of `behind` (samples behind the surface) is point `i`'s sample `j`.
    fn pairs(
        &mut self,
        integrator: &Integrator,
        points: &[Point],
        (dark, behind): (&[bool], &[bool]),
        ends: &SharedEnds,
    ) {
        // Samples behind the surface wait for the second pass, from the other side.
        let any_behind = masks(&mut self.blocked, dark, behind, false);
        let side = |origins: &mut [Vec<f32>; 3], at: fn(&Point) -> glam::Vec3| {
            for (a, axis) in origins.iter_mut().enumerate() {
                axis.clear();
                axis.extend(points.iter().map(|p| at(p)[a]));
            }
        };
        side(&mut self.origin, |p| p.front);
        let accel = integrator.world.accel();
        accel.occlude_shared(
            integrator.path,
            &self.origin,
            ends,
            SHADOW_T_MAX,
            &mut self.blocked,
        );
        if !any_behind {
            return;
        }
        side(&mut self.end, |p| p.back);
        masks(&mut self.back, dark, behind, true);
        accel.occlude_shared(
            integrator.path,
            &self.end,
            ends,
            SHADOW_T_MAX,
            &mut self.back,
        );
        let n = dark.len();
        let (blocked, back, behind) = (&mut self.blocked[..n], &self.back[..n], &behind[..n]);
        for i in 0..n {
            blocked[i] = if behind[i] { back[i] } else { blocked[i] };
        }
    }

    /// Traces the points' shadow rays as [`Segments`], sample-major with `lanes` slots per
    /// sample: the segments of one packet run from neighbouring points to one light sample.
    /// Slots of no point stay blocked.
    fn segments(
        &mut self,
        integrator: &Integrator,
        points: &[Scratch],
        prepared: &[Point],
        lanes: usize,
    ) {
        let (count, samples) = (points.len(), points.first().map_or(0, |p| p.ends.len()));
        let slots = samples * lanes;
        for axis in self.origin.iter_mut().chain(self.end.iter_mut()) {
            axis.resize(slots, 0.0);
        }
        self.blocked.clear();
        self.blocked.resize(slots, true);
        // Row `j` holds the segments toward sample `j`, point by point: the writes are
        // contiguous, and each row's slices are cut once so that the loop needs no bounds
        // checks.
        for j in 0..samples {
            let row = j * lanes..j * lanes + count;
            let [ox, oy, oz] = self.origin.each_mut().map(|v| &mut v[row.clone()]);
            let [ex, ey, ez] = self.end.each_mut().map(|v| &mut v[row.clone()]);
            let blocked = &mut self.blocked[row];
            for (i, (point, p)) in points.iter().zip(prepared.iter()).enumerate() {
                let was = point.blocked[j];
                blocked[i] = was;
                if !was {
                    let o = if point.behind[j] { p.back } else { p.front };
                    (ox[i], oy[i], oz[i]) = (o.x, o.y, o.z);
                    let e = point.ends[j];
                    (ex[i], ey[i], ez[i]) = (e.x, e.y, e.z);
                }
            }
        }
        let segments = Segments {
            origin: self.origin.each_ref().map(|axis| &axis[..]),
            end: self.end.each_ref().map(|axis| &axis[..]),
        };
        let accel = integrator.world.accel();
        accel.occlude_segments_on(integrator.path, segments, SHADOW_T_MAX, &mut self.blocked);
    }
}

/// Sets `mask` to the slots one side's shadow rays skip: those of samples that cannot
/// contribute, or that lie on the other side (behind the surface, or in front of it when
/// `back`). Returns whether any slot is left to the back side. Indexed loops over slices of
/// one length, so that they vectorize.
#[allow(clippy::needless_range_loop)]
fn masks(mask: &mut Vec<bool>, dark: &[bool], behind: &[bool], back: bool) -> bool {
    let n = dark.len();
    mask.resize(n, true);
    let (mask, behind) = (&mut mask[..n], &behind[..n]);
    let mut any_behind = false;
    for i in 0..n {
        mask[i] = dark[i] | (behind[i] != back);
        any_behind |= !dark[i] & behind[i];
    }
    any_behind
}

impl Integrator<'_> {
    /// Shades several points at once (camera rays along `directions`, their `hits` and
    /// `rngs` side by side): the radiance leaving each point back along its ray and the
    /// number of shadow rays it took, in order, appended to `out`. `rngs` supply the jitter of
    /// jittered lights. Each point's answer does not depend on the others; neighbouring
    /// points (the samples of a few adjacent pixels) make it faster. Each hit's surface is
    /// found where it is shaded, so that it stays in registers: built into a list first, each
    /// was assembled on the stack and copied, and the copy's wide loads waited on the narrow
    /// stores of its fields (measured: docs/benchmarks.md, «Design measurements»,
    /// `shade_batch`).
    pub(crate) fn shade_batch(
        &self,
        directions: &[Vec3],
        hits: &[Hit],
        rngs: &mut [Rng],
        scratch: &mut BatchScratch,
        out: &mut Vec<(Rgb, u64)>,
    ) {
        assert!(directions.len() == hits.len() && directions.len() == rngs.len());
        let kernel = ShadeBatch {
            integrator: self,
            directions,
            hits,
            rngs,
            scratch,
            out,
        };
        dispatch(self.path, kernel);
    }
}

#[cfg(test)]
mod tests {
    use super::super::BUNDLE_POINTS;
    use super::*;
    use crate::geometry::{sphere, Mesh};
    use crate::integrator::{LightModel, Shading, ShadingSettings};
    use crate::light::{AreaLight, Light, PointLight};
    use crate::material::Material;
    use crate::math::{Ray, Transform};
    use crate::world::{World, WorldBuilder};

    /// A floor under a sphere, both shiny, an area light (`jitter`ed or not), a point light, a
    /// 4×4 and a 9×9 area light above, and an area light low beside the floor, partly below its
    /// plane.
    fn world(jitter: bool) -> World {
        let mut b = WorldBuilder::new();
        let m = b
            .add_material(Material {
                specular: Vec3::splat(0.4),
                shininess: 20.0,
                ..Material::default()
            })
            .unwrap();
        // The floor's shading normals lean toward +x, so that samples of the low light
        // below the floor's plane are lit yet behind the surface: their shadow rays leave
        // from below it.
        let corners = [
            [-4.0, 0.0, -4.0],
            [4.0, 0.0, -4.0],
            [4.0, 0.0, 4.0],
            [-4.0, 0.0, 4.0],
        ];
        let floor = Mesh {
            positions: corners.map(Vec3::from).to_vec(),
            normals: vec![Vec3::new(0.8, 1.0, 0.0).normalize(); 4],
            indices: vec![[0, 1, 2], [0, 2, 3]],
            ..Mesh::default()
        };
        b.add_mesh(&floor, &Transform::IDENTITY, &[m]).unwrap();
        let lift = Transform::from_matrix(glam::Mat4::from_translation(Vec3::new(0.0, 1.0, 0.0)));
        b.add_mesh(&sphere(0.8), &lift, &[m]).unwrap();
        b.add_light(Light::Area(AreaLight {
            center: Vec3::new(0.3, 3.0, 0.2),
            u: Vec3::new(1.5, 0.0, 0.0),
            v: Vec3::new(0.0, 0.0, 1.5),
            radiance: Vec3::splat(2.0),
            n: 3,
            jitter,
        }));
        b.add_light(Light::Area(AreaLight {
            center: Vec3::new(6.0, -0.6, 0.0),
            u: Vec3::new(0.0, 1.0, 0.0),
            v: Vec3::new(0.0, 0.0, -1.5),
            radiance: Vec3::splat(1.0),
            n: 2,
            jitter: false,
        }));
        b.add_light(Light::Point(PointLight {
            position: Vec3::new(-2.0, 2.5, 1.0),
            intensity: Vec3::splat(0.5),
        }));
        // Enough samples for a shaft of its own: the bundles trace it apart from the others.
        b.add_light(Light::Area(AreaLight {
            center: Vec3::new(-1.0, 3.5, -1.0),
            u: Vec3::new(1.0, 0.0, 0.0),
            v: Vec3::new(0.0, 0.0, 1.0),
            radiance: Vec3::splat(0.5),
            n: 4,
            jitter: false,
        }));
        // With it the points have more samples than jittered lights may bundle (64): fixed,
        // they still bundle.
        b.add_light(Light::Area(AreaLight {
            center: Vec3::new(1.5, 4.0, 1.0),
            u: Vec3::new(0.8, 0.0, 0.0),
            v: Vec3::new(0.0, 0.0, 0.8),
            radiance: Vec3::splat(0.3),
            n: 9,
            jitter: false,
        }));
        b.build(1)
    }

    #[test]
    fn bundles_and_fans_shade_every_point_alike() {
        for jitter in [true, false] {
            shade_both_ways(&world(jitter));
        }
    }

    fn shade_both_ways(world: &World) {
        // Rays from above and from below the floor, so that samples lie on both sides.
        let mut rays = Vec::new();
        for k in 0..40 {
            let (x, z) = ((k % 8) as f32 * 0.6 - 2.1, (k / 8) as f32 * 0.7 - 1.4);
            let eye = Vec3::new(0.5, if k % 5 == 0 { -2.0 } else { 4.0 }, 5.0);
            rays.push(Ray::new(eye, Vec3::new(x, 0.5, z) - eye));
        }
        let hits: Vec<_> = rays
            .iter()
            .filter_map(|r| world.intersect(r, 1e-4, f32::INFINITY).map(|h| (*r, h)))
            .collect();
        assert!(hits.len() > 30, "{} hits", hits.len());
        let (rays, hits): (Vec<Vec3>, Vec<Hit>) =
            hits.iter().map(|(r, h)| (r.direction, *h)).unzip();
        let models = [LightModel::Phong, LightModel::Physical];
        let lobes = [Shading::Phong, Shading::BlinnPhong];
        for (light_model, shading) in models.into_iter().flat_map(|m| lobes.map(|s| (m, s))) {
            let settings = ShadingSettings {
                shading,
                light_model,
                ambient: Vec3::splat(0.1),
                light_samples: None,
            };
            // Fans, and bundles (gathered across points for fixed lights).
            let mut shaded = [Vec::new(), Vec::new()];
            for (fans, out) in [true, false].into_iter().zip(&mut shaded) {
                let mut integrator = Integrator::new(world, settings);
                integrator.grouping = match (fans, integrator.fixed_ends.is_some()) {
                    (true, _) => Grouping::Fans,
                    (false, false) => Grouping::Segments,
                    (false, true) => Grouping::Pairs,
                };
                let mut rngs: Vec<Rng> =
                    (0..rays.len() as u64).map(|i| Rng::new(7, &[i])).collect();
                let mut scratch = BatchScratch::default();
                for start in (0..rays.len()).step_by(BUNDLE_POINTS) {
                    let end = (start + BUNDLE_POINTS).min(rays.len());
                    let points = start..end;
                    integrator.shade_batch(
                        &rays[points.clone()],
                        &hits[points.clone()],
                        &mut rngs[points],
                        &mut scratch,
                        out,
                    );
                }
            }
            assert_eq!(shaded[0], shaded[1], "{light_model:?}, {shading:?}");
            let traced: u64 = shaded[0].iter().map(|s| s.1).sum();
            let lit = shaded[0].iter().filter(|s| s.0.x > 0.1 + 1e-3).count();
            assert!(
                traced > 100 && lit > 10,
                "{traced} shadow rays, {lit} lit points"
            );
        }
    }
}
