//! PLY (Stanford polygon file format) meshes: the reader of `.ply` files, ASCII and binary in
//! either byte order, into the same object-space [`Mesh`] an OBJ file gives (every triangle
//! in material slot 0).
//!
//! - The `vertex` element gives positions from `x`, `y`, `z` (any numeric type), shading
//!   normals from `nx`, `ny`, `nz`, and uvs from the first complete pair of `u`/`v`, `s`/`t`,
//!   `texture_u`/`texture_v` or `texture_s`/`texture_t`. Without normals the mesh is shaded
//!   flat; a normal that is not finite is read as none (zero), which the integrator shades
//!   with the geometric normal. Without uvs every uv is (0, 0).
//! - The `face` element's `vertex_indices` (or `vertex_index`) list, of any integer count and
//!   index types, gives polygons, fan-triangulated as (0, i, i + 1) as OBJ faces are.
//! - Everything else is read and dropped: vertex colours (`red`, `green`, `blue`, `alpha`;
//!   penumbra has no vertex colours yet), other properties, other elements (`edge`,
//!   `material`, …), per-face `texcoord` lists, comments and `obj_info` lines. A binary
//!   file's skipped values still take their bytes.
//!
//! Every problem is a [`PlyError`] at a header or body line (ASCII) or byte offset (binary)
//! naming the element row and property, never a panic: a header that announces more rows
//! than the file holds (the body ends early), an index not below the vertex count, a negative
//! list count, a position that is not finite in 32 bits, a file without triangles. Memory
//! follows the bytes, not the header: nothing is reserved beyond what the rest of the file
//! can hold.
//!
//! A small reader of its own rather than a PLY crate: the crates read every row into a map of
//! named values (tens of bytes per value, several times the file), trust the header's counts
//! when reserving, and report errors without the line or byte; what penumbra needs (three
//! roles in two elements, everything else skipped) is a few hundred lines.

mod body;
mod header;
#[cfg(test)]
mod tests;

use std::fmt;
use std::path::Path;

use glam::{Vec2, Vec3};

use super::obj::{summarize, ObjInfo, ObjModel, MAX_FILE_BYTES};
use crate::files::Files;
use crate::geometry::Mesh;
use body::Body;
use header::{Element, Format, Kind, Property};

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

/// Reads the PLY file at `path` through `files`, within the size limit of OBJ files.
pub(crate) fn load_ply(files: &Files, path: &Path) -> Result<Mesh, PlyError> {
    let bytes = files
        .read(path, MAX_FILE_BYTES)
        .map_err(|e| PlyError::new(At::File, e.to_string()))?;
    parse_ply(&bytes)
}

/// [`load_ply`] as the model an OBJ file gives (without materials), for the scene's mesh
/// objects; the error is its message.
pub(crate) fn load_model(files: &Files, path: &Path) -> Result<ObjModel, String> {
    let mesh = load_ply(files, path).map_err(|e| e.to_string())?;
    Ok(ObjModel {
        mesh,
        materials: Vec::new(),
        mtl_files: Vec::new(),
    })
}

/// Reads the PLY file at `path` and summarizes it, as [`inspect_obj`](super::inspect_obj)
/// does an OBJ file (no materials). The error says what is wrong, with the line or byte.
pub fn inspect_ply(path: &Path) -> Result<ObjInfo, String> {
    Ok(summarize(&load_model(&Files::disk(), path)?))
}

/// [`inspect_ply`] for the bytes of a PLY file.
pub fn inspect_ply_bytes(bytes: &[u8]) -> Result<ObjInfo, String> {
    let mesh = parse_ply(bytes).map_err(|e| e.to_string())?;
    Ok(summarize(&ObjModel {
        mesh,
        materials: Vec::new(),
        mtl_files: Vec::new(),
    }))
}

/// What a vertex property is read into.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Role {
    /// Component `k` of the position.
    Position(usize),
    Normal(usize),
    Uv(usize),
    /// A face's corner list.
    Corners,
    Skip,
}

/// The names uvs go by, as (u, v) pairs in order of preference.
const UV_NAMES: [[&str; 2]; 4] = [
    ["u", "v"],
    ["s", "t"],
    ["texture_u", "texture_v"],
    ["texture_s", "texture_t"],
];

/// The role of each property of the `vertex` element, and whether it has normals and uvs.
fn vertex_roles(e: &Element) -> Result<(Vec<Role>, bool, bool), String> {
    let find = |name: &str| e.properties.iter().position(|p| p.name == name);
    let mut roles = vec![Role::Skip; e.properties.len()];
    let mut assign = |names: &[&str], role: fn(usize) -> Role| -> Result<bool, String> {
        let Some(found) = names.iter().map(|n| find(n)).collect::<Option<Vec<_>>>() else {
            return Ok(false);
        };
        for (k, i) in found.into_iter().enumerate() {
            if let Kind::List { .. } = e.properties[i].kind {
                return Err(format!(
                    "element `vertex`: property {} is a list, not a number",
                    quoted(&e.properties[i].name)
                ));
            }
            roles[i] = role(k);
        }
        Ok(true)
    };
    if !assign(&["x", "y", "z"], Role::Position)? {
        return Err("element `vertex` lacks one of the properties `x`, `y`, `z`".into());
    }
    let normals = assign(&["nx", "ny", "nz"], Role::Normal)?;
    let mut uvs = false;
    for pair in UV_NAMES {
        if assign(&pair, Role::Uv)? {
            uvs = true;
            break;
        }
    }
    Ok((roles, normals, uvs))
}

