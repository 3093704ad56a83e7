//! Reading the files a scene names: only regular files, and never more than a bound, so that a
//! folder, a device such as `/dev/zero`, a named pipe or a huge file is refused at once
//! instead of hanging or exhausting memory. A scene's files come from the file system or from
//! a pack carried in memory ([`Files`]), so that a scene built on one machine can be built
//! again on another without a shared file system.

use std::collections::BTreeMap;
use std::io::{self, Read};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// Where the files a scene names (meshes, material libraries, images) are read from: the file
/// system, or a set of files carried in memory, each under the path the scene resolves it to
/// (see [`SceneFile::pack`](crate::SceneFile::pack)). Reading a path the pack does not hold is
/// a "not found" error, as on disk.
#[derive(Clone, Debug, Default)]
pub struct Files {
    packed: Option<Arc<BTreeMap<PathBuf, Vec<u8>>>>,
    /// When set, a copy of every file read from disk, by the path it was read under: the
    /// bytes a build read, so that a pack of it holds them whatever the files hold later.
    kept: Option<Arc<Mutex<ByPath>>>,
    /// Folders every file of the scene may read besides its own (see [`crate::reach`]).
    allowed: Arc<[PathBuf]>,
}

/// Files' bytes by path.
type ByPath = BTreeMap<PathBuf, Vec<u8>>;

impl Files {
    /// The file system.
    pub fn disk() -> Files {
        Files::default()
    }

    /// The files of `files`, by path, and no others.
    pub fn packed(files: BTreeMap<PathBuf, Vec<u8>>) -> Files {
        Files {
            packed: Some(Arc::new(files)),
            kept: None,
            allowed: Arc::new([]),
        }
    }

    /// The same files, keeping a copy of every file read from disk from now on (see
    /// [`Files::kept`]): a scene built from them is a snapshot, whose pack holds the bytes its
    /// build read even after the files change on disk. The copies cost memory as large as
    /// the files, for as long as the `Files` (or a clone) lives. Packed files are kept already.
    pub fn keeping(self) -> Files {
        match self.packed {
            Some(_) => self,
            None => Files {
                packed: None,
                kept: Some(Arc::default()),
                allowed: self.allowed,
            },
        }
    }

    /// The files kept so far (see [`Files::keeping`]) as a pack, the same folders allowed:
    /// a scene built again from them reads the bytes its first build read, and nothing from
    /// disk. A pack is itself; files not kept are an empty pack.
    pub fn snapshot(&self) -> Files {
        match (&self.packed, &self.kept) {
            (Some(_), _) => self.clone(),
            (None, kept) => Files {
                packed: Some(Arc::new(
                    kept.as_ref().map(|k| lock(k).clone()).unwrap_or_default(),
                )),
                kept: None,
                allowed: self.allowed.clone(),
            },
        }
    }

    /// The same files, where every file of a scene may read in `folders` (and below) besides
    /// its own folder: `--allow-path DIR`. A file names another only within these (see the
    /// module `reach`); in a pack, the folders are compared by name with the pack's paths.
    pub fn allowing(self, folders: Vec<PathBuf>) -> Files {
        Files {
            allowed: folders.into(),
            ..self
        }
    }

    /// The folders allowed besides each file's own (see [`Files::allowing`]).
    pub fn allowed(&self) -> &[PathBuf] {
        &self.allowed
    }

    /// The bytes `path` had when it was read: from the pack, or the copy kept when it was read
    /// from disk (see [`Files::keeping`]). `None` for a file not read, or read from disk
    /// without keeping.
    pub fn kept(&self, path: &Path) -> Option<Vec<u8>> {
        match (&self.packed, &self.kept) {
            (Some(files), _) => files.get(path).cloned(),
            (None, Some(kept)) => lock(kept).get(path).cloned(),
            (None, None) => None,
        }
    }

    /// True when the files come from a pack rather than the file system.
    pub fn is_packed(&self) -> bool {
        self.packed.is_some()
    }

    /// The bytes of the regular file `path`, at most `limit` of them (see [`read_bounded`]).
    pub(crate) fn read(&self, path: &Path, limit: u64) -> io::Result<Vec<u8>> {
        match &self.packed {
            None => {
                let bytes = read_bounded(path, limit)?;
                if let Some(kept) = &self.kept {
                    lock(kept).insert(path.to_owned(), bytes.clone());
                }
                Ok(bytes)
            }
            Some(files) => {
                let bytes = packed_file(files, path)?;
                if bytes.len() as u64 > limit {
                    return Err(too_large(bytes.len() as u64, limit));
                }
                Ok(bytes.clone())
            }
        }
    }

