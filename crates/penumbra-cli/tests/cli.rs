//! End-to-end tests of the `penumbra` binary: what a user sees when they run it. Exit codes,
//! the one-line `error:` messages of SPEC §8 (docs/spec.md), that a failed run leaves no image
//! (and no temporary file) behind, usage errors naming their flags, the success paths of SPEC
//! §9, and that images do not depend on the thread count or on rendering a sub-region.
//!
//! Which error each mistake in a scene file gives, and the line, column and key path it names,
//! is tested on the library, row by row, in `crates/penumbra/tests/errors.rs`; here a few scene
//! errors check that the binary prints them as its contract says.
//!
//! Every test works in its own fresh folder, removed when it ends (see `support::TempDir`).

#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use penumbra::SceneFile;
use support::{
    edit, line_of, position_of, with_mesh, with_texture, TempDir, BASE_JSON, BASE_TOML as BASE,
    BASE_TRIANGLES,
};

// ---------------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------------

/// What a test folder holds after a run of the binary.
trait Outputs {
    /// The conventional output of failing runs: `-o` points here.
    fn out(&self) -> PathBuf;
    /// Asserts that no image and no half-written temporary file (`.out.png.tmp-PID`) exists.
    fn assert_no_output(&self);
}

impl Outputs for TempDir {
    fn out(&self) -> PathBuf {
        self.join("out.png")
    }

