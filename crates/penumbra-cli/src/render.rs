//! `penumbra render`: load and build the scene once, plan one render per task (camera ×
//! frame; settings, region and output, all checked before any work; see `plan`), write the
//! poses, then render, write and report each task of this shard (skipping, with `--resume`,
//! those done before).

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use penumbra::{
    AovPixel, Film, OutputFormat, Pass, PixelBounds, RenderError, RenderOptions, Rgb, Scene,
    StagedFile, MAX_THREADS,
};

use crate::aov::{self, Passes};
use crate::args::RenderArgs;
use crate::display::Preview;
use crate::failure::{invalid, note, runtime, say, Failure};
use crate::input::{self, is_stdin};
use crate::output::{self, Target};
use crate::plan::{self, Job};
use crate::settings::flag_of;
use crate::signals::Interrupt;
use crate::summary::Report;
use crate::{poses, record};

pub fn run(args: &RenderArgs) -> Result<(), Failure> {
    let interrupt = Interrupt::install();
    if args.threads > MAX_THREADS {
        return Err(invalid(format!(
            "--threads: at most {MAX_THREADS} worker threads, not {}",
            args.threads
        )));
    }
    if args.json && args.output.as_deref() == Some(Path::new("-")) {
        return Err(invalid(
            "--json: standard output carries the image with -o -; drop --json",
        ));
    }
    let load_start = Instant::now();
    let file = input::load(&args.scene, &args.set, input::Reader::Render)?;
    let file_time = load_start.elapsed();
    let scene = file.build(args.threads).map_err(invalid)?;
    // The scene file, then its meshes and textures: everything of loading but the BVH.
    let parse_time = file_time + scene.load_time;
    let all = plan::plan(args, &file, &scene)?;
    if let Some(path) = &args.poses {
        // From here on files are written: a signal stops the run between two writes.
        interrupt.defer();
        poses::write(path, &args.poses_format, &all, &scene, &interrupt)?;
    }
    let count = all.len();
    let jobs: Vec<Job> = match args.shard {
        Some(shard) => all.into_iter().filter(|j| shard.takes(j.task)).collect(),
        None => all,
    };
    let digest = (args.resume || args.meta).then(|| record::digest(file.text(), &args.set));
    let load_time = load_start.elapsed();
    interrupt.check()?;
    let mut preview = args
        .display_server
        .as_deref()
        .and_then(|server| Preview::connect(server, note));

    for job in &jobs {
        interrupt.check()?;
        let recorded = digest
            .as_deref()
            .map(|d| record::settings(job, d, args.aov.as_ref(), scene.gamma));
        if let Some(settings) = recorded.as_ref().filter(|_| args.resume) {
            if record::done(job, settings) {
                skipped(args, job, count)?;
                continue;
            }
        }
        job.output.make_folder()?;
        if let Some(p) = preview.as_mut() {
            let passes = args.aov.clone().unwrap_or(Passes(Vec::new()));
            p.begin(
                &job.output.display(),
                job.settings.width,
                job.settings.height,
                &passes,
            );
        }
        // With --progressive, the image of the last finished pass: what Ctrl-C writes.
        let last_pass: Mutex<Option<(u32, Film)>> = Mutex::new(None);
        let keep = |pass: &Pass| {
            let mut last = last_pass.lock().unwrap_or_else(|e| e.into_inner());
            *last = Some((pass.samples, pass.film.clone()));
        };
        let show = |tile: &PixelBounds, pixels: &[Rgb], aovs: &[AovPixel]| {
            if let Some(p) = preview.as_ref() {
                p.tile(tile, pixels, aovs);
            }
        };
        let options = RenderOptions {
            threads: args.threads,
            region: job.region,
            cancel: Some(interrupt.flag()),
            progress: None,
            tiles: preview.is_some().then_some(&show as _),
            passes: args.progressive.then_some(&keep as _),
        };
        interrupt.defer();
        let (film, aovs, stats) = with_progress(args.quiet, |progress| {
            let options = RenderOptions {
                progress: Some(progress),
                ..options
            };
            if args.aov.is_some() {
                penumbra::render_with_aovs(&scene.world, &job.settings, &options)
                    .map(|(film, aovs, stats)| (film, Some(aovs), stats))
            } else {
                penumbra::render(&scene.world, &job.settings, &options)
                    .map(|(film, stats)| (film, None, stats))
            }
        })
        .map_err(|e| match e {
            RenderError::Cancelled => {
                let last = last_pass.lock().unwrap_or_else(|e| e.into_inner()).take();
                match last {
                    Some((samples, film)) => {
                        write_last_pass(job, &film, samples, &scene, &interrupt)
                    }
                    None => interrupt.failure(),
                }
            }
            e @ RenderError::BadRegion { .. } => invalid(format!("{}: {e}", region_flag(args))),
            RenderError::Settings(e) => invalid(format!("{}: {e}", flag_of(&e))),
            e => runtime(e),
        })?;
        interrupt.check()?;
        // With --resume, the old record goes before the image is replaced, and the new one is
        // renamed into place right after it (see `record`).
        let mut record = match (recorded, &job.output.target) {
            (Some(settings), Target::File(image)) => {
                record::remove(image)?;
                Some((settings, image))
            }
            _ => None,
        };
        let mut stage_record = |aov_files: &[PathBuf]| -> Result<Vec<StagedFile>, Failure> {
            let Some((settings, image)) = record.take() else {
                return Ok(Vec::new());
            };
            let mut files = vec![image.clone()];
            files.extend(aov_files.iter().cloned());
            Ok(vec![record::stage(job, settings, &files, &file, &scene)?])
        };
        // The files written beside the image, one per pass (none for an EXR, which holds them).
        // The image and its pass files are staged, then renamed into place together.
        let aov_files = match (&args.aov, &aovs, &job.output.target) {
            (Some(passes), Some(aovs), Target::File(path)) => {
                if job.output.format == OutputFormat::Exr {
                    let exr = aov::stage_exr(path, &film, aovs, passes)?;
                    let mut files = vec![exr];
                    files.extend(stage_record(&[])?);
                    output::commit(files, &interrupt)?;
                    Vec::new()
                } else {
                    let files = aov::stage_files(path, aovs, passes, &interrupt)?;
                    let paths: Vec<PathBuf> = files.iter().map(|f| f.path().to_owned()).collect();
                    let after = stage_record(&paths)?;
                    job.output
                        .write(&film, scene.gamma, files, after, &interrupt)?;
                    paths
                }
            }
            _ => {
                let after = stage_record(&[])?;
                job.output
                    .write(&film, scene.gamma, Vec::new(), after, &interrupt)?;
                Vec::new()
            }
        };

        let report = Report {
            scene: &scene_name(&args.scene),
            camera: &job.camera,
            frame: job.frame,
            task: (job.task, count),
            output: &job.output.display(),
            aov_files: &aov_files,
            film: &film,
            settings: &job.settings,
            world: &scene.world,
            stats: &stats,
            load_time,
            parse_time,
        };
        if !args.quiet {
            note(&report.line());
        }
        if args.json {
            say(&report.json().to_string())?;
        }
    }
    Ok(())
}

