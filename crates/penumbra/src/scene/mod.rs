//! Scene files. Data flows one way: text → [`SceneDesc`] (serde types that mirror the file,
//! see `desc`) → [`Scene`]: a shared [`World`] plus the file's default [`RenderSettings`] and
//! output, with every error located in the file.

mod build;
mod camera_table;
pub mod desc;
mod digest;
mod error;
mod gltf;
mod locate;
mod model;
mod moves;
mod npy;
mod obj;
mod overrides;
mod pack;
mod parse;
mod ply;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use crate::camera_path::CameraPath;
use crate::files::{read_bounded, Files};
use crate::reach::Reach;
use crate::render::RenderSettings;
use crate::world::World;

pub use camera_table::camera_from_table;
pub use desc::SceneDesc;
pub use error::{AssetKind, ErrorKind, KeyPath, Location, SceneError};
pub use gltf::{inspect_gltf, inspect_gltf_bytes, inspect_gltf_in, GltfInfo};
pub use model::ModelFormat;
pub use obj::{inspect_mtl, inspect_obj, inspect_obj_bytes, inspect_obj_in, ObjInfo};
pub use overrides::{Override, OverrideError};
pub use pack::{PackError, ScenePack};
use parse::Source;
pub use ply::{inspect_ply, inspect_ply_bytes};

/// Largest scene file read: 256 MiB of text, far beyond any hand-written or exported scene.
pub const MAX_SCENE_BYTES: u64 = 256 << 20;

/// The syntax of a scene file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneFormat {
    /// TOML.
    Toml,
    /// JSON with the same schema.
    Json,
}

impl SceneFormat {
    /// The format a file name's extension names.
    pub fn from_path(path: &Path) -> Option<SceneFormat> {
        match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
            "toml" => Some(SceneFormat::Toml),
            "json" => Some(SceneFormat::Json),
            _ => None,
        }
    }
}

/// A parsed scene file: its description plus the text it came from, kept to locate errors
/// found while building.
#[derive(Clone, Debug)]
pub struct SceneFile {
    /// The description, as written.
    pub desc: SceneDesc,
    /// Folder that relative paths in the file are relative to.
    pub base_dir: PathBuf,
    source: Source,
    /// Where the meshes and images it names are read from.
    files: Files,
}

/// A scene file built: the world it describes, shared, and what the file says about rendering
/// it. Render it with [`render`](crate::render)`(&scene.world, &scene.settings, …)`, or with
/// settings changed per call: the world is never rebuilt.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Geometry, acceleration structure, materials, textures, lights and every camera.
    pub world: Arc<World>,
    /// The file's `[film]` size and `[render]` settings, through its first camera.
    pub settings: RenderSettings,
    /// The file's `film.output`, resolved against its folder.
    pub output: Option<PathBuf>,
    /// The file's `film.gamma`: a power-law encoding exponent, or `None` for the sRGB curve.
    pub gamma: Option<f32>,
    /// Time [`SceneFile::build`] spent before the BVH build: reading and parsing meshes (OBJ,
    /// MTL) and textures and adding everything to the world. The BVH build's own time is
    /// `world.stats().bvh_build_time`; the scene file's parsing happens before, in
    /// [`SceneFile::load`] or [`SceneFile::from_str`].
    pub load_time: Duration,
    /// Every file the build read besides the scene file (meshes, material libraries, images),
    /// by the path the scene resolved it to, sorted: with the scene's text, all it takes to
    /// build it again (see [`SceneFile::pack`]).
    pub files: Vec<PathBuf>,
    /// For each `[[objects]]` entry, in file order, the object ids it added: one, or one per
    /// copy for `type = "instances"` (and one per placed mesh of a glTF file).
    pub objects: Vec<std::ops::Range<u32>>,
    /// What the build ignored in the files it read (glTF features penumbra does not render:
    /// animations, normal maps, …; a PLY file's ignored properties, values or missing
    /// `TextureFile`), one sentence each, naming the file.
    pub warnings: Vec<String>,
    /// The cameras with keys or a path, by name, in file order. The world holds each under
    /// its name at the path's first frame.
    pub paths: Vec<(String, CameraPath)>,
}

