//! Scene files. Data flows one way: text → [`SceneDesc`] (serde types that mirror the file,
//! see `desc`) → [`Scene`]: a shared [`World`] plus the file's default [`RenderSettings`] and
//! output, with every error located in the file.

mod build;
pub mod desc;
mod error;
mod locate;
mod obj;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::render::RenderSettings;
use crate::world::World;

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

    /// Builds the scene the file describes (loading every mesh and texture) with `threads`
    /// workers for the BVH (0: all cores).
    pub fn build(&self, threads: usize) -> Result<Scene, SceneError> {
        build::build(self, threads)
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
