//! Ray casting from Python: [`CoreRaycastingScene`] holds a library `RaycastingScene` and runs
//! its batch queries with the GIL released (Ctrl-C stops them); arrays come in as flat
//! C-contiguous float32 rows (`penumbra.RaycastingScene` reshapes and converts them) and go
//! out as numpy arrays in dicts keyed as Open3D's results.

use std::sync::{RwLock, RwLockReadGuard, RwLockWriteGuard, TryLockError};

use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{Element, IntoPyArray, PyReadonlyArray2, PyUntypedArrayMethods};
use penumbra::{QueryOptions, RaycastError, RaycastingScene, World};
use pyo3::exceptions::{PyMemoryError, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::raycast_error;
use crate::interrupt::{interruptible, POLL};

/// Triangle meshes to cast rays against; see `penumbra.RaycastingScene`.
///
/// Frozen, the scene behind a lock: a query holds it shared while it runs with the GIL
/// released, and `add_triangles` from another thread meanwhile waits for the queries to end
/// (Ctrl-C still stops the wait) rather than failing with PyO3's "Already borrowed".
#[pyclass(module = "penumbra._core", frozen)]
pub struct CoreRaycastingScene {
    scene: RwLock<RaycastingScene>,
    /// Worker threads of a query whose own `nthreads` is 0 (0: one per core).
    threads: usize,
}

/// The argument a ray-casting error is about, as the Python API names it.
fn argument(e: &RaycastError) -> Option<&'static str> {
    Some(match e {
        RaycastError::IndexOutOfRange { .. } => "triangle_indices",
        RaycastError::NotFinite { .. } | RaycastError::Beyond { what: "vertex", .. } => {
            "vertex_positions"
        }
        RaycastError::Beyond { what: "ray", .. } => "rays",
        RaycastError::UnknownGeometry { .. } | RaycastError::NotAPlacement { .. } => "geometry_id",
        RaycastError::TransformNotFinite { .. }
        | RaycastError::TransformNotAffine
        | RaycastError::SingularTransform
        | RaycastError::Beyond {
            what: "placed vertex",
            ..
        } => "transform",
        RaycastError::Beyond { .. } => "query_points",
        RaycastError::InvalidSamples(_) => "nsamples",
        _ => return None,
    })
}

/// A ray-casting error of the call `call` as Python sees it, its message naming the call and
/// the argument: `MemoryError` for a result too large, `OSError` for threads that cannot
/// start, `KeyboardInterrupt` for a cancelled query, else `ValueError`.
pub(crate) fn call_error(call: &str, e: RaycastError) -> PyErr {
    let message = match argument(&e) {
        Some(arg) => format!("{call}: {arg}: {e}"),
        None => format!("{call}: {e}"),
    };
    match e {
        RaycastError::OutOfMemory { .. } => PyMemoryError::new_err(message),
        RaycastError::Threads(_) => PyOSError::new_err(message),
        RaycastError::Cancelled => raycast_error(e),
        _ => PyValueError::new_err(message),
    }
}

impl CoreRaycastingScene {
    /// The triangles of a built world, instances included, geometry id = object index.
    pub fn from_world(world: &World) -> Result<CoreRaycastingScene, RaycastError> {
        Ok(CoreRaycastingScene {
            scene: RwLock::new(RaycastingScene::from_world(world)?),
            threads: 0,
        })
    }

