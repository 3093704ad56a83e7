//! A [`Camera`] on a film: film points become rays, by the camera's lens model
//! (docs/scene-format.md, "Camera models").
//!
//! Every model but the field of view's pinhole works in double precision in OpenCV's camera
//! axes (x right, y down, z forward) and turns to the world at the end, so that a hit projects
//! back through the model onto its film point.

use glam::{DVec2, DVec3, Vec2, Vec3};

use super::grid::Guesses;
use super::{Aperture, Camera, Lens};
use crate::math::Ray;
use crate::sampling::concentric_disk;

/// A [`Camera`] projected onto a film of `width × height` pixels: turns film points into rays.
#[derive(Clone, Debug, PartialEq)]
pub struct FilmCamera {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    /// forward, right and up in double precision, for [`FilmCamera::in_world`].
    basis: [DVec3; 3],
    /// tan(fov_y / 2).
    half_height: f32,
    aspect: f32,
    width: f32,
    height: f32,
    /// K⁻¹ on this film as `(1/fx, 1/fy, cx + ½, cy + ½, skew)` (film points, whose pixel
    /// centres lie at +½): a given K, or for a distorted lens or an aperture without K the
    /// pinhole K of the field of view. `None` for the plain fov pinhole and the models
    /// without K (panorama, orthographic).
    k: Option<[f64; 5]>,
    lens: Lens,
    aperture: Option<Aperture>,
    /// OpenCV's model's first guesses on this film.
    guesses: Option<Guesses>,
}

impl FilmCamera {
    /// `camera` on a film of `width × height` pixels (both at least 1).
    pub fn new(camera: &Camera, width: u32, height: u32) -> Self {
        let (forward, right, up) = camera.basis();
        let half_height = (0.5 * camera.fov_y_deg().to_radians()).tan();
        let k = match (camera.intrinsics(), camera.lens()) {
            (Some(k), _) => {
                let k = k.on_film(width, height);
                Some([1.0 / k.fx, 1.0 / k.fy, k.cx + 0.5, k.cy + 0.5, k.skew])
            }
            // Every perspective camera but the plain fov pinhole works through K.
            (None, Lens::Pinhole) if camera.aperture().is_none() => None,
            (None, Lens::Pinhole | Lens::OpenCv(_) | Lens::Fisheye(_)) => {
                let f = 0.5 * f64::from(height) / f64::from(half_height);
                let (w, h) = (f64::from(width), f64::from(height));
                Some([1.0 / f, 1.0 / f, 0.5 * w, 0.5 * h, 0.0])
            }
            (None, _) => None,
        };
        let guesses = match (camera.lens(), k) {
            (Lens::OpenCv(d), Some(k)) => {
                let film = (width as f32, height as f32);
                Some(Guesses::new(&d, film, |x, y| unproject(k, x, y)))
            }
            _ => None,
        };
        Self {
            eye: camera.position(),
            forward,
            right,
            up,
            basis: [forward, right, up].map(|v| v.as_dvec3()),
            half_height,
            aspect: width as f32 / height as f32,
            width: width as f32,
            height: height as f32,
            k,
            lens: camera.lens(),
            aperture: camera.aperture(),
            guesses,
        }
    }

    /// The camera's position: where every ray starts unless [`FilmCamera::shares_origin`] is
    /// false.
    pub fn eye(&self) -> Vec3 {
        self.eye
    }

    /// The unit direction the camera looks in (toward `look_at`).
    pub fn forward(&self) -> Vec3 {
        self.forward
    }

    /// True when every ray starts at [`FilmCamera::eye`]: not orthographic, no aperture.
    pub fn shares_origin(&self) -> bool {
        self.aperture.is_none() && !matches!(self.lens, Lens::Orthographic { .. })
    }

    /// True when rays go through the lens's aperture ([`FilmCamera::sample_ray`] reads its
    /// lens sample).
    pub fn has_aperture(&self) -> bool {
        self.aperture.is_some()
    }

    /// True for the pinhole, whose every film point has a ray from the eye
    /// ([`FilmCamera::extend_directions`]).
    pub fn is_pinhole(&self) -> bool {
        matches!(self.lens, Lens::Pinhole) && self.aperture.is_none()
    }

    /// The ray through film point `(x, y)` from the lens's centre: x in `[0, width)` from the
    /// left edge, y in `[0, height)` from the top edge, a unit direction. `None` where the
    /// lens model sees nothing (beyond a distortion's valid radius or a fisheye's
    /// `max_angle`).
    pub fn ray(&self, x: f32, y: f32) -> Option<Ray> {
        self.sample_ray(x, y, Vec2::splat(0.5))
    }

    /// [`FilmCamera::ray`] through the point of the aperture that the lens sample `lens` (in
    /// [0, 1)²) picks (the aperture's centre for (½, ½), and for a camera without one).
    pub fn sample_ray(&self, x: f32, y: f32, lens: Vec2) -> Option<Ray> {
        if self.k.is_none() && self.is_pinhole() {
            return Some(Ray::new(self.eye, self.through_fov(x, y)));
        }
        // A ray out of f32's range (an orthographic plane or an aperture of 10³⁸) sees nothing.
        self.model_ray(x, y, lens)
            .filter(|r| r.origin.is_finite() && r.direction.is_finite())
    }

