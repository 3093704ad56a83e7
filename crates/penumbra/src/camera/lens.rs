//! Lens distortion as OpenCV models it, forward (what `cv2.projectPoints` and
//! `cv2.fisheye.projectPoints` compute) and inverted numerically, in double precision: a
//! camera ray leaves through the undistorted point whose distortion is the film point.
//!
//! Both work on normalized image coordinates: (X/Z, Y/Z) of a camera-space point in OpenCV's
//! axes (x right, y down, z forward), before K.

use glam::DVec2;

/// How close a distorted point must come to its target, in normalized image coordinates
/// (at a focal length of 10⁴ pixels, 10⁻¹⁰ px).
const CONVERGED: f64 = 1e-14;
/// A Newton step this short (in normalized coordinates) is the last: the error it leaves is
/// of the order of its square.
const TINY_STEP: f64 = 1e-9;
/// Newton steps before an inversion gives up.
const MAX_STEPS: usize = 60;
/// How far out (in normalized radius, 89.4° off the axis) the radial-tangential model's
/// valid radius is looked for.
const SEARCH_RADIUS: f64 = 100.0;
/// Steps of that search (each bisected where the model folds).
const SEARCH_STEPS: usize = 20_000;

/// OpenCV's radial-tangential model with thin-prism terms (`cv2.projectPoints`'
/// `distCoeffs`, in its order): k1 k2 p1 p2 k3 k4 k5 k6 s1 s2 s3 s4, missing ones 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OpenCvDistortion {
    /// The coefficients, in OpenCV's order.
    pub coefficients: [f64; 12],
    /// How many were given (4, 5, 8 or 12).
    given: usize,
    /// Whether the radial factor has a denominator (k4, k5 or k6 not 0): without one,
    /// [`OpenCvDistortion::radial`] skips its division, giving the same bits.
    rational: bool,
    /// The radius (in normalized undistorted coordinates) where the model stops being
    /// invertible: its radial part stops growing or its denominator reaches 0. Infinite when
    /// it never does within 89.4° of the axis.
    valid_radius: f64,
}

/// Why a distortion cannot be used.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DistortionError {
    /// Not 4, 5, 8 or 12 coefficients for OpenCV's model, or not 4 for the fisheye.
    Count(usize),
    /// A coefficient that is NaN or infinite (or a fisheye whose θ_d overflows).
    NotFinite,
    /// A fisheye `max_angle` outside (0, 180) degrees.
    MaxAngle(f64),
    /// The fisheye's coefficients fold (θ_d stops growing) at this angle in degrees, before
    /// `max_angle`.
    Folds(f64),
}

impl std::fmt::Display for DistortionError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DistortionError::Count(n) => write!(
                f,
                "{n} distortion coefficients: OpenCV's model takes 4, 5, 8 or 12 \
                 (k1 k2 p1 p2 [k3 [k4 k5 k6 [s1 s2 s3 s4]]]), the fisheye 4 (k1 k2 k3 k4)"
            ),
            DistortionError::NotFinite => f.write_str("distortion coefficients must be finite"),
            DistortionError::MaxAngle(a) => {
                write!(f, "max_angle must be between 0 and 180 degrees, not {a}")
            }
            DistortionError::Folds(a) => write!(
                f,
                "the fisheye coefficients stop growing at {a:.2}° off the axis: max_angle \
                 must be below it"
            ),
        }
    }
}

impl std::error::Error for DistortionError {}

impl OpenCvDistortion {
    /// The model of `coefficients` (4, 5, 8 or 12 of them, in OpenCV's order).
    pub fn new(coefficients: &[f64]) -> Result<OpenCvDistortion, DistortionError> {
        if ![4, 5, 8, 12].contains(&coefficients.len()) {
            return Err(DistortionError::Count(coefficients.len()));
        }
        if !coefficients.iter().all(|c| c.is_finite()) {
            return Err(DistortionError::NotFinite);
        }
        let mut all = [0.0; 12];
        all[..coefficients.len()].copy_from_slice(coefficients);
        let mut model = OpenCvDistortion {
            coefficients: all,
            given: coefficients.len(),
            rational: all[5..8].iter().any(|&k| k != 0.0),
            valid_radius: f64::INFINITY,
        };
        model.valid_radius = model.find_valid_radius();
        Ok(model)
    }

    /// The coefficients as given, in OpenCV's order.
    pub fn given(&self) -> &[f64] {
        &self.coefficients[..self.given]
    }

