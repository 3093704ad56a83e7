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
    },
    /// A path of a kind: `path = { type = "orbit", ... }`.
    Path {
        /// Up direction (default +y); an orbit's must be an axis.
        up: Option<Vec3Desc>,
        /// Vertical field of view in degrees, in (0, 180).
        fov: Num,
        /// The path.
        path: CameraPathDesc,
    },
}

/// A still camera.
#[derive(Clone, Debug, PartialEq)]
pub struct StillCameraDesc {
    /// Eye position.
    pub position: Vec3Desc,
    /// The point seen at the film's center.
    pub look_at: Vec3Desc,
    /// Up direction (default +y).
    pub up: Option<Vec3Desc>,
    /// Vertical field of view in degrees, in (0, 180).
    pub fov: Num,
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
    keys: Option<Vec<CameraKeyDesc>>,
    path: Option<CameraPathDesc>,
}

impl<'de> Deserialize<'de> for CameraDesc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let t = CameraTable::deserialize(d)?;
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
        }
        Ok(match (t.keys, t.path) {
            (Some(keys), _) => CameraDesc::Keys {
                up: t.up,
                fov: t.fov,
                keys,
            },
            (None, Some(path)) => CameraDesc::Path {
                up: t.up,
                fov: t.fov.ok_or_else(|| D::Error::missing_field("fov"))?,
                path,
            },
            (None, None) => CameraDesc::Still(StillCameraDesc {
                position: t
                    .position
                    .ok_or_else(|| D::Error::missing_field("position"))?,
                look_at: t
                    .look_at
                    .ok_or_else(|| D::Error::missing_field("look_at"))?,
                up: t.up,
                fov: t.fov.ok_or_else(|| D::Error::missing_field("fov"))?,
            }),
        })
    }
}
