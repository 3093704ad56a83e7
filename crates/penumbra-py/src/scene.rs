//! Loading scenes: `load` and `loads` parse and build a scene with the GIL released, into a
//! [`CoreScene`] (see `built`), and the scene's methods as Python sees them.

use std::path::PathBuf;

use numpy::PyReadonlyArray2;
use penumbra::{ObjectIndex, SceneFile, SceneFormat, View};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::built::build;
pub use crate::built::CoreScene;
use crate::raycast::{call_error, rows, vec2, CoreRaycastingScene};
use crate::render::{render_scene, CameraArgs, Request};

/// An object of a scene file: its position in `objects`, or its `name`.
#[derive(FromPyObject)]
pub(crate) enum ObjectRef {
    Index(usize),
    Name(String),
}

/// Loads and builds the `.toml` or `.json` scene file at `path`, or the scene of a bare
/// `.obj` or `.ply` mesh (see `SceneFile::for_model`); its files may also read in the
/// folders `allow_paths` (see `SceneFile::load_allowing`).
#[pyfunction]
#[pyo3(signature = (path, threads = 0, allow_paths = Vec::new()))]
pub fn load(
    py: Python<'_>,
    path: PathBuf,
    threads: usize,
    allow_paths: Vec<PathBuf>,
) -> PyResult<CoreScene> {
    build(py, threads, || {
        SceneFile::load_allowing(&path, &[], allow_paths)
    })
}

/// Parses and builds scene text in `format` ("toml" or "json"); `name` names it in messages
/// and relative paths resolve against `base_dir`, the folder its files may read in (and below,
/// and in `allow_paths`).
#[pyfunction]
#[pyo3(signature = (text, format = "toml", base_dir = PathBuf::from("."), name = "<string>".to_owned(), threads = 0, allow_paths = Vec::new()))]
pub fn loads(
    py: Python<'_>,
    text: String,
    format: &str,
    base_dir: PathBuf,
    name: String,
    threads: usize,
    allow_paths: Vec<PathBuf>,
) -> PyResult<CoreScene> {
    let format = match format.to_ascii_lowercase().as_str() {
        "toml" => SceneFormat::Toml,
        "json" => SceneFormat::Json,
        other => {
            return Err(PyValueError::new_err(format!(
                "unknown scene format {other:?} (use \"toml\" or \"json\")"
            )))
        }
    };
    build(py, threads, move || {
        let files = penumbra::Files::disk().allowing(allow_paths);
        SceneFile::from_str(&text, format, name, base_dir).map(|file| file.with_files(files))
    })
}

