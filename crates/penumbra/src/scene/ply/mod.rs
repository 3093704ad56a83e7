//! PLY (Stanford polygon file format) meshes: the reader of `.ply` files, ASCII and binary in
//! either byte order, into the same object-space [`Mesh`] an OBJ file gives (every triangle
//! in material slot 0).
//!
//! - The `vertex` element gives positions from `x`, `y`, `z` (any numeric type), shading
//!   normals from `nx`, `ny`, `nz`, uvs from the first complete pair of `u`/`v`, `s`/`t`,
//!   `texture_u`/`texture_v` or `texture_s`/`texture_t`, and vertex colours from `red`,
//!   `green`, `blue` (or `diffuse_red`, …; see `color` for their encoding). Without normals
//!   the mesh is shaded flat; a normal that is not finite is read as none (zero), which the
//!   integrator shades with the geometric normal. Without uvs every uv is (0, 0).
//! - The `face` element's `vertex_indices` (or `vertex_index`) list, of any integer count and
//!   index types, gives polygons, fan-triangulated as (0, i, i + 1) as OBJ faces are. A
//!   `texcoord` list (MeshLab, VCGlib: two values per corner) gives the corners' uvs, and
//!   vertices are split where their faces disagree (see `texcoords`).
//! - A `comment TextureFile NAME` line names the diffuse texture, as an MTL's `map_Kd` would
//!   (relative to the PLY file's folder); only the first is used.
//! - Everything else is read and dropped, and [`inspect_ply`] names it once in its warnings:
//!   vertex `alpha`, other properties, other elements (`edge`, `material`, …). Comments and
//!   `obj_info` lines are ignored. A binary file's skipped values still take their bytes.
//!
//! Every problem is a [`PlyError`] at a header or body line (ASCII) or byte offset (binary)
//! naming the element row and property, never a panic: a header that announces more rows
//! than the file holds (the body ends early), an index not below the vertex count, a negative
//! list count, a position, uv or colour that is not finite in 32 bits, a file without
//! triangles. Memory follows the bytes, not the header: nothing is reserved beyond what the
//! rest of the file can hold.
//!
//! A small reader of its own rather than a PLY crate: the crates read every row into a map of
//! named values (tens of bytes per value, several times the file), trust the header's counts
//! when reserving, and report errors without the line or byte; what penumbra needs (a few
//! roles in two elements, everything else skipped) is a few hundred lines. Binary bodies of
//! the usual layouts are read in bulk (`fast`), everything else value by value (`rows`).

mod body;
mod color;
mod fast;
mod header;
mod roles;
mod rows;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_errors;
mod texcoords;

use std::fmt;
use std::path::Path;

use super::obj::{mesh_bounds, summarize, ObjInfo, ObjMaterial, ObjModel, MAX_FILE_BYTES};
use crate::files::Files;
use crate::geometry::Mesh;
use crate::math::Aabb;
use crate::reach::Reach;
use body::Body;
use header::{Element, Format, Kind, Property};
use roles::{face_roles, ignored, vertex_roles, Role};
use rows::{read_rows, Sink};

/// The most triangles a mesh may have: indices are 32-bit (as for OBJ files).
const MAX_TRIANGLES: u64 = (u32::MAX / 4) as u64;

/// Where in a PLY file a problem is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum At {
    /// A line of the header or of an ASCII body (1-based).
    Line(usize),
    /// A byte offset into the file (binary body).
    Byte(usize),
    /// The file as a whole.
    File,
}

/// A PLY file that cannot be read: where, and what is wrong (naming the element row and the
/// property when there is one). It does not name the file; the caller does.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlyError {
    /// Where the problem is.
    pub at: At,
    /// What is wrong, one line.
    pub message: String,
}

impl PlyError {
    fn new(at: At, message: impl Into<String>) -> PlyError {
        PlyError {
            at,
            message: message.into(),
        }
    }
}

impl fmt::Display for PlyError {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self.at {
            At::Line(n) => write!(f, "line {n}: {}", self.message),
            At::Byte(n) => write!(f, "byte {n}: {}", self.message),
            At::File => f.write_str(&self.message),
        }
    }
}

impl std::error::Error for PlyError {}

/// A name from the file, in backquotes, with any control character escaped.
fn quoted(name: &str) -> String {
    format!("`{}`", name.escape_debug())
}

/// True for a path naming a PLY file (by its extension, in any case).
pub(crate) fn is_ply(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("ply"))
}