    /// The radius in normalized undistorted coordinates within which rays are traced (see the
    /// field); `f64::INFINITY` when the model never folds.
    pub fn valid_radius(&self) -> f64 {
        self.valid_radius
    }

    /// The radial factor (1 + k1 r² + k2 r⁴ + k3 r⁶) / (1 + k4 r² + k5 r⁴ + k6 r⁶) and its
    /// derivative by r², and the denominator.
    fn radial(&self, r2: f64) -> (f64, f64, f64) {
        let [k1, k2, _, _, k3, k4, k5, k6, ..] = self.coefficients;
        let n = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
        let dn = k1 + r2 * (2.0 * k2 + r2 * 3.0 * k3);
        if !self.rational {
            // d = 1 and d′ = 0 exactly: R = n and R′ = n′ to the bit, without a division.
            return (n, dn, 1.0);
        }
        let d = 1.0 + r2 * (k4 + r2 * (k5 + r2 * k6));
        let dd = k4 + r2 * (2.0 * k5 + r2 * 3.0 * k6);
        // One division: R = n/d and R′ = (n′ − R·d′)/d.
        let inv = 1.0 / d;
        let f = n * inv;
        (f, (dn - f * dd) * inv, d)
    }

    /// The first radius where the radial part r·R(r²) stops growing or R's denominator
    /// reaches 0, scanned and then bisected; infinite when there is none within
    /// [`SEARCH_RADIUS`].
    fn find_valid_radius(&self) -> f64 {
        // Along a radius, d(r·R)/dr = R + 2r²·R′; the denominator is checked with it.
        let good = |r: f64| {
            let (f, df, d) = self.radial(r * r);
            d > 0.0 && f + 2.0 * r * r * df > 0.0
        };
        let step = SEARCH_RADIUS / SEARCH_STEPS as f64;
        let Some(i) = (1..=SEARCH_STEPS).find(|&i| !good(i as f64 * step)) else {
            return f64::INFINITY;
        };
        let (mut lo, mut hi) = ((i - 1) as f64 * step, i as f64 * step);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if good(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    }

    /// The distorted point of the undistorted `p`, as `cv2.projectPoints` computes it, and
    /// the Jacobian of the map at `p` by columns (∂/∂x, ∂/∂y).
    pub fn distort(&self, p: DVec2) -> (DVec2, [DVec2; 2]) {
        let [_, _, p1, p2, _, _, _, _, s1, s2, s3, s4] = self.coefficients;
        let (x, y) = (p.x, p.y);
        let r2 = x * x + y * y;
        let (f, df, _) = self.radial(r2);
        let (sx, sy) = (s1 + 2.0 * s2 * r2, s3 + 2.0 * s4 * r2);
        let out = DVec2::new(
            x * f + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x) + r2 * (s1 + s2 * r2),
            y * f + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y + r2 * (s3 + s4 * r2),
        );
        let by_x = DVec2::new(
            f + 2.0 * x * x * df + 2.0 * p1 * y + 6.0 * p2 * x + 2.0 * x * sx,
            2.0 * x * y * df + 2.0 * p1 * x + 2.0 * p2 * y + 2.0 * x * sy,
        );
        let by_y = DVec2::new(
            2.0 * x * y * df + 2.0 * p1 * x + 2.0 * p2 * y + 2.0 * y * sx,
            f + 2.0 * y * y * df + 6.0 * p1 * y + 2.0 * p2 * x + 2.0 * y * sy,
        );
        (out, [by_x, by_y])
    }

    /// The undistorted point whose distortion is `target`, by Newton's method from `target`;
    /// `None` where there is none inside the valid radius (the sample misses).
    pub fn undistort(&self, target: DVec2) -> Option<DVec2> {
        self.undistort_from(target, target)
    }

    /// [`OpenCvDistortion::undistort`] from the first guess `guess`: the closer, the fewer
    /// steps. It stops when the distortion meets `target` to [`CONVERGED`], or after a step
    /// shorter than [`TINY_STEP`], which it takes (Newton's error after a step is of the
    /// order of the step squared).
    pub fn undistort_from(&self, target: DVec2, guess: DVec2) -> Option<DVec2> {
        // Squared lengths throughout: no square root per step.
        let scale2 = target.length_squared().max(1.0);
        let (converged2, tiny2) = (
            CONVERGED * CONVERGED * scale2,
            TINY_STEP * TINY_STEP * scale2,
        );
        let mut p = guess;
        for _ in 0..MAX_STEPS {
            let (at, [jx, jy]) = self.distort(p);
            let e = at - target;
            let det = jx.x * jy.y - jy.x * jx.y;
            if det.is_nan() || det <= 0.0 {
                return None;
            }
            if e.length_squared() <= converged2 {
                return self.inside(p);
            }
            // p −= J⁻¹·e.
            let step = DVec2::new(jy.y * e.x - jy.x * e.y, jx.x * e.y - jx.y * e.x) / det;
            p -= step;
            if !p.is_finite() {
                return None;
            }
            if step.length_squared() <= tiny2 {
                return self.inside(p);
            }
        }
        None
    }

