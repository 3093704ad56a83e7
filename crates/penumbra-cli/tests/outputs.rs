//! Output names and records (issue 63): a pattern's fields never take an image out of the
//! folder the pattern names nor two renders to one file; `--resume` trusts an image only at
//! the size and digest its record keeps, never opens a record that is not a regular file,
//! and removes what a killed run left; errors name the image asked for, never a temporary
//! file.

mod harness;
#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use harness::{error_line, ok, run_in};
use serde_json::Value;
use support::{TempDir, BASE_CAMERA, BASE_TOML};

/// The base scene with an orbit camera `turn` of three frames.
fn scene() -> String {
    BASE_TOML.replace(
        BASE_CAMERA,
        "[cameras.turn]\nfov = 40\n\
         path = { type = \"orbit\", center = [0, 0, 0], radius = 5, height = 1, frames = 3 }\n",
    )
}

/// Every file under `dir`, relative, sorted.
fn tree(dir: &Path) -> Vec<String> {
    let mut all = Vec::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p.clone());
            }
            all.push(p.strip_prefix(dir).unwrap().display().to_string());
        }
    }
    all.sort();
    all
}

/// The `status` of each task of a `--json` run.
fn statuses(r: &harness::Run) -> Vec<String> {
    r.out()
        .lines()
        .map(|l| {
            serde_json::from_str::<Value>(l).unwrap()["status"]
                .as_str()
                .unwrap()
                .to_owned()
        })
        .collect()
}

#[test]
fn patterns_that_climb_out_or_collide_are_refused_before_rendering() {
    let dir = TempDir::new("out-patterns");
    dir.write("s.toml", scene());
    let before = tree(dir.path());
    let render = |pattern: &str| {
        let args = ["render", "s.toml", "--camera", "turn", "-q", "-o", pattern];
        run_in(dir.path(), args)
    };
    // Three frames, one file: each would overwrite the one before.
    let e = error_line(&render("f{frame}/../x.pfm"), 2);
    assert!(e.contains("-o f{frame}/../x.pfm"), "{e}");
    assert!(e.contains("two renders would write x.pfm"), "{e}");
    // Out of the folder the pattern names.
    let e = error_line(&render("out/{frame}/../../x{frame}.png"), 2);
    assert!(
        e.contains("out/{frame}/../../x{frame}.png") && e.contains("outside its folder out"),
        "{e}"
    );
    assert_eq!(tree(dir.path()), before, "nothing written");
    // Inside it, a `..` is fine.
    ok(render("out/{frame}/../x{frame}.png"));
    assert!(dir.join("out/x0.png").is_file() && dir.join("out/x2.png").is_file());
}

#[test]
fn a_scene_named_dot_dot_stays_in_the_patterns_folder() {
    let dir = TempDir::new("out-scene-stem");
    // `...toml`: its stem is `..`.
    dir.write("...toml", BASE_TOML);
    ok(run_in(
        dir.path(),
        ["render", "...toml", "-q", "-o", "out/sub/{scene}/a.png"],
    ));
    assert!(
        dir.join("out/sub/_./a.png").is_file(),
        "{:?}",
        tree(dir.path())
    );
    assert!(!dir.join("out/a.png").exists());
}

#[test]
fn resume_renders_again_an_image_cut_short_or_changed_after_its_record() {
    let dir = TempDir::new("out-resume-digest");
    dir.write("s.toml", BASE_TOML);
    let run = || {
        let args = [
            "render", "s.toml", "-o", "out.pfm", "--resume", "--json", "-q",
        ];
        statuses(&ok(run_in(dir.path(), args)))
    };
    assert_eq!(run(), ["rendered"]);
    let whole = std::fs::read(dir.join("out.pfm")).unwrap();
    let record: Value =
        serde_json::from_slice(&std::fs::read(dir.join("out.meta.json")).unwrap()).unwrap();
    assert_eq!(record["digests"][0]["bytes"], whole.len());
    assert_eq!(run(), ["skipped"]);
    // Cut short (a full disk, a copy interrupted) with its record in place.
    std::fs::write(dir.join("out.pfm"), &whole[..whole.len() / 2]).unwrap();
    assert_eq!(run(), ["rendered"]);
    assert_eq!(std::fs::read(dir.join("out.pfm")).unwrap(), whole);
    // The same size, one byte changed.
    let mut changed = whole.clone();
    *changed.last_mut().unwrap() ^= 1;
    std::fs::write(dir.join("out.pfm"), &changed).unwrap();
    assert_eq!(run(), ["rendered"]);
    assert_eq!(run(), ["skipped"]);
}

