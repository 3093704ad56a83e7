//! Output names: a pattern such as `out/{scene}/{camera}_{frame:04}.png` with each field
//! replaced ([`expand`]), and the checks that keep the names it gives inside the pattern's
//! folder ([`check_inside`]). A name from a file (a camera's, a scene's) stays one file name
//! ([`file_name_part`]).
//!
//! ```
//! use penumbra::products::output_name::{expand, Fields};
//!
//! let f = Fields { camera: "side/left", scene: "cornell", spp: 16, seed: 7, frame: Some(42) };
//! assert_eq!(expand("out/{scene}_{camera}_{frame:04}.png", &f).unwrap(), "out/cornell_side_left_0042.png");
//! ```

use std::path::{Path, PathBuf};

use crate::names::file_name_part;

/// `path` with each `.` dropped and each `..` taking off the name before it, as the path would
/// resolve if no name in it were a link; a `..` with no name before it stays.
pub fn normalized(path: &Path) -> PathBuf {
    use std::path::Component;
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir
                if matches!(out.components().next_back(), Some(Component::Normal(_))) =>
            {
                out.pop();
            }
            c => out.push(c),
        }
    }
    out
}

/// The folder `pattern` names: the folders before its first name with a field, normalized,
/// their `{{` and `}}` the braces every name the pattern gives has there
/// (`out/{scene}/{camera}.png` → `out`; `{camera}.png` → the current folder, empty).
pub fn folder_of(pattern: &str) -> PathBuf {
    let path = Path::new(pattern);
    let mut names: Vec<_> = path.components().collect();
    names.pop(); // The file's name.
    let literal = names
        .iter()
        .map(|c| c.as_os_str().to_string_lossy())
        .take_while(|c| !c.replace("{{", "").contains('{'))
        .map(|c| c.replace("{{", "{").replace("}}", "}"))
        .collect::<PathBuf>();
    normalized(&literal)
}

/// An error when `expanded`, a name `pattern` gave, leaves the folder the pattern names (a
/// `..` after a field: `out/{camera}/../../x.png`).
pub fn check_inside(pattern: &str, expanded: &Path) -> Result<(), PatternError> {
    let folder = folder_of(pattern);
    let inside = normalized(expanded)
        .strip_prefix(&folder)
        .is_ok_and(|rest| rest.components().next() != Some(std::path::Component::ParentDir));
    match inside {
        true => Ok(()),
        false => Err(PatternError(format!(
            "`{pattern}` gives {}, outside its folder {}: a `..` after a field leaves it",
            expanded.display(),
            match folder.as_os_str().is_empty() {
                true => ".".to_owned(),
                false => folder.display().to_string(),
            }
        ))),
    }
}

/// The values a pattern's fields take for one render.
#[derive(Clone, Copy, Debug)]
pub struct Fields<'a> {
    /// The camera's name (made one file name by [`file_name_part`]).
    pub camera: &'a str,
    /// The scene file's stem (`stdin` for standard input).
    pub scene: &'a str,
    /// Samples per pixel.
    pub spp: u32,
    /// The seed.
    pub seed: u64,
    /// The frame of a path camera; `None` for a still camera.
    pub frame: Option<i64>,
}

/// A pattern that gives no name: an unknown field, an unclosed brace, a frame of a still
/// camera, a name outside the pattern's folder. The message quotes the pattern.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct PatternError(pub String);

/// `pattern` with each `{field}` replaced; `{{` and `}}` are literal braces.
pub fn expand(pattern: &str, f: &Fields) -> Result<String, PatternError> {
    let frame = f.frame.map(|n| Value::Number(n.into())).ok_or_else(|| {
        format!(
            "`{{frame}}` in `{pattern}`: camera `{}` is a still camera, with no frames",
            f.camera
        )
    });
    let fields = [
        // One file name each: a scene file `...toml` has the stem `..`.
        ("camera", Ok(Value::Text(file_name_part(f.camera)))),
        ("frame", frame),
        ("scene", Ok(Value::Text(file_name_part(f.scene)))),
        ("spp", Ok(Value::Number(f.spp.into()))),
        ("seed", Ok(Value::Number(f.seed.into()))),
    ];
    expand_fields(pattern, &fields)
}

