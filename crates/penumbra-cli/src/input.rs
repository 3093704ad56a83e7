//! Where a scene comes from: a file, or standard input when the path is `-`.

use std::io::Read;
use std::path::{Path, PathBuf};

use penumbra::{Files, ModelFormat, Override, SceneFile, SceneFormat, MAX_SCENE_BYTES};

use crate::failure::{invalid, Failure};

/// The name messages give a scene read from standard input.
pub const STDIN_NAME: &str = "<stdin>";

/// True when `path` means standard input.
pub fn is_stdin(path: &Path) -> bool {
    path.as_os_str() == "-"
}

/// The subcommand reading a scene: each accepts its own kinds of file.
#[derive(Clone, Copy)]
pub enum Reader {
    Render,
    Check,
}

impl Reader {
    /// What it reads, as a message says it.
    fn accepts(self) -> &'static str {
        match self {
            Reader::Render => "`penumbra render` reads a .toml or .json scene file, or a .obj, .ply, .gltf or .glb model (rendered with its own or a default camera and lights)",
            Reader::Check => "`penumbra check` reads a .toml or .json scene file, or a .obj, .ply, .gltf or .glb model",
        }
    }
}

/// The files of the disk, where a scene's files may also read in the `--allow-path` folders
/// `allowed`, each checked to be a folder.
pub fn files(allowed: &[PathBuf]) -> Result<Files, Failure> {
    for dir in allowed {
        if !dir.is_dir() {
            return Err(invalid(format!(
                "--allow-path {}: not a folder",
                dir.display()
            )));
        }
    }
    Ok(Files::disk().allowing(allowed.to_vec()))
}

/// Reads and parses the scene at `path` (`-`: standard input, whose relative paths are relative
/// to the current folder, its root) with `set` applied, its files also reading in the folders
/// `allowed`, for `reader`. A bare `.obj` or `.ply` mesh is the scene
/// [`SceneFile::for_model`] makes of it.
pub fn load(
    path: &Path,
    set: &[Override],
    allowed: &[PathBuf],
    reader: Reader,
) -> Result<SceneFile, Failure> {
    let files = files(allowed)?;
    if !is_stdin(path) {
        if SceneFormat::from_path(path).is_none() && ModelFormat::from_path(path).is_none() {
            return Err(invalid(format!(
                "{}: unknown file type: {}",
                path.display(),
                reader.accepts()
            )));
        }
        return SceneFile::load_allowing(path, set, allowed.to_vec()).map_err(invalid);
    }
    let mut bytes = Vec::new();
    std::io::stdin()
        .lock()
        .take(MAX_SCENE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| invalid(format!("{STDIN_NAME}: cannot read scene: {e}")))?;
    if bytes.len() as u64 > MAX_SCENE_BYTES {
        return Err(invalid(format!(
            "{STDIN_NAME}: cannot read scene: larger than {MAX_SCENE_BYTES} bytes"
        )));
    }
    let text = String::from_utf8(bytes)
        .map_err(|_| invalid(format!("{STDIN_NAME}: cannot read scene: not UTF-8 text")))?;
    SceneFile::from_str_with(&text, format_of(&text), STDIN_NAME, "", set)
        .map(|file| file.with_files(files))
        .map_err(invalid)
}

/// JSON when the text starts with `{` (which no TOML document does), else TOML.
fn format_of(text: &str) -> SceneFormat {
    if text.trim_start().starts_with('{') {
        SceneFormat::Json
    } else {
        SceneFormat::Toml
    }
}
