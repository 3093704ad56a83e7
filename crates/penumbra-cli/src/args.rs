//! The command line's grammar: subcommands, flags and the parsers of their values. Nothing
//! here loads or renders.

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{ArgAction, Parser, Subcommand};
use penumbra::{OutputFormat, Override, PixelBounds, Sampler, MAX_THREADS};

use crate::aov::Passes;

#[derive(Parser)]
#[command(name = "penumbra", version, about = "A fast, exact CPU ray tracer")]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

/// The command line with `render` put in front of a first argument that names a scene or a
/// model file (`penumbra scene.toml -o out.png`, as `mitsuba scene.xml` renders): a path
/// alone means render. Anything else (a subcommand, a flag, a typo) is left to clap.
pub fn with_subcommand(args: impl IntoIterator<Item = OsString>) -> Vec<OsString> {
    let mut args: Vec<OsString> = args.into_iter().collect();
    let names_file = args.get(1).is_some_and(|a| {
        let path = Path::new(a);
        let known = ["render", "check", "completions", "help"];
        !known.iter().any(|k| a == k)
            && (a == "-"
                || penumbra::SceneFormat::from_path(path).is_some()
                || penumbra::ModelFormat::from_path(path).is_some()
                || path.is_file())
    });
    if names_file {
        args.insert(1, OsString::from("render"));
    }
    args
}