/// What a PLY file gives: its mesh, the texture file its first `comment TextureFile` line
/// names (as written), and what of it is read but ignored, each named once.
#[derive(Debug)]
pub(crate) struct PlyModel {
    pub mesh: Mesh,
    pub texture_file: Option<String>,
    pub warnings: Vec<String>,
}

/// Reads the PLY file at `path` through `files`, within the size limit of OBJ files.
pub(crate) fn load_ply(files: &Files, path: &Path) -> Result<PlyModel, PlyError> {
    let bytes = files
        .read(path, MAX_FILE_BYTES)
        .map_err(|e| PlyError::new(At::File, e.to_string()))?;
    read_ply(&bytes)
}

/// [`load_ply`] as the model an OBJ file gives, for the scene's mesh objects: a texture file
/// becomes one material with it as `map_Kd` (resolved against the PLY file's folder), which
/// every triangle uses; it must be in the PLY file's folder or below, or in a folder `files`
/// allows (see the module `reach`); a texture file that is not there is dropped with a warning
/// (see [`drop_missing_textures`]). The error is its message; the warnings come beside the
/// model.
pub(crate) fn load_model(files: &Files, path: &Path) -> Result<(ObjModel, Vec<String>), String> {
    let ply = load_ply(files, path).map_err(|e| e.to_string())?;
    if let Some(name) = &ply.texture_file {
        let dir = path.parent().unwrap_or(Path::new(""));
        Reach::new(files, path, dir, "model")
            .resolve(dir, name)
            .map_err(|e| format!("`comment TextureFile` {e}"))?;
    }
    let (mut model, mut warnings) = model(ply, path);
    drop_missing_textures(files, &mut model, &mut warnings);
    Ok((model, warnings))
}

/// Drops the material of a `TextureFile` that `files` does not have, with a warning: the
/// geometry is read without its texture (default material), as trimesh and MeshLab read it,
/// rather than the whole file refused.
fn drop_missing_textures(files: &Files, model: &mut ObjModel, warnings: &mut Vec<String>) {
    model.materials.retain(|m| match &m.diffuse_texture {
        Some(t) if !files.is_file(t) => {
            warnings.push(format!(
                "the texture file \"{}\" (`comment TextureFile`) is not there: the mesh is \
                 read without it",
                t.display()
            ));
            false
        }
        _ => true,
    });
}

/// The OBJ model of `ply`, read from `path`, and its warnings.
fn model(ply: PlyModel, path: &Path) -> (ObjModel, Vec<String>) {
    let dir = path.parent().unwrap_or(Path::new(""));
    let materials = ply
        .texture_file
        .map(|name| ObjMaterial {
            name: "TextureFile".into(),
            diffuse_texture: Some(dir.join(name)),
            ..ObjMaterial::default()
        })
        .into_iter()
        .collect();
    let model = ObjModel {
        mesh: ply.mesh,
        materials,
        mtl_files: Vec::new(),
    };
    (model, ply.warnings)
}

/// Reads the PLY file at `path` and summarizes it, as [`inspect_obj`](super::inspect_obj)
/// does an OBJ file, with the warnings of what it holds that penumbra ignores. The error says
/// what is wrong, with the line or byte.
pub fn inspect_ply(path: &Path) -> Result<ObjInfo, String> {
    let (model, warnings) = load_model(&Files::disk(), path)?;
    Ok(ObjInfo {
        warnings,
        ..summarize(&model)
    })
}

/// The bounds of the PLY file at `path`: all a model's scene needs (see `obj_bounds`).
pub(crate) fn ply_bounds(path: &Path) -> Result<Aabb, String> {
    let ply = load_ply(&Files::disk(), path).map_err(|e| e.to_string())?;
    Ok(mesh_bounds(&ply.mesh))
}

/// [`inspect_ply`] for the bytes of a PLY file (a texture file it names is relative to the
/// current folder).
pub fn inspect_ply_bytes(bytes: &[u8]) -> Result<ObjInfo, String> {
    let ply = read_ply(bytes).map_err(|e| e.to_string())?;
    Ok(summary(ply, Path::new("")))
}

/// The summary of `ply` read from `path`, with its warnings.
fn summary(ply: PlyModel, path: &Path) -> ObjInfo {
    let (model, warnings) = model(ply, path);
    ObjInfo {
        warnings,
        ..summarize(&model)
    }
}

/// The fewest bytes a row of `properties` takes in a body of `format`: what reservations are
/// measured against, so that a header's counts never reserve more than the file can hold.
fn row_bytes(properties: &[Property], format: Format) -> usize {
    let binary = |p: &Property| match p.kind {
        Kind::Scalar(t) | Kind::List { count: t, .. } => t.size(),
    };
    match format {
        // A word and a separator for each value (the last one's may be the end of the file).
        Format::Ascii => 2 * properties.len(),
        _ => properties.iter().map(binary).sum(),
    }
    .max(1)
}

