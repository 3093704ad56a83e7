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

/// [`camera`], on a film of `width × height` pixels: `ValueError` for an empty one.
fn film_camera(
    position: [f32; 3],
    look_at: [f32; 3],
    up: [f32; 3],
    fov: f32,
    (width, height): (u32, u32),
) -> PyResult<Camera> {
    if width == 0 || height == 0 {
        return Err(PyValueError::new_err(format!(
            "a {width}x{height} film has no pixels"
        )));
    }
    camera(position, look_at, up, fov)
}

/// The camera's intrinsics and poses on a `width × height` film (see `penumbra::CameraPose`
/// and docs/spec.md §10): K, camera_to_world (OpenCV axes), camera_to_world_opengl and
/// world_to_camera, each a list of rows. Raises `ValueError` as [`check_camera`] does, and
/// for an empty film.
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn camera_pose(
    position: [f32; 3],
    look_at: [f32; 3],
    up: [f32; 3],
    fov: f32,
    width: u32,
    height: u32,
) -> PyResult<(
    penumbra::Mat3Rows,
    penumbra::Mat4Rows,
    penumbra::Mat4Rows,
    penumbra::Mat4Rows,
)> {
    let c = film_camera(position, look_at, up, fov, (width, height))?;
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
/// direction, row 0 at the top. Raises `ValueError` as [`camera_pose`] does.
#[pyfunction]
pub fn camera_rays<'py>(
    py: Python<'py>,
    position: [f32; 3],
    look_at: [f32; 3],
    up: [f32; 3],
    fov: f32,
    width: u32,
    height: u32,
) -> PyResult<Bound<'py, numpy::PyArray3<f32>>> {
    use numpy::IntoPyArray;
    let c = film_camera(position, look_at, up, fov, (width, height))?;
    let pinhole = penumbra::FilmCamera::new(&c, width, height);
    let (w, h) = (width as usize, height as usize);
    let rays = py.detach(|| {
        let no_memory = || crate::errors::no_memory("camera_rays", "the rays");
        let len = h.checked_mul(w).and_then(|n| n.checked_mul(6));
        let mut rows = Vec::new();
        rows.try_reserve_exact(len.ok_or_else(no_memory)?)
            .map_err(|_| no_memory())?;
        for y in 0..h {
            for x in 0..w {
                let ray = pinhole
                    .ray(x as f32 + 0.5, y as f32 + 0.5)
                    .expect("a pinhole sees every film point");
                rows.extend(ray.origin.to_array());
                rows.extend(ray.direction.to_array());
            }
        }
        numpy::ndarray::Array3::from_shape_vec((h, w, 6), rows)
            .map_err(|e| PyValueError::new_err(e.to_string()))
    })?;
    Ok(rays.into_pyarray(py))
}
