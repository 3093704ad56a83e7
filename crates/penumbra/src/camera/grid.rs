//! First guesses for inverting OpenCV's distortion on one film: the undistorted points of a
//! grid of film points, every [`SPACING`] pixels, solved once when the camera meets the film;
//! a sample's guess interpolates its cell's four corners. Newton's method from there needs
//! about two steps where it needs five or six from the distorted point itself.
//!
//! The guess only decides where the search starts: every sample is still solved to
//! convergence, and the grid depends only on the camera and the film, so the same film point
//! gives the same ray in any render of any region.

use std::sync::Arc;

use glam::DVec2;

use super::lens::OpenCvDistortion;

/// Pixels between grid points.
const SPACING: f32 = 8.0;

/// The grid of one film.
#[derive(Clone, Debug, PartialEq)]
pub struct Guesses {
    columns: usize,
    rows: usize,
    /// Row by row, the undistorted point of film point (i·SPACING, j·SPACING); NaN where the
    /// model sees nothing.
    points: Arc<[DVec2]>,
}

impl Guesses {
    /// The grid of a `width × height` film, whose film point (x, y) is the distorted point
    /// `unproject(x, y)` of `model`.
    pub fn new(
        model: &OpenCvDistortion,
        (width, height): (f32, f32),
        unproject: impl Fn(f32, f32) -> DVec2,
    ) -> Guesses {
        let columns = (width / SPACING).ceil() as usize + 1;
        let rows = (height / SPACING).ceil() as usize + 1;
        let points = (0..rows)
            .flat_map(|j| (0..columns).map(move |i| (i, j)))
            .map(|(i, j)| {
                let q = unproject(i as f32 * SPACING, j as f32 * SPACING);
                model.undistort(q).unwrap_or(DVec2::NAN)
            })
            .collect();
        Guesses {
            columns,
            rows,
            points,
        }
    }

    /// The interpolated guess for film point (x, y); `None` off the grid or where a corner of
    /// its cell sees nothing.
    pub fn at(&self, x: f32, y: f32) -> Option<DVec2> {
        let (gx, gy) = (f64::from(x / SPACING), f64::from(y / SPACING));
        if !(gx >= 0.0 && gy >= 0.0) {
            return None;
        }
        // Truncation is the floor of these (and no call to libm's floor).
        let (i, j) = (gx as usize, gy as usize);
        if i + 1 >= self.columns || j + 1 >= self.rows {
            return None;
        }
        let (fx, fy) = (gx - i as f64, gy - j as f64);
        let at = |i: usize, j: usize| self.points[j * self.columns + i];
        let top = at(i, j).lerp(at(i + 1, j), fx);
        let bottom = at(i, j + 1).lerp(at(i + 1, j + 1), fx);
        Some(top.lerp(bottom, fy)).filter(|p| p.is_finite())
    }
}
