//! `--set KEY.PATH=VALUE` and its alias `-D`: any scene key overridden from the command line,
//! checked like the file, with errors that name `--set` and the key. (The rules of paths and
//! values are tested on the library, in `crates/penumbra/tests/overrides.rs`.)

mod harness;
#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use std::path::{Path, PathBuf};

use harness::{error_line, image, ok, run_in};
use support::{TempDir, BASE_TOML};

#[test]
fn set_changes_the_render_like_the_file_would() {
    let dir = TempDir::new("set-render");
    dir.write("s.toml", BASE_TOML);
    let edited = BASE_TOML
        .replace("width = 16", "width = 10")
        .replace("diffuse = [0.8, 0.1, 0.1]", "diffuse = [0.1, 0.1, 0.8]");
    dir.write("edited.toml", edited);
    ok(run_in(
        dir.path(),
        [
            "render",
            "s.toml",
            "-o",
            "set.png",
            "--set",
            "film.width=10",
            "-D",
            "materials.red.diffuse=[0.1, 0.1, 0.8]",
            "-q",
        ],
    ));
    ok(run_in(
        dir.path(),
        ["render", "edited.toml", "-o", "file.png", "-q"],
    ));
    let (a, b) = (image(&dir.join("set.png")), image(&dir.join("file.png")));
    assert_eq!(a.dimensions(), (10, 12));
    assert_eq!(
        a, b,
        "--set and the same edit in the file must give the same image"
    );
}

#[test]
fn flags_still_win_over_set() {
    let dir = TempDir::new("set-flags");
    dir.write("s.toml", BASE_TOML);
    let r = ok(run_in(
        dir.path(),
        [
            "render",
            "s.toml",
            "-o",
            "o.png",
            "-D",
            "film.width=10",
            "--width",
            "8",
            "--json",
            "-q",
        ],
    ));
    assert!(r.out().contains("\"width\":8"), "{}", r.out());
}

#[test]
fn bad_overrides_name_set_and_the_key() {
    let dir = TempDir::new("set-errors");
    dir.write("s.toml", BASE_TOML);
    let cases: [(&str, &[&str]); 5] = [
        ("film.width=wide", &["film.width", "expected an integer"]),
        ("film.widht=3", &["film.widht", "unknown field `widht`"]),
        (
            "objects[1].material=blue",
            &["objects[1].material", "unknown material \"blue\""],
        ),
        ("objects.7.material=red", &["objects", "2 entries"]),
        ("render.samples=3", &["render.samples", "perfect square"]),
    ];
    for (set, words) in cases {
        let render = ["render", "s.toml", "-o", "o.png", "--set", set];
        let check = ["check", "s.toml", "--set", set, "--json"];
        for r in [run_in(dir.path(), render), run_in(dir.path(), check)] {
            assert!(r.stdout.is_empty(), "{}", r.out());
            let line = error_line(&r, 2);
            assert!(line.starts_with("error: s.toml: "), "{line}");
            assert!(line.contains(&format!("(--set {set})")), "{line}");
            for w in words {
                assert!(line.contains(w), "{line} lacks {w}");
            }
            assert!(!dir.join("o.png").exists());
        }
    }
}

#[test]
fn a_malformed_override_is_a_usage_error() {
    let dir = TempDir::new("set-usage");
    dir.write("s.toml", BASE_TOML);
    let r = run_in(dir.path(), ["render", "s.toml", "--set", "film.width"]);
    let line = error_line(&r, 2);
    assert!(line.contains("--set"), "{line}");
    assert!(line.contains("KEY.PATH=VALUE"), "{line}");
}

/// The repository's own scenes, the ones a newcomer tries first.
fn shipped_scenes() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml" || e == "json"))
        .collect();
    scenes.sort();
    scenes
}

#[test]
fn set_sampler_center_means_one_sample_on_every_shipped_scene() {
    let dir = TempDir::new("set-center");
    let scenes = shipped_scenes();
    assert!(scenes.len() >= 5, "{scenes:?}");
    // Some shipped scenes read the repository's assets/, beside scenes/.
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
    let assets = assets.to_str().unwrap();
    for scene in &scenes {
        let scene = scene.to_str().unwrap();
        let r = ok(run_in(
            dir.path(),
            [
                "check",
                scene,
                "-D",
                "render.sampler=center",
                "--json",
                "--allow-path",
                assets,
            ],
        ));
        let summary: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
        assert_eq!(summary["sampler"], "center", "{scene}");
        assert_eq!(summary["spp"], 1, "{scene}");
    }
    // The override and the flag render the same image.
    let cornell = scenes.iter().find(|p| p.ends_with("cornell.toml")).unwrap();
    let cornell = cornell.to_str().unwrap();
    let small = ["--width", "8", "--height", "8", "-q"];
    let set = [
        "render",
        cornell,
        "-o",
        "set.png",
        "-D",
        "render.sampler=center",
    ];
    let flag = ["render", cornell, "-o", "flag.png", "--sampler", "center"];
    ok(run_in(dir.path(), set.iter().chain(&small)));
    ok(run_in(dir.path(), flag.iter().chain(&small)));
    assert_eq!(image(&dir.join("set.png")), image(&dir.join("flag.png")));
}

#[test]
fn center_with_an_explicit_count_names_the_override_not_a_line() {
    let dir = TempDir::new("set-center-count");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell.toml");
    let scene = scene.to_str().unwrap();
    for pair in [
        ["render.sampler=center", "render.samples=4"],
        ["render.samples=4", "render.sampler=center"],
    ] {
        let r = run_in(
            dir.path(),
            ["render", scene, "-o", "o.png", "-D", pair[0], "-D", pair[1]],
        );
        let line = error_line(&r, 2);
        assert!(
            line.contains("render.samples (--set render.samples=4)"),
            "{line}"
        );
        assert!(
            line.contains("the center sampler takes exactly 1 sample"),
            "{line}"
        );
        // The file's name with no line:column after it: the override is to blame.
        assert!(line.contains("cornell.toml: render.samples"), "{line}");
        assert!(!dir.join("o.png").exists());
    }
}
