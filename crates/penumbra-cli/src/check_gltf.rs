//! `penumbra check model.glb` (or `.gltf`): the file read, and its scene built as `render`
//! would build it (so a missing or broken image fails here too), then summarized: triangles
//! (every node's use of a mesh counted, beside the unique ones), vertices, bounds after the
//! node transforms, meshes and instances, materials, textures, cameras, lights, extensions,
//! and warnings for what penumbra ignores (also on stderr).

use std::path::Path;

use penumbra::{inspect_gltf_in, Files, SceneFile};
use serde_json::json;

use crate::failure::{invalid, note, say, Failure};
use crate::summary::{bounds_json, bounds_text};

pub fn run(path: &Path, json: bool, files: &Files) -> Result<(), Failure> {
    let info = inspect_gltf_in(files, path)
        .map_err(|e| invalid(format!("{}: cannot load glTF: {e}", path.display())))?;
    SceneFile::load_allowing(path, &[], files.allowed().to_vec())
        .and_then(|file| file.build(0))
        .map_err(invalid)?;
    for w in &info.warnings {
        note(&format!("warning: {}: {w}", path.display()));
    }
    if json {
        let summary = json!({
            "mesh": path.display().to_string(),
            "triangles": info.triangles,
            "unique_triangles": info.unique_triangles,
            "vertices": info.vertices,
            "bounds": bounds_json(info.bounds),
            "normals": info.normals,
            "uvs": info.uvs,
            "meshes": info.meshes,
            "instances": info.instances,
            "materials": info.materials,
            "textures": info.textures,
            "cameras": info.cameras,
            "lights": info.lights,
            "extensions": info.extensions,
            "warnings": info.warnings,
        });
        return say(&summary.to_string());
    }
    let yes_no = |b: bool| if b { "yes" } else { "no" };
    let list = |v: &[String]| match v.is_empty() {
        true => String::new(),
        false => format!(" ({})", v.join(", ")),
    };
    let lines = [
        format!("{}: ok", path.display()),
        format!(
            "  triangles  {} ({} in memory: {} mesh{} placed {} time{})",
            info.triangles,
            info.unique_triangles,
            info.meshes,
            if info.meshes == 1 { "" } else { "es" },
            info.instances,
            if info.instances == 1 { "" } else { "s" }
        ),
        format!("  vertices   {}", info.vertices),
        format!("  bounds     {}", bounds_text(info.bounds)),
        format!(
            "  normals    {}, uvs {}",
            yes_no(info.normals),
            yes_no(info.uvs)
        ),
        format!(
            "  materials  {}{}",
            info.materials.len(),
            list(&info.materials)
        ),
        format!("  textures   {}", info.textures),
        format!("  cameras    {}{}", info.cameras.len(), list(&info.cameras)),
        format!("  lights     {}", info.lights),
        format!(
            "  extensions {}{}",
            info.extensions.len(),
            list(&info.extensions)
        ),
        format!("  warnings   {}", info.warnings.len()),
    ];
    say(&lines.join("\n"))
}
