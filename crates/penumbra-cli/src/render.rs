//! `penumbra render`: load, build, apply the flags, render, write, report.

use std::io::IsTerminal;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use penumbra::{write_image, OutputFormat, RenderError, RenderOptions, SceneFile, MAX_THREADS};

use crate::args::RenderArgs;
use crate::failure::{invalid, note, runtime, say, Failure};
use crate::settings::{flag_of, output_path, settings};
use crate::signals::{interrupted, Interrupt};
use crate::summary::Report;

pub fn run(args: &RenderArgs) -> Result<(), Failure> {
    let interrupt = Interrupt::install();
    if args.threads > MAX_THREADS {
        return Err(invalid(format!(
            "--threads: at most {MAX_THREADS} worker threads, not {}",
            args.threads
        )));
    }
    let load_start = Instant::now();
    let file = SceneFile::load_with(&args.scene, &args.set).map_err(invalid)?;
    let file_time = load_start.elapsed();
    let scene = file.build(args.threads).map_err(invalid)?;
    // The scene file, then its meshes and textures: everything of loading but the BVH.
    let parse_time = file_time + scene.load_time;
    let settings = settings(args, &file, &scene);
    // Settings from flags are checked before anything is written or rendered.
    settings
        .check(&scene.world)
        .map_err(|e| invalid(format!("{}: {e}", flag_of(&e))))?;
    let load_time = load_start.elapsed();
    interrupt.check()?;

    let out = output_path(args, &scene);
    let Some(format) = OutputFormat::from_path(&out) else {
        return Err(invalid(format!(
            "{}: unknown image format (use .png, .jpg, .exr or .pfm)",
            out.display()
        )));
    };
    // Refused before rendering: an image the format cannot hold would be lost after the work.
    let (image_w, image_h) = match args.pixelbounds {
        Some(b) => (b.x1.saturating_sub(b.x0), b.y1.saturating_sub(b.y0)),
        None => (settings.width, settings.height),
    };
    if let Some(max) = format.max_dimension() {
        if image_w > max || image_h > max {
            return Err(invalid(format!(
                "{}: a {image_w}x{image_h} image is too large for this format (at most {max} pixels wide and high)",
                out.display()
            )));
        }
    }
    let out_dir = out.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(dir) = out_dir {
        if !dir.is_dir() {
            return Err(runtime(format!(
                "{}: cannot write image: folder {} does not exist",
                out.display(),
                dir.display()
            )));
        }
    }

    let bar = (!args.quiet && std::io::stderr().is_terminal()).then(|| {
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
    let options = RenderOptions {
        threads: args.threads,
        region: args.pixelbounds,
        cancel: Some(interrupt.cancel_flag()),
        progress: Some(&progress),
    };
    interrupt.start_rendering();
    let result = penumbra::render(&scene.world, &settings, &options);
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    let (film, stats) = match result {
        Ok(r) => r,
        Err(RenderError::Cancelled) => return Err(interrupted()),
        Err(e @ RenderError::BadRegion { .. }) => {
            return Err(invalid(format!("--pixelbounds: {e}")))
        }
        Err(RenderError::Settings(e)) => return Err(invalid(format!("{}: {e}", flag_of(&e)))),
        Err(e) => return Err(runtime(e)),
    };
    interrupt.check()?;
    write_image(&film, &out, scene.gamma).map_err(runtime)?;

    let report = Report {
        scene: &args.scene,
        output: &out,
        film: &film,
        settings: &settings,
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
    Ok(())
}
