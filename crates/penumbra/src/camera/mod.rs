//! The camera of SPEC §3 (docs/spec.md): a [`Camera`] is a pose, a field of view or K, and a
//! lens model; paired with a film size it becomes a [`FilmCamera`] that turns film points into
//! rays.

mod film;
mod grid;
mod lens;

use glam::{DVec3, Vec3};

pub use film::FilmCamera;
pub use lens::{DistortionError, FisheyeDistortion, OpenCvDistortion};

use crate::math::{unit, Aabb};

/// Vertical field of view of the framing camera ([`Camera::framing`]), in degrees.
pub const FRAMING_FOV_DEG: f64 = 40.0;
/// Direction from the framed bounds' centre to the framing camera (normalized before use):
/// front-right-above.
const FRAMING_DIR: [f64; 3] = [1.0, 0.8, 1.4];

/// The name under which a render asks for the framing camera ([`Camera::framing`]) of a world
/// that has no camera of that name: `--camera auto`, f3d's and Blender's "frame all".
pub const FRAMING_CAMERA: &str = "auto";

/// Where a pinhole camera stands and what it sees: a checked pose and vertical field of view,
/// independent of any film. A [`World`](crate::World) keeps its cameras in this form; a render
/// pairs one with a film size ([`FilmCamera::new`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    position: Vec3,
    look_at: Vec3,
    up: Vec3,
    fov_y_deg: f32,
    /// A calibrated K in place of the field of view ([`Camera::with_intrinsics`]).
    intrinsics: Option<Intrinsics>,
    /// The lens model ([`Camera::with_lens`]).
    lens: Lens,
    /// A thin lens's aperture, for depth of field ([`Camera::with_aperture`]).
    aperture: Option<Aperture>,
}

/// How a camera maps film points to directions (docs/scene-format.md, "Camera models").
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lens {
    /// The pinhole: the field of view or K.
    Pinhole,
    /// The pinhole's K, then OpenCV's radial-tangential distortion.
    OpenCv(OpenCvDistortion),
    /// K over OpenCV's fisheye (Kannala–Brandt) model.
    Fisheye(FisheyeDistortion),
    /// A 360° × 180° latitude–longitude image around the camera.
    Equirectangular,
    /// Parallel rays along forward from an image plane `height` world units tall, through the
    /// camera's position (the film's centre).
    Orthographic {
        /// The image's height in world units (its width follows the film's aspect).
        height: f32,
    },
}

/// A thin lens's opening, as pbrt's `lensradius` and `focaldistance`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aperture {
    /// The lens's radius in world units, > 0.
    pub radius: f32,
    /// The distance along forward to the plane in focus, > 0.
    pub focus_distance: f32,
}

/// What a camera sees through, apart from where it stands (see [`Camera::optics`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Optics {
    /// K and the vertical field of view it gives.
    intrinsics: Option<(Intrinsics, f32)>,
    lens: Lens,
    aperture: Option<Aperture>,
}

/// A pinhole's intrinsic matrix K as OpenCV writes it, in pixels of a `width × height`
/// image whose pixel centres lie at integer coordinates (docs/spec.md, "Poses and
/// intrinsics"): `[[fx, skew, cx], [0, fy, cy], [0, 0, 1]]`. On a film of another size it is
/// scaled with the film ([`Intrinsics::on_film`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Intrinsics {
    /// The horizontal focal length in pixels, > 0.
    pub fx: f64,
    /// The vertical focal length in pixels, > 0.
    pub fy: f64,
    /// The principal point's column, in pixels (a centred one is (W − 1)/2).
    pub cx: f64,
    /// The principal point's row, in pixels (a centred one is (H − 1)/2).
    pub cy: f64,
    /// The skew term K[0][1] (0 for square-cornered pixels).
    pub skew: f64,
    /// The width of the image K is given for.
    pub width: u32,
    /// The height of the image K is given for.
    pub height: u32,
}

impl Intrinsics {
    /// K on a `width × height` film: each axis scaled by the film's size over K's, about the
    /// image's corner (so a pixel centre stays a pixel centre: c′ + ½ = (c + ½)·s).
    pub fn on_film(&self, width: u32, height: u32) -> Intrinsics {
        if (width, height) == (self.width, self.height) {
            // K as given, every digit (`(c + ½) − ½` need not be c in floating point).
            return *self;
        }
        let sx = f64::from(width) / f64::from(self.width);
        let sy = f64::from(height) / f64::from(self.height);
        Intrinsics {
            fx: self.fx * sx,
            fy: self.fy * sy,
            cx: (self.cx + 0.5) * sx - 0.5,
            cy: (self.cy + 0.5) * sy - 0.5,
            skew: self.skew * sx,
            width,
            height,
        }
    }

