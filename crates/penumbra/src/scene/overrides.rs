//! Overrides of scene keys from outside the file: `KEY.PATH=VALUE`, the command line's `--set`
//! (Mitsuba's `-D`). The file is read into a value tree, each override replaces (or adds) the
//! value at its path, and the tree is then deserialized exactly like the file's text, so an
//! overridden value gets the same types, checks and messages as one written in the file; a
//! message about it names the override instead of a line.
//!
//! Paths are the file's own keys joined by dots: `film.width`, `render.sampler`,
//! `cameras.side.fov`, `materials.red.diffuse`. An array entry is picked by its index, written
//! `objects[0].material` (as messages write it) or `objects.0.material`; an index must name an
//! existing entry (an override replaces values, it never appends). Missing tables on the way
//! are created, so `cameras.top.fov=30` adds a key to a new camera table. A key containing a
//! dot is written in quotes: `materials."red.glossy".shininess=40`.
//!
//! The value is read as a TOML value (`64`, `0.5`, `[0, 1, 5]`, `"rgss"`,
//! `{ diffuse = [1, 0, 0] }`); anything that is not one is taken as a bare string, so
//! `render.sampler=rgss` works without quotes.
//!
//! ```
//! use penumbra::{Override, SceneFile, SceneFormat};
//!
//! let text = "[film]\nwidth = 64\nheight = 48\n[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov = 40\n";
//! let set = [Override::parse("film.width=32")?, Override::parse("render.sampler=center")?];
//! let file = SceneFile::from_str_with(text, SceneFormat::Toml, "s.toml", ".", &set)?;
//! assert_eq!(file.desc.film.width, 32);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::fmt;

use thiserror::Error;
use toml::{Table, Value};

use super::error::KeyPath;

/// One step of an override's path as written.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Step {
    /// A key; digits only also index an array.
    Name(String),
    /// `[n]`: an array index.
    Index(usize),
}

/// One `KEY.PATH=VALUE` override of a scene file's value.
#[derive(Clone, Debug, PartialEq)]
pub struct Override {
    text: String,
    steps: Vec<Step>,
    value: Value,
}

/// An override that is not of the form `KEY.PATH=VALUE`.
#[derive(Clone, Debug, Error, PartialEq, Eq)]
#[error("{reason} in `{text}` (expected KEY.PATH=VALUE, such as film.width=640)")]
pub struct OverrideError {
    /// The override as given.
    pub text: String,
    /// What is wrong with it.
    pub reason: String,
}

impl Override {
    /// Parses `KEY.PATH=VALUE` (spaces around the `=` are ignored).
    pub fn parse(text: &str) -> Result<Override, OverrideError> {
        let fail = |reason: &str| OverrideError {
            text: text.to_owned(),
            reason: reason.to_owned(),
        };
        let (key, value) = text.split_once('=').ok_or_else(|| fail("no `=`"))?;
        let steps = parse_key(key.trim()).map_err(|r| fail(&r))?;
        Ok(Override {
            text: text.to_owned(),
            steps,
            value: parse_value(value.trim()),
        })
    }

    /// The override as given.
    pub fn text(&self) -> &str {
        &self.text
    }
}

