//! `[camera]` and `[cameras.NAME]`: a still camera, keyframes or an orbit.
//!
//! ```
//! let file = penumbra::SceneFile::from_str(r#"
//! [film]
//! width = 8
//! height = 8
//!
//! [cameras.fly]
//! fov = 40
//! [[cameras.fly.keys]]
//! frame = 1
//! position = [0, 1, 5]
//! look_at = [0, 0, 0]
//! [[cameras.fly.keys]]
//! frame = 24
//! position = [3, 1, 4]
//! look_at = [0, 0, 0]
//! fov = 30
//!
//! [cameras.turn]
//! fov = 40
//! path = { type = "orbit", center = [0, 0, 0], radius = 5, height = 1, frames = 48 }
//! "#, penumbra::SceneFormat::Toml, "paths.toml", ".").unwrap();
//! let scene = file.build(1).unwrap();
//! assert_eq!(scene.path("fly").unwrap().frames(), 1..=24);
//! assert_eq!(scene.path("turn").unwrap().frames(), 0..=47);
//! ```

use serde::de::{Deserializer, Error as _};
use serde::Deserialize;

use super::objects::Matrix;
use super::values::{Num, Vec3Desc};

/// `[camera]` or `[cameras.NAME]`.
#[derive(Clone, Debug, PartialEq)]
pub enum CameraDesc {
    /// A camera that stays where it is.
    Still(StillCameraDesc),
    /// Keyframes: `[[cameras.NAME.keys]]`, with `fov` and `up` of the table as the keys'
    /// defaults.
    Keys {
        /// The keys' default up direction (else +y).
        up: Option<Vec3Desc>,
        /// The keys' default field of view.
        fov: Option<Num>,
        /// The keys, as written.
        keys: Vec<CameraKeyDesc>,
        /// What every frame sees through.
        optics: OpticsDesc,
    },
    /// A path of a kind: `path = { type = "orbit", ... }`.
    Path {
        /// Up direction (default +y); an orbit's must be an axis.
        up: Option<Vec3Desc>,
        /// Vertical field of view in degrees, in (0, 180): required unless `K` or the
        /// model sets the view.
        fov: Option<Num>,
        /// The path.
        path: CameraPathDesc,
        /// What every frame sees through.
        optics: OpticsDesc,
    },
}

/// What a moving camera sees through at every frame: `K`, `model` and its keys, the
/// aperture (a still camera's keys but its pose and fov).
#[derive(Clone, Debug, PartialEq)]
pub struct OpticsDesc {
    /// `K`, instead of the field of view.
    pub k: Option<[[Num; 3]; 3]>,
    /// Its lens model.
    pub model: ModelDesc,
    /// `aperture_radius` and `focus_distance`.
    pub aperture: Option<ApertureDesc>,
}

impl OpticsDesc {
    /// True when the frames need a field of view: a pinhole or OpenCV lens without K.
    pub fn needs_fov(&self) -> bool {
        self.k.is_none() && matches!(self.model, ModelDesc::Pinhole | ModelDesc::OpenCv { .. })
    }
}

/// A still camera: where it stands, and what it sees.
#[derive(Clone, Debug, PartialEq)]
pub struct StillCameraDesc {
    /// Its pose.
    pub pose: PoseDesc,
    /// Its field of view or K (the perspective models').
    pub lens: LensDesc,
    /// Its lens model (`model`, default the pinhole).
    pub model: ModelDesc,
    /// `aperture_radius` and `focus_distance`, for depth of field.
    pub aperture: Option<ApertureDesc>,
}

/// `model` and the keys of its kind.
#[derive(Clone, Debug, PartialEq)]
pub enum ModelDesc {
    /// `"pinhole"`.
    Pinhole,
    /// `"opencv"`: K or fov, then OpenCV's radial-tangential `distortion`.
    OpenCv {
        /// k1 k2 p1 p2 [k3 [k4 k5 k6 [s1 s2 s3 s4]]].
        distortion: Vec<Num>,
    },
    /// `"fisheye"`: K over OpenCV's fisheye model.
    Fisheye {
        /// k1 k2 k3 k4.
        distortion: Vec<Num>,
        /// The widest angle seen off the axis, in degrees (default 90).
        max_angle: Option<Num>,
    },
    /// `"equirectangular"`: a 360° × 180° panorama.
    Equirectangular,
    /// `"orthographic"`: parallel rays.
    Orthographic {
        /// The image's height in world units.
        height: Num,
    },
}

/// A thin lens: `aperture_radius` and `focus_distance` (pbrt's `lensradius` and
/// `focaldistance`).
#[derive(Clone, Debug, PartialEq)]
pub struct ApertureDesc {
    /// The lens's radius in world units (0: the pinhole).
    pub radius: Num,
    /// The distance along forward to the plane in focus.
    pub focus_distance: Num,
}