impl Scene {
    /// The path of the camera called `name`; `None` for a still camera or an unknown name.
    pub fn path(&self, name: &str) -> Option<&CameraPath> {
        self.paths.iter().find(|(n, _)| n == name).map(|(_, p)| p)
    }
}

impl SceneFile {
    /// Reads and parses a `.toml` or `.json` scene file, or makes the scene of a bare `.obj`,
    /// `.ply`, `.gltf` or `.glb` model file (see [`SceneFile::for_model`]).
    pub fn load(path: impl AsRef<Path>) -> Result<SceneFile, SceneError> {
        SceneFile::load_with(path, &[])
    }

    /// Reads and parses a scene file with `overrides` applied in order (see [`Override`]):
    /// an overridden value is checked like one in the file, and errors about it name the
    /// override.
    pub fn load_with(
        path: impl AsRef<Path>,
        overrides: &[Override],
    ) -> Result<SceneFile, SceneError> {
        SceneFile::load_allowing(path, overrides, Vec::new())
    }

    /// [`SceneFile::load_with`] where every file of the scene may read in the folders
    /// `allowed` (and below) besides its own folder (`--allow-path DIR`; see
    /// [`Files::allowing`]). Without them, a scene file reads only files in its folder and
    /// below, and a model only files in its own folder and below.
    pub fn load_allowing(
        path: impl AsRef<Path>,
        overrides: &[Override],
        allowed: Vec<PathBuf>,
    ) -> Result<SceneFile, SceneError> {
        let path = path.as_ref();
        let files = Files::disk().allowing(allowed);
        if ModelFormat::from_path(path).is_some() {
            return SceneFile::for_model_in(path, overrides, files);
        }
        let format = SceneFormat::from_path(path).ok_or_else(|| SceneError::UnknownFormat {
            path: path.to_owned(),
        })?;
        let read = |source| SceneError::Read {
            path: path.to_owned(),
            source,
        };
        let bytes = read_bounded(path, MAX_SCENE_BYTES).map_err(read)?;
        let text =
            String::from_utf8(bytes).map_err(|e| not_utf8(path, e.as_bytes(), e.utf8_error()))?;
        let base_dir = path.parent().map(Path::to_owned).unwrap_or_default();
        Ok(SceneFile::from_str_with(&text, format, path, base_dir, overrides)?.with_files(files))
    }

    /// Parses scene text. `name` is used in messages; relative paths in the file are resolved
    /// against `base_dir`.
    pub fn from_str(
        text: &str,
        format: SceneFormat,
        name: impl Into<PathBuf>,
        base_dir: impl Into<PathBuf>,
    ) -> Result<SceneFile, SceneError> {
        SceneFile::from_str_with(text, format, name, base_dir, &[])
    }

    /// [`SceneFile::from_str`] with `overrides` applied in order (see [`Override`]).
    pub fn from_str_with(
        text: &str,
        format: SceneFormat,
        name: impl Into<PathBuf>,
        base_dir: impl Into<PathBuf>,
        overrides: &[Override],
    ) -> Result<SceneFile, SceneError> {
        let source = Source::new(name.into(), text.to_owned(), format);
        SceneFile::from_source(source, base_dir, overrides)
    }

    /// The scene file of `source` with `overrides` applied in order.
    fn from_source(
        mut source: Source,
        base_dir: impl Into<PathBuf>,
        overrides: &[Override],
    ) -> Result<SceneFile, SceneError> {
        Ok(SceneFile {
            desc: source.parse(overrides)?,
            base_dir: base_dir.into(),
            source,
            files: Files::disk(),
        })
    }

    /// The same scene file reading its meshes and images from `files` instead.
    pub fn with_files(self, files: Files) -> SceneFile {
        SceneFile { files, ..self }
    }

