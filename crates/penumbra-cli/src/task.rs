//! One task of a render run: render the job's image (with its passes), then write it, its
//! pass files and, with `--resume` or `--meta`, its record, each renamed into place whole.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::Mutex;

use indicatif::{ProgressBar, ProgressStyle};
use penumbra::products::RecordSettings;
use penumbra::{
    Film, OutputFormat, Pass, RenderError, RenderOptions, RenderStats, Scene, SceneFile,
    StagedFile, Tile,
};

use crate::aov::{self, Passes};
use crate::args::RenderArgs;
use crate::display::Preview;
use crate::failure::{invalid, note, runtime, Failure};
use crate::output::{self, Target};
use crate::plan::Job;
use crate::record;
use crate::settings::flag_of;
use crate::signals::Interrupt;

/// What a task made: its image, the render's statistics, and the pass files beside it.
pub struct Done {
    pub film: Film,
    pub stats: RenderStats,
    pub aov_files: Vec<PathBuf>,
}

/// Renders and writes `job`; `recorded`: the settings its record keeps (with `--resume` or
/// `--meta`), `None` for no record.
pub fn run(
    args: &RenderArgs,
    file: &SceneFile,
    scene: &Scene,
    job: &Job,
    recorded: Option<RecordSettings>,
    preview: &mut Option<Preview>,
    interrupt: &Interrupt,
) -> Result<Done, Failure> {
    job.output.make_folder()?;
    if let Some(p) = preview.as_mut() {
        let passes = args.aov.clone().unwrap_or(Passes(Vec::new()));
        let size = (job.settings.width, job.settings.height);
        p.begin(&job.output.display(), size, job.settings.alpha, &passes);
    }
    // With --progressive, the image of the last finished pass: what Ctrl-C writes.
    let last_pass: Mutex<Option<(u32, Film)>> = Mutex::new(None);
    let keep = |pass: &Pass| {
        let mut last = last_pass.lock().unwrap_or_else(|e| e.into_inner());
        *last = Some((pass.samples, pass.film.clone()));
    };
    let show = |tile: &Tile| {
        if let Some(p) = preview.as_ref() {
            p.tile(tile);
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
                Some((samples, film)) => write_last_pass(job, &film, samples, scene, interrupt),
                None => interrupt.failure(),
            }
        }
        e @ RenderError::BadRegion { .. } => invalid(format!("{}: {e}", region_flag(args))),
        RenderError::Settings(e) => invalid(format!("{}: {e}", flag_of(&e))),
        e => runtime(e),
    })?;
    interrupt.check()?;
    let Target::File(path) = &job.output.target else {
        job.output.write_stdout(&film, scene.gamma)?;
        return Ok(Done {
            film,
            stats,
            aov_files: Vec::new(),
        });
    };
    // With --resume, the old record goes before the image is replaced, and the new one is
    // renamed into place right after it (see `record`).
    if recorded.is_some() {
        record::remove(path)?;
    }
    // The image and the files beside it, each staged whole, then renamed into place
    // together: its pass files (none for an EXR, which holds them), the image, its record.
    let (mut files, aov_files) = match (&args.aov, &aovs) {
        (Some(passes), Some(aovs)) if job.output.format == OutputFormat::Exr => (
            vec![aov::stage_exr(path, &film, aovs, passes, interrupt)?],
            Vec::new(),
        ),
        (Some(passes), Some(aovs)) => {
            let mut files = aov::stage_files(path, aovs, passes, interrupt)?;
            let paths: Vec<PathBuf> = files.iter().map(|f| f.path().to_owned()).collect();
            files.push(job.output.stage(path, &film, scene.gamma, interrupt)?);
            (files, paths)
        }
        _ => {
            let image = job.output.stage(path, &film, scene.gamma, interrupt)?;
            (vec![image], Vec::new())
        }
    };
    if let (Some(settings), Some((image, passes))) = (recorded, files.split_last()) {
        // As the record lists them: the image (staged last), then its pass files.
        let listed: Vec<&StagedFile> = std::iter::once(image).chain(passes).collect();
        let staged = record::stage(job, settings, &listed, file, scene)?;
        files.push(staged);
    }
    output::commit(files, interrupt)?;

    Ok(Done {
        film,
        stats,
        aov_files,
    })
}

/// The flag that chose the region.
fn region_flag(args: &RenderArgs) -> &'static str {
    if args.cropwindow.is_some() {
        "--cropwindow"
    } else {
        "--pixelbounds"
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