/// Reads the bytes of a PLY file into a mesh (for the tests).
#[cfg(test)]
fn parse_ply(bytes: &[u8]) -> Result<Mesh, PlyError> {
    read_ply(bytes).map(|m| m.mesh)
}

/// Reads the bytes of a PLY file.
pub(crate) fn read_ply(bytes: &[u8]) -> Result<PlyModel, PlyError> {
    let header = header::parse(bytes)?;
    let at_file = |m: String| PlyError::new(At::File, m);
    let vertex_count = {
        let mut vertices = header.elements.iter().filter(|e| e.name == "vertex");
        let first = vertices
            .next()
            .ok_or_else(|| at_file("no `vertex` element".into()))?;
        if vertices.next().is_some() {
            return Err(at_file("more than one `vertex` element".into()));
        }
        // Checked before any row is read, so that the vertex rows are never empty.
        vertex_roles(first).map_err(at_file)?;
        first.count
    };
    if header.elements.iter().filter(|e| e.name == "face").count() > 1 {
        return Err(at_file("more than one `face` element".into()));
    }
    let mut body = Body::new(bytes, header.format, header.body, header.body_line);
    let mut out = Sink {
        mesh: Mesh::default(),
        texcoords: Vec::new(),
        decoder: color::Decoder::new(),
    };
    let mut warnings = Vec::new();
    for element in &header.elements {
        let roles = match element.name.as_str() {
            "vertex" => {
                let v = vertex_roles(element).map_err(at_file)?;
                let n = reservable(element, &body);
                let mesh = &mut out.mesh;
                mesh.positions.reserve(n);
                mesh.normals.reserve(if v.normals { n } else { 0 });
                mesh.uvs.reserve(if v.uvs { n } else { 0 });
                mesh.colors.reserve(if v.colors { n } else { 0 });
                Some(v.roles)
            }
            "face" => {
                out.mesh.indices.reserve(reservable(element, &body));
                Some(face_roles(element).map_err(at_file)?)
            }
            _ => None,
        };
        warnings.extend(ignored(element, roles.as_deref()));
        if element.properties.is_empty() {
            // Rows without values take no bytes, however many the header announces.
            continue;
        }
        let roles = roles.unwrap_or_else(|| vec![Role::Skip; element.properties.len()]);
        let first = match element.name.as_str() {
            "vertex" => fast::vertex_rows(&mut body, element, &roles, &mut out),
            "face" => fast::face_rows(&mut body, element, vertex_count, &mut out),
            _ => 0,
        };
        let extra = read_rows(&mut body, element, &roles, vertex_count, first, &mut out)?;
        if extra.values > 0 {
            warnings.push(format!(
                "{} value(s) at the ends of {} {} row(s), beyond the header's properties, are \
                 ignored (the first on line {})",
                extra.values,
                extra.rows,
                quoted(&element.name),
                extra.first_line
            ));
        }
    }
    let Sink {
        mut mesh,
        texcoords,
        ..
    } = out;
    if mesh.indices.is_empty() {
        return Err(at_file(
            "no triangles (no `face` element, or only empty ones): nothing to render".into(),
        ));
    }
    if !texcoords.is_empty() {
        texcoords::split_vertices(&mut mesh, &texcoords);
    }
    mesh.material_slots = vec![0; mesh.indices.len()];
    warnings.extend(texture_warnings(&header.texture_files, &mesh));
    Ok(PlyModel {
        mesh,
        texture_file: header.texture_files.into_iter().next(),
        warnings,
    })
}

/// Warnings about the texture files a header names: beyond the first, or without uvs.
fn texture_warnings(files: &[String], mesh: &Mesh) -> Vec<String> {
    let mut warnings = Vec::new();
    if files.len() > 1 {
        let rest: Vec<String> = files[1..].iter().map(|f| quoted(f)).collect();
        warnings.push(format!(
            "only the first `comment TextureFile` is used; ignored: {}",
            rest.join(", ")
        ));
    }
    if let Some(first) = files.first().filter(|_| !mesh.has_uvs()) {
        warnings.push(format!(
            "the texture file {} is named but the mesh has no texture coordinates",
            quoted(first)
        ));
    }
    warnings
}

/// How many rows of `element` the rest of `body` can hold (at most its count).
fn reservable(element: &Element, body: &Body) -> usize {
    let fit = body.left() / row_bytes(&element.properties, body.format());
    (element.count.min(fit as u64)) as usize
}