    fn assert_no_output(&self) {
        assert!(!self.out().exists(), "an output image was written");
        let leftovers: Vec<String> = std::fs::read_dir(self.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains("out.") || n.contains(".tmp"))
            .collect();
        assert!(leftovers.is_empty(), "files left behind: {leftovers:?}");
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
    /// The 1-based column, in characters.
    column: usize,
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
    assert_eq!(
        c.parse::<usize>().ok(),
        Some(want.column),
        "column in: {line}"
    );
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

/// The error the library gives for a scene file, as the binary must print it.
fn library_error(scene: &Path) -> String {
    let e = SceneFile::load(scene)
        .and_then(|f| f.build(1))
        .expect_err("the scene is bad");
    format!("error: {e}")
}

/// Renders a bad scene file: exit 2, one located message (the library's error as it is), no
/// output on stdout, no image. Returns the message.
fn expect_scene_error(sb: &TempDir, name: &str, text: &str, want: Expect) -> String {
    let scene = sb.write(name, text);
    let r = render(&scene, &sb.out(), &[]);
    let line = error_line(&r, 2);
    assert_eq!(r.stderr.lines().count(), 1, "one line: {}", r.stderr);
    assert_located(&line, &scene, &want);
    assert_eq!(line, library_error(&scene));
    assert!(r.stdout.is_empty(), "stdout: {}", r.stdout);
    sb.assert_no_output();
    line
}

/// A usage error: exit 2 (or `code`), one message containing `words`, no image.
fn expect_usage_error(sb: &TempDir, r: &Run, code: i32, words: &[&str]) -> String {
    let line = error_line(r, code);
    for w in words {
        assert!(r.stderr.contains(w), "{w:?} missing in: {}", r.stderr);
    }
    sb.assert_no_output();
    line
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
// Scene-file errors (SPEC §8)
// ---------------------------------------------------------------------------------------------

#[test]
fn the_base_scenes_are_valid() {
    // The tests below break one thing in these; they must render as they are.
    let sb = TempDir::new("base");
    for (name, text) in [("scene.toml", BASE), ("scene.json", BASE_JSON)] {
        let scene = sb.write(name, text);
        ok(render(&scene, &sb.out(), &["--quiet"]));
        assert_eq!(decode(&sb.out()).dimensions(), (16, 12));
        std::fs::remove_file(sb.out()).unwrap();
    }
}

#[test]
fn a_toml_scene_error_is_one_located_line() {
    // An error found while building the scene (a name that refers to nothing).
    let sb = TempDir::new("toml-error");
    let text = edit(BASE, "material = \"red\"", "material = \"rde\"");
    let (line, column) = position_of(&text, "material = ");
    let want = Expect {
        line,
        column,
        key: Some("objects[1].material"),
        words: &["unknown material", "\"rde\"", "known: red"],
    };
    expect_scene_error(&sb, "s.toml", &text, want);
}

#[test]
fn a_json_scene_error_is_one_located_line() {
    // An error found while parsing, at serde_json's position: the end of the bad value.
    let sb = TempDir::new("json-error");
    let text = edit(BASE_JSON, "\"width\": 16", "\"width\": \"16\"");
    let (line, quote) = position_of(&text, "\"16\"");
    let want = Expect {
        line,
        // The closing quote.
        column: quote + 3,
        key: Some("film.width"),
        words: &["string", "expected an integer"],
    };
    expect_scene_error(&sb, "s.json", &text, want);
}

#[test]
fn resolution_too_large_from_the_flags() {
    // Through the command line, a bad resolution is named by its flags instead of a line.
    let sb = TempDir::new("too-large");
    let scene = sb.write("ok.toml", BASE);
    let r = render(
        &scene,
        &sb.out(),
        &["--width", "100000", "--height", "100000"],
    );
    expect_usage_error(&sb, &r, 2, &["--width/--height", "too large"]);
    let r = render(&scene, &sb.out(), &["--width", "0"]);
    expect_usage_error(&sb, &r, 2, &["--width/--height", "0x12"]);
}

#[test]
fn unknown_output_format_in_the_scene() {
    // film.output is part of the scene file, so a bad one is located like any other value,
    // whether or not the image would go there.
    let sb = TempDir::new("film-output-format");
    let text = edit(BASE, "height = 12\n", "height = 12\noutput = \"out.bmp\"\n");
    let want = Expect {
        line: line_of(&text, "output"),
        column: 1,
        key: Some("film.output"),
        words: &["out.bmp", ".png"],
    };
    let scene = sb.write("s.toml", &text);
    // Without -o (the image would go to film.output) ...
    let line = error_line(&run(["render".as_ref(), scene.as_os_str()]), 2);
    assert_located(&line, &scene, &want);
    assert!(!sb.join("out.bmp").exists());
    // ... with `check` ...
    let line = error_line(&run(["check".as_ref(), scene.as_os_str()]), 2);
    assert_located(&line, &scene, &want);
    // ... and even when -o names a good file: the scene file is wrong either way.
    expect_scene_error(&sb, "s.toml", &text, want);
}

// ---------------------------------------------------------------------------------------------
// Files the scene refers to, and the scene file itself
// ---------------------------------------------------------------------------------------------

#[test]
fn missing_scene_file() {
    let sb = TempDir::new("missing-scene");
    let scene = sb.join("nosuch.toml");
    let line = error_line(&render(&scene, &sb.out(), &[]), 2);
    assert!(line.contains(&scene.display().to_string()), "{line}");
    sb.assert_no_output();
}

#[test]
fn unknown_scene_extension() {
    let sb = TempDir::new("scene-extension");
    let scene = sb.write("scene.yaml", BASE);
    let line = error_line(&render(&scene, &sb.out(), &[]), 2);
    assert!(line.contains(&scene.display().to_string()), "{line}");
    assert!(line.contains(".toml") && line.contains(".json"), "{line}");
    sb.assert_no_output();
}

#[test]
fn textures_are_relative_to_the_scene_folder() {
    let sb = TempDir::new("texture-relative");
    sb.png("scenes/textures/wood.png", 4, 4, |x, y| {
        [(x * 60) as u8, (y * 60) as u8, 0]
    });
    let scene = sb.write("scenes/s.toml", with_texture("textures/wood.png"));
    ok(render(&scene, &sb.out(), &["--quiet"]));
    assert_eq!(decode(&sb.out()).dimensions(), (16, 12));
}

#[test]
fn meshes_are_relative_to_the_scene_folder() {
    let sb = TempDir::new("mesh-relative");
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
    let sb = TempDir::new("unknown-flag");
    let scene = sb.write("s.toml", BASE);
    let r = render(&scene, &sb.out(), &["--sppp", "4"]);
    expect_usage_error(&sb, &r, 2, &["--sppp"]);
}

#[test]
fn spp_not_a_perfect_square() {
    let sb = TempDir::new("spp");
    let scene = sb.write("s.toml", BASE);
    let r = render(&scene, &sb.out(), &["--spp", "3"]);
    expect_usage_error(&sb, &r, 2, &["--spp", "perfect square"]);
}

#[test]
fn huge_spp_is_an_error_not_a_panic() {
    // 4294967295 rounds to a square root of 65536, whose square overflows 32 bits.
    let sb = TempDir::new("spp-huge");
    let scene = sb.write("s.toml", BASE);
    let r = render(&scene, &sb.out(), &["--spp", "4294967295"]);
    expect_usage_error(&sb, &r, 2, &["--spp", "perfect square"]);
}

#[test]
fn malformed_pixel_bounds() {
    let sb = TempDir::new("bounds-malformed");
    let scene = sb.write("s.toml", BASE);
    for bounds in ["1,2,3", "1,2,3,x", "-1,4,0,4", "4,2,0,4", "0,4,3,3"] {
        let r = render(&scene, &sb.out(), &["--pixelbounds", bounds]);
        expect_usage_error(&sb, &r, 2, &["--pixelbounds"]);
    }
}

#[test]
fn pixel_bounds_outside_the_film() {
    let sb = TempDir::new("bounds-outside");
    let scene = sb.write("s.toml", BASE);
    for bounds in ["0,17,0,12", "0,16,0,13", "20,30,0,4"] {
        let r = render(&scene, &sb.out(), &["--pixelbounds", bounds]);
        expect_usage_error(&sb, &r, 2, &["--pixelbounds", "16x12"]);
    }
}

#[test]
fn unknown_output_extension() {
    let sb = TempDir::new("out-extension");
    let scene = sb.write("s.toml", BASE);
    let out = sb.join("out.bmp");
    let r = render(&scene, &out, &[]);
    expect_usage_error(&sb, &r, 2, &["out.bmp", ".png"]);
    assert!(!out.exists());
}

#[test]
fn names_from_the_file_cannot_drive_the_terminal() {
    // A material name with ESC, BEL and a newline (TOML escapes), and a mesh path with them.
    let sb = TempDir::new("escapes");
    let text = edit(
        BASE,
        "material = \"red\"",
        "material = \"r\\u001b[31m\\u0007\\nX\"",
    );
    let scene = sb.write("s.toml", &text);
    let r = render(&scene, &sb.out(), &[]);
    let line = error_line(&r, 2);
    assert_eq!(r.stderr.lines().count(), 1, "one line: {:?}", r.stderr);
    assert!(
        !r.stderr.contains('\u{1b}') && !r.stderr.contains('\u{7}'),
        "{:?}",
        r.stderr
    );
    assert!(line.contains("\\u{1b}[31m\\u{7}\\nX"), "{line}");
}

/// Runs `penumbra ARGS` for at most 10 s (killing it then), and returns its exit code and
/// stderr; `None` as the code when it had to be killed.
fn run_bounded(args: &[&OsStr]) -> (Option<i32>, String) {
    let mut child = command()
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(10);
    while Instant::now() < deadline {
        if child.try_wait().unwrap().is_some() {
            let out = child.wait_with_output().unwrap();
            return (
                out.status.code(),
                String::from_utf8_lossy(&out.stderr).into_owned(),
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    (None, String::new())
}

#[test]
fn files_that_are_not_files_are_refused_at_once() {
    let sb = TempDir::new("not-files");
    let out = sb.join("out.png");
    let render_args = |scene: &Path| -> (Option<i32>, String) {
        run_bounded(&[
            "render".as_ref(),
            scene.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
        ])
    };
    // A folder and a named pipe as the scene file.
    let folder = sb.join("folder.toml");
    std::fs::create_dir_all(&folder).unwrap();
    let fifo = sb.join("pipe.toml");
    let made = Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success());
    let mut scenes = vec![(folder, "folder")];
    if made {
        scenes.push((fifo, "not a regular file"));
    }
    // /dev/zero as a mesh (outside the scene's folder: refused before anything opens it; a
    // device allowed is refused by `files::read_bounded`) and a folder as a texture.
    let mesh = sb.write("mesh.toml", with_mesh("/dev/zero"));
    std::fs::create_dir_all(sb.join("tex.png")).unwrap();
    let texture = sb.write("texture.toml", with_texture("tex.png"));
    scenes.push((mesh, "is outside the scene's folder"));
    scenes.push((texture, "folder"));
    for (scene, words) in &scenes {
        let (code, stderr) = render_args(scene);
        assert_eq!(code, Some(2), "{}: {stderr}", scene.display());
        assert!(stderr.contains(words), "{}: {stderr}", scene.display());
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
    }
    assert!(!out.exists());
}

#[test]
fn absurd_thread_counts_are_refused_at_once() {
    let sb = TempDir::new("threads-bound");
    let scene = sb.write("s.toml", BASE);
    let out = sb.join("out.png");
    let start = std::time::Instant::now();
    let r = render(&scene, &out, &["-t", "100000"]);
    expect_usage_error(&sb, &r, 2, &["--threads", "1024", "100000"]);
    assert!(
        start.elapsed().as_secs() < 5,
        "refused before starting threads"
    );
    assert!(!out.exists());
    ok(render(&scene, &out, &["-t", "1024", "--quiet"]));
}

#[test]
fn a_jpeg_wider_than_the_format_allows_is_refused_before_rendering() {
    let sb = TempDir::new("jpeg-limit");
    let scene = sb.write("s.toml", BASE);
    let out = sb.join("wide.jpg");
    let r = render(&scene, &out, &["--width", "70000", "--height", "1"]);
    expect_usage_error(&sb, &r, 2, &["wide.jpg", "70000x1", "65535"]);
    assert!(!out.exists());
    // A region of such a film fits, and PNG has no such limit.
    let region = sb.join("region.jpg");
    let bounds = [
        "--width",
        "70000",
        "--height",
        "1",
        "--pixelbounds",
        "0,16,0,1",
        "--quiet",
    ];
    ok(render(&scene, &region, &bounds));
}

#[test]
fn unknown_camera_name() {
    let sb = TempDir::new("camera-name");
    let text = edit(BASE, "[camera]", "[cameras.front]");
    let scene = sb.write("s.toml", text);
    let r = render(&scene, &sb.out(), &["--camera", "nosuch"]);
    // The message lists the cameras there are.
    expect_usage_error(&sb, &r, 2, &["--camera", "nosuch", "front"]);
}

#[test]
fn light_samples_out_of_range() {
    let sb = TempDir::new("light-samples");
    let scene = sb.write("s.toml", BASE);
    for n in ["0", "1025"] {
        let r = render(&scene, &sb.out(), &["--light-samples", n]);
        expect_usage_error(&sb, &r, 2, &["--light-samples", "between 1 and 1024"]);
    }
}

#[test]
fn missing_output_folders_are_made() {
    let sb = TempDir::new("out-folder");
    let scene = sb.write("s.toml", BASE);
    let out = sb.join("new/deeper/out.png");
    ok(render(&scene, &out, &["-q"]));
    assert_eq!(decode(&out).dimensions(), (16, 12));
}

#[test]
fn an_output_folder_that_cannot_be_made_is_a_runtime_failure() {
    // Valid input, but the image cannot be written (a file stands where the folder would
    // go): a runtime failure, exit 1, before rendering.
    let sb = TempDir::new("out-folder-blocked");
    let scene = sb.write("s.toml", BASE);
    sb.write("blocked", "a file");
    let out = sb.join("blocked/out.png");
    let line = error_line(&render(&scene, &out, &[]), 1);
    assert!(line.contains(&out.display().to_string()), "{line}");
    assert!(line.contains("cannot make folder"), "{line}");
    sb.assert_no_output();
}

// ---------------------------------------------------------------------------------------------
// Rendering and checking (SPEC §9)
// ---------------------------------------------------------------------------------------------

#[test]
fn renders_a_png_of_the_film_size_with_a_summary() {
    let sb = TempDir::new("render");
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
    let leftovers = std::fs::read_dir(sb.path()).unwrap().count();
    assert_eq!(leftovers, 2, "only the scene and the image");
}

#[test]
fn json_summary_on_stdout() {
    let sb = TempDir::new("json-summary");
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
    let sb = TempDir::new("quiet");
    let scene = sb.write("s.toml", BASE);
    let r = ok(render(&scene, &sb.out(), &["--quiet"]));
    assert!(r.stderr.is_empty(), "stderr: {}", r.stderr);
    assert!(r.stdout.is_empty(), "stdout: {}", r.stdout);
    assert!(sb.out().exists());
}

#[test]
fn default_output_is_next_to_the_scene() {
    // Run from another folder: the image goes beside the scene, not into the working folder.
    let sb = TempDir::new("default-output");
    let scene = sb.write("scenes/room.toml", BASE);
    ok(run_in(
        sb.path(),
        ["render".as_ref(), scene.as_os_str(), "--quiet".as_ref()],
    ));
    assert_eq!(decode(&sb.join("scenes/room.png")).dimensions(), (16, 12));
    assert!(!sb.join("room.png").exists());

    // The same with a relative scene path.
    std::fs::remove_file(sb.join("scenes/room.png")).unwrap();
    ok(run_in(sb.path(), ["render", "scenes/room.toml", "--quiet"]));
    assert!(sb.join("scenes/room.png").exists());
    assert!(!sb.join("room.png").exists());
}

#[test]
fn film_output_is_relative_to_the_scene_folder() {
    let sb = TempDir::new("film-output");
    let text = edit(
        BASE,
        "height = 12\n",
        "height = 12\noutput = \"renders/img.png\"\n",
    );
    let scene = sb.write("scenes/room.toml", text);
    std::fs::create_dir_all(sb.join("scenes/renders")).unwrap();
    std::fs::create_dir_all(sb.join("renders")).unwrap();
    ok(run_in(sb.path(), ["render", "scenes/room.toml", "--quiet"]));
    assert_eq!(
        decode(&sb.join("scenes/renders/img.png")).dimensions(),
        (16, 12)
    );
    assert!(!sb.join("renders/img.png").exists());
    assert!(!sb.join("scenes/room.png").exists());

    // -o wins over film.output.
    let out = sb.join("cli.png");
    std::fs::remove_file(sb.join("scenes/renders/img.png")).unwrap();
    ok(render(&scene, &out, &["--quiet"]));
    assert!(out.exists());
    assert!(!sb.join("scenes/renders/img.png").exists());
}

#[test]
fn width_and_height_flags_override_the_film() {
    let sb = TempDir::new("override-size");
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
        let sb = TempDir::new("cameras");
        let scene = sb.write(name, text);
        let render_with = |extra: &[&str]| {
            let out = sb.join("img.png");
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
    let sb = TempDir::new("check");
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
    assert_eq!(std::fs::read_dir(sb.path()).unwrap().count(), 1);
}

#[test]
fn check_reports_a_bad_scene() {
    let sb = TempDir::new("check-bad");
    let text = edit(BASE, "material = \"red\"", "material = \"rde\"");
    let scene = sb.write("s.toml", &text);
    for json in [false, true] {
        let mut args = vec!["check".as_ref(), scene.as_os_str()];
        if json {
            args.push("--json".as_ref());
        }
        let r = run(args);
        let line = error_line(&r, 2);
        let (line_no, column) = position_of(&text, "material = ");
        let want = Expect {
            line: line_no,
            column,
            key: Some("objects[1].material"),
            words: &["rde"],
        };
        assert_located(&line, &scene, &want);
        assert_eq!(line, library_error(&scene));
        assert!(r.stdout.is_empty(), "stdout: {}", r.stdout);
    }
}

// ---------------------------------------------------------------------------------------------
// Determinism (SPEC §7, §9)
// ---------------------------------------------------------------------------------------------

/// Runs `penumbra ARGS` with stdout and stderr sent where `stdout` and `stderr` say.
fn run_with_streams(args: &[&OsStr], stdout: Stdio, stderr: Stdio) -> std::process::Output {
    command()
        .args(args)
        .stdin(Stdio::null())
        .stdout(stdout)
        .stderr(stderr)
        .output()
        .expect("run the penumbra binary")
}

fn dev_full() -> Stdio {
    Stdio::from(
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap(),
    )
}

#[test]
fn a_full_stdout_is_an_error_and_a_closed_one_a_quiet_end_never_a_panic() {
    let sb = TempDir::new("streams");
    let scene = sb.write("s.toml", noisy_scene(8, 6));
    let image = sb.join("out.png");
    let check_json: Vec<&OsStr> = vec!["check".as_ref(), scene.as_os_str(), "--json".as_ref()];
    let check_text: Vec<&OsStr> = vec!["check".as_ref(), scene.as_os_str()];
    let render_json: Vec<&OsStr> = vec![
        "render".as_ref(),
        scene.as_os_str(),
        "-o".as_ref(),
        image.as_os_str(),
        "--json".as_ref(),
        "--quiet".as_ref(),
    ];
    for args in [&check_json, &check_text, &render_json] {
        let out = run_with_streams(args, dev_full(), Stdio::piped());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(
            stderr.contains("cannot write to standard output"),
            "{stderr}"
        );
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
    // A pipe whose reader has gone, like `| head -c0`: the listing ends quietly, as a
    // listing piped into `head` does.
    let mut child = command()
        .args(&check_json)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(stderr.is_empty(), "{stderr}");
}

#[test]
fn a_full_stderr_keeps_the_exit_code() {
    let sb = TempDir::new("stderr-full");
    let good = sb.write("good.toml", noisy_scene(8, 6));
    let bad = sb.write("bad.toml", "[film]\nwidth = 0\n");
    let image = sb.join("out.png");
    let render: Vec<&OsStr> = vec![
        "render".as_ref(),
        good.as_os_str(),
        "-o".as_ref(),
        image.as_os_str(),
    ];
    let out = run_with_streams(&render, Stdio::null(), dev_full());
    assert_eq!(
        out.status.code(),
        Some(0),
        "the summary cannot be written, the image was"
    );
    assert!(image.exists());
    let failing: Vec<&OsStr> = vec![
        "render".as_ref(),
        bad.as_os_str(),
        "-o".as_ref(),
        image.as_os_str(),
    ];
    let out = run_with_streams(&failing, Stdio::null(), dev_full());
    assert_eq!(
        out.status.code(),
        Some(2),
        "the error cannot be written, the code says it"
    );
}

#[test]
fn the_summary_says_thread_or_threads() {
    let sb = TempDir::new("summary-threads");
    let scene = sb.write("s.toml", noisy_scene(8, 6));
    let one = ok(render(&scene, &sb.join("one.png"), &["-t", "1"]));
    assert!(one.stderr.contains(", 1 thread -> "), "{}", one.stderr);
    let two = ok(render(&scene, &sb.join("two.png"), &["-t", "2"]));
    assert!(two.stderr.contains(", 2 threads -> "), "{}", two.stderr);
}

#[test]
fn images_do_not_depend_on_the_simd_path() {
    // PENUMBRA_SIMD picks the kernels' instruction set; every path must give the same bits.
    let sb = TempDir::new("simd");
    let noisy = sb.write("noisy.toml", noisy_scene(48, 36));
    let room = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell.toml");
    for (name, scene) in [("noisy", noisy.as_path()), ("room", room.as_path())] {
        let mut images = Vec::new();
        for path in penumbra::supported_paths().iter().map(|p| p.name()) {
            let out = sb.join(format!("{name}-{path}.pfm"));
            let status = command()
                .args([
                    "render".as_ref(),
                    scene.as_os_str(),
                    "-o".as_ref(),
                    out.as_os_str(),
                ])
                .args(["--width", "64", "--height", "48", "--quiet"])
                .env("PENUMBRA_SIMD", path)
                .stdin(Stdio::null())
                .status()
                .expect("run the penumbra binary");
            assert!(status.success(), "{name} on {path}");
            images.push((path, std::fs::read(&out).unwrap()));
        }
        for (path, bytes) in &images[1..] {
            assert!(
                *bytes == images[0].1,
                "{name}: {path} differs from {}",
                images[0].0
            );
        }
    }
}

#[test]
fn a_simd_path_that_cannot_be_honoured_is_refused() {
    let sb = TempDir::new("simd-typo");
    let scene = sb.write("s.toml", noisy_scene(8, 6));
    let lacking = ["avx512", "avx2"].into_iter().find(|name| {
        !penumbra::supported_paths()
            .iter()
            .any(|p| p.name() == *name)
    });
    for (value, says) in [
        ("avx-2", "not one of avx512, avx2, portable"),
        ("AVX2", "not one of avx512, avx2, portable"),
    ]
    .into_iter()
    .chain(lacking.map(|name| (name, "this CPU does not support")))
    {
        let out = sb.join("x.png");
        for sub in ["render", "check"] {
            let mut args = vec![sub.as_ref(), scene.as_os_str()];
            if sub == "render" {
                args.extend(["-o".as_ref(), out.as_os_str()]);
            }
            let r = command()
                .args(args)
                .env("PENUMBRA_SIMD", value)
                .stdin(Stdio::null())
                .output()
                .expect("run the penumbra binary");
            let stderr = String::from_utf8_lossy(&r.stderr);
            assert_eq!(r.status.code(), Some(2), "{sub} with {value}: {stderr}");
            assert!(
                stderr.contains("PENUMBRA_SIMD") && stderr.contains(says),
                "{stderr}"
            );
            assert!(!out.exists());
        }
    }
}

#[test]
fn images_do_not_depend_on_the_thread_count() {
    let sb = TempDir::new("threads");
    let scene = sb.write("s.toml", noisy_scene(40, 30));
    let one = sb.join("t1.png");
    let two = sb.join("t2.png");
    let again = sb.join("t2-again.png");
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
    let seeded = sb.join("seeded.png");
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
    let sb = TempDir::new("pixelbounds");
    let scene = sb.write("s.toml", noisy_scene(32, 24));
    let (x0, x1, y0, y1) = (5u32, 23u32, 3u32, 17u32);
    let bounds = format!("{x0},{x1},{y0},{y1}");
    for ext in ["exr", "png"] {
        let full = sb.join(format!("full.{ext}"));
        let part = sb.join(format!("part.{ext}"));
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
    let sb = TempDir::new("interrupt");
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