/// The names of `model`.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum ModelName {
    Pinhole,
    OpenCv,
    Fisheye,
    Equirectangular,
    Orthographic,
}

/// Where a still camera stands.
#[derive(Clone, Debug, PartialEq)]
pub enum PoseDesc {
    /// `position`, `look_at` and `up`.
    LookAt {
        /// Eye position.
        position: Vec3Desc,
        /// The point seen at the film's center.
        look_at: Vec3Desc,
        /// Up direction (default +y).
        up: Option<Vec3Desc>,
    },
    /// `camera_to_world`: a rigid 4×4 matrix by rows in OpenCV's camera axes (x right, y
    /// down, z forward), as `--poses` writes it.
    Matrix(Matrix),
}

/// What a perspective camera sees through.
#[derive(Clone, Debug, PartialEq)]
pub enum LensDesc {
    /// `fov`: the vertical field of view in degrees, in (0, 180).
    Fov(Num),
    /// `K`: the intrinsic matrix by rows, in pixels of the film (`film.width × film.height`).
    K([[Num; 3]; 3]),
    /// Neither: a panorama or an orthographic camera.
    None,
}

/// `[[cameras.NAME.keys]]`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CameraKeyDesc {
    /// The frame, an integer (keys in increasing frame order).
    pub frame: i64,
    /// Eye position.
    pub position: Vec3Desc,
    /// The point seen at the film's center.
    pub look_at: Vec3Desc,
    /// Up direction (default: the camera table's, else +y).
    pub up: Option<Vec3Desc>,
    /// Vertical field of view in degrees (default: the camera table's).
    pub fov: Option<Num>,
}

/// The kinds of `path`.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum PathType {
    /// A turntable around a point.
    Orbit,
}

/// `path = { type = "orbit", center, radius, height, frames, start_angle }`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CameraPathDesc {
    /// The kind of path: "orbit".
    #[serde(rename = "type")]
    pub kind: PathType,
    /// The point looked at.
    pub center: Vec3Desc,
    /// The circle's radius (> 0).
    pub radius: Num,
    /// Height of the circle above `center`, along up (default 0).
    pub height: Option<Num>,
    /// Number of frames (frames 0 to frames − 1).
    pub frames: i64,
    /// Angle of frame 0 in degrees (default 0: on the axis after up, +z for y up).
    pub start_angle: Option<Num>,
}

/// Every key a camera table may have, read before the table's kind is decided.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraTable {
    position: Option<Vec3Desc>,
    look_at: Option<Vec3Desc>,
    up: Option<Vec3Desc>,
    fov: Option<Num>,
    #[serde(rename = "K")]
    k: Option<[[Num; 3]; 3]>,
    camera_to_world: Option<Matrix>,
    keys: Option<Vec<CameraKeyDesc>>,
    path: Option<CameraPathDesc>,
    model: Option<ModelName>,
    distortion: Option<Vec<Num>>,
    max_angle: Option<Num>,
    height: Option<Num>,
    aperture_radius: Option<Num>,
    focus_distance: Option<Num>,
}

impl CameraTable {
    /// `model` and its keys, each only on its model.
    fn model<E: serde::de::Error>(&mut self) -> Result<ModelDesc, E> {
        let model = self.model.unwrap_or(ModelName::Pinhole);
        let name = format!("{model:?}").to_lowercase();
        let only = |key: &str, owner: &str| {
            E::custom(format!(
                "{key} is a key of model = \"{owner}\" cameras, not of model = \"{name}\""
            ))
        };
        if self.max_angle.is_some() && model != ModelName::Fisheye {
            return Err(only("max_angle", "fisheye"));
        }
        if self.height.is_some() && model != ModelName::Orthographic {
            return Err(only("height", "orthographic"));
        }
        let distorted = matches!(model, ModelName::OpenCv | ModelName::Fisheye);
        if self.distortion.is_some() && !distorted {
            return Err(E::custom(format!(
                "distortion is a key of model = \"opencv\" or \"fisheye\" cameras, not of \
                 model = \"{name}\""
            )));
        }
        let perspective = distorted || model == ModelName::Pinhole;
        let opening = self.aperture_radius.is_some() || self.focus_distance.is_some();
        if opening && !perspective {
            return Err(E::custom(format!(
                "a model = \"{name}\" camera has no aperture: aperture_radius and \
                 focus_distance are the perspective models' (pinhole, opencv, fisheye)"
            )));
        }
        if !perspective && (self.fov.is_some() || self.k.is_some()) {
            return Err(E::custom(format!(
                "a model = \"{name}\" camera takes no fov or K"
            )));
        }
        if model == ModelName::Fisheye && self.fov.is_some() {
            return Err(E::custom(
                "a fisheye camera takes K, not fov (its coefficients and max_angle give its view)",
            ));
        }
        let mut distortion = || {
            self.distortion
                .take()
                .ok_or_else(|| E::missing_field("distortion"))
        };
        Ok(match model {
            ModelName::Pinhole => ModelDesc::Pinhole,
            ModelName::OpenCv => ModelDesc::OpenCv {
                distortion: distortion()?,
            },
            ModelName::Fisheye => ModelDesc::Fisheye {
                distortion: distortion()?,
                max_angle: self.max_angle,
            },
            ModelName::Equirectangular => ModelDesc::Equirectangular,
            ModelName::Orthographic => ModelDesc::Orthographic {
                height: self.height.ok_or_else(|| E::missing_field("height"))?,
            },
        })
    }