    /// The scene, shared with other queries.
    fn read(&self) -> RwLockReadGuard<'_, RaycastingScene> {
        self.scene.read().unwrap_or_else(|e| e.into_inner())
    }

    /// The scene alone, once the queries running from other threads are done: waited for
    /// without the GIL, checking for signals every [`POLL`].
    fn write(&self, py: Python<'_>) -> PyResult<RwLockWriteGuard<'_, RaycastingScene>> {
        loop {
            match self.scene.try_write() {
                Ok(scene) => return Ok(scene),
                Err(TryLockError::Poisoned(e)) => return Ok(e.into_inner()),
                Err(TryLockError::WouldBlock) => {
                    py.detach(|| std::thread::sleep(POLL));
                    py.check_signals()?;
                }
            }
        }
    }

    /// Runs `query` (the call `call`) on the scene with the GIL released and the thread count
    /// of the call.
    fn query<T: Send>(
        &self,
        py: Python<'_>,
        call: &str,
        nthreads: usize,
        query: impl FnOnce(&RaycastingScene, &QueryOptions) -> Result<T, RaycastError> + Send,
    ) -> PyResult<T> {
        let threads = if nthreads == 0 {
            self.threads
        } else {
            nthreads
        };
        if threads > penumbra::MAX_THREADS {
            return Err(PyValueError::new_err(format!(
                "{call}: nthreads must be from 0 to {}, not {threads}",
                penumbra::MAX_THREADS
            )));
        }
        let scene = &self.scene;
        interruptible(py, move |cancel| {
            let options = QueryOptions {
                threads,
                cancel: Some(cancel),
            };
            let scene = scene.read().unwrap_or_else(|e| e.into_inner());
            query(&scene, &options)
        })?
        .map_err(|e| call_error(call, e))
    }
}

/// The rows of an (n, N) C-contiguous array.
pub(crate) fn rows<'a, T: Element, const N: usize>(
    array: &'a PyReadonlyArray2<'_, T>,
    what: &str,
) -> PyResult<&'a [[T; N]]> {
    let cols = array.shape()[1];
    if cols != N {
        return Err(PyValueError::new_err(format!(
            "{what} must have shape (n, {N}), not (n, {cols})"
        )));
    }
    let flat = array
        .as_slice()
        .map_err(|_| PyValueError::new_err(format!("{what} must be C-contiguous")))?;
    Ok(flat.as_chunks::<N>().0)
}

/// A vector as a 1-D array.
fn vec1<T: Element>(py: Python<'_>, v: Vec<T>) -> Bound<'_, PyAny> {
    Array1::from_vec(v).into_pyarray(py).into_any()
}

/// A vector of rows as an (n, N) array.
pub(crate) fn vec2<T: Element, const N: usize>(
    py: Python<'_>,
    v: Vec<[T; N]>,
) -> PyResult<Bound<'_, PyAny>> {
    let n = v.len();
    Ok(Array2::from_shape_vec((n, N), v.into_flattened())
        .map_err(|e| PyValueError::new_err(e.to_string()))?
        .into_pyarray(py)
        .into_any())
}

