//! `--poses FILE.json`: every task's camera as computer vision reads it, in penumbra's layout
//! or NeRF's `transforms.json` (see [`penumbra::products::poses`], which writes both), written
//! before rendering begins, for the whole task list (every shard writes the same file).

use std::path::Path;

use penumbra::products::poses::{self, PoseFrame, PosesFormat};
use penumbra::products::ProductError;
use penumbra::Scene;

use crate::failure::{invalid, runtime, Failure};
use crate::plan::Job;
use crate::record::{camera_of, pose_of, size};
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
    let named_json = json.is_some_and(|e| e.eq_ignore_ascii_case("json"));
    if format != "colmap" && !named_json {
        return Err(invalid(format!(
            "--poses {}: the poses file is JSON: name it .json",
            path.display()
        )));
    }
    if format == "colmap" && named_json {
        return Err(invalid(format!(
            "--poses {}: COLMAP's model is a folder (cameras.txt, images.txt, points3D.txt): \
             name the folder, such as out/sparse/0",
            path.display()
        )));
    }
    let name = format;
    let format = match format {
        "nerf" => PosesFormat::Nerf,
        "colmap" => PosesFormat::Colmap,
        _ => PosesFormat::Penumbra,
    };
    let frames: Vec<PoseFrame> = jobs
        .iter()
        .filter_map(|job| {
            let camera = camera_of(job, &scene.world)?;
            let pose = pose_of(job, &scene.world)?;
            let file = job.output.display();
            Some(PoseFrame::new(
                job.frame,
                &job.camera,
                &file,
                &camera,
                pose,
                size(job),
            ))
        })
        .collect();
    interrupt.check()?;
    poses::write(path, format, &frames).map_err(|e| match e {
        // "--poses out/p.json: cannot make its folder: ..."
        ProductError::Io { .. } => runtime(format!("--poses {e}")),
        // A camera the layout cannot hold: the input's fault, found before rendering.
        ProductError::Invalid { .. } => invalid(format!("--poses-format {name}: {e}")),
        e => runtime(format!("--poses: {e}")),
    })
}
