//! Batches any scheduler can run (issue 28, part 5): `--manifest` lines, `--retries` and the
//! failures listed at the end, `--dry-run`, and an unwritable manifest refused up front.

mod harness;
#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use harness::{error_line, ok, run_in};
use serde_json::Value;
use support::{TempDir, BASE_CAMERA as STILL, BASE_TOML};

/// The base scene seen by an orbit of 6 frames.
fn scene() -> String {
    BASE_TOML.replace(
        STILL,
        "[camera]\nfov = 40\n\
         path = { type = \"orbit\", center = [0, 0, 0], radius = 5, height = 1, frames = 6 }\n",
    )
}

fn lines(text: &str) -> Vec<Value> {
    text.lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

#[test]
fn the_manifest_has_a_line_per_task_of_every_run() {
    let dir = TempDir::new("batch-manifest");
    dir.write("s.toml", scene());
    let run = |frames: &str| {
        ok(run_in(
            dir.path(),
            [
                "render",
                "s.toml",
                "-o",
                "out/{frame}.png",
                "--frames",
                frames,
                "--resume",
                "--manifest",
                "logs/manifest.jsonl",
                "-q",
            ],
        ))
    };
    run("0:2");
    run("all");
    let text = std::fs::read_to_string(dir.join("logs/manifest.jsonl")).unwrap();
    let m = lines(&text);
    let status: Vec<(i64, &str)> = m
        .iter()
        .map(|l| (l["frame"].as_i64().unwrap(), l["status"].as_str().unwrap()))
        .collect();
    assert_eq!(
        status,
        [
            (0, "rendered"),
            (1, "rendered"),
            (2, "rendered"),
            (0, "skipped"),
            (1, "skipped"),
            (2, "skipped"),
            (3, "rendered"),
            (4, "rendered"),
            (5, "rendered"),
        ],
        "no frame rendered twice"
    );
    let first = &m[0];
    assert_eq!(first["task"], 0);
    assert_eq!(first["camera"], "camera");
    assert_eq!(first["seed"], 0);
    assert_eq!(first["attempts"], 1);
    assert_eq!(first["error"], Value::Null);
    assert_eq!(first["outputs"], serde_json::json!(["out/0.png"]));
    assert!(first["seconds"].as_f64().unwrap() >= 0.0);
    assert!(!first["host"].as_str().unwrap().is_empty());
    if cfg!(target_os = "linux") {
        assert!(first["peak_memory_bytes"].as_u64().unwrap() > 1 << 20);
    }
}

#[test]
fn a_failing_task_is_retried_then_listed_while_the_others_render() {
    let dir = TempDir::new("batch-retries");
    dir.write("s.toml", scene());
    // Frame 2's image cannot be written: a folder has its name.
    std::fs::create_dir_all(dir.join("out/2.png")).unwrap();
    let r = run_in(
        dir.path(),
        [
            "render",
            "s.toml",
            "-o",
            "out/{frame}.png",
            "--retries",
            "2",
            "--manifest",
            "m.jsonl",
            "--json",
        ],
    );
    let e = error_line(&r, 1);
    assert!(e.contains("1 of 6 tasks failed: task 2 (out/2.png)"), "{e}");
    assert_eq!(r.stderr.matches("[3/6] attempt").count(), 2, "{}", r.stderr);
    let rendered: Vec<i64> = lines(&r.out())
        .iter()
        .map(|l| l["frame"].as_i64().unwrap())
        .collect();
    assert_eq!(rendered, [0, 1, 3, 4, 5]);
    for f in [0, 1, 3, 4, 5] {
        assert!(dir.join(format!("out/{f}.png")).is_file());
    }
    let m = lines(&std::fs::read_to_string(dir.join("m.jsonl")).unwrap());
    let failed: Vec<&Value> = m.iter().filter(|l| l["status"] == "failed").collect();
    assert_eq!(failed.len(), 1);
    assert_eq!(
        (&failed[0]["frame"], &failed[0]["attempts"]),
        (&Value::from(2), &Value::from(3))
    );
    assert!(failed[0]["error"].as_str().unwrap().contains("out/2.png"));
}

#[test]
fn a_dry_run_lists_the_tasks_and_writes_nothing() {
    let dir = TempDir::new("batch-dry");
    dir.write("s.toml", scene());
    let r = ok(run_in(
        dir.path(),
        [
            "render",
            "s.toml",
            "-o",
            "out/{frame}.png",
            "--dry-run",
            "--shard",
            "1/2",
            "--poses",
            "p.json",
            "--manifest",
            "m.jsonl",
        ],
    ));
    assert_eq!(
        r.out(),
        "task 1 of 6: camera camera frame 1 -> out/1.png\n\
         task 3 of 6: camera camera frame 3 -> out/3.png\n\
         task 5 of 6: camera camera frame 5 -> out/5.png\n"
    );
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["s.toml"]);
    // With --resume, what a run would skip.
    ok(run_in(
        dir.path(),
        [
            "render",
            "s.toml",
            "-o",
            "out/{frame}.png",
            "--frames",
            "3",
            "--resume",
            "-q",
        ],
    ));
    let r = ok(run_in(
        dir.path(),
        [
            "render",
            "s.toml",
            "-o",
            "out/{frame}.png",
            "--resume",
            "--dry-run",
            "--json",
        ],
    ));
    let status: Vec<String> = lines(&r.out())
        .iter()
        .map(|l| l["status"].as_str().unwrap().to_owned())
        .collect();
    assert_eq!(
        status,
        ["planned", "planned", "planned", "skipped", "planned", "planned"]
    );
}

#[test]
fn an_unwritable_manifest_is_refused_before_any_work() {
    let dir = TempDir::new("batch-bad-manifest");
    dir.write("s.toml", scene());
    std::fs::create_dir(dir.join("folder.jsonl")).unwrap();
    let r = run_in(
        dir.path(),
        [
            "render",
            "s.toml",
            "-o",
            "out/{frame}.png",
            "--manifest",
            "folder.jsonl",
        ],
    );
    let e = error_line(&r, 2);
    assert!(
        e.contains("--manifest folder.jsonl: cannot write the manifest"),
        "{e}"
    );
    assert!(!dir.join("out").exists(), "nothing rendered");
}
