//! Explicit cameras from Python: a `penumbra.Camera` arrives as its (position, look_at, up,
//! fov) when it is a plain pinhole, else as its scene table (JSON text in a 1-tuple), built
//! as a scene file's camera is on the film it is used with.

use glam::Vec3;
use penumbra::{camera_from_table, Camera, SceneError};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// A camera as Python passes it: a pinhole's (position, look_at, up, fov), or a `[camera]`
/// table as JSON (in a 1-tuple, apart from a camera's name).
#[derive(Clone, Debug, FromPyObject)]
pub enum CameraSpec {
    /// A pinhole's position, look_at, up and vertical fov in degrees.
    Pinhole([f32; 3], [f32; 3], [f32; 3], f32),
    /// The keys of a `[camera]` table, as a JSON object.
    Table((String,)),
}

impl CameraSpec {
    /// The library's camera on a `width × height` film (a table's `K` counts its pixels), or
    /// a `ValueError` saying why there is none: for a table, naming the key.
    pub fn camera(&self, (width, height): (u32, u32)) -> PyResult<Camera> {
        match self {
            CameraSpec::Pinhole(position, look_at, up, fov) => Camera::new(
                Vec3::from(*position),
                Vec3::from(*look_at),
                Vec3::from(*up),
                *fov,
            )
            .map_err(|e| PyValueError::new_err(e.to_string())),
            CameraSpec::Table((table,)) => {
                camera_from_table(table, width, height).map_err(table_error)
            }
        }
    }
}

/// A table's error as `KEY: message` (the key without its `camera.`), or the message alone
/// for the table as a whole (a missing key).
fn table_error(e: SceneError) -> PyErr {
    match &e {
        SceneError::Invalid {
            location, message, ..
        } => {
            match location
                .key
                .as_deref()
                .and_then(|k| k.strip_prefix("camera."))
            {
                Some(key) => PyValueError::new_err(format!("{key}: {message}")),
                None => PyValueError::new_err(message.clone()),
            }
        }
        _ => PyValueError::new_err(e.to_string()),
    }
}

/// Raises `ValueError` when the camera cannot exist: a degenerate frame, the field of view
/// outside (0, 180) degrees, a bad key of a table.
#[pyfunction]
pub fn check_camera(camera: CameraSpec) -> PyResult<()> {
    camera.camera((1, 1)).map(|_| ())
}

/// `camera` on a film of `width × height` pixels: `ValueError` for an empty one.
fn film_camera(camera: &CameraSpec, (width, height): (u32, u32)) -> PyResult<Camera> {
    if width == 0 || height == 0 {
        return Err(PyValueError::new_err(format!(
            "a {width}x{height} film has no pixels"
        )));
    }
    camera.camera((width, height))
}

/// The camera's intrinsics and poses on a `width × height` film (see `penumbra::CameraPose`
/// and docs/spec.md §10): K, camera_to_world (OpenCV axes), camera_to_world_opengl and
/// world_to_camera, each a list of rows. Raises `ValueError` as [`check_camera`] does, and
/// for an empty film.
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn camera_pose(
    camera: CameraSpec,
    width: u32,
    height: u32,
) -> PyResult<(
    penumbra::Mat3Rows,
    penumbra::Mat4Rows,
    penumbra::Mat4Rows,
    penumbra::Mat4Rows,
)> {
    let c = film_camera(&camera, (width, height))?;
    let p = penumbra::CameraPose::new(&c, width, height, (0, 0));
    Ok((
        p.k,
        p.camera_to_world,
        p.camera_to_world_opengl,
        p.world_to_camera,
    ))
}

/// The ray through each pixel's center, as the renderer makes the rays of its one-ray AOVs
/// (`object_id`, `depth`, ...): a `(height, width, 6)` float32 array of origin and unit
/// direction, row 0 at the top; NaN where the camera's lens model sees nothing (beyond a
/// distortion's valid radius or a fisheye's `max_angle`). A thin lens's rays leave its
/// centre. Raises `ValueError` as [`camera_pose`] does.
#[pyfunction]
pub fn camera_rays(
    py: Python<'_>,
    camera: CameraSpec,
    width: u32,
    height: u32,
) -> PyResult<Bound<'_, numpy::PyArray3<f32>>> {
    use numpy::IntoPyArray;
    let c = film_camera(&camera, (width, height))?;
    let film = penumbra::FilmCamera::new(&c, width, height);
    let (w, h) = (width as usize, height as usize);
    let rays = py.detach(|| {
        let no_memory = || crate::errors::no_memory("camera_rays", "the rays");
        let len = h.checked_mul(w).and_then(|n| n.checked_mul(6));
        let mut rows = Vec::new();
        rows.try_reserve_exact(len.ok_or_else(no_memory)?)
            .map_err(|_| no_memory())?;
        for y in 0..h {
            for x in 0..w {
                match film.ray(x as f32 + 0.5, y as f32 + 0.5) {
                    Some(ray) => {
                        rows.extend(ray.origin.to_array());
                        rows.extend(ray.direction.to_array());
                    }
                    None => rows.extend([f32::NAN; 6]),
                }
            }
        }
        numpy::ndarray::Array3::from_shape_vec((h, w, 6), rows)
            .map_err(|e| PyValueError::new_err(e.to_string()))
    })?;
    Ok(rays.into_pyarray(py))
}
