//! `penumbra check`: load and build a scene, then print what it holds: totals, each object's
//! triangles and bounds, and warnings (on stderr; see `warnings`) for scene mistakes. A
//! `.obj` file is summarized on its own (see `check_obj`).

use std::path::Path;

use penumbra::{desc::ShapeDesc, Aabb, SceneDesc, World};
use serde_json::{json, Value};

use crate::args::CheckArgs;
use crate::check_obj;
use crate::failure::{invalid, note, say, Failure};
use crate::input;
use crate::summary::{bounds_json, bounds_text, light_samples};
use crate::warnings::{light_warnings, unused_warnings, view_warnings};

pub fn run(args: &CheckArgs) -> Result<(), Failure> {
    let path: &Path = &args.scene;
    if check_obj::is_obj(path) {
        if let Some(o) = args.set.first() {
            return Err(invalid(format!(
                "--set {o}: overrides change scene keys, and a .obj mesh has none (check a scene that places the mesh instead)"
            )));
        }
        return check_obj::run(path, args.json);
    }
    let file = input::load(path, &args.set, input::Reader::Check)?;
    let scene = file.build(0).map_err(invalid)?;
    let world = &scene.world;
    let name = if input::is_stdin(path) {
        input::STDIN_NAME.to_owned()
    } else {
        path.display().to_string()
    };
    let objects = objects(world, &file.desc);
    let bounds: Vec<(String, Aabb)> = objects.iter().map(|o| (o.key.clone(), o.bounds)).collect();
    let aspect = scene.settings.width as f32 / scene.settings.height as f32;
    let mut warnings = light_warnings(world, scene.settings.light_model);
    warnings.extend(unused_warnings(&file.desc));
    warnings.extend(view_warnings(world, aspect, &bounds));
    for w in &warnings {
        note(&format!("warning: {name}: {w}"));
    }
    let s = world.stats();
    let settings = &scene.settings;
    let cameras: Vec<&str> = world.cameras().iter().map(|(n, _)| n.as_str()).collect();
    if args.json {
        let summary = json!({
            "scene": name,
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
            "bounds": bounds_json(world.bounds()),
            "objects": objects.iter().map(|o| json!({
                "key": o.key,
                "type": o.kind,
                "triangles": o.triangles,
                "bounds": bounds_json(o.bounds),
            })).collect::<Vec<Value>>(),
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
        format!("  triangles  {}", s.triangles),
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
        format!("  materials  {}", s.materials),
        format!("  textures   {}", s.textures),
        format!("  cameras    {}", cameras.join(", ")),
        format!("  bounds     {}", bounds_text(world.bounds())),
        format!("  objects    {}", objects.len()),
    ];
    let key_width = objects.iter().map(|o| o.key.len()).max().unwrap_or(0);
    let kind_width = objects.iter().map(|o| o.kind.len()).max().unwrap_or(0);
    for o in &objects {
        lines.push(format!(
            "    {:key_width$}  {:kind_width$}  {:>7} triangles  {}",
            o.key,
            o.kind,
            o.triangles,
            bounds_text(o.bounds)
        ));
    }
    say(&lines.join("\n"))
}

/// One object of the scene as `check` lists it.
struct ObjectInfo {
    /// `objects[i]`.
    key: String,
    /// Its type, and the file for a mesh: `mesh models/bunny.obj`.
    kind: String,
    triangles: usize,
    bounds: Aabb,
}

/// Each object's triangles and world-space bounds, in file order (object ids are file
/// indexes: every `[[objects]]` entry adds one object).
fn objects(world: &World, desc: &SceneDesc) -> Vec<ObjectInfo> {
    let mut acc = vec![(0usize, Aabb::EMPTY); desc.objects.len()];
    let geometry = world.geometry();
    for (i, t) in geometry.triangles.iter().enumerate() {
        if let Some((count, bounds)) = acc.get_mut(t.object as usize) {
            *count += 1;
            *bounds = geometry.corners(i).into_iter().fold(*bounds, Aabb::grow);
        }
    }
    desc.objects
        .iter()
        .zip(acc)
        .enumerate()
        .map(|(i, (o, (triangles, bounds)))| ObjectInfo {
            key: format!("objects[{i}]"),
            kind: match &o.shape {
                ShapeDesc::Triangle(_) => "triangle".to_owned(),
                ShapeDesc::Quad(_) => "quad".to_owned(),
                ShapeDesc::Cube(_) => "cube".to_owned(),
                ShapeDesc::Sphere(_) => "sphere".to_owned(),
                ShapeDesc::Mesh(m) => format!("mesh {}", m.file),
            },
            triangles,
            bounds,
        })
        .collect()
}
