//! What a finished render reports: the one-line summary on stderr and the `--json` object on
//! stdout.

use std::path::{Path, PathBuf};
use std::time::Duration;

use penumbra::{Aabb, Film, Light, RenderSettings, RenderStats, World};
use serde_json::{json, Value};

/// Light samples per shading point: N² for each area light, environment and sun with an
/// angular size (N from `n`, else the light's own), 1 for each point, spot or point-like sun.
pub fn light_samples(world: &World, n: Option<u32>) -> u64 {
    world
        .lights()
        .iter()
        .map(|l| match l {
            Light::Area(a) => n.unwrap_or(a.n) as u64 * n.unwrap_or(a.n) as u64,
            Light::Point(_) => 1,
            Light::Environment(e) => n.unwrap_or(e.n) as u64 * n.unwrap_or(e.n) as u64,
            Light::Directional(d) if d.cos_half_angle < 1.0 => {
                n.unwrap_or(d.n) as u64 * n.unwrap_or(d.n) as u64
            }
            Light::Directional(_) | Light::Spot(_) => 1,
        })
        .sum()
}

/// One finished render, as the summaries describe it.
pub struct Report<'a> {
    pub scene: &'a Path,
    /// The camera's name.
    pub camera: &'a str,
    /// The frame of a path camera.
    pub frame: Option<i64>,
    /// The task's place in the run (from 0) and the run's number of tasks.
    pub task: (usize, usize),
    pub output: &'a str,
    /// The `--aov` files written beside the output, if any.
    pub aov_files: &'a [PathBuf],
    pub film: &'a Film,
    pub settings: &'a RenderSettings,
    pub world: &'a World,
    pub stats: &'a RenderStats,
    /// Reading the scene file, its meshes and textures, and building the BVH.
    pub load_time: Duration,
    /// Everything of loading but the BVH.
    pub parse_time: Duration,
}

impl Report<'_> {
    /// The one-line summary for stderr.
    pub fn line(&self) -> String {
        let (film, settings, stats) = (self.film, self.settings, self.stats);
        // "640x480", or "64x48 of 640x480" for a --pixelbounds region.
        let size = if (film.width, film.height) == (settings.width, settings.height) {
            format!("{}x{}", film.width, film.height)
        } else {
            format!(
                "{}x{} of {}x{}",
                film.width, film.height, settings.width, settings.height
            )
        };
        let world_stats = self.world.stats();
        let samples = light_samples(self.world, settings.light_samples);
        // "[3/120] frame 2, " for a task of a sequence.
        let task = match (self.frame, self.task) {
            (Some(frame), (i, n)) => format!("[{}/{n}] frame {frame}, ", i + 1),
            (None, (i, n)) if n > 1 => format!("[{}/{n}] ", i + 1),
            _ => String::new(),
        };
        format!(
            "penumbra: {task}{size}, {} spp {}, {} light sample{}, {} triangles, load {:.2} s (BVH {:.2} s), render {:.2} s, {:.2} Mrays/s, {} thread{} -> {}",
            settings.spp,
            settings.sampler.name(),
            samples,
            if samples == 1 { "" } else { "s" },
            world_stats.triangles,
            self.load_time.as_secs_f64(),
            world_stats.bvh_build_time.as_secs_f64(),
            stats.time.as_secs_f64(),
            stats.rays_per_second() / 1e6,
            stats.threads,
            if stats.threads == 1 { "" } else { "s" },
            self.output
        ) + &aov_files_text(self.aov_files)
    }

    /// The `--json` object.
    pub fn json(&self) -> Value {
        let (film, settings, stats) = (self.film, self.settings, self.stats);
        let world_stats = self.world.stats();
        json!({
            "scene": self.scene.display().to_string(),
            "camera": self.camera,
            "frame": self.frame,
            "task": self.task.0,
            "status": "rendered",
            "output": self.output,
            "aovs": self.aov_files.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
            "width": film.width,
            "height": film.height,
            "film_width": settings.width,
            "film_height": settings.height,
            "spp": settings.spp,
            "sampler": settings.sampler.name(),
            "light_samples": light_samples(self.world, settings.light_samples),
            "triangles": world_stats.triangles,
            "load_seconds": self.load_time.as_secs_f64(),
            "parse_seconds": self.parse_time.as_secs_f64(),
            "bvh_build_seconds": world_stats.bvh_build_time.as_secs_f64(),
            "render_seconds": stats.time.as_secs_f64(),
            "camera_rays": stats.camera_rays,
            "shadow_rays": stats.shadow_rays,
            "rays_per_second": stats.rays_per_second(),
            "threads": stats.threads,
        })
    }
}

/// " + 2 AOV files: out.depth.pfm, out.normal.pfm" after the output's name; empty for none.
fn aov_files_text(files: &[PathBuf]) -> String {
    match files.len() {
        0 => String::new(),
        n => {
            let names: Vec<String> = files.iter().map(|p| p.display().to_string()).collect();
            let s = if n == 1 { "" } else { "s" };
            format!(" + {n} AOV file{s}: {}", names.join(", "))
        }
    }
}

/// `[x, y, z] to [x, y, z]`, four decimals; zeros for nothing.
pub fn bounds_text(b: Aabb) -> String {
    let (min, max) = min_max(b);
    format!(
        "[{:.4}, {:.4}, {:.4}] to [{:.4}, {:.4}, {:.4}]",
        min[0], min[1], min[2], max[0], max[1], max[2]
    )
}

/// `{"min": [..], "max": [..]}`.
pub fn bounds_json(b: Aabb) -> Value {
    let (min, max) = min_max(b);
    json!({ "min": min, "max": max })
}

fn min_max(b: Aabb) -> ([f32; 3], [f32; 3]) {
    if b.is_empty() {
        ([0.0; 3], [0.0; 3])
    } else {
        (b.min.to_array(), b.max.to_array())
    }
}
