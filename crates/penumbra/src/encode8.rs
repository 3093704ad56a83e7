//! 8-bit encoding: [`encode_8bit`] for one value, and for a whole film ([`film_codes`]) the
//! same codes without a `powf` per channel.
//!
//! The code of a value is a non-decreasing step function of it, so it is the number of the 255
//! step thresholds at or below the value: found once per film by bisection over the `f32`
//! values in `[0, 1]`. A table indexed by the value's high bits gives the code of every bucket
//! of values without a threshold near it; in the others the thresholds are looked up by binary
//! search. Within [`WINDOW`] representable values
//! of a threshold the code is computed directly, as [`encode_8bit`] does. Farther away the
//! lookup cannot differ from it: `powf` is accurate to about one ulp, while 64 steps of the
//! input move the exact result by many ulps of the output, and the linear segment of the sRGB
//! curve is a single exact product.

use crate::film::Film;
use crate::math::Rgb;
use crate::texture::linear_to_srgb;

/// The 8-bit code of a linear value: `round(255·encode(clamp(c, 0, 1)))` with the sRGB curve,
/// or `c^(1/gamma)` when `gamma` is given.
pub fn encode_8bit(c: f32, gamma: Option<f32>) -> u8 {
    let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
    let e = match gamma {
        Some(g) => c.powf(1.0 / g),
        None => linear_to_srgb(c),
    };
    (255.0 * e).round() as u8
}

/// Inputs this many representable values or fewer from a threshold are encoded directly.
const WINDOW: i64 = 64;

/// Below this many values a film is encoded directly: the table costs about 8,000 `powf`.
const MIN_VALUES: usize = 16 * 1024;

/// Buckets of the table: values in `[0, 1]` whose bit patterns agree above bit `BUCKET_BITS`.
const BUCKET_BITS: u32 = 14;

/// A table entry for a bucket that needs the binary search.
const MIXED: u16 = u16::MAX;

/// The thresholds of one transfer function.
pub(crate) struct Encoder8 {
    gamma: Option<f32>,
    /// `thresholds[k - 1]`: the smallest value in `[0, 1]` whose code is at least `k`
    /// (infinite when no value reaches `k`).
    thresholds: [f32; 255],
    /// Per bucket: the code of all its values, or [`MIXED`].
    buckets: Vec<u16>,
}

