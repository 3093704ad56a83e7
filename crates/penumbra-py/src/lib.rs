//! The `penumbra._core` Python extension module: a thin layer over the `penumbra` library.
//! It converts arguments and results between Python and Rust, releases the GIL while the
//! library works, and turns the library's errors into Python exceptions; it renders nothing
//! itself. The public Python API (`penumbra`) is the pure-Python package in `python/penumbra`,
//! which wraps these functions.

use pyo3::prelude::*;

mod built;
mod camera;
mod errors;
mod image;
mod interrupt;
mod layouts;
mod names;
mod pack;
mod raycast;
mod records;
mod render;
mod scene;
mod staged;

/// The compiled core of the `penumbra` package.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    // numpy's C API is looked up on first use, which runs Python code: done lazily, a Ctrl-C
    // arriving during that first lookup (say, the first image a batch writes) made the numpy
    // crate panic instead of raising KeyboardInterrupt. Look it up now, at import.
    numpy::PyArray1::<f32>::zeros(py, 0, false);
    m.add("SceneError", py.get_type::<errors::SceneError>())?;
    m.add_class::<scene::CoreScene>()?;
    m.add_class::<raycast::CoreRaycastingScene>()?;
    m.add_function(wrap_pyfunction!(raycast::create_rays_pinhole, m)?)?;
    m.add_function(wrap_pyfunction!(raycast::create_rays_pinhole_fov, m)?)?;
    m.add("INVALID_ID", penumbra::INVALID_ID)?;
    m.add_function(wrap_pyfunction!(scene::load, m)?)?;
    m.add_function(wrap_pyfunction!(scene::loads, m)?)?;
    m.add_function(wrap_pyfunction!(pack::load_pack, m)?)?;
    m.add_function(wrap_pyfunction!(names::file_name_part, m)?)?;
    m.add_function(wrap_pyfunction!(camera::check_camera, m)?)?;
    m.add_function(wrap_pyfunction!(camera::camera_pose, m)?)?;
    m.add_function(wrap_pyfunction!(camera::camera_rays, m)?)?;
    m.add_function(wrap_pyfunction!(image::write_image, m)?)?;
    m.add_function(wrap_pyfunction!(image::stage_image, m)?)?;
    m.add_function(wrap_pyfunction!(image::file_digest, m)?)?;
    m.add_class::<staged::Staged>()?;
    m.add_function(wrap_pyfunction!(staged::write_bytes, m)?)?;
    m.add_function(wrap_pyfunction!(staged::stage_npz, m)?)?;
    m.add_function(wrap_pyfunction!(records::record_path, m)?)?;
    m.add_function(wrap_pyfunction!(records::aov_path, m)?)?;
    m.add_function(wrap_pyfunction!(records::read_record, m)?)?;
    m.add_function(wrap_pyfunction!(records::record_intact, m)?)?;
    m.add_function(wrap_pyfunction!(records::record_finished, m)?)?;
    m.add_function(wrap_pyfunction!(records::write_record, m)?)?;
    m.add_function(wrap_pyfunction!(records::commit_view, m)?)?;
    m.add("MAX_RECORD_BYTES", records::MAX_RECORD_BYTES)?;
    m.add_function(wrap_pyfunction!(layouts::pose_frames, m)?)?;
    m.add_function(wrap_pyfunction!(layouts::poses_layout, m)?)?;
    m.add_function(wrap_pyfunction!(layouts::write_poses, m)?)?;
    m.add_function(wrap_pyfunction!(layouts::view_output_path, m)?)?;
    m.add_class::<layouts::CoreManifest>()?;
    m.add_function(wrap_pyfunction!(layouts::host_name, m)?)?;
    m.add_function(wrap_pyfunction!(layouts::peak_memory_bytes, m)?)?;
    m.add_function(wrap_pyfunction!(image::to_srgb8, m)?)?;
    m.add_function(wrap_pyfunction!(image::encode_png, m)?)?;
    m.add(
        "AOV_NAMES",
        penumbra::Aov::ALL.map(penumbra::Aov::name).to_vec(),
    )?;
    m.add("NO_ID", penumbra::NO_ID)?;
    m.add("MAX_THREADS", penumbra::MAX_THREADS)?;
    // The workspace's version, which maturin also gives the Python package.
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // Why PENUMBRA_SIMD cannot be honoured (a typo, or a path this CPU lacks), or None: the
    // package warns on import, since the library then runs the best path it has.
    let simd_problem = penumbra::forced_simd_path().err().map(|e| e.to_string());
    m.add("SIMD_ENV_PROBLEM", simd_problem)?;
    Ok(())
}
