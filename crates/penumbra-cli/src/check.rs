//! `penumbra check`: load and build a scene, then print what it holds: totals, each object's
//! triangles and bounds, and warnings (on stderr; see `warnings`) for scene mistakes. A
//! `.obj` or `.ply` mesh is summarized on its own (see `check_obj`).

use std::ops::Range;
use std::path::Path;

use penumbra::{Aabb, Light, SceneDesc, World, WorldStats};
use serde_json::{json, Value};

use crate::args::CheckArgs;
use crate::check_obj;
use crate::failure::{invalid, note, say, Failure};
use crate::input;
use crate::summary::{bounds_json, bounds_text, light_samples};
use crate::warnings::{light_warnings, no_light_warning, unused_warnings, view_warnings};

pub fn run(args: &CheckArgs) -> Result<(), Failure> {
    let path: &Path = &args.scene;
    if check_obj::is_mesh(path) {
        if let Some(o) = args.set.first() {
            return Err(invalid(format!(
                "--set {o}: overrides change scene keys, and a mesh file has none (check a scene that places the mesh instead)"
            )));
        }
        return check_obj::run(path, args.json, &args.allow_path);
    }
    let file = input::load(path, &args.set, &args.allow_path, input::Reader::Check)?;
    let scene = file.build(0).map_err(invalid)?;
    let world = &scene.world;
    let name = if input::is_stdin(path) {
        input::STDIN_NAME.to_owned()
    } else {
        path.display().to_string()
    };
    let objects = objects(world, &file.desc, &scene.objects);
    let bounds: Vec<(String, Aabb)> = objects.iter().map(|o| (o.key.clone(), o.bounds)).collect();
    let aspect = scene.settings.width as f32 / scene.settings.height as f32;
    let mut warnings: Vec<String> = no_light_warning(world, scene.settings.ambient)
        .into_iter()
        .collect();
    warnings.extend(light_warnings(world, scene.settings.light_model));
    warnings.extend(unused_warnings(&file.desc));
    warnings.extend(view_warnings(world, aspect, &bounds));
    for w in &warnings {
        note(&format!("warning: {name}: {w}"));
    }
    let s = world.stats();
    let settings = &scene.settings;
    let cameras: Vec<&str> = world.cameras().iter().map(|(n, _)| n.as_str()).collect();
    // A camera with keys or a path, with its frames: "turn (frames 0 to 119)".
    let camera_text: Vec<String> = cameras
        .iter()
        .map(|&n| match scene.path(n) {
            Some(p) => format!(
                "{n} (frames {} to {})",
                p.frames().start(),
                p.frames().end()
            ),
            None => n.to_owned(),
        })
        .collect();
    let paths: serde_json::Map<String, Value> = scene
        .paths
        .iter()
        .map(|(n, p)| (n.clone(), json!([p.frames().start(), p.frames().end()])))
        .collect();
    if args.json {
        let summary = json!({
            "scene": name,
            "width": settings.width,
            "height": settings.height,
            "spp": settings.spp,
            "sampler": settings.sampler.name(),
            "triangles": s.triangles,
            "unique_triangles": s.unique_triangles,
            "meshes": s.meshes,
            "instances": s.instances,
            "lights": s.lights,
            "light_samples": light_samples(world, None),
            "environments": environments(world).iter().map(|e| json!({
                "light": e.light,
                "width": e.size.0,
                "height": e.size.1,
                "mean_radiance": e.mean.to_array(),
                "peak_radiance": e.peak.to_array(),
            })).collect::<Vec<Value>>(),
            "materials": s.materials,
            "textures": s.textures,
            "cameras": cameras,
            "camera_frames": paths,
            "bounds": bounds_json(world.bounds()),
            "objects": objects.iter().map(|o| {
                let mut entry = json!({
                    "key": o.key,
                    "type": o.kind,
                    "triangles": o.triangles,
                    "bounds": bounds_json(o.bounds),
                });
                if let Some(name) = &o.name {
                    entry["name"] = json!(name);
                }
                entry
            }).collect::<Vec<Value>>(),
            "warnings": warnings,
        });
        return say(&summary.to_string());
    }
    let mut lines = vec![
        format!("{name}: ok"),
        format!(
            "  film       {}x{}, {} spp {}",
            settings.width,
            settings.height,
            settings.spp,
            settings.sampler.name()
        ),
        triangles_line(&s),
        format!(
            "  lights     {} ({} light sample{} per shading point)",
            s.lights,
            light_samples(world, None),
            if light_samples(world, None) == 1 {
                ""
            } else {
                "s"
            }
        ),
    ];
    for e in environments(world) {
        lines.push(format!(
            "    lights[{}]  environment {}x{}, mean radiance {}, peak {}",
            e.light,
            e.size.0,
            e.size.1,
            rgb_text(e.mean),
            rgb_text(e.peak)
        ));
    }
    lines.extend([
        format!("  materials  {}", s.materials),
        format!("  textures   {}", s.textures),
        format!("  cameras    {}", camera_text.join(", ")),
        format!("  bounds     {}", bounds_text(world.bounds())),
        format!("  objects    {}", objects.len()),
    ]);
    // An entry by its key, and its name when it has one: `objects[3] "chair"`.
    let key = |o: &ObjectInfo| match &o.name {
        Some(name) => format!("{} {name:?}", o.key),
        None => o.key.clone(),
    };
    let key_width = objects
        .iter()
        .map(|o| key(o).chars().count())
        .max()
        .unwrap_or(0);
    let kind_width = objects.iter().map(|o| o.kind.len()).max().unwrap_or(0);
    for o in &objects {
        lines.push(format!(
            "    {:key_width$}  {:kind_width$}  {:>7} triangles  {}",
            key(o),
            o.kind,
            o.triangles,
            bounds_text(o.bounds)
        ));
    }
    say(&lines.join("\n"))
}

