//! The `penumbra` command: parse flags, load, build, render, write. The only place where errors
//! become exit codes: 0 success, 1 runtime failure, 2 invalid input or usage, 128 + the signal's
//! number when a signal stopped it (130 Ctrl-C, 143 SIGTERM, 129 SIGHUP; see `signals`).

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use clap::{Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

use penumbra::{
    escape_controls, render, write_image_unless, ImageError, Light, OutputFormat, PixelBounds,
    RenderError, RenderOptions, RenderSettings, Sampler, Scene, SceneFile, SettingsError, View,
    World, MAX_THREADS,
};
use serde_json::json;

mod signals;
use signals::Interrupt;

#[derive(Parser)]
#[command(name = "penumbra", version, about = "A fast, exact CPU ray tracer")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene file to an image (.png, .jpg, .exr or .pfm).
    Render(RenderArgs),
    /// Validate a scene file and print a summary.
    Check {
        /// The scene file (.toml or .json).
        scene: PathBuf,
        /// Print the summary as one JSON object.
        #[arg(long)]
        json: bool,
    },
}

#[derive(Clone, Copy, ValueEnum)]
enum SamplerArg {
    Center,
    Grid,
    Rgss,
    Jittered,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// The scene file (.toml or .json).
    scene: PathBuf,
    /// Output image; the extension picks the format. Default: film.output, else
    /// <scene stem>.png next to the scene.
    #[arg(short, long, value_name = "OUT")]
    output: Option<PathBuf>,
    /// Film width in pixels.
    #[arg(long, value_name = "W")]
    width: Option<u32>,
    /// Film height in pixels.
    #[arg(long, value_name = "H")]
    height: Option<u32>,
    /// Pixel sampler (center means 1 sample unless --spp is given).
    #[arg(long, value_enum, value_name = "S")]
    sampler: Option<SamplerArg>,
    /// Samples per pixel, a perfect square.
    #[arg(long, value_name = "N")]
    spp: Option<u32>,
    /// N for every area light (N×N samples), overriding the scene's values.
    #[arg(long, value_name = "N")]
    light_samples: Option<u32>,
    /// Render the camera with this name.
    #[arg(long, value_name = "NAME")]
    camera: Option<String>,
    /// Worker threads (0: all cores).
    #[arg(short, long, value_name = "N", default_value_t = 0)]
    threads: usize,
    /// Seed for every random choice.
    #[arg(long, value_name = "N")]
    seed: Option<u64>,
    /// Render only the pixels [x0, x1) × [y0, y1) of the full film.
    // Hyphen values are taken so that "-1,..." is reported as a bad region, not a bad flag.
    #[arg(
        long,
        value_name = "x0,x1,y0,y1",
        value_parser = parse_bounds,
        allow_hyphen_values = true
    )]
    pixelbounds: Option<PixelBounds>,
    /// Print the summary as one JSON object on stdout.
    #[arg(long)]
    json: bool,
    /// No progress bar and no summary on stderr.
    #[arg(short, long)]
    quiet: bool,
}

fn parse_bounds(s: &str) -> Result<PixelBounds, String> {
    let v: Vec<u32> = s
        .split(',')
        .map(|p| p.trim().parse::<u32>())
        .collect::<Result<_, _>>()
        .map_err(|_| "expected four non-negative integers x0,x1,y0,y1".to_owned())?;
    match v[..] {
        [x0, x1, y0, y1] if x0 < x1 && y0 < y1 => Ok(PixelBounds { x0, x1, y0, y1 }),
        [_, _, _, _] => Err("the region is empty (need x0 < x1 and y0 < y1)".to_owned()),
        _ => Err("expected four non-negative integers x0,x1,y0,y1".to_owned()),
    }
}

/// An error and the exit code it ends with.
struct Failure {
    code: u8,
    message: String,
}

fn invalid(e: impl std::fmt::Display) -> Failure {
    Failure {
        code: 2,
        message: e.to_string(),
    }
}

fn runtime(e: impl std::fmt::Display) -> Failure {
    Failure {
        code: 1,
        message: e.to_string(),
    }
}

/// Writes `text` and a newline to stdout. A closed pipe or a full device is a runtime
/// failure, never a panic (which `println!` would be).
fn say(text: &str) -> Result<(), Failure> {
    let mut out = std::io::stdout().lock();
    writeln!(out, "{text}")
        .and_then(|()| out.flush())
        .map_err(|e| runtime(format!("cannot write to standard output: {e}")))
}