    /// `p`, when it lies inside the valid radius.
    fn inside(&self, p: DVec2) -> Option<DVec2> {
        (p.length_squared() <= self.valid_radius * self.valid_radius).then_some(p)
    }
}

/// OpenCV's fisheye (Kannala–Brandt) model, as `cv2.fisheye.projectPoints` takes it: a ray θ
/// off the axis lands at radius θ_d = θ(1 + k1θ² + k2θ⁴ + k3θ⁶ + k4θ⁸) of the normalized
/// image, in the ray's azimuth; rays beyond `max_angle` are not seen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FisheyeDistortion {
    /// k1 k2 k3 k4.
    pub coefficients: [f64; 4],
    /// The widest angle seen off the axis, in radians.
    max_angle: f64,
    /// θ_d at `max_angle`.
    max_radius: f64,
}

impl FisheyeDistortion {
    /// The model of `coefficients` (k1 k2 k3 k4), seeing up to `max_angle_deg` off the axis:
    /// θ_d must grow all the way there.
    pub fn new(
        coefficients: &[f64],
        max_angle_deg: f64,
    ) -> Result<FisheyeDistortion, DistortionError> {
        let &[k1, k2, k3, k4] = coefficients else {
            return Err(DistortionError::Count(coefficients.len()));
        };
        if !coefficients.iter().all(|c| c.is_finite()) {
            return Err(DistortionError::NotFinite);
        }
        if !(max_angle_deg > 0.0 && max_angle_deg < 180.0) {
            return Err(DistortionError::MaxAngle(max_angle_deg));
        }
        let mut model = FisheyeDistortion {
            coefficients: [k1, k2, k3, k4],
            max_angle: max_angle_deg.to_radians(),
            max_radius: 0.0,
        };
        // The derivative at fine steps up to max_angle, and at max_angle itself.
        let steps = 4096;
        let fold = (1..=steps)
            .map(|i| model.max_angle * i as f64 / steps as f64)
            .find(|&theta| {
                let slope = model.theta_d(theta).1;
                slope.is_nan() || slope <= 0.0
            });
        if let Some(theta) = fold {
            return Err(DistortionError::Folds(theta.to_degrees()));
        }
        model.max_radius = model.theta_d(model.max_angle).0;
        if !model.max_radius.is_finite() {
            return Err(DistortionError::NotFinite);
        }
        Ok(model)
    }

    /// The widest angle seen off the axis, in degrees.
    pub fn max_angle_deg(&self) -> f64 {
        self.max_angle.to_degrees()
    }

