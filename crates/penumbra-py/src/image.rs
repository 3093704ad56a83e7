//! Images from arrays: writing an (H, W, 3) float32 array (or (H, W, 4) premultiplied RGBA)
//! with the library's atomic image writer, and its 8-bit encoding (the bytes the CLI puts in
//! a PNG).

use std::path::PathBuf;

use numpy::ndarray::Array3;
use numpy::{IntoPyArray, PyArray3, PyReadonlyArray3};
use penumbra::{encode_image, film_codes, Film, ImageError, OutputFormat, Rgb};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::errors::{buffer, image_error, write_error};
use crate::staged::Staged;

/// The pixels of an (H, W, 3) float32 array as a film, or of an (H, W, 4) one as a film
/// with alpha (RGB premultiplied, as `render(alpha=True)` returns it).
fn film(call: &str, array: &PyReadonlyArray3<'_, f32>) -> PyResult<Film> {
    let view = array.as_array();
    let (h, w, c) = view.dim();
    if !(c == 3 || c == 4) || h == 0 || w == 0 {
        return Err(PyValueError::new_err(format!(
            "an image is a non-empty (height, width, 3) or (height, width, 4) array, not shape ({h}, {w}, {c})"
        )));
    }
    let (width, height) = (
        u32::try_from(w).map_err(|_| PyValueError::new_err("image too wide"))?,
        u32::try_from(h).map_err(|_| PyValueError::new_err("image too high"))?,
    );
    let what = format!("a {width}x{height} image");
    let mut pixels = buffer(call, &what, w * h)?;
    for row in view.outer_iter() {
        pixels.extend(row.outer_iter().map(|p| Rgb::new(p[0], p[1], p[2])));
    }
    let alpha = match c {
        4 => {
            let mut alpha = buffer(call, &what, w * h)?;
            // The fourth of each pixel's values, in the array's logical order.
            alpha.extend(view.iter().skip(3).step_by(4));
            Some(alpha)
        }
        _ => None,
    };
    Ok(Film {
        width,
        height,
        pixels,
        alpha,
    })
}

/// Writes an (H, W, 3) float32 linear RGB array to `path` in the format its extension names
/// (PNG, JPEG, EXR, PFM), atomically, as the command line writes images.
#[pyfunction]
#[pyo3(signature = (path, array, gamma = None))]
pub fn write_image(
    py: Python<'_>,
    path: PathBuf,
    array: PyReadonlyArray3<'_, f32>,
    gamma: Option<f32>,
) -> PyResult<()> {
    ImageError::check_gamma(gamma).map_err(|e| image_error("write_image", e))?;
    let film = film("write_image", &array)?;
    py.detach(|| penumbra::write_image(&film, &path, gamma))
        .map_err(|e| write_error("write_image", e))
}

/// Stages an (H, W, 3) float32 linear RGB array for `path` (its extension names the format)
/// under a temporary name beside it, as the command line stages an image, for `commit_view`
/// to rename into place with the files that go with it (a batch's AOVs and record). Errors
/// name `path`.
#[pyfunction]
#[pyo3(signature = (path, array, gamma = None))]
pub fn stage_image(
    py: Python<'_>,
    path: PathBuf,
    array: PyReadonlyArray3<'_, f32>,
    gamma: Option<f32>,
) -> PyResult<Staged> {
    ImageError::check_gamma(gamma).map_err(|e| image_error("write_image", e))?;
    let film = film("write_image", &array)?;
    py.detach(|| {
        let never = std::sync::atomic::AtomicBool::new(false);
        penumbra::stage_image(&film, &path, gamma, &never)
    })
    .map(Staged::from)
    .map_err(|e| write_error("write_image", e))
}

/// The size and FNV-1a digest (16 hex digits) of the regular file at `path`, as records keep
/// them beside `files`.
#[pyfunction]
pub fn file_digest(py: Python<'_>, path: PathBuf) -> PyResult<(u64, String)> {
    py.detach(|| penumbra::FileDigest::of_file(&path))
        .map(|d| (d.bytes, d.hex()))
        .map_err(|e| pyo3::exceptions::PyOSError::new_err(format!("{}: {e}", path.display())))
}

/// The 8-bit encoding of an (H, W, 3) float32 linear RGB array: clamped to [0, 1], then the
/// sRGB curve (or `c^(1/gamma)`, for a positive finite gamma), rounded; the bytes the
/// command line writes to a PNG. An (H, W, 4) premultiplied RGBA array gives the PNG's
/// straight RGBA: the colour divided by alpha, then encoded; alpha linear.
#[pyfunction]
#[pyo3(signature = (array, gamma = None))]
pub fn to_srgb8<'py>(
    py: Python<'py>,
    array: PyReadonlyArray3<'py, f32>,
    gamma: Option<f32>,
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    ImageError::check_gamma(gamma).map_err(|e| image_error("to_srgb8", e))?;
    let dim = array.as_array().dim();
    let film = film("to_srgb8", &array)?;
    let bytes = py.detach(|| film_codes(&film, gamma));
    let out =
        Array3::from_shape_vec(dim, bytes).map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(out.into_pyarray(py))
}

/// The PNG file (bytes) of an (H, W, 3) float32 linear RGB array, encoded as `to_srgb8`
/// encodes it: what `penumbra.display` shows in a notebook.
#[pyfunction]
#[pyo3(signature = (array, gamma = None))]
pub fn encode_png<'py>(
    py: Python<'py>,
    array: PyReadonlyArray3<'py, f32>,
    gamma: Option<f32>,
) -> PyResult<Bound<'py, PyBytes>> {
    ImageError::check_gamma(gamma).map_err(|e| image_error("encode_png", e))?;
    let film = film("encode_png", &array)?;
    let bytes = py
        .detach(|| encode_image(&film, OutputFormat::Png, gamma))
        .map_err(|e| image_error("encode_png", e))?;
    Ok(PyBytes::new(py, &bytes))
}
