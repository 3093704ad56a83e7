//! The manifest (`--manifest FILE.jsonl`): one JSON line per task as it ends ([`ManifestLine`]:
//! task, camera, frame, seed, seconds, peak memory, host, outputs, attempts, status and
//! error), appended, so that the runs of every shard, every `--resume` and every Python batch
//! add up to the whole story.
//!
//! Each line is written with one `write` to a file opened for appending: lines of processes
//! sharing the file (shards on one machine) do not interleave.

use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::ProductError;

/// How a task ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Rendered and written.
    Rendered,
    /// Done before (`--resume`, or a Python batch's record that matches).
    Skipped,
    /// Failed on its last attempt.
    Failed,
}

impl Status {
    /// Its name in the manifest: `rendered`, `skipped` or `failed`.
    pub fn name(self) -> &'static str {
        match self {
            Status::Rendered => "rendered",
            Status::Skipped => "skipped",
            Status::Failed => "failed",
        }
    }
}

impl std::str::FromStr for Status {
    type Err = crate::UnknownName;

    fn from_str(name: &str) -> Result<Status, crate::UnknownName> {
        let all = [Status::Rendered, Status::Skipped, Status::Failed];
        crate::names::parse_name("status", name, &all, Status::name)
    }
}

/// One task's line (read from JSON by Python's batches, which hand their lines over as JSON:
/// every key, no other).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ManifestLine {
    /// Its place in the task list (a batch's view index), from 0.
    pub task: usize,
    /// The camera's name; `None` for an explicit camera.
    pub camera: Option<String>,
    /// The frame of a path camera.
    pub frame: Option<i64>,
    /// The seed.
    pub seed: u64,
    /// Wall time of the task in seconds.
    pub seconds: f64,
    /// Peak resident memory of the process that rendered it ([`peak_memory_bytes`]).
    pub peak_memory_bytes: Option<u64>,
    /// The machine that rendered it ([`host_name`]).
    pub host: Option<String>,
    /// The files written.
    pub outputs: Vec<String>,
    /// Attempts made (`None` where another system retries, such as Ray).
    pub attempts: Option<u32>,
    /// How it ended.
    pub status: Status,
    /// The failure, in one line.
    pub error: Option<String>,
}

/// A manifest file, open for appending.
#[derive(Debug)]
pub struct Manifest {
    file: File,
    path: PathBuf,
}

impl Manifest {
    /// Opens `path` for appending, making its folder.
    pub fn open(path: &Path) -> Result<Manifest, ProductError> {
        let cannot = |e: std::io::Error| {
            ProductError::io(path, format_args!("cannot write the manifest: {e}"))
        };
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(cannot)?;
        }
        let file = OpenOptions::new()
            .append(true)
            .create(true)
            .open(path)
            .map_err(cannot)?;
        Ok(Manifest {
            file,
            path: path.to_owned(),
        })
    }

    /// Appends `line`, with one `write`.
    pub fn append(&mut self, line: &ManifestLine) -> Result<(), ProductError> {
        let cannot = |e: &dyn std::fmt::Display| {
            ProductError::io(&self.path, format_args!("cannot write the manifest: {e}"))
        };
        let text = serde_json::to_string(line).map_err(|e| cannot(&e))? + "\n";
        self.file
            .write_all(text.as_bytes())
            .and_then(|()| self.file.flush())
            .map_err(|e| cannot(&e))
    }
}

/// The machine's name: the kernel's, else `$HOSTNAME`, else "unknown".
pub fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .map(|h| h.trim().to_owned())
        .filter(|h| !h.is_empty())
        .or_else(|| std::env::var("HOSTNAME").ok())
        .unwrap_or_else(|| "unknown".to_owned())
}

/// The process's peak resident memory so far in bytes (Linux's VmHWM); `None` elsewhere.
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_has_every_key_in_order() {
        let dir = std::env::temp_dir().join(format!("penumbra-manifest-{}", std::process::id()));
        let path = dir.join("sub/m.jsonl");
        let mut m = Manifest::open(&path).unwrap();
        let line = ManifestLine {
            task: 3,
            camera: Some("front".into()),
            frame: None,
            seed: 7,
            seconds: 0.5,
            peak_memory_bytes: Some(1024),
            host: Some("h".into()),
            outputs: vec!["a.png".into()],
            attempts: Some(1),
            status: Status::Rendered,
            error: None,
        };
        m.append(&line).unwrap();
        m.append(&ManifestLine {
            status: Status::Failed,
            error: Some("x".into()),
            ..line
        })
        .unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let first = r#"{"task":3,"camera":"front","frame":null,"seed":7,"seconds":0.5,"peak_memory_bytes":1024,"host":"h","outputs":["a.png"],"attempts":1,"status":"rendered","error":null}"#;
        assert_eq!(text.lines().next(), Some(first));
        assert!(text
            .lines()
            .nth(1)
            .unwrap()
            .ends_with(r#""status":"failed","error":"x"}"#));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
