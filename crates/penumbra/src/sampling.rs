//! Sample generators: the pixel offset patterns of SPEC §4 (docs/spec.md) and a counter-based random
//! generator, seeded per pixel and sample, so that images never depend on scheduling.

use glam::Vec2;

use crate::names::{parse_name, UnknownName};

/// How pixel samples are placed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Sampler {
    /// One sample at the pixel center.
    Center,
    /// An n×n grid of cell centers.
    Grid,
    /// The grid rotated by arctan(1/2) and wrapped into the pixel (rotated-grid supersampling).
    Rgss,
    /// One uniformly random point in each cell of an n×n grid.
    Jittered,
}

impl Sampler {
    /// Every sampler, in the order messages list them.
    pub const ALL: [Sampler; 4] = [
        Sampler::Center,
        Sampler::Grid,
        Sampler::Rgss,
        Sampler::Jittered,
    ];

    /// The name used in scene files, on the command line and in Python; [`str::parse`] takes
    /// it back.
    pub fn name(self) -> &'static str {
        match self {
            Sampler::Center => "center",
            Sampler::Grid => "grid",
            Sampler::Rgss => "rgss",
            Sampler::Jittered => "jittered",
        }
    }
}

/// A sampler by its [`Sampler::name`]; an unknown name is an error listing the names.
///
/// ```
/// use penumbra::Sampler;
///
/// assert_eq!("rgss".parse(), Ok(Sampler::Rgss));
/// let e = "sobol".parse::<Sampler>().unwrap_err();
/// assert_eq!(e.to_string(), r#"unknown sampler "sobol" (use "center", "grid", "rgss" or "jittered")"#);
/// ```
impl std::str::FromStr for Sampler {
    type Err = UnknownName;

    fn from_str(name: &str) -> Result<Sampler, UnknownName> {
        parse_name("sampler", name, &Sampler::ALL, Sampler::name)
    }
}

/// The integer square root of `samples` when it is a perfect square.
pub fn perfect_square_root(samples: u32) -> Option<u32> {
    let n = (samples as f64).sqrt().round() as u64;
    (n >= 1 && n * n == samples as u64).then_some(n as u32)
}

/// What a message about a sample count `samples` that is not a perfect square from 1 to `max`
/// adds after the count: the counts nearest to it that are, as " (the nearest are 4 and 9)".
/// `samples` may be any integer a user typed (negative, beyond `u32`).
pub fn nearest_squares(samples: i64, max: u32) -> String {
    if samples < 1 {
        return " (the smallest is 1)".to_owned();
    }
    if samples > max as i64 {
        return format!(" (the largest is {max})");
    }
    let below = (samples as f64).sqrt().floor() as i64;
    let (low, high) = (below * below, (below + 1) * (below + 1));
    match high <= max as i64 {
        true => format!(" (the nearest are {low} and {high})"),
        false => format!(" (the nearest is {low})"),
    }
}

/// Offset of grid cell `(k, l)` of `n × n` from the pixel center, in `[-½, ½)²`.
pub fn grid_offset(n: u32, k: u32, l: u32) -> Vec2 {
    jittered_offset(n, k, l, Vec2::splat(0.5))
}

/// The fixed offsets of a deterministic sampler (`center`, `grid`, `rgss`) for `n × n`
/// samples, in the order k-major (sample `k·n + l` is cell `(k, l)`). `None` for `jittered`,
/// whose offsets depend on the pixel.
pub fn fixed_offsets(sampler: Sampler, n: u32) -> Option<Vec<Vec2>> {
    let cells = (0..n).flat_map(|k| (0..n).map(move |l| grid_offset(n, k, l)));
    match sampler {
        Sampler::Center => Some(vec![Vec2::ZERO; (n * n) as usize]),
        Sampler::Grid => Some(cells.collect()),
        Sampler::Rgss => {
            // θ = arctan(1/2): cos θ = 2/√5, sin θ = 1/√5.
            let (sin, cos) = (1.0 / 5f32.sqrt(), 2.0 / 5f32.sqrt());
            Some(
                cells
                    .map(|d| Vec2::new(d.x * cos - d.y * sin, d.x * sin + d.y * cos))
                    .map(|d| Vec2::new(wrap_half(d.x), wrap_half(d.y)))
                    .collect(),
            )
        }
        Sampler::Jittered => None,
    }
}

