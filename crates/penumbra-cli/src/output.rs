//! Where an image goes: the output name (with `{camera}`, `{frame}`, `{scene}`, `{spp}` and
//! `{seed}` replaced), its format, its folder (made when missing), or standard output for `-o -`.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use penumbra::{
    commit_all, encode_image, file_name_part, stage_image, Film, ImageError, OutputFormat,
    StagedFile,
};

use crate::failure::{invalid, runtime, Failure};
use crate::signals::Interrupt;

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

/// The folder `pattern` names: the folders before its first name with a field, normalized
/// (`out/{scene}/{camera}.png` → `out`; `{camera}.png` → the current folder, empty).
pub fn folder_of(pattern: &str) -> PathBuf {
    let path = Path::new(pattern);
    let mut names: Vec<_> = path.components().collect();
    names.pop(); // The file's name.
    let literal = names
        .iter()
        .take_while(|c| {
            !c.as_os_str()
                .to_string_lossy()
                .replace("{{", "")
                .contains('{')
        })
        .collect::<PathBuf>();
    normalized(&literal)
}

/// An error when `expanded`, a name `pattern` gave, leaves the folder the pattern names (a
/// `..` after a field: `out/{camera}/../../x.png`).
pub fn check_inside(pattern: &str, expanded: &Path) -> Result<(), String> {
    let folder = folder_of(pattern);
    let inside = normalized(expanded)
        .strip_prefix(&folder)
        .is_ok_and(|rest| rest.components().next() != Some(std::path::Component::ParentDir));
    match inside {
        true => Ok(()),
        false => Err(format!(
            "`{pattern}` gives {}, outside its folder {}: a `..` after a field leaves it",
            expanded.display(),
            match folder.as_os_str().is_empty() {
                true => ".".to_owned(),
                false => folder.display().to_string(),
            }
        )),
    }
}

/// The values a pattern's fields take for one render.
pub struct Fields<'a> {
    /// The camera's name (made one file name by [`file_name_part`]).
    pub camera: &'a str,
    /// The scene file's stem (`stdin` for standard input).
    pub scene: &'a str,
    pub spp: u32,
    pub seed: u64,
    /// The frame of a path camera; `None` for a still camera.
    pub frame: Option<i64>,
}

/// The names a pattern may use.
const FIELDS: &str = "{camera}, {frame} (or {frame:04}), {scene}, {spp}, {seed}";

/// `pattern` with each `{field}` replaced; `{{` and `}}` are literal braces.
pub fn expand(pattern: &str, f: &Fields) -> Result<String, String> {
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

/// An image's destination.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Target {
    File(PathBuf),
    Stdout,
}

/// A resolved output: where, and in which format.
#[derive(Clone, Debug)]
pub struct Output {
    pub target: Target,
    pub format: OutputFormat,
}

impl Output {
    /// The output of the expanded name `path` (`-`: standard output) and `--format`.
    pub fn new(path: PathBuf, format: Option<OutputFormat>) -> Result<Output, Failure> {
        if path.as_os_str() == "-" {
            let format = format.ok_or_else(|| {
                invalid("-o -: give the image format with --format png|jpg|exr|pfm")
            })?;
            return Ok(Output {
                target: Target::Stdout,
                format,
            });
        }
        let name = path.display().to_string();
        let Some(by_name) = OutputFormat::from_path(&path) else {
            return Err(invalid(format!(
                "{name}: unknown image format (use .png, .jpg, .exr or .pfm)"
            )));
        };
        if let Some(f) = format.filter(|&f| f != by_name) {
            let (asked, named) = (f.extension(), by_name.extension());
            return Err(invalid(format!(
                "--format {asked} disagrees with the extension of {name} ({named}): drop --format, or name the file .{asked}"
            )));
        }
        Ok(Output {
            target: Target::File(path),
            format: by_name,
        })
    }

    /// How summaries name it.
    pub fn display(&self) -> String {
        match &self.target {
            Target::File(p) => p.display().to_string(),
            Target::Stdout => "-".to_owned(),
        }
    }

    /// Refuses an image the format cannot hold, before the work of rendering it.
    pub fn check_size(&self, width: u32, height: u32) -> Result<(), Failure> {
        match self.format.max_dimension() {
            Some(max) if width > max || height > max => Err(invalid(format!(
                "{}: a {width}x{height} image is too large for this format (at most {max} pixels wide and high)",
                self.display()
            ))),
            _ => Ok(()),
        }
    }

    /// Makes the file's folder (and its parents) when missing.
    pub fn make_folder(&self) -> Result<(), Failure> {
        let Target::File(path) = &self.target else {
            return Ok(());
        };
        match path.parent().filter(|p| !p.as_os_str().is_empty()) {
            Some(dir) if !dir.is_dir() => std::fs::create_dir_all(dir).map_err(|e| {
                runtime(format!(
                    "{}: cannot write image: cannot make folder {}: {e}",
                    path.display(),
                    dir.display()
                ))
            }),
            _ => Ok(()),
        }
    }

    /// Writes `film` although a signal was received: the last pass of an interrupted
    /// `--progressive` render (staged and renamed into place like any image).
    pub fn write_anyway(&self, film: &Film, gamma: Option<f32>) -> Result<(), Failure> {
        let never = AtomicBool::new(false);
        match &self.target {
            Target::File(path) => {
                let image = stage_image(film, path, gamma, &never).map_err(runtime)?;
                commit_all(vec![image]).map_err(runtime)
            }
            Target::Stdout => self.write_stdout(film, gamma),
        }
    }

    /// Stages the image of a file output under a temporary name beside it (see
    /// [`StagedFile`]), to be renamed into place by [`commit`] with the files that go with it
    /// (its AOVs before it, its `--resume` record after it): files appear complete and
    /// together or not at all (a signal or a failed write leaves the old files, or none).
    pub fn stage(
        &self,
        path: &Path,
        film: &Film,
        gamma: Option<f32>,
        interrupt: &Interrupt,
    ) -> Result<StagedFile, Failure> {
        stage_image(film, path, gamma, interrupt.flag()).map_err(|e| match e {
            ImageError::Cancelled => interrupt.failure(),
            e @ ImageError::NonFinite { .. } => invalid(e),
            e => runtime(e),
        })
    }

    /// Writes the image's encoded bytes to standard output at once.
    pub fn write_stdout(&self, film: &Film, gamma: Option<f32>) -> Result<(), Failure> {
        let bytes = encode_image(film, self.format, gamma).map_err(runtime)?;
        let mut out = std::io::stdout().lock();
        out.write_all(&bytes)
            .and_then(|()| out.flush())
            .map_err(|e| runtime(format!("cannot write to standard output: {e}")))
    }
}

/// Renames staged `files` into place together, unless a signal arrived while they were
/// written (then they are removed and the old files stay).
pub fn commit(files: Vec<StagedFile>, interrupt: &Interrupt) -> Result<(), Failure> {
    interrupt.check()?;
    commit_all(files).map_err(runtime)
}

/// The scene's stem for `{scene}` and default names.
pub fn scene_stem(scene: &Path, stdin: bool) -> String {
    if stdin {
        return "stdin".to_owned();
    }
    scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
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
        let e = |p: &str| expand(p, &fields());
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
        assert_eq!(folder_of("a/{{b}}/c/x.png"), Path::new("a/{{b}}/c"));
        let inside = |p: &str, e: &str| check_inside(p, Path::new(e));
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