impl fmt::Display for Override {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

/// The value as TOML, else the text itself as a string.
fn parse_value(text: &str) -> Value {
    // The one key of a one-line document: anything that is more than one value (a newline
    // and another key) is not a TOML value either.
    let parsed = format!("v = {text}")
        .parse::<Table>()
        .ok()
        .filter(|t| t.len() == 1 && !text.contains('\n'))
        .and_then(|mut t| t.remove("v"));
    parsed.unwrap_or_else(|| Value::String(text.to_owned()))
}

/// `a.b[2]."c.d".0` → steps.
fn parse_key(key: &str) -> Result<Vec<Step>, String> {
    let mut steps = Vec::new();
    let mut rest = key;
    loop {
        let name;
        if let Some(quoted) = rest.strip_prefix('"') {
            let end = quoted
                .find('"')
                .ok_or_else(|| "an unclosed quote in the key".to_owned())?;
            name = quoted[..end].to_owned();
            rest = &quoted[end + 1..];
        } else {
            let end = rest.find(['.', '[', ']', '"']).unwrap_or(rest.len());
            name = rest[..end].trim().to_owned();
            if name.is_empty() {
                return Err("an empty key".to_owned());
            }
            rest = &rest[end..];
        }
        steps.push(Step::Name(name));
        while let Some(inner) = rest.strip_prefix('[') {
            let end = inner
                .find(']')
                .ok_or_else(|| "an unclosed `[` in the key".to_owned())?;
            let index = inner[..end]
                .trim()
                .parse()
                .map_err(|_| format!("`[{}]` is not an array index", &inner[..end]))?;
            steps.push(Step::Index(index));
            rest = &inner[end + 1..];
        }
        match rest.strip_prefix('.') {
            Some(after) => rest = after,
            None if rest.is_empty() => return Ok(steps),
            None => {
                let c = rest.chars().next().unwrap_or_default();
                return Err(format!("unexpected `{c}` in the key"));
            }
        }
    }
}

/// Why an override could not be applied: the path of the value in the way, and the message.
pub(crate) type ApplyError = (KeyPath, String);

/// Sets `o`'s value in `root`; returns the path of what it owns, with every index resolved:
/// the value it set, or the first table it had to create on the way (`cameras.top` for
/// `cameras.top.fov=30` in a file without that camera), since everything under it comes from
/// the override.
pub(crate) fn apply(root: &mut Table, o: &Override) -> Result<KeyPath, ApplyError> {
    // `parse_key` always starts with a name.
    let Some((Step::Name(first), rest)) = o.steps.split_first() else {
        return Err((
            KeyPath::default(),
            "a key must start with a name".to_owned(),
        ));
    };
    let mut path = KeyPath::root(first);
    let mut created = (!root.contains_key(first)).then(|| path.clone());
    let mut slot = root
        .entry(first.clone())
        .or_insert_with(|| placeholder(rest.is_empty()));
    for (i, step) in rest.iter().enumerate() {
        let (next, next_path, existed) = child(slot, step, &path, i + 1 == rest.len())?;
        if !existed && created.is_none() {
            created = Some(next_path.clone());
        }
        slot = next;
        path = next_path;
    }
    *slot = o.value.clone();
    Ok(created.unwrap_or(path))
}

/// What a missing key holds until it is set: a new table on the way, anything at the end.
fn placeholder(is_last: bool) -> Value {
    if is_last {
        Value::Boolean(false)
    } else {
        Value::Table(Table::new())
    }
}

/// The value `step` names inside `slot` (a table entry made when missing: a new table on the
/// way, a placeholder for the last step), its path, and whether it was there before.
fn child<'v>(
    slot: &'v mut Value,
    step: &Step,
    path: &KeyPath,
    is_last: bool,
) -> Result<(&'v mut Value, KeyPath, bool), ApplyError> {
    let kind = slot.type_str();
    match (slot, step) {
        (Value::Table(t), Step::Name(name)) => {
            let existed = t.contains_key(name);
            let entry = t
                .entry(name.clone())
                .or_insert_with(|| placeholder(is_last));
            Ok((entry, path.key(name), existed))
        }
        (Value::Array(a), step) => {
            let index = match step {
                Step::Index(i) => *i,
                Step::Name(name) => name.parse::<usize>().map_err(|_| {
                    let m =
                        format!("`{path}` is an array: pick an entry by index, such as {path}[0]");
                    (path.clone(), m)
                })?,
            };
            let len = a.len();
            let entry = a.get_mut(index).ok_or_else(|| {
                let m = match len {
                    0 => format!("`{path}` is empty: an override cannot add entries"),
                    _ => format!(
                        "`{path}` has {len} entries (indexes 0 to {}): an override cannot add entries",
                        len - 1
                    ),
                };
                (path.clone(), m)
            })?;
            Ok((entry, path.index(index), true))
        }
        (Value::Table(_), Step::Index(_)) => {
            Err((path.clone(), format!("`{path}` is a table, not an array")))
        }
        (_, _) => Err((
            path.clone(),
            format!("`{path}` is {} {kind}, not a table", article(kind)),
        )),
    }
}

/// The override that set the value at `path` or a value containing it: the last one whose
/// path is a prefix of `path`.
pub(crate) fn setter<'a>(set: &'a [(KeyPath, String)], path: &KeyPath) -> Option<&'a str> {
    set.iter()
        .rev()
        .find(|(p, _)| path.0.starts_with(&p.0))
        .map(|(_, text)| text.as_str())
}

