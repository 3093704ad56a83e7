//! What pbrt, Mitsuba and Blender users reach for: `--quick`, `--cropwindow`, the `--outfile`
//! and `--nthreads` aliases, a scene on stdin (`-`), the image on stdout (`-o -` with
//! `--format`), and `--version` on every subcommand.

mod harness;
#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use harness::{error_line, image, ok, run_in, run_with};
use support::{TempDir, BASE_JSON, BASE_TOML};

fn scene_dir(name: &str) -> TempDir {
    let dir = TempDir::new(name);
    // 64x48 so that a quarter is still an image worth comparing.
    let text = BASE_TOML
        .replace("width = 16", "width = 64")
        .replace("height = 12", "height = 48");
    dir.write("s.toml", text);
    dir
}

fn render(dir: &TempDir, args: &[&str]) -> harness::Run {
    let mut all = vec!["render", "s.toml"];
    all.extend(args);
    run_in(dir.path(), all)
}

#[test]
fn quick_is_a_quarter_size_one_sample_preview() {
    let dir = scene_dir("quick");
    let r = ok(render(&dir, &["--quick", "-o", "quick.png"]));
    assert!(
        r.stderr.contains("16x12, 1 spp center, 1 light sample, "),
        "{}",
        r.stderr
    );
    ok(render(
        &dir,
        &[
            "-o",
            "explicit.png",
            "--width",
            "16",
            "--height",
            "12",
            "--sampler",
            "center",
            "--light-samples",
            "1",
            "-q",
        ],
    ));
    assert_eq!(
        image(&dir.join("quick.png")),
        image(&dir.join("explicit.png"))
    );
    // Explicit quality flags still win over --quick.
    let r = ok(render(
        &dir,
        &["--quick", "--sampler", "grid", "--spp", "4", "-o", "g.png"],
    ));
    assert!(r.stderr.contains("16x12, 4 spp grid"), "{}", r.stderr);
}

#[test]
fn cropwindow_is_pbrts_fractions_of_the_film() {
    let dir = scene_dir("crop");
    // x: ceil(64·0.3) = 20 to ceil(64·0.7) = 45; y: ceil(48·0.1) = 5 to 48.
    ok(render(
        &dir,
        &["--cropwindow", "0.3,0.7,0.1,1", "-o", "crop.png", "-q"],
    ));
    ok(render(
        &dir,
        &["--pixelbounds", "20,45,5,48", "-o", "bounds.png", "-q"],
    ));
    let crop = image(&dir.join("crop.png"));
    assert_eq!(crop.dimensions(), (25, 43));
    assert_eq!(crop, image(&dir.join("bounds.png")));
}

#[test]
fn bad_crop_windows_are_usage_errors() {
    let dir = scene_dir("crop-bad");
    for (window, words) in [
        ("0,1.5,0,1", "in [0, 1]"),
        ("0.5,0.5,0,1", "empty"),
        ("0,1,0", "four numbers"),
        ("0.001,0.002,0,1", "--cropwindow"),
    ] {
        let r = render(&dir, &["--cropwindow", window, "-o", "c.png"]);
        let line = error_line(&r, 2);
        assert!(
            line.contains("--cropwindow") && line.contains(words),
            "{window}: {line}"
        );
        assert!(!dir.join("c.png").exists());
    }
    let r = render(
        &dir,
        &["--cropwindow", "0,1,0,1", "--pixelbounds", "0,1,0,1"],
    );
    assert!(error_line(&r, 2).contains("cannot be used with"));
}

#[test]
fn pbrt_aliases_work() {
    let dir = scene_dir("aliases");
    ok(render(
        &dir,
        &["--outfile", "a.png", "--nthreads", "1", "--spp", "1", "-q"],
    ));
    ok(render(
        &dir,
        &["-o", "b.png", "--threads", "1", "--spp", "1", "-q"],
    ));
    assert_eq!(image(&dir.join("a.png")), image(&dir.join("b.png")));
}

#[test]
fn a_scene_on_stdin_renders_like_the_file() {
    let dir = scene_dir("stdin");
    ok(render(&dir, &["-o", "file.png", "-q"]));
    let text = std::fs::read(dir.join("s.toml")).unwrap();
    let r = ok(run_with(
        dir.path(),
        ["render", "-", "-o", "stdin.png"],
        Some(&text),
    ));
    assert!(r.stderr.contains("-> stdin.png"), "{}", r.stderr);
    assert_eq!(image(&dir.join("stdin.png")), image(&dir.join("file.png")));
    // JSON is recognized by its opening brace.
    let json = BASE_JSON.replace(
        "\"width\": 16, \"height\": 12",
        "\"width\": 64, \"height\": 48",
    );
    ok(run_with(
        dir.path(),
        ["render", "-", "-o", "json.png", "-q"],
        Some(json.as_bytes()),
    ));
    assert_eq!(image(&dir.join("json.png")), image(&dir.join("file.png")));
}

#[test]
fn stdin_scene_errors_name_stdin_and_assets_are_relative_to_the_cwd() {
    let dir = scene_dir("stdin-errors");
    let bad = BASE_TOML.replace("fov = 45", "fov = 45\nzoom = 2");
    let r = run_with(
        dir.path(),
        ["render", "-", "-o", "x.png"],
        Some(bad.as_bytes()),
    );
    assert!(
        error_line(&r, 2).starts_with("error: <stdin>:10:1: camera.zoom"),
        "{r:?}"
    );
    // A mesh named relative to the current folder.
    dir.write("m/tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let text = format!("{BASE_TOML}\n[[objects]]\ntype = \"mesh\"\nfile = \"m/tri.obj\"\n");
    ok(run_with(
        dir.path(),
        ["render", "-", "-o", "mesh.png", "-q"],
        Some(text.as_bytes()),
    ));
    // Without -o there is no name to derive an output from.
    let r = run_with(dir.path(), ["render", "-"], Some(BASE_TOML.as_bytes()));
    assert!(error_line(&r, 2).contains("needs -o"));
}

#[test]
fn the_image_goes_to_stdout_with_an_explicit_format() {
    let dir = scene_dir("stdout");
    ok(render(&dir, &["-o", "file.png", "-q"]));
    let r = ok(render(&dir, &["-o", "-", "--format", "png"]));
    // The summary stays on stderr; stdout is the PNG alone.
    assert!(r.stderr.contains("-> -"), "{}", r.stderr);
    let piped = image::load_from_memory(&r.stdout).unwrap().to_rgb8();
    assert_eq!(piped, image(&dir.join("file.png")));
    let r = ok(render(&dir, &["-o", "-", "--format", "pfm", "-q"]));
    assert!(r.stdout.starts_with(b"PF\n64 48\n"), "not a PFM");
    assert_eq!(r.stdout.len(), "PF\n64 48\n-1.0\n".len() + 64 * 48 * 12);
    for (args, words) in [
        (&["-o", "-"][..], "--format"),
        (&["-o", "-", "--format", "png", "--json"][..], "--json"),
        (&["-o", "x.exr", "--format", "png"][..], "disagrees"),
    ] {
        let r = render(&dir, args);
        assert!(error_line(&r, 2).contains(words), "{args:?}: {r:?}");
        assert!(r.stdout.is_empty());
    }
}

#[test]
fn every_subcommand_takes_version() {
    let dir = TempDir::new("version");
    let version = env!("CARGO_PKG_VERSION");
    for sub in [
        &["--version"][..],
        &["render", "--version"],
        &["check", "--version"],
    ] {
        let r = ok(run_in(dir.path(), sub));
        assert!(r.out().contains(version), "{sub:?}: {}", r.out());
    }
}
