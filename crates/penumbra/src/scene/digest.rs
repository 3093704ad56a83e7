//! The scene digest that records beside images keep (`penumbra render --meta` and `--resume`,
//! and Python's `render_views(meta=True)`): a short hash of everything a scene's world is
//! built from, so that a record tells runs of one scene apart from runs of an edited one, or
//! of one whose mesh or texture changed.

use std::path::PathBuf;

use super::SceneFile;
use crate::fnv::Fnv1a;

impl SceneFile {
    /// The digest of this file's text, the overrides applied to it (in order) and the bytes
    /// of `read`, every file its build read ([`Scene::files`](super::Scene::files)): 64-bit
    /// FNV-1a, as 16 hex digits. A file's bytes are those the build read when this file keeps
    /// them ([`SceneFile::keeping_files`], or a pack's), else read again now; a file that
    /// cannot be read counts as such, so the digest always exists. Not a cryptographic hash:
    /// it tells versions of one scene apart, it does not defend against forgery.
    ///
    /// ```
    /// let text = "[film]\nwidth = 4\nheight = 3\n\
    ///     [camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov = 40\n";
    /// let file =
    ///     penumbra::SceneFile::from_str(text, penumbra::SceneFormat::Toml, "a.toml", ".").unwrap();
    /// let edited = penumbra::SceneFile::from_str(
    ///     &text.replace("40", "41"), penumbra::SceneFormat::Toml, "a.toml", ".",
    /// ).unwrap();
    /// assert_eq!(file.digest(&[]).len(), 16);
    /// assert_ne!(file.digest(&[]), edited.digest(&[]));
    /// ```
    pub fn digest(&self, read: &[PathBuf]) -> String {
        let mut hash = Fnv1a::new();
        hash.eat(self.text().as_bytes());
        for text in self.source.overrides() {
            hash.eat(b"\0--set\0");
            hash.eat(text.as_bytes());
        }
        for path in read {
            hash.eat(b"\0file\0");
            let bytes = match self.files().kept(path) {
                Some(bytes) => Ok(bytes),
                None => self.files().read(path, u64::MAX),
            };
            match bytes {
                Ok(bytes) => hash.eat(&bytes),
                Err(_) => hash.eat(b"\0unreadable\0"),
            }
        }
        format!("{:016x}", hash.0)
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use super::*;
    use crate::files::Files;
    use crate::scene::{Override, SceneFormat};

    const TEXT: &str = "[film]\nwidth = 4\nheight = 3\n\
        [camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov = 40\n";

    fn file(overrides: &[&str]) -> SceneFile {
        let set: Vec<Override> = overrides
            .iter()
            .map(|o| Override::parse(o).unwrap())
            .collect();
        SceneFile::from_str_with(TEXT, SceneFormat::Toml, "a.toml", ".", &set).unwrap()
    }

    /// FNV-1a of the bytes, written out as the algorithm states it.
    fn fnv(bytes: &[u8]) -> String {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for &b in bytes {
            h = (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3);
        }
        format!("{h:016x}")
    }

    #[test]
    fn the_digest_is_fnv1a_of_the_text_the_overrides_and_the_files() {
        assert_eq!(file(&[]).digest(&[]), fnv(TEXT.as_bytes()));
        let set = file(&["film.width=8", "render.seed=3"]);
        let expected = format!("{TEXT}\0--set\0film.width=8\0--set\0render.seed=3");
        assert_eq!(set.digest(&[]), fnv(expected.as_bytes()));
        // Files come from the pack (as a kept build's do): their bytes, in the order given;
        // one missing counts as unreadable.
        let packed = BTreeMap::from([(PathBuf::from("m.obj"), b"v 0 0 0".to_vec())]);
        let f = file(&[]).with_files(Files::packed(packed));
        let read = [PathBuf::from("m.obj"), PathBuf::from("gone.png")];
        let expected = format!("{TEXT}\0file\0v 0 0 0\0file\0\0unreadable\0");
        assert_eq!(f.digest(&read), fnv(expected.as_bytes()));
    }

    #[test]
    fn a_changed_file_changes_the_digest() {
        let dir = std::env::temp_dir().join(format!("penumbra-digest-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mesh = dir.join("m.obj");
        std::fs::write(&mesh, "v 0 0 0\n").unwrap();
        let read = [mesh.clone()];
        let before = file(&[]).digest(&read);
        assert_eq!(before, file(&[]).digest(&read));
        std::fs::write(&mesh, "v 0 0 1\n").unwrap();
        let after = file(&[]).digest(&read);
        std::fs::remove_dir_all(&dir).unwrap();
        assert_ne!(before, after);
        assert_ne!(
            after,
            file(&[]).digest(&read),
            "a missing file is unreadable"
        );
    }
}