    /// K by rows.
    pub fn rows(&self) -> [[f64; 3]; 3] {
        [
            [self.fx, self.skew, self.cx],
            [0.0, self.fy, self.cy],
            [0.0, 0.0, 1.0],
        ]
    }
}

/// Why a camera cannot be made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraError {
    /// `position`, `look_at` or `up` has a NaN or infinite coordinate.
    NotFinite,
    /// `look_at` equals `position`, or the view direction is parallel to `up`.
    Degenerate,
    /// The field of view is not inside (0, 180) degrees.
    FovOutOfRange,
    /// K has a focal length that is not a positive finite number, or an entry not finite.
    BadIntrinsics,
    /// An orthographic height that is not a positive finite number.
    BadHeight,
    /// An aperture radius below 0 or a focus distance not above 0 (or either not finite).
    BadAperture,
    /// An aperture on a lens that has none (a panorama, an orthographic camera).
    NoAperture,
}

impl std::fmt::Display for CameraError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            CameraError::NotFinite => "camera position, look_at and up must be finite numbers",
            CameraError::Degenerate => {
                "degenerate camera: look_at equals position or the view direction is parallel to up"
            }
            CameraError::FovOutOfRange => "fov must be between 0 and 180 degrees",
            CameraError::BadIntrinsics => {
                "K must have finite entries and focal lengths fx and fy greater than 0"
            }
            CameraError::BadHeight => "an orthographic camera's height must be greater than 0",
            CameraError::BadAperture => {
                "aperture_radius must be at least 0 and focus_distance greater than 0"
            }
            CameraError::NoAperture => {
                "only perspective cameras (pinhole, opencv, fisheye) have an aperture"
            }
        })
    }
}

impl std::error::Error for CameraError {}

/// The camera's orthonormal frame: forward, right, up.
fn frame(position: Vec3, look_at: Vec3, up: Vec3) -> Option<(Vec3, Vec3, Vec3)> {
    let mut to_target = look_at - position;
    if !to_target.is_finite() {
        // The difference of two finite points can overflow (3e38 − −3e38); halves cannot.
        to_target = 0.5 * look_at - 0.5 * position;
    }
    let forward = unit(to_target);
    let right = unit(forward.cross(up));
    if forward == Vec3::ZERO || right == Vec3::ZERO || !right.is_finite() {
        return None;
    }
    Some((forward, right, right.cross(forward)))
}

impl Camera {
    /// A camera at `position` looking at `look_at`, with `up` giving the vertical and
    /// `fov_y_deg` the vertical field of view in degrees, inside (0, 180).
    pub fn new(
        position: Vec3,
        look_at: Vec3,
        up: Vec3,
        fov_y_deg: f32,
    ) -> Result<Self, CameraError> {
        if !(fov_y_deg > 0.0 && fov_y_deg < 180.0) {
            return Err(CameraError::FovOutOfRange);
        }
        if !(position.is_finite() && look_at.is_finite() && up.is_finite()) {
            return Err(CameraError::NotFinite);
        }
        frame(position, look_at, up).ok_or(CameraError::Degenerate)?;
        Ok(Self {
            position,
            look_at,
            up,
            fov_y_deg,
            intrinsics: None,
            lens: Lens::Pinhole,
            aperture: None,
        })
    }

    /// This camera seeing through `k` instead of its field of view: rays leave through K's
    /// pixels exactly (see [`FilmCamera::ray`]), and `--poses` writes K as given.
    /// The vertical field of view then reports the one K has through its principal point
    /// (`2·atan((H/2)/fy)`), for what only describes the view.
    pub fn with_intrinsics(self, k: Intrinsics) -> Result<Camera, CameraError> {
        let entries = [k.fx, k.fy, k.cx, k.cy, k.skew];
        let sized = k.width > 0 && k.height > 0;
        if !(entries.iter().all(|v| v.is_finite()) && k.fx > 0.0 && k.fy > 0.0 && sized) {
            return Err(CameraError::BadIntrinsics);
        }
        let fov = (2.0 * (0.5 * f64::from(k.height) / k.fy).atan()).to_degrees() as f32;
        Ok(Camera {
            fov_y_deg: fov,
            intrinsics: Some(k),
            ..self
        })
    }

    /// This camera seeing through `lens`. A distorted lens without K distorts the field of
    /// view's pinhole (a centred K with fx = fy).
    pub fn with_lens(self, lens: Lens) -> Result<Camera, CameraError> {
        if let Lens::Orthographic { height } = lens {
            if !(height > 0.0 && height.is_finite()) {
                return Err(CameraError::BadHeight);
            }
        }
        if self.aperture.is_some() && !lens.has_aperture() {
            return Err(CameraError::NoAperture);
        }
        Ok(Camera { lens, ..self })
    }

