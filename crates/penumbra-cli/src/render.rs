//! `penumbra render`: load and build the scene once, plan one render per task (camera ×
//! frame; settings, region and output, all checked before any work; see `plan`), write the
//! poses, then render, write (see `task`) and report each task of this shard: skipping, with
//! `--resume`, those done before; trying a failed one again up to `--retries` times, then
//! going on and listing the failures at the end (exit code 1); one `--manifest` line each.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::args::RenderArgs;
use crate::display::Preview;
use crate::failure::{invalid, note, runtime, say, say_beside, Failure};
use crate::input::{self, is_stdin};
use crate::manifest::{Manifest, Status};
use crate::output::Target;
use crate::plan::{self, Job};
use crate::signals::Interrupt;
use crate::summary::Report;
use crate::warnings::no_light_warning;
use crate::{poses, record, task};

pub fn run(args: &RenderArgs) -> Result<(), Failure> {
    let interrupt = Interrupt::install();
    if args.json && args.output.as_deref() == Some(Path::new("-")) {
        return Err(invalid(
            "--json: standard output carries the image with -o -; drop --json",
        ));
    }
    let load_start = Instant::now();
    let file = input::load(
        &args.scene,
        &args.set,
        &args.allow_path,
        input::Reader::Render,
    )?;
    let file_time = load_start.elapsed();
    let scene = file.build(args.threads).map_err(invalid)?;
    if let Some(w) = no_light_warning(&scene.world, scene.settings.ambient) {
        note(&format!(
            "warning: {}: {w}",
            scene_name(&args.scene).display()
        ));
    }
    // The scene file, then its meshes and textures: everything of loading but the BVH.
    let parse_time = file_time + scene.load_time;
    let all = plan::plan(args, &file, &scene)?;
    let count = all.len();
    // This process's tasks, by index into `all`.
    let jobs: Vec<usize> = (0..count)
        .filter(|&i| args.shard.is_none_or(|shard| shard.takes(i)))
        .collect();
    let digest = (args.resume || args.meta).then(|| file.digest(&scene.files));
    let load_time = load_start.elapsed();
    interrupt.check()?;
    if args.dry_run {
        return dry_run(args, &jobs, &all, digest.as_deref(), scene.gamma, count);
    }
    let mut preview = args
        .display_server
        .as_deref()
        .and_then(|server| Preview::connect(server, note));
    let mut manifest = Manifest::open(args.manifest.as_deref())?;
    if let Some(path) = &args.poses {
        // From here on files are written: a signal stops the run between two writes.
        interrupt.defer();
        poses::write(path, &args.poses_format, &all, &scene, &interrupt)?;
    }
    let mut failed: Vec<(&Job, String)> = Vec::new();
    // With --resume, what a killed run left beside the outputs of this one goes.
    let mut tidy = record::Tidy::default();
    for job in jobs.iter().map(|&i| &all[i]) {
        interrupt.check()?;
        let start = Instant::now();
        let recorded = digest
            .as_deref()
            .map(|d| record::settings(job, d, args.aov.as_ref(), scene.gamma));
        if let Some(settings) = recorded.as_ref().filter(|_| args.resume) {
            if let Some(mut files) = record::finished(job, settings) {
                files.extend(files.first().map(|image| record::path_of(image)));
                tidy.finished(&files);
                skipped(args, job, count)?;
                let outputs = [job.output.display()];
                manifest.write(job, Status::Skipped, 0.0, 0, &outputs, None)?;
                continue;
            }
        }
        // A runtime failure (a file that cannot be written, memory) is tried again up to
        // --retries times; invalid input and signals end the run at once.
        let mut attempts = 0;
        let outcome = loop {
            attempts += 1;
            let r = task::run(
                args,
                &file,
                &scene,
                job,
                recorded.clone(),
                &mut preview,
                &interrupt,
            );
            match r {
                Err(f) if f.code == 1 && attempts <= args.retries => {
                    note(&format!(
                        "penumbra: [{}/{count}] attempt {attempts} failed, trying again: {}",
                        job.task + 1,
                        f.message
                    ));
                }
                r => break r,
            }
        };
        let seconds = start.elapsed().as_secs_f64();
        let done = match outcome {
            Ok(done) => done,
            Err(f) => {
                let outputs: [String; 0] = [];
                manifest.write(
                    job,
                    Status::Failed,
                    seconds,
                    attempts,
                    &outputs,
                    Some(&f.message),
                )?;
                if f.code != 1 {
                    return Err(f);
                }
                if count > 1 {
                    note(&format!(
                        "penumbra: [{}/{count}] failed: {}",
                        job.task + 1,
                        f.message
                    ));
                }
                failed.push((job, f.message));
                continue;
            }
        };
        if let (true, Target::File(image)) = (args.resume, &job.output.target) {
            let mut files = vec![image.clone(), record::path_of(image)];
            files.extend(done.aov_files.iter().cloned());
            tidy.finished(&files);
        }
        let mut outputs = vec![job.output.display()];
        outputs.extend(done.aov_files.iter().map(|p| p.display().to_string()));
        manifest.write(job, Status::Rendered, seconds, attempts, &outputs, None)?;
        let report = Report {
            scene: &scene_name(&args.scene),
            camera: &job.camera,
            frame: job.frame,
            task: (job.task, count),
            output: &job.output.display(),
            aov_files: &done.aov_files,
            film: &done.film,
            settings: &job.settings,
            world: &scene.world,
            stats: &done.stats,
            load_time,
            parse_time,
        };
        // --json is the summary, on stdout: the line for people stays off stderr.
        if !args.quiet && !args.json {
            note(&report.line());
        }
        if args.json {
            say_beside(&report.json().to_string())?;
        }
    }
    match &failed[..] {
        [] => Ok(()),
        // One task of one: its own message, as a run of one image has always said it.
        [(_, message)] if count == 1 => Err(runtime(message)),
        _ => {
            let list: Vec<String> = failed
                .iter()
                .map(|(job, message)| {
                    format!("task {} ({}): {message}", job.task, job.output.display())
                })
                .collect();
            Err(runtime(format!(
                "{} of {} tasks failed: {}",
                failed.len(),
                jobs.len(),
                list.join("; ")
            )))
        }
    }
}

