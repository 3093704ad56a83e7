//! Packed scenes as plain Python values: a dict of the scene file's text and the bytes of every
//! file its build read, which pickles and travels to other processes and machines (Ray
//! workers), and the scene built again from it there without those files on disk.

use std::collections::BTreeMap;
use std::ffi::OsString;
use std::path::PathBuf;

use penumbra::{SceneFormat, ScenePack};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

use crate::built::{build, CoreScene};

/// The pack as a dict: `name`, `text`, `format` ("toml" or "json"), `base_dir`,
/// `overrides` (list of str), `allow_paths` (list of str: the folders its files may read in
/// besides their own) and `files` ({path: bytes}); paths as str (file system encoding).
pub(crate) fn to_dict<'py>(py: Python<'py>, pack: &ScenePack) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("name", pack.name.as_os_str())?;
    d.set_item("text", &pack.text)?;
    d.set_item(
        "format",
        match pack.format {
            SceneFormat::Toml => "toml",
            SceneFormat::Json => "json",
        },
    )?;
    d.set_item("base_dir", pack.base_dir.as_os_str())?;
    d.set_item("overrides", &pack.overrides)?;
    let allowed: Vec<&std::ffi::OsStr> = pack.allowed.iter().map(|p| p.as_os_str()).collect();
    d.set_item("allow_paths", allowed)?;
    let files = PyDict::new(py);
    for (path, bytes) in &pack.files {
        files.set_item(path.as_os_str(), PyBytes::new(py, bytes))?;
    }
    d.set_item("files", files)?;
    Ok(d)
}

/// Builds the scene of a pack dict (as `CoreScene.pack` makes them), reading nothing from
/// disk: its meshes and images come from the pack.
#[pyfunction]
#[pyo3(signature = (pack, threads = 0))]
pub fn load_pack(py: Python<'_>, pack: &Bound<'_, PyDict>, threads: usize) -> PyResult<CoreScene> {
    let item = |key: &str| {
        pack.get_item(key)?
            .ok_or_else(|| PyValueError::new_err(format!("a scene pack needs the key {key:?}")))
    };
    let format = match item("format")?.extract::<String>()?.as_str() {
        "toml" => SceneFormat::Toml,
        "json" => SceneFormat::Json,
        other => {
            return Err(PyValueError::new_err(format!(
                "unknown scene format {other:?} in a scene pack"
            )))
        }
    };
    // As bytes objects: one copy each, not a conversion byte by byte.
    let files: BTreeMap<OsString, Bound<'_, PyBytes>> = item("files")?.extract()?;
    let pack = ScenePack {
        name: PathBuf::from(item("name")?.extract::<OsString>()?),
        text: item("text")?.extract()?,
        format,
        base_dir: PathBuf::from(item("base_dir")?.extract::<OsString>()?),
        overrides: item("overrides")?.extract()?,
        // Absent from the packs of versions before it: none allowed.
        allowed: match pack.get_item("allow_paths")? {
            Some(paths) => paths.extract::<Vec<PathBuf>>()?,
            None => Vec::new(),
        },
        files: files
            .into_iter()
            .map(|(p, b)| (PathBuf::from(p), b.as_bytes().to_vec()))
            .collect(),
    };
    build(py, threads, move || pack.load())
}