/// Rays as an (height, width, 6) array.
fn ray_image(py: Python<'_>, rays: Vec<[f32; 6]>, w: u32, h: u32) -> PyResult<Bound<'_, PyAny>> {
    Ok(
        Array3::from_shape_vec((h as usize, w as usize, 6), rays.into_flattened())
            .map_err(|e| PyValueError::new_err(e.to_string()))?
            .into_pyarray(py)
            .into_any(),
    )
}

#[pymethods]
impl CoreRaycastingScene {
    /// An empty scene whose queries use `nthreads` workers unless they name their own.
    #[new]
    #[pyo3(signature = (nthreads = 0))]
    fn new(nthreads: usize) -> Self {
        CoreRaycastingScene {
            scene: RwLock::new(RaycastingScene::new()),
            threads: nthreads,
        }
    }

    /// Adds an (N, 3) float32 vertex array and an (M, 3) uint32 index array; returns the id.
    fn add_triangles(
        &self,
        py: Python<'_>,
        vertices: PyReadonlyArray2<'_, f32>,
        triangles: PyReadonlyArray2<'_, u32>,
    ) -> PyResult<u32> {
        let v = rows::<f32, 3>(&vertices, "vertex_positions")?;
        let t = rows::<u32, 3>(&triangles, "triangle_indices")?;
        let mut scene = self.write(py)?;
        scene
            .add_triangles(v, t)
            .map_err(|e| call_error("add_triangles", e))
    }

    /// Places geometry `geometry_id` by a row-major 4×4 object-to-world matrix (its
    /// triangles are not copied); returns the placement's id.
    fn add_instance(
        &self,
        py: Python<'_>,
        geometry_id: u32,
        transform: [[f32; 4]; 4],
    ) -> PyResult<u32> {
        let mut scene = self.write(py)?;
        scene
            .add_instance(geometry_id, &transform)
            .map_err(|e| call_error("add_instance", e))
    }

    /// Moves placement `geometry_id` to a row-major 4×4 object-to-world matrix.
    fn set_transform(
        &self,
        py: Python<'_>,
        geometry_id: u32,
        transform: [[f32; 4]; 4],
    ) -> PyResult<()> {
        let mut scene = self.write(py)?;
        scene
            .set_transform(geometry_id, &transform)
            .map_err(|e| call_error("set_transform", e))
    }

    /// Number of geometries added.
    #[getter]
    fn geometry_count(&self) -> u32 {
        self.read().geometry_count()
    }

    /// Number of triangles of all geometries.
    #[getter]
    fn triangle_count(&self) -> usize {
        self.read().triangle_count()
    }

    /// Closest hits of (n, 6) rays; `row_length` > 0 when they are the rows of an image,
    /// that many rays per row (the same results, traced in square packets).
    #[pyo3(signature = (rays, nthreads, row_length = 0, tnear = 0.0, tfar = f32::INFINITY))]
    fn cast_rays<'py>(
        &self,
        py: Python<'py>,
        rays: PyReadonlyArray2<'py, f32>,
        nthreads: usize,
        row_length: usize,
        tnear: f32,
        tfar: f32,
    ) -> PyResult<Bound<'py, PyDict>> {
        let rays = rows::<f32, 6>(&rays, "rays")?;
        let hits = self.query(py, "cast_rays", nthreads, |s, o| {
            s.cast_rays_between(rays, row_length, (tnear, tfar), o)
        })?;
        let d = PyDict::new(py);
        d.set_item("t_hit", vec1(py, hits.t_hit))?;
        d.set_item("geometry_ids", vec1(py, hits.geometry_ids))?;
        d.set_item("primitive_ids", vec1(py, hits.primitive_ids))?;
        d.set_item("primitive_uvs", vec2(py, hits.primitive_uvs)?)?;
        d.set_item("primitive_normals", vec2(py, hits.primitive_normals)?)?;
        Ok(d)
    }

    /// Whether each of (n, 6) rays meets a triangle with t in [tnear, tfar].
    fn test_occlusions<'py>(
        &self,
        py: Python<'py>,
        rays: PyReadonlyArray2<'py, f32>,
        tnear: f32,
        tfar: f32,
        nthreads: usize,
    ) -> PyResult<Bound<'py, PyAny>> {
        let rays = rows::<f32, 6>(&rays, "rays")?;
        let hit = self.query(py, "test_occlusions", nthreads, |s, o| {
            s.test_occlusions(rays, tnear, tfar, o)
        })?;
        Ok(vec1(py, hit))
    }

    /// Surface crossings of each of (n, 6) rays with t in [tnear, tfar], int32.
    #[pyo3(signature = (rays, nthreads, tnear = 0.0, tfar = f32::INFINITY))]
    fn count_intersections<'py>(
        &self,
        py: Python<'py>,
        rays: PyReadonlyArray2<'py, f32>,
        nthreads: usize,
        tnear: f32,
        tfar: f32,
    ) -> PyResult<Bound<'py, PyAny>> {
        let rays = rows::<f32, 6>(&rays, "rays")?;
        let counts = self.query(py, "count_intersections", nthreads, |s, o| {
            s.count_intersections_between(rays, (tnear, tfar), o)
        })?;
        Ok(vec1(py, counts))
    }

    /// Every crossing of (n, 6) rays, as Open3D lists them.
    fn list_intersections<'py>(
        &self,
        py: Python<'py>,
        rays: PyReadonlyArray2<'py, f32>,
        nthreads: usize,
    ) -> PyResult<Bound<'py, PyDict>> {
        let rays = rows::<f32, 6>(&rays, "rays")?;
        let all = self.query(py, "list_intersections", nthreads, |s, o| {
            s.list_intersections(rays, o)
        })?;
        let d = PyDict::new(py);
        d.set_item("ray_splits", vec1(py, all.ray_splits))?;
        d.set_item("ray_ids", vec1(py, all.ray_ids))?;
        d.set_item("t_hit", vec1(py, all.t_hit))?;
        d.set_item("geometry_ids", vec1(py, all.geometry_ids))?;
        d.set_item("primitive_ids", vec1(py, all.primitive_ids))?;
        d.set_item("primitive_uvs", vec2(py, all.primitive_uvs)?)?;
        Ok(d)
    }

    /// Closest surface points of (n, 3) query points.
    fn compute_closest_points<'py>(
        &self,
        py: Python<'py>,
        points: PyReadonlyArray2<'py, f32>,
        nthreads: usize,
    ) -> PyResult<Bound<'py, PyDict>> {
        let points = rows::<f32, 3>(&points, "query_points")?;
        let near = self.query(py, "compute_closest_points", nthreads, |s, o| {
            s.compute_closest_points(points, o)
        })?;
        let d = PyDict::new(py);
        d.set_item("points", vec2(py, near.points)?)?;
        d.set_item("geometry_ids", vec1(py, near.geometry_ids))?;
        d.set_item("primitive_ids", vec1(py, near.primitive_ids))?;
        d.set_item("primitive_uvs", vec2(py, near.primitive_uvs)?)?;
        d.set_item("primitive_normals", vec2(py, near.primitive_normals)?)?;
        Ok(d)
    }

    /// Distances of (n, 3) query points to the surface.
    fn compute_distance<'py>(
        &self,
        py: Python<'py>,
        points: PyReadonlyArray2<'py, f32>,
        nthreads: usize,
    ) -> PyResult<Bound<'py, PyAny>> {
        let points = rows::<f32, 3>(&points, "query_points")?;
        let d = self.query(py, "compute_distance", nthreads, |s, o| {
            s.compute_distance(points, o)
        })?;
        Ok(vec1(py, d))
    }

    /// Signed distances of (n, 3) query points, negative inside.
    fn compute_signed_distance<'py>(
        &self,
        py: Python<'py>,
        points: PyReadonlyArray2<'py, f32>,
        nthreads: usize,
        nsamples: u32,
    ) -> PyResult<Bound<'py, PyAny>> {
        let points = rows::<f32, 3>(&points, "query_points")?;
        let d = self.query(py, "compute_signed_distance", nthreads, |s, o| {
            s.compute_signed_distance(points, nsamples, o)
        })?;
        Ok(vec1(py, d))
    }

    /// Occupancy (1.0 inside, 0.0 outside) of (n, 3) query points.
    fn compute_occupancy<'py>(
        &self,
        py: Python<'py>,
        points: PyReadonlyArray2<'py, f32>,
        nthreads: usize,
        nsamples: u32,
    ) -> PyResult<Bound<'py, PyAny>> {
        let points = rows::<f32, 3>(&points, "query_points")?;
        let d = self.query(py, "compute_occupancy", nthreads, |s, o| {
            s.compute_occupancy(points, nsamples, o)
        })?;
        Ok(vec1(py, d))
    }
}

/// The (height, width, 6) rays of a camera given by its intrinsic and extrinsic matrices.
#[pyfunction]
pub fn create_rays_pinhole(
    py: Python<'_>,
    intrinsic: [[f64; 3]; 3],
    extrinsic: [[f64; 4]; 4],
    width: u32,
    height: u32,
) -> PyResult<Bound<'_, PyAny>> {
    let rays = py
        .detach(|| penumbra::create_rays_pinhole(intrinsic, extrinsic, width, height))
        .map_err(|e| call_error("create_rays_pinhole", e))?;
    ray_image(py, rays, width, height)
}

/// The (height, width, 6) rays of a camera at `eye` looking at `center`.
#[pyfunction]
pub fn create_rays_pinhole_fov(
    py: Python<'_>,
    fov_deg: f64,
    center: [f64; 3],
    eye: [f64; 3],
    up: [f64; 3],
    width: u32,
    height: u32,
) -> PyResult<Bound<'_, PyAny>> {
    let rays = py
        .detach(|| penumbra::create_rays_pinhole_fov(fov_deg, center, eye, up, width, height))
        .map_err(|e| call_error("create_rays_pinhole", e))?;
    ray_image(py, rays, width, height)
}
