//! End-to-end tests of the `penumbra` binary: what a user sees when they run it. Exit codes,
//! the one-line `error:` messages of SPEC §8 (docs/spec.md) (file, line:col, key path), that a failed run
//! leaves no image (and no temporary file) behind, the success paths of SPEC §9, and that
//! images do not depend on the thread count or on rendering a sub-region.
//!
//! Every test works in its own fresh folder under the system temp dir, removed when it ends.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

// ---------------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------------

/// A fresh folder for one test, holding its scenes, meshes, textures and images. Removed on
/// drop, so a failing test leaves nothing behind either.
struct Sandbox {
    dir: PathBuf,
}

impl Sandbox {
    fn new(test: &str) -> Sandbox {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!(
            "penumbra-cli-test-{test}-{}-{n}",
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("create the test folder");
        Sandbox { dir }
    }

    /// `rel` inside the sandbox (not created).
    fn path(&self, rel: &str) -> PathBuf {
        self.dir.join(rel)
    }

    /// Writes a file (scene, mesh, texture), creating its folder; returns its path.
    fn write(&self, rel: &str, contents: impl AsRef<[u8]>) -> PathBuf {
        let path = self.path(rel);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, contents).unwrap();
        path
    }

    /// The conventional output of failing runs: `-o` points here.
    fn out(&self) -> PathBuf {
        self.path("out.png")
    }

    /// Asserts that no image and no half-written temporary file (`.out.png.tmp-PID`) exists.
    fn assert_no_output(&self) {
        assert!(!self.out().exists(), "an output image was written");
        let leftovers: Vec<String> = std::fs::read_dir(&self.dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains("out.") || n.contains(".tmp"))
            .collect();
        assert!(leftovers.is_empty(), "files left behind: {leftovers:?}");
    }
}

impl Drop for Sandbox {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// What a run of the binary produced.
#[derive(Debug)]
struct Run {
    /// Exit code; `None` when killed by a signal.
    code: Option<i32>,
    stdout: String,
    stderr: String,
}

fn command() -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_penumbra"));
    // Without it, a panic prints the hint "run with `RUST_BACKTRACE=1`", which the error
    // checks look for; with it set by the caller, a backtrace would be printed instead.
    cmd.env_remove("RUST_BACKTRACE");
    cmd
}

/// Runs `penumbra ARGS` in `cwd` and collects its exit code and output.
fn run_in<S: AsRef<OsStr>>(cwd: &Path, args: impl IntoIterator<Item = S>) -> Run {
    let out = command()
        .args(args)
        .current_dir(cwd)
        .stdin(Stdio::null())
        .output()
        .expect("run the penumbra binary");
    Run {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// Runs `penumbra ARGS` in the system temp dir (tests pass absolute paths).
fn run<S: AsRef<OsStr>>(args: impl IntoIterator<Item = S>) -> Run {
    run_in(&std::env::temp_dir(), args)
}

/// `penumbra render SCENE -o OUT [EXTRA...]`.
fn render(scene: &Path, out: &Path, extra: &[&str]) -> Run {
    let mut args: Vec<&OsStr> = vec![
        "render".as_ref(),
        scene.as_ref(),
        "-o".as_ref(),
        out.as_ref(),
    ];
    args.extend(extra.iter().map(OsStr::new));
    run(args)
}

/// Asserts a successful run and returns it.
fn ok(r: Run) -> Run {
    assert_eq!(r.code, Some(0), "expected success: {r:#?}");
    r
}

/// The single `error:` line of a failed run, after checking what SPEC §8 asks of every
/// failure: the exit code, exactly one message, no panic or backtrace.
fn error_line(r: &Run, code: i32) -> String {
    assert_eq!(r.code, Some(code), "exit code: {r:#?}");
    for word in ["panicked", "RUST_BACKTRACE", "backtrace"] {
        assert!(!r.stderr.contains(word), "panic on stderr: {}", r.stderr);
    }
    let errors: Vec<&str> = r
        .stderr
        .lines()
        .filter(|l| l.starts_with("error:"))
        .collect();
    assert_eq!(errors.len(), 1, "want one error line: {}", r.stderr);
    assert!(
        r.stderr.starts_with("error:"),
        "stderr must start with the error: {}",
        r.stderr
    );
    errors[0].to_owned()
}

/// What a scene-file error must say.
struct Expect<'a> {
    /// The 1-based line the error is on.
    line: usize,
    /// The key path, as `objects[1].material`; `None` for errors about the whole file.
    key: Option<&'a str>,
    /// Words the message must contain (what is wrong), case-insensitive.
    words: &'a [&'a str],
}

/// Checks a scene-file error line: `error: FILE:LINE:COL: KEY: message`.
fn assert_located(line: &str, scene: &Path, want: &Expect) {
    let prefix = format!("error: {}:", scene.display());
    let rest = line
        .strip_prefix(&prefix)
        .unwrap_or_else(|| panic!("error does not start with {prefix:?}: {line}"));
    let mut parts = rest.splitn(3, ':');
    let (l, c, message) = (
        parts.next().unwrap_or(""),
        parts.next().unwrap_or(""),
        parts.next().unwrap_or(""),
    );
    assert_eq!(l.parse::<usize>().ok(), Some(want.line), "line in: {line}");
    let col: usize = c.parse().unwrap_or_else(|_| panic!("no column in: {line}"));
    assert!(col >= 1, "columns are 1-based: {line}");
    match want.key {
        Some(key) => assert!(
            message.starts_with(&format!(" {key}: ")),
            "key path {key:?} missing in: {line}"
        ),
        // An error about the whole file names no key path, just the message.
        None => assert!(message.starts_with(' '), "{line}"),
    }
    assert!(message.trim().len() > 3, "says what is wrong: {line}");
    let lower = message.to_lowercase();
    for w in want.words {
        assert!(
            lower.contains(&w.to_lowercase()),
            "{w:?} missing in: {line}"
        );
    }
}

