//! Output files that appear complete or not at all, alone or as a group: each is written under
//! a temporary name in its destination's folder and synced, and only then renamed into place.
//!
//! A group (an image and its AOV files) is staged whole before any of it is renamed, so a full
//! disk or a signal while writing leaves every old file as it was: what can fail for lack of
//! space happens before the first rename, and a rename within one folder takes no space.
//!
//! ```
//! use penumbra::{commit_all, StagedFile};
//! let dir = std::env::temp_dir().join(format!("penumbra-staged-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir)?;
//! let image = StagedFile::write_bytes(&dir.join("a.pfm"), b"Pf\n1 1\n-1.0\n\0\0\0\0")?;
//! let depth = StagedFile::write_bytes(&dir.join("a.depth.pfm"), b"Pf\n1 1\n-1.0\n\0\0\0\0")?;
//! assert!(!dir.join("a.pfm").exists()); // nothing is in place before the commit
//! commit_all(vec![image, depth])?;
//! assert!(dir.join("a.pfm").exists() && dir.join("a.depth.pfm").exists());
//! # std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::collections::HashMap;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::fnv::FileDigest;
use crate::image_error::ImageError;

/// What a temporary name holds after the destination's file name: `.a.png` + `.tmp-` + the
/// writer's process id, `-`, a count (`.a.png.tmp-22127-0`).
const TAG: &str = ".tmp-";

/// A file written beside its destination under a temporary name, not yet in place. Dropping
/// it without [`commit`](StagedFile::commit) removes the temporary file.
#[derive(Debug)]
pub struct StagedFile {
    tmp: PathBuf,
    path: PathBuf,
}

impl StagedFile {
    /// Stages the file `write` writes (then synced to disk) for `path`. On an error the
    /// temporary file is removed and `path` is untouched.
    pub fn write_with(
        path: &Path,
        write: impl FnOnce(&mut File) -> Result<(), String>,
    ) -> Result<StagedFile, ImageError> {
        let fail = |message: String| ImageError::Write {
            path: path.to_owned(),
            message,
        };
        let name = path
            .file_name()
            .ok_or_else(|| fail("not a file name".into()))?;
        // The rename would fail: say so before anything of a group is in place.
        if path.is_dir() {
            return Err(fail("a folder has that name".into()));
        }
        // Unique per process and per call, so concurrent writers never share a temporary file.
        static WRITES: AtomicU64 = AtomicU64::new(0);
        let tmp = path.with_file_name(format!(
            ".{}{TAG}{}-{}",
            name.to_string_lossy(),
            std::process::id(),
            WRITES.fetch_add(1, Ordering::Relaxed)
        ));
        let mut file = File::create(&tmp).map_err(|e| fail(e.to_string()))?;
        // From here on, dropping `staged` removes the temporary file.
        let staged = StagedFile {
            tmp,
            path: path.to_owned(),
        };
        write(&mut file)
            .and_then(|()| file.sync_all().map_err(|e| e.to_string()))
            .map_err(fail)?;
        Ok(staged)
    }

    /// Stages `bytes` for `path`.
    pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<StagedFile, ImageError> {
        StagedFile::write_with(path, |f| f.write_all(bytes).map_err(|e| e.to_string()))
    }

    /// Where the file goes.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The size and digest of the bytes staged (read back from the temporary file), for a
    /// record of the file; errors name the destination.
    pub fn digest(&self) -> Result<FileDigest, ImageError> {
        FileDigest::of_file(&self.tmp).map_err(|e| ImageError::Write {
            path: self.path.clone(),
            message: format!("cannot read back what was written: {e}"),
        })
    }

    /// Renames the file into place.
    pub fn commit(self) -> Result<(), ImageError> {
        std::fs::rename(&self.tmp, &self.path).map_err(|e| ImageError::Write {
            path: self.path.clone(),
            message: e.to_string(),
        })
        // On success the temporary name is gone; dropping `self` finds nothing to remove.
    }
}

impl Drop for StagedFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.tmp);
    }
}

/// The destination's file name and the writer's process id of a temporary name of this
/// module's scheme (`.a.png.tmp-22127-0` → `("a.png", 22127)`; also `.a.png.tmp-22127-0.png`,
/// the name Python's batches used to stage images under), or `None` for any other name.
pub fn staged_for(name: &str) -> Option<(&str, u32)> {
    let (target, tail) = name.strip_prefix('.')?.rsplit_once(TAG)?;
    let ext = Path::new(target).extension().and_then(|e| e.to_str());
    let tail = match ext.and_then(|e| tail.strip_suffix(&format!(".{e}")[..])) {
        Some(t) => t,
        None => tail,
    };
    let (pid, count) = tail.split_once('-')?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    (!target.is_empty() && digits(pid) && digits(count)).then_some(())?;
    Some((target, pid.parse().ok()?))
}

/// True when process `pid` may still be writing: this process, or (where `/proc` tells) a
/// running one.
fn may_be_alive(pid: u32) -> bool {
    pid == std::process::id()
        || (Path::new("/proc/self").exists() && Path::new("/proc").join(pid.to_string()).exists())
}