/// "a" or "an" before a TOML type name.
fn article(kind: &str) -> &'static str {
    if kind.starts_with(['a', 'e', 'i', 'o', 'u']) {
        "an"
    } else {
        "a"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn steps(key: &str) -> Vec<Step> {
        parse_key(key).unwrap()
    }

    #[test]
    fn keys_are_dotted_with_indexes_and_quotes() {
        use Step::*;
        assert_eq!(
            steps("objects[0].material"),
            [Name("objects".into()), Index(0), Name("material".into())]
        );
        assert_eq!(
            steps("objects.0.material"),
            [
                Name("objects".into()),
                Name("0".into()),
                Name("material".into())
            ]
        );
        assert_eq!(
            steps(r#"materials."a.b".diffuse"#),
            [
                Name("materials".into()),
                Name("a.b".into()),
                Name("diffuse".into())
            ]
        );
        for bad in ["", "a..b", "a.", ".a", "a[x]", "a[1", "\"a", "a]b"] {
            assert!(parse_key(bad).is_err(), "{bad:?} was accepted");
        }
    }

    #[test]
    fn values_are_toml_else_strings() {
        assert_eq!(parse_value("64"), Value::Integer(64));
        assert_eq!(parse_value("0.5"), Value::Float(0.5));
        assert_eq!(parse_value("\"rgss\""), Value::String("rgss".into()));
        assert_eq!(parse_value("rgss"), Value::String("rgss".into()));
        assert_eq!(
            parse_value("out/a b.png"),
            Value::String("out/a b.png".into())
        );
        assert_eq!(parse_value(""), Value::String(String::new()));
        assert_eq!(
            parse_value("[0, 1, 5]"),
            Value::Array(vec![0.into(), 1.into(), 5.into()])
        );
        // Two keys are not one value.
        assert_eq!(parse_value("1\nx = 2"), Value::String("1\nx = 2".into()));
    }

    #[test]
    fn an_override_needs_an_equals_sign() {
        let e = Override::parse("film.width").unwrap_err();
        assert!(e.to_string().contains("no `=` in `film.width`"), "{e}");
    }

    fn applied(text: &str, o: &str) -> Result<(Table, String), String> {
        let mut t: Table = text.parse().unwrap();
        let o = Override::parse(o).unwrap();
        apply(&mut t, &o)
            .map(|p| (t, p.to_string()))
            .map_err(|(p, m)| format!("{p}: {m}"))
    }

    #[test]
    fn overrides_replace_add_and_index() {
        let text = "[film]\nwidth = 1\n[[objects]]\ntype = \"cube\"\n";
        let (t, p) = applied(text, "film.width=64").unwrap();
        assert_eq!(
            (t["film"]["width"].as_integer(), p.as_str()),
            (Some(64), "film.width")
        );
        // A table the override made is the override's, all of it.
        let (t, p) = applied(text, "render.seed=7").unwrap();
        assert_eq!(
            (t["render"]["seed"].as_integer(), p.as_str()),
            (Some(7), "render")
        );
        let (t, p) = applied(text, "objects.0.material=red").unwrap();
        assert_eq!(t["objects"][0]["material"].as_str(), Some("red"));
        assert_eq!(p, "objects[0].material");
        let (t, _) = applied(text, "objects[0].type=sphere").unwrap();
        assert_eq!(t["objects"][0]["type"].as_str(), Some("sphere"));
    }

    #[test]
    fn overrides_that_cannot_apply_say_why() {
        let text = "[film]\nwidth = 1\n[[objects]]\ntype = \"cube\"\n";
        let e = applied(text, "film.width.x=1").unwrap_err();
        assert_eq!(e, "film.width: `film.width` is an integer, not a table");
        let e = applied(text, "objects[3].material=red").unwrap_err();
        assert!(e.contains("has 1 entries (indexes 0 to 0)"), "{e}");
        let e = applied(text, "objects.first=1").unwrap_err();
        assert!(e.contains("pick an entry by index"), "{e}");
        let e = applied(text, "film[0]=1").unwrap_err();
        assert!(e.contains("is a table, not an array"), "{e}");
    }
}
