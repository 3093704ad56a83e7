//! `--resume` and `--meta`: the record written beside each image (`out.png` →
//! `out.meta.json`) saying how it was made, the files written, the camera (K and pose) and
//! which object ids belong to which `[[objects]]` entry; and the test of whether a task is
//! done.
//!
//! A task is done when its image and every file its record lists are there, each a regular
//! file of the size and FNV-1a digest the record keeps for it (`digests`, beside `files`: an
//! image cut short or changed after its record was written is rendered again), and the
//! record's `settings` are exactly those the task would render with now: the scene's digest
//! (of its text, `--set` overrides and the files its build read: [`penumbra::SceneFile::digest`]),
//! penumbra's version, the camera (its pose to the bit), film,
//! region, sampler, samples, seed, shading, passes and output format. A record is removed
//! before its image is replaced and written after it, so that an interrupted run never
//! leaves a record beside an image it does not describe.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use penumbra::{leftovers, CameraPose, FileDigest, Scene, SceneFile, StagedFile, World};
use serde_json::{json, Value};

use crate::aov::Passes;
use crate::failure::{runtime, Failure};
use crate::output::Target;
use crate::plan::Job;

/// The largest record read back: far more than any record penumbra writes.
const MAX_RECORD_BYTES: u64 = 1 << 20;

/// Where the record of the image at `image` goes: its stem with `.meta.json`, beside the
/// `--aov` files (`out.depth.pfm`).
pub fn path_of(image: &Path) -> PathBuf {
    image.with_extension("meta.json")
}

/// What a task's image depends on, as its record keeps it.
pub fn settings(job: &Job, digest: &str, passes: Option<&Passes>, gamma: Option<f32>) -> Value {
    json!({
        "penumbra": env!("CARGO_PKG_VERSION"),
        "scene_digest": digest,
        "camera": job.camera,
        "frame": job.frame,
        // Debug formatting writes every f32 so that it reads back to the same bits.
        "render": format!("{:?}", job.settings),
        "region": job.region.map(|b| [b.x0, b.x1, b.y0, b.y1]),
        "aovs": format!("{passes:?}"),
        "gamma": gamma,
        "format": job.output.format.extension(),
    })
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

/// True when the job's image is there, made with exactly `settings`, whole (see the module's
/// docs).
pub fn done(job: &Job, settings: &Value) -> bool {
    finished(job, settings).is_some()
}

/// The files of the job's image (the image, then its pass files), when it is [`done`].
pub fn finished(job: &Job, settings: &Value) -> Option<Vec<PathBuf>> {
    let Target::File(image) = &job.output.target else {
        return None;
    };
    let record = read(&path_of(image)).ok()?;
    let files = record["files"].as_array()?;
    let digests = record["digests"].as_array()?;
    let image_listed = files.first().and_then(Value::as_str) == Some(&image.display().to_string());
    if record.get("settings") != Some(settings) || !image_listed || files.len() != digests.len() {
        return None;
    }
    // Read last: every byte of every file.
    let whole = files.iter().zip(digests).all(|(f, d)| {
        f.as_str()
            .is_some_and(|f| FileDigest::of_file(Path::new(f)).is_ok_and(|got| kept(&got) == *d))
    });
    whole.then(|| {
        files
            .iter()
            .filter_map(Value::as_str)
            .map(PathBuf::from)
            .collect()
    })
}

/// A file's size and digest as a record keeps them.
fn kept(d: &FileDigest) -> Value {
    json!({"bytes": d.bytes, "fnv1a64": d.hex()})
}

/// The record at `path`, when it is a regular file of at most [`MAX_RECORD_BYTES`] holding
/// JSON: a named pipe, a device or a folder there is never opened (opening a pipe would wait
/// for a writer forever).
fn read(path: &Path) -> std::io::Result<Value> {
    use std::io::{Error, ErrorKind, Read};
    if !std::fs::metadata(path)?.is_file() {
        return Err(Error::new(ErrorKind::InvalidInput, "not a regular file"));
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(MAX_RECORD_BYTES)
        .read_to_end(&mut bytes)?;
    serde_json::from_slice(&bytes).map_err(|e| Error::new(ErrorKind::InvalidData, e))
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
    let path = path_of(image);
    match std::fs::remove_file(&path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(runtime(format!(
            "{}: cannot remove the old record: {e}",
            path.display()
        ))),
        _ => Ok(()),
    }
}

/// Each `[[objects]]` entry: its key, its type (and file) and the object ids it added, as
/// `[first, end)` (one id, or one per copy of `instances`): what `object_id` values name.
fn objects(file: &SceneFile, scene: &Scene) -> Vec<Value> {
    file.desc
        .objects
        .iter()
        .zip(&scene.objects)
        .enumerate()
        .map(|(i, (o, ids))| {
            json!({
                "key": format!("objects[{i}]"),
                "type": o.kind(),
                "ids": [ids.start, ids.end],
            })
        })
        .collect()
}

/// The record of a finished job, staged: its settings, the files written (`files`, staged
/// but not yet in place: the image, then its pass files) with their sizes and digests, and its
/// camera.
pub fn stage(
    job: &Job,
    settings: Value,
    files: &[&StagedFile],
    file: &SceneFile,
    scene: &Scene,
) -> Result<StagedFile, Failure> {
    let Target::File(image) = &job.output.target else {
        return Err(runtime("a record needs an image file"));
    };
    let digests = files
        .iter()
        .map(|f| f.digest().map(|d| kept(&d)))
        .collect::<Result<Vec<_>, _>>()
        .map_err(runtime)?;
    let pose = pose_of(job, &scene.world);
    let record = json!({
        "settings": settings,
        "image": image.display().to_string(),
        "files": files.iter().map(|f| f.path().display().to_string()).collect::<Vec<_>>(),
        "digests": digests,
        "width": job.region.map_or(job.settings.width, |b| b.x1.saturating_sub(b.x0)),
        "height": job.region.map_or(job.settings.height, |b| b.y1.saturating_sub(b.y0)),
        "K": pose.map(|p| p.k),
        "camera_to_world": pose.map(|p| p.camera_to_world),
        "camera_to_world_opengl": pose.map(|p| p.camera_to_world_opengl),
        "world_to_camera": pose.map(|p| p.world_to_camera),
        "objects": objects(file, scene),
    });
    let text = serde_json::to_string(&record).map_err(runtime)? + "\n";
    StagedFile::write_bytes(&path_of(image), text.as_bytes()).map_err(runtime)
}