/// `--dry-run`: the tasks this process would render, one line each on stdout (a JSON object
/// each with --json), and whether `--resume` would skip them; nothing is written.
fn dry_run(
    args: &RenderArgs,
    jobs: &[usize],
    all: &[Job],
    digest: Option<&str>,
    gamma: Option<f32>,
    count: usize,
) -> Result<(), Failure> {
    for job in jobs.iter().map(|&i| &all[i]) {
        let done = args.resume
            && digest.is_some_and(|d| {
                record::done(job, &record::settings(job, d, args.aov.as_ref(), gamma))
            });
        let status = if done { "skipped" } else { "planned" };
        if args.json {
            let line = serde_json::json!({
                "task": job.task,
                "camera": job.camera,
                "frame": job.frame,
                "seed": job.settings.seed,
                "output": job.output.display(),
                "status": status,
            });
            say(&line.to_string())?;
        } else {
            let frame = job.frame.map_or(String::new(), |f| format!(" frame {f}"));
            say(&format!(
                "task {} of {count}: camera {}{frame} -> {}{}",
                job.task,
                job.camera,
                job.output.display(),
                if done {
                    " (done before: skipped with --resume)"
                } else {
                    ""
                }
            ))?;
        }
    }
    Ok(())
}

/// Reports a task `--resume` skips: its image is there, made with the same settings.
fn skipped(args: &RenderArgs, job: &Job, count: usize) -> Result<(), Failure> {
    if !args.quiet && !args.json {
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
        say_beside(&line.to_string())?;
    }
    Ok(())
}

/// How summaries name the scene.
fn scene_name(scene: &Path) -> PathBuf {
    if is_stdin(scene) {
        PathBuf::from(input::STDIN_NAME)
    } else {
        scene.to_owned()
    }
}
