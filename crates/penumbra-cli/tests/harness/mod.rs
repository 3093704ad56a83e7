//! Running the `penumbra` binary from the integration tests added with the command line of
//! issue 11 (`set.rs`, `cameras.rs`, `habits.rs`, `check.rs`): run it with arguments and
//! optional stdin, and read its exit code and output. (`cli.rs` keeps its own helpers.)

#![allow(dead_code)]

use std::ffi::OsStr;
use std::io::Write;
use std::path::Path;
use std::process::{Command, Stdio};

/// What a run of the binary produced.
#[derive(Debug)]
pub struct Run {
    /// Exit code; `None` when killed by a signal.
    pub code: Option<i32>,
    pub stdout: Vec<u8>,
    pub stderr: String,
}

impl Run {
    /// stdout as text.
    pub fn out(&self) -> String {
        String::from_utf8_lossy(&self.stdout).into_owned()
    }
}

/// Runs `penumbra ARGS` in `cwd` with `stdin` (nothing when `None`).
pub fn run_with<S: AsRef<OsStr>>(
    cwd: &Path,
    args: impl IntoIterator<Item = S>,
    stdin: Option<&[u8]>,
) -> Run {
    let mut child = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(args)
        .current_dir(cwd)
        .env_remove("RUST_BACKTRACE")
        .stdin(if stdin.is_some() {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run the penumbra binary");
    if let Some(bytes) = stdin {
        // A binary that stops reading early closes the pipe; that is its answer, not ours.
        let _ = child.stdin.take().unwrap().write_all(bytes);
    }
    let out = child.wait_with_output().expect("wait for penumbra");
    Run {
        code: out.status.code(),
        stdout: out.stdout,
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// Runs `penumbra ARGS` in `cwd`.
pub fn run_in<S: AsRef<OsStr>>(cwd: &Path, args: impl IntoIterator<Item = S>) -> Run {
    run_with(cwd, args, None)
}

/// Asserts a successful run and returns it.
pub fn ok(r: Run) -> Run {
    assert_eq!(r.code, Some(0), "expected success: {r:#?}");
    r
}

/// The single `error:` line of a failed run, after checking the exit code and that there is
/// exactly one message and no panic.
pub fn error_line(r: &Run, code: i32) -> String {
    assert_eq!(r.code, Some(code), "exit code: {r:#?}");
    assert!(!r.stderr.contains("panicked"), "panic: {}", r.stderr);
    let errors: Vec<&str> = r
        .stderr
        .lines()
        .filter(|l| l.starts_with("error:"))
        .collect();
    assert_eq!(errors.len(), 1, "want one error line: {}", r.stderr);
    errors[0].to_owned()
}

/// The image at `path`, decoded.
pub fn image(path: &Path) -> image::RgbImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8()
}

/// A PFM's width, height, channels and values, rows top to bottom.
pub fn read_pfm(path: &Path) -> (usize, usize, usize, Vec<f32>) {
    let bytes = std::fs::read(path).unwrap();
    let mut fields = Vec::new();
    let mut start = 0;
    while fields.len() < 4 {
        let end = start
            + bytes[start..]
                .iter()
                .position(|b| b.is_ascii_whitespace())
                .unwrap();
        fields.push(String::from_utf8(bytes[start..end].to_vec()).unwrap());
        start = end + 1;
    }
    let channels = if fields[0] == "Pf" { 1 } else { 3 };
    assert!(["Pf", "PF"].contains(&fields[0].as_str()), "{fields:?}");
    assert_eq!(fields[3], "-1.0", "little-endian");
    let (w, h): (usize, usize) = (fields[1].parse().unwrap(), fields[2].parse().unwrap());
    let floats: Vec<f32> = bytes[start..]
        .chunks(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(floats.len(), w * h * channels);
    let rows: Vec<&[f32]> = floats.chunks(w * channels).rev().collect();
    (w, h, channels, rows.concat())
}