#[test]
fn resume_never_opens_a_record_that_is_a_named_pipe() {
    let dir = TempDir::new("out-resume-fifo");
    dir.write("s.toml", BASE_TOML);
    ok(run_in(
        dir.path(),
        ["render", "s.toml", "-o", "out.png", "-q"],
    ));
    let made = Command::new("mkfifo")
        .arg(dir.join("out.meta.json"))
        .status()
        .unwrap();
    assert!(made.success());
    let mut child = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args([
            "render", "s.toml", "-o", "out.png", "--resume", "--json", "-q",
        ])
        .current_dir(dir.path())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(60) {
            child.kill().unwrap();
            panic!("--resume blocked on a named pipe");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let out = child.wait_with_output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("\"rendered\""));
    assert!(dir.join("out.meta.json").is_file(), "a record in its place");
}

#[test]
fn resume_removes_what_a_killed_run_left_beside_its_outputs() {
    let dir = TempDir::new("out-resume-tidy");
    dir.write("s.toml", BASE_TOML);
    // A process id above Linux's largest is no running process: as if killed.
    let left = [
        "out/.a.png.tmp-99999999-0",
        "out/.a.depth.pfm.tmp-99999999-1",
        "out/.a.meta.json.tmp-99999999-2",
    ];
    let other = "out/.b.png.tmp-99999999-0";
    let leave = || {
        for name in left.iter().chain([&other]) {
            dir.write(name, b"half");
        }
    };
    let run = || {
        let args = [
            "render",
            "s.toml",
            "-o",
            "out/a.png",
            "--aov",
            "depth",
            "--resume",
            "--json",
            "-q",
        ];
        statuses(&ok(run_in(dir.path(), args)))
    };
    leave();
    assert_eq!(run(), ["rendered"]);
    assert!(
        left.iter().all(|n| !dir.join(n).exists()),
        "{:?}",
        tree(dir.path())
    );
    assert!(
        dir.join(other).exists(),
        "another output's is not this run's to remove"
    );
    // Skipped as done: what is left beside it goes too.
    leave();
    assert_eq!(run(), ["skipped"]);
    assert!(
        left.iter().all(|n| !dir.join(n).exists()),
        "{:?}",
        tree(dir.path())
    );
}

#[test]
fn an_image_that_cannot_be_written_is_named_not_its_temporary_file() {
    let dir = TempDir::new("out-name");
    dir.write("s.toml", BASE_TOML);
    // A name the file system takes, whose temporary name is too long for it.
    let name = format!("{}.png", "a".repeat(240));
    let r = run_in(dir.path(), ["render", "s.toml", "-q", "-o", &name]);
    let e = error_line(&r, 1);
    assert!(e.contains(&name) && !e.contains(".tmp-"), "{e}");
    assert_eq!(tree(dir.path()), ["s.toml"]);
}

#[test]
fn alpha_is_written_as_rgba_and_refused_where_a_format_has_none() {
    let dir = TempDir::new("out-alpha");
    dir.write("s.toml", BASE_TOML);
    let render = |args: &[&str]| {
        let mut all = vec!["render", "s.toml", "-q"];
        all.extend_from_slice(args);
        run_in(dir.path(), all)
    };
    // The sky above the floor is transparent, the cube and floor opaque.
    ok(render(&["--alpha", "-o", "a.png", "--meta"]));
    let png = image::open(dir.join("a.png")).unwrap();
    let rgba = png.as_rgba8().expect("an RGBA PNG");
    let alphas: Vec<u8> = rgba.pixels().map(|p| p[3]).collect();
    assert!(alphas.contains(&0) && alphas.contains(&255), "{alphas:?}");
    assert!(rgba.pixels().all(|p| p[3] > 0 || p.0 == [0, 0, 0, 0]));
    let record: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("a.meta.json")).unwrap()).unwrap();
    assert_eq!(
        record["settings"]["render"]["alpha"],
        Value::Bool(true),
        "{record}"
    );
    // The file's key, by --set, and the multi-layer EXR: A beside R, G, B.
    ok(render(&[
        "--set",
        "film.alpha=true",
        "--aov",
        "depth",
        "-o",
        "a.exr",
    ]));
    let layer = exr::prelude::read_first_flat_layer_from_file(dir.join("a.exr")).unwrap();
    let names: Vec<String> = (layer.layer_data.channel_data.list.iter())
        .map(|c| c.name.to_string())
        .collect();
    assert_eq!(names, ["A", "B", "G", "R", "depth.Z"]);
    // Formats without alpha are refused before anything is rendered.
    let before = tree(dir.path());
    for out in ["a.jpg", "a.pfm"] {
        let e = error_line(&render(&["--alpha", "-o", out]), 2);
        assert!(e.contains(out) && e.contains("no alpha channel"), "{e}");
    }
    assert_eq!(tree(dir.path()), before);
}