/// Writes `text` and a newline to stderr, if it can: with stderr closed or full there is
/// nowhere left to report to, and the exit code still tells what happened.
fn note(text: &str) {
    let _ = writeln!(std::io::stderr().lock(), "{text}");
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => run_render(args),
        Command::Check { scene, json } => run_check(&scene, json),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            if !f.message.is_empty() {
                // One message, one line: nothing from a file or path drives the terminal.
                note(&format!("error: {}", escape_controls(&f.message)));
            }
            ExitCode::from(f.code)
        }
    }
}

/// The scene file's settings with the command line's flags applied.
fn settings(args: &RenderArgs, file: &SceneFile, scene: &Scene) -> RenderSettings {
    let mut s = scene.settings.clone();
    if let Some(w) = args.width {
        s.width = w;
    }
    if let Some(h) = args.height {
        s.height = h;
    }
    if let Some(sampler) = args.sampler {
        s.sampler = match sampler {
            SamplerArg::Center => Sampler::Center,
            SamplerArg::Grid => Sampler::Grid,
            SamplerArg::Rgss => Sampler::Rgss,
            SamplerArg::Jittered => Sampler::Jittered,
        };
        // A sampler without --spp takes its own default count: 1 for center, else the
        // file's `samples`, else 4.
        s.spp = match (s.sampler, file.desc.render.samples) {
            (Sampler::Center, _) => 1,
            (_, Some(n)) => u32::try_from(n).unwrap_or(u32::MAX),
            (_, None) => 4,
        };
    }
    if let Some(spp) = args.spp {
        s.spp = spp;
    }
    if args.light_samples.is_some() {
        s.light_samples = args.light_samples;
    }
    if let Some(seed) = args.seed {
        s.seed = seed;
    }
    if let Some(name) = &args.camera {
        s.view = View::Named(name.clone());
    }
    s
}

/// The flag a settings error is about, as the user typed it.
fn flag_of(e: &SettingsError) -> &'static str {
    match e {
        SettingsError::Spp(_) | SettingsError::CenterSpp => "--spp",
        SettingsError::LightSamples(_) => "--light-samples",
        SettingsError::EmptyFilm { .. } | SettingsError::FilmTooLarge { .. } => "--width/--height",
        SettingsError::UnknownCamera { .. } | SettingsError::NoCamera => "--camera",
    }
}

/// Where the image goes: `-o`, else `film.output`, else `<scene stem>.png` beside the scene.
fn output_path(args: &RenderArgs, scene: &Scene) -> PathBuf {
    if let Some(o) = &args.output {
        return o.clone();
    }
    if let Some(o) = &scene.output {
        return o.clone();
    }
    let stem = args.scene.file_stem().unwrap_or_default();
    args.scene
        .with_file_name(Path::new(stem).with_extension("png"))
}

/// Light samples per shading point: N² for each area light (N from `n`, else the light's
/// own), 1 for each point light.
fn light_samples(world: &World, n: Option<u32>) -> u64 {
    world
        .lights()
        .iter()
        .map(|l| match l {
            Light::Area(a) => n.unwrap_or(a.n) as u64 * n.unwrap_or(a.n) as u64,
            Light::Point(_) => 1,
        })
        .sum()
}

