//! One image's camera as the poses layouts and records write it ([`PoseFrame`], its lens
//! [`LensFields`]), and the refusals the layouts share: what each layout module
//! ([`super::poses`], [`super::colmap`]) reads.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::ProductError;
use crate::camera::{Camera, Lens};
use crate::pose::{CameraPose, Mat3Rows, Mat4Rows};

/// One image's frame of penumbra's layout. The camera's numbers are its `f32`s widened to
/// `f64`, as written; a frame read back (Python's `penumbra.poses.nerf` of a penumbra
/// layout) keeps them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PoseFrame {
    /// The frame (a path camera's, or a view's index); `None` for a still camera.
    pub frame: Option<i64>,
    /// The camera's (or the view's) name.
    pub camera: String,
    /// The image file.
    pub file: String,
    /// Its width in pixels.
    pub width: u32,
    /// Its height in pixels.
    pub height: u32,
    /// Vertical field of view in degrees.
    pub fov: f64,
    /// K.
    #[serde(rename = "K")]
    pub k: Mat3Rows,
    /// Camera to world, OpenCV axes.
    pub camera_to_world: Mat4Rows,
    /// Camera to world, OpenGL axes.
    pub camera_to_world_opengl: Mat4Rows,
    /// World to camera, OpenCV axes.
    pub world_to_camera: Mat4Rows,
    /// The eye.
    pub position: [f64; 3],
    /// The point looked at.
    pub look_at: [f64; 3],
    /// The up direction.
    pub up: [f64; 3],
    /// The camera's lens.
    #[serde(flatten)]
    pub lens: LensFields,
}

/// A camera's lens as poses and records write it: `model` and, as the model has them, its
/// coefficients and aperture.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LensFields {
    /// The lens model, as the scene's `model` key names it (files written before lens
    /// models read as "pinhole").
    #[serde(default = "pinhole")]
    pub model: String,
    /// The distortion coefficients as given, in OpenCV's order (`opencv`, `fisheye`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub distortion: Vec<f64>,
    /// A fisheye's widest angle off the axis, in degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_angle: Option<f64>,
    /// An orthographic camera's image height in world units.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orthographic_height: Option<f64>,
    /// A thin lens's radius and focus distance (the pose is its centre's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aperture_radius: Option<f64>,
    /// See `aperture_radius`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub focus_distance: Option<f64>,
}

impl LensFields {
    /// The lens of `pose`.
    pub fn of(pose: &CameraPose) -> LensFields {
        let lens = pose.lens;
        let aperture = pose.aperture;
        LensFields {
            model: lens.name().to_owned(),
            distortion: match lens {
                Lens::OpenCv(d) => d.given().to_vec(),
                Lens::Fisheye(d) => d.coefficients.to_vec(),
                _ => vec![],
            },
            max_angle: match lens {
                Lens::Fisheye(d) => Some(d.max_angle_deg()),
                _ => None,
            },
            orthographic_height: match lens {
                Lens::Orthographic { height } => Some(f64::from(height)),
                _ => None,
            },
            aperture_radius: aperture.map(|a| f64::from(a.radius)),
            focus_distance: aperture.map(|a| f64::from(a.focus_distance)),
        }
    }

    /// OpenCV's distortion coefficients, all twelve (the ones not given 0).
    pub(crate) fn opencv_coefficients(&self) -> [f64; 12] {
        let mut all = [0.0; 12];
        let n = self.distortion.len().min(12);
        all[..n].copy_from_slice(&self.distortion[..n]);
        all
    }
}

fn pinhole() -> String {
    "pinhole".to_owned()
}

impl PoseFrame {
    /// The frame of the image `file`, `width × height`, of `camera` seen as `pose`.
    pub fn new(
        frame: Option<i64>,
        name: &str,
        file: &str,
        camera: &Camera,
        pose: CameraPose,
        (width, height): (u32, u32),
    ) -> PoseFrame {
        let wide = |v: glam::Vec3| v.as_dvec3().to_array();
        PoseFrame {
            frame,
            camera: name.to_owned(),
            file: file.to_owned(),
            width,
            height,
            fov: f64::from(camera.fov_y_deg()),
            k: pose.k,
            camera_to_world: pose.camera_to_world,
            camera_to_world_opengl: pose.camera_to_world_opengl,
            world_to_camera: pose.world_to_camera,
            position: wide(camera.position()),
            look_at: wide(camera.look_at()),
            up: wide(camera.up()),
            lens: LensFields::of(&pose),
        }
    }
}

/// An error naming the first camera of `frames` whose K has a skew, which `model` (NeRF's,
/// COLMAP's `PINHOLE`) cannot hold: written without it, the file would describe another
/// camera.
pub(crate) fn unskewed(frames: &[PoseFrame], path: &Path, model: &str) -> Result<(), ProductError> {
    match frames.iter().find(|f| f.k[0][1] != 0.0) {
        None => Ok(()),
        Some(f) => Err(ProductError::Invalid {
            path: path.to_owned(),
            message: format!(
                "camera `{}` has a skew (K[0][1] = {}), which {model} cannot hold: write the \
                 penumbra layout",
                f.camera, f.k[0][1]
            ),
        }),
    }
}

/// An error for the camera of frame `f`, which `format` cannot hold because of `why`.
pub(crate) fn cannot_hold(path: &Path, f: &PoseFrame, format: &str, why: &str) -> ProductError {
    ProductError::Invalid {
        path: path.to_owned(),
        message: format!(
            "camera `{}` ({}) {why}, which {format} cannot hold: write the penumbra layout",
            f.camera, f.lens.model
        ),
    }
}
