//! Scene files and built scenes. Data flows one way: text → [`SceneDesc`] (serde types that
//! mirror the file, see `desc`) → [`Scene`] (world-space triangles, BVH, materials, lights,
//! camera, settings), with every error located in the file.

mod build;
pub mod desc;
mod error;
mod locate;
mod obj;

use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::accel::Bvh;
use crate::camera::PinholeCamera;
use crate::geometry::Geometry;
use crate::integrator::Settings;
use crate::light::Light;
use crate::material::Material;
use crate::sampling::Sampler;
use crate::texture::Texture;

pub use desc::SceneDesc;
pub use error::{KeyPath, Location, SceneError, Segment};

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
}

/// A scene file's text, its syntax and the name messages use for it: all an error needs to
/// say where it is.
#[derive(Clone, Debug)]
struct Source {
    name: PathBuf,
    text: String,
    format: SceneFormat,
}

/// Values that replace the scene file's, as the command line gives them. `None` keeps the
/// file's value.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Overrides {
    /// Film width.
    pub width: Option<u32>,
    /// Film height.
    pub height: Option<u32>,
    /// Pixel sampler; `center` without `spp` means one sample.
    pub sampler: Option<Sampler>,
    /// Samples per pixel (a perfect square).
    pub spp: Option<u32>,
    /// N of every area light, including lights that set their own.
    pub light_samples: Option<u32>,
    /// Random seed.
    pub seed: Option<u64>,
    /// Name of the camera to render (default: the first).
    pub camera: Option<String>,
}

/// Film settings of a built scene.
#[derive(Clone, Debug, PartialEq)]
pub struct FilmSettings {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Output path from the file, resolved against its folder.
    pub output: Option<PathBuf>,
    /// Power-law encoding exponent, or `None` for the sRGB curve.
    pub gamma: Option<f32>,
}

/// Summary statistics of a built scene.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneStats {
    /// Number of triangles.
    pub triangles: usize,
    /// Number of lights.
    pub lights: usize,
    /// Number of materials (including those made from MTL files).
    pub materials: usize,
    /// Number of textures.
    pub textures: usize,
    /// Camera names, the rendered one first.
    pub cameras: Vec<String>,
    /// Time spent building the BVH.
    pub bvh_build_time: Duration,
    /// Number of BVH nodes.
    pub bvh_nodes: usize,
}

/// A scene ready to render: immutable and shareable between threads.
#[derive(Clone, Debug)]
pub struct Scene {
    /// All triangles in world space.
    pub geometry: Geometry,
    /// The acceleration structure over `geometry`.
    pub bvh: Bvh,
    /// Materials, indexed by `Triangle::material`.
    pub materials: Vec<Material>,
    /// Textures, indexed by `Material::texture`.
    pub textures: Vec<Texture>,
    /// Lights.
    pub lights: Vec<Light>,
    /// The camera to render.
    pub camera: PinholeCamera,
    /// Film size and encoding.
    pub film: FilmSettings,
    /// Sampling and shading settings.
    pub settings: Settings,
    /// Counts and timings.
    pub stats: SceneStats,
}

impl SceneFile {
    /// Reads and parses a `.toml` or `.json` scene file.
    pub fn load(path: impl AsRef<Path>) -> Result<SceneFile, SceneError> {
        let path = path.as_ref();
        let format = SceneFormat::from_path(path).ok_or_else(|| SceneError::UnknownFormat {
            path: path.to_owned(),
        })?;
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Read {
            path: path.to_owned(),
            source,
        })?;
        let base_dir = path.parent().map(Path::to_owned).unwrap_or_default();
        SceneFile::from_str(&text, format, path, base_dir)
    }

    /// Parses scene text. `name` is used in messages; relative paths in the file are resolved
    /// against `base_dir`.
    pub fn from_str(
        text: &str,
        format: SceneFormat,
        name: impl Into<PathBuf>,
        base_dir: impl Into<PathBuf>,
    ) -> Result<SceneFile, SceneError> {
        let source = Source {
            name: name.into(),
            text: text.to_owned(),
            format,
        };
        Ok(SceneFile {
            desc: source.parse()?,
            base_dir: base_dir.into(),
            source,
        })
    }

    /// The name used in messages (the path as given).
    pub fn name(&self) -> &Path {
        &self.source.name
    }

    /// An error about the value at `path`, located in the file.
    pub(crate) fn error(&self, path: &KeyPath, message: impl Into<String>) -> SceneError {
        self.source.error(path, message)
    }

    /// Builds the scene as the file describes it, with `overrides` applied, using every core
    /// for the BVH.
    pub fn build(&self, overrides: &Overrides) -> Result<Scene, SceneError> {
        build::build(self, overrides, 0)
    }

    /// Like [`SceneFile::build`], with `threads` workers for the BVH (0: all cores).
    pub fn build_with_threads(
        &self,
        overrides: &Overrides,
        threads: usize,
    ) -> Result<Scene, SceneError> {
        build::build(self, overrides, threads)
    }

    /// Resolves a path written in the scene file against its folder.
    pub fn resolve(&self, path: &str) -> PathBuf {
        self.base_dir.join(path)
    }
}

