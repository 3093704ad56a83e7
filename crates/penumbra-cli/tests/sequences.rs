//! Sequences (issue 28): path cameras rendered frame by frame from one loaded scene,
//! `--frames`, `{frame}` in `-o`, `--shard`, `--resume`, and their errors.

mod harness;
#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use std::path::Path;

use harness::{error_line, ok, run_in};
use serde_json::Value;
use support::{TempDir, BASE_CAMERA as STILL, BASE_TOML};

/// The base scene with a still camera `front`, a keyframed camera `fly` (frames 2 to 9) and
/// an orbit `turn` (frames 0 to 5).
fn scene() -> String {
    BASE_TOML.replace(
        STILL,
        "[cameras.front]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\nfov = 45\n\
         [cameras.fly]\nfov = 45\n\
         [[cameras.fly.keys]]\nframe = 2\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\n\
         [[cameras.fly.keys]]\nframe = 6\nposition = [3, 2, 4]\nlook_at = [0, 0.2, 0]\nfov = 35\n\
         [[cameras.fly.keys]]\nframe = 9\nposition = [4, 1, -1]\nlook_at = [0, 0, 0]\n\
         [cameras.turn]\nfov = 40\n\
         path = { type = \"orbit\", center = [0, 0, 0], radius = 5, height = 1, frames = 6 }\n",
    )
}

