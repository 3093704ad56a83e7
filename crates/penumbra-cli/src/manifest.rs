//! `--manifest FILE.jsonl`: one JSON line per task as it ends, appended (see
//! [`penumbra::products::manifest`], which writes it for the command line and Python).

use std::path::Path;

pub use penumbra::products::manifest::Status;
use penumbra::products::manifest::{self, ManifestLine};

use crate::failure::{invalid, runtime, Failure};
use crate::plan::Job;

/// The manifest, or none without `--manifest`.
pub struct Manifest {
    file: Option<manifest::Manifest>,
    host: String,
}

impl Manifest {
    /// Opens `path` for appending (making its folder); a manifest that cannot be written is
    /// the command line's mistake, found before any work.
    pub fn open(path: Option<&Path>) -> Result<Manifest, Failure> {
        let file = path
            .map(|p| manifest::Manifest::open(p).map_err(|e| invalid(format!("--manifest {e}"))))
            .transpose()?;
        Ok(Manifest {
            file,
            host: manifest::host_name(),
        })
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
        let Some(file) = self.file.as_mut() else {
            return Ok(());
        };
        let line = ManifestLine {
            task: job.task,
            camera: Some(job.camera.clone()),
            frame: job.frame,
            seed: job.settings.seed,
            seconds,
            peak_memory_bytes: manifest::peak_memory_bytes(),
            host: Some(self.host.clone()),
            outputs: outputs.to_vec(),
            attempts: Some(attempts),
            status,
            error: error.map(str::to_owned),
        };
        file.append(&line)
            .map_err(|e| runtime(format!("--manifest {e}")))
    }
}
