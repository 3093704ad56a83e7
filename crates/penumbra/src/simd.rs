//! Instruction-set dispatch: the crate's only `unsafe` code.
#![allow(unsafe_code)]
//!
//! The hot kernels (shadow packets in `accel::shadow_fans`, the light-sample lanes of the
//! integrator) are plain safe Rust over fixed-size lane arrays and slices. A [`Kernel`] is
//! compiled once per instruction set here (`#[target_feature]` functions into which its
//! `run::<N>` is inlined: 16 lanes for AVX-512, 8 for AVX2, 8 on the portable baseline, which
//! is SSE2 on x86-64), and one of those is chosen once per process: the best the CPU
//! supports, or the one named by the environment variable `PENUMBRA_SIMD` (`avx512`, `avx2` or
//! `portable`) when the CPU supports it. Rust never fuses a multiply and an add on its own, so
//! every path computes the same results bit for bit.

use std::sync::OnceLock;

/// An instruction set the kernels are compiled for.
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

/// Why `PENUMBRA_SIMD` cannot be honoured.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SimdEnvError {
    /// It names no path.
    #[error("PENUMBRA_SIMD={0:?} is not one of avx512, avx2, portable")]
    Unknown(String),
    /// It names a path this CPU cannot run.
    #[error("PENUMBRA_SIMD={} names a path this CPU does not support (it supports {})", .0.name(), names(&supported_paths()))]
    Unsupported(SimdPath),
}

fn names(paths: &[SimdPath]) -> String {
    paths
        .iter()
        .map(|p| p.name())
        .collect::<Vec<_>>()
        .join(", ")
}

/// What the environment variable `PENUMBRA_SIMD` asks for: `None` when it is unset or empty,
/// the path when it names one this CPU supports, else why not. [`simd_path`] falls back to the
/// best path on an error; front ends call this first to report it.
pub fn forced_simd_path() -> Result<Option<SimdPath>, SimdEnvError> {
    parse_forced(std::env::var("PENUMBRA_SIMD").ok().as_deref())
}

fn parse_forced(value: Option<&str>) -> Result<Option<SimdPath>, SimdEnvError> {
    let Some(name) = value.filter(|v| !v.is_empty()) else {
        return Ok(None);
    };
    let path = [SimdPath::Avx512, SimdPath::Avx2, SimdPath::Portable]
        .into_iter()
        .find(|p| p.name() == name)
        .ok_or_else(|| SimdEnvError::Unknown(name.to_owned()))?;
    if path.is_supported() {
        Ok(Some(path))
    } else {
        Err(SimdEnvError::Unsupported(path))
    }
}

/// The path this process uses, chosen on first use: `PENUMBRA_SIMD` if it names a supported
/// path (see [`forced_simd_path`]), else the best supported one.
pub fn simd_path() -> SimdPath {
    static PATH: OnceLock<SimdPath> = OnceLock::new();
    *PATH.get_or_init(|| {
        forced_simd_path()
            .ok()
            .flatten()
            .unwrap_or(supported_paths()[0])
    })
}

/// Work to compile per instruction set: `run::<N, I>` with `N` lanes per vector group and the
/// instruction set's own operations in `I`. Its implementation, and every function it calls
/// that should use the instruction set, must be `#[inline(always)]`: code that is not inlined
/// into the dispatching function is compiled for the baseline only.
pub(crate) trait Kernel {
    /// What the work returns.
    type Output;
    /// Does the work with `N` lanes.
    fn run<const N: usize, I: Isa>(self) -> Self::Output;
}

/// The few operations that plain Rust does not compile well, per instruction set.
pub(crate) trait Isa {
    /// Bit `i` set where lane `i` is negative (all ones, for a comparison's result): one
    /// move-mask instruction where the instruction set has it for `N` lanes.
    fn mask<const N: usize>(lanes: &[i32; N]) -> u32;
}

/// The sign bits of `lanes` one by one: what every path falls back on.
#[inline(always)]
fn mask_by_lane<const N: usize>(lanes: &[i32; N]) -> u32 {
    let mut bits = 0;
    for (i, &lane) in lanes.iter().enumerate() {
        bits |= ((lane as u32) >> 31) << i;
    }
    bits
}

/// AVX-512 F/VL/BW/DQ.
struct Avx512;
/// AVX2.
struct Avx2;
/// The target's baseline (SSE2 on x86-64); what a query that uses no SIMD names as its `Isa`.
pub(crate) struct Baseline;