    /// [`FilmCamera::sample_ray`] by the lens model.
    fn model_ray(&self, x: f32, y: f32, lens: Vec2) -> Option<Ray> {
        if let Lens::Orthographic { height } = self.lens {
            let half = 0.5 * height;
            let sx = (2.0 * x / self.width - 1.0) * self.aspect * half;
            let sy = (1.0 - 2.0 * y / self.height) * half;
            let origin = self.eye + sx * self.right + sy * self.up;
            return Some(Ray::new(origin, self.forward));
        }
        let c = self.camera_direction(x, y)?;
        let Some(a) = self.aperture.filter(|_| c.z > 0.0) else {
            return Some(Ray::new(self.eye, self.in_world(c).normalize().as_vec3()));
        };
        // pbrt's thin lens: the ray from a point of the aperture through the point that the
        // centre's ray meets on the plane in focus.
        let on_lens = concentric_disk(lens).as_dvec2() * f64::from(a.radius);
        let lens_point = DVec3::new(on_lens.x, on_lens.y, 0.0);
        let focus = c * (f64::from(a.focus_distance) / c.z);
        let origin = self.eye.as_dvec3() + self.in_world(lens_point);
        let dir = self.in_world(focus - lens_point).normalize();
        Some(Ray::new(origin.as_vec3(), dir.as_vec3()))
    }

    /// The unit directions of film points `points` from the eye, appended to `out`, for a
    /// pinhole ([`FilmCamera::is_pinhole`]; other cameras, [`FilmCamera::sample_ray`]). The
    /// camera's kind is decided once, so that the loop of a camera without K stays plain
    /// arithmetic and vectorizes.
    #[inline(always)]
    pub fn extend_directions(&self, points: &[(f32, f32)], out: &mut Vec<Vec3>) {
        debug_assert!(self.is_pinhole());
        match self.k {
            Some(k) => out.extend(points.iter().map(|&(x, y)| self.through_k(k, x, y))),
            None => out.extend(points.iter().map(|&(x, y)| self.through_fov(x, y))),
        }
    }

    /// The field of view's pinhole direction.
    #[inline(always)]
    fn through_fov(&self, x: f32, y: f32) -> Vec3 {
        let sx = (2.0 * x / self.width - 1.0) * self.aspect * self.half_height;
        let sy = (1.0 - 2.0 * y / self.height) * self.half_height;
        let dir = self.forward + sx * self.right + sy * self.up;
        dir.normalize()
    }

    /// The direction through K: the camera-space point `K⁻¹·(x − ½, y − ½, 1)` (OpenCV's
    /// pixel coordinates), out of line so that the field of view's loop compiles as it did
    /// before K.
    #[inline(never)]
    fn through_k(&self, k: [f64; 5], x: f32, y: f32) -> Vec3 {
        let p = unproject(k, x, y);
        self.in_world(DVec3::new(p.x, p.y, 1.0))
            .normalize()
            .as_vec3()
    }

    /// The camera-space direction (OpenCV axes, not unit) seen at film point (x, y) by a
    /// model that works in them; `None` where the model sees nothing.
    fn camera_direction(&self, x: f32, y: f32) -> Option<DVec3> {
        let k = self.k.unwrap_or_default();
        match self.lens {
            Lens::Pinhole => {
                let p = unproject(k, x, y);
                Some(DVec3::new(p.x, p.y, 1.0))
            }
            Lens::OpenCv(d) => {
                let q = unproject(k, x, y);
                let guess = self.guesses.as_ref().and_then(|g| g.at(x, y));
                let p = d.undistort_from(q, guess.unwrap_or(q))?;
                Some(DVec3::new(p.x, p.y, 1.0))
            }
            Lens::Fisheye(d) => {
                let q = unproject(k, x, y);
                let radius = q.length();
                let theta = d.theta(radius)?;
                if radius == 0.0 {
                    return Some(DVec3::Z);
                }
                let side = q * (theta.sin() / radius);
                Some(DVec3::new(side.x, side.y, theta.cos()))
            }
            Lens::Equirectangular => {
                let tau = std::f64::consts::TAU;
                let longitude = tau * (f64::from(x) / f64::from(self.width) - 0.5);
                let latitude = 0.5 * tau * (0.5 - f64::from(y) / f64::from(self.height));
                let (sin_lat, cos_lat) = latitude.sin_cos();
                let (sin_lon, cos_lon) = longitude.sin_cos();
                Some(DVec3::new(cos_lat * sin_lon, -sin_lat, cos_lat * cos_lon))
            }
            Lens::Orthographic { .. } => Some(DVec3::Z),
        }
    }

    /// A camera-space vector (OpenCV axes) in the world, in double precision.
    fn in_world(&self, c: DVec3) -> DVec3 {
        let [f, r, u] = self.basis;
        f * c.z + r * c.x - u * c.y
    }
}

/// `K⁻¹·(x − ½, y − ½, 1)`'s first two coordinates, with `k` as [`FilmCamera`] holds it.
fn unproject([ifx, ify, cx, cy, skew]: [f64; 5], x: f32, y: f32) -> DVec2 {
    let down = (f64::from(y) - cy) * ify;
    let right = (f64::from(x) - cx - skew * down) * ifx;
    DVec2::new(right, down)
}