    /// The size of `path` in bytes, or `None` when it cannot be known (a missing file).
    pub(crate) fn size(&self, path: &Path) -> Option<u64> {
        match &self.packed {
            None => std::fs::metadata(path).ok().map(|m| m.len()),
            Some(files) => files.get(path).map(|b| b.len() as u64),
        }
    }

    /// True when `path` is a regular file (or a packed one).
    pub(crate) fn is_file(&self, path: &Path) -> bool {
        match &self.packed {
            None => path.is_file(),
            Some(files) => files.contains_key(path),
        }
    }

    /// The name under which `path` is read once per scene: the canonical path on disk (so
    /// that two spellings of one file share it), the path itself in a pack.
    pub(crate) fn identity(&self, path: &Path) -> PathBuf {
        match &self.packed {
            None => std::fs::canonicalize(path).unwrap_or_else(|_| path.to_owned()),
            Some(_) => path.to_owned(),
        }
    }
}

/// The kept files, even after a panic elsewhere while they were locked (a map of whole
/// entries cannot be left half-changed by one).
fn lock(kept: &Mutex<ByPath>) -> std::sync::MutexGuard<'_, ByPath> {
    kept.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

fn packed_file<'a>(files: &'a BTreeMap<PathBuf, Vec<u8>>, path: &Path) -> io::Result<&'a Vec<u8>> {
    files
        .get(path)
        .ok_or_else(|| io::Error::new(io::ErrorKind::NotFound, "not in the scene's packed files"))
}

/// Checks that `path` is a regular file of at most `limit` bytes, before anything opens it
/// (opening a named pipe would wait for a writer). Returns its size.
pub(crate) fn check_regular(path: &Path, limit: u64) -> io::Result<u64> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        let what = if meta.is_dir() {
            "a folder"
        } else {
            "not a regular file (a device or a pipe)"
        };
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("it is {what}"),
        ));
    }
    if meta.len() > limit {
        return Err(too_large(meta.len(), limit));
    }
    Ok(meta.len())
}

/// The bytes of the regular file `path`, at most `limit` of them.
pub(crate) fn read_bounded(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    let size = check_regular(path, limit)?;
    let mut bytes = Vec::new();
    bytes
        .try_reserve_exact(size as usize)
        .map_err(|_| too_large(size, limit))?;
    // Bounded even if the file grows after the check.
    std::fs::File::open(path)?
        .take(limit.saturating_add(1))
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(bytes.len() as u64, limit));
    }
    Ok(bytes)
}

fn too_large(size: u64, limit: u64) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidData,
        format!("the file is too large ({size} bytes; at most {limit})"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folders_devices_and_large_files_are_refused() {
        let dir = std::env::temp_dir();
        let e = read_bounded(&dir, 1 << 20).unwrap_err();
        assert!(e.to_string().contains("folder"), "{e}");
        if Path::new("/dev/zero").exists() {
            let e = read_bounded(Path::new("/dev/zero"), 1 << 20).unwrap_err();
            assert!(e.to_string().contains("not a regular file"), "{e}");
        }
        let file = dir.join(format!("penumbra-files-test-{}", std::process::id()));
        std::fs::write(&file, b"0123456789").unwrap();
        assert_eq!(read_bounded(&file, 10).unwrap(), b"0123456789");
        let e = read_bounded(&file, 9).unwrap_err();
        assert!(e.to_string().contains("too large"), "{e}");
        std::fs::remove_file(&file).unwrap();
    }

    #[test]
    fn packed_files_are_read_by_their_exact_path_with_the_same_bound() {
        let files = Files::packed(BTreeMap::from([(
            PathBuf::from("/scenes/mesh.obj"),
            b"v 0 0 0".to_vec(),
        )]));
        let path = Path::new("/scenes/mesh.obj");
        assert_eq!(files.read(path, 100).unwrap(), b"v 0 0 0");
        assert!(files.is_file(path) && files.size(path) == Some(7));
        let e = files.read(path, 6).unwrap_err();
        assert!(e.to_string().contains("too large"), "{e}");
        // Looked up by path components: `.` is no component, `..` is.
        assert!(files.is_file(Path::new("/scenes/./mesh.obj")));
        let other = Path::new("/scenes/../scenes/mesh.obj");
        assert_eq!(
            files.read(other, 100).unwrap_err().kind(),
            io::ErrorKind::NotFound
        );
        assert!(!files.is_file(other) && files.size(other).is_none());
    }
}
