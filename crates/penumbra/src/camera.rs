//! The pinhole camera of SPEC §3: a film point becomes a ray from the eye.

use glam::Vec3;

use crate::math::Ray;

/// A pinhole camera for a film of `width × height` pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PinholeCamera {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    /// tan(fov_y / 2).
    half_height: f32,
    aspect: f32,
    width: f32,
    height: f32,
}

/// Why a camera cannot be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraError {
    /// `look_at` equals `position`, or the view direction is parallel to `up`.
    Degenerate,
    /// The field of view is not inside (0, 180) degrees.
    FovOutOfRange,
    /// Width or height is below one pixel.
    EmptyFilm,
}

impl PinholeCamera {
    /// A camera at `eye` looking at `look_at`, with `up` giving the vertical and `fov_y_deg`
    /// the vertical field of view, for a film of `width × height` pixels.
    pub fn new(
        eye: Vec3,
        look_at: Vec3,
        up: Vec3,
        fov_y_deg: f32,
        width: u32,
        height: u32,
    ) -> Result<Self, CameraError> {
        if !(fov_y_deg > 0.0 && fov_y_deg < 180.0) {
            return Err(CameraError::FovOutOfRange);
        }
        if width < 1 || height < 1 {
            return Err(CameraError::EmptyFilm);
        }
        let forward = (look_at - eye).normalize_or_zero();
        let right = forward.cross(up).normalize_or_zero();
        if forward == Vec3::ZERO || right == Vec3::ZERO || !right.is_finite() {
            return Err(CameraError::Degenerate);
        }
        Ok(Self {
            eye,
            forward,
            right,
            up: right.cross(forward),
            half_height: (0.5 * fov_y_deg.to_radians()).tan(),
            aspect: width as f32 / height as f32,
            width: width as f32,
            height: height as f32,
        })
    }

    /// The ray through film point `(x, y)`: x in `[0, width)` from the left edge, y in
    /// `[0, height)` from the top edge. The direction is normalized.
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let sx = (2.0 * x / self.width - 1.0) * self.aspect * self.half_height;
        let sy = (1.0 - 2.0 * y / self.height) * self.half_height;
        let dir = self.forward + sx * self.right + sy * self.up;
        Ray::new(self.eye, dir.normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(w: u32, h: u32) -> PinholeCamera {
        PinholeCamera::new(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 90.0, w, h).unwrap()
    }

    #[test]
    fn film_center_looks_at_the_target() {
        let r = cam(200, 100).ray(100.0, 50.0);
        assert!((r.direction - -Vec3::Z).length() < 1e-6);
        assert_eq!(r.origin, Vec3::new(0.0, 0.0, 5.0));
    }

    #[test]
    fn corners_match_the_vertical_fov_and_aspect() {
        // fov 90: tan(45°) = 1, so the top edge center is 45° up and, with aspect 2, the right
        // edge center is atan(2) to the right.
        let c = cam(200, 100);
        let top = c.ray(100.0, 0.0).direction;
        assert!((top - Vec3::new(0.0, 1.0, -1.0).normalize()).length() < 1e-6);
        let right = c.ray(200.0, 50.0).direction;
        assert!((right - Vec3::new(2.0, 0.0, -1.0).normalize()).length() < 1e-6);
        // Top-left corner: +y is up, x grows to the right.
        let tl = c.ray(0.0, 0.0).direction;
        assert!((tl - Vec3::new(-2.0, 1.0, -1.0).normalize()).length() < 1e-6);
    }

    #[test]
    fn rejects_bad_cameras() {
        let new =
            |at: Vec3, up: Vec3, fov: f32| PinholeCamera::new(Vec3::ZERO, at, up, fov, 10, 10);
        assert_eq!(new(Vec3::Y, Vec3::Y, 45.0), Err(CameraError::Degenerate));
        assert_eq!(new(Vec3::ZERO, Vec3::Y, 45.0), Err(CameraError::Degenerate));
        assert_eq!(new(Vec3::Z, Vec3::Y, 0.0), Err(CameraError::FovOutOfRange));
        assert_eq!(
            new(Vec3::Z, Vec3::Y, 180.0),
            Err(CameraError::FovOutOfRange)
        );
        assert!(PinholeCamera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 45.0, 0, 10).is_err());
    }
}