/// An environment light as `check` reports it: its map's size, and its mean (over the sphere)
/// and largest radiance, scaled by its intensity.
struct EnvironmentInfo {
    /// Index in the scene's lights.
    light: usize,
    size: (u32, u32),
    mean: glam::Vec3,
    peak: glam::Vec3,
}

fn environments(world: &World) -> Vec<EnvironmentInfo> {
    let lights = world.lights().iter().enumerate();
    lights
        .filter_map(|(light, l)| match l {
            Light::Environment(e) => {
                let (mean, peak) = e.map.mean_and_peak();
                Some(EnvironmentInfo {
                    light,
                    size: e.map.size(),
                    mean: mean * e.intensity,
                    peak: peak * e.intensity,
                })
            }
            _ => None,
        })
        .collect()
}

/// `(r, g, b)` with 4 decimals.
fn rgb_text(c: glam::Vec3) -> String {
    format!("({:.4}, {:.4}, {:.4})", c.x, c.y, c.z)
}

/// One object of the scene as `check` lists it.
struct ObjectInfo {
    /// `objects[i]`.
    key: String,
    /// Its `name`, when it has one.
    name: Option<String>,
    /// Its type, and the file for a mesh: `mesh models/bunny.obj`.
    kind: String,
    triangles: usize,
    bounds: Aabb,
}

/// "  triangles  N", and when instances place meshes, how many of those are in memory.
fn triangles_line(s: &WorldStats) -> String {
    if s.instances == 0 {
        return format!("  triangles  {}", s.triangles);
    }
    format!(
        "  triangles  {} ({} in memory: {} instance{} of {} mesh{})",
        s.triangles,
        s.unique_triangles,
        s.instances,
        if s.instances == 1 { "" } else { "s" },
        s.meshes,
        if s.meshes == 1 { "" } else { "es" }
    )
}

/// Each `[[objects]]` entry's triangles (as rays see them: every copy counted) and
/// world-space bounds, in file order; `ids` are the object ids each entry added.
fn objects(world: &World, desc: &SceneDesc, ids: &[Range<u32>]) -> Vec<ObjectInfo> {
    // The entry of each object id.
    let mut entry_of = Vec::new();
    for (entry, range) in ids.iter().enumerate() {
        entry_of.extend(range.clone().map(|_| entry));
    }
    let mut acc = vec![(0usize, Aabb::EMPTY); desc.objects.len()];
    let mut add = |object: u32, triangles: usize, b: Aabb| {
        if let Some((count, bounds)) = entry_of.get(object as usize).and_then(|&e| acc.get_mut(e)) {
            *count += triangles;
            *bounds = bounds.union(b);
        }
    };
    let geometry = world.geometry();
    for (i, t) in geometry.triangles.iter().enumerate() {
        let corners = geometry
            .corners(i)
            .into_iter()
            .fold(Aabb::EMPTY, Aabb::grow);
        add(t.object, 1, corners);
    }
    for (object, triangles, bounds) in world.instance_summary() {
        add(object, triangles, bounds);
    }
    desc.objects
        .iter()
        .zip(acc)
        .enumerate()
        .map(|(i, (o, (triangles, bounds)))| ObjectInfo {
            key: format!("objects[{i}]"),
            name: o.name.clone(),
            kind: o.kind(),
            triangles,
            bounds,
        })
        .collect()
}
