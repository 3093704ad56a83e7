//! Signals sent to a real `penumbra` process (issue 10, class 6): SIGINT, SIGTERM and SIGHUP
//! stop a render promptly, however much work one pixel holds, with the shell's exit code for
//! the signal (128 + its number: 130, 143, 129), one `error:` line, and no image or temporary
//! file left behind; a signal that arrives while the image is being written leaves the old
//! file as it was.
//!
//! Signals are sent with the `kill` command, as a user or a job system would.
#![cfg(unix)]

#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use support::TempDir;

/// One pixel of a floor lit by one area light: with `--spp 65536 --light-samples 256` that
/// pixel alone takes 65536 × 65536 shadow rays, hours of work.
const ONE_HEAVY_PIXEL: &str = r#"[film]
width = 1
height = 1

[camera]
position = [0, 2, 1]
look_at = [0, 0, 0]
fov = 60

[[lights]]
type = "area"
center = [0, 3, 0]
u = [1, 0, 0]
v = [0, 0, 1]
samples = 4

[[objects]]
type = "quad"
corner = [-50, 0, 50]
u = [100, 0, 0]
v = [0, 0, -100]
"#;

/// Starts `penumbra render SCENE -o OUT --quiet ARGS`.
fn spawn_render(scene: &Path, out: &Path, args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .env_remove("RUST_BACKTRACE")
        .arg("render")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .arg("--quiet")
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start the penumbra binary")
}

/// Sends `signal` (as `kill -SIGNAL` names it) to `child`.
fn send(child: &Child, signal: &str) {
    let status = Command::new("kill")
        .args([&format!("-{signal}"), &child.id().to_string()])
        .status()
        .expect("run kill");
    assert!(status.success(), "kill -{signal} failed");
}

/// Waits at most `limit` for `child` to exit (killing it then, and failing), and returns its
/// exit code, its stderr and how long the wait took.
fn wait_at_most(mut child: Child, limit: Duration, what: &str) -> (Option<i32>, String, Duration) {
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{what}: still running {limit:?} after the signal");
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    let took = start.elapsed();
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    (out.status.code(), stderr, took)
}

/// Files in `dir` whose names mark a temporary image (`.NAME.tmp-PID-N`).
fn temporary_files(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp"))
        .collect()
}

/// Asserts the one `error:` line of an interrupted run.
fn assert_interrupted(what: &str, stderr: &str) {
    for word in ["panicked", "backtrace"] {
        assert!(!stderr.contains(word), "{what}: panic: {stderr}");
    }
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 1, "{what}: want one error line: {stderr}");
    assert!(errors[0].contains("interrupted"), "{what}: {}", errors[0]);
}

#[test]
fn int_term_and_hup_stop_even_one_heavy_pixel_at_once() {
    let sb = TempDir::new("signal-heavy-pixel");
    let scene = sb.write("s.toml", ONE_HEAVY_PIXEL);
    let out = sb.join("out.png");
    for (signal, code) in [("INT", 130), ("TERM", 143), ("HUP", 129)] {
        let child = spawn_render(
            &scene,
            &out,
            &["--spp", "65536", "--light-samples", "256", "-t", "1"],
        );
        // Loading this scene takes milliseconds: after a second the pixel is being worked on.
        std::thread::sleep(Duration::from_secs(1));
        assert!(
            !out.exists(),
            "SIG{signal}: an image appeared before the signal"
        );
        send(&child, signal);
        // The promise is 100 ms; the bound leaves room for a loaded test machine.
        let (got, stderr, took) =
            wait_at_most(child, Duration::from_secs(2), &format!("SIG{signal}"));
        eprintln!(
            "SIG{signal}: exited {got:?} {} ms after the signal",
            took.as_millis()
        );
        assert_eq!(got, Some(code), "SIG{signal}: exit code; stderr: {stderr}");
        assert_interrupted(&format!("SIG{signal}"), &stderr);
        assert!(!out.exists(), "SIG{signal}: an image was written");
        assert!(
            temporary_files(sb.path()).is_empty(),
            "SIG{signal}: temporary files left: {:?}",
            temporary_files(sb.path())
        );
    }
}

#[test]
fn a_signal_while_the_image_is_written_keeps_the_old_image_and_no_temporary_file() {
    let sb = TempDir::new("signal-while-writing");
    // A large film without lights renders in a moment but takes a while to encode as PNG.
    let scene = sb.write(
        "s.toml",
        ONE_HEAVY_PIXEL
            .replace("width = 1\n", "width = 3000\n")
            .replace("height = 1\n", "height = 3000\n")
            .replace("samples = 4\n", "samples = 1\n"),
    );
    let out = sb.join("out.png");
    let old = b"the previous image".to_vec();
    std::fs::write(&out, &old).unwrap();
    let child = spawn_render(&scene, &out, &["--sampler", "center"]);
    // The temporary file appears when writing begins; signal the process as soon as it does.
    let start = Instant::now();
    while temporary_files(sb.path()).is_empty() {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no temporary image file appeared"
        );
        std::thread::sleep(Duration::from_micros(200));
    }
    send(&child, "TERM");
    let (got, stderr, took) = wait_at_most(child, Duration::from_secs(10), "SIGTERM");
    eprintln!(
        "SIGTERM while writing: exited {got:?} {} ms after the signal",
        took.as_millis()
    );
    assert_eq!(got, Some(143), "exit code; stderr: {stderr}");
    assert_interrupted("SIGTERM while writing", &stderr);
    assert_eq!(
        std::fs::read(&out).unwrap(),
        old,
        "the old image was changed"
    );
    assert!(
        temporary_files(sb.path()).is_empty(),
        "temporary files left: {:?}",
        temporary_files(sb.path())
    );
}