impl Source {
    fn parse(&self) -> Result<SceneDesc, SceneError> {
        match self.format {
            SceneFormat::Toml => {
                let de = toml::Deserializer::parse(&self.text).map_err(|e| {
                    self.error_at_offset(e.span().map(|s| s.start), None, e.message())
                })?;
                // toml's `preserve_order` feature hands table keys over in file order, so the
                // default camera is the first one written, as in JSON.
                serde_path_to_error::deserialize(de).map_err(|e| {
                    let path = convert_path(e.path());
                    let inner = e.inner();
                    let offset = inner
                        .span()
                        .map(|s| s.start)
                        .or_else(|| locate::locate(&self.text, self.format, &path));
                    self.error_at_offset(offset, Some(&path), inner.message())
                })
            }
            SceneFormat::Json => {
                let mut de = serde_json::Deserializer::from_str(&self.text);
                let desc: SceneDesc = serde_path_to_error::deserialize(&mut de)
                    .map_err(|e| self.json_error(Some(convert_path(e.path())), e.inner()))?;
                de.end().map_err(|e| self.json_error(None, &e))?;
                Ok(desc)
            }
        }
    }

    fn json_error(&self, path: Option<KeyPath>, e: &serde_json::Error) -> SceneError {
        // serde_json's message ends in " at line L column C", which the location already says.
        let full = e.to_string();
        let message = full
            .rfind(" at line ")
            .map_or(full.as_str(), |i| &full[..i]);
        // serde_json counts columns in bytes, with column 0 just after a newline; as a byte
        // offset, the location counts characters from 1 like every other error.
        let offset = (e.line() > 0).then(|| {
            let line_start: usize = self
                .text
                .split_inclusive('\n')
                .take(e.line() - 1)
                .map(str::len)
                .sum();
            line_start + e.column().saturating_sub(1)
        });
        self.error_at_offset(offset, path.as_ref(), message)
    }

    fn error_at_offset(
        &self,
        offset: Option<usize>,
        path: Option<&KeyPath>,
        message: &str,
    ) -> SceneError {
        let (line, column) = match offset {
            Some(o) => {
                let (l, c) = error::line_col(&self.text, o);
                (Some(l), Some(c))
            }
            None => (None, None),
        };
        SceneError::Invalid {
            location: Location {
                file: self.name.clone(),
                line,
                column,
                key: path.filter(|p| !p.is_empty()).map(|p| p.to_string()),
            },
            message: plain_type_names(message.trim()),
        }
    }

    /// An error about the value at `path`, located in the file.
    pub(crate) fn error(&self, path: &KeyPath, message: impl Into<String>) -> SceneError {
        let offset = locate::locate(&self.text, self.format, path);
        self.error_at_offset(offset, Some(path), &message.into())
    }
}

/// serde names Rust types in its messages ("expected i64"); users read scene files, not Rust.
fn plain_type_names(message: &str) -> String {
    [
        ("expected i64", "expected an integer"),
        ("expected u64", "expected a non-negative integer"),
        ("expected f64", "expected a number"),
        ("expected a string", "expected a string in quotes"),
    ]
    .iter()
    .fold(message.to_owned(), |m, (rust, plain)| {
        m.replace(rust, plain)
    })
}

fn convert_path(path: &serde_path_to_error::Path) -> KeyPath {
    KeyPath(
        path.iter()
            .filter_map(|s| match s {
                serde_path_to_error::Segment::Seq { index } => Some(Segment::Index(*index)),
                serde_path_to_error::Segment::Map { key } => Some(Segment::Key(key.clone())),
                serde_path_to_error::Segment::Enum { .. }
                | serde_path_to_error::Segment::Unknown => None,
            })
            .collect(),
    )
}
