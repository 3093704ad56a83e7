//! Helpers shared by the integration tests of both crates: a temporary folder per test, files
//! and PNGs written into it, editing a scene text one change at a time, finding the line and
//! column of a piece of it, and the small valid scene (TOML and JSON) that tests break.
//!
//! Used as `mod support;` by the tests of `penumbra` and as
//! `#[path = "../../penumbra/tests/support/mod.rs"] mod support;` by those of `penumbra-cli`.

// Every test crate compiles its own copy of this module and uses only part of it; what one
// crate leaves unused is not dead code for the others.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// A fresh folder of its own under Cargo's `CARGO_TARGET_TMPDIR`, removed (with everything
/// in it) when dropped, so that a failing test leaves nothing behind either.
pub struct TempDir {
    path: PathBuf,
}

impl TempDir {
    /// A new empty folder; `name` (the test's) makes it recognizable, the process id and a
    /// counter make it unique among test binaries and tests running at the same time.
    pub fn new(name: &str) -> TempDir {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let path = Path::new(env!("CARGO_TARGET_TMPDIR"))
            .join(format!("penumbra-test-{name}-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&path);
        std::fs::create_dir_all(&path).unwrap_or_else(|e| panic!("create {}: {e}", path.display()));
        TempDir { path }
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// `rel` inside the folder (not created).
    pub fn join(&self, rel: impl AsRef<Path>) -> PathBuf {
        self.path.join(rel)
    }

    /// Writes `contents` to `rel`, creating its folders; returns the full path.
    pub fn write(&self, rel: impl AsRef<Path>, contents: impl AsRef<[u8]>) -> PathBuf {
        let path = self.join(rel);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, contents).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        path
    }

    /// Writes a `width`×`height` 8-bit RGB PNG to `rel` (folders created), with `pixel(x, y)`
    /// at column x, row y from the top; returns the full path.
    pub fn png(
        &self,
        rel: impl AsRef<Path>,
        width: u32,
        height: u32,
        pixel: impl Fn(u32, u32) -> [u8; 3],
    ) -> PathBuf {
        let path = self.join(rel);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        image::RgbImage::from_fn(width, height, |x, y| image::Rgb(pixel(x, y)))
            .save(&path)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        path
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.path);
    }
}

/// `text` with `from`, which must occur exactly once, replaced by `to`.
pub fn edit(text: &str, from: &str, to: &str) -> String {
    assert_eq!(text.matches(from).count(), 1, "{from:?} must occur once");
    text.replacen(from, to, 1)
}

/// 1-based line and column (in characters, as editors count) of the first character of the
/// `n`th (0-based) occurrence of `needle` in `text`.
pub fn nth_position_of(text: &str, needle: &str, n: usize) -> (usize, usize) {
    let (offset, _) = text
        .match_indices(needle)
        .nth(n)
        .unwrap_or_else(|| panic!("{needle:?} does not occur {} times", n + 1));
    let before = &text[..offset];
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (
        before.matches('\n').count() + 1,
        before[line_start..].chars().count() + 1,
    )
}

/// Line and column of the only occurrence of `needle`.
pub fn position_of(text: &str, needle: &str) -> (usize, usize) {
    assert_eq!(
        text.matches(needle).count(),
        1,
        "{needle:?} must occur once"
    );
    nth_position_of(text, needle, 0)
}

/// The 1-based line of the `n`th (0-based) line that contains `needle`. Tests compute the
/// expected line from the text they wrote, so editing a scene cannot silently shift it.
pub fn nth_line_of(text: &str, needle: &str, n: usize) -> usize {
    text.lines()
        .enumerate()
        .filter(|(_, l)| l.contains(needle))
        .nth(n)
        .unwrap_or_else(|| panic!("{needle:?} not on {} lines", n + 1))
        .0
        + 1
}

/// The line of the only line that contains `needle`.
pub fn line_of(text: &str, needle: &str) -> usize {
    assert_eq!(
        text.lines().filter(|l| l.contains(needle)).count(),
        1,
        "{needle:?} must be on one line"
    );
    nth_line_of(text, needle, 0)
}

/// A small valid scene: a floor quad (objects[0]) and a red cube (objects[1]) under a point
/// light (lights[0]). Tests break one thing at a time with [`edit`].
pub const BASE_TOML: &str = r#"[film]
width = 16
height = 12

[camera]
position = [0, 1, 5]
look_at = [0, 0, 0]
up = [0, 1, 0]
fov = 45

[materials.red]
diffuse = [0.8, 0.1, 0.1]
specular = 0.3

[[lights]]
type = "point"
position = [0, 5, 5]

[[objects]]
type = "quad"
corner = [-3, -0.5, 3]
u = [6, 0, 0]
v = [0, 0, -6]

[[objects]]
type = "cube"
material = "red"
center = [0, 0, 0]
size = 1
"#;

/// The camera table of [`BASE_TOML`], for tests that replace it (with cameras of their own,
/// paths, keys).
pub const BASE_CAMERA: &str =
    "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\nup = [0, 1, 0]\nfov = 45\n";

/// [`BASE_TOML`] in JSON, one table or object per line so that lines can be asserted.
pub const BASE_JSON: &str = r#"{
  "film": {"width": 16, "height": 12},
  "camera": {"position": [0, 1, 5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 45},
  "materials": {"red": {"diffuse": [0.8, 0.1, 0.1], "specular": 0.3}},
  "lights": [{"type": "point", "position": [0, 5, 5]}],
  "objects": [
    {"type": "quad", "corner": [-3, -0.5, 3], "u": [6, 0, 0], "v": [0, 0, -6]},
    {"type": "cube", "material": "red", "center": [0, 0, 0], "size": 1}
  ]
}
"#;

/// Triangles of the base scene: a quad (2) and a cube (12).
pub const BASE_TRIANGLES: u64 = 14;

/// [`BASE_TOML`] with the cube's material textured by the image `file` (the texture `wood`).
pub fn with_texture(file: &str) -> String {
    let text = edit(
        BASE_TOML,
        "specular = 0.3\n",
        "specular = 0.3\ntexture = \"wood\"\n",
    );
    format!("{text}\n[textures.wood]\ntype = \"image\"\nfile = \"{file}\"\n")
}

/// [`BASE_TOML`] with the mesh `file` as objects[2].
pub fn with_mesh(file: &str) -> String {
    format!("{BASE_TOML}\n[[objects]]\ntype = \"mesh\"\nfile = \"{file}\"\n")
}

/// A NumPy `.npy` file (version 1, as `numpy.save` writes it) whose header gives `descr` (say
/// `<f4`) and `shape` (say `(2, 4, 4)`), followed by `data`.
pub fn npy(descr: &str, shape: &str, data: &[u8]) -> Vec<u8> {
    let mut text = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    while (10 + text.len() + 1) % 64 != 0 {
        text.push(' ');
    }
    text.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend((text.len() as u16).to_le_bytes());
    bytes.extend(text.as_bytes());
    bytes.extend(data);
    bytes
}

/// A unit cube centred at the origin, as an OBJ file (12 triangles).
pub const CUBE_OBJ: &str = "v -0.5 -0.5 -0.5\nv 0.5 -0.5 -0.5\nv 0.5 0.5 -0.5\nv -0.5 0.5 -0.5\n\
v -0.5 -0.5 0.5\nv 0.5 -0.5 0.5\nv 0.5 0.5 0.5\nv -0.5 0.5 0.5\n\
f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 4 7 3\nf 4 8 7\nf 1 5 8\nf 1 8 4\n\
f 2 3 7\nf 2 7 6\n";