/// The temporary files in `folder` that a run killed before its renames left behind (of this
/// module's naming scheme, written by a process no longer running), by the file name they were
/// staged for. A folder that cannot be read has none.
pub fn leftovers(folder: &Path) -> HashMap<String, Vec<PathBuf>> {
    let mut found: HashMap<String, Vec<PathBuf>> = HashMap::new();
    let folder = if folder.as_os_str().is_empty() {
        Path::new(".")
    } else {
        folder
    };
    let Ok(entries) = std::fs::read_dir(folder) else {
        return found;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some((target, pid)) = name.to_str().and_then(staged_for) else {
            continue;
        };
        let regular = entry.file_type().is_ok_and(|t| t.is_file());
        if regular && !may_be_alive(pid) {
            found
                .entry(target.to_owned())
                .or_default()
                .push(entry.path());
        }
    }
    found
}

/// Renames every staged file into place, in order (stage them all first: see the module docs;
/// put the main file, an image, last). Stops at the first rename that fails; the files not yet
/// renamed are removed.
pub fn commit_all(files: Vec<StagedFile>) -> Result<(), ImageError> {
    files.into_iter().try_for_each(StagedFile::commit)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("penumbra-staged-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_failed_member_leaves_every_old_file_and_no_temporary_one() {
        let dir = scratch("group");
        std::fs::write(dir.join("a.png"), b"old image").unwrap();
        std::fs::write(dir.join("a.depth.pfm"), b"old depth").unwrap();
        let image = StagedFile::write_bytes(&dir.join("a.png"), b"new image").unwrap();
        let depth = StagedFile::write_with(&dir.join("a.depth.pfm"), |f| {
            f.write_all(b"half").unwrap();
            Err("No space left on device".into())
        });
        let e = depth.unwrap_err();
        assert!(e.to_string().contains("a.depth.pfm") && e.to_string().contains("No space"));
        drop(image);
        assert_eq!(names(&dir), ["a.depth.pfm", "a.png"]);
        assert_eq!(std::fs::read(dir.join("a.png")).unwrap(), b"old image");
        assert_eq!(
            std::fs::read(dir.join("a.depth.pfm")).unwrap(),
            b"old depth"
        );

        let image = StagedFile::write_bytes(&dir.join("a.png"), b"new image").unwrap();
        let depth = StagedFile::write_bytes(&dir.join("a.depth.pfm"), b"new depth").unwrap();
        assert_eq!(std::fs::read(dir.join("a.png")).unwrap(), b"old image");
        commit_all(vec![image, depth]).unwrap();
        assert_eq!(names(&dir), ["a.depth.pfm", "a.png"]);
        assert_eq!(std::fs::read(dir.join("a.png")).unwrap(), b"new image");
        assert_eq!(
            std::fs::read(dir.join("a.depth.pfm")).unwrap(),
            b"new depth"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn an_unwritable_folder_is_an_error_naming_the_file() {
        let dir = scratch("missing");
        let path = dir.join("no/such/folder/x.png");
        let e = StagedFile::write_bytes(&path, b"x").unwrap_err();
        assert!(e.to_string().contains("x.png"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn temporary_names_tell_their_file_and_writer() {
        assert_eq!(staged_for(".a.png.tmp-22127-0"), Some(("a.png", 22127)));
        assert_eq!(staged_for(".a.png.tmp-22127-3.png"), Some(("a.png", 22127)));
        assert_eq!(
            staged_for(".a.meta.json.tmp-9-12"),
            Some(("a.meta.json", 9))
        );
        for other in [
            "a.png",
            ".a.png",
            ".a.png.tmp-x-0",
            ".a.png.tmp-1-",
            ".tmp-1-2",
            ".a.png.tmp-1-2.jpg",
        ] {
            assert_eq!(staged_for(other), None, "{other}");
        }
        // A name staged now reads back as this process's.
        let dir = scratch("names");
        let staged = StagedFile::write_bytes(&dir.join("b.pfm"), b"x").unwrap();
        let [name] = &names(&dir)[..] else {
            panic!("{:?}", names(&dir))
        };
        assert_eq!(staged_for(name), Some(("b.pfm", std::process::id())));
        drop(staged);
        assert!(names(&dir).is_empty(), "dropped: removed");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn leftovers_are_those_of_writers_no_longer_running() {
        let dir = scratch("leftovers");
        // A process id above Linux's largest (4194304) is no running process.
        std::fs::write(dir.join(".a.png.tmp-99999999-0"), b"half").unwrap();
        std::fs::write(dir.join(".a.depth.pfm.tmp-99999999-1"), b"half").unwrap();
        let mine = StagedFile::write_bytes(&dir.join("a.png"), b"now").unwrap();
        std::fs::write(dir.join("a.png"), b"old").unwrap();
        let found = leftovers(&dir);
        assert_eq!(found.len(), 2, "{found:?}");
        assert_eq!(found["a.png"], [dir.join(".a.png.tmp-99999999-0")]);
        assert_eq!(
            found["a.depth.pfm"],
            [dir.join(".a.depth.pfm.tmp-99999999-1")]
        );
        drop(mine);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