/// The role of each property of the `face` element: its first `vertex_indices` or
/// `vertex_index` list gives the corners.
fn face_roles(e: &Element) -> Result<Vec<Role>, String> {
    let corners = e
        .properties
        .iter()
        .position(|p| p.name == "vertex_indices" || p.name == "vertex_index")
        .ok_or("element `face` has no `vertex_indices` (or `vertex_index`) property")?;
    match e.properties[corners].kind {
        Kind::List { item, .. } if !item.is_float() => {}
        _ => {
            return Err(format!(
                "element `face`: property {} must be a list of integers",
                quoted(&e.properties[corners].name)
            ))
        }
    }
    let mut roles = vec![Role::Skip; e.properties.len()];
    roles[corners] = Role::Corners;
    Ok(roles)
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

/// Reads the bytes of a PLY file into a mesh.
pub(crate) fn parse_ply(bytes: &[u8]) -> Result<Mesh, PlyError> {
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
    let mut mesh = Mesh::default();
    for element in &header.elements {
        if element.properties.is_empty() {
            // Rows without values take no bytes, however many the header announces.
            continue;
        }
        let roles = match element.name.as_str() {
            "vertex" => {
                let (roles, normals, uvs) = vertex_roles(element).map_err(at_file)?;
                let n = reservable(element, &body);
                mesh.positions.reserve(n);
                mesh.normals.reserve(if normals { n } else { 0 });
                mesh.uvs.reserve(if uvs { n } else { 0 });
                roles
            }
            "face" => {
                mesh.indices.reserve(reservable(element, &body));
                face_roles(element).map_err(at_file)?
            }
            _ => vec![Role::Skip; element.properties.len()],
        };
        read_rows(&mut body, element, &roles, vertex_count, &mut mesh)?;
    }
    if mesh.indices.is_empty() {
        return Err(at_file(
            "no triangles (no `face` element, or only empty ones): nothing to render".into(),
        ));
    }
    mesh.material_slots = vec![0; mesh.indices.len()];
    Ok(mesh)
}

/// How many rows of `element` the rest of `body` can hold (at most its count).
fn reservable(element: &Element, body: &Body) -> usize {
    let fit = body.left() / row_bytes(&element.properties, body.format());
    (element.count.min(fit as u64)) as usize
}

/// Reads every row of `element`, each property into its role in `mesh`.
fn read_rows(
    body: &mut Body,
    element: &Element,
    roles: &[Role],
    vertex_count: u64,
    mesh: &mut Mesh,
) -> Result<(), PlyError> {
    let mut corners: Vec<u32> = Vec::new();
    let (mut p, mut n, mut uv) = ([0f32; 3], [0f32; 3], [0f32; 2]);
    let [vertex, normals, uvs] =
        [Role::Position(0), Role::Normal(0), Role::Uv(0)].map(|r| roles.contains(&r));
    for row in 0..element.count {
        for (property, &role) in element.properties.iter().zip(roles) {
            // The element row and property, for an error.
            let locate = |e: PlyError| {
                let message = format!(
                    "element {} row {row}, property {}: {}",
                    quoted(&element.name),
                    quoted(&property.name),
                    e.message
                );
                PlyError::new(e.at, message)
            };
            let (ty, count_ty) = match property.kind {
                Kind::Scalar(t) => (t, None),
                Kind::List { count, item } => (item, Some(count)),
            };
            let Some(count_ty) = count_ty else {
                let value = body.scalar(ty).map_err(locate)?;
                let narrow = value as f32;
                match role {
                    Role::Position(_) if !narrow.is_finite() => {
                        let m = format!("{value} is not a finite number (in 32 bits)");
                        return Err(locate(PlyError::new(body.at(), m)));
                    }
                    Role::Uv(_) if !narrow.is_finite() => {
                        let m = format!("texture coordinate {value} is not a finite number");
                        return Err(locate(PlyError::new(body.at(), m)));
                    }
                    Role::Position(k) => p[k] = narrow,
                    Role::Normal(k) => n[k] = narrow,
                    Role::Uv(k) => uv[k] = narrow,
                    Role::Corners | Role::Skip => {}
                }
                continue;
            };
            let len = body.count(count_ty).map_err(locate)?;
            if role != Role::Corners {
                body.skip(ty, len).map_err(locate)?;
                continue;
            }
            corners.clear();
            for _ in 0..len {
                let i = body.scalar(ty).map_err(locate)?;
                if i < 0.0 || i >= vertex_count as f64 {
                    let m = format!(
                        "vertex index {i} is out of range (the file has {vertex_count} vertices)"
                    );
                    return Err(locate(PlyError::new(body.at(), m)));
                }
                corners.push(i as u32);
            }
            if len < 3 {
                let m = format!("a face needs at least 3 vertices, this one has {len}");
                return Err(locate(PlyError::new(body.at(), m)));
            }
            if (mesh.indices.len() + corners.len() - 2) as u64 > MAX_TRIANGLES {
                let m = "the mesh is too large (more than a billion triangles)";
                return Err(locate(PlyError::new(body.at(), m)));
            }
            for k in 1..corners.len() - 1 {
                mesh.indices.push([corners[0], corners[k], corners[k + 1]]);
            }
        }
        if vertex {
            mesh.positions.push(Vec3::from(p));
            if normals {
                let n = Vec3::from(n);
                mesh.normals
                    .push(if n.is_finite() { n } else { Vec3::ZERO });
            }
            if uvs {
                mesh.uvs.push(Vec2::from(uv));
            }
        }
    }
    Ok(())
}
