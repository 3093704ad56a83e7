//! What a newcomer from other renderers tries (issue 62): a scene path alone renders, as
//! `mitsuba scene.xml` does; `--res WxH`; `--camera auto` (frame all); a listing piped into
//! `head` ends quietly; a scene without light is warned of; the answers name ranges, not
//! clap's tips.

mod harness;
#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

use harness::{error_line, image, ok, run_in};
use support::{edit, TempDir, BASE_CAMERA, BASE_TOML};

const TRIANGLE_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

fn scene_dir(name: &str) -> TempDir {
    let dir = TempDir::new(name);
    dir.write("s.toml", BASE_TOML);
    dir
}

/// [`BASE_TOML`] without its point light.
fn without_light() -> String {
    edit(
        BASE_TOML,
        "[[lights]]\ntype = \"point\"\nposition = [0, 5, 5]\n",
        "",
    )
}

#[test]
fn a_scene_path_alone_means_render() {
    let dir = scene_dir("bare-path");
    ok(run_in(dir.path(), ["s.toml", "-o", "a.png", "-q"]));
    ok(run_in(
        dir.path(),
        ["render", "s.toml", "-o", "b.png", "-q"],
    ));
    assert_eq!(image(&dir.join("a.png")), image(&dir.join("b.png")));
    // A model too; and a word that is no file stays clap's unknown subcommand.
    dir.write("tri.obj", TRIANGLE_OBJ);
    ok(run_in(dir.path(), ["tri.obj", "--res", "8x6", "-q"]));
    assert_eq!(image(&dir.join("tri.png")).dimensions(), (8, 6));
    let r = run_in(dir.path(), ["rendr", "s.toml"]);
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(r.stderr.contains("unrecognized subcommand"), "{}", r.stderr);
}

#[test]
fn resolution_sets_both_sides_and_names_its_form() {
    let dir = scene_dir("resolution");
    let r = ok(run_in(
        dir.path(),
        ["render", "s.toml", "-o", "a.png", "--res", "20x10"],
    ));
    assert!(r.stderr.contains("20x10, "), "{}", r.stderr);
    ok(run_in(
        dir.path(),
        [
            "render", "s.toml", "-o", "b.png", "--width", "20", "--height", "10", "-q",
        ],
    ));
    assert_eq!(image(&dir.join("a.png")), image(&dir.join("b.png")));
    for bad in ["20", "0x10", "20x", "axb"] {
        let r = run_in(
            dir.path(),
            ["render", "s.toml", "-o", "c.png", "--resolution", bad],
        );
        let line = error_line(&r, 2);
        assert!(line.contains("expected WIDTHxHEIGHT"), "{bad}: {line}");
    }
    let r = run_in(
        dir.path(),
        [
            "render", "s.toml", "-o", "c.png", "--res", "4x4", "--width", "8",
        ],
    );
    assert_eq!(r.code, Some(2), "{r:?}");
    assert!(!dir.join("c.png").exists());
}

#[test]
fn threads_and_samples_are_answered_with_what_they_take() {
    let dir = scene_dir("ranges");
    let r = run_in(dir.path(), ["render", "s.toml", "-o", "a.png", "-t", "-1"]);
    let line = error_line(&r, 2);
    assert!(
        line.contains("0 (all cores)") && line.contains("not -1"),
        "{line}"
    );
    assert!(!r.stderr.contains("-- -1"), "{}", r.stderr);
    let r = run_in(
        dir.path(),
        ["render", "s.toml", "-o", "a.png", "--spp", "5"],
    );
    let line = error_line(&r, 2);
    assert!(line.contains("not 5 (the nearest are 4 and 9)"), "{line}");
    let r = run_in(
        dir.path(),
        ["render", "s.toml", "-o", "a.png", "--spp", "0"],
    );
    assert!(error_line(&r, 2).contains("(the smallest is 1)"), "{r:?}");
    assert!(!dir.join("a.png").exists());
}

#[test]
fn every_subcommand_calls_itself_penumbra_in_its_version() {
    let dir = scene_dir("versions");
    for args in [
        &["--version"][..],
        &["render", "--version"],
        &["check", "--version"],
    ] {
        let r = ok(run_in(dir.path(), args));
        let out = r.out();
        assert!(out.starts_with("penumbra "), "{args:?}: {out}");
        assert!(!out.contains("penumbra-"), "{args:?}: {out}");
    }
}