#[derive(Subcommand)]
pub enum Command {
    /// Render a scene file or a model to an image (.png, .jpg, .exr or .pfm); `penumbra
    /// SCENE` alone means `penumbra render SCENE`.
    #[command(version, display_name = "penumbra")]
    Render(Box<RenderArgs>),
    /// Validate a scene file (or a bare .obj, .ply, .gltf or .glb model) and print a summary.
    #[command(version, display_name = "penumbra")]
    Check(CheckArgs),
    /// Print a shell completion script: source it, or save it where the shell looks.
    #[command(version, display_name = "penumbra")]
    Completions {
        /// bash, zsh, fish, elvish or powershell.
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
}

/// `penumbra check`.
#[derive(clap::Args)]
pub struct CheckArgs {
    /// The scene file (.toml or .json; - reads standard input), or a model: a Wavefront .obj,
    /// .ply, .gltf or .glb file.
    pub scene: PathBuf,
    /// Override a scene key: KEY.PATH=VALUE (repeatable).
    #[arg(long = "set", short = 'D', value_name = "KEY.PATH=VALUE", value_parser = parse_override, action = ArgAction::Append)]
    pub set: Vec<Override>,
    /// Let the scene's files also read files in DIR and below (repeatable). By default a scene
    /// file reads only files in its own folder and below, and a model only in its own folder.
    #[arg(long = "allow-path", value_name = "DIR", action = ArgAction::Append)]
    pub allow_path: Vec<PathBuf>,
    /// Print the summary as one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// `penumbra render`.
#[derive(clap::Args)]
pub struct RenderArgs {
    /// The scene file (.toml or .json). - reads it from standard input (TOML, or JSON when it
    /// starts with `{`), with relative paths in it relative to the current folder. A model
    /// (.obj, .ply, .gltf or .glb) is rendered as a scene of its own: its cameras and lights,
    /// or a camera framing it and a default light rig.
    pub scene: PathBuf,
    /// Output image; the extension picks the format; - writes to standard output (needs
    /// --format). {camera}, {frame} (or {frame:04}), {scene}, {spp} and {seed} are replaced;
    /// missing folders are made. Default: film.output, else <scene stem>.png next to a scene
    /// file, in the current folder for a model (<scene stem>_{camera}.png for several cameras,
    /// <scene stem>_{frame:04}.png for several frames).
    #[arg(short, long, visible_alias = "outfile", value_name = "OUT")]
    pub output: Option<PathBuf>,
    /// Image format: required with -o -, else it must agree with the extension.
    #[arg(long, value_name = "F", value_parser = format_parser())]
    pub format: Option<OutputFormat>,
    /// Override a scene key, as if the file said so: KEY.PATH=VALUE, such as film.width=640,
    /// render.sampler=rgss or objects[0].material=red. Repeatable; the VALUE is read as TOML,
    /// else taken as a string.
    #[arg(long = "set", short = 'D', value_name = "KEY.PATH=VALUE", value_parser = parse_override, action = ArgAction::Append)]
    pub set: Vec<Override>,
    /// Film width and height in pixels, WIDTHxHEIGHT (f3d's flag): --resolution 640x480.
    #[arg(long, visible_alias = "res", value_name = "WxH", value_parser = parse_resolution, conflicts_with_all = ["width", "height"])]
    pub resolution: Option<(u32, u32)>,
    /// Let the scene's files also read files in DIR and below (repeatable). By default a scene
    /// file reads only files in its own folder and below, and a model only in its own folder.
    #[arg(long = "allow-path", value_name = "DIR", action = ArgAction::Append)]
    pub allow_path: Vec<PathBuf>,
    /// Film width in pixels.
    #[arg(long, value_name = "W")]
    pub width: Option<u32>,
    /// Film height in pixels.
    #[arg(long, value_name = "H")]
    pub height: Option<u32>,
    /// Pixel sampler (center means 1 sample unless --spp is given).
    #[arg(long, value_name = "S", value_parser = sampler_parser())]
    pub sampler: Option<Sampler>,
    /// Samples per pixel, a perfect square.
    // pbrt's flag; the alias is the scene key's name (`render.samples`), which clap would
    // otherwise answer with a suggestion of --sampler.
    #[arg(long, visible_alias = "samples", value_name = "N")]
    pub spp: Option<u32>,
    /// N for every area light (N×N samples), overriding the scene's values.
    #[arg(long, value_name = "N")]
    pub light_samples: Option<u32>,
    /// The camera(s) to render: a name, a comma list, `all`, or name patterns with * and ?
    /// (several cameras render one after another from one loaded scene; -o then needs
    /// {camera}). `auto` (unless the scene has a camera of that name) frames the whole scene
    /// as a bare model's default camera does.
    #[arg(long, value_name = "NAMES")]
    pub camera: Option<String>,
    /// Frames of path cameras ([[cameras.NAME.keys]] or an orbit) to render: A:B (both
    /// included, as in Blender), A:B:STEP, one frame A, or `all` (the default for a path
    /// camera). -o then needs {frame} (or {frame:04}) when more than one image is rendered.
    #[arg(long, value_name = "A:B[:STEP]", value_parser = crate::sequence::parse_frames, allow_hyphen_values = true)]
    pub frames: Option<crate::sequence::Frames>,
    /// Render only every N-th task of the run (cameras × frames, in order), starting at the
    /// K-th (0-based): a SLURM array or a Kubernetes indexed job gives each process its K.
    #[arg(long, value_name = "K/N", value_parser = crate::sequence::parse_shard)]
    pub shard: Option<crate::sequence::Shard>,
    /// Skip a task whose image exists and whose record beside it (OUT.meta.json, written by
    /// every run with --resume) says it was rendered with exactly the same settings.
    #[arg(long)]
    pub resume: bool,
    /// Append one JSON line per task to this file as it ends: task, camera, frame, seed,
    /// seconds, peak memory, host, outputs, attempts, status (rendered, skipped, failed).
    #[arg(long, value_name = "FILE.jsonl")]
    pub manifest: Option<PathBuf>,
    /// Try a task that failed at run time (a file not written, memory) up to N more times;
    /// then go on, and list the failed tasks at the end (exit code 1).
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub retries: u32,
    /// List the tasks of this run (and shard) on stdout, and whether --resume would skip
    /// them; render and write nothing.
    #[arg(long)]
    pub dry_run: bool,
    /// Write OUT.meta.json beside each image (as --resume does): how it was made, the files
    /// written, K and the pose, and which object ids belong to which [[objects]] entry.
    #[arg(long)]
    pub meta: bool,
    /// Write every task's camera (intrinsics K and pose) to this JSON file (a folder for
    /// --poses-format colmap).
    #[arg(long, value_name = "FILE.json")]
    pub poses: Option<PathBuf>,
    /// The layout of --poses: `penumbra` ({"frames": [...]}, OpenCV and OpenGL poses),
    /// `nerf` (a transforms.json as instant-ngp and nerfstudio read it) or `colmap` (COLMAP's
    /// text model: cameras.txt, images.txt and points3D.txt in the folder --poses names).
    #[arg(long, value_name = "F", default_value = "penumbra", value_parser = ["penumbra", "nerf", "colmap"], requires = "poses")]
    pub poses_format: String,
    /// Worker threads (0: all cores).
    // Hyphen values are taken so that "-1" is answered with the range, not with clap's
    // "use -- -1" tip.
    #[arg(
        short,
        long,
        visible_alias = "nthreads",
        value_name = "N",
        default_value_t = 0,
        value_parser = parse_threads,
        allow_hyphen_values = true
    )]
    pub threads: usize,
    /// Seed for every random choice.
    #[arg(long, value_name = "N")]
    pub seed: Option<u64>,
    /// Render only the pixels [x0, x1) × [y0, y1) of the full film.
    // Hyphen values are taken so that "-1,..." is reported as a bad region, not a bad flag.
    #[arg(
        long,
        value_name = "x0,x1,y0,y1",
        value_parser = parse_bounds,
        allow_hyphen_values = true
    )]
    pub pixelbounds: Option<PixelBounds>,
    /// Render only the part [x0, x1) × [y0, y1) of the film given as fractions in [0, 1] (y
    /// down), as pbrt: pixels ceil(width·x0) to ceil(width·x1), likewise in y.
    #[arg(
        long,
        value_name = "x0,x1,y0,y1",
        value_parser = parse_crop,
        allow_hyphen_values = true,
        conflicts_with = "pixelbounds"
    )]
    pub cropwindow: Option<CropWindow>,
    /// A fast preview (pbrt's --quick): a quarter of the width and height, center sampling
    /// with 1 sample per pixel, 1 light sample per area light. Explicit --sampler, --spp and
    /// --light-samples still apply (--spp without --sampler keeps the scene's sampler).
    #[arg(long)]
    pub quick: bool,
    /// Passes beside the image: a comma list of depth (the distance along the ray; alias
    /// range), normal, albedo, position, object_id, primitive_id, z (planar depth along the
    /// camera's forward axis), or all. An .exr output holds them as extra channels; other outputs get
    /// one file per pass (out.depth.pfm, ..., out.object_id.exr).
    #[arg(long, value_name = "PASSES", value_parser = crate::aov::parse)]
    pub aov: Option<Passes>,
    /// Coverage alpha (film.alpha; Blender's transparent film): write RGBA, alpha the
    /// fraction of each pixel's samples that hit geometry, what camera rays miss (the
    /// background, a visible environment) transparent. PNG gets straight alpha, EXR
    /// premultiplied; JPEG and PFM cannot hold it.
    #[arg(long)]
    pub alpha: bool,
    /// Render in passes over the whole image (a preview of every second row, then 1, 2, 4,
    /// ... samples per pixel), each shown by --display-server; the final image is the same
    /// as without. Ctrl-C writes the last finished pass and exits with 130.
    #[arg(long, conflicts_with = "aov")]
    pub progressive: bool,
    /// Show the image in tev as it renders (pbrt's flag): tev's IPC at HOST, port 14158
    /// unless given. Without a viewer there the render goes on as usual.
    #[arg(long, value_name = "HOST[:PORT]")]
    pub display_server: Option<String>,
    /// Print the summary as one JSON object on stdout (per image), instead of the line on
    /// stderr.
    #[arg(long)]
    pub json: bool,
    /// No progress bar and no summary on stderr.
    #[arg(short, long)]
    pub quiet: bool,
}

