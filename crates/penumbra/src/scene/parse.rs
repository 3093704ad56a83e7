//! Scene text → [`SceneDesc`], with every error located: the parser's own position where it
//! has one, else the position of the key path the error is about (see `locate`).

use std::path::{Path, PathBuf};

use serde::de::{self as serde_de, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;
use toml::{Table, Value};

use super::desc::SceneDesc;
use super::error::{self, classify, ErrorKind, KeyPath, Location, SceneError, Segment};
use super::overrides::{self, Override};
use super::{locate, SceneFormat};

/// A scene file's text, its syntax and the name messages use for it: all an error needs to
/// say where it is.
#[derive(Clone, Debug)]
pub(super) struct Source {
    name: PathBuf,
    text: String,
    format: SceneFormat,
    /// The overrides applied, each with the path it set: values at or under one of these
    /// paths are not in the text, and their errors name the override instead.
    set: Vec<(KeyPath, String)>,
    /// True when penumbra wrote the text (the scene of a bare mesh file): errors then name
    /// the key, never a line of text the user has not seen.
    generated: bool,
}

impl Source {
    pub(super) fn new(name: PathBuf, text: String, format: SceneFormat) -> Self {
        Self {
            name,
            text,
            format,
            set: Vec::new(),
            generated: false,
        }
    }

    /// The same source, marked as text penumbra wrote (see `generated`).
    pub(super) fn generated(self) -> Self {
        Self {
            generated: true,
            ..self
        }
    }

    /// The name used in messages.
    pub(super) fn name(&self) -> &Path {
        &self.name
    }

    /// The text, as read.
    pub(super) fn text(&self) -> &str {
        &self.text
    }

    /// The syntax of the text.
    pub(super) fn format(&self) -> SceneFormat {
        self.format
    }

    /// The overrides applied, as given, in order.
    pub(super) fn overrides(&self) -> impl Iterator<Item = &str> {
        self.set.iter().map(|(_, text)| text.as_str())
    }

    /// True when an override set `render.sampler` and none set `render.samples` (nor a
    /// table holding it).
    pub(super) fn sampler_set_alone(&self) -> bool {
        let render = KeyPath::root("render");
        overrides::setter(&self.set, &render.key("sampler")).is_some()
            && overrides::setter(&self.set, &render.key("samples")).is_none()
    }

    /// The description: the text as written, or with `overrides` applied in order.
    pub(super) fn parse(&mut self, overrides: &[Override]) -> Result<SceneDesc, SceneError> {
        if overrides.is_empty() {
            return self.parse_text();
        }
        let mut table = self.tree()?;
        for o in overrides {
            let path = overrides::apply(&mut table, o).map_err(|(path, message)| {
                self.override_error(ErrorKind::BadValue, &path, o.text(), &message)
            })?;
            self.set.push((path, o.text().to_owned()));
        }
        serde_path_to_error::deserialize(Value::Table(table)).map_err(|e| {
            let path = convert_path(e.path());
            let message = e.inner().message();
            let offset = locate::locate(&self.text, self.format, &path);
            self.error_at_offset(classify(message), offset, Some(&path), message)
        })
    }

    /// The same text, with no override applied yet.
    pub(super) fn unset(&self) -> Source {
        Source {
            set: Vec::new(),
            ..self.clone()
        }
    }

    /// The overrides applied, each with the path of what it set.
    pub(super) fn set(&self) -> &[(KeyPath, String)] {
        &self.set
    }

    /// The value tree with the overrides applied (each parsed again from its text).
    pub(super) fn tree_now(&self) -> Result<Table, SceneError> {
        let mut table = self.tree()?;
        for (path, text) in &self.set {
            let applied = Override::parse(text)
                .map_err(|e| e.to_string())
                .and_then(|o| overrides::apply(&mut table, &o).map_err(|(_, m)| m));
            applied.map_err(|m| self.override_error(ErrorKind::BadValue, path, text, &m))?;
        }
        Ok(table)
    }

    /// The file as a value tree (tables keep the file's order) for overrides to change.
    fn tree(&self) -> Result<Table, SceneError> {
        match self.format {
            SceneFormat::Toml => self.text.parse::<Table>().map_err(|e| {
                let offset = e.span().map(|s| s.start);
                self.error_at_offset(ErrorKind::Syntax, offset, None, e.message())
            }),
            SceneFormat::Json => {
                let mut de = serde_json::Deserializer::from_str(&self.text);
                let root: JsonTable = serde_path_to_error::deserialize(&mut de)
                    .map_err(|e| self.json_error(Some(convert_path(e.path())), e.inner()))?;
                de.end().map_err(|e| self.json_error(None, &e))?;
                Ok(root.0)
            }
        }
    }

    fn parse_text(&self) -> Result<SceneDesc, SceneError> {
        match self.format {
            SceneFormat::Toml => {
                let de = toml::Deserializer::parse(&self.text).map_err(|e| {
                    let message = e.message();
                    // A nesting limit comes without a place: the line dotted deepest is the one
                    // that went past it.
                    let offset = e.span().map(|s| s.start).or_else(|| {
                        message
                            .contains("recurs")
                            .then(|| locate::deepest_toml_line(&self.text))
                            .flatten()
                    });
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
        if let Some(path) = path {
            if let Some(set) = overrides::setter(&self.set, path) {
                return self.override_error(classify_kind(kind, message), path, set, message);
            }
        }
        let (line, column) = match offset.filter(|_| !self.generated) {
            Some(o) => {
                let (l, c) = error::line_col(&self.text, o);
                (Some(l), Some(c))
            }
            None => (None, None),
        };
        SceneError::Invalid {
            kind,
            location: Box::new(Location {
                file: self.name.clone(),
                line,
                column,
                key: path.filter(|p| !p.is_empty()).map(|p| p.to_string()),
                set_by: None,
            }),
            message: plain_type_names(message.trim()),
        }
    }

    /// An error about a value that the override `set` put at (or above) `path`.
    fn override_error(
        &self,
        kind: ErrorKind,
        path: &KeyPath,
        set: &str,
        message: &str,
    ) -> SceneError {
        SceneError::Invalid {
            kind,
            location: Box::new(Location {
                file: self.name.clone(),
                line: None,
                column: None,
                key: Some(path.to_string()),
                set_by: Some(set.to_owned()),
            }),
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

/// The kind an error keeps when it is about an override: a syntax error inside the override's
/// value is a bad value of the scene, not a mistake in the file's text.
fn classify_kind(kind: ErrorKind, message: &str) -> ErrorKind {
    match kind {
        ErrorKind::Syntax => classify(message),
        kind => kind,
    }
}

/// A JSON object read into a TOML table for overrides: keys keep the file's order, a `null`
/// member is left out (as an absent optional key, which is what `null` means in the file), a
/// duplicate key is an error as it is when the file is read directly.
struct JsonTable(Table);

/// A JSON value as TOML; `None` for `null`.
struct JsonValue(Option<Value>);

impl<'de> Deserialize<'de> for JsonTable {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        match JsonValue::deserialize(d)?.0 {
            Some(Value::Table(t)) => Ok(JsonTable(t)),
            _ => Err(serde_de::Error::custom("a scene file is one JSON object")),
        }
    }
}

impl<'de> Deserialize<'de> for JsonValue {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(JsonVisitor)
    }
}

struct JsonVisitor;

impl<'de> Visitor<'de> for JsonVisitor {
    type Value = JsonValue;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_unit<E>(self) -> Result<JsonValue, E> {
        Ok(JsonValue(None))
    }
    fn visit_bool<E>(self, v: bool) -> Result<JsonValue, E> {
        Ok(JsonValue(Some(Value::Boolean(v))))
    }
    fn visit_i64<E>(self, v: i64) -> Result<JsonValue, E> {
        Ok(JsonValue(Some(Value::Integer(v))))
    }
    fn visit_u64<E>(self, v: u64) -> Result<JsonValue, E> {
        // TOML's integers are 64-bit signed: a larger one is kept as its digits, which the one
        // key that takes one (`render.seed`) reads as it reads an override's.
        Ok(JsonValue(Some(match i64::try_from(v) {
            Ok(v) => Value::Integer(v),
            Err(_) => Value::String(v.to_string()),
        })))
    }
    fn visit_f64<E>(self, v: f64) -> Result<JsonValue, E> {
        Ok(JsonValue(Some(Value::Float(v))))
    }
    fn visit_str<E>(self, v: &str) -> Result<JsonValue, E> {
        Ok(JsonValue(Some(Value::String(v.to_owned()))))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<JsonValue, A::Error> {
        let mut out = Vec::new();
        while let Some(JsonValue(v)) = seq.next_element()? {
            out.push(v.ok_or_else(|| {
                serde_de::Error::invalid_type(serde_de::Unexpected::Unit, &"a value")
            })?);
        }
        Ok(JsonValue(Some(Value::Array(out))))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<JsonValue, A::Error> {
        let mut out = Table::new();
        while let Some(key) = map.next_key::<String>()? {
            if out.contains_key(&key) {
                return Err(serde_de::Error::custom(format!("duplicate key `{key}`")));
            }
            if let JsonValue(Some(v)) = map.next_value()? {
                out.insert(key, v);
            }
        }
        Ok(JsonValue(Some(Value::Table(out))))
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
