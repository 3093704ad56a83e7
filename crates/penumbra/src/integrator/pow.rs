//! The specular lobe's power `x^p`, written so that loops over many lanes vectorize: no call,
//! no table, no branch. libm's `powf` is a call per sample, and a loop that holds one stays
//! scalar; this function is plain arithmetic that the compiler turns into vector instructions
//! on every instruction set, and the same scalar function on the portable path, so every path
//! gives the same bits.
//!
//! It works in `f64`, as libm's own `powf` does: `x^p = 2^(p · log2 x)`, with `log2 x` from the
//! exponent and the series `ln m = 2 atanh((m − 1)/(m + 1))` of the mantissa, and `2^y` from a
//! power of two and the Taylor series of `e^(f ln 2)` for the fraction `|f| ≤ ½`. Both series
//! are truncated below 10⁻¹¹ relative, so the one rounding to `f32` at the end gives the
//! correctly rounded power except when the exact power lies within 10⁻¹¹ of halfway between
//! two floats: then it may be the other neighbour (tested against `f64::powf`).

/// √2 as an `f32` (rounded down, so that `m > SQRT_2` moves every mantissa above √2).
const SQRT_2: f32 = std::f32::consts::SQRT_2;

/// 1.5 · 2⁵²: adding it rounds an `f64` of magnitude below 2⁵¹ to an integer, which then sits
/// in the low bits of the sum.
const SHIFTER: f64 = 6_755_399_441_055_744.0;

/// `x^p` for `x > 0` and `p ≥ 0`, both finite (`x` may be subnormal), within one unit in the
/// last place of the exact power (see the module's docs). `p = 0` or `x = 1` gives exactly 1;
/// a power below the smallest subnormal gives 0 and one above `f32::MAX` gives infinity.
#[inline(always)]
pub(super) fn pow(x: f32, p: f32) -> f32 {
    exp2(p as f64 * log2(x)) as f32
}

/// `log2 x` for a finite `x > 0`, to about 10⁻¹² relative.
#[inline(always)]
fn log2(x: f32) -> f64 {
    // A subnormal is scaled into the normal range first (by 2²⁴, exactly).
    let subnormal = x < f32::MIN_POSITIVE;
    let (x, bias) = match subnormal {
        true => (x * 16_777_216.0, 127 + 24),
        false => (x, 127),
    };
    let bits = x.to_bits();
    let mut e = (bits >> 23) as i32 - bias;
    // The mantissa in [1, 2), then in [√½, √2) so that the series converges fast.
    let mut m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
    if m > SQRT_2 {
        (m, e) = (m * 0.5, e + 1);
    }
    let m = m as f64;
    // ln m = 2 atanh(s) = 2 (s + s³/3 + s⁵/5 + …), |s| ≤ 0.1716: seven terms leave 10⁻¹²,
    // summed by Estrin's scheme (pairs, then pairs of pairs), whose chain of dependent
    // operations is half as long as Horner's.
    let s = (m - 1.0) / (m + 1.0);
    let w = s * s;
    let (w2, w4) = (w * w, (w * w) * (w * w));
    let series = (1.0 + w * (1.0 / 3.0))
        + w2 * ((1.0 / 5.0 + w * (1.0 / 7.0)) + w2 * (1.0 / 9.0 + w * (1.0 / 11.0)))
        + w4 * (w2 * (1.0 / 13.0));
    e as f64 + (2.0 * std::f64::consts::LOG2_E) * (s * series)
}

