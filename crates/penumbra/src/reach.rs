//! What a file may read. A scene file names meshes, images, `.npy` transforms and its output;
//! a model names material libraries, textures and buffers. A render service that takes
//! uploads must not let such a reference read the server's other files (a buffer read from
//! `/etc/passwd` becomes geometry in the image), so one rule holds for every reference:
//!
//! A file reads only files in its root folder and below: a scene file's own folder (standard
//! input's: the current folder), a model's own folder (for its material libraries, their
//! textures and its buffers and images). Folders allowed besides ([`Files::allowing`],
//! `--allow-path DIR`) widen it for every file of the scene. An absolute path, a `..` that
//! climbs out (also percent-encoded in a glTF URI, decoded before this check) and a symbolic
//! link that points out are all refused: on disk the paths are compared with every link
//! resolved; a path that does not exist yet (an output) by its nearest existing folder plus
//! the rest, `..` applied. A pack's files are compared by the names the pack gives them,
//! `..` applied, since a pack reads no disk.

use std::path::{Component, Path, PathBuf};

use thiserror::Error;

use crate::files::Files;

/// The rule, in a sentence, that ends every refusal.
pub const RULE: &str = "a file reads only files in its own folder and below; --allow-path DIR \
                        (allow_paths= in Python) widens that";

/// A reference that names a file outside what its file may read.
#[derive(Clone, Debug, Error, PartialEq, Eq)]
#[error(
    "\"{}\" is outside the {owner}'s folder {} ({RULE})",
    crate::names::escape_controls(reference),
    shown(root)
)]
pub struct Outside {
    /// The file whose reference it is (a scene, a model, a material library).
    pub referrer: PathBuf,
    /// The reference as the file writes it (percent-decoded for a glTF URI).
    pub reference: String,
    /// The folder the file may read in: the scene's or the model's.
    pub root: PathBuf,
    /// Whose folder: "scene" or "model".
    pub owner: &'static str,
}

/// A folder as a message shows it: with a trailing `/`, `./` for the current one.
fn shown(dir: &Path) -> String {
    let text = crate::names::escape_controls(&dir.display().to_string());
    match text.as_str() {
        "" => "./".to_owned(),
        t if t.ends_with('/') => text,
        _ => format!("{text}/"),
    }
}

/// Where the references of one file resolve: its root folder, the folders allowed besides,
/// and the files they are read from.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Reach<'a> {
    files: &'a Files,
    referrer: &'a Path,
    root: &'a Path,
    owner: &'static str,
}

impl<'a> Reach<'a> {
    /// The reach of `referrer`, a scene file (`owner` "scene") or a model ("model"), whose
    /// references may read in `root` and below and in the folders `files` allows.
    pub(crate) fn new(
        files: &'a Files,
        referrer: &'a Path,
        root: &'a Path,
        owner: &'static str,
    ) -> Reach<'a> {
        Reach {
            files,
            referrer,
            root,
            owner,
        }
    }

    /// `reference` (written in the file), resolved against `dir` (the folder of the file that
    /// writes it, below the root), when the rule lets the file read it.
    pub(crate) fn resolve(&self, dir: &Path, reference: &str) -> Result<PathBuf, Outside> {
        let path = dir.join(reference);
        self.check(reference, &path).map(|()| path)
    }

    /// `Ok` when the rule lets the file read `path`, which `reference` names.
    pub(crate) fn check(&self, reference: &str, path: &Path) -> Result<(), Outside> {
        let inside = |dir: &Path| match self.files.is_packed() {
            false => canonical(path).starts_with(canonical(dir)),
            true => lexical(path).starts_with(lexical(dir)),
        };
        if inside(self.root) || self.files.allowed().iter().any(|d| inside(d)) {
            return Ok(());
        }
        Err(Outside {
            referrer: self.referrer.to_owned(),
            reference: reference.to_owned(),
            root: self.root.to_owned(),
            owner: self.owner,
        })
    }
}