/// What a field of a pattern stands for: text, given as it is, or a number, which a pattern
/// may pad with zeros to a width (`{frame:04}`, or `{frame:04d}` as Python writes it).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Value {
    /// Text, as it is (the caller makes a name from a file one file name).
    Text(String),
    /// A whole number: a frame, a seed, an index.
    Number(i128),
}

/// `pattern` with each `{name}` of `fields` replaced by its value (an error, for a field
/// that has none here, is the message); `{{` and `}}` are literal braces. The one expander
/// of the command line's names and Python's batches (`{name}`, `{index}`).
pub fn expand_fields(
    pattern: &str,
    fields: &[(&str, Result<Value, String>)],
) -> Result<String, PatternError> {
    let mut out = String::new();
    let mut rest = pattern;
    while let Some(i) = rest.find(['{', '}']) {
        out.push_str(&rest[..i]);
        let tail = &rest[i..];
        if let Some(after) = tail.strip_prefix("{{").or_else(|| tail.strip_prefix("}}")) {
            out.push_str(&tail[..1]);
            rest = after;
            continue;
        }
        if let Some(after) = tail.strip_prefix('}') {
            out.push('}');
            rest = after;
            continue;
        }
        let end = tail.find('}').ok_or_else(|| {
            PatternError(format!(
                "an unclosed `{{` in `{pattern}` (write {{{{ for a brace)"
            ))
        })?;
        let field = &tail[1..end];
        let (name, spec) = field.split_once(':').unwrap_or((field, ""));
        let Some((_, value)) = fields.iter().find(|(n, _)| *n == name) else {
            return Err(PatternError(format!(
                "unknown field `{{{field}}}` in `{pattern}` (known: {})",
                known(fields)
            )));
        };
        let value = value.clone().map_err(PatternError)?;
        out.push_str(&formatted(&value, spec).ok_or_else(|| {
            PatternError(match value {
                Value::Number(_) => {
                    format!("`{{{field}}}` in `{pattern}`: a width is written {{{name}:04}}")
                }
                Value::Text(_) => format!("`{{{field}}}` in `{pattern}`: `{name}` takes no format"),
            })
        })?);
        rest = &tail[end + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

/// `value` written by `spec`: nothing for text, or `0N` (`0Nd`), N ≤ 20, for a number.
fn formatted(value: &Value, spec: &str) -> Option<String> {
    match (value, spec) {
        (Value::Text(t), "") => Some(t.clone()),
        (Value::Text(_), _) => None,
        (Value::Number(n), "") => Some(n.to_string()),
        (Value::Number(n), spec) => {
            let digits = spec.strip_suffix('d').unwrap_or(spec);
            let width = (digits.starts_with('0'))
                .then(|| digits.parse::<usize>().ok())
                .flatten()
                .filter(|&w| w <= 20)?;
            Some(format!("{n:0width$}"))
        }
    }
}

/// The fields a pattern may use, as an error lists them.
fn known(fields: &[(&str, Result<Value, String>)]) -> String {
    let each = fields.iter().map(|(name, value)| match value {
        Ok(Value::Text(_)) => format!("{{{name}}}"),
        _ => format!("{{{name}}} (or {{{name}:04}})"),
    });
    each.collect::<Vec<_>>().join(", ")
}

/// True when `pattern` names the camera, so that several cameras get several files.
pub fn names_camera(pattern: &str) -> bool {
    pattern.replace("{{", "").contains("{camera}")
}

/// True when `pattern` names the frame (`{frame}` or `{frame:04}`).
pub fn names_frame(pattern: &str) -> bool {
    let p = pattern.replace("{{", "");
    p.contains("{frame}") || p.contains("{frame:")
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;

    fn fields() -> Fields<'static> {
        Fields {
            camera: "side/left",
            scene: "cornell",
            spp: 16,
            seed: 7,
            frame: Some(42),
        }
    }

    #[test]
    fn a_batch_pattern_expands_names_and_indices_in_either_spelling() {
        let fields = [
            ("name", Ok(Value::Text("front".to_owned()))),
            ("index", Ok(Value::Number(7))),
        ];
        let e = |p: &str| expand_fields(p, &fields).map_err(|e| e.0);
        assert_eq!(e("out/{name}_{index}.png").unwrap(), "out/front_7.png");
        // Python's spelling of a width, and the command line's.
        assert_eq!(e("{index:04d}.png").unwrap(), "0007.png");
        assert_eq!(e("{index:04}.png").unwrap(), "0007.png");
        assert!(e("{name:>9}.png")
            .unwrap_err()
            .contains("`name` takes no format"));
        assert!(e("{index:4}.png").unwrap_err().contains("{index:04}"));
        let unknown = e("{camera}.png").unwrap_err();
        assert!(
            unknown.contains("known: {name}, {index} (or {index:04})"),
            "{unknown}"
        );
    }

    #[test]
    fn patterns_expand_their_fields() {
        let e = |p: &str| expand(p, &fields()).map_err(|e| e.0);
        assert_eq!(
            e("out/{scene}_{camera}.png").unwrap(),
            "out/cornell_side_left.png"
        );
        assert_eq!(e("{spp}spp-{seed}.exr").unwrap(), "16spp-7.exr");
        assert_eq!(e("plain.png").unwrap(), "plain.png");
        assert_eq!(e("{{camera}}.png").unwrap(), "{camera}.png");
        assert_eq!(e("a}b.png").unwrap(), "a}b.png");
        assert!(e("{frames}.png")
            .unwrap_err()
            .contains("unknown field `{frames}`"));
        assert_eq!(e("f{frame}.png").unwrap(), "f42.png");
        assert_eq!(e("f{frame:04}.png").unwrap(), "f0042.png");
        assert_eq!(
            e("f{frame:1}.png").map_err(|e| e.contains("{frame:04}")),
            Err(true)
        );
        let still = Fields {
            frame: None,
            ..fields()
        };
        assert!(expand("{frame}.png", &still)
            .unwrap_err()
            .0
            .contains("still camera"));
        let negative = Fields {
            frame: Some(-3),
            ..fields()
        };
        assert_eq!(expand("{frame:04}.png", &negative).unwrap(), "-003.png");
        assert!(e("{camera.png").unwrap_err().contains("unclosed"));
    }

    #[test]
    fn field_values_stay_one_name_and_dots_stay_in_the_patterns_folder() {
        let up = Fields {
            scene: "..",
            camera: "..",
            ..fields()
        };
        assert_eq!(
            expand("out/sub/{scene}/x.png", &up).unwrap(),
            "out/sub/_./x.png"
        );
        assert_eq!(expand("{camera}.png", &up).unwrap(), "_..png");
        assert_eq!(normalized(Path::new("f1/../x.pfm")), Path::new("x.pfm"));
        assert_eq!(normalized(Path::new("../a/./b/..")), Path::new("../a"));
        assert_eq!(
            folder_of("out/sub/{scene}/{camera}.png"),
            Path::new("out/sub")
        );
        assert_eq!(folder_of("{camera}.png"), Path::new(""));
        assert_eq!(folder_of("a/{{b}}/c/x.png"), Path::new("a/{b}/c"));
        let braces = Fields {
            camera: "x",
            ..fields()
        };
        let name = expand("a/{{b}}/{camera}.png", &braces).unwrap();
        assert_eq!(name, "a/{b}/x.png");
        assert!(check_inside("a/{{b}}/{camera}.png", Path::new(&name)).is_ok());
        let inside = |p: &str, e: &str| check_inside(p, Path::new(e)).map_err(|e| e.0);
        assert!(inside("f{frame}/../x.pfm", "f1/../x.pfm").is_ok());
        assert!(inside("../out/{camera}.png", "../out/a.png").is_ok());
        assert!(inside("out/{camera}/../../x.png", "out/a/../../x.png")
            .unwrap_err()
            .contains("outside its folder out"));
        assert!(inside("{camera}/../../x.png", "a/../../x.png").is_err());
    }

    #[test]
    fn only_a_real_camera_field_names_the_camera() {
        assert!(names_camera("out/{camera}.png"));
        assert!(!names_camera("out/{{camera}}.png"));
        assert!(!names_camera("out/x.png"));
        assert!(names_frame("out/{frame:04}.png") && names_frame("{frame}"));
        assert!(!names_frame("{{frame}}.png") && !names_frame("frame.png"));
    }
}
