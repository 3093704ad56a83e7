//! Files that appear whole or not at all, for every file Python writes: the library's
//! [`penumbra::StagedFile`] (written under a temporary name in its destination's folder,
//! synced, then renamed into place) as the Python class `StagedFile`, and the writers of whole
//! files (`write_bytes`) and of a view's `.aovs.npz` (`stage_npz`). Errors name the file asked
//! for, never its temporary name.

use std::path::PathBuf;

use numpy::{PyReadonlyArrayDyn, PyUntypedArrayMethods};
use penumbra::products::{aov_files, NpyArray, NpyData};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{product_error, write_error};

/// A file staged for its destination and not yet in place: `commit_view` renames it, and
/// dropping it (or `discard()`) removes it.
#[pyclass(module = "penumbra._core", name = "StagedFile")]
pub struct Staged {
    file: Option<penumbra::StagedFile>,
    path: PathBuf,
}

impl Staged {
    /// The staged file, taken: renamed into place or removed by its new owner.
    pub(crate) fn take(&mut self) -> PyResult<penumbra::StagedFile> {
        self.file.take().ok_or_else(|| {
            PyValueError::new_err(format!(
                "{}: this staged file was committed or discarded already",
                self.path.display()
            ))
        })
    }
}

impl From<penumbra::StagedFile> for Staged {
    fn from(file: penumbra::StagedFile) -> Staged {
        Staged {
            path: file.path().to_owned(),
            file: Some(file),
        }
    }
}

#[pymethods]
impl Staged {
    /// Where the file goes.
    #[getter]
    fn path(&self) -> PathBuf {
        self.path.clone()
    }

    /// Removes the temporary file (nothing when it was committed or discarded already).
    fn discard(&mut self) {
        self.file = None;
    }
}

/// Writes `data` to `path`, whole or not at all (the folder must exist).
#[pyfunction]
pub fn write_bytes(py: Python<'_>, path: PathBuf, data: Vec<u8>) -> PyResult<()> {
    py.detach(|| penumbra::StagedFile::write_bytes(&path, &data)?.commit())
        .map_err(|e| write_error("write_bytes", e))
}

/// Stages the AOVs `arrays` (name → float32 or uint32 array) as the NumPy `.npz` at `path`,
/// as `numpy.savez` writes one (see `penumbra::products::aov_files::stage_npz`).
#[pyfunction]
pub fn stage_npz(py: Python<'_>, path: PathBuf, arrays: &Bound<'_, PyDict>) -> PyResult<Staged> {
    let mut named = Vec::with_capacity(arrays.len());
    for (name, value) in arrays.iter() {
        let name: String = name.extract()?;
        named.push((name.clone(), npy(&name, &value)?));
    }
    py.detach(|| aov_files::stage_npz(&path, &named))
        .map(Staged::from)
        .map_err(|e| product_error("stage_npz", e))
}

/// The values of a float32 or uint32 array, in C order, with its shape.
fn npy(name: &str, value: &Bound<'_, PyAny>) -> PyResult<NpyArray> {
    if let Ok(a) = value.extract::<PyReadonlyArrayDyn<'_, f32>>() {
        let data = NpyData::F32(a.as_array().iter().copied().collect());
        return Ok(NpyArray {
            shape: a.shape().to_vec(),
            data,
        });
    }
    if let Ok(a) = value.extract::<PyReadonlyArrayDyn<'_, u32>>() {
        let data = NpyData::U32(a.as_array().iter().copied().collect());
        return Ok(NpyArray {
            shape: a.shape().to_vec(),
            data,
        });
    }
    let what = match value.getattr("dtype") {
        Ok(dtype) => format!("a {} array", dtype.str()?),
        Err(_) => value.get_type().name()?.to_string(),
    };
    Err(PyTypeError::new_err(format!(
        "AOV {name:?}: a float32 or uint32 numpy array, not {what}"
    )))
}