    /// `aperture_radius` with `focus_distance`, or neither.
    fn aperture<E: serde::de::Error>(&self) -> Result<Option<ApertureDesc>, E> {
        match (self.aperture_radius, self.focus_distance) {
            (None, None) => Ok(None),
            (Some(radius), Some(focus_distance)) => Ok(Some(ApertureDesc {
                radius,
                focus_distance,
            })),
            (Some(_), None) => Err(E::missing_field("focus_distance")),
            (None, Some(_)) => Err(E::missing_field("aperture_radius")),
        }
    }
}

impl<'de> Deserialize<'de> for CameraDesc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let mut t = CameraTable::deserialize(d)?;
        let moving = match (&t.keys, &t.path) {
            (Some(_), Some(_)) => {
                return Err(D::Error::custom(
                    "a camera has either keys or a path, not both",
                ))
            }
            (Some(_), None) => Some("keys"),
            (None, Some(_)) => Some("path"),
            (None, None) => None,
        };
        if let Some(how) = moving {
            if t.position.is_some() || t.look_at.is_some() {
                return Err(D::Error::custom(format!(
                    "a camera with {how} takes no position or look_at of its own (its {how} give them)"
                )));
            }
            if t.camera_to_world.is_some() {
                return Err(D::Error::custom(format!(
                    "camera_to_world is a still camera's: a camera with {how} takes its \
                     positions from its {how}"
                )));
            }
            if t.k.is_some() && t.fov.is_some() {
                return Err(D::Error::custom("a camera takes fov or K, not both"));
            }
        }
        let model = t.model()?;
        let aperture = t.aperture()?;
        let perspective = matches!(
            model,
            ModelDesc::Pinhole | ModelDesc::OpenCv { .. } | ModelDesc::Fisheye { .. }
        );
        let optics = |k| OpticsDesc {
            k,
            model: model.clone(),
            aperture: aperture.clone(),
        };
        if moving.is_some() && matches!(model, ModelDesc::Fisheye { .. }) && t.k.is_none() {
            return Err(D::Error::missing_field("K"));
        }
        Ok(match (t.keys, t.path) {
            (Some(keys), _) => CameraDesc::Keys {
                up: t.up,
                fov: t.fov,
                keys,
                optics: optics(t.k),
            },
            (None, Some(path)) => {
                let optics = optics(t.k);
                if optics.needs_fov() && t.fov.is_none() {
                    return Err(D::Error::missing_field("fov"));
                }
                CameraDesc::Path {
                    up: t.up,
                    fov: t.fov,
                    path,
                    optics,
                }
            }
            (None, None) => CameraDesc::Still(StillCameraDesc {
                pose: match t.camera_to_world {
                    Some(_) if t.position.is_some() || t.look_at.is_some() || t.up.is_some() => {
                        return Err(D::Error::custom(
                            "a camera takes camera_to_world or position, look_at and up, not both",
                        ))
                    }
                    Some(m) => PoseDesc::Matrix(m),
                    None => PoseDesc::LookAt {
                        position: t
                            .position
                            .ok_or_else(|| D::Error::missing_field("position"))?,
                        look_at: t
                            .look_at
                            .ok_or_else(|| D::Error::missing_field("look_at"))?,
                        up: t.up,
                    },
                },
                lens: match (t.fov, t.k) {
                    (Some(_), Some(_)) => {
                        return Err(D::Error::custom("a camera takes fov or K, not both"))
                    }
                    (Some(fov), None) => LensDesc::Fov(fov),
                    (None, Some(k)) => LensDesc::K(k),
                    (None, None) if !perspective => LensDesc::None,
                    (None, None) if matches!(model, ModelDesc::Fisheye { .. }) => {
                        return Err(D::Error::missing_field("K"))
                    }
                    (None, None) => return Err(D::Error::missing_field("fov")),
                },
                model,
                aperture,
            }),
        })
    }
}