    /// This camera with a thin lens of `radius` focused at `focus_distance` along forward
    /// (pbrt's `lensradius` and `focaldistance`). A radius of 0 is the pinhole, exactly.
    pub fn with_aperture(self, radius: f32, focus_distance: f32) -> Result<Camera, CameraError> {
        let finite = radius.is_finite() && focus_distance.is_finite();
        if !(finite && radius >= 0.0 && focus_distance > 0.0) {
            return Err(CameraError::BadAperture);
        }
        if radius > 0.0 && !self.lens.has_aperture() {
            return Err(CameraError::NoAperture);
        }
        let aperture = (radius > 0.0).then_some(Aperture {
            radius,
            focus_distance,
        });
        Ok(Camera { aperture, ..self })
    }

    /// What this camera sees through, apart from where it stands: its K (and the field of view
    /// K gives), lens model and aperture, for [`Camera::with_optics`].
    pub fn optics(&self) -> Optics {
        Optics {
            intrinsics: self.intrinsics.map(|k| (k, self.fov_y_deg)),
            lens: self.lens,
            aperture: self.aperture,
        }
    }

    /// This camera seeing through `optics` (another camera's, checked there): what a camera
    /// path with a lens gives each frame's pinhole.
    pub fn with_optics(self, optics: Optics) -> Camera {
        Camera {
            fov_y_deg: optics.intrinsics.map_or(self.fov_y_deg, |(_, fov)| fov),
            intrinsics: optics.intrinsics.map(|(k, _)| k),
            lens: optics.lens,
            aperture: optics.aperture,
            ..self
        }
    }

    /// True when the camera is all its pose and field of view: a pinhole without K or an
    /// aperture (what a plain `penumbra.Camera(position, look_at, up, fov)` holds, and what a
    /// view from the fov describes).
    pub fn sees_by_fov(&self) -> bool {
        self.intrinsics.is_none() && self.lens == Lens::Pinhole && self.aperture.is_none()
    }

    /// The lens model.
    pub fn lens(&self) -> Lens {
        self.lens
    }

    /// The aperture, for depth of field.
    pub fn aperture(&self) -> Option<Aperture> {
        self.aperture
    }

    /// K, when the camera was given one ([`Camera::with_intrinsics`]).
    pub fn intrinsics(&self) -> Option<Intrinsics> {
        self.intrinsics
    }

    /// The eye position.
    pub fn position(&self) -> Vec3 {
        self.position
    }

    /// The point seen at the film's center.
    pub fn look_at(&self) -> Vec3 {
        self.look_at
    }

    /// The up direction as given (not orthogonalized).
    pub fn up(&self) -> Vec3 {
        self.up
    }

    /// The vertical field of view in degrees.
    pub fn fov_y_deg(&self) -> f32 {
        self.fov_y_deg
    }

    /// The camera that frames `bounds`, the one a bare model file gets: fov
    /// [`FRAMING_FOV_DEG`], up +y, looking at the centre c of the bounding sphere (radius r,
    /// half the diagonal; 1 for bounds of no extent) from c + d·normalize(1, 0.8, 1.4)
    /// (front-right-above), with d = r / sin(fov/2) the distance at which the sphere fills
    /// the vertical field of view. Empty bounds are framed as the unit sphere at the origin;
    /// `None` only where the camera would stand beyond f32's range.
    pub fn framing(bounds: Aabb) -> Option<Camera> {
        let (position, look_at) = framing_view(bounds);
        Camera::new(
            position.as_vec3(),
            look_at.as_vec3(),
            Vec3::Y,
            FRAMING_FOV_DEG as f32,
        )
        .ok()
    }

    /// The camera's orthonormal frame as rays are made from it (SPEC §3): forward
    /// f = normalize(look_at − position), right r = normalize(f × up) and the true up r × f.
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        // `Camera::new` checked the frame, so it exists.
        frame(self.position, self.look_at, self.up).unwrap_or((Vec3::NEG_Z, Vec3::X, Vec3::Y))
    }
}

impl Lens {
    /// The model's name, as the scene's `model` key takes it.
    pub fn name(&self) -> &'static str {
        match self {
            Lens::Pinhole => "pinhole",
            Lens::OpenCv(_) => "opencv",
            Lens::Fisheye(_) => "fisheye",
            Lens::Equirectangular => "equirectangular",
            Lens::Orthographic { .. } => "orthographic",
        }
    }

    /// True for the perspective models, which a thin lens can open.
    pub fn has_aperture(&self) -> bool {
        matches!(self, Lens::Pinhole | Lens::OpenCv(_) | Lens::Fisheye(_))
    }
}

