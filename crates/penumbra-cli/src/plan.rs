//! The run's plan: one [`Job`] per task (camera × frame, see `sequence`), each with its
//! settings, region and output checked before any work.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use penumbra::{
    ImageError, ModelFormat, PixelBounds, RenderSettings, Scene, SceneFile, SettingsError, View,
    World,
};

use crate::args::RenderArgs;
use crate::cameras;
use crate::failure::{invalid, Failure};
use crate::input::is_stdin;
use crate::output::{
    check_inside, expand, names_camera, names_frame, normalized, scene_stem, Fields, Output, Target,
};
use crate::sequence::{self, Task};
use crate::settings::{flag_of, patch, region};

/// One render of the run.
pub struct Job {
    /// Its place in the run's task list (before `--shard`), from 0.
    pub task: usize,
    /// The camera's name, as `{camera}` and the summaries give it.
    pub camera: String,
    /// The frame of a path camera.
    pub frame: Option<i64>,
    pub settings: RenderSettings,
    pub region: Option<PixelBounds>,
    pub output: Output,
}

/// Every render of the run (for all shards: `--shard` picks from these), each checked
/// (settings, output name and format, image size) before anything is rendered or written.
pub fn plan(args: &RenderArgs, file: &SceneFile, scene: &Scene) -> Result<Vec<Job>, Failure> {
    let views = cameras::select(args.camera.as_deref(), &scene.world)?;
    let tasks = sequence::tasks(&views, args.frames, scene)?;
    let several_cameras = views.len() > 1;
    let several_frames = tasks.iter().filter(|t| t.frame.is_some()).count() > 1;
    let (pattern, from) = output_pattern(args, scene, several_cameras, several_frames)?;
    let text = pattern.to_str();
    if several_cameras && text.is_none_or(|p| !names_camera(p)) {
        return Err(invalid(format!(
            "{from}: {} cameras need {{camera}} in the output name, such as out/{{scene}}_{{camera}}.png",
            views.len()
        )));
    }
    if tasks.len() > 1 && !several_cameras && text.is_none_or(|p| !names_frame(p)) {
        return Err(invalid(format!(
            "{from}: {} frames need {{frame}} in the output name, such as out/{{camera}}_{{frame:04}}.png",
            tasks.len()
        )));
    }
    let stem = scene_stem(&args.scene, is_stdin(&args.scene));
    let mut jobs: Vec<Job> = Vec::with_capacity(tasks.len());
    let mut targets: HashSet<Target> = HashSet::with_capacity(tasks.len());
    for (i, task) in tasks.into_iter().enumerate() {
        let job = job(args, file, scene, &pattern, from, &stem, i, task)?;
        // Camera names that differ only in a path separator (made `_`) meet here, and so do
        // frames of a pattern without {frame} beside {camera}, and names that a `..` after a
        // field makes one (`f{frame}/../x.pfm`).
        let (target, name) = match &job.output.target {
            Target::File(path) => (
                Target::File(normalized(path)),
                normalized(path).display().to_string(),
            ),
            Target::Stdout => (Target::Stdout, "-".to_owned()),
        };
        if !targets.insert(target) {
            return Err(invalid(format!(
                "{from} {}: two renders would write {name} (use {{camera}} and {{frame}} in \
                 it, and no `..` after them)",
                pattern.display(),
            )));
        }
        jobs.push(job);
    }
    Ok(jobs)
}

/// The checked job of one task.
#[allow(clippy::too_many_arguments)]
fn job(
    args: &RenderArgs,
    file: &SceneFile,
    scene: &Scene,
    pattern: &Path,
    from: &str,
    stem: &str,
    i: usize,
    task: Task,
) -> Result<Job, Failure> {
    // Settings from flags are checked before anything is written or rendered.
    let bad = |e: SettingsError| invalid(format!("{}: {e}", flag_of(&e)));
    let mut settings = patch(args, &scene.settings, task.camera.as_deref())
        .apply(&scene.settings, file.samples())
        .map_err(bad)?;
    if let Some(camera) = task.view {
        settings.view = View::Camera(camera);
    }
    settings.check(&scene.world).map_err(bad)?;
    let camera = match &task.camera {
        Some(name) => name.clone(),
        None => camera_name(&settings.view, &scene.world).to_owned(),
    };
    let name = match pattern.to_str() {
        Some(p) => {
            let fields = Fields {
                camera: &camera,
                scene: stem,
                spp: settings.spp,
                seed: settings.seed,
                frame: task.frame,
            };
            let name =
                PathBuf::from(expand(p, &fields).map_err(|e| invalid(format!("{from}: {e}")))?);
            check_inside(p, &name).map_err(|e| invalid(format!("{from}: {e}")))?;
            name
        }
        // Not UTF-8: no fields to expand.
        None => pattern.to_owned(),
    };
    let output = Output::new(name, args.format)?;
    if settings.alpha && !output.format.has_alpha() {
        let path = PathBuf::from(output.display());
        let format = output.format.name();
        return Err(invalid(ImageError::NoAlpha { path, format }));
    }
    if args.aov.is_some() && output.target == Target::Stdout {
        return Err(invalid(
            "--aov: passes are written beside an image file, not to standard output (-o -)",
        ));
    }
    if (args.resume || args.meta) && output.target == Target::Stdout {
        let flag = if args.resume { "--resume" } else { "--meta" };
        return Err(invalid(format!(
            "{flag}: a record is written beside an image file, not standard output (-o -)"
        )));
    }
    let region = region(args, &settings);
    let (w, h) = match region {
        Some(b) => (b.x1.saturating_sub(b.x0), b.y1.saturating_sub(b.y0)),
        None => (settings.width, settings.height),
    };
    output.check_size(w, h)?;
    Ok(Job {
        task: i,
        camera,
        frame: task.frame,
        settings,
        region,
        output,
    })
}

/// The output name before expansion and the flag or key it comes from: `-o`, else
/// `film.output`, else `<scene stem>.png` beside a scene file, as Mitsuba writes it, or in the
/// current folder for a bare model (whose folder, an asset's, may be read-only or shared), with
/// `_{camera}` for several cameras and `_{frame:04}` for several frames.
fn output_pattern(
    args: &RenderArgs,
    scene: &Scene,
    several_cameras: bool,
    several_frames: bool,
) -> Result<(PathBuf, &'static str), Failure> {
    if let Some(o) = &args.output {
        return Ok((o.clone(), "-o"));
    }
    if let Some(o) = &scene.output {
        return Ok((o.clone(), "film.output"));
    }
    if is_stdin(&args.scene) {
        return Err(invalid(
            "-o: a scene read from standard input needs -o (or film.output)",
        ));
    }
    let stem = args.scene.file_stem().unwrap_or_default();
    let mut name = stem.to_owned();
    if several_cameras {
        name.push("_{camera}");
    }
    if several_frames {
        name.push("_{frame:04}");
    }
    name.push(".png");
    if ModelFormat::from_path(&args.scene).is_some() {
        return Ok((PathBuf::from(name), "-o"));
    }
    Ok((args.scene.with_file_name(name), "-o"))
}

/// The camera's name for `{camera}`.
pub fn camera_name<'a>(view: &'a View, world: &'a World) -> &'a str {
    match view {
        View::Named(n) => n,
        View::First => world.cameras().first().map_or("camera", |(n, _)| n),
        View::Camera(_) => "camera",
    }
}
