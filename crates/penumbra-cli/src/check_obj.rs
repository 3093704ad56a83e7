//! `penumbra check model.obj` (or `model.ply`): a Wavefront OBJ or PLY mesh on its own, to
//! place it in a scene: triangles, bounds (in the file's own units and axes), materials and
//! their textures, whether it has normals, uvs and vertex colours, whether it is closed, and
//! warnings (on stderr) for what the file holds that penumbra ignores.

use std::path::{Path, PathBuf};

use penumbra::{inspect_obj_in, inspect_ply};
use serde_json::json;

use crate::failure::{invalid, note, say, Failure};
use crate::summary::{bounds_json, bounds_text};

/// True for a path naming a mesh file: OBJ or PLY, by its extension in any case.
pub fn is_mesh(path: &Path) -> bool {
    penumbra::ModelFormat::from_path(path).is_some()
}

fn has_extension(path: &Path, extension: &str) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case(extension))
}

pub fn run(path: &Path, json: bool, allowed: &[PathBuf]) -> Result<(), Failure> {
    let files = crate::input::files(allowed)?;
    if penumbra::ModelFormat::from_path(path) == Some(penumbra::ModelFormat::Gltf) {
        return crate::check_gltf::run(path, json, &files);
    }
    let info = match has_extension(path, "ply") {
        true => inspect_ply(path),
        false => inspect_obj_in(&files, path),
    }
    .map_err(|e| invalid(format!("{}: cannot load mesh: {e}", path.display())))?;
    let textures: Vec<String> = info
        .materials
        .iter()
        .filter_map(|(_, t)| t.as_ref().map(|t| t.display().to_string()))
        .collect();
    let names: Vec<&str> = info.materials.iter().map(|(n, _)| n.as_str()).collect();
    for w in &info.warnings {
        note(&format!("warning: {}: {w}", path.display()));
    }
    if json {
        let summary = json!({
            "mesh": path.display().to_string(),
            "triangles": info.triangles,
            "vertices": info.vertices,
            "bounds": bounds_json(info.bounds),
            "normals": info.normals,
            "uvs": info.uvs,
            "colors": info.colors,
            "materials": names,
            "textures": textures,
            "closed": info.closed,
            "warnings": info.warnings,
        });
        return say(&summary.to_string());
    }
    let yes_no = |b: bool| if b { "yes" } else { "no" };
    let lines = [
        format!("{}: ok", path.display()),
        format!("  triangles  {}", info.triangles),
        format!("  vertices   {}", info.vertices),
        format!("  bounds     {}", bounds_text(info.bounds)),
        format!(
            "  normals    {}, uvs {}, colours {}",
            yes_no(info.normals),
            yes_no(info.uvs),
            yes_no(info.colors)
        ),
        format!(
            "  materials  {}{}",
            names.len(),
            if names.is_empty() {
                String::new()
            } else {
                format!(" ({})", names.join(", "))
            }
        ),
        format!(
            "  textures   {}{}",
            textures.len(),
            if textures.is_empty() {
                String::new()
            } else {
                format!(" ({})", textures.join(", "))
            }
        ),
        format!("  closed     {}", yes_no(info.closed)),
    ];
    say(&lines.join("\n"))
}