/// Renders a bad scene file: exit 2, one located message, no image. Returns the message.
fn expect_scene_error(sb: &Sandbox, name: &str, text: &str, want: Expect) -> String {
    let scene = sb.write(name, text);
    let r = render(&scene, &sb.out(), &[]);
    let line = error_line(&r, 2);
    assert_eq!(r.stderr.lines().count(), 1, "one line: {}", r.stderr);
    assert_located(&line, &scene, &want);
    assert!(r.stdout.is_empty(), "stdout: {}", r.stdout);
    sb.assert_no_output();
    line
}

/// A usage error: exit 2 (or `code`), one message containing `words`, no image.
fn expect_usage_error(sb: &Sandbox, r: &Run, code: i32, words: &[&str]) -> String {
    let line = error_line(r, code);
    for w in words {
        assert!(r.stderr.contains(w), "{w:?} missing in: {}", r.stderr);
    }
    sb.assert_no_output();
    line
}

/// `text` with `from` (which must occur exactly once) replaced by `to`.
fn edit(text: &str, from: &str, to: &str) -> String {
    assert_eq!(text.matches(from).count(), 1, "{from:?} must occur once");
    text.replacen(from, to, 1)
}

/// The 1-based line of the `n`th (0-based) line that contains `needle`. Tests compute the
/// expected line from the text they wrote, so editing a scene cannot silently shift it.
fn nth_line_of(text: &str, needle: &str, n: usize) -> usize {
    text.lines()
        .enumerate()
        .filter(|(_, l)| l.contains(needle))
        .nth(n)
        .unwrap_or_else(|| panic!("{needle:?} not in the scene"))
        .0
        + 1
}

/// The line of the only line that contains `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    assert_eq!(
        text.lines().filter(|l| l.contains(needle)).count(),
        1,
        "{needle:?} must be on one line"
    );
    nth_line_of(text, needle, 0)
}

fn decode(path: &Path) -> image::RgbImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8()
}

fn distinct_pixels(img: &image::RgbImage) -> usize {
    let mut px: Vec<[u8; 3]> = img.pixels().map(|p| p.0).collect();
    px.sort_unstable();
    px.dedup();
    px.len()
}

// ---------------------------------------------------------------------------------------------
// Scenes
// ---------------------------------------------------------------------------------------------

/// A small valid scene: a floor quad (objects[0]) and a red cube (objects[1]) under a point
/// light. Tests break one thing at a time with `edit`.
const BASE: &str = r#"[film]
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

/// The same scene in JSON, one entry per line so that lines can be asserted.
const BASE_JSON: &str = r#"{
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

/// Triangles of BASE: a quad (2) and a cube (12).
const BASE_TRIANGLES: u64 = 14;

/// The second `[[objects]]` header: where errors about the cube as a whole point.
fn cube_header_line(text: &str) -> usize {
    nth_line_of(text, "[[objects]]", 1)
}

/// A scene whose image depends on every random choice: jittered pixel samples, a jittered
/// area light with soft shadows, and a checker texture.
fn noisy_scene(width: u32, height: u32) -> String {
    format!(
        r#"[film]
width = {width}
height = {height}

[camera]
position = [0, 2, 5]
look_at = [0, 0, 0]
fov = 50

[render]
sampler = "jittered"
samples = 4
seed = 7

[textures.board]
type = "checker"
checks = 4

[materials.floor]
texture = "board"

[materials.red]
diffuse = [0.8, 0.1, 0.1]
specular = 0.5
shininess = 20

[[lights]]
type = "area"
center = [0, 3, 0]
u = [2, 0, 0]
v = [0, 0, 2]
samples = 3
jitter = true

[[objects]]
type = "quad"
material = "floor"
corner = [-3, -0.5, 3]
u = [6, 0, 0]
v = [0, 0, -6]

[[objects]]
type = "sphere"
material = "red"
center = [0, 0.3, 0]
radius = 0.8
"#
    )
}

// ---------------------------------------------------------------------------------------------
// Scene-file errors (SPEC §8): TOML
// ---------------------------------------------------------------------------------------------

#[test]
fn the_base_scenes_are_valid() {
    // Every error test below breaks one thing in these; they must render as they are.
    let sb = Sandbox::new("base");
    for (name, text) in [("scene.toml", BASE), ("scene.json", BASE_JSON)] {
        let scene = sb.write(name, text);
        ok(render(&scene, &sb.out(), &["--quiet"]));
        assert_eq!(decode(&sb.out()).dimensions(), (16, 12));
        std::fs::remove_file(sb.out()).unwrap();
    }
}

#[test]
fn unknown_top_level_key() {
    let sb = Sandbox::new("unknown-top");
    let text = format!("colour = 1\n{BASE}");
    let words = &["unknown", "colour"];
    expect_scene_error(
        &sb,
        "s.toml",
        &text,
        Expect {
            line: 1,
            key: Some("colour"),
            words,
        },
    );
}

