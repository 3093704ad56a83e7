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

/// Writes `text` and a newline to stdout. A closed pipe or a full device is a runtime
/// failure, never a panic (which `println!` would be).
pub fn say(text: &str) -> Result<(), Failure> {
    let mut out = std::io::stdout().lock();
    writeln!(out, "{text}")
        .and_then(|()| out.flush())
        .map_err(|e| runtime(format!("cannot write to standard output: {e}")))
}

/// Writes `text` and a newline to stderr, if it can: with stderr closed or full there is
/// nowhere left to report to, and the exit code still tells what happened.
pub fn note(text: &str) {
    let _ = writeln!(std::io::stderr().lock(), "{text}");
}