impl Encoder8 {
    /// The thresholds for `gamma` (`None`: the sRGB curve).
    pub(crate) fn new(gamma: Option<f32>) -> Self {
        let one = 1.0f32.to_bits();
        let mut thresholds = [f32::INFINITY; 255];
        for (k, t) in (1..=255u8).zip(thresholds.iter_mut()) {
            if encode_8bit(1.0, gamma) < k {
                continue;
            }
            // The smallest bit pattern in [0, one] whose code is at least k.
            let (mut lo, mut hi) = (0u32, one);
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if encode_8bit(f32::from_bits(mid), gamma) >= k {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            *t = f32::from_bits(lo);
        }
        let mut encoder = Self {
            gamma,
            thresholds,
            buckets: Vec::new(),
        };
        let last = one >> BUCKET_BITS;
        encoder.buckets = (0..=last)
            .map(|b| {
                let first = b << BUCKET_BITS;
                let end = (first | ((1 << BUCKET_BITS) - 1)).min(one);
                let code = encoder.search(f32::from_bits(first));
                let uniform = code == encoder.search(f32::from_bits(end))
                    && !encoder.near_threshold(f32::from_bits(first), code)
                    && !encoder.near_threshold(f32::from_bits(end), code);
                if uniform {
                    code as u16
                } else {
                    MIXED
                }
            })
            .collect();
        encoder
    }

    /// The number of thresholds at or below `c` (in `[0, 1]`).
    fn search(&self, c: f32) -> u8 {
        self.thresholds.partition_point(|&t| t <= c) as u8
    }

    /// Whether `c`, whose lookup is `k`, lies within [`WINDOW`] of a threshold next to it.
    fn near_threshold(&self, c: f32, k: u8) -> bool {
        let near =
            |t: f32| t.is_finite() && (c.to_bits() as i64 - t.to_bits() as i64).abs() <= WINDOW;
        let below = (k as usize).checked_sub(1).map(|i| self.thresholds[i]);
        let above = self.thresholds.get(k as usize).copied();
        below.is_some_and(near) || above.is_some_and(near)
    }

    /// `encode_8bit(c, gamma)`.
    #[inline]
    pub(crate) fn encode(&self, c: f32) -> u8 {
        // NaN, −0 and negative values all encode as 0.
        let c = if c > 0.0 { c.min(1.0) } else { 0.0 };
        let entry = self.buckets[(c.to_bits() >> BUCKET_BITS) as usize];
        if entry != MIXED {
            return entry as u8;
        }
        let k = self.search(c);
        if self.near_threshold(c, k) {
            encode_8bit(c, self.gamma)
        } else {
            k
        }
    }
}

/// The 8-bit codes of the channels of `pixels`, in order.
pub(crate) fn encode_all(pixels: &[Rgb], gamma: Option<f32>) -> Vec<u8> {
    let values = pixels.iter().flat_map(|p| p.to_array());
    if pixels.len() * 3 < MIN_VALUES {
        return values.map(|c| encode_8bit(c, gamma)).collect();
    }
    let encoder = Encoder8::new(gamma);
    values.map(|c| encoder.encode(c)).collect()
}

/// The 8-bit codes of `film` as a PNG holds them, row by row: R, G, B per pixel; with alpha
/// (premultiplied in the film), the colour divided by it (straight alpha, PNG's convention;
/// 0 where nothing was covered), then A, linear (never gamma-encoded), rounded.
pub fn film_codes(film: &Film, gamma: Option<f32>) -> Vec<u8> {
    let Some(alpha) = &film.alpha else {
        return encode_all(&film.pixels, gamma);
    };
    let straight: Vec<Rgb> = (film.pixels.iter().zip(alpha))
        .map(|(&c, &a)| if a > 0.0 { c / a } else { Rgb::ZERO })
        .collect();
    let codes = encode_all(&straight, gamma);
    let a8 = |a: f32| (a.clamp(0.0, 1.0) * 255.0).round() as u8;
    (codes.chunks_exact(3).zip(alpha))
        .flat_map(|(rgb, &a)| [rgb[0], rgb[1], rgb[2], a8(a)])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eight_bit_encoding_follows_the_srgb_curve_and_clamps() {
        assert_eq!(encode_8bit(0.0, None), 0);
        assert_eq!(encode_8bit(1.0, None), 255);
        assert_eq!(encode_8bit(7.0, None), 255);
        assert_eq!(encode_8bit(-1.0, None), 0);
        // sRGB(0.18) = 0.4614 → 117.7 → 118.
        assert_eq!(encode_8bit(0.18, None), 118);
        // gamma 2.2: 0.5^(1/2.2) = 0.7297 → 186.
        assert_eq!(encode_8bit(0.5, Some(2.2)), 186);
        assert_eq!(encode_8bit(f32::NAN, None), 0);
    }

    const GAMMAS: [Option<f32>; 5] = [None, Some(2.2), Some(1.0), Some(1.8), Some(0.45)];

    #[test]
    fn thresholds_step_the_code_up_by_one() {
        for gamma in GAMMAS {
            let e = Encoder8::new(gamma);
            for (i, &t) in e.thresholds.iter().enumerate() {
                let k = i as u8 + 1;
                if t.is_finite() {
                    assert_eq!(encode_8bit(t, gamma), k, "{gamma:?} at {t}");
                    assert_eq!(encode_8bit(f32::from_bits(t.to_bits() - 1), gamma), k - 1);
                }
            }
        }
    }

    /// Every value near a threshold, and a sample of all values in [0, 1] (one bit pattern in
    /// 61), plus out-of-range, infinite and NaN inputs.
    #[test]
    fn codes_equal_encode_8bit() {
        let specials = [
            -1.0,
            -0.0,
            0.0,
            1.0,
            1.5,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        for gamma in GAMMAS {
            let e = Encoder8::new(gamma);
            let check = |c: f32| assert_eq!(e.encode(c), encode_8bit(c, gamma), "{gamma:?} {c}");
            specials.iter().copied().for_each(check);
            for &t in e.thresholds.iter().filter(|t| t.is_finite()) {
                for d in -3 * WINDOW..=3 * WINDOW {
                    check(f32::from_bits((t.to_bits() as i64 + d) as u32));
                }
            }
            (0..=1.0f32.to_bits())
                .step_by(61)
                .map(f32::from_bits)
                .for_each(check);
        }
    }

    #[test]
    fn small_and_large_films_encode_alike() {
        let ramp = |i: usize| (i as f32 / 39_999.0).powi(3) * 1.2;
        for n in [10, 40_000] {
            let pixels: Vec<Rgb> = (0..n).map(|i| Rgb::new(ramp(i), 0.5, -ramp(i))).collect();
            let direct: Vec<u8> = pixels
                .iter()
                .flat_map(|p| p.to_array().map(|c| encode_8bit(c, None)))
                .collect();
            assert_eq!(encode_all(&pixels, None), direct);
        }
    }
}