#[test]
fn ctrl_c_during_progressive_writes_the_last_finished_pass() {
    let sb = TempDir::new("signal-progressive");
    let scene = sb.write("s.toml", ONE_HEAVY_PIXEL);
    let out = sb.join("out.pfm");
    // Passes of 1, 2, 4, ... samples of 256 × 256 shadow rays each: after a second some
    // passes are done, and the last ones take far longer than the test.
    let child = spawn_render(
        &scene,
        &out,
        &[
            "--spp",
            "65536",
            "--light-samples",
            "256",
            "-t",
            "1",
            "--progressive",
        ],
    );
    std::thread::sleep(Duration::from_secs(1));
    send(&child, "INT");
    let (got, stderr, _) = wait_at_most(child, Duration::from_secs(5), "SIGINT");
    assert_eq!(got, Some(130), "exit code; stderr: {stderr}");
    assert_interrupted("SIGINT", &stderr);
    assert!(
        stderr.contains("interrupted: wrote the last finished pass ("),
        "{stderr}"
    );
    // The pass's image is whole: a PFM of one lit pixel.
    let bytes = std::fs::read(&out).expect("the last pass was written");
    assert!(bytes.starts_with(b"PF\n1 1\n-1.0\n"));
    let red = f32::from_le_bytes(bytes[bytes.len() - 12..bytes.len() - 8].try_into().unwrap());
    assert!(red > 0.0, "a lit floor: {red}");
    assert!(temporary_files(sb.path()).is_empty());
}

/// [`ONE_HEAVY_PIXEL`] seen by an orbit of 4 frames.
fn heavy_orbit() -> String {
    ONE_HEAVY_PIXEL.replace(
        "[camera]\nposition = [0, 2, 1]\nlook_at = [0, 0, 0]\nfov = 60\n",
        "[camera]\nfov = 60\npath = { type = \"orbit\", center = [0, 0, 0], radius = 1, height = 2, frames = 4 }\n",
    )
}

/// The status of each task of a `--json` run's stdout, by frame.
fn statuses(stdout: &[u8]) -> Vec<(i64, String)> {
    String::from_utf8_lossy(stdout)
        .lines()
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            (
                v["frame"].as_i64().unwrap(),
                v["status"].as_str().unwrap().to_owned(),
            )
        })
        .collect()
}

#[test]
fn a_sequence_stopped_by_a_signal_keeps_its_frames_and_resume_finishes_it() {
    let sb = TempDir::new("signal-sequence");
    let scene = sb.write("s.toml", heavy_orbit());
    // Each frame is 4096 × 4096 shadow rays on one thread: a fraction of a second.
    let manifest = sb.join("manifest.jsonl");
    let manifest_arg = manifest.to_str().unwrap();
    let args = [
        "--spp",
        "4096",
        "--light-samples",
        "64",
        "-t",
        "1",
        "--resume",
        "--json",
        "--manifest",
        manifest_arg,
    ];
    let out = sb.join("run/f{frame}.png");
    let clean = sb.join("clean/f{frame}.png");
    for (signal, code) in [("INT", Some(130)), ("KILL", None)] {
        let _ = std::fs::remove_dir_all(sb.join("run"));
        let child = spawn_render(&scene, &out, &args);
        // Frame 1 is done when its record is there (renamed into place right after it).
        let second = sb.join("run/f1.meta.json");
        let start = Instant::now();
        while !second.exists() {
            assert!(
                start.elapsed() < Duration::from_secs(60),
                "frame 1 never came"
            );
            std::thread::sleep(Duration::from_millis(2));
        }
        send(&child, signal);
        let (got, stderr, _) = wait_at_most(child, Duration::from_secs(5), signal);
        assert_eq!(got, code, "SIG{signal}: {stderr}");
        if signal == "INT" {
            assert_interrupted(signal, &stderr);
            assert!(temporary_files(&sb.join("run")).is_empty());
        }
        // Frames 0 and 1 are done; the rest render now, none twice.
        let rerun = Command::new(env!("CARGO_BIN_EXE_penumbra"))
            .arg("render")
            .arg(&scene)
            .arg("-o")
            .arg(&out)
            .args(["--quiet"])
            .args(args)
            .output()
            .unwrap();
        assert!(rerun.status.success(), "{rerun:?}");
        let got = statuses(&rerun.stdout);
        let done: Vec<i64> = got
            .iter()
            .filter(|(_, s)| s == "skipped")
            .map(|(f, _)| *f)
            .collect();
        assert!(done.starts_with(&[0, 1]), "SIG{signal}: {got:?}");
        assert_eq!(
            got.iter().map(|(f, _)| *f).collect::<Vec<_>>(),
            [0, 1, 2, 3]
        );
        // The manifest of both runs: no frame rendered twice.
        let text = std::fs::read_to_string(&manifest).unwrap();
        let mut counts = [0; 4];
        for (f, status) in statuses(text.as_bytes()) {
            if status == "rendered" {
                counts[f as usize] += 1;
            }
        }
        assert!(
            counts.iter().all(|&n| n <= 1),
            "SIG{signal}: {counts:?}\n{text}"
        );
        std::fs::remove_file(&manifest).unwrap();
    }
    // Every frame is the one a run without interruption writes.
    let full = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(&clean)
        .args(["--quiet"])
        .args(args)
        .output()
        .unwrap();
    assert!(full.status.success());
    for f in 0..4 {
        let read = |dir: &str| std::fs::read(sb.join(dir).join(format!("f{f}.png"))).unwrap();
        assert_eq!(read("run"), read("clean"), "frame {f}");
    }
}