#[pymethods]
impl CoreScene {
    /// Renders with the file's settings changed by the keyword arguments given; see
    /// `penumbra.Scene.render`.
    #[pyo3(signature = (**kwargs))]
    fn render<'py>(
        &self,
        py: Python<'py>,
        kwargs: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let request = Request::from_kwargs(kwargs)?;
        render_scene(py, &self.world, &self.settings, self.file_samples, request)
    }

    /// This scene with object `object` placed by `matrix` (by rows) instead of its own
    /// transform, or for an `instances` object with `placement`, that copy's placement (see
    /// `penumbra::SceneFile::with_transform`), as a fresh load of the file with that
    /// transform builds it (see `CoreScene::with_move` in `built`).
    #[pyo3(signature = (object, matrix, placement = None, threads = 0))]
    fn moved(
        &self,
        py: Python<'_>,
        object: ObjectRef,
        matrix: [[f64; 4]; 4],
        placement: Option<usize>,
        threads: usize,
    ) -> PyResult<CoreScene> {
        let object = match object {
            ObjectRef::Index(i) => i,
            ObjectRef::Name(name) => {
                (self.file.object_index(&name)).map_err(|e| crate::errors::scene_error(py, e))?
            }
        };
        self.with_move(py, object, placement, matrix, threads)
    }

    /// A ray-casting scene of the world's triangles, instances placed (their meshes' trees
    /// shared, not copied), geometry id = object index.
    fn raycasting_scene(&self, py: Python<'_>) -> PyResult<CoreRaycastingScene> {
        py.detach(|| CoreRaycastingScene::from_world(&self.world))
            .map_err(|e| call_error("Scene.raycasting_scene", e))
    }

    /// The surface attributes (`albedo`, `shading_normal`, `uv`: (n, 3), (n, 3), (n, 2)
    /// float32) of ray-casting hits on this scene's triangles, given as `raycasting_scene()`
    /// names them: (n, 1) geometry ids (object ids), (n, 1) primitive ids and (n, 2)
    /// barycentric weights. Zero where the scene has no such triangle (a miss, or a geometry
    /// added to the ray-casting scene later).
    fn surface_attributes<'py>(
        &self,
        py: Python<'py>,
        geometry_ids: PyReadonlyArray2<'py, u32>,
        primitive_ids: PyReadonlyArray2<'py, u32>,
        primitive_uvs: PyReadonlyArray2<'py, f32>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let g = rows::<u32, 1>(&geometry_ids, "geometry_ids")?;
        let p = rows::<u32, 1>(&primitive_ids, "primitive_ids")?;
        let b = rows::<f32, 2>(&primitive_uvs, "primitive_uvs")?;
        if g.len() != p.len() || g.len() != b.len() {
            return Err(PyValueError::new_err(format!(
                "surface_attributes: {}, {} and {} ids and weights",
                g.len(),
                p.len(),
                b.len()
            )));
        }
        let world = &self.world;
        let (albedo, normal, uv) = py.detach(|| {
            let index = self.object_index.get_or_init(|| ObjectIndex::new(world));
            let mut out = (Vec::new(), Vec::new(), Vec::new());
            for ((g, p), b) in g.iter().zip(p).zip(b) {
                let a = world.surface_attributes(index, g[0], p[0], *b);
                out.0.push(a.map_or([0.0; 3], |a| a.albedo.to_array()));
                out.1
                    .push(a.map_or([0.0; 3], |a| a.shading_normal.to_array()));
                out.2.push(a.map_or([0.0; 2], |a| a.uv.to_array()));
            }
            out
        });
        let d = PyDict::new(py);
        d.set_item("albedo", vec2(py, albedo)?)?;
        d.set_item("shading_normal", vec2(py, normal)?)?;
        d.set_item("uv", vec2(py, uv)?)?;
        Ok(d)
    }

    /// The record (JSON text, see `penumbra::products::record`) of the image `image` that a
    /// render with these keyword arguments (those of `render`: the camera, the settings, the
    /// AOVs) makes, as `penumbra render --meta` writes it, without digests: its `settings`
    /// (the render's resolved against the file's, by name, every number to the bit; no camera
    /// is the first, by name), the image's files (the image, then its `.aovs.npz` when there
    /// are AOVs), size, K and poses, the objects' ids, and `view`. `scene_digest` saves
    /// computing it again. Raises `ValueError` for an image whose extension names no format
    /// and as `render` does for bad settings.
    #[pyo3(signature = (image, view = None, scene_digest = None, **kwargs))]
    fn record(
        &self,
        py: Python<'_>,
        image: PathBuf,
        view: Option<String>,
        scene_digest: Option<String>,
        kwargs: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<String> {
        crate::records::make(py, self, &image, view, scene_digest, kwargs)
    }

    /// The camera `name` (None: the first, the default) as (position, look_at, up, fov);
    /// `None` for a name the scene lacks. A camera with keys or a path gives its first
    /// frame's, the camera a render of the name uses.
    /// Raises `ValueError` for a camera given by an intrinsic matrix `K`, a lens model other
    /// than the pinhole or an aperture, which Python's `Camera` cannot hold yet (it renders
    /// by name).
    #[pyo3(signature = (name = None))]
    fn camera(&self, name: Option<&str>) -> PyResult<Option<CameraArgs>> {
        let view = name.map_or(View::First, |n| View::Named(n.to_owned()));
        let Ok(camera) = view.camera(&self.world) else {
            return Ok(None);
        };
        if !camera.sees_by_fov() {
            return Err(PyValueError::new_err(format!(
                "camera {} sees through an intrinsic matrix K, a lens model or an aperture, \
                 which penumbra.Camera cannot hold yet: render it by its name \
                 (render(camera=...))",
                name.map_or("(the first)".to_owned(), |n| format!("{n:?}"))
            )));
        }
        let [p, l, u] = [camera.position(), camera.look_at(), camera.up()].map(|v| v.to_array());
        Ok(Some((p, l, u, camera.fov_y_deg())))
    }

    /// The file's `film.gamma`: 8-bit images encode `c^(1/gamma)`; `None` for the sRGB curve.
    #[getter]
    fn gamma(&self) -> Option<f32> {
        self.gamma
    }

    /// The digest of the scene's text and every file its build read, as `penumbra render
    /// --meta` records it (see `penumbra::SceneFile::digest`).
    #[getter]
    fn scene_digest(&self, py: Python<'_>) -> String {
        self.digest(py)
    }

    /// For each `objects` entry, in file order, its first object id and how many it added.
    #[getter]
    fn object_ids(&self) -> Vec<(u32, u32)> {
        self.objects.iter().map(|r| (r.start, r.end)).collect()
    }

    /// The `objects` entries (JSON text) as records beside images list them: `key`, `name`
    /// (when it has one), `type` and `ids` (see `penumbra::products::record::objects`).
    #[getter]
    fn objects(&self) -> PyResult<String> {
        crate::records::to_json(&penumbra::products::record::objects(
            &self.file,
            &self.objects,
        ))
    }

    /// The files the build read besides the scene file (meshes, MTL libraries, images).
    #[getter]
    fn files(&self) -> Vec<PathBuf> {
        self.files.clone()
    }

    /// The scene file's text and the bytes of every file its build read, as a dict of plain
    /// Python values; see `penumbra._core.load_pack`.
    fn pack<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let pack = py
            .detach(|| self.file.pack(&self.files))
            .map_err(|e| crate::errors::os_error(&e.source, &e.path))?;
        crate::pack::to_dict(py, &pack)
    }

    /// The world's bounding box as ((min x, y, z), (max x, y, z)).
    #[getter]
    fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        let b = self.world.bounds();
        (b.min.to_array(), b.max.to_array())
    }

    /// A camera with keys or a path, frame by frame: its first frame and each frame's
    /// (position, look_at, up, fov); `None` for a still camera or an unknown name. Raises
    /// `ValueError` for a path seeing through K, a lens model or an aperture, as `camera`
    /// does.
    #[allow(clippy::type_complexity)]
    fn camera_path(&self, name: &str) -> PyResult<Option<(i64, Vec<CameraArgs>)>> {
        let Some(path) = self.paths.iter().find(|(n, _)| n == name).map(|(_, p)| p) else {
            return Ok(None);
        };
        if path
            .camera(*path.frames().start())
            .is_some_and(|c| !c.sees_by_fov())
        {
            return Err(PyValueError::new_err(format!(
                "camera {name:?} sees through an intrinsic matrix K, a lens model or an \
                 aperture, which its frames as (position, look_at, up, fov) cannot hold: \
                 render it by its name (render(camera=...))"
            )));
        }
        let cameras = path
            .frames()
            .filter_map(|f| path.camera(f))
            .map(|c| {
                let [p, l, u] = [c.position(), c.look_at(), c.up()].map(|v| v.to_array());
                (p, l, u, c.fov_y_deg())
            })
            .collect();
        Ok(Some((*path.frames().start(), cameras)))
    }

    /// The names of the scene's cameras, in file order (the first is the default).
    #[getter]
    fn cameras(&self) -> Vec<String> {
        self.world
            .cameras()
            .iter()
            .map(|(n, _)| n.clone())
            .collect()
    }

    /// The file's default settings as a dict.
    #[getter]
    fn settings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = &self.settings;
        let d = PyDict::new(py);
        d.set_item("width", s.width)?;
        d.set_item("height", s.height)?;
        d.set_item("spp", s.spp)?;
        d.set_item("sampler", s.sampler.name())?;
        d.set_item("light_samples", s.light_samples)?;
        d.set_item("seed", s.seed)?;
        d.set_item("alpha", s.alpha)?;
        Ok(d)
    }

    /// Counts and build times of the world as a dict.
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let st = self.world.stats();
        let d = PyDict::new(py);
        d.set_item("triangles", st.triangles)?;
        d.set_item("unique_triangles", st.unique_triangles)?;
        d.set_item("objects", st.objects)?;
        d.set_item("meshes", st.meshes)?;
        d.set_item("instances", st.instances)?;
        d.set_item("lights", st.lights)?;
        d.set_item("materials", st.materials)?;
        d.set_item("textures", st.textures)?;
        d.set_item("cameras", st.cameras)?;
        d.set_item("bvh_nodes", st.bvh_nodes)?;
        d.set_item("bvh_build_seconds", st.bvh_build_time.as_secs_f64())?;
        d.set_item("load_seconds", self.load_seconds)?;
        Ok(d)
    }
}