/// `--sampler`: the library's names, listed in help and completions.
fn sampler_parser() -> impl TypedValueParser<Value = Sampler> {
    let names = Sampler::ALL.map(|s| PossibleValue::new(s.name()));
    PossibleValuesParser::new(names).try_map(|s| s.parse::<Sampler>())
}

/// `--format`: the library's names (`jpeg` too, unlisted), listed in help and completions.
fn format_parser() -> impl TypedValueParser<Value = OutputFormat> {
    let names = OutputFormat::ALL.map(|f| match f {
        OutputFormat::Jpeg => PossibleValue::new(f.extension()).alias("jpeg"),
        _ => PossibleValue::new(f.extension()),
    });
    PossibleValuesParser::new(names).try_map(|s| s.parse::<OutputFormat>())
}

/// A crop window in fractions of the film: [x0, x1) × [y0, y1), y down.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CropWindow {
    pub x0: f32,
    pub x1: f32,
    pub y0: f32,
    pub y1: f32,
}

fn parse_crop(s: &str) -> Result<CropWindow, String> {
    let expected = "expected four numbers x0,x1,y0,y1 in [0, 1]";
    let v: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| expected.to_owned())?;
    match v[..] {
        [x0, x1, y0, y1] if v.iter().all(|c| (0.0..=1.0).contains(c)) => {
            if x0 < x1 && y0 < y1 {
                Ok(CropWindow { x0, x1, y0, y1 })
            } else {
                Err("the window is empty (need x0 < x1 and y0 < y1)".to_owned())
            }
        }
        _ => Err(expected.to_owned()),
    }
}

/// `--threads`: 0 (all cores) or 1 to [`MAX_THREADS`].
fn parse_threads(s: &str) -> Result<usize, String> {
    let range = format!("expected 0 (all cores) or a number of threads from 1 to {MAX_THREADS}");
    match s.trim().parse::<i64>() {
        Ok(n) if (0..=MAX_THREADS as i64).contains(&n) => Ok(n as usize),
        Ok(n) => Err(format!("{range}, not {n}")),
        Err(_) => Err(format!("{range}, not `{s}`")),
    }
}

/// `--resolution WxH` (f3d's flag): the film's width and height.
fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let expected = || format!("expected WIDTHxHEIGHT in pixels, such as 640x480, not `{s}`");
    let (w, h) = s.split_once(['x', 'X', '*']).ok_or_else(expected)?;
    let size = |t: &str| t.trim().parse::<u32>().ok().filter(|&n| n > 0);
    size(w).zip(size(h)).ok_or_else(expected)
}

fn parse_override(s: &str) -> Result<Override, String> {
    Override::parse(s).map_err(|e| e.to_string())
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