/// `path` with every symbolic link resolved: the canonical path of its nearest existing
/// ancestor, then the rest with `..` applied (a missing folder holds no link). Lexical when
/// not even the current folder resolves.
fn canonical(path: &Path) -> PathBuf {
    let path = if path.as_os_str().is_empty() {
        Path::new(".")
    } else {
        path
    };
    for ancestor in path.ancestors() {
        let existing = match ancestor.as_os_str().is_empty() {
            true => Path::new("."),
            false => ancestor,
        };
        let Ok(mut real) = std::fs::canonicalize(existing) else {
            // A link that leads nowhere (or where the path cannot be followed) could lead
            // anywhere once made: no folder holds it.
            if std::fs::symlink_metadata(existing).is_ok() {
                return PathBuf::new();
            }
            continue;
        };
        let rest = path.strip_prefix(ancestor).unwrap_or(Path::new(""));
        for c in rest.components() {
            match c {
                Component::ParentDir => {
                    real.pop();
                }
                Component::Normal(name) => real.push(name),
                _ => {}
            }
        }
        return real;
    }
    lexical(path)
}

/// `path` made absolute against the current folder, `.` dropped and `..` applied, without
/// looking at the file system.
fn lexical(path: &Path) -> PathBuf {
    let path = if path.as_os_str().is_empty() {
        Path::new(".")
    } else {
        path
    };
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_owned());
    let mut out = PathBuf::new();
    for c in absolute.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn temp(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("penumbra-reach-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("scene/sub")).unwrap();
        std::fs::create_dir_all(dir.join("assets")).unwrap();
        std::fs::write(dir.join("scene/sub/m.obj"), "").unwrap();
        std::fs::write(dir.join("assets/a.obj"), "").unwrap();
        std::fs::write(dir.join("secret"), "").unwrap();
        dir
    }

    #[test]
    fn a_file_reads_in_its_folder_and_below_and_in_allowed_folders() {
        let dir = temp("rule");
        let root = dir.join("scene");
        let referrer = root.join("s.toml");
        let disk = Files::disk();
        let reach = Reach::new(&disk, &referrer, &root, "scene");
        assert!(reach.resolve(&root, "sub/m.obj").is_ok());
        assert!(reach.resolve(&root, "./sub/../sub/m.obj").is_ok());
        // Not there yet (an output): its existing folder decides.
        assert!(reach.resolve(&root, "out/new/x.png").is_ok());
        assert!(reach.resolve(&root, "out/new/../../../x.png").is_err());
        for outside in [
            "../secret",
            "../assets/a.obj",
            "sub/../../secret",
            "/etc/passwd",
        ] {
            let e = reach.resolve(&root, outside).unwrap_err();
            assert_eq!(e.reference, outside);
            let message = e.to_string();
            assert!(message.contains("outside the scene's folder"), "{message}");
            assert!(message.contains("--allow-path"), "{message}");
        }
        let allowed = Files::disk().allowing(vec![dir.join("assets")]);
        let reach = Reach::new(&allowed, &referrer, &root, "scene");
        assert!(reach.resolve(&root, "../assets/a.obj").is_ok());
        assert!(reach.resolve(&root, "../secret").is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_symbolic_link_out_of_the_folder_is_refused() {
        let dir = temp("link");
        let root = dir.join("scene");
        std::os::unix::fs::symlink(dir.join("secret"), root.join("inner")).unwrap();
        std::os::unix::fs::symlink(&dir, root.join("up")).unwrap();
        let disk = Files::disk();
        let reach = Reach::new(&disk, &root, &root, "model");
        assert!(reach.resolve(&root, "inner").is_err());
        assert!(reach.resolve(&root, "up/secret").is_err());
        assert!(reach.resolve(&root, "up/scene/sub/m.obj").is_ok());
        // A root reached through a link is the folder it points to.
        std::os::unix::fs::symlink(&root, dir.join("alias")).unwrap();
        let alias = dir.join("alias");
        let reach = Reach::new(&disk, &alias, &alias, "model");
        assert!(reach.resolve(&alias, "sub/m.obj").is_ok());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn packed_files_are_compared_by_their_names() {
        let files = Files::packed(BTreeMap::new());
        let root = Path::new("scenes");
        let reach = Reach::new(&files, root, root, "scene");
        assert!(reach.resolve(root, "a/b.obj").is_ok());
        assert!(reach.resolve(root, "../assets/b.obj").is_err());
        let files = files.allowing(vec![PathBuf::from("assets")]);
        let reach = Reach::new(&files, root, root, "scene");
        assert!(reach.resolve(root, "../assets/b.obj").is_ok());
        assert!(reach.resolve(root, "../assets/../x").is_err());
    }

    #[test]
    fn folders_are_shown_with_a_slash() {
        assert_eq!(shown(Path::new("")), "./");
        assert_eq!(shown(Path::new("scenes")), "scenes/");
        assert_eq!(shown(Path::new("/")), "/");
    }
}
