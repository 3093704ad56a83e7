//! `penumbra check`: load and build a scene, then print what it holds.

use std::path::Path;

use serde_json::json;

use crate::args::CheckArgs;
use crate::failure::{invalid, say, Failure};
use crate::input;
use crate::summary::light_samples;

pub fn run(args: &CheckArgs) -> Result<(), Failure> {
    let path: &Path = &args.scene;
    let file = input::load(path, &args.set)?;
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
    if args.json {
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