    /// Where the meshes and images the file names are read from.
    pub fn files(&self) -> &Files {
        &self.files
    }

    /// The text of the file, as read (before any override).
    pub fn text(&self) -> &str {
        self.source.text()
    }

    /// The syntax of the file.
    pub fn format(&self) -> SceneFormat {
        self.source.format()
    }

    /// The name used in messages (the path as given).
    pub fn name(&self) -> &Path {
        self.source.name()
    }

    /// An error of `kind` about the value at `path`, located in the file.
    pub(crate) fn error(
        &self,
        kind: ErrorKind,
        path: &KeyPath,
        message: impl Into<String>,
    ) -> SceneError {
        self.source.error(kind, path, message)
    }

    /// Builds the scene the file describes (loading every mesh and texture) with `threads`
    /// workers for reading meshes and building the BVH (0: all cores).
    pub fn build(&self, threads: usize) -> Result<Scene, SceneError> {
        build::build(self, threads)
    }

    /// The file's `render.samples` (with overrides), when it gives one: the count a sampler
    /// chosen without one takes, unless it is center (see
    /// [`SettingsPatch::apply`](crate::SettingsPatch::apply)).
    ///
    /// ```
    /// use penumbra::{Sampler, SceneFile, SceneFormat, SettingsPatch};
    ///
    /// let text = "[film]\nwidth = 8\nheight = 8\n[camera]\nposition = [0, 0, 3]\n\
    ///             look_at = [0, 0, 0]\nfov = 40\n[render]\nsampler = \"rgss\"\nsamples = 16\n";
    /// let file = SceneFile::from_str(text, SceneFormat::Toml, "s.toml", ".")?;
    /// assert_eq!(file.samples(), Some(16));
    /// let scene = file.build(1)?;
    /// let spp = |sampler| {
    ///     let patch = SettingsPatch { sampler: Some(sampler), ..SettingsPatch::default() };
    ///     patch.apply(&scene.settings, file.samples()).map(|s| s.spp)
    /// };
    /// assert_eq!(spp(Sampler::Center)?, 1);
    /// assert_eq!(spp(Sampler::Grid)?, 16);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn samples(&self) -> Option<u32> {
        // A count out of range cannot come from a file that builds; it is passed on as
        // u32::MAX for the settings check to refuse.
        self.desc
            .render
            .samples
            .map(|n| u32::try_from(n).unwrap_or(u32::MAX))
    }

    /// True when an override set `render.sampler` and none set `render.samples`: the file's
    /// count was written for another sampler, so the new one takes its own (as a
    /// [`SettingsPatch`](crate::SettingsPatch) of the sampler alone does).
    pub(crate) fn sampler_set_alone(&self) -> bool {
        self.source.sampler_set_alone()
    }

    /// Resolves a path written in the scene file against its folder (whether the scene may
    /// read it or not: building it checks that).
    pub fn resolve(&self, path: &str) -> PathBuf {
        self.base_dir.join(path)
    }

    /// What the file may read: its folder and below, and the folders its files allow.
    pub(crate) fn reach(&self) -> Reach<'_> {
        Reach::new(&self.files, self.name(), &self.base_dir, "scene")
    }
}

/// The error for a scene file that is not UTF-8: at the line and column of the first byte
/// that cannot be read, as every other mistake in the file is.
fn not_utf8(path: &Path, bytes: &[u8], e: std::str::Utf8Error) -> SceneError {
    let valid = e.valid_up_to();
    let prefix = std::str::from_utf8(&bytes[..valid]).unwrap_or_default();
    let (line, column) = error::line_col(prefix, prefix.len());
    SceneError::Invalid {
        kind: ErrorKind::Syntax,
        location: Box::new(error::Location {
            file: path.to_owned(),
            line: Some(line),
            column: Some(column),
            key: None,
            set_by: None,
        }),
        message: format!(
            "byte 0x{:02X} is not UTF-8 text (scene files must be saved as UTF-8)",
            bytes[valid]
        ),
    }
}
