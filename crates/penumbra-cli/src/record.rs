//! `--resume` and `--meta`: the record beside each image (`out.png` → `out.meta.json`, see
//! [`penumbra::products::record`], which writes it and holds the rule of whether a task is
//! done), from a job: its settings (the scene's digest, penumbra's version, the camera, film,
//! region, sampler, samples, seed, shading, passes, gamma and output format) and its camera.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use penumbra::products::record::{self, Record};
use penumbra::products::{RecordSettings, RenderRecord};
use penumbra::{leftovers, CameraPose, Scene, SceneFile, StagedFile, World};

use crate::aov::Passes;
use crate::failure::{runtime, Failure};
use crate::output::Target;
use crate::plan::Job;

pub use record::path_of;

/// What a task's image depends on, as its record keeps it.
pub fn settings(
    job: &Job,
    digest: &str,
    passes: Option<&Passes>,
    gamma: Option<f32>,
) -> RecordSettings {
    RecordSettings {
        penumbra: env!("CARGO_PKG_VERSION").to_owned(),
        scene_digest: digest.to_owned(),
        camera: Some(job.camera.clone()),
        frame: job.frame,
        render: RenderRecord::of(&job.settings),
        region: job.region.map(|b| [b.x0, b.x1, b.y0, b.y1]),
        aovs: passes.map_or_else(Vec::new, |p| {
            p.0.iter().map(|a| a.name().to_owned()).collect()
        }),
        gamma,
        format: job.output.format.extension().to_owned(),
    }
}

/// The camera of a job, for its pose.
pub fn camera_of(job: &Job, world: &World) -> Option<penumbra::Camera> {
    job.settings.view.camera(world).ok()
}

/// The pose of a job's image (of its region, when it has one).
pub fn pose_of(job: &Job, world: &World) -> Option<CameraPose> {
    let offset = job.region.map_or((0, 0), |b| (b.x0, b.y0));
    camera_of(job, world)
        .map(|c| CameraPose::new(&c, job.settings.width, job.settings.height, offset))
}

/// The image size of a job (its region's, when it has one).
pub fn size(job: &Job) -> (u32, u32) {
    match job.region {
        Some(b) => (b.x1.saturating_sub(b.x0), b.y1.saturating_sub(b.y0)),
        None => (job.settings.width, job.settings.height),
    }
}

/// True when the job's image is there, made with exactly `settings`, whole.
pub fn done(job: &Job, settings: &RecordSettings) -> bool {
    finished(job, settings).is_some()
}

/// The files of the job's image (the image, then its pass files), when it is [`done`].
pub fn finished(job: &Job, settings: &RecordSettings) -> Option<Vec<PathBuf>> {
    match &job.output.target {
        Target::File(image) => record::finished(image, settings),
        Target::Stdout => None,
    }
}

/// Removes the temporary files a killed run left beside the files of finished tasks (see
/// [`penumbra::leftovers`]): each folder is listed once, when a task in it first finishes.
#[derive(Default)]
pub struct Tidy {
    folders: HashMap<PathBuf, HashMap<String, Vec<PathBuf>>>,
}

impl Tidy {
    /// Removes what was left of earlier attempts at `files` (the files of one finished task).
    pub fn finished(&mut self, files: &[PathBuf]) {
        for file in files {
            let (Some(folder), Some(name)) = (file.parent(), file.file_name()) else {
                continue;
            };
            let left = self
                .folders
                .entry(folder.to_owned())
                .or_insert_with(|| leftovers(folder));
            for tmp in left.remove(&*name.to_string_lossy()).unwrap_or_default() {
                let _ = std::fs::remove_file(tmp);
            }
        }
    }
}

/// Removes the record of `image`, if any, before the image is replaced.
pub fn remove(image: &Path) -> Result<(), Failure> {
    record::remove(image).map_err(runtime)
}

/// The record of a finished job, staged: its settings, the files written (`files`, staged
/// but not yet in place: the image, then its pass files) with their sizes and digests, and its
/// camera.
pub fn stage(
    job: &Job,
    settings: RecordSettings,
    files: &[&StagedFile],
    file: &SceneFile,
    scene: &Scene,
) -> Result<StagedFile, Failure> {
    let Target::File(image) = &job.output.target else {
        return Err(runtime("a record needs an image file"));
    };
    let pose = pose_of(job, &scene.world);
    let objects = record::objects(file, &scene.objects);
    let value = Record::new(settings, image, size(job), pose, objects);
    record::stage(value, files).map_err(runtime)
}