/// Wraps a coordinate into `[-½, ½)` by adding or subtracting 1.
fn wrap_half(x: f32) -> f32 {
    if x >= 0.5 {
        x - 1.0
    } else if x < -0.5 {
        x + 1.0
    } else {
        x
    }
}

/// Offset of jittered sample `(k, l)` of `n × n` given a uniform point `xi` in `[0, 1)²`.
pub fn jittered_offset(n: u32, k: u32, l: u32, xi: Vec2) -> Vec2 {
    let n = n as f32;
    Vec2::new((k as f32 + xi.x) / n - 0.5, (l as f32 + xi.y) / n - 0.5)
}

/// A small counter-based generator (SplitMix64, Steele et al. 2014) whose stream is chosen by
/// hashing the seed with the caller's counters: the same (seed, pixel, sample, …) always gives
/// the same numbers, whatever thread asks.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
}

fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl Rng {
    /// The stream for `seed` and the given counters (for example pixel index and sample).
    pub fn new(seed: u64, counters: &[u64]) -> Self {
        let state = counters
            .iter()
            .fold(mix(seed ^ 0x9e37_79b9_7f4a_7c15), |h, &c| {
                mix(h ^ c.wrapping_add(0x632b_e59b_d9b4_e019))
            });
        Self { state }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        mix(self.state)
    }

    /// A uniform float in `[0, 1)`.
    pub fn uniform(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    /// A uniform point in `[0, 1)²`.
    pub fn uniform2(&mut self) -> Vec2 {
        let x = self.uniform();
        Vec2::new(x, self.uniform())
    }
}

/// Shirley and Chiu's concentric map of `u` in [0, 1)² onto the unit disk: area-preserving,
/// with (½, ½) at the centre.
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o == Vec2::ZERO {
        return Vec2::ZERO;
    }
    let quarter = std::f32::consts::FRAC_PI_4;
    let (r, theta) = match o.x.abs() > o.y.abs() {
        true => (o.x, quarter * (o.y / o.x)),
        false => (o.y, 2.0 * quarter - quarter * (o.x / o.y)),
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampler_names_round_trip() {
        for s in Sampler::ALL {
            assert_eq!(s.name().parse::<Sampler>(), Ok(s));
            // The scene file's reader (serde) knows each by the same name.
            let quoted = format!("\"{}\"", s.name());
            assert_eq!(serde_json::from_str::<Sampler>(&quoted).unwrap(), s);
        }
        // Names are exact: no other case, no spaces.
        for bad in ["Rgss", " grid", "", "random"] {
            let e = bad.parse::<Sampler>().unwrap_err();
            assert_eq!(e.name, bad);
            assert_eq!(e.known, ["center", "grid", "rgss", "jittered"]);
        }
    }

    #[test]
    fn rgss_4_matches_the_spec() {
        let o = fixed_offsets(Sampler::Rgss, 2).unwrap();
        let expected = [
            (0.1118, 0.3354),
            (-0.3354, 0.1118),
            (-0.1118, -0.3354),
            (0.3354, -0.1118),
        ];
        let mut got: Vec<_> = o.iter().map(|v| (v.x, v.y)).collect();
        for e in expected {
            let i = got
                .iter()
                .position(|g| (g.0 - e.0).abs() < 1e-4 && (g.1 - e.1).abs() < 1e-4)
                .unwrap_or_else(|| panic!("{e:?} not in {o:?}"));
            got.remove(i);
        }
    }

    #[test]
    fn rgss_stays_in_the_pixel_and_4_samples_cover_4_columns_and_rows() {
        for n in 1..=6 {
            let o = fixed_offsets(Sampler::Rgss, n).unwrap();
            assert_eq!(o.len() as u32, n * n);
            for a in &o {
                assert!(a.x >= -0.5 && a.x < 0.5 && a.y >= -0.5 && a.y < 0.5);
            }
        }
        // The point of the rotation: with 4 samples, no two share a column or a row.
        let o = fixed_offsets(Sampler::Rgss, 2).unwrap();
        for (i, a) in o.iter().enumerate() {
            for b in &o[i + 1..] {
                assert!((a.x - b.x).abs() > 0.2 && (a.y - b.y).abs() > 0.2);
            }
        }
    }

    #[test]
    fn grid_puts_one_sample_in_each_cell() {
        let n = 3;
        let o = fixed_offsets(Sampler::Grid, n).unwrap();
        let mut cells = [0; 9];
        for v in o {
            let cx = ((v.x + 0.5) * 3.0).floor() as usize;
            let cy = ((v.y + 0.5) * 3.0).floor() as usize;
            cells[cy * 3 + cx] += 1;
            // At the cell's center.
            assert!((((v.x + 0.5) * 3.0).fract() - 0.5).abs() < 1e-6);
        }
        assert!(cells.iter().all(|&c| c == 1));
    }

    #[test]
    fn jittered_samples_are_stratified_and_repeatable() {
        let n = 4;
        let mut cells = [0; 16];
        for k in 0..n {
            for l in 0..n {
                let mut rng = Rng::new(7, &[42, (k * n + l) as u64]);
                let xi = rng.uniform2();
                assert_eq!(xi, Rng::new(7, &[42, (k * n + l) as u64]).uniform2());
                let v = jittered_offset(n, k, l, xi);
                let cx = ((v.x + 0.5) * 4.0).floor() as u32;
                let cy = ((v.y + 0.5) * 4.0).floor() as u32;
                assert_eq!((cx, cy), (k, l));
                cells[(cy * 4 + cx) as usize] += 1;
            }
        }
        assert!(cells.iter().all(|&c| c == 1));
    }

    #[test]
    fn rng_is_uniform_enough_and_seed_dependent() {
        let mut rng = Rng::new(1, &[2, 3]);
        let mean = (0..10_000).map(|_| rng.uniform()).sum::<f32>() / 10_000.0;
        assert!((mean - 0.5).abs() < 0.02);
        assert_ne!(Rng::new(1, &[2]).next_u64(), Rng::new(2, &[2]).next_u64());
        assert_ne!(
            Rng::new(1, &[2, 3]).next_u64(),
            Rng::new(1, &[3, 2]).next_u64()
        );
    }

    #[test]
    fn a_count_that_is_no_square_is_told_its_neighbours() {
        assert_eq!(nearest_squares(5, 65536), " (the nearest are 4 and 9)");
        assert_eq!(nearest_squares(2, 65536), " (the nearest are 1 and 4)");
        assert_eq!(
            nearest_squares(65535, 65536),
            " (the nearest are 65025 and 65536)"
        );
        assert_eq!(nearest_squares(0, 65536), " (the smallest is 1)");
        assert_eq!(nearest_squares(-3, 65536), " (the smallest is 1)");
        assert_eq!(nearest_squares(70000, 65536), " (the largest is 65536)");
        assert_eq!(nearest_squares(10, 12), " (the nearest is 9)");
    }

    #[test]
    fn perfect_squares() {
        assert_eq!(perfect_square_root(1), Some(1));
        assert_eq!(perfect_square_root(16), Some(4));
        assert_eq!(perfect_square_root(15), None);
        assert_eq!(perfect_square_root(0), None);
        assert_eq!(perfect_square_root(u32::MAX), None);
    }
}
