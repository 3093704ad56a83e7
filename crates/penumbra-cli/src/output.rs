//! Where an image goes: the output name (with `{camera}`, `{frame}`, `{scene}`, `{spp}` and
//! `{seed}` replaced: [`penumbra::products::output_name`]), its format, its folder (made when missing), or standard output for `-o -`.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use penumbra::{commit_all, encode_image, stage_image, Film, ImageError, OutputFormat, StagedFile};

use crate::failure::{invalid, runtime, Failure};
use crate::signals::Interrupt;

pub use penumbra::products::output_name::{
    check_inside, expand, names_camera, names_frame, normalized, Fields,
};

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
