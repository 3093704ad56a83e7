//! Instruction-set dispatch for the packet kernels: the crate's only `unsafe` code.
#![allow(unsafe_code)]
//!
//! The kernels (`packet`) are plain safe Rust over fixed-size lane arrays. Here they are
//! compiled once per instruction set (`#[target_feature]` functions that inline the same
//! generic body: 16 lanes for AVX-512, 8 for AVX2, 8 on the portable baseline, which is SSE2
//! on x86-64), and one of those is chosen once per process: the best the CPU supports, or the
//! one named by the environment variable `PENUMBRA_SIMD` (`avx512`, `avx2` or `portable`)
//! when the CPU supports it. Every path computes the same results bit for bit (see `packet`).

use std::sync::OnceLock;

use glam::Vec3;

use super::{packet, traverse, Bvh};
use crate::math::Ray;

/// An instruction set the packet kernels are compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SimdPath {
    /// AVX-512 (F, VL, BW, DQ): 16 lanes.
    Avx512,
    /// AVX2: 8 lanes.
    Avx2,
    /// No extension beyond the target's baseline (SSE2 on x86-64): 8 lanes.
    Portable,
}

impl SimdPath {
    /// The name `PENUMBRA_SIMD` takes.
    pub fn name(self) -> &'static str {
        match self {
            SimdPath::Avx512 => "avx512",
            SimdPath::Avx2 => "avx2",
            SimdPath::Portable => "portable",
        }
    }

    /// True when this CPU can run the path.
    pub fn is_supported(self) -> bool {
        match self {
            #[cfg(target_arch = "x86_64")]
            SimdPath::Avx512 => {
                is_x86_feature_detected!("avx512f")
                    && is_x86_feature_detected!("avx512vl")
                    && is_x86_feature_detected!("avx512bw")
                    && is_x86_feature_detected!("avx512dq")
            }
            #[cfg(target_arch = "x86_64")]
            SimdPath::Avx2 => is_x86_feature_detected!("avx2"),
            #[cfg(not(target_arch = "x86_64"))]
            SimdPath::Avx512 | SimdPath::Avx2 => false,
            SimdPath::Portable => true,
        }
    }
}

/// Every path this CPU supports, best first.
pub fn supported_paths() -> Vec<SimdPath> {
    [SimdPath::Avx512, SimdPath::Avx2, SimdPath::Portable]
        .into_iter()
        .filter(|p| p.is_supported())
        .collect()
}

/// The path this process uses, chosen on first use: `PENUMBRA_SIMD` if it names a supported
/// path, else the best supported one.
pub fn simd_path() -> SimdPath {
    static PATH: OnceLock<SimdPath> = OnceLock::new();
    *PATH.get_or_init(|| {
        let supported = supported_paths();
        let forced = std::env::var("PENUMBRA_SIMD").ok();
        supported
            .iter()
            .copied()
            .find(|p| forced.as_deref() == Some(p.name()))
            .unwrap_or(supported[0])
    })
}

/// [`Bvh::occlude_from`] on `path`, which must be supported (else the portable path runs).
pub(super) fn occlude_from(
    path: SimdPath,
    bvh: &Bvh,
    origin: Vec3,
    ends: &[Vec3],
    t_max: f32,
    blocked: &mut [bool],
) {
    assert_eq!(ends.len(), blocked.len(), "one mask slot per segment");
    #[cfg(target_arch = "x86_64")]
    if path.is_supported() {
        match path {
            // SAFETY: the CPU supports AVX-512 F/VL/BW/DQ (checked just above), all that
            // `occlude_from_avx512` is compiled for.
            SimdPath::Avx512 => {
                return unsafe { occlude_from_avx512(bvh, origin, ends, t_max, blocked) }
            }
            // SAFETY: the CPU supports AVX2 (checked just above).
            SimdPath::Avx2 => {
                return unsafe { occlude_from_avx2(bvh, origin, ends, t_max, blocked) }
            }
            SimdPath::Portable => {}
        }
    }
    packets::<8>(bvh, origin, ends, t_max, blocked);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl,avx512bw,avx512dq")]
unsafe fn occlude_from_avx512(
    bvh: &Bvh,
    origin: Vec3,
    ends: &[Vec3],
    t_max: f32,
    blocked: &mut [bool],
) {
    packets::<16>(bvh, origin, ends, t_max, blocked);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn occlude_from_avx2(
    bvh: &Bvh,
    origin: Vec3,
    ends: &[Vec3],
    t_max: f32,
    blocked: &mut [bool],
) {
    packets::<8>(bvh, origin, ends, t_max, blocked);
}

/// The segments in packets of `N` lanes; a packet with a quarter of its lanes or fewer to
/// trace goes one ray at a time.
#[inline(always)]
fn packets<const N: usize>(
    bvh: &Bvh,
    origin: Vec3,
    ends: &[Vec3],
    t_max: f32,
    blocked: &mut [bool],
) {
    if bvh.nodes.is_empty() {
        return;
    }
    for (ends, blocked) in ends.chunks(N).zip(blocked.chunks_mut(N)) {
        let live = blocked.iter().filter(|&&b| !b).count();
        if live == 0 {
            continue;
        }
        if live * 4 <= N {
            for (&end, b) in ends.iter().zip(blocked) {
                if !*b {
                    *b = traverse::occluded(bvh, &Ray::new(origin, end - origin), 0.0, t_max);
                }
            }
        } else {
            packet::occlude_packet::<N>(bvh, origin, ends, t_max, blocked);
        }
    }
}