impl Isa for Avx512 {
    #[inline(always)]
    fn mask<const N: usize>(lanes: &[i32; N]) -> u32 {
        #[cfg(target_arch = "x86_64")]
        if N == 16 {
            // SAFETY: `Avx512` is only used by `run_avx512`, which runs only on CPUs with
            // AVX-512 F/DQ; the 16 lanes are 64 readable bytes.
            return unsafe { mask16_avx512(lanes.as_ptr()) };
        }
        #[cfg(target_arch = "x86_64")]
        if N == 32 {
            // SAFETY: as for 16 lanes, twice.
            return unsafe {
                mask16_avx512(lanes.as_ptr()) | mask16_avx512(lanes.as_ptr().add(16)) << 16
            };
        }
        #[cfg(target_arch = "x86_64")]
        if N == 8 {
            // SAFETY: `Avx512` is only used by `run_avx512`, which runs only on CPUs with
            // AVX-512 F, hence AVX2; the 8 lanes are 32 readable bytes.
            return unsafe { mask8_avx2(lanes.as_ptr()) };
        }
        mask_by_lane(lanes)
    }
}

impl Isa for Avx2 {
    #[inline(always)]
    fn mask<const N: usize>(lanes: &[i32; N]) -> u32 {
        #[cfg(target_arch = "x86_64")]
        if N == 8 {
            // SAFETY: `Avx2` is only used by `run_avx2`, which runs only on CPUs with AVX2;
            // the 8 lanes are 32 readable bytes.
            return unsafe { mask8_avx2(lanes.as_ptr()) };
        }
        #[cfg(target_arch = "x86_64")]
        if N == 16 {
            // SAFETY: as for 8 lanes, twice.
            return unsafe { mask8_avx2(lanes.as_ptr()) | mask8_avx2(lanes.as_ptr().add(8)) << 8 };
        }
        #[cfg(target_arch = "x86_64")]
        if N == 32 {
            // SAFETY: as for 8 lanes, four times.
            let at = |k: usize| unsafe { mask8_avx2(lanes.as_ptr().add(8 * k)) << (8 * k) };
            return at(0) | at(1) | at(2) | at(3);
        }
        mask_by_lane(lanes)
    }
}

impl Isa for Baseline {
    #[inline(always)]
    fn mask<const N: usize>(lanes: &[i32; N]) -> u32 {
        #[cfg(target_arch = "x86_64")]
        if N == 8 {
            // SAFETY: SSE2 is part of every x86-64 CPU; the 8 lanes are 32 readable bytes.
            return unsafe { mask8_sse2(lanes.as_ptr()) };
        }
        #[cfg(target_arch = "x86_64")]
        if N == 16 {
            // SAFETY: as for 8 lanes, twice.
            return unsafe { mask8_sse2(lanes.as_ptr()) | mask8_sse2(lanes.as_ptr().add(8)) << 8 };
        }
        #[cfg(target_arch = "x86_64")]
        if N == 32 {
            // SAFETY: as for 8 lanes, four times.
            let at = |k: usize| unsafe { mask8_sse2(lanes.as_ptr().add(8 * k)) << (8 * k) };
            return at(0) | at(1) | at(2) | at(3);
        }
        mask_by_lane(lanes)
    }
}

/// `vpmovd2m` of 16 lanes at `lanes`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq")]
#[inline]
unsafe fn mask16_avx512(lanes: *const i32) -> u32 {
    use std::arch::x86_64::{_mm512_loadu_si512, _mm512_movepi32_mask};
    // SAFETY: the caller guarantees 64 readable bytes; `loadu` takes any alignment.
    let v = unsafe { _mm512_loadu_si512(lanes.cast()) };
    _mm512_movepi32_mask(v) as u32
}

/// `vmovmskps` of 8 lanes at `lanes`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn mask8_avx2(lanes: *const i32) -> u32 {
    use std::arch::x86_64::{_mm256_castsi256_ps, _mm256_loadu_si256, _mm256_movemask_ps};
    // SAFETY: the caller guarantees 32 readable bytes; `loadu` takes any alignment.
    let v = unsafe { _mm256_loadu_si256(lanes.cast()) };
    _mm256_movemask_ps(_mm256_castsi256_ps(v)) as u32
}

/// Two `movmskps` of 4 lanes each at `lanes`.
#[cfg(target_arch = "x86_64")]
#[inline]
unsafe fn mask8_sse2(lanes: *const i32) -> u32 {
    use std::arch::x86_64::{_mm_castsi128_ps, _mm_loadu_si128, _mm_movemask_ps};
    // SAFETY: the caller guarantees 32 readable bytes; `loadu` takes any alignment, and SSE2
    // is baseline on x86-64.
    unsafe {
        let lo = _mm_loadu_si128(lanes.cast());
        let hi = _mm_loadu_si128(lanes.add(4).cast());
        (_mm_movemask_ps(_mm_castsi128_ps(lo)) | (_mm_movemask_ps(_mm_castsi128_ps(hi)) << 4))
            as u32
    }
}

