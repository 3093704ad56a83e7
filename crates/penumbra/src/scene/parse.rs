//! Scene text → [`SceneDesc`], with every error located: the parser's own position where it
//! has one, else the position of the key path the error is about (see `locate`).

use std::path::{Path, PathBuf};

use super::desc::SceneDesc;
use super::error::{self, classify, ErrorKind, KeyPath, Location, SceneError, Segment};
use super::{locate, SceneFormat};

/// A scene file's text, its syntax and the name messages use for it: all an error needs to
/// say where it is.
#[derive(Clone, Debug)]
pub(super) struct Source {
    name: PathBuf,
    text: String,
    format: SceneFormat,
}

impl Source {
    pub(super) fn new(name: PathBuf, text: String, format: SceneFormat) -> Self {
        Self { name, text, format }
    }

    /// The name used in messages.
    pub(super) fn name(&self) -> &Path {
        &self.name
    }

    pub(super) fn parse(&self) -> Result<SceneDesc, SceneError> {
        match self.format {
            SceneFormat::Toml => {
                let de = toml::Deserializer::parse(&self.text).map_err(|e| {
                    let offset = e.span().map(|s| s.start);
                    let message = e.message();
                    // A duplicate or a nesting too deep is about a key, which the parser does
                    // not name: find it from the text, as JSON's errors name theirs.
                    let about_a_key =
                        message.starts_with("duplicate key") || message.contains("recurs");
                    match offset.filter(|_| about_a_key) {
                        Some(o) => {
                            let path = locate::toml_path_at(&self.text, o);
                            let message = match (message, path.last_key()) {
                                ("duplicate key", Some(key)) => format!("duplicate key `{key}`"),
                                ("duplicate key", None) => message.to_owned(),
                                _ => format!("arrays or tables nested too deeply ({message})"),
                            };
                            self.error_at_offset(ErrorKind::Syntax, offset, Some(&path), &message)
                        }
                        None => self.error_at_offset(ErrorKind::Syntax, offset, None, message),
                    }
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
                    let message = inner.message();
                    self.error_at_offset(classify(message), offset, Some(&path), message)
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
        let kind = match e.classify() {
            serde_json::error::Category::Syntax | serde_json::error::Category::Eof => {
                ErrorKind::Syntax
            }
            _ => classify(message),
        };
        let offset = (e.line() > 0).then(|| {
            let line_start: usize = self
                .text
                .split_inclusive('\n')
                .take(e.line() - 1)
                .map(str::len)
                .sum();
            line_start + e.column().saturating_sub(1)
        });
        self.error_at_offset(kind, offset, path.as_ref(), message)
    }

    fn error_at_offset(
        &self,
        kind: ErrorKind,
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
            kind,
            location: Location {
                file: self.name.clone(),
                line,
                column,
                key: path.filter(|p| !p.is_empty()).map(|p| p.to_string()),
            },
            message: plain_type_names(message.trim()),
        }
    }

    /// An error of `kind` about the value at `path`, located in the file.
    pub(super) fn error(
        &self,
        kind: ErrorKind,
        path: &KeyPath,
        message: impl Into<String>,
    ) -> SceneError {
        let offset = locate::locate(&self.text, self.format, path);
        self.error_at_offset(kind, offset, Some(path), &message.into())
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
