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

/// The names a pattern may use.
const FIELDS: &str = "{camera}, {frame} (or {frame:04}), {scene}, {spp}, {seed}";

/// A pattern that gives no name: an unknown field, an unclosed brace, a frame of a still
/// camera, a name outside the pattern's folder. The message quotes the pattern.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct PatternError(pub String);

/// `pattern` with each `{field}` replaced; `{{` and `}}` are literal braces.
pub fn expand(pattern: &str, f: &Fields) -> Result<String, PatternError> {
    expand_text(pattern, f).map_err(PatternError)
}

fn expand_text(pattern: &str, f: &Fields) -> Result<String, String> {
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
        let end = tail
            .find('}')
            .ok_or_else(|| format!("an unclosed `{{` in `{pattern}` (write {{{{ for a brace)"))?;
        let value = match &tail[1..end] {
            "camera" => file_name_part(f.camera),
            // One file name, like a camera's: a scene file `...toml` has the stem `..`.
            "scene" => file_name_part(f.scene),
            "spp" => f.spp.to_string(),
            "seed" => f.seed.to_string(),
            field if field == "frame" || field.starts_with("frame:") => {
                let width = match &field["frame".len()..] {
                    "" => 0,
                    spec => spec[1..]
                        .parse::<usize>()
                        .ok()
                        .filter(|&w| w <= 20 && spec[1..].starts_with('0'))
                        .ok_or_else(|| {
                            format!("`{{{field}}}` in `{pattern}`: a frame's width is written {{frame:04}}")
                        })?,
                };
                let frame = f.frame.ok_or_else(|| {
                    format!(
                        "`{{frame}}` in `{pattern}`: camera `{}` is a still camera, with no frames",
                        f.camera
                    )
                })?;
                format!("{frame:0width$}")
            }
            other => {
                return Err(format!(
                    "unknown field `{{{other}}}` in `{pattern}` (known: {FIELDS})"
                ))
            }
        };
        out.push_str(&value);
        rest = &tail[end + 1..];
    }
    out.push_str(rest);
    Ok(out)
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