fn files(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map(|d| {
            d.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

fn json_lines(out: &str) -> Vec<Value> {
    out.lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

#[test]
fn a_path_camera_renders_every_frame_from_one_loaded_scene() {
    let dir = TempDir::new("seq-all");
    dir.write("s.toml", scene());
    let r = ok(run_in(
        dir.path(),
        [
            "render",
            "s.toml",
            "--camera",
            "turn",
            "-o",
            "out/{camera}_{frame:03}.png",
        ],
    ));
    assert!(r.stderr.contains("[6/6] frame 5"), "{}", r.stderr);
    let names = files(&dir.join("out"));
    let expected: Vec<String> = (0..6).map(|f| format!("turn_{f:03}.png")).collect();
    assert_eq!(names, expected);
    // The frames differ: the camera moves.
    let a = std::fs::read(dir.join("out/turn_000.png")).unwrap();
    let b = std::fs::read(dir.join("out/turn_003.png")).unwrap();
    assert_ne!(a, b);
    // One load for all: every frame's summary reports the same load time.
    let r = ok(run_in(
        dir.path(),
        [
            "render",
            "s.toml",
            "--camera",
            "fly",
            "--frames",
            "3:9:3",
            "-o",
            "f/{frame}.png",
            "--json",
            "-q",
        ],
    ));
    let lines = json_lines(&r.out());
    let frames: Vec<i64> = lines.iter().map(|l| l["frame"].as_i64().unwrap()).collect();
    assert_eq!(frames, [3, 6, 9]);
    assert!(lines
        .iter()
        .all(|l| l["load_seconds"] == lines[0]["load_seconds"]));
    assert_eq!(files(&dir.join("f")), ["3.png", "6.png", "9.png"]);
}

#[test]
fn a_frame_on_a_key_is_that_keys_camera_to_the_byte() {
    let dir = TempDir::new("seq-key");
    dir.write("s.toml", scene());
    ok(run_in(
        dir.path(),
        [
            "render", "s.toml", "--camera", "fly", "--frames", "6", "-o", "key.png",
        ],
    ));
    // The key of frame 6 as a still camera.
    let still = BASE_TOML.replace(
        STILL,
        "[camera]\nposition = [3, 2, 4]\nlook_at = [0, 0.2, 0]\nfov = 35\n",
    );
    dir.write("still.toml", still);
    ok(run_in(
        dir.path(),
        ["render", "still.toml", "-o", "still.png"],
    ));
    assert_eq!(
        std::fs::read(dir.join("key.png")).unwrap(),
        std::fs::read(dir.join("still.png")).unwrap()
    );
}

#[test]
fn four_shards_write_the_files_one_process_writes_byte_for_byte() {
    let dir = TempDir::new("seq-shard");
    dir.write("s.toml", scene());
    let args = ["render", "s.toml", "--camera", "fly,turn", "-o"];
    ok(run_in(
        dir.path(),
        args.iter().copied().chain(["one/{camera}_{frame}.png"]),
    ));
    for k in 0..4 {
        let shard = format!("{k}/4");
        let r = ok(run_in(
            dir.path(),
            args.iter().copied().chain([
                "four/{camera}_{frame}.png",
                "--shard",
                &shard,
                "--json",
                "-q",
            ]),
        ));
        // Tasks k, k + 4, ... of the 14 (8 of fly, then 6 of turn).
        let tasks: Vec<u64> = json_lines(&r.out())
            .iter()
            .map(|l| l["task"].as_u64().unwrap())
            .collect();
        let expected: Vec<u64> = (0..14).filter(|t| t % 4 == k).collect();
        assert_eq!(tasks, expected, "shard {shard}");
    }
    let one = files(&dir.join("one"));
    assert_eq!(one.len(), 14);
    assert_eq!(files(&dir.join("four")), one);
    for name in &one {
        let read = |sub: &str| std::fs::read(dir.join(sub).join(name)).unwrap();
        assert_eq!(read("one"), read("four"), "{name}");
    }
}

#[test]
fn resume_skips_exactly_the_frames_done_with_the_same_settings() {
    let dir = TempDir::new("seq-resume");
    dir.write("s.toml", scene());
    let run = |extra: &[&str]| {
        let mut args = vec![
            "render",
            "s.toml",
            "--camera",
            "turn",
            "-o",
            "out/{frame}.png",
        ];
        args.extend(["--resume", "--json", "-q"]);
        args.extend(extra);
        let r = ok(run_in(dir.path(), args));
        json_lines(&r.out())
            .iter()
            .map(|l| {
                (
                    l["frame"].as_i64().unwrap(),
                    l["status"].as_str().unwrap().to_owned(),
                )
            })
            .collect::<Vec<_>>()
    };
    let status = |frames: &[(i64, &str)]| -> Vec<(i64, String)> {
        frames.iter().map(|(f, s)| (*f, s.to_string())).collect()
    };
    assert_eq!(
        run(&["--frames", "0:2"]),
        status(&[(0, "rendered"), (1, "rendered"), (2, "rendered")])
    );
    assert!(dir.join("out/0.meta.json").is_file());
    let first = std::fs::read(dir.join("out/1.png")).unwrap();
    // A lost image and a damaged record are rendered again.
    std::fs::remove_file(dir.join("out/0.png")).unwrap();
    dir.write("out/2.meta.json", "{not json");
    assert_eq!(
        run(&[]),
        status(&[
            (0, "rendered"),
            (1, "skipped"),
            (2, "rendered"),
            (3, "rendered"),
            (4, "rendered"),
            (5, "rendered")
        ])
    );
    assert_eq!(std::fs::read(dir.join("out/1.png")).unwrap(), first);
    // Everything done: nothing rendered.
    assert!(run(&[]).iter().all(|(_, s)| s == "skipped"));
    // Other settings are another image: all rendered again.
    assert!(run(&["--spp", "1"]).iter().all(|(_, s)| s == "rendered"));
    assert!(run(&["--spp", "1"]).iter().all(|(_, s)| s == "skipped"));
    // So is an edited scene.
    dir.write("s.toml", scene().replace("size = 1\n", "size = 1.5\n"));
    assert!(run(&["--spp", "1"]).iter().all(|(_, s)| s == "rendered"));
}

#[test]
fn bad_sequences_are_one_line_errors_with_exit_code_2() {
    let dir = TempDir::new("seq-errors");
    dir.write("s.toml", scene());
    let err = |args: &[&str]| {
        let mut all = vec!["render", "s.toml"];
        all.extend(args);
        let r = run_in(dir.path(), all);
        error_line(&r, 2)
    };
    let e = err(&["--camera", "turn", "--frames", "0:6", "-o", "{frame}.png"]);
    assert!(
        e.contains("--frames 0:6") && e.contains("frames 0 to 5"),
        "{e}"
    );
    let e = err(&["--camera", "fly", "--frames", "0:4", "-o", "{frame}.png"]);
    assert!(e.contains("frames 2 to 9"), "{e}");
    let e = err(&["--camera", "front", "--frames", "1:2", "-o", "{frame}.png"]);
    assert!(e.contains("--frames") && e.contains("still camera"), "{e}");
    let e = err(&["--camera", "turn", "-o", "x.png"]);
    assert!(e.contains("6 frames need {frame}"), "{e}");
    let e = err(&["--camera", "front", "-o", "{frame}.png"]);
    assert!(e.contains("{frame}") && e.contains("still camera"), "{e}");
    for (shard, words) in [("5/4", "0 to 3"), ("0/0", "at least 1"), ("x", "K/N")] {
        let r = run_in(dir.path(), ["render", "s.toml", "--shard", shard]);
        assert_eq!(r.code, Some(2), "{shard}");
        assert!(
            r.stderr.lines().next().unwrap().contains(words),
            "{}",
            r.stderr
        );
    }
    // The file's errors name file, line and key.
    let out_of_order = scene().replace("frame = 6", "frame = 12");
    dir.write("bad.toml", out_of_order);
    let r = run_in(dir.path(), ["render", "bad.toml"]);
    let e = error_line(&r, 2);
    assert!(
        e.contains("bad.toml:") && e.contains("cameras.fly.keys[2].frame"),
        "{e}"
    );
    assert!(e.contains("frame 9 comes after frame 12"), "{e}");
    dir.write("zero.toml", scene().replace("frames = 6", "frames = 0"));
    let e = error_line(&run_in(dir.path(), ["render", "zero.toml"]), 2);
    assert!(
        e.contains("zero.toml:") && e.contains("cameras.turn.path.frames"),
        "{e}"
    );
    // Nothing was written by any of them.
    assert_eq!(files(dir.path()), ["bad.toml", "s.toml", "zero.toml"]);
}

#[test]
fn without_camera_a_first_path_camera_renders_every_frame() {
    // The first camera is a path: without --camera or --frames it renders every frame, named
    // after the scene with the frame.
    let dir = TempDir::new("seq-default");
    let first_turn = scene().replace("[cameras.front]", "[cameras.a_front]");
    let turn_first = first_turn.replacen(
        "[cameras.a_front]",
        "[cameras.turn2]\nfov = 40\npath = { type = \"orbit\", center = [0, 0, 0], radius = 5, frames = 3 }\n[cameras.a_front]",
        1,
    );
    dir.write("s.toml", turn_first);
    ok(run_in(dir.path(), ["render", "s.toml"]));
    assert_eq!(
        files(dir.path()),
        ["s.toml", "s_0000.png", "s_0001.png", "s_0002.png"]
    );
}

#[test]
fn check_lists_each_path_cameras_frames() {
    let dir = TempDir::new("seq-check");
    dir.write("s.toml", scene());
    let r = ok(run_in(dir.path(), ["check", "s.toml"]));
    assert!(
        r.out()
            .contains("cameras    front, fly (frames 2 to 9), turn (frames 0 to 5)"),
        "{}",
        r.out()
    );
    let r = ok(run_in(dir.path(), ["check", "s.toml", "--json"]));
    let v: Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(v["cameras"], serde_json::json!(["front", "fly", "turn"]));
    assert_eq!(
        v["camera_frames"],
        serde_json::json!({"fly": [2, 9], "turn": [0, 5]})
    );
}

#[test]
fn resume_renders_a_frame_again_when_one_of_its_pass_files_is_gone() {
    let dir = TempDir::new("seq-resume-aov");
    dir.write("s.toml", scene());
    let run = || {
        let r = ok(run_in(
            dir.path(),
            [
                "render",
                "s.toml",
                "--camera",
                "turn",
                "--frames",
                "0:2",
                "--aov",
                "depth",
                "-o",
                "out/{frame}.png",
                "--resume",
                "--json",
                "-q",
            ],
        ));
        json_lines(&r.out())
            .iter()
            .map(|l| l["status"].as_str().unwrap().to_owned())
            .collect::<Vec<_>>()
    };
    assert_eq!(run(), ["rendered", "rendered", "rendered"]);
    let record: Value =
        serde_json::from_slice(&std::fs::read(dir.join("out/1.meta.json")).unwrap()).unwrap();
    assert_eq!(
        record["files"],
        serde_json::json!(["out/1.png", "out/1.depth.pfm"])
    );
    std::fs::remove_file(dir.join("out/1.depth.pfm")).unwrap();
    assert_eq!(run(), ["skipped", "rendered", "skipped"]);
    assert!(dir.join("out/1.depth.pfm").is_file());
}

#[test]
fn resume_renders_again_when_a_mesh_the_scene_reads_changed() {
    let dir = TempDir::new("seq-resume-mesh");
    let triangle = "v -1 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    dir.write("tri.obj", triangle);
    dir.write(
        "s.toml",
        format!("{BASE_TOML}\n[[objects]]\ntype = \"mesh\"\nfile = \"tri.obj\"\n"),
    );
    let run = || {
        let args = [
            "render", "s.toml", "-o", "out.png", "--resume", "--json", "-q",
        ];
        let r = ok(run_in(dir.path(), args));
        json_lines(&r.out())[0]["status"]
            .as_str()
            .unwrap()
            .to_owned()
    };
    assert_eq!(run(), "rendered");
    assert_eq!(run(), "skipped");
    // The same scene text, another mesh: its record no longer matches.
    dir.write("tri.obj", triangle.replace("v 0 1 0", "v 0 2 0"));
    assert_eq!(run(), "rendered");
    assert_eq!(run(), "skipped");
}
