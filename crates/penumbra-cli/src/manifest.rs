//! `--manifest FILE.jsonl`: one JSON line per task as it ends (task, camera, frame, seed,
//! seconds, peak memory, host, outputs, attempts, status and error), appended, so that the
//! runs of every shard and every `--resume` add up to the whole story.
//!
//! Each line is written with one `write` to a file opened for appending: lines of
//! processes sharing the file (shards on one machine) do not interleave.

use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::Path;

use serde_json::{json, Value};

use crate::failure::{invalid, runtime, Failure};
use crate::plan::Job;

/// How a task ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// Rendered and written.
    Rendered,
    /// Done before (`--resume`).
    Skipped,
    /// Failed on its last attempt.
    Failed,
}

impl Status {
    pub fn name(self) -> &'static str {
        match self {
            Status::Rendered => "rendered",
            Status::Skipped => "skipped",
            Status::Failed => "failed",
        }
    }
}

/// The manifest, or none without `--manifest`.
pub struct Manifest {
    file: Option<(File, String)>,
    host: String,
}

impl Manifest {
    /// Opens `path` for appending (making its folder); a manifest that cannot be written is
    /// the command line's mistake, found before any work.
    pub fn open(path: Option<&Path>) -> Result<Manifest, Failure> {
        let file = match path {
            None => None,
            Some(path) => {
                let name = path.display().to_string();
                let cannot = |e: std::io::Error| {
                    invalid(format!("--manifest {name}: cannot write the manifest: {e}"))
                };
                if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
                    std::fs::create_dir_all(dir).map_err(cannot)?;
                }
                let file = OpenOptions::new()
                    .append(true)
                    .create(true)
                    .open(path)
                    .map_err(cannot)?;
                Some((file, name))
            }
        };
        Ok(Manifest { file, host: host() })
    }

    /// Appends the line of `job`.
    pub fn write(
        &mut self,
        job: &Job,
        status: Status,
        seconds: f64,
        attempts: u32,
        outputs: &[String],
        error: Option<&str>,
    ) -> Result<(), Failure> {
        let Some((file, name)) = self.file.as_mut() else {
            return Ok(());
        };
        let line: Value = json!({
            "task": job.task,
            "camera": job.camera,
            "frame": job.frame,
            "seed": job.settings.seed,
            "seconds": seconds,
            "peak_memory_bytes": peak_memory(),
            "host": self.host,
            "outputs": outputs,
            "attempts": attempts,
            "status": status.name(),
            "error": error,
        });
        let text = line.to_string() + "\n";
        file.write_all(text.as_bytes())
            .and_then(|()| file.flush())
            .map_err(|e| runtime(format!("--manifest {name}: cannot write the manifest: {e}")))
    }
}

/// The machine's name: the kernel's, else `$HOSTNAME`, else "unknown".
fn host() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .map(|h| h.trim().to_owned())
        .filter(|h| !h.is_empty())
        .or_else(|| std::env::var("HOSTNAME").ok())
        .unwrap_or_else(|| "unknown".to_owned())
}

/// The process's peak resident memory so far in bytes (Linux's VmHWM); `None` elsewhere.
fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}