fn run_render(args: RenderArgs) -> Result<(), Failure> {
    // A signal while loading ends the process at once (nothing is written yet); while
    // rendering or writing it asks them to stop, which then leaves no image either.
    let interrupt = Interrupt::install();
    let interrupted = || {
        let (code, message) = interrupt.report();
        Failure { code, message }
    };
    if args.threads > MAX_THREADS {
        return Err(invalid(format!(
            "--threads: at most {MAX_THREADS} worker threads, not {}",
            args.threads
        )));
    }
    let load_start = Instant::now();
    let file = SceneFile::load(&args.scene).map_err(invalid)?;
    let file_time = load_start.elapsed();
    let scene = file.build(args.threads).map_err(invalid)?;
    // The scene file, then its meshes and textures: everything of loading but the BVH.
    let parse_time = file_time + scene.load_time;
    let settings = settings(&args, &file, &scene);
    // Settings from flags are checked before anything is written or rendered.
    settings
        .check(&scene.world)
        .map_err(|e| invalid(format!("{}: {e}", flag_of(&e))))?;
    let load_time = load_start.elapsed();

    let out = output_path(&args, &scene);
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
        cancel: Some(interrupt.flag()),
        progress: Some(&progress),
    };
    interrupt.defer();
    let result = render(&scene.world, &settings, &options);
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
    match write_image_unless(&film, &out, scene.gamma, interrupt.flag()) {
        Ok(()) => {}
        Err(ImageError::Cancelled) => return Err(interrupted()),
        Err(e @ ImageError::NonFinite { .. }) => return Err(invalid(e)),
        Err(e) => return Err(runtime(e)),
    }

    let spp = settings.spp;
    let world_stats = scene.world.stats();
    let mrays = stats.rays_per_second() / 1e6;
    if !args.quiet {
        // "640x480", or "64x48 of 640x480" for a --pixelbounds region.
        let size = if (film.width, film.height) == (settings.width, settings.height) {
            format!("{}x{}", film.width, film.height)
        } else {
            format!(
                "{}x{} of {}x{}",
                film.width, film.height, settings.width, settings.height
            )
        };
        note(&format!(
            "penumbra: {size}, {spp} spp {}, {} light samples, {} triangles, load {:.2} s (BVH {:.2} s), render {:.2} s, {mrays:.2} Mrays/s, {} thread{} -> {}",
            settings.sampler.name(),
            light_samples(&scene.world, settings.light_samples),
            world_stats.triangles,
            load_time.as_secs_f64(),
            world_stats.bvh_build_time.as_secs_f64(),
            stats.time.as_secs_f64(),
            stats.threads,
            if stats.threads == 1 { "" } else { "s" },
            out.display()
        ));
    }
    if args.json {
        let summary = json!({
            "scene": args.scene.display().to_string(),
            "output": out.display().to_string(),
            "width": film.width,
            "height": film.height,
            "film_width": settings.width,
            "film_height": settings.height,
            "spp": spp,
            "sampler": settings.sampler.name(),
            "light_samples": light_samples(&scene.world, settings.light_samples),
            "triangles": world_stats.triangles,
            "load_seconds": load_time.as_secs_f64(),
            "parse_seconds": parse_time.as_secs_f64(),
            "bvh_build_seconds": world_stats.bvh_build_time.as_secs_f64(),
            "render_seconds": stats.time.as_secs_f64(),
            "camera_rays": stats.camera_rays,
            "shadow_rays": stats.shadow_rays,
            "rays_per_second": stats.rays_per_second(),
            "threads": stats.threads,
        });
        say(&summary.to_string())?;
    }
    Ok(())
}

fn run_check(path: &Path, json: bool) -> Result<(), Failure> {
    let file = SceneFile::load(path).map_err(invalid)?;
    let scene = file.build(0).map_err(invalid)?;
    let world = &scene.world;
    let bounds = world.bounds();
    let (min, max) = if bounds.is_empty() {
        ([0.0; 3], [0.0; 3])
    } else {
        (bounds.min.to_array(), bounds.max.to_array())
    };
    let s = world.stats();
    let settings = &scene.settings;
    let cameras: Vec<&str> = world.cameras().iter().map(|(n, _)| n.as_str()).collect();
    if json {
        let summary = json!({
            "scene": path.display().to_string(),
            "width": settings.width,
            "height": settings.height,
            "spp": settings.spp,
            "sampler": settings.sampler.name(),
            "triangles": s.triangles,
            "lights": s.lights,
            "light_samples": light_samples(world, None),
            "materials": s.materials,
            "textures": s.textures,
            "cameras": cameras,
            "bounds": { "min": min, "max": max },
        });
        say(&summary.to_string())
    } else {
        let lines = [
            format!("{}: ok", path.display()),
            format!(
                "  film       {}x{}, {} spp {}",
                settings.width,
                settings.height,
                settings.spp,
                settings.sampler.name()
            ),
            format!("  triangles  {}", s.triangles),
            format!(
                "  lights     {} ({} light samples per shading point)",
                s.lights,
                light_samples(world, None)
            ),
            format!("  materials  {}", s.materials),
            format!("  textures   {}", s.textures),
            format!("  cameras    {}", cameras.join(", ")),
            format!(
                "  bounds     [{:.4}, {:.4}, {:.4}] to [{:.4}, {:.4}, {:.4}]",
                min[0], min[1], min[2], max[0], max[1], max[2]
            ),
        ];
        say(&lines.join("\n"))
    }
}
