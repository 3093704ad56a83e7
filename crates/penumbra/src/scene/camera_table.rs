//! A still camera from its scene-file table alone: the keys of a `[camera]` table as a JSON
//! object, checked and built exactly as a scene file's camera is (what Python's `Camera`
//! holds), on the film whose pixels its `K` counts.

use super::{SceneError, SceneFile, SceneFormat};
use crate::camera::Camera;
use crate::scene::error::{ErrorKind, Location};

/// Keys of a camera that moves: a table of them is a scene's, not a single camera's.
const MOVING: [&str; 2] = ["keys", "path"];

/// The name errors give the table.
const FILE: &str = "camera.json";

/// The camera the `[camera]` table `table` (a JSON object of its keys: `position`,
/// `look_at`, `up`, `fov` or `camera_to_world`, `K`, `model`, `distortion`, …) describes, on
/// a `width × height` film: `K`, when given, is in that film's pixels. Errors are a scene
/// file's, at `camera.KEY` (in a file named `camera.json`).
///
/// ```
/// use penumbra::{camera_from_table, Lens};
///
/// let table = r#"{"position": [0, 0, 5], "look_at": [0, 0, 0], "model": "opencv",
///                 "K": [[300, 0, 159.5], [0, 300, 119.5], [0, 0, 1]],
///                 "distortion": [-0.2, 0.05, 0, 0]}"#;
/// let camera = camera_from_table(table, 320, 240)?;
/// assert!(matches!(camera.lens(), Lens::OpenCv(_)));
/// let e = camera_from_table(r#"{"position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 200}"#, 8, 8)
///     .unwrap_err();
/// assert_eq!(e.location().unwrap().key.as_deref(), Some("camera.fov"));
/// # Ok::<(), penumbra::SceneError>(())
/// ```
pub fn camera_from_table(table: &str, width: u32, height: u32) -> Result<Camera, SceneError> {
    let keys: serde_json::Map<String, serde_json::Value> = serde_json::from_str(table)
        .map_err(|e| table_error("camera", format!("not a camera table: {e}")))?;
    if let Some(key) = MOVING.iter().find(|k| keys.contains_key(**k)) {
        let message = "a single camera has no keys or path: a scene file's camera moves";
        return Err(table_error(&format!("camera.{key}"), message.into()));
    }
    // Only a film and the camera: the table cannot name a file or add anything else.
    let scene = serde_json::json!({
        "film": { "width": width, "height": height },
        "camera": keys,
    });
    let world = SceneFile::from_str(&scene.to_string(), SceneFormat::Json, FILE, ".")?
        .build(1)?
        .world;
    let first = world.cameras().first().map(|(_, c)| *c);
    first.ok_or_else(|| table_error("camera", "no camera".into()))
}

/// An error about `key` of a camera table.
fn table_error(key: &str, message: String) -> SceneError {
    SceneError::Invalid {
        kind: ErrorKind::BadValue,
        location: Box::new(Location {
            file: FILE.into(),
            line: None,
            column: None,
            key: Some(key.to_owned()),
            set_by: None,
        }),
        message,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key_of(table: &str) -> Option<String> {
        let e = camera_from_table(table, 8, 8).unwrap_err();
        e.location().and_then(|l| l.key.clone())
    }

    #[test]
    fn a_table_is_one_still_camera_and_nothing_else() {
        let still = r#"{"position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 40"#;
        assert!(camera_from_table(&format!("{still}}}"), 8, 8).is_ok());
        let keys = format!(r#"{still}, "keys": [{{"frame": 0, "position": [0, 0, 4]}}]}}"#);
        assert_eq!(key_of(&keys).as_deref(), Some("camera.keys"));
        // Not an object, or not JSON: the table as a whole.
        assert_eq!(key_of("[1, 2]").as_deref(), Some("camera"));
        assert_eq!(key_of(r#"{"fov": 40"#).as_deref(), Some("camera"));
        // A key of another table is unknown in a camera's.
        let other = format!(r#"{still}, "objects": []}}"#);
        assert_eq!(key_of(&other).as_deref(), Some("camera.objects"));
    }
}