/// Runs `kernel` compiled for `path` (the portable build when the CPU lacks `path`).
#[inline]
pub(crate) fn dispatch<K: Kernel>(path: SimdPath, kernel: K) -> K::Output {
    #[cfg(target_arch = "x86_64")]
    if path.is_supported() {
        match path {
            // SAFETY: the CPU supports AVX-512 F/VL/BW/DQ (checked just above), all that
            // `run_avx512` is compiled for.
            SimdPath::Avx512 => return unsafe { run_avx512(kernel) },
            // SAFETY: the CPU supports AVX2 (checked just above), all that `run_avx2` is
            // compiled for.
            SimdPath::Avx2 => return unsafe { run_avx2(kernel) },
            SimdPath::Portable => {}
        }
    }
    kernel.run::<8, Baseline>()
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl,avx512bw,avx512dq")]
unsafe fn run_avx512<K: Kernel>(kernel: K) -> K::Output {
    kernel.run::<16, Avx512>()
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn run_avx2<K: Kernel>(kernel: K) -> K::Output {
    kernel.run::<8, Avx2>()
}

/// `a < b ? a : b`: the vector min instruction's semantics, so that lane loops written with
/// it compile to one instruction per vector (and a NaN in `a` gives `b`, as the instruction).
#[inline(always)]
pub(crate) fn min(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

/// `a > b ? a : b`: the vector max instruction's semantics (see [`min`]).
#[inline(always)]
pub(crate) fn max(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

/// Asks the CPU to start loading the cache lines of `value` into its caches: a hint that
/// changes no result. The traversals call it for the nodes and triangles they will visit a
/// little later, so that the loads overlap the work in between.
#[inline(always)]
pub(crate) fn prefetch<T>(value: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let p: *const i8 = (value as *const T).cast();
        for offset in (0..std::mem::size_of::<T>()).step_by(64) {
            // SAFETY: a prefetch never faults and reads nothing the program sees; `p + offset`
            // stays inside `value`. SSE is part of every x86-64 CPU.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(offset)) };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = value;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn penumbra_simd_is_checked_name_by_name() {
        assert_eq!(parse_forced(None), Ok(None));
        assert_eq!(parse_forced(Some("")), Ok(None));
        assert_eq!(parse_forced(Some("portable")), Ok(Some(SimdPath::Portable)));
        for typo in ["avx-2", "AVX2", "sse2", "avx512 "] {
            let err = parse_forced(Some(typo)).unwrap_err();
            assert_eq!(err, SimdEnvError::Unknown(typo.into()));
            assert!(err
                .to_string()
                .contains("not one of avx512, avx2, portable"));
        }
        for path in [SimdPath::Avx512, SimdPath::Avx2] {
            let expected = if path.is_supported() {
                Ok(Some(path))
            } else {
                Err(SimdEnvError::Unsupported(path))
            };
            assert_eq!(parse_forced(Some(path.name())), expected);
        }
    }

    /// `Isa::mask` of 8, 16 and 32 lanes with the sign bits of `bits`, on the path that runs.
    struct Masks(u32);

    impl Kernel for Masks {
        type Output = [u32; 3];

        fn run<const N: usize, I: Isa>(self) -> [u32; 3] {
            let lanes = |i: usize| {
                if self.0 >> i & 1 == 1 {
                    -1 - i as i32
                } else {
                    i as i32
                }
            };
            let (a, b, c): ([i32; 8], [i32; 16], [i32; 32]) = (
                std::array::from_fn(lanes),
                std::array::from_fn(lanes),
                std::array::from_fn(lanes),
            );
            [I::mask(&a), I::mask(&b), I::mask(&c)]
        }
    }

    #[test]
    fn masks_of_one_to_four_vectors_are_the_lanes_sign_bits() {
        for bits in [
            0,
            u32::MAX,
            0x8000_0001,
            0x1234_5678,
            0xdead_beef,
            1 << 16,
            0xff00,
        ] {
            let want = [bits & 0xff, bits & 0xffff, bits];
            for path in supported_paths() {
                assert_eq!(dispatch(path, Masks(bits)), want, "{bits:#x} on {path:?}");
            }
        }
    }
}