/// `2^y`, to about 10⁻¹¹ relative; `y` beyond ±1022 is clamped there (already far beyond
/// `f32`'s range, so the final rounding gives 0 or infinity).
#[inline(always)]
fn exp2(y: f64) -> f64 {
    let y = clamp(y, -1022.0, 1022.0);
    // y = k + f with k an integer and |f| ≤ ½; 2^k from k's bits.
    let t = y + SHIFTER;
    let k = t - SHIFTER;
    let f = y - k;
    let scale = f64::from_bits(t.to_bits().wrapping_add(1023) << 52);
    // 2^f = e^z, |z| ≤ 0.347: ten terms of the Taylor series leave 10⁻¹¹ (Estrin's scheme).
    let z = f * std::f64::consts::LN_2;
    let (z2, z4) = (z * z, (z * z) * (z * z));
    let low = (1.0 + z) + z2 * ((1.0 / 2.0) + z * (1.0 / 6.0));
    let mid = ((1.0 / 24.0) + z * (1.0 / 120.0)) + z2 * ((1.0 / 720.0) + z * (1.0 / 5040.0));
    let high = (1.0 / 40_320.0) + z * (1.0 / 362_880.0);
    let series = low + z4 * (mid + z4 * high);
    series * scale
}

/// `y` limited to `[lo, hi]` with the vector min and max instructions' semantics (a NaN gives
/// `lo`).
#[inline(always)]
fn clamp(y: f64, lo: f64, hi: f64) -> f64 {
    let y = if y > lo { y } else { lo };
    if y < hi {
        y
    } else {
        hi
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The correctly rounded power, from `f64` (whose own `powf` is within an ulp of `f64`,
    /// far below `f32`'s rounding).
    fn exact(x: f32, p: f32) -> f32 {
        (x as f64).powf(p as f64) as f32
    }

    /// Distance in units in the last place between two non-negative floats.
    fn ulps(a: f32, b: f32) -> u32 {
        a.to_bits().abs_diff(b.to_bits())
    }

    #[test]
    fn powers_are_within_an_ulp_and_mostly_exact() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let (mut total, mut off) = (0u32, 0u32);
        for _ in 0..200_000 {
            // Bases over (0, 1] as a lobe gives them, with many close to 1; exponents from 0
            // to 10,000 (glTF's shininess range), many small.
            let x = match total % 3 {
                0 => next(),
                1 => 1.0 - next() * 1e-3,
                _ => next() * next() * next(),
            }
            .max(f32::MIN_POSITIVE);
            let p = match total % 4 {
                0 => next() * 4.0,
                1 => next() * 100.0,
                2 => (next() * 200.0).round(),
                _ => next() * 10_000.0,
            };
            let (got, want) = (pow(x, p), exact(x, p));
            assert!(ulps(got, want) <= 1, "{x}^{p}: {got} against {want}");
            total += 1;
            off += u32::from(got != want);
        }
        assert!(off * 1000 < total, "{off} of {total} not correctly rounded");
    }

    #[test]
    fn exact_cases_and_the_ends_of_the_range() {
        for x in [1e-30, 0.3, 1.0, 1.5] {
            assert_eq!(pow(x, 0.0), 1.0, "{x}^0");
        }
        for p in [0.0, 0.5, 3.0, 1e4, 1e30] {
            assert_eq!(pow(1.0, p), 1.0, "1^{p}");
        }
        for (x, p) in [
            (0.5, 2.0),
            (0.25, 3.0),
            (2.0, 10.0),
            (0.5, 149.0),
            (0.5, 126.0),
        ] {
            assert_eq!(pow(x, p), exact(x, p), "{x}^{p}");
        }
        assert_eq!(pow(0.5, 151.0), 0.0);
        assert_eq!(pow(0.9, 1e9), 0.0);
        assert_eq!(pow(1.1, 1e9), f32::INFINITY);
        // Subnormal bases, and powers that are subnormal.
        for x in [1e-40f32, f32::MIN_POSITIVE / 3.0, 1e-45] {
            for p in [0.25, 0.5, 1.0] {
                assert!(ulps(pow(x, p), exact(x, p)) <= 1, "{x}^{p}");
            }
        }
        assert!(ulps(pow(0.3, 80.0), exact(0.3, 80.0)) <= 1);
    }
}
