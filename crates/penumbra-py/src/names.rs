//! Names inside file names, by the library's one rule (`penumbra::file_name_part`): what
//! `penumbra.views.output_path` puts for `{name}`, as the command line puts it for `{camera}`.

use pyo3::prelude::*;

/// `name` as a part of one file name: path separators, `:` and control characters become
/// `_`, and so does a leading `.` or `-`; an empty name is `_`.
#[pyfunction]
pub fn file_name_part(name: &str) -> String {
    penumbra::file_name_part(name)
}
