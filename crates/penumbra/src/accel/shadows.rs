//! The shadow rays of many points, as the integrator asks for them: which grouping a render's
//! shadow rays take ([`Grouping`], chosen by [`Levels::grouping`] from the tree's size and the
//! samples), the light samples every point shares and the runs they are traced in
//! ([`SharedEnds`]), and the queries of each grouping that take more than one kernel call
//! (fans from both sides of a surface, pairs run by run). The integrator gathers its samples
//! and reads the answers; how they are traced is decided here, beside the kernels, as pbrt's
//! integrators ask `IntersectP` and leave the rest to the aggregate.
//!
//! Every grouping answers each segment as [`Levels::occluded`] would (the kernels agree with
//! the single-ray walk), so the image does not depend on it: only the time does (measured:
//! docs/benchmarks.md, «Design measurements»).

use std::ops::Range;

use glam::Vec3;

use super::{Levels, Pairs, SHAFT_MIN_ENDS};
use crate::simd::SimdPath;

/// Points with more light samples than this (over all lights) trace each their own fan when
/// their samples are their own (jittered lights): a bundle would hold every point's segments
/// in memory at once.
const BUNDLE_MAX_SAMPLES: u64 = 64;

/// Points whose lights are all fixed bundle their shadow rays as pairs up to this many light
/// samples (64×64), whatever the tree: pairs write each sample once per render and each point
/// once per batch, so a batch holds only its points' shading terms, about 1 MB at this bound.
/// Pairs take less time than fans in the seed's room, under four lights
/// (scenes/bench/four_lights.toml) or at 16×16 samples, and in the 1M-triangle room (measured:
/// docs/benchmarks.md, «Design measurements», `BUNDLE_MAX_FIXED`). Beyond the bound (lights
/// of up to 1024×1024 samples) a batch would hold hundreds of megabytes, and fans trace one
/// point at a time.
const BUNDLE_MAX_FIXED: u64 = 4096;

/// Fans of fewer samples than this are poor packets (they go one ray at a time): such points
/// bundle whatever the tree.
const FAN_MIN_SAMPLES: u64 = 8;

/// Trees with at least this many nodes are deep enough for bundles of segments (jittered
/// lights: each point has samples of its own) to beat fans. On a room of a few large triangles
/// a fan's rays stay together anyway, and a fan shares its origin, which saves a third of each
/// triangle test; bundles of segments gain the more the deeper the tree (the bunny room, the
/// 1M-triangle room). Fixed samples bundle as pairs, which write each point and sample once
/// (not once per segment) and beat fans on every tree, the seed's room too (measured:
/// docs/benchmarks.md, «Design measurements», `BUNDLE_MIN_NODES`).
const BUNDLE_MIN_NODES: usize = 4096;

/// How a render's shadow rays are grouped into the kernels' queries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Grouping {
    /// Each point's rays as a fan from the point to its samples ([`Levels::occlude_sides`]).
    Fans,
    /// The rays of neighbouring points to each of their own samples as bundles of segments
    /// ([`Levels::occlude_segments_on`]).
    Segments,
    /// Neighbouring points and the samples they all share ([`SharedEnds`]), the segments
    /// between them implied ([`Levels::occlude_shared`]).
    Pairs,
}

/// Every light sample of a render whose points all have the same ones, and the runs of them
/// traced together.
#[derive(Clone, Debug, Default)]
pub(crate) struct SharedEnds {
    /// The samples by axis, in light and sample order.
    pub(crate) axes: [Vec<f32>; 3],
    /// The runs of samples traced together (indices into `axes`): a light with enough samples
    /// for a shaft of its own ([`SHAFT_MIN_ENDS`]) alone, lights with fewer together, in runs
    /// too short for a shaft. A shaft around one light is far narrower than one around
    /// several, so it holds few triangles more often.
    runs: Vec<Range<usize>>,
}

impl SharedEnds {
    /// Adds one light's samples, by axis.
    pub(crate) fn push_light(&mut self, [x, y, z]: [&[f32]; 3]) {
        let (start, n) = (self.axes[0].len(), x.len());
        for (axis, from) in self.axes.iter_mut().zip([x, y, z]) {
            axis.extend_from_slice(from);
        }
        let end = start + n;
        match self.runs.last_mut() {
            Some(run) if n < SHAFT_MIN_ENDS && run.len() + n < SHAFT_MIN_ENDS => run.end = end,
            _ => self.runs.push(start..end),
        }
    }

    /// The runs, for tests.
    #[cfg(test)]
    pub(crate) fn runs(&self) -> &[Range<usize>] {
        &self.runs
    }
}

impl Levels {
    /// How points with `samples` light samples each group their shadow rays in this tree;
    /// `shared` when every point has the same samples (no jittered light).
    pub(crate) fn grouping(&self, samples: u64, shared: bool) -> Grouping {
        let bundles = match shared {
            true => samples <= BUNDLE_MAX_FIXED,
            false => {
                samples <= BUNDLE_MAX_SAMPLES
                    && (samples < FAN_MIN_SAMPLES || self.node_count() >= BUNDLE_MIN_NODES)
            }
        };
        match (bundles, shared) {
            (false, _) => Grouping::Fans,
            (true, false) => Grouping::Segments,
            (true, true) => Grouping::Pairs,
        }
    }

    /// Blocks `blocked[i]` when something occludes the segment to `ends[i]` (up to `t_max` of
    /// it) from `front`, or from `back` where `behind[i]` (a sample behind the surface). Slots
    /// already blocked are not traced; `sides` are buffers reused from call to call.
    pub(crate) fn occlude_sides(
        &self,
        (front, back): (Vec3, Vec3),
        ends: &[Vec3],
        behind: &[bool],
        t_max: f32,
        blocked: &mut [bool],
        sides: &mut (Vec<bool>, Vec<bool>),
    ) {
        let both_sides = blocked.iter().zip(behind).any(|(&b, &h)| !b && h);
        if !both_sides {
            self.occlude_from(front, ends, t_max, blocked);
            return;
        }
        let (to_front, to_back) = sides;
        to_front.clear();
        to_front.extend(blocked.iter().zip(behind).map(|(&b, &h)| b | h));
        to_back.clear();
        to_back.extend(blocked.iter().zip(behind).map(|(&b, &h)| b | !h));
        self.occlude_from(front, ends, t_max, to_front);
        self.occlude_from(back, ends, t_max, to_back);
        for i in 0..blocked.len() {
            blocked[i] = if behind[i] { to_back[i] } else { to_front[i] };
        }
    }

    /// Blocks slot `j · origins.len() + i` of `blocked` when something occludes the segment
    /// from origin `i` to sample `j` of `ends` (up to `t_max` of it), run by run; slots
    /// already blocked are not traced.
    pub(crate) fn occlude_shared(
        &self,
        path: SimdPath,
        origins: &[Vec<f32>; 3],
        ends: &SharedEnds,
        t_max: f32,
        blocked: &mut [bool],
    ) {
        let m = origins[0].len();
        for run in &ends.runs {
            let pairs = Pairs {
                origins: origins.each_ref().map(|axis| &axis[..]),
                ends: ends.axes.each_ref().map(|axis| &axis[run.clone()]),
            };
            let slots = &mut blocked[run.start * m..run.end * m];
            self.occlude_pairs_on(path, pairs, t_max, slots);
        }
    }
}
