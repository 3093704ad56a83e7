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

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::image_error::ImageError;

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
            ".{}.tmp-{}-{}",
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
}
