//! `penumbra render`: load and build the scene once, plan one render per camera (settings,
//! region and output, all checked before any work), then render, write and report each.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use penumbra::{
    AovPixel, Film, OutputFormat, Pass, PixelBounds, RenderError, RenderOptions, RenderSettings,
    Rgb, Scene, SceneFile, SettingsError, View, World, MAX_THREADS,
};

use crate::aov::{self, Passes};
use crate::args::RenderArgs;
use crate::cameras;
use crate::display::Preview;
use crate::failure::{invalid, note, runtime, say, Failure};
use crate::input::{self, is_stdin};
use crate::output::{self, expand, names_camera, scene_stem, Fields, Output, Target};
use crate::settings::{flag_of, patch, region};
use crate::signals::Interrupt;
use crate::summary::Report;

/// One render of the run.
struct Job {
    settings: RenderSettings,
    region: Option<PixelBounds>,
    output: Output,
}

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
    let jobs = plan(args, &file, &scene)?;
    let load_time = load_start.elapsed();
    interrupt.check()?;
    let mut preview = args
        .display_server
        .as_deref()
        .and_then(|server| Preview::connect(server, note));

    for job in &jobs {
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
        // The files written beside the image, one per pass (none for an EXR, which holds them).
        // The image and its pass files are staged, then renamed into place together.
        let aov_files = match (&args.aov, &aovs, &job.output.target) {
            (Some(passes), Some(aovs), Target::File(path)) => {
                if job.output.format == OutputFormat::Exr {
                    let exr = aov::stage_exr(path, &film, aovs, passes)?;
                    output::commit(vec![exr], &interrupt)?;
                    Vec::new()
                } else {
                    let files = aov::stage_files(path, aovs, passes, &interrupt)?;
                    let paths = files.iter().map(|f| f.path().to_owned()).collect();
                    job.output.write(&film, scene.gamma, files, &interrupt)?;
                    paths
                }
            }
            _ => {
                job.output
                    .write(&film, scene.gamma, Vec::new(), &interrupt)?;
                Vec::new()
            }
        };

        let report = Report {
            scene: &scene_name(&args.scene),
            camera: camera_name(&job.settings.view, &scene.world),
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

/// Every render of the run, each checked (settings, output name and format, image size)
/// before anything is rendered or written.
fn plan(args: &RenderArgs, file: &SceneFile, scene: &Scene) -> Result<Vec<Job>, Failure> {
    let views = cameras::select(args.camera.as_deref(), &scene.world)?;
    let several = views.len() > 1;
    let (pattern, from) = output_pattern(args, scene, several)?;
    if several && pattern.to_str().is_none_or(|p| !names_camera(p)) {
        return Err(invalid(format!(
            "{from}: {} cameras need {{camera}} in the output name, such as out/{{scene}}_{{camera}}.png",
            views.len()
        )));
    }
    let stem = scene_stem(&args.scene, is_stdin(&args.scene));
    let mut jobs: Vec<Job> = Vec::new();
    for view in &views {
        // Settings from flags are checked before anything is written or rendered.
        let bad = |e: SettingsError| invalid(format!("{}: {e}", flag_of(&e)));
        let settings = patch(args, &scene.settings, view.as_deref())
            .apply(&scene.settings, file.samples())
            .map_err(bad)?;
        settings.check(&scene.world).map_err(bad)?;
        let name = match pattern.to_str() {
            Some(p) => {
                let fields = Fields {
                    camera: camera_name(&settings.view, &scene.world),
                    scene: &stem,
                    spp: settings.spp,
                    seed: settings.seed,
                };
                PathBuf::from(expand(p, &fields).map_err(|e| invalid(format!("{from}: {e}")))?)
            }
            // Not UTF-8: no fields to expand.
            None => pattern.clone(),
        };
        let output = Output::new(name, args.format)?;
        if args.aov.is_some() && output.target == Target::Stdout {
            return Err(invalid(
                "--aov: passes are written beside an image file, not to standard output (-o -)",
            ));
        }
        let region = region(args, &settings);
        let (w, h) = match region {
            Some(b) => (b.x1.saturating_sub(b.x0), b.y1.saturating_sub(b.y0)),
            None => (settings.width, settings.height),
        };
        output.check_size(w, h)?;
        // Camera names that differ only in a path separator (made `_`) meet here.
        if let Some(other) = jobs.iter().find(|j| j.output.target == output.target) {
            return Err(invalid(format!(
                "{from}: two renders would write {}",
                other.output.display()
            )));
        }
        jobs.push(Job {
            settings,
            region,
            output,
        });
    }
    Ok(jobs)
}

/// The output name before expansion and the flag or key it comes from: `-o`, else
/// `film.output`, else `<scene stem>.png` beside the scene (`<scene stem>_{camera}.png` for
/// several cameras).
fn output_pattern(
    args: &RenderArgs,
    scene: &Scene,
    several: bool,
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
    name.push(if several { "_{camera}.png" } else { ".png" });
    Ok((args.scene.with_file_name(name), "-o"))
}

/// The camera's name for `{camera}`.
fn camera_name<'a>(view: &'a View, world: &'a World) -> &'a str {
    match view {
        View::Named(n) => n,
        View::First => world.cameras().first().map_or("camera", |(n, _)| n),
        View::Camera(_) => "camera",
    }
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
        Ok(()) if samples == 0 => note(&format!(
            "interrupted: wrote the preview pass (the first sample of every second row, each \
             shown twice) to {}",
            job.output.display()
        )),
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
