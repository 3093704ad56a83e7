//! `--poses FILE.json`: every task's camera as computer vision reads it (see
//! `penumbra::CameraPose` and docs/spec.md, "Poses and intrinsics"), written before rendering
//! begins, for the whole task list (every shard writes the same file).
//!
//! - `penumbra` (the default): `{"frames": [...]}`, per image its `frame`, `camera`, `file`,
//!   `width`, `height`, `fov` (vertical, degrees), `K` (OpenCV: pixel centres at integer
//!   coordinates), `camera_to_world` (OpenCV axes), `camera_to_world_opengl` and
//!   `world_to_camera`, plus the camera's `position`, `look_at` and `up`;
//! - `nerf`: a `transforms.json` as instant-ngp and nerfstudio read it: `camera_model`
//!   "OPENCV", `fl_x`, `fl_y`, `cx`, `cy`, `w`, `h` (NeRF's pixel centres at +½, so a centred
//!   camera has cx = W/2), `camera_angle_x`/`_y`, and per frame `file_path` (relative to the
//!   file's folder) and `transform_matrix` (camera to world, OpenGL axes), with the
//!   intrinsics repeated per frame for paths whose fov changes.

use std::path::{Path, PathBuf};

use penumbra::{CameraPose, Scene, StagedFile};
use serde_json::{json, Value};

use crate::failure::{invalid, runtime, Failure};
use crate::output;
use crate::plan::Job;
use crate::record::{camera_of, pose_of};
use crate::signals::Interrupt;

/// Writes the poses of `jobs` to `path` in `format` (`penumbra` or `nerf`), atomically.
pub fn write(
    path: &Path,
    format: &str,
    jobs: &[Job],
    scene: &Scene,
    interrupt: &Interrupt,
) -> Result<(), Failure> {
    let json = path.extension().and_then(|e| e.to_str());
    if !json.is_some_and(|e| e.eq_ignore_ascii_case("json")) {
        return Err(invalid(format!(
            "--poses {}: the poses file is JSON: name it .json",
            path.display()
        )));
    }
    let value = match format {
        "nerf" => nerf(path, jobs, scene),
        _ => penumbra_poses(jobs, scene),
    };
    let text = serde_json::to_string_pretty(&value).map_err(runtime)? + "\n";
    if let Some(dir) = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty() && !d.is_dir())
    {
        std::fs::create_dir_all(dir).map_err(|e| {
            runtime(format!(
                "--poses {}: cannot make its folder: {e}",
                path.display()
            ))
        })?;
    }
    let staged = StagedFile::write_bytes(path, text.as_bytes())
        .map_err(|e| runtime(format!("--poses: {e}")))?;
    output::commit(vec![staged], interrupt)
}

/// The image size of a job (its region's, when it has one).
fn size(job: &Job) -> (u32, u32) {
    match job.region {
        Some(b) => (b.x1.saturating_sub(b.x0), b.y1.saturating_sub(b.y0)),
        None => (job.settings.width, job.settings.height),
    }
}

fn penumbra_poses(jobs: &[Job], scene: &Scene) -> Value {
    let frames: Vec<Value> = jobs
        .iter()
        .filter_map(|job| {
            let camera = camera_of(job, &scene.world)?;
            let pose = pose_of(job, &scene.world)?;
            let (w, h) = size(job);
            Some(json!({
                "frame": job.frame,
                "camera": job.camera,
                "file": job.output.display(),
                "width": w,
                "height": h,
                "fov": camera.fov_y_deg(),
                "K": pose.k,
                "camera_to_world": pose.camera_to_world,
                "camera_to_world_opengl": pose.camera_to_world_opengl,
                "world_to_camera": pose.world_to_camera,
                "position": camera.position().to_array(),
                "look_at": camera.look_at().to_array(),
                "up": camera.up().to_array(),
            }))
        })
        .collect();
    json!({ "frames": frames })
}

/// NeRF's intrinsics of one image: pixel centres at +½, so cx and cy are K's plus ½.
fn nerf_intrinsics(pose: &CameraPose, (w, h): (u32, u32)) -> serde_json::Map<String, Value> {
    let (fx, fy) = (pose.k[0][0], pose.k[1][1]);
    let mut m = serde_json::Map::new();
    m.insert("fl_x".into(), json!(fx));
    m.insert("fl_y".into(), json!(fy));
    m.insert("cx".into(), json!(pose.k[0][2] + 0.5));
    m.insert("cy".into(), json!(pose.k[1][2] + 0.5));
    m.insert("w".into(), json!(w));
    m.insert("h".into(), json!(h));
    m.insert(
        "camera_angle_x".into(),
        json!(2.0 * (f64::from(w) / (2.0 * fx)).atan()),
    );
    m.insert(
        "camera_angle_y".into(),
        json!(2.0 * (f64::from(h) / (2.0 * fy)).atan()),
    );
    m
}

fn nerf(path: &Path, jobs: &[Job], scene: &Scene) -> Value {
    let folder = absolute(path.parent().unwrap_or(Path::new("")));
    let mut top = serde_json::Map::new();
    top.insert("camera_model".into(), json!("OPENCV"));
    let mut frames = Vec::new();
    for job in jobs {
        let Some(pose) = pose_of(job, &scene.world) else {
            continue;
        };
        let intrinsics = nerf_intrinsics(&pose, size(job));
        if frames.is_empty() {
            top.extend(intrinsics.clone());
            for k in ["k1", "k2", "p1", "p2"] {
                top.insert(k.into(), json!(0.0));
            }
        }
        let file = absolute(&PathBuf::from(job.output.display()));
        let file_path = file
            .strip_prefix(&folder)
            .map_or(file.clone(), Path::to_path_buf);
        let mut frame = serde_json::Map::new();
        frame.insert("file_path".into(), json!(file_path.display().to_string()));
        frame.insert(
            "transform_matrix".into(),
            json!(pose.camera_to_world_opengl),
        );
        frame.extend(intrinsics);
        frame.insert("camera".into(), json!(job.camera));
        frame.insert("frame".into(), json!(job.frame));
        frames.push(Value::Object(frame));
    }
    top.insert("frames".into(), Value::Array(frames));
    Value::Object(top)
}

/// `path` from the current folder, without `.` parts.
fn absolute(path: &Path) -> PathBuf {
    let joined = std::env::current_dir()
        .map(|d| d.join(path))
        .unwrap_or_else(|_| path.to_owned());
    joined
        .components()
        .filter(|c| !matches!(c, std::path::Component::CurDir))
        .collect()
}
