//! Errors of scene loading and building, each naming the file, the line and column, and the
//! key path it is about.

use std::fmt;
use std::path::PathBuf;

use thiserror::Error;

use crate::names::escape_controls;

/// One step of a key path: a table key or an array index.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Segment {
    /// A key of a table (object).
    Key(String),
    /// An index into an array.
    Index(usize),
}

/// A path to a value in the scene file, shown as `objects[2].material`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct KeyPath(pub Vec<Segment>);

impl KeyPath {
    /// The path of a top-level key.
    pub fn root(key: &str) -> Self {
        KeyPath(vec![Segment::Key(key.to_owned())])
    }

    /// This path extended by a key.
    pub fn key(&self, key: &str) -> Self {
        let mut p = self.clone();
        p.0.push(Segment::Key(key.to_owned()));
        p
    }

    /// This path extended by an index.
    pub fn index(&self, i: usize) -> Self {
        let mut p = self.clone();
        p.0.push(Segment::Index(i));
        p
    }

    /// True for the empty path (the whole file).
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The last key of the path (`size` in `objects[1].size`), if it ends in a key.
    pub fn last_key(&self) -> Option<&str> {
        match self.0.last()? {
            Segment::Key(k) => Some(k),
            Segment::Index(_) => None,
        }
    }
}

impl fmt::Display for KeyPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, s) in self.0.iter().enumerate() {
            match s {
                Segment::Key(k) if i == 0 => write!(f, "{k}")?,
                Segment::Key(k) => write!(f, ".{k}")?,
                Segment::Index(n) => write!(f, "[{n}]")?,
            }
        }
        Ok(())
    }
}

/// Where in a scene file an error is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    /// The scene file.
    pub file: PathBuf,
    /// 1-based line, when known.
    pub line: Option<usize>,
    /// 1-based column (in characters), when known.
    pub column: Option<usize>,
    /// The key path, when the error is about a key.
    pub key: Option<String>,
    /// The override (`KEY.PATH=VALUE`, see [`Override`](super::Override)) that set the value
    /// the error is about, which is then not in the file: no line or column.
    pub set_by: Option<String>,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", escape_controls(&self.file.display().to_string()))?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(col) = self.column {
                write!(f, ":{col}")?;
            }
        }
        if let Some(key) = &self.key {
            write!(f, ": {}", escape_controls(key))?;
        }
        if let Some(set) = &self.set_by {
            write!(f, " (--set {})", escape_controls(set))?;
        }
        Ok(())
    }
}

/// What kind of mistake a [`SceneError`] reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    /// The text is not valid TOML or JSON (including a duplicate TOML key).
    Syntax,
    /// A key the table (or that kind of object, light or texture) does not take.
    UnknownKey,
    /// A required key is absent.
    MissingKey,
    /// A value of the wrong type, out of range, not finite, or not one of the allowed names.
    BadValue,
    /// A name that refers to nothing: a material, texture or camera.
    UnknownName,
    /// A file the scene refers to cannot be loaded.
    Asset(AssetKind),
    /// The scene file itself cannot be read, or its name names no format.
    File,
}

/// Which kind of file an [`ErrorKind::Asset`] error is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AssetKind {
    /// A Wavefront OBJ mesh or its MTL material library.
    Mesh,
    /// A texture image.
    Image,
    /// A `.npy` file of instance transforms.
    Transforms,
}

/// Why a scene could not be loaded or built. Every variant is the user's input being wrong.
#[derive(Debug, Error)]
pub enum SceneError {
    /// The scene file could not be read.
    #[error("{}: cannot read scene file: {source}", escape_controls(&path.display().to_string()))]
    Read {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The file name does not say TOML or JSON (or a mesh format).
    #[error(
        "{}: unknown scene format (the file name must end in .toml or .json, or .obj, .ply, .gltf or .glb for a bare model)",
        escape_controls(&path.display().to_string())
    )]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// Something in the file is wrong, located in it.
    #[error("{location}: {}", escape_controls(message))]
    Invalid {
        /// What kind of mistake.
        kind: ErrorKind,
        /// Where (boxed: errors stay small to return).
        location: Box<Location>,
        /// What is wrong.
        message: String,
    },
}

impl SceneError {
    /// What kind of mistake this is.
    pub fn kind(&self) -> ErrorKind {
        match self {
            SceneError::Read { .. } | SceneError::UnknownFormat { .. } => ErrorKind::File,
            SceneError::Invalid { kind, .. } => *kind,
        }
    }

    /// Where in the file, for errors about its contents.
    pub fn location(&self) -> Option<&Location> {
        match self {
            SceneError::Invalid { location, .. } => Some(&**location),
            _ => None,
        }
    }
}

/// The kind of a parser's message. serde reports mistakes as text only, so its standard
/// phrases (and this crate's own, from the scene types' deserializers) are matched here.
pub(crate) fn classify(message: &str) -> ErrorKind {
    if message.starts_with("unknown field") || message.starts_with("unknown key") {
        ErrorKind::UnknownKey
    } else if message.starts_with("missing field") || message.starts_with("missing key") {
        ErrorKind::MissingKey
    } else {
        ErrorKind::BadValue
    }
}

/// 1-based line and column (in characters) of a byte offset.
pub(crate) fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[line_start..].chars().count() + 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_characters_are_escaped() {
        assert_eq!(escape_controls("plain é"), "plain é");
        assert_eq!(
            escape_controls("a\nb\u{1b}[31m\u{7}"),
            "a\\nb\\u{1b}[31m\\u{7}"
        );
    }

    #[test]
    fn key_paths_read_like_the_file() {
        let p = KeyPath::root("objects").index(2).key("material");
        assert_eq!(p.to_string(), "objects[2].material");
    }

    #[test]
    fn line_and_column_are_one_based() {
        let text = "a = 1\nbé = 2\n";
        assert_eq!(line_col(text, 0), (1, 1));
        assert_eq!(line_col(text, 6), (2, 1));
        // 'é' is two bytes but one column.
        assert_eq!(line_col(text, 9), (2, 3));
    }
}
