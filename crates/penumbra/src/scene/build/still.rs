//! A still camera of the file: its pose (`position`, `look_at` and `up`, or a
//! `camera_to_world` matrix in OpenCV's axes, as `--poses` writes one), its lens (`fov`, or
//! an intrinsic matrix `K` in pixels of the file's film), its model (`model` and its keys) and
//! its aperture, checked at their keys; and a moving camera's lens, the same at every frame.

use glam::{DMat3, DVec3, Vec3};

use super::{Builder, Result};
use crate::camera::{
    Camera, CameraError, DistortionError, FisheyeDistortion, Intrinsics, Lens, OpenCvDistortion,
};
use crate::camera_path::CameraPath;
use crate::scene::desc::{
    ApertureDesc, LensDesc, Matrix, ModelDesc, Num, OpticsDesc, PoseDesc, StillCameraDesc,
};
use crate::scene::error::KeyPath;

/// How far `camera_to_world`'s rotation may be from orthonormal, entry by entry of RᵀR − I:
/// a matrix written with six or seven digits passes.
const RIGID: f64 = 1e-4;

impl Builder<'_> {
    /// A still camera, checked.
    pub(super) fn still_camera(&self, path: &KeyPath, c: &StillCameraDesc) -> Result<Camera> {
        let (position, look_at, up) = match &c.pose {
            PoseDesc::LookAt {
                position,
                look_at,
                up,
            } => (
                position.vec3(),
                look_at.vec3(),
                up.map_or(Vec3::Y, |u| u.vec3()),
            ),
            PoseDesc::Matrix(m) => self.camera_to_world(&path.key("camera_to_world"), m)?,
        };
        let fov = match &c.lens {
            LensDesc::Fov(fov) => fov.f32(),
            // Replaced by K's own below; a panorama's or orthographic camera's is not used.
            LensDesc::K(_) | LensDesc::None => 60.0,
        };
        let camera = Camera::new(position, look_at, up, fov).map_err(|e| match e {
            CameraError::FovOutOfRange => self.bad(
                &path.key("fov"),
                format!("fov must be between 0 and 180 degrees, not {fov}"),
            ),
            CameraError::NotFinite | CameraError::Degenerate => {
                let key = match (&c.pose, e) {
                    (PoseDesc::Matrix(_), _) => "camera_to_world",
                    (_, CameraError::Degenerate) => "look_at",
                    _ => [("position", position), ("look_at", look_at)]
                        .into_iter()
                        .find(|(_, v)| !v.is_finite())
                        .map_or("up", |(key, _)| key),
                };
                self.bad(&path.key(key), e.to_string())
            }
            // Only the lens and aperture make these, below.
            CameraError::BadIntrinsics
            | CameraError::BadHeight
            | CameraError::BadAperture
            | CameraError::NoAperture => self.bad(&path.key("K"), e.to_string()),
        })?;
        let k = match &c.lens {
            LensDesc::K(k) => Some(k),
            LensDesc::Fov(_) | LensDesc::None => None,
        };
        self.see_through(path, camera, k, &c.model, c.aperture.as_ref())
    }

    /// A moving camera's `path` (of the table at `table`), every frame seeing through
    /// `optics`, checked on the first frame's camera.
    pub(super) fn path_optics(
        &self,
        table: &KeyPath,
        path: CameraPath,
        optics: &OpticsDesc,
    ) -> Result<CameraPath> {
        let plain = optics.k.is_none() && optics.model == ModelDesc::Pinhole;
        if plain && optics.aperture.is_none() {
            return Ok(path);
        }
        // A checked path has a camera at each of its frames.
        let first = path
            .camera(*path.frames().start())
            .ok_or_else(|| self.bad(table, "the path has no first frame"))?;
        let (k, model) = (optics.k.as_ref(), &optics.model);
        let camera = self.see_through(table, first, k, model, optics.aperture.as_ref())?;
        Ok(path.with_optics(camera.optics()))
    }

    /// `camera` (of the table at `path`) seeing through `k`, `model` and `aperture`.
    fn see_through(
        &self,
        path: &KeyPath,
        camera: Camera,
        k: Option<&[[Num; 3]; 3]>,
        model: &ModelDesc,
        aperture: Option<&ApertureDesc>,
    ) -> Result<Camera> {
        let camera = match k {
            Some(k) => {
                let at = path.key("K");
                let k = self.intrinsics(&at, k)?;
                camera
                    .with_intrinsics(k)
                    .map_err(|e| self.bad(&at, e.to_string()))?
            }
            None => camera,
        };
        let camera = self.model(path, camera, model)?;
        let Some(a) = aperture else {
            return Ok(camera);
        };
        let (radius, focus) = (a.radius.f32(), a.focus_distance.f32());
        camera.with_aperture(radius, focus).map_err(|e| {
            let key = match radius >= 0.0 && radius.is_finite() {
                true => "focus_distance",
                false => "aperture_radius",
            };
            let message = format!("{e} (aperture_radius {radius}, focus_distance {focus})");
            self.bad(&path.key(key), message)
        })
    }

    /// `camera` seeing through its `model`.
    fn model(&self, path: &KeyPath, camera: Camera, model: &ModelDesc) -> Result<Camera> {
        let values = |d: &[Num]| d.iter().map(|n| n.0).collect::<Vec<f64>>();
        let lens = match model {
            ModelDesc::Pinhole => Lens::Pinhole,
            ModelDesc::OpenCv { distortion } => {
                let d = OpenCvDistortion::new(&values(distortion));
                Lens::OpenCv(d.map_err(|e| self.bad(&path.key("distortion"), e.to_string()))?)
            }
            ModelDesc::Fisheye {
                distortion,
                max_angle,
            } => {
                let angle = max_angle.as_ref().map_or(90.0, |a| a.0);
                let d = FisheyeDistortion::new(&values(distortion), angle).map_err(|e| {
                    let key = match e {
                        DistortionError::Count(_) | DistortionError::NotFinite => "distortion",
                        DistortionError::MaxAngle(_) | DistortionError::Folds(_) => "max_angle",
                    };
                    self.bad(&path.key(key), e.to_string())
                })?;
                Lens::Fisheye(d)
            }
            ModelDesc::Equirectangular => Lens::Equirectangular,
            ModelDesc::Orthographic { height } => Lens::Orthographic {
                height: height.f32(),
            },
        };
        camera.with_lens(lens).map_err(|e| {
            let message = match model {
                ModelDesc::Orthographic { height } => format!("{e}, not {}", height.0),
                _ => e.to_string(),
            };
            self.bad(&path.key("height"), message)
        })
    }

    /// `K` by rows, `[[fx, skew, cx], [0, fy, cy], [0, 0, 1]]`, in pixels of the file's film.
    fn intrinsics(&self, at: &KeyPath, k: &[[Num; 3]; 3]) -> Result<Intrinsics> {
        let v = k.map(|row| row.map(|n| n.0));
        if let Some(bad) = v.iter().flatten().find(|x| !x.is_finite()) {
            return Err(self.bad(at, format!("{bad} in K")));
        }
        if v[1][0] != 0.0 || v[2] != [0.0, 0.0, 1.0] {
            return Err(self.bad(
                at,
                "K is [[fx, skew, cx], [0, fy, cy], [0, 0, 1]] (OpenCV's camera matrix)",
            ));
        }
        let (fx, fy) = (v[0][0], v[1][1]);
        if !(fx > 0.0 && fy > 0.0) {
            let message = format!("K's focal lengths must be greater than 0, not fx {fx}, fy {fy}");
            return Err(self.bad(at, message));
        }
        let film = &self.file.desc.film;
        // The film was checked before the cameras.
        let size = |v: i64| u32::try_from(v).unwrap_or(1).max(1);
        Ok(Intrinsics {
            fx,
            fy,
            cx: v[0][2],
            cy: v[1][2],
            skew: v[0][1],
            width: size(film.width),
            height: size(film.height),
        })
    }

    /// The (position, look_at, up) of a `camera_to_world` matrix in OpenCV's axes: rigid
    /// (a rotation, no scale or mirror, within [`RIGID`]) with the last row 0, 0, 0, 1.
    fn camera_to_world(&self, at: &KeyPath, m: &Matrix) -> Result<(Vec3, Vec3, Vec3)> {
        let v = m.map(|row| row.map(|n| n.0));
        if let Some(bad) = v.iter().flatten().find(|x| !x.is_finite()) {
            return Err(self.bad(at, format!("{bad} in camera_to_world")));
        }
        if v[3] != [0.0, 0.0, 0.0, 1.0] {
            return Err(self.bad(at, "camera_to_world's last row must be [0, 0, 0, 1]"));
        }
        let column = |j: usize| DVec3::new(v[0][j], v[1][j], v[2][j]);
        let r = DMat3::from_cols(column(0), column(1), column(2));
        let off = (r.transpose() * r - DMat3::IDENTITY).to_cols_array();
        if off.iter().any(|e| e.abs() > RIGID) || r.determinant() <= 0.0 {
            return Err(self.bad(
                at,
                "camera_to_world must be rigid: a rotation (orthonormal columns x right, \
                 y down, z forward, right-handed) and a translation, no scale or mirror",
            ));
        }
        let position = column(3);
        // Forward from the position, far enough that the difference keeps its digits.
        let reach = position.abs().max_element().max(1.0);
        let look_at = position + column(2) * reach;
        Ok((
            position.as_vec3(),
            look_at.as_vec3(),
            (-column(1)).as_vec3(),
        ))
    }
}
