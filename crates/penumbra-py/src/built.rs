//! A built scene as the Python package holds it ([`CoreScene`]: the world, shared and never
//! changed, the file's settings and what a pack and a record need), its build with the GIL
//! released, and the scene with an object moved ([`CoreScene::with_move`]). Its methods as Python
//! sees them are in `scene`.

use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

use penumbra::{ObjectIndex, RenderSettings, SceneFile, World};
use pyo3::prelude::*;

use crate::errors::scene_error;

/// A built scene: the world (geometry and BVH, materials, textures, lights, cameras) and the
/// scene file's default render settings.
#[pyclass(frozen, module = "penumbra._core")]
pub struct CoreScene {
    pub(crate) world: Arc<World>,
    pub(crate) settings: RenderSettings,
    /// The file's `render.samples`, the sample count a sampler change falls back to.
    pub(crate) file_samples: Option<u32>,
    /// The file's `film.gamma` (`None`: 8-bit images take the sRGB curve).
    pub(crate) gamma: Option<f32>,
    pub(crate) load_seconds: f64,
    /// The parsed file and the files its build read: what a pack of the scene holds.
    pub(crate) file: SceneFile,
    pub(crate) files: Vec<PathBuf>,
    /// For each `objects` entry, the object ids it added.
    pub(crate) objects: Vec<std::ops::Range<u32>>,
    /// Where each object's triangles are, for `surface_attributes`: made by its first call,
    /// not once per call (a walk over every triangle).
    pub(crate) object_index: OnceLock<ObjectIndex>,
    /// The cameras with keys or a path, by name.
    pub(crate) paths: Vec<(String, penumbra::CameraPath)>,
}

impl CoreScene {
    /// The digest of the scene's text and every file its build read.
    pub(crate) fn digest(&self, py: Python<'_>) -> String {
        py.detach(|| self.file.digest(&self.files))
    }
}

impl CoreScene {
    /// This scene with object `object` (or its copy `placement`) placed by `matrix`: the file
    /// with the move (`SceneFile::with_transform`), reading the bytes this scene's build read
    /// (`Files::snapshot`: nothing from disk), and its world: this one with instances moved
    /// when the object's copies are instances (`SceneFile::moved_world`), else built again
    /// with `threads` workers.
    pub(crate) fn with_move(
        &self,
        py: Python<'_>,
        object: usize,
        placement: Option<usize>,
        matrix: [[f64; 4]; 4],
        threads: usize,
    ) -> PyResult<CoreScene> {
        let moved = py.detach(|| {
            // What the build read, as a pack: the moved scene reads nothing from disk.
            let files = self.file.files().snapshot();
            let file =
                (self.file.clone().with_files(files)).with_transform(object, placement, matrix)?;
            let ids = self.objects[object].clone();
            let world = file.moved_world(object, &self.world, ids)?;
            Ok::<_, penumbra::SceneError>((file, world))
        });
        let (file, world) = moved.map_err(|e| scene_error(py, e))?;
        let Some(world) = world else {
            return build(py, threads, move || Ok(file));
        };
        Ok(CoreScene {
            world: Arc::new(world),
            settings: self.settings.clone(),
            file_samples: self.file_samples,
            gamma: self.gamma,
            load_seconds: self.load_seconds,
            file,
            files: self.files.clone(),
            objects: self.objects.clone(),
            object_index: OnceLock::new(),
            paths: self.paths.clone(),
        })
    }
}

/// Parses and builds with the GIL released.
pub(crate) fn build(
    py: Python<'_>,
    threads: usize,
    parse: impl FnOnce() -> Result<SceneFile, penumbra::SceneError> + Send,
) -> PyResult<CoreScene> {
    let built = py.detach(|| {
        // A snapshot: its pack holds the bytes this build reads, whatever the files hold later.
        let file = parse()?.keeping_files();
        let scene = file.build(threads)?;
        Ok::<_, penumbra::SceneError>((file, scene))
    });
    let (file, scene) = built.map_err(|e| scene_error(py, e))?;
    Ok(CoreScene {
        world: scene.world,
        settings: scene.settings,
        file_samples: file.samples(),
        gamma: scene.gamma,
        load_seconds: scene.load_time.as_secs_f64(),
        file,
        files: scene.files,
        objects: scene.objects,
        paths: scene.paths,
        object_index: OnceLock::new(),
    })
}
