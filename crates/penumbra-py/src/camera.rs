//! Explicit pinhole cameras from Python's (position, look_at, up, fov).

use glam::Vec3;
use penumbra::Camera;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// The library's camera, or a `ValueError` saying why there is none.
pub(crate) fn camera(
    position: [f32; 3],
    look_at: [f32; 3],
    up: [f32; 3],
    fov: f32,
) -> PyResult<Camera> {
    Camera::new(
        Vec3::from(position),
        Vec3::from(look_at),
        Vec3::from(up),
        fov,
    )
    .map_err(|e| PyValueError::new_err(e.to_string()))
}

/// Raises `ValueError` when the pinhole camera cannot exist (a degenerate frame, or the field
/// of view outside (0, 180) degrees).
#[pyfunction]
pub fn check_camera(position: [f32; 3], look_at: [f32; 3], up: [f32; 3], fov: f32) -> PyResult<()> {
    camera(position, look_at, up, fov).map(|_| ())
}