/// The framing camera's (position, look_at) for `bounds`, in double precision (see
/// [`Camera::framing`]). Empty or non-finite bounds are framed as the unit sphere at the
/// origin.
pub(crate) fn framing_view(bounds: Aabb) -> (DVec3, DVec3) {
    let (centre, radius) = bounds.bounding_sphere().unwrap_or((DVec3::ZERO, 1.0));
    let distance = radius / (FRAMING_FOV_DEG.to_radians() / 2.0).sin();
    let dir = DVec3::from(FRAMING_DIR).normalize();
    (centre + distance * dir, centre)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(w: u32, h: u32) -> FilmCamera {
        let c = Camera::new(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 90.0).unwrap();
        FilmCamera::new(&c, w, h)
    }

    #[test]
    fn a_nan_or_infinite_pose_is_not_called_degenerate() {
        for bad in [f32::NAN, f32::INFINITY] {
            let v = Vec3::new(bad, 0.0, 0.0);
            for (p, l, u) in [
                (v, Vec3::ZERO, Vec3::Y),
                (Vec3::Z, v, Vec3::Y),
                (Vec3::Z, Vec3::ZERO, v),
            ] {
                let e = Camera::new(p, l, u, 45.0).unwrap_err();
                assert_eq!(e, CameraError::NotFinite);
                assert!(e.to_string().contains("finite"), "{e}");
            }
        }
        assert_eq!(
            Camera::new(Vec3::Y, Vec3::ZERO, Vec3::Y, 45.0),
            Err(CameraError::Degenerate)
        );
    }

    #[test]
    fn film_center_looks_at_the_target() {
        let r = cam(200, 100).ray(100.0, 50.0).unwrap();
        assert!((r.direction - -Vec3::Z).length() < 1e-6);
        assert_eq!(r.origin, Vec3::new(0.0, 0.0, 5.0));
    }

    #[test]
    fn corners_match_the_vertical_fov_and_aspect() {
        // fov 90: tan(45°) = 1, so the top edge center is 45° up and, with aspect 2, the right
        // edge center is atan(2) to the right.
        let c = cam(200, 100);
        let top = c.ray(100.0, 0.0).unwrap().direction;
        assert!((top - Vec3::new(0.0, 1.0, -1.0).normalize()).length() < 1e-6);
        let right = c.ray(200.0, 50.0).unwrap().direction;
        assert!((right - Vec3::new(2.0, 0.0, -1.0).normalize()).length() < 1e-6);
        // Top-left corner: +y is up, x grows to the right.
        let tl = c.ray(0.0, 0.0).unwrap().direction;
        assert!((tl - Vec3::new(-2.0, 1.0, -1.0).normalize()).length() < 1e-6);
    }

    #[test]
    fn far_and_near_targets_are_not_degenerate() {
        // The squared distance overflows (1e40), underflows (1e-50), or the difference itself
        // overflows (6e38); each camera still looks straight at its target along −x.
        for (position, at) in [
            (Vec3::new(1e20, 0.0, 0.0), Vec3::ZERO),
            (Vec3::new(1e-25, 0.0, 0.0), Vec3::ZERO),
            (Vec3::new(3e38, 0.0, 0.0), Vec3::new(-3e38, 0.0, 0.0)),
        ] {
            let c = Camera::new(position, at, Vec3::new(0.0, 1e30, 0.0), 60.0)
                .unwrap_or_else(|e| panic!("{position}: {e}"));
            let r = FilmCamera::new(&c, 2, 2).ray(1.0, 1.0).unwrap();
            assert!(
                (r.direction - -Vec3::X).length() < 1e-6,
                "{position}: {r:?}"
            );
        }
    }

    #[test]
    fn rejects_bad_cameras() {
        let new = |at: Vec3, up: Vec3, fov: f32| Camera::new(Vec3::ZERO, at, up, fov);
        assert_eq!(new(Vec3::Y, Vec3::Y, 45.0), Err(CameraError::Degenerate));
        assert_eq!(new(Vec3::ZERO, Vec3::Y, 45.0), Err(CameraError::Degenerate));
        assert_eq!(new(Vec3::Z, Vec3::Y, 0.0), Err(CameraError::FovOutOfRange));
        assert_eq!(
            new(Vec3::Z, Vec3::Y, 180.0),
            Err(CameraError::FovOutOfRange)
        );
    }
}
