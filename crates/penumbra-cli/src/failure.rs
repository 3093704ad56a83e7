//! How a command ends: a [`Failure`] carries the exit code and the one-line message, and
//! [`say`] / [`note`] write to stdout and stderr without ever panicking.

use std::io::Write;

/// An error and the exit code it ends with.
pub struct Failure {
    /// 1 runtime failure, 2 invalid input or usage, 128 + a signal's number when one stopped the run.
    pub code: u8,
    /// The message after `error: `; empty for none.
    pub message: String,
}

/// Invalid input or usage: exit code 2.
pub fn invalid(e: impl std::fmt::Display) -> Failure {
    Failure {
        code: 2,
        message: e.to_string(),
    }
}

/// A runtime failure: exit code 1.
pub fn runtime(e: impl std::fmt::Display) -> Failure {
    Failure {
        code: 1,
        message: e.to_string(),
    }
}

/// The end of a command whose reader has gone: exit code 0 and nothing to say, as a listing
/// piped into `head -1` ends.
fn reader_gone() -> Failure {
    Failure {
        code: 0,
        message: String::new(),
    }
}

/// Writes `text` and a newline to stdout, for a line of what the command exists to print (a
/// listing, a summary). When the reader has gone (a closed pipe: `penumbra render --dry-run |
/// head -1`) the command stops quietly with exit code 0; a full device is a runtime failure;
/// never a panic (which `println!` would be).
pub fn say(text: &str) -> Result<(), Failure> {
    let mut out = std::io::stdout().lock();
    writeln!(out, "{text}")
        .and_then(|()| out.flush())
        .map_err(|e| match e.kind() {
            std::io::ErrorKind::BrokenPipe => reader_gone(),
            _ => runtime(format!("cannot write to standard output: {e}")),
        })
}

/// [`say`] for a line beside what the command makes (a render's `--json` line per image,
/// whose product is the image): when the reader has gone, the work goes on unreported.
pub fn say_beside(text: &str) -> Result<(), Failure> {
    match say(text) {
        Err(f) if f.code == 0 => Ok(()),
        r => r,
    }
}

/// Writes `text` and a newline to stderr, if it can: with stderr closed or full there is
/// nowhere left to report to, and the exit code still tells what happened.
pub fn note(text: &str) {
    let _ = writeln!(std::io::stderr().lock(), "{text}");
}
