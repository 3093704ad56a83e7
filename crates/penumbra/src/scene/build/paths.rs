//! Camera paths: `[[cameras.NAME.keys]]` and `path = { type = "orbit", ... }` checked into a
//! [`CameraPath`], every error at the key it is about.

use glam::DVec3;

use super::{Builder, Result};
use crate::camera::CameraError;
use crate::camera_path::{CameraKey, CameraPath, Orbit, PathError};
use crate::scene::desc::{CameraKeyDesc, CameraPathDesc, Num, PathType, Vec3Desc};
use crate::scene::error::{ErrorKind, KeyPath};

/// The field of view of the pinholes a path with K or a model that sets the view moves: K or
/// the model replaces it at every frame.
const UNUSED_FOV: Num = Num(60.0);

impl Builder<'_> {
    /// The path of the camera table at `table` with `keys`, the table's `up` and `fov` being
    /// the keys' defaults; without `needs_fov` (K or the model gives the view) no key takes a
    /// fov.
    pub(super) fn key_path(
        &self,
        table: &KeyPath,
        keys: &[CameraKeyDesc],
        up: Option<Vec3Desc>,
        fov: Option<Num>,
        needs_fov: bool,
    ) -> Result<CameraPath> {
        let mut checked = Vec::with_capacity(keys.len());
        for (i, k) in keys.iter().enumerate() {
            let at = table.key("keys").index(i);
            if !needs_fov && k.fov.is_some() {
                let message = "this camera's K or model gives its view: its keys take no fov";
                return Err(self.bad(&at.key("fov"), message));
            }
            let fov = k.fov.or(fov).or((!needs_fov).then_some(UNUSED_FOV));
            let fov = fov.ok_or_else(|| {
                self.err(
                    ErrorKind::MissingKey,
                    &at,
                    "missing key `fov` (give it in each key, or once in the camera's table)",
                )
            })?;
            if !(fov.0 > 0.0 && fov.0 < 180.0) {
                let message = format!("fov must be between 0 and 180 degrees, not {}", fov.0);
                return Err(self.bad(&at.key("fov"), message));
            }
            checked.push(CameraKey {
                frame: k.frame,
                position: dvec(k.position),
                look_at: dvec(k.look_at),
                up: k.up.or(up).map_or(DVec3::Y, dvec),
                fov_y_deg: fov.0,
            });
        }
        CameraPath::keys(checked).map_err(|e| {
            let keys = table.key("keys");
            let at = match &e {
                PathError::OutOfOrder { index, .. } | PathError::Duplicate { index, .. } => {
                    keys.index(*index).key("frame")
                }
                PathError::Camera { key: Some(i), .. } => keys.index(*i),
                _ => keys,
            };
            self.bad(&at, e.to_string())
        })
    }

    /// The path of the camera table at `table` with `path = {...}`.
    pub(super) fn kind_path(
        &self,
        table: &KeyPath,
        path: &CameraPathDesc,
        up: Option<Vec3Desc>,
        fov: Option<Num>,
    ) -> Result<CameraPath> {
        let at = table.key("path");
        // The deserializer required fov where the lens needs one.
        let fov = fov.unwrap_or(UNUSED_FOV);
        if !(fov.0 > 0.0 && fov.0 < 180.0) {
            let message = format!("fov must be between 0 and 180 degrees, not {}", fov.0);
            return Err(self.bad(&table.key("fov"), message));
        }
        match path.kind {
            PathType::Orbit => {
                let orbit = Orbit {
                    center: dvec(path.center),
                    radius: path.radius.0,
                    height: path.height.map_or(0.0, |h| h.0),
                    frames: path.frames,
                    start_deg: path.start_angle.map_or(0.0, |a| a.0),
                    up: up.map_or(DVec3::Y, dvec),
                    fov_y_deg: fov.0,
                };
                CameraPath::orbit(orbit).map_err(|e| {
                    let key = match &e {
                        PathError::Frames(_) => at.key("frames"),
                        PathError::Radius(_) => at.key("radius"),
                        PathError::Up(_) => table.key("up"),
                        PathError::Camera {
                            source: CameraError::NotFinite,
                            ..
                        } => at.key("radius"),
                        _ => at.clone(),
                    };
                    self.bad(&key, e.to_string())
                })
            }
        }
    }
}

fn dvec(v: Vec3Desc) -> DVec3 {
    DVec3::from_array(v.0)
}