    /// θ_d of θ and its derivative by θ.
    pub fn theta_d(&self, theta: f64) -> (f64, f64) {
        let [k1, k2, k3, k4] = self.coefficients;
        let t2 = theta * theta;
        let poly = 1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4)));
        let dpoly = 1.0 + t2 * (3.0 * k1 + t2 * (5.0 * k2 + t2 * (7.0 * k3 + t2 * 9.0 * k4)));
        (theta * poly, dpoly)
    }

    /// The angle off the axis whose θ_d is `radius`; `None` beyond `max_angle` (or, never
    /// seen, where the search does not converge). Newton's method kept inside a shrinking
    /// bracket (θ_d grows on [0, max_angle]).
    pub fn theta(&self, radius: f64) -> Option<f64> {
        if radius.is_nan() || radius > self.max_radius {
            return None;
        }
        let (mut lo, mut hi) = (0.0, self.max_angle);
        let mut theta = radius.min(hi);
        for _ in 0..MAX_STEPS {
            let (at, slope) = self.theta_d(theta);
            let e = at - radius;
            if e.abs() <= CONVERGED * radius.max(1.0) {
                return Some(theta);
            }
            if e > 0.0 {
                hi = theta;
            } else {
                lo = theta;
            }
            let next = theta - e / slope;
            theta = if next > lo && next < hi {
                next
            } else {
                0.5 * (lo + hi)
            };
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The example: strong barrel distortion.
    const BARREL: [f64; 5] = [-0.28, 0.07, 0.0002, -0.0001, 0.0];

    #[test]
    fn counts_and_values_are_checked() {
        for n in [0, 3, 6, 7, 9, 13] {
            assert_eq!(
                OpenCvDistortion::new(&vec![0.0; n]),
                Err(DistortionError::Count(n))
            );
        }
        assert!(OpenCvDistortion::new(&[0.0, f64::NAN, 0.0, 0.0]).is_err());
        assert!(FisheyeDistortion::new(&[0.0; 5], 90.0).is_err());
        assert_eq!(
            FisheyeDistortion::new(&[0.0; 4], 180.0),
            Err(DistortionError::MaxAngle(180.0))
        );
        // θ(1 − 0.5θ²) stops growing at θ = √(2/3) rad = 46.8°.
        let e = FisheyeDistortion::new(&[-0.5, 0.0, 0.0, 0.0], 60.0).unwrap_err();
        let DistortionError::Folds(at) = e else {
            panic!("{e:?}")
        };
        assert!(
            (at - (2.0f64 / 3.0).sqrt().to_degrees()).abs() < 0.05,
            "{at}"
        );
        assert!(FisheyeDistortion::new(&[-0.5, 0.0, 0.0, 0.0], 45.0).is_ok());
    }

    #[test]
    fn the_jacobian_is_the_maps_derivative() {
        let all = [
            -0.28, 0.07, 0.002, -0.001, 0.01, 0.02, -0.01, 0.005, 0.001, -0.002, 0.003, 0.0005,
        ];
        let m = OpenCvDistortion::new(&all).unwrap();
        let h = 1e-7;
        for p in [DVec2::new(0.3, -0.2), DVec2::new(-0.6, 0.45), DVec2::ZERO] {
            let (_, [jx, jy]) = m.distort(p);
            let dx = (m.distort(p + DVec2::X * h).0 - m.distort(p - DVec2::X * h).0) / (2.0 * h);
            let dy = (m.distort(p + DVec2::Y * h).0 - m.distort(p - DVec2::Y * h).0) / (2.0 * h);
            assert!(
                (dx - jx).length() < 1e-7 && (dy - jy).length() < 1e-7,
                "{p}"
            );
        }
    }

    #[test]
    fn undistortion_inverts_distortion_inside_the_valid_radius() {
        let m = OpenCvDistortion::new(&BARREL).unwrap();
        // r(1 − 0.28r² + 0.07r⁴) stops growing where 1 − 0.84r² + 0.35r⁴ = 0: it never does
        // (the discriminant is negative), so the model is valid out to the search's end.
        assert!(m.valid_radius() > 1.5, "{}", m.valid_radius());
        for i in 0..=40 {
            for j in 0..=40 {
                let p = DVec2::new(i as f64 / 20.0 - 1.0, j as f64 / 20.0 - 1.0);
                let (d, _) = m.distort(p);
                let back = m.undistort(d).expect("inside the valid radius");
                assert!((back - p).length() < 1e-11, "{p} -> {d} -> {back}");
            }
        }
    }

    #[test]
    fn beyond_the_fold_nothing_is_seen() {
        // r(1 − 0.3r²) peaks at r = 1/√0.9 with ρ = 0.7027; the radial part's fold.
        let m = OpenCvDistortion::new(&[-0.3, 0.0, 0.0, 0.0]).unwrap();
        let fold = 1.0 / 0.9f64.sqrt();
        assert!(
            (m.valid_radius() - fold).abs() < 1e-9,
            "{}",
            m.valid_radius()
        );
        let peak = fold * (1.0 - 0.3 * fold * fold);
        assert!(m.undistort(DVec2::new(peak * 0.999, 0.0)).is_some());
        assert_eq!(m.undistort(DVec2::new(peak * 1.001, 0.0)), None);
        // A pole of the rational part: 1 − r² reaches 0 at r = 1.
        let pole = OpenCvDistortion::new(&[0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0]).unwrap();
        assert!(pole.valid_radius() < 1.0 && pole.valid_radius() > 0.5);
    }

    #[test]
    fn fisheye_angles_invert() {
        let m = FisheyeDistortion::new(&[0.05, -0.01, 0.002, -0.0003], 120.0).unwrap();
        for i in 0..=240 {
            let theta = (i as f64 / 2.0).to_radians();
            let back = m.theta(m.theta_d(theta).0).unwrap();
            assert!((back - theta).abs() < 1e-12, "{theta} -> {back}");
        }
        let edge = m.theta_d(120f64.to_radians()).0;
        assert_eq!(m.theta(edge * 1.0001), None);
        assert_eq!(m.theta(f64::NAN), None);
    }
}