#[test]
fn unknown_key_in_film() {
    let sb = Sandbox::new("unknown-film");
    let text = edit(BASE, "height = 12\n", "height = 12\nwidht = 3\n");
    let want = Expect {
        line: line_of(&text, "widht"),
        key: Some("film.widht"),
        words: &["unknown", "widht"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn unknown_key_in_an_object() {
    let sb = Sandbox::new("unknown-object");
    let text = edit(BASE, "size = 1\n", "size = 1\ncolor = [1, 0, 0]\n");
    let want = Expect {
        line: line_of(&text, "color ="),
        key: Some("objects[1].color"),
        words: &["unknown", "color"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn key_of_another_object_type() {
    // `radius` is a key of spheres: known to the schema, but meaningless on a cube.
    let sb = Sandbox::new("foreign-key");
    let text = edit(BASE, "size = 1\n", "size = 1\nradius = 2\n");
    let want = Expect {
        line: line_of(&text, "radius"),
        key: Some("objects[1].radius"),
        words: &["radius", "cube"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn wrong_type() {
    let sb = Sandbox::new("wrong-type");
    let text = edit(BASE, "width = 16", "width = \"16\"");
    let want = Expect {
        line: line_of(&text, "width"),
        key: Some("film.width"),
        words: &["string"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);

    let text = edit(BASE, "size = 1", "size = \"big\"");
    let want = Expect {
        line: line_of(&text, "size ="),
        key: Some("objects[1].size"),
        words: &["string"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn missing_film_width() {
    // A missing key points at the table that lacks it, and the message names the key.
    let sb = Sandbox::new("missing-width");
    let text = edit(BASE, "width = 16\n", "");
    let want = Expect {
        line: line_of(&text, "[film]"),
        key: Some("film"),
        words: &["missing", "width"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn missing_camera_position() {
    let sb = Sandbox::new("missing-position");
    let text = edit(BASE, "position = [0, 1, 5]\n", "");
    let want = Expect {
        line: line_of(&text, "[camera]"),
        key: Some("camera"),
        words: &["missing", "position"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn missing_cube_center() {
    let sb = Sandbox::new("missing-center");
    let text = edit(BASE, "center = [0, 0, 0]\n", "");
    let want = Expect {
        line: cube_header_line(&text),
        key: Some("objects[1]"),
        words: &["missing", "center"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn missing_camera_table() {
    // Nothing to point at but the file itself: its first line.
    let sb = Sandbox::new("missing-camera");
    let start = BASE.find("[camera]").unwrap();
    let end = BASE.find("[materials.red]").unwrap();
    let text = format!("{}{}", &BASE[..start], &BASE[end..]);
    let words = &["missing", "camera"];
    expect_scene_error(
        &sb,
        "s.toml",
        &text,
        Expect {
            line: 1,
            key: None,
            words,
        },
    );
}

#[test]
fn unknown_material_name() {
    let sb = Sandbox::new("unknown-material");
    let text = edit(BASE, "material = \"red\"", "material = \"rde\"");
    let want = Expect {
        line: line_of(&text, "material = "),
        key: Some("objects[1].material"),
        // The message lists the names that exist, to spot the typo.
        words: &["unknown material", "rde", "red"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn unknown_texture_name() {
    let sb = Sandbox::new("unknown-texture");
    let text = edit(
        BASE,
        "specular = 0.3\n",
        "specular = 0.3\ntexture = \"wood\"\n",
    );
    let want = Expect {
        line: line_of(&text, "texture ="),
        key: Some("materials.red.texture"),
        words: &["unknown texture", "wood"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn samples_not_a_perfect_square() {
    let sb = Sandbox::new("samples");
    let text = format!("{BASE}\n[render]\nsamples = 3\n");
    let want = Expect {
        line: line_of(&text, "samples = 3"),
        key: Some("render.samples"),
        words: &["perfect square", "3"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn fov_out_of_range() {
    let sb = Sandbox::new("fov");
    for fov in ["0", "180", "-10", "200"] {
        let text = edit(BASE, "fov = 45", &format!("fov = {fov}"));
        let want = Expect {
            line: line_of(&text, "fov"),
            key: Some("camera.fov"),
            words: &["fov", fov],
        };
        expect_scene_error(&sb, "s.toml", &text, want);
    }
}

#[test]
fn degenerate_camera() {
    let sb = Sandbox::new("degenerate");
    // look_at == position: no view direction at all.
    let text = edit(BASE, "look_at = [0, 0, 0]", "look_at = [0, 1, 5]");
    let want = Expect {
        line: line_of(&text, "look_at"),
        key: Some("camera.look_at"),
        words: &["degenerate"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);

    // Looking straight down with up = +y: no way to tell right from left.
    let text = edit(BASE, "look_at = [0, 0, 0]", "look_at = [0, -3, 5]");
    let want = Expect {
        line: line_of(&text, "look_at"),
        key: Some("camera.look_at"),
        words: &["degenerate", "parallel"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn degenerate_named_camera_that_is_not_rendered() {
    // Every camera is checked, not only the one rendered: the file is wrong either way.
    let sb = Sandbox::new("degenerate-named");
    let text = edit(BASE, "[camera]", "[cameras.front]");
    let text =
        format!("{text}\n[cameras.top]\nposition = [0, 5, 0]\nlook_at = [0, 0, 0]\nfov = 30\n");
    let want = Expect {
        line: nth_line_of(&text, "look_at", 1),
        key: Some("cameras.top.look_at"),
        words: &["degenerate"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn non_finite_numbers() {
    let sb = Sandbox::new("non-finite");
    let text = edit(BASE, "fov = 45", "fov = inf");
    let want = Expect {
        line: line_of(&text, "fov"),
        key: Some("camera.fov"),
        words: &["finite"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);

    let text = edit(BASE, "position = [0, 1, 5]", "position = [0, nan, 5]");
    let want = Expect {
        line: line_of(&text, "nan"),
        key: Some("camera.position[1]"),
        words: &["finite"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);

    // Colors take a plain number too, through another code path.
    let text = edit(BASE, "specular = 0.3", "specular = -inf");
    let want = Expect {
        line: line_of(&text, "specular"),
        key: Some("materials.red.specular"),
        words: &["finite"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn numbers_beyond_the_range_of_32_bit_floats() {
    // Finite as f64 but infinite once the renderer stores them as f32.
    let sb = Sandbox::new("f32-range");
    let text = edit(BASE, "position = [0, 1, 5]", "position = [0, 1e39, 5]");
    let want = Expect {
        line: line_of(&text, "1e39"),
        key: Some("camera.position[1]"),
        words: &["out of range"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);

    let text = edit(BASE, "specular = 0.3", "specular = 1e300");
    let want = Expect {
        line: line_of(&text, "specular"),
        key: Some("materials.red.specular"),
        words: &["out of range"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn negative_sizes() {
    let sb = Sandbox::new("negative");
    for size in ["-1", "[1, -1, 1]"] {
        let text = edit(BASE, "size = 1", &format!("size = {size}"));
        let want = Expect {
            line: line_of(&text, "size ="),
            key: Some("objects[1].size"),
            words: &["negative"],
        };
        expect_scene_error(&sb, "s.toml", &text, want);
    }
    let text = edit(BASE, "type = \"cube\"", "type = \"sphere\"\nradius = -1\n");
    let text = edit(&text, "size = 1\n", "");
    let want = Expect {
        line: line_of(&text, "radius"),
        key: Some("objects[1].radius"),
        words: &["negative"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn both_camera_and_named_cameras() {
    let sb = Sandbox::new("both-cameras");
    let text =
        format!("{BASE}\n[cameras.side]\nposition = [5, 1, 0]\nlook_at = [0, 0, 0]\nfov = 45\n");
    let want = Expect {
        line: line_of(&text, "[cameras.side]"),
        key: Some("cameras"),
        words: &["either", "not both"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn toml_syntax_errors() {
    let sb = Sandbox::new("toml-syntax");
    for (from, to) in [
        ("fov = 45", "fov = = 45"),
        ("look_at = [0, 0, 0]", "look_at = [0, 0, 0]]"),
        ("fov = 45", "fov = 45 45"),
        ("[materials.red]", "[materials.red"),
        ("size = 1", "size = 1\nsize = 2"),
    ] {
        let text = edit(BASE, from, to);
        let bad = to.lines().last().unwrap();
        let want = Expect {
            line: line_of(&text, bad),
            key: None,
            words: &[],
        };
        expect_scene_error(&sb, "s.toml", &text, want);
    }
}

#[test]
fn resolution_too_large() {
    let sb = Sandbox::new("too-large");
    let text = edit(
        BASE,
        "width = 16\nheight = 12",
        "width = 100000\nheight = 100000",
    );
    let want = Expect {
        line: line_of(&text, "width"),
        key: Some("film.width"),
        words: &["too large", "100000x100000"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);

    // The same through the command line: named by its flags instead of a line.
    let scene = sb.write("ok.toml", BASE);
    let r = render(
        &scene,
        &sb.out(),
        &["--width", "100000", "--height", "100000"],
    );
    expect_usage_error(&sb, &r, 2, &["--width", "too large"]);
}

#[test]
fn unknown_output_format_in_the_scene() {
    // film.output is part of the scene file, so a bad one is located like any other value.
    let sb = Sandbox::new("film-output-format");
    let text = edit(BASE, "height = 12\n", "height = 12\noutput = \"out.bmp\"\n");
    let want = Expect {
        line: line_of(&text, "output"),
        key: Some("film.output"),
        words: &["out.bmp", ".png"],
    };
    let scene = sb.write("s.toml", &text);
    // Without -o (the image would go to film.output) ...
    let line = error_line(&run(["render".as_ref(), scene.as_os_str()]), 2);
    assert_located(&line, &scene, &want);
    assert!(!sb.path("out.bmp").exists());
    // ... with `check` ...
    let line = error_line(&run(["check".as_ref(), scene.as_os_str()]), 2);
    assert_located(&line, &scene, &want);
    // ... and even when -o names a good file: the scene file is wrong either way.
    expect_scene_error(&sb, "s.toml", &text, want);
}

// ---------------------------------------------------------------------------------------------
// Scene-file errors: JSON
// ---------------------------------------------------------------------------------------------

#[test]
fn json_unknown_keys() {
    let sb = Sandbox::new("json-unknown");
    let text = edit(
        BASE_JSON,
        "{\n  \"film\"",
        "{\n  \"colour\": 1,\n  \"film\"",
    );
    let want = Expect {
        line: line_of(&text, "colour"),
        key: Some("colour"),
        words: &["unknown", "colour"],
    };
    expect_scene_error(&sb, "s.json", &text, want);

    let text = edit(
        BASE_JSON,
        "\"height\": 12}",
        "\"height\": 12, \"widht\": 3}",
    );
    let want = Expect {
        line: line_of(&text, "widht"),
        key: Some("film.widht"),
        words: &["unknown", "widht"],
    };
    expect_scene_error(&sb, "s.json", &text, want);

    let text = edit(BASE_JSON, "\"size\": 1}", "\"size\": 1, \"radius\": 2}");
    let want = Expect {
        line: line_of(&text, "radius"),
        key: Some("objects[1].radius"),
        words: &["radius", "cube"],
    };
    expect_scene_error(&sb, "s.json", &text, want);
}

#[test]
fn json_wrong_type_and_missing_keys() {
    let sb = Sandbox::new("json-type");
    let text = edit(BASE_JSON, "\"width\": 16", "\"width\": \"16\"");
    let want = Expect {
        line: line_of(&text, "width"),
        key: Some("film.width"),
        words: &["string"],
    };
    expect_scene_error(&sb, "s.json", &text, want);

    let text = edit(BASE_JSON, "\"width\": 16, ", "");
    let want = Expect {
        line: line_of(&text, "film"),
        key: Some("film"),
        words: &["missing", "width"],
    };
    expect_scene_error(&sb, "s.json", &text, want);

    let text = edit(BASE_JSON, "\"position\": [0, 1, 5], ", "");
    let want = Expect {
        line: line_of(&text, "camera"),
        key: Some("camera"),
        words: &["missing", "position"],
    };
    expect_scene_error(&sb, "s.json", &text, want);

    let text = edit(BASE_JSON, "\"center\": [0, 0, 0], ", "");
    let want = Expect {
        line: line_of(&text, "cube"),
        key: Some("objects[1]"),
        words: &["missing", "center"],
    };
    expect_scene_error(&sb, "s.json", &text, want);
}

#[test]
fn json_bad_values() {
    let sb = Sandbox::new("json-values");
    let text = edit(BASE_JSON, "\"material\": \"red\"", "\"material\": \"rde\"");
    let want = Expect {
        line: line_of(&text, "rde"),
        key: Some("objects[1].material"),
        words: &["unknown material", "rde"],
    };
    expect_scene_error(&sb, "s.json", &text, want);

    let text = edit(BASE_JSON, "\"fov\": 45", "\"fov\": 180");
    let want = Expect {
        line: line_of(&text, "fov"),
        key: Some("camera.fov"),
        words: &["fov"],
    };
    expect_scene_error(&sb, "s.json", &text, want);

    let text = edit(
        BASE_JSON,
        "\"look_at\": [0, 0, 0]",
        "\"look_at\": [0, 1, 5]",
    );
    let want = Expect {
        line: line_of(&text, "look_at"),
        key: Some("camera.look_at"),
        words: &["degenerate"],
    };
    expect_scene_error(&sb, "s.json", &text, want);

    let text = edit(BASE_JSON, "\"size\": 1}", "\"size\": -1}");
    let want = Expect {
        line: line_of(&text, "\"size\""),
        key: Some("objects[1].size"),
        words: &["negative"],
    };
    expect_scene_error(&sb, "s.json", &text, want);

    // JSON has no infinity; a number too large for a double is its way of writing one.
    let text = edit(BASE_JSON, "\"fov\": 45", "\"fov\": 1e999");
    let want = Expect {
        line: line_of(&text, "fov"),
        key: Some("camera.fov"),
        words: &[],
    };
    expect_scene_error(&sb, "s.json", &text, want);
}

#[test]
fn json_syntax_errors() {
    let sb = Sandbox::new("json-syntax");
    let text = edit(BASE_JSON, "\"fov\": 45}", "\"fov\": 45,}");
    let want = Expect {
        line: line_of(&text, "fov"),
        key: None,
        words: &[],
    };
    // serde_json names the enclosing key (`camera`) for errors inside a value; either way
    // the line must be right.
    let scene = sb.write("s.json", &text);
    let line = error_line(&render(&scene, &sb.out(), &[]), 2);
    let want_prefix = format!("error: {}:{}:", scene.display(), want.line);
    assert!(line.starts_with(&want_prefix), "{line}");
    sb.assert_no_output();

    // A file cut off after a newline: the column must still be 1-based.
    let text = &BASE_JSON[..BASE_JSON.find("  \"lights\"").unwrap()];
    let lines = text.lines().count();
    let want = Expect {
        line: lines + 1,
        key: None,
        words: &["eof"],
    };
    expect_scene_error(&sb, "s.json", text, want);
}

#[test]
fn json_columns_count_characters() {
    // Columns are in characters, as editors count them, also for serde_json's own errors.
    let sb = Sandbox::new("json-columns");
    let text = "{\"film\": {\"width\": 16, \"höhe\": 12}}\n";
    let scene = sb.write("s.json", text);
    let line = error_line(&render(&scene, &sb.out(), &[]), 2);
    let byte = text.find("höhe").unwrap();
    let chars = text[..byte].chars().count() + 1;
    // The column points at or just after the key, in characters.
    let col: usize = line
        .strip_prefix(&format!("error: {}:1:", scene.display()))
        .and_then(|r| r.split(':').next())
        .and_then(|c| c.parse().ok())
        .unwrap_or_else(|| panic!("{line}"));
    // From the key's opening quote to its closing one; counting bytes would land one past.
    let close = text[..byte + "höhe".len()].chars().count() + 1;
    assert!(
        (chars - 1..=close).contains(&col),
        "column {col} should be within {}..={close}: {line}",
        chars - 1
    );
}

// ---------------------------------------------------------------------------------------------
// Files the scene refers to, and the scene file itself
// ---------------------------------------------------------------------------------------------

#[test]
fn missing_scene_file() {
    let sb = Sandbox::new("missing-scene");
    let scene = sb.path("nosuch.toml");
    let line = error_line(&render(&scene, &sb.out(), &[]), 2);
    assert!(line.contains(&scene.display().to_string()), "{line}");
    sb.assert_no_output();
}

#[test]
fn unknown_scene_extension() {
    let sb = Sandbox::new("scene-extension");
    let scene = sb.write("scene.yaml", BASE);
    let line = error_line(&render(&scene, &sb.out(), &[]), 2);
    assert!(line.contains(&scene.display().to_string()), "{line}");
    assert!(line.contains(".toml") && line.contains(".json"), "{line}");
    sb.assert_no_output();
}

/// BASE with an image texture on the cube's material.
fn with_texture(file: &str) -> String {
    let text = edit(
        BASE,
        "specular = 0.3\n",
        "specular = 0.3\ntexture = \"wood\"\n",
    );
    format!("{text}\n[textures.wood]\ntype = \"image\"\nfile = \"{file}\"\n")
}

#[test]
fn missing_texture_file() {
    let sb = Sandbox::new("missing-texture");
    let text = with_texture("textures/nosuch.png");
    let want = Expect {
        line: line_of(&text, "nosuch.png"),
        key: Some("textures.wood.file"),
        words: &["nosuch.png"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn corrupt_texture_file() {
    let sb = Sandbox::new("corrupt-texture");
    sb.write("textures/wood.png", b"this is not a PNG file");
    let text = with_texture("textures/wood.png");
    let want = Expect {
        line: line_of(&text, "wood.png"),
        key: Some("textures.wood.file"),
        words: &["wood.png"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn textures_are_relative_to_the_scene_folder() {
    // The same texture path that fails above works once the file is where the scene says.
    let sb = Sandbox::new("texture-relative");
    let img =
        image::RgbImage::from_fn(4, 4, |x, y| image::Rgb([(x * 60) as u8, (y * 60) as u8, 0]));
    std::fs::create_dir_all(sb.path("scenes/textures")).unwrap();
    img.save(sb.path("scenes/textures/wood.png")).unwrap();
    let scene = sb.write("scenes/s.toml", with_texture("textures/wood.png"));
    ok(render(&scene, &sb.out(), &["--quiet"]));
    assert_eq!(decode(&sb.out()).dimensions(), (16, 12));
}

/// BASE with a mesh as objects[2].
fn with_mesh(file: &str) -> String {
    format!("{BASE}\n[[objects]]\ntype = \"mesh\"\nfile = \"{file}\"\n")
}

#[test]
fn missing_mesh_file() {
    let sb = Sandbox::new("missing-mesh");
    let text = with_mesh("meshes/nosuch.obj");
    let want = Expect {
        line: line_of(&text, "nosuch.obj"),
        key: Some("objects[2].file"),
        words: &["nosuch.obj"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn obj_index_out_of_range() {
    let sb = Sandbox::new("obj-index");
    sb.write("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    let text = with_mesh("bad.obj");
    let want = Expect {
        line: line_of(&text, "bad.obj"),
        key: Some("objects[2].file"),
        words: &["bad.obj"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn corrupt_obj_file() {
    let sb = Sandbox::new("obj-corrupt");
    sb.write("bad.obj", "v 0 0 0\nv 1 0 zero\nv 0 1 0\nf 1 2 3\n");
    let text = with_mesh("bad.obj");
    let want = Expect {
        line: line_of(&text, "bad.obj"),
        key: Some("objects[2].file"),
        words: &["bad.obj"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn meshes_are_relative_to_the_scene_folder() {
    let sb = Sandbox::new("mesh-relative");
    sb.write(
        "scenes/meshes/tri.obj",
        "v -1 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    let scene = sb.write("scenes/s.toml", with_mesh("meshes/tri.obj"));
    let r = ok(run([
        "check".as_ref(),
        scene.as_os_str(),
        "--json".as_ref(),
    ]));
    let v: serde_json::Value = serde_json::from_str(r.stdout.trim()).unwrap();
    assert_eq!(v["triangles"], BASE_TRIANGLES + 1);
}

// ---------------------------------------------------------------------------------------------
// Usage errors (SPEC §9)
// ---------------------------------------------------------------------------------------------

#[test]
fn unknown_flag() {
    let sb = Sandbox::new("unknown-flag");
    let scene = sb.write("s.toml", BASE);
    let r = render(&scene, &sb.out(), &["--sppp", "4"]);
    expect_usage_error(&sb, &r, 2, &["--sppp"]);
}

#[test]
fn spp_not_a_perfect_square() {
    let sb = Sandbox::new("spp");
    let scene = sb.write("s.toml", BASE);
    let r = render(&scene, &sb.out(), &["--spp", "3"]);
    expect_usage_error(&sb, &r, 2, &["--spp", "perfect square"]);
}

#[test]
fn huge_spp_is_an_error_not_a_panic() {
    // 4294967295 rounds to a square root of 65536, whose square overflows 32 bits.
    let sb = Sandbox::new("spp-huge");
    let scene = sb.write("s.toml", BASE);
    let r = render(&scene, &sb.out(), &["--spp", "4294967295"]);
    expect_usage_error(&sb, &r, 2, &["--spp", "perfect square"]);
}

#[test]
fn malformed_pixel_bounds() {
    let sb = Sandbox::new("bounds-malformed");
    let scene = sb.write("s.toml", BASE);
    for bounds in ["1,2,3", "1,2,3,x", "-1,4,0,4", "4,2,0,4", "0,4,3,3"] {
        let r = render(&scene, &sb.out(), &["--pixelbounds", bounds]);
        expect_usage_error(&sb, &r, 2, &["--pixelbounds"]);
    }
}

#[test]
fn pixel_bounds_outside_the_film() {
    let sb = Sandbox::new("bounds-outside");
    let scene = sb.write("s.toml", BASE);
    for bounds in ["0,17,0,12", "0,16,0,13", "20,30,0,4"] {
        let r = render(&scene, &sb.out(), &["--pixelbounds", bounds]);
        expect_usage_error(&sb, &r, 2, &["--pixelbounds", "16x12"]);
    }
}

#[test]
fn unknown_output_extension() {
    let sb = Sandbox::new("out-extension");
    let scene = sb.write("s.toml", BASE);
    let out = sb.path("out.bmp");
    let r = render(&scene, &out, &[]);
    expect_usage_error(&sb, &r, 2, &["out.bmp", ".png"]);
    assert!(!out.exists());
}

#[test]
fn unknown_camera_name() {
    let sb = Sandbox::new("camera-name");
    let text = edit(BASE, "[camera]", "[cameras.front]");
    let scene = sb.write("s.toml", text);
    let r = render(&scene, &sb.out(), &["--camera", "nosuch"]);
    // The message lists the cameras there are.
    expect_usage_error(&sb, &r, 2, &["--camera", "nosuch", "front"]);
}

#[test]
fn output_folder_does_not_exist() {
    // Valid input, but the image cannot be written: a runtime failure, exit 1.
    let sb = Sandbox::new("out-folder");
    let scene = sb.write("s.toml", BASE);
    let out = sb.path("nosuch/out.png");
    let line = error_line(&render(&scene, &out, &[]), 1);
    assert!(line.contains(&out.display().to_string()), "{line}");
    assert!(!sb.path("nosuch").exists());
    sb.assert_no_output();
}

// ---------------------------------------------------------------------------------------------
// Rendering and checking (SPEC §9)
// ---------------------------------------------------------------------------------------------

#[test]
fn renders_a_png_of_the_film_size_with_a_summary() {
    let sb = Sandbox::new("render");
    let scene = sb.write("s.toml", BASE);
    let r = ok(render(&scene, &sb.out(), &[]));
    let img = decode(&sb.out());
    assert_eq!(img.dimensions(), (16, 12));
    // The red cube on the grey floor: not a blank image.
    assert!(distinct_pixels(&img) > 2);
    assert!(r.stdout.is_empty(), "stdout: {}", r.stdout);
    // stderr is not a terminal here: no progress bar, only the one-line summary.
    let lines: Vec<&str> = r.stderr.lines().collect();
    assert_eq!(lines.len(), 1, "stderr: {}", r.stderr);
    assert!(lines[0].contains("16x12"), "{}", lines[0]);
    assert!(lines[0].contains("Mrays/s"), "{}", lines[0]);
    assert!(
        lines[0].contains(&BASE_TRIANGLES.to_string()),
        "{}",
        lines[0]
    );
    let leftovers = std::fs::read_dir(&sb.dir).unwrap().count();
    assert_eq!(leftovers, 2, "only the scene and the image");
}

#[test]
fn json_summary_on_stdout() {
    let sb = Sandbox::new("json-summary");
    let scene = sb.write("s.toml", BASE);
    let r = ok(render(&scene, &sb.out(), &["--json", "--quiet"]));
    assert_eq!(r.stdout.lines().count(), 1, "one object: {}", r.stdout);
    let v: serde_json::Value = serde_json::from_str(&r.stdout).expect("stdout is JSON");
    assert_eq!(v["width"], 16);
    assert_eq!(v["height"], 12);
    assert_eq!(v["triangles"], BASE_TRIANGLES);
    assert!(v["rays_per_second"].as_f64().unwrap() > 0.0, "{v}");
    // Loading is parsing (scene file, meshes, textures) then the BVH build.
    let seconds = |key: &str| v[key].as_f64().unwrap_or_else(|| panic!("no {key}: {v}"));
    let (load, parse, bvh) = (
        seconds("load_seconds"),
        seconds("parse_seconds"),
        seconds("bvh_build_seconds"),
    );
    assert!(parse > 0.0 && bvh > 0.0 && parse + bvh <= load, "{v}");
    assert!(sb.out().exists());
}

#[test]
fn quiet_prints_nothing() {
    let sb = Sandbox::new("quiet");
    let scene = sb.write("s.toml", BASE);
    let r = ok(render(&scene, &sb.out(), &["--quiet"]));
    assert!(r.stderr.is_empty(), "stderr: {}", r.stderr);
    assert!(r.stdout.is_empty(), "stdout: {}", r.stdout);
    assert!(sb.out().exists());
}

#[test]
fn default_output_is_next_to_the_scene() {
    // Run from another folder: the image goes beside the scene, not into the working folder.
    let sb = Sandbox::new("default-output");
    let scene = sb.write("scenes/room.toml", BASE);
    ok(run_in(
        &sb.dir,
        ["render".as_ref(), scene.as_os_str(), "--quiet".as_ref()],
    ));
    assert_eq!(decode(&sb.path("scenes/room.png")).dimensions(), (16, 12));
    assert!(!sb.path("room.png").exists());

    // The same with a relative scene path.
    std::fs::remove_file(sb.path("scenes/room.png")).unwrap();
    ok(run_in(&sb.dir, ["render", "scenes/room.toml", "--quiet"]));
    assert!(sb.path("scenes/room.png").exists());
    assert!(!sb.path("room.png").exists());
}

#[test]
fn film_output_is_relative_to_the_scene_folder() {
    let sb = Sandbox::new("film-output");
    let text = edit(
        BASE,
        "height = 12\n",
        "height = 12\noutput = \"renders/img.png\"\n",
    );
    let scene = sb.write("scenes/room.toml", text);
    std::fs::create_dir_all(sb.path("scenes/renders")).unwrap();
    std::fs::create_dir_all(sb.path("renders")).unwrap();
    ok(run_in(&sb.dir, ["render", "scenes/room.toml", "--quiet"]));
    assert_eq!(
        decode(&sb.path("scenes/renders/img.png")).dimensions(),
        (16, 12)
    );
    assert!(!sb.path("renders/img.png").exists());
    assert!(!sb.path("scenes/room.png").exists());

    // -o wins over film.output.
    let out = sb.path("cli.png");
    std::fs::remove_file(sb.path("scenes/renders/img.png")).unwrap();
    ok(render(&scene, &out, &["--quiet"]));
    assert!(out.exists());
    assert!(!sb.path("scenes/renders/img.png").exists());
}

#[test]
fn width_and_height_flags_override_the_film() {
    let sb = Sandbox::new("override-size");
    let scene = sb.write("s.toml", BASE);
    let r = ok(render(
        &scene,
        &sb.out(),
        &["--width", "20", "--height", "10", "--json"],
    ));
    assert_eq!(decode(&sb.out()).dimensions(), (20, 10));
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(
        (v["width"].as_u64(), v["height"].as_u64()),
        (Some(20), Some(10))
    );
}

/// Two cameras in an order unlike their alphabetical one: `zeta` sees the cube, `alpha`
/// looks away into the (black) background.
const TWO_CAMERAS_TOML: &str = r#"[film]
width = 16
height = 12

[cameras.zeta]
position = [0, 1, 5]
look_at = [0, 0, 0]
fov = 45

[cameras.alpha]
position = [0, 1, 5]
look_at = [0, 1, 10]
fov = 45

[[lights]]
type = "point"
position = [0, 5, 5]

[[objects]]
type = "cube"
center = [0, 0, 0]
size = 1
"#;

const TWO_CAMERAS_JSON: &str = r#"{
  "film": {"width": 16, "height": 12},
  "cameras": {
    "zeta": {"position": [0, 1, 5], "look_at": [0, 0, 0], "fov": 45},
    "alpha": {"position": [0, 1, 5], "look_at": [0, 1, 10], "fov": 45}
  },
  "lights": [{"type": "point", "position": [0, 5, 5]}],
  "objects": [{"type": "cube", "center": [0, 0, 0], "size": 1}]
}
"#;

#[test]
fn named_cameras_default_to_the_first_in_file_order() {
    for (name, text) in [("s.toml", TWO_CAMERAS_TOML), ("s.json", TWO_CAMERAS_JSON)] {
        let sb = Sandbox::new("cameras");
        let scene = sb.write(name, text);
        let render_with = |extra: &[&str]| {
            let out = sb.path("img.png");
            let mut args = vec!["--quiet"];
            args.extend_from_slice(extra);
            ok(render(&scene, &out, &args));
            decode(&out)
        };
        let default = render_with(&[]);
        let zeta = render_with(&["--camera", "zeta"]);
        let alpha = render_with(&["--camera", "alpha"]);
        assert!(distinct_pixels(&zeta) > 1, "{name}: zeta sees the cube");
        assert_eq!(distinct_pixels(&alpha), 1, "{name}: alpha sees nothing");
        assert!(
            default == zeta,
            "{name}: the default camera is the first in the file"
        );

        let r = ok(run([
            "check".as_ref(),
            scene.as_os_str(),
            "--json".as_ref(),
        ]));
        let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
        assert_eq!(v["cameras"], serde_json::json!(["zeta", "alpha"]), "{name}");
    }
}

#[test]
fn check_prints_a_summary() {
    let sb = Sandbox::new("check");
    let text = edit(
        TWO_CAMERAS_TOML,
        "[cameras.alpha]",
        "[materials.red]\ndiffuse = 0.5\n\n[cameras.alpha]",
    );
    let scene = sb.write("s.toml", text);
    let r = ok(run(["check".as_ref(), scene.as_os_str()]));
    assert!(
        r.stdout.contains(&scene.display().to_string()),
        "{}",
        r.stdout
    );
    let field = |name: &str| -> String {
        let line = r.stdout.lines().find(|l| l.trim_start().starts_with(name));
        let line = line.unwrap_or_else(|| panic!("no {name} in: {}", r.stdout));
        line.trim_start()[name.len()..].trim().to_owned()
    };
    assert_eq!(field("triangles"), "12", "a cube is 12 triangles");
    assert!(field("lights").starts_with('1'), "{}", r.stdout);
    assert_eq!(field("materials"), "1");
    assert!(field("cameras").contains("zeta"));
    assert!(field("film").contains("16x12"));
    // The exact bounds of the unit cube, not the BVH's conservatively padded box.
    let json = ok(run([
        "check".as_ref(),
        scene.as_os_str(),
        "--json".as_ref(),
    ]));
    let summary: serde_json::Value = serde_json::from_str(&json.stdout).unwrap();
    assert_eq!(
        summary["bounds"]["min"],
        serde_json::json!([-0.5, -0.5, -0.5])
    );
    assert_eq!(summary["bounds"]["max"], serde_json::json!([0.5, 0.5, 0.5]));
    // Checking renders nothing.
    assert_eq!(std::fs::read_dir(&sb.dir).unwrap().count(), 1);
}

#[test]
fn check_reports_a_bad_scene() {
    let sb = Sandbox::new("check-bad");
    let text = edit(BASE, "material = \"red\"", "material = \"rde\"");
    let scene = sb.write("s.toml", &text);
    for json in [false, true] {
        let mut args = vec!["check".as_ref(), scene.as_os_str()];
        if json {
            args.push("--json".as_ref());
        }
        let r = run(args);
        let line = error_line(&r, 2);
        let want = Expect {
            line: line_of(&text, "material = "),
            key: Some("objects[1].material"),
            words: &["rde"],
        };
        assert_located(&line, &scene, &want);
        assert!(r.stdout.is_empty(), "stdout: {}", r.stdout);
    }
}

// ---------------------------------------------------------------------------------------------
// Determinism (SPEC §7, §9)
// ---------------------------------------------------------------------------------------------

#[test]
fn images_do_not_depend_on_the_thread_count() {
    let sb = Sandbox::new("threads");
    let scene = sb.write("s.toml", noisy_scene(40, 30));
    let one = sb.path("t1.png");
    let two = sb.path("t2.png");
    let again = sb.path("t2-again.png");
    ok(render(&scene, &one, &["-t", "1", "--quiet"]));
    ok(render(&scene, &two, &["-t", "2", "--quiet"]));
    ok(render(&scene, &again, &["--threads", "2", "--quiet"]));
    let bytes = std::fs::read(&one).unwrap();
    assert!(
        bytes == std::fs::read(&two).unwrap(),
        "1 vs 2 threads differ"
    );
    assert!(bytes == std::fs::read(&again).unwrap(), "two runs differ");
    // Meaningful only if the random choices show: a varied image.
    assert!(distinct_pixels(&decode(&one)) > 20);

    // The seed does change the noise, so the comparison above is not vacuous.
    let seeded = sb.path("seeded.png");
    ok(render(
        &scene,
        &seeded,
        &["-t", "2", "--seed", "8", "--quiet"],
    ));
    assert!(
        bytes != std::fs::read(&seeded).unwrap(),
        "--seed changed nothing"
    );
}

#[test]
fn pixel_bounds_render_the_same_pixels_as_the_full_film() {
    // A region not aligned to the renderer's 16-pixel tiles, in float EXR so that equality is
    // bit-exact, and in PNG as users would stitch it.
    let sb = Sandbox::new("pixelbounds");
    let scene = sb.write("s.toml", noisy_scene(32, 24));
    let (x0, x1, y0, y1) = (5u32, 23u32, 3u32, 17u32);
    let bounds = format!("{x0},{x1},{y0},{y1}");
    for ext in ["exr", "png"] {
        let full = sb.path(&format!("full.{ext}"));
        let part = sb.path(&format!("part.{ext}"));
        ok(render(&scene, &full, &["-t", "2", "--quiet"]));
        let r = ok(render(
            &scene,
            &part,
            &["-t", "2", "--pixelbounds", &bounds, "--json"],
        ));
        let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
        assert_eq!(
            (v["width"].as_u64(), v["height"].as_u64()),
            (Some(18), Some(14))
        );
        assert_eq!(
            (v["film_width"].as_u64(), v["film_height"].as_u64()),
            (Some(32), Some(24))
        );

        let full = image::open(&full).unwrap().to_rgb32f();
        let part = image::open(&part).unwrap().to_rgb32f();
        assert_eq!(full.dimensions(), (32, 24));
        assert_eq!(part.dimensions(), (x1 - x0, y1 - y0));
        for (x, y, p) in part.enumerate_pixels() {
            let f = full.get_pixel(x0 + x, y0 + y);
            let bits = |c: &image::Rgb<f32>| c.0.map(f32::to_bits);
            assert_eq!(bits(p), bits(f), "{ext}: pixel ({}, {})", x0 + x, y0 + y);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Interrupt (SPEC §9: exit 130, no output file)
// ---------------------------------------------------------------------------------------------

#[test]
#[cfg(unix)]
fn interrupt_exits_130_without_an_image() {
    let sb = Sandbox::new("interrupt");
    // Far too much work to finish in the test (minutes): 16 spp and 32x32 shadow rays per
    // sample on every pixel of a floor that fills the view.
    let text = r#"[film]
width = 512
height = 512

[camera]
position = [0, 2, 1]
look_at = [0, 0, 0]
fov = 60

[render]
samples = 16

[[lights]]
type = "area"
center = [0, 3, 0]
u = [1, 0, 0]
v = [0, 0, 1]
samples = 32

[[objects]]
type = "quad"
corner = [-50, 0, 50]
u = [100, 0, 0]
v = [0, 0, -100]
"#;
    let scene = sb.write("s.toml", text);
    let mut child = command()
        .args([
            "render".as_ref(),
            scene.as_os_str(),
            "-o".as_ref(),
            sb.out().as_os_str(),
        ])
        .arg("--quiet")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Give it time to load the scene and install its Ctrl-C handler (a tiny scene: a few
    // milliseconds), then interrupt it mid-render.
    std::thread::sleep(Duration::from_secs(2));
    assert!(
        child.try_wait().unwrap().is_none(),
        "the render finished too soon"
    );
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            panic!("no exit within 60 s of SIGINT");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    let r = Run {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    };
    let line = error_line(&r, 130);
    assert!(line.contains("interrupted"), "{line}");
    sb.assert_no_output();
}
