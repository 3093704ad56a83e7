//! Packed scenes: a scene file's text with every file its build reads, held in memory, so that
//! another process or machine builds the same world without those files on its disk.

use std::collections::BTreeMap;
use std::io;
use std::path::PathBuf;

use thiserror::Error;

use super::{ErrorKind, Location, Override, SceneError, SceneFile, SceneFormat};
use crate::files::Files;

/// A scene file and the bytes of every file its build reads (meshes, material libraries,
/// images), each under the path the scene resolves it to. [`ScenePack::load`] parses it again;
/// the build then reads nothing from disk, and builds the world the original file builds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScenePack {
    /// The name messages use for the file.
    pub name: PathBuf,
    /// The file's text.
    pub text: String,
    /// Its syntax.
    pub format: SceneFormat,
    /// The folder its relative paths were resolved against (only a name now: the files are
    /// looked up by the paths it gave them).
    pub base_dir: PathBuf,
    /// The `KEY.PATH=VALUE` overrides applied to it, in order.
    pub overrides: Vec<String>,
    /// The folders its files may read in besides their own (see
    /// [`Files::allowing`]), as given: compared by name with the packed files' paths.
    pub allowed: Vec<PathBuf>,
    /// The files, by resolved path.
    pub files: BTreeMap<PathBuf, Vec<u8>>,
}

/// A file of the scene could not be read into the pack.
#[derive(Debug, Error)]
#[error("cannot pack \"{}\": {source}", path.display())]
pub struct PackError {
    /// The file.
    pub path: PathBuf,
    /// The cause.
    pub source: io::Error,
}

impl From<PackError> for SceneError {
    /// A file that could not be packed is a file that could not be read.
    fn from(e: PackError) -> SceneError {
        SceneError::Read {
            path: e.path,
            source: e.source,
        }
    }
}

impl SceneFile {
    /// This file, keeping a copy of every file its builds read (see [`Files::keeping`]), so
    /// that [`SceneFile::pack`] holds the bytes the build read: a snapshot, which a change to
    /// the files on disk after the build does not reach.
    pub fn keeping_files(self) -> SceneFile {
        let files = self.files.clone().keeping();
        self.with_files(files)
    }

    /// Packs this file with the files `read`, the [`Scene::files`](super::Scene::files) of its
    /// build: the bytes its build read when it keeps them (see [`SceneFile::keeping_files`],
    /// and a packed file's own), else read again from disk now (so the files must not have
    /// changed since the build for the pack to build the same world).
    pub fn pack(&self, read: &[PathBuf]) -> Result<ScenePack, PackError> {
        let files = read
            .iter()
            .map(|path| {
                let bytes = match self.files.kept(path) {
                    Some(bytes) => bytes,
                    None => self
                        .files
                        .read(path, u64::MAX)
                        .map_err(|source| PackError {
                            path: path.clone(),
                            source,
                        })?,
                };
                Ok((path.clone(), bytes))
            })
            .collect::<Result<_, PackError>>()?;
        Ok(ScenePack {
            name: self.name().to_owned(),
            text: self.text().to_owned(),
            format: self.format(),
            base_dir: self.base_dir.clone(),
            overrides: self.source.overrides().map(str::to_owned).collect(),
            allowed: self.files.allowed().to_vec(),
            files,
        })
    }
}

impl ScenePack {
    /// The bytes of the files together.
    pub fn file_bytes(&self) -> usize {
        self.files.values().map(Vec::len).sum()
    }

    /// Parses the packed file; building it reads only the packed files. An override that is
    /// not `KEY.PATH=VALUE` is a syntax error naming it, as a bad one in the file would be.
    pub fn load(self) -> Result<SceneFile, SceneError> {
        let overrides = self
            .overrides
            .iter()
            .map(|text| Override::parse(text))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| SceneError::Invalid {
                kind: ErrorKind::Syntax,
                location: Box::new(Location {
                    file: self.name.clone(),
                    line: None,
                    column: None,
                    key: None,
                    set_by: Some(e.text.clone()),
                }),
                message: format!(
                    "{} in this override (expected KEY.PATH=VALUE, such as film.width=640)",
                    e.reason
                ),
            })?;
        let file = SceneFile::from_str_with(
            &self.text,
            self.format,
            self.name,
            self.base_dir,
            &overrides,
        )?;
        Ok(file.with_files(Files::packed(self.files).allowing(self.allowed)))
    }
}