/// Reports a task `--resume` skips: its image is there, made with the same settings.
fn skipped(args: &RenderArgs, job: &Job, count: usize) -> Result<(), Failure> {
    if !args.quiet {
        note(&format!(
            "penumbra: [{}/{count}] done before, skipped -> {}",
            job.task + 1,
            job.output.display()
        ));
    }
    if args.json {
        let line = serde_json::json!({
            "camera": job.camera,
            "frame": job.frame,
            "task": job.task,
            "output": job.output.display(),
            "status": "skipped",
        });
        say(&line.to_string())?;
    }
    Ok(())
}

/// The flag that chose the region.
fn region_flag(args: &RenderArgs) -> &'static str {
    if args.cropwindow.is_some() {
        "--cropwindow"
    } else {
        "--pixelbounds"
    }
}

/// How summaries name the scene.
fn scene_name(scene: &Path) -> PathBuf {
    if is_stdin(scene) {
        PathBuf::from(input::STDIN_NAME)
    } else {
        scene.to_owned()
    }
}

/// The failure of a `--progressive` render that a signal stopped, after writing the image of
/// its last finished pass (`samples` per pixel) where the final image would have gone.
fn write_last_pass(
    job: &Job,
    film: &Film,
    samples: u32,
    scene: &Scene,
    interrupt: &Interrupt,
) -> Failure {
    match job.output.write_anyway(film, scene.gamma) {
        Ok(()) => note(&format!(
            "interrupted: wrote the last finished pass ({samples} of {} samples per pixel) to {}",
            job.settings.spp,
            job.output.display()
        )),
        Err(e) => note(&format!("error: {}", e.message)),
    }
    interrupt.failure()
}

/// Runs `work` with a progress bar on stderr (none with `quiet` or when stderr is not a
/// terminal).
fn with_progress<T>(quiet: bool, work: impl FnOnce(&(dyn Fn(u64, u64) + Sync)) -> T) -> T {
    let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
        let bar = ProgressBar::new(100);
        bar.set_style(
            ProgressStyle::with_template(
                "{bar:40.cyan/blue} {percent:>3}% {elapsed_precise} eta {eta}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        bar
    });
    let progress = |done: u64, total: u64| {
        if let Some(bar) = &bar {
            bar.set_length(total);
            bar.set_position(done);
        }
    };
    let result = work(&progress);
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    result
}
