//! The other files of a batch, by the library's one layout each (`penumbra::products`): the
//! poses file (penumbra's layout or NeRF's `transforms.json`), the manifest's lines, and a
//! view's output name (expanded, and kept inside its pattern's folder). Frames and lines cross from
//! Python as JSON text.

use std::path::PathBuf;

use penumbra::products::manifest::{self, Manifest, ManifestLine};
use penumbra::products::output_name;
use penumbra::products::poses::{self, PoseFrame, PosesFormat};
use penumbra::CameraPose;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::camera::CameraSpec;
use crate::errors::product_error;
use crate::records::to_json;

/// One image of a poses file as Python gives it: its frame, its camera's (or view's) name,
/// its file, its camera and its width and height.
type FrameSpec = (Option<i64>, String, String, CameraSpec, u32, u32);

/// The frames (JSON text, a list of penumbra's layout's frames) of the images `specs`, as
/// `penumbra render --poses` makes them. Raises `ValueError` for a camera that cannot exist.
#[pyfunction]
pub fn pose_frames(specs: Vec<FrameSpec>) -> PyResult<String> {
    let frames = specs
        .into_iter()
        .map(|(frame, name, file, camera, w, h)| {
            let c = camera.camera((w, h))?;
            let pose = CameraPose::new(&c, w, h, (0, 0));
            Ok(PoseFrame::new(frame, &name, &file, &c, pose, (w, h)))
        })
        .collect::<PyResult<Vec<_>>>()?;
    to_json(&frames)
}

fn format_of(name: &str) -> PyResult<PosesFormat> {
    name.parse()
        .map_err(|e: penumbra::UnknownName| PyValueError::new_err(e.to_string()))
}

fn frames_of(text: &str) -> PyResult<Vec<PoseFrame>> {
    serde_json::from_str(text)
        .map_err(|e| PyValueError::new_err(format!("poses: frames of penumbra's layout, not: {e}")))
}

/// The poses file (JSON text) of `frames` (JSON text, see `pose_frames`) in `format`
/// (`penumbra` or `nerf`) for the file at `path` (NeRF's file paths are relative to its
/// folder).
#[pyfunction]
pub fn poses_layout(format: &str, frames: &str, path: PathBuf) -> PyResult<String> {
    let layout = poses::layout(format_of(format)?, &frames_of(frames)?, &path)
        .map_err(|e| product_error("poses_layout", e))?;
    Ok(layout.to_string())
}

/// Writes the poses of `frames` (JSON text, see `pose_frames`) to `path` in `format`, as
/// `penumbra render --poses` does: whole or not at all, its folder made when missing.
#[pyfunction]
pub fn write_poses(py: Python<'_>, path: PathBuf, format: &str, frames: &str) -> PyResult<()> {
    let (format, frames) = (format_of(format)?, frames_of(frames)?);
    py.detach(|| poses::write(&path, format, &frames))
        .map_err(|e| product_error("write_poses", e))
}

/// The file of the view `name`, number `index` of its batch, by the output `pattern`: its
/// `{name}` made one file name and its `{index}` counted from 0, by the library's expander
/// (`{index:04}` or Python's `{index:04d}`). Raises `ValueError` for a pattern that gives no
/// name, or one outside its folder (a `..` after a field).
#[pyfunction]
pub fn view_output_path(pattern: &str, name: &str, index: usize) -> PyResult<String> {
    use output_name::Value;
    let fields = [
        ("name", Ok(Value::Text(penumbra::file_name_part(name)))),
        ("index", Ok(Value::Number(index as i128))),
    ];
    let path = output_name::expand_fields(pattern, &fields)
        .and_then(|path| output_name::check_inside(pattern, path.as_ref()).map(|()| path));
    path.map_err(|e| PyValueError::new_err(format!("output pattern {e}")))
}

/// A manifest file open for appending (its folder made), as `penumbra render --manifest`
/// writes one: each line one `write`, so that processes sharing the file do not interleave.
#[pyclass(module = "penumbra._core", name = "Manifest")]
pub struct CoreManifest {
    file: Option<Manifest>,
}

#[pymethods]
impl CoreManifest {
    /// Opens `path`; an `OSError` saying that the manifest cannot be written names it.
    #[new]
    fn new(py: Python<'_>, path: PathBuf) -> PyResult<CoreManifest> {
        let file = py
            .detach(|| Manifest::open(&path))
            .map_err(|e| product_error("Manifest", e))?;
        Ok(CoreManifest { file: Some(file) })
    }

    /// Appends `line` (JSON text of a task's line: every key of the manifest's, no other).
    fn append(&mut self, py: Python<'_>, line: &str) -> PyResult<()> {
        let line: ManifestLine = serde_json::from_str(line)
            .map_err(|e| PyValueError::new_err(format!("not a manifest line: {e}")))?;
        let file = self
            .file
            .as_mut()
            .ok_or_else(|| PyValueError::new_err("the manifest is closed"))?;
        py.detach(|| file.append(&line))
            .map_err(|e| product_error("Manifest.append", e))
    }

    /// Closes the file.
    fn close(&mut self) {
        self.file = None;
    }
}

/// The machine's name, as the manifest's `host`.
#[pyfunction]
pub fn host_name() -> String {
    manifest::host_name()
}

/// This process's peak resident memory so far in bytes, as the manifest's
/// `peak_memory_bytes`; `None` where the system does not tell (Linux's VmHWM).
#[pyfunction]
pub fn peak_memory_bytes() -> Option<u64> {
    manifest::peak_memory_bytes()
}