#[test]
fn a_listing_stops_quietly_when_its_reader_does() {
    let dir = TempDir::new("broken-pipe");
    let orbit = "[cameras.turn]\nfov = 45\n\
                 path = { type = \"orbit\", center = [0, 0, 0], radius = 5, height = 1, frames = 5000 }\n";
    dir.write("s.toml", edit(BASE_TOML, BASE_CAMERA, orbit));
    // Five thousand lines overflow any pipe's buffer: the listing meets the closed pipe.
    let mut child = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(["render", "s.toml", "--dry-run", "-o", "out/{frame}.png"])
        .current_dir(dir.path())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    assert!(
        first.starts_with("task 0 of 5000: camera turn frame 0"),
        "{first}"
    );
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(stderr.is_empty(), "{stderr}");
}

#[test]
fn a_scene_without_light_is_warned_of_by_render_and_check() {
    let dir = TempDir::new("no-light");
    dir.write("dark.toml", without_light());
    dir.write(
        "black.toml",
        format!("{}\n[render]\nambient = 0\n", without_light()),
    );
    dir.write("lit.toml", BASE_TOML);
    for sub in ["render", "check"] {
        let r = ok(run_in(dir.path(), [sub, "dark.toml"]));
        assert!(
            r.stderr
                .contains("warning: dark.toml: the scene has no light")
                && r.stderr.contains("only render.ambient lights it"),
            "{sub}: {}",
            r.stderr
        );
        let r = ok(run_in(dir.path(), [sub, "black.toml"]));
        assert!(r.stderr.contains("renders black"), "{sub}: {}", r.stderr);
        let r = ok(run_in(dir.path(), [sub, "lit.toml"]));
        assert!(!r.stderr.contains("no light"), "{sub}: {}", r.stderr);
    }
    assert!(dir.join("dark.png").exists() && dir.join("black.png").exists());
}

#[test]
fn camera_auto_frames_any_scene_as_a_bare_model_is_framed() {
    let dir = scene_dir("camera-auto");
    dir.write("tri.obj", TRIANGLE_OBJ);
    let small = ["--res", "16x12", "-q"];
    // A bare model: auto is the camera it gets anyway.
    ok(run_in(
        dir.path(),
        [&["render", "tri.obj", "-o", "a.png"][..], &small].concat(),
    ));
    ok(run_in(
        dir.path(),
        [
            &["render", "tri.obj", "-o", "b.png", "--camera", "auto"][..],
            &small,
        ]
        .concat(),
    ));
    assert_eq!(image(&dir.join("a.png")), image(&dir.join("b.png")));
    // A scene with cameras of its own: auto looks from elsewhere.
    ok(run_in(
        dir.path(),
        [&["render", "s.toml", "-o", "c.png"][..], &small].concat(),
    ));
    ok(run_in(
        dir.path(),
        [
            &["render", "s.toml", "-o", "d.png", "--camera", "auto"][..],
            &small,
        ]
        .concat(),
    ));
    assert_ne!(image(&dir.join("c.png")), image(&dir.join("d.png")));
    // A camera the scene calls `auto` is that camera.
    let named = edit(BASE_TOML, "[camera]\n", "[cameras.auto]\n");
    dir.write("named.toml", named);
    ok(run_in(
        dir.path(),
        [
            &["render", "named.toml", "-o", "e.png", "--camera", "auto"][..],
            &small,
        ]
        .concat(),
    ));
    assert_eq!(image(&dir.join("c.png")), image(&dir.join("e.png")));
}

#[test]
fn a_bare_models_image_lands_in_the_current_folder() {
    let dir = TempDir::new("model-output");
    dir.write("models/tri.obj", TRIANGLE_OBJ);
    ok(run_in(
        dir.path(),
        ["render", "models/tri.obj", "--res", "8x6", "-q"],
    ));
    assert!(dir.join("tri.png").exists());
    assert!(!dir.join("models/tri.png").exists());
}

#[test]
fn json_keeps_the_line_for_people_off_stderr() {
    let dir = scene_dir("json-quiet");
    let r = ok(run_in(
        dir.path(),
        ["render", "s.toml", "-o", "a.png", "--json"],
    ));
    let line: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(line["output"], "a.png");
    assert!(!r.stderr.contains("Mrays/s"), "{}", r.stderr);
}
