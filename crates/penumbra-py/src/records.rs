//! The record beside an image (`out.png` → `out.meta.json`), made, written and read back by
//! `penumbra::products::record`, as the command line's `--meta` and `--resume` do: Python's
//! `penumbra.record` and its batches call these. Records cross to Python as JSON text, every
//! number to the bit.

use std::path::{Path, PathBuf};

use penumbra::products::record::{self, Record};
use penumbra::products::{aov_files, RecordSettings, RenderRecord};
use penumbra::{CameraPose, OutputFormat, RenderError, View};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::built::CoreScene;
use crate::errors::{product_error, render_error};
use crate::render::Request;
use crate::staged::Staged;

/// The largest record read back.
pub const MAX_RECORD_BYTES: u64 = record::MAX_RECORD_BYTES;

/// `text` as a `T`, or a `ValueError` saying that it is no `what`.
fn parse<T: serde::de::DeserializeOwned>(text: &str, what: &str) -> PyResult<T> {
    serde_json::from_str(text).map_err(|e| PyValueError::new_err(format!("not {what}: {e}")))
}

/// `value` as JSON text.
pub(crate) fn to_json(value: &impl serde::Serialize) -> PyResult<String> {
    serde_json::to_string(value).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// The record (JSON text) of `scene` rendered with the keyword arguments of `render`
/// (`kwargs`: camera, settings, aovs) to `image`, named `view`, without digests: see
/// `CoreScene.record`.
pub(crate) fn make(
    py: Python<'_>,
    scene: &CoreScene,
    image: &Path,
    view: Option<String>,
    scene_digest: Option<String>,
    kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<String> {
    let format = OutputFormat::from_path(image).ok_or_else(|| {
        let ext = image.extension().map_or("none".to_owned(), |e| {
            format!(".{}", e.to_string_lossy().to_lowercase())
        });
        PyValueError::new_err(format!(
            "{}: a record's image is .png, .jpg, .jpeg, .exr or .pfm, not '{ext}'",
            image.display()
        ))
    })?;
    let request = Request::from_kwargs(kwargs)?;
    let settings_error = |e| render_error(RenderError::Settings(e));
    let mut settings = request.settings(&scene.settings, scene.file_samples)?;
    // No camera is the scene's first, by name, as the command line records it.
    if let (View::First, Some((name, _))) = (&settings.view, scene.world.cameras().first()) {
        settings.view = View::Named(name.clone());
    }
    let camera = settings.view.camera(&scene.world).map_err(settings_error)?;
    let size = (settings.width, settings.height);
    let aovs: Vec<String> = request.aovs.iter().map(|a| a.name().to_owned()).collect();
    let recorded = RecordSettings {
        penumbra: env!("CARGO_PKG_VERSION").to_owned(),
        scene_digest: scene_digest.unwrap_or_else(|| scene.digest(py)),
        camera: match &settings.view {
            View::Named(name) => Some(name.clone()),
            _ => None,
        },
        frame: None,
        render: RenderRecord::of(&settings),
        region: None,
        aovs,
        gamma: scene.gamma,
        format: format.extension().to_owned(),
    };
    let pose = CameraPose::new(&camera, size.0, size.1, (0, 0));
    let objects = record::objects(&scene.file, &scene.objects);
    let mut value = Record::new(recorded, image, size, Some(pose), objects);
    if !request.aovs.is_empty() {
        let npz = aov_files::npz_path(image);
        value.files.push(npz.display().to_string());
    }
    value.view = view;
    to_json(&value)
}

/// Where the record of the image at `image` goes: `out/a.png` → `out/a.meta.json`.
#[pyfunction]
pub fn record_path(image: PathBuf) -> PathBuf {
    record::path_of(&image)
}

/// Where a batch puts the AOVs of the image at `image`: `out/a.png` → `out/a.aovs.npz`.
#[pyfunction]
pub fn aov_path(image: PathBuf) -> PathBuf {
    aov_files::npz_path(&image)
}

/// The record at `path` as JSON text, or `None` when there is none that can be read: missing,
/// not a regular file (never opened), larger than `MAX_RECORD_BYTES`, or not JSON.
#[pyfunction]
pub fn read_record(py: Python<'_>, path: PathBuf) -> Option<String> {
    py.detach(|| record::read(&path).ok())
        .map(|value| value.to_string())
}

/// True when every file the record (JSON text) lists is a regular file of the size and
/// digest it keeps.
#[pyfunction]
pub fn record_intact(py: Python<'_>, record: &str) -> PyResult<bool> {
    let value: serde_json::Value = parse(record, "JSON")?;
    Ok(py.detach(|| record::intact(&value)))
}

/// The files of the image at `image` (the image, then its AOV file) when it is done: its
/// record was made with exactly `settings` (JSON text, a record's `settings`) and every file
/// it lists is intact; `None` otherwise.
#[pyfunction]
pub fn record_finished(
    py: Python<'_>,
    image: PathBuf,
    settings: &str,
) -> PyResult<Option<Vec<PathBuf>>> {
    let settings: RecordSettings = parse(settings, "a record's settings")?;
    Ok(py.detach(|| record::finished(&image, &settings)))
}

/// Writes the record (JSON text) beside its image, whole or not at all; returns its path.
#[pyfunction]
pub fn write_record(py: Python<'_>, record: &str) -> PyResult<PathBuf> {
    let value: Record = parse(record, "a record")?;
    py.detach(|| record::write(&value))
        .map_err(|e| product_error("write_record", e))
}

/// Renames a view's staged files into place together: the files `beside` its `image` (its
/// `.aovs.npz`), the image, then its `record` (JSON text, listing them with their sizes and
/// digests) when given; the old record is removed first (see
/// `penumbra::products::record::commit_with_record`).
#[pyfunction]
#[pyo3(signature = (image, beside, record = None))]
pub fn commit_view(
    py: Python<'_>,
    image: &Bound<'_, Staged>,
    beside: Vec<Bound<'_, Staged>>,
    record: Option<&str>,
) -> PyResult<()> {
    let record: Option<Record> = record.map(|r| parse(r, "a record")).transpose()?;
    let image = image.borrow_mut().take()?;
    let beside = beside
        .iter()
        .map(|f| f.borrow_mut().take())
        .collect::<PyResult<Vec<_>>>()?;
    py.detach(|| record::commit_with_record(image, beside, record))
        .map_err(|e| product_error("write_view", e))
}
