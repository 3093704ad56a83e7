//! Wavefront OBJ meshes: the reader of `.obj` files and the assembly of their faces into one
//! indexed triangle mesh. Their MTL material libraries are read by [`mtl`], and the line rules
//! both file kinds share (comments, continuations) live in [`lines`].
//!
//! A small reader of its own rather than a general OBJ crate, so that every face keeps exactly
//! the data it has and every problem is an error message with a line number, never a panic:
//!
//! - `v`, `vt`, `vn` and `f` (also `fo`) statements; polygons are fan-triangulated as
//!   (0, i, i + 1). Indices are 1-based; negative indices count back from the last element
//!   defined so far. A face corner may be `v`, `v/vt`, `v//vn` or `v/vt/vn`, and corners of
//!   one face may mix these forms.
//! - A corner without `vt` has uv (0, 0). A face whose corners all have a usable `vn` (finite,
//!   non-zero) is shaded smoothly; any other face is flat. When a file mixes the two, the flat
//!   faces get vertices of their own whose normals are zero, which the integrator reads as
//!   "no shading normal" and so shades with the geometric normal.
//! - `mtllib` (relative to the OBJ file's folder; several names on one line are allowed) and
//!   `usemtl`. Materials are assigned by `usemtl` only; `o` and `g` are ignored, as are `s`,
//!   `l`, `p` and every other statement. A `usemtl` name that no library defines leaves its
//!   faces with the default material. Only the materials that faces use are returned, in order
//!   of first use, so an unused material's missing texture is not an error.
//! - `#` starts a comment anywhere on a line; a line ending in `\` continues on the next one;
//!   CRLF line endings, tabs, a UTF-8 byte-order mark and bytes that are not UTF-8 are fine.

mod lines;
mod mtl;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use crate::geometry::Mesh;

use lines::{for_each_line, numbers, rest_of_line};
use mtl::{resolve, Library};

/// A material from an MTL file.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ObjMaterial {
    pub name: String,
    pub diffuse: Option<[f32; 3]>,
    pub ambient: Option<[f32; 3]>,
    pub specular: Option<[f32; 3]>,
    pub shininess: Option<f32>,
    /// `map_Kd`, resolved against the MTL file's folder.
    pub diffuse_texture: Option<PathBuf>,
}

/// An OBJ file as one mesh. Triangle material slot `k < materials.len()` is `materials[k]`;
/// slot `materials.len()` marks faces without a (known) `usemtl` material.
#[derive(Clone, Debug)]
pub(crate) struct ObjModel {
    pub mesh: Mesh,
    pub materials: Vec<ObjMaterial>,
}

/// Largest OBJ file read: 4 GiB of text is some 100 million triangles, about what memory holds.
const MAX_FILE_BYTES: u64 = 4 << 30;
/// The most triangles a mesh may have: indices are 32-bit.
const MAX_TRIANGLES: usize = (u32::MAX / 4) as usize;
/// "No index": a corner without `vt` or `vn`, a face without `usemtl`.
const NONE: u32 = u32::MAX;

/// One polygon: `corners[first..first + len]`, its `usemtl` name (an index into the names
/// seen, or `NONE`) and the line it was read from.
struct Face {
    first: usize,
    len: u32,
    material: u32,
    line: u32,
}

/// Everything read from an OBJ file, indices already 0-based but not yet checked against the
/// final counts (a positive index may refer to a vertex defined further down).
#[derive(Default)]
struct ObjData {
    positions: Vec<Vec3>,
    uvs: Vec<Vec2>,
    normals: Vec<Vec3>,
    /// (v, vt, vn) per face corner; `NONE` for a missing vt or vn.
    corners: Vec<[u32; 3]>,
    faces: Vec<Face>,
    triangles: usize,
    /// Names given to `usemtl`, in order of first appearance.
    material_names: Vec<String>,
    library: Library,
}

/// Loads `path`. Errors are messages that do not repeat the OBJ file's path (the caller adds
/// it) but do name any other file involved.
pub(crate) fn load_obj(path: &Path) -> Result<ObjModel, String> {
    let size = std::fs::metadata(path).map_err(|e| e.to_string())?.len();
    if size > MAX_FILE_BYTES {
        return Err(format!(
            "the file is too large for memory ({size} bytes; at most {MAX_FILE_BYTES})"
        ));
    }
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    let text = String::from_utf8_lossy(&bytes);
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut data = ObjData::default();
    let mut names: HashMap<String, u32> = HashMap::new();
    let mut current_material = NONE;
    for_each_line(&text, |n, line| {
        let at = |message: String| format!("line {n}: {message}");
        let mut words = line.split_ascii_whitespace();
        let Some(keyword) = words.next() else {
            return Ok(());
        };
        match keyword {
            "v" => {
                let p = numbers::<3>(&mut words, 3)
                    .ok_or_else(|| at("a vertex `v` needs three numbers (x y z)".into()))?;
                if !p.iter().all(|c| c.is_finite()) {
                    return Err(at("a vertex coordinate is not a finite number".into()));
                }
                data.positions.push(Vec3::from(p));
            }
            "vt" => {
                let t = numbers::<2>(&mut words, 1)
                    .ok_or_else(|| at("a texture coordinate `vt` needs numbers (u [v])".into()))?;
                if !t.iter().all(|c| c.is_finite()) {
                    return Err(at("a texture coordinate is not a finite number".into()));
                }
                data.uvs.push(Vec2::from(t));
            }
            "vn" => {
                let v = numbers::<3>(&mut words, 3)
                    .ok_or_else(|| at("a normal `vn` needs three numbers (x y z)".into()))?;
                // A non-finite normal is kept and makes its faces flat (see `usable`).
                data.normals.push(Vec3::from(v));
            }
            "f" | "fo" => {
                let first = data.corners.len();
                for word in words {
                    let corner = parse_corner(
                        word,
                        [data.positions.len(), data.uvs.len(), data.normals.len()],
                    )
                    .map_err(at)?;
                    data.corners.push(corner);
                }
                let len = data.corners.len() - first;
                if len < 3 {
                    return Err(at(format!(
                        "a face needs at least 3 vertices, this one has {len}"
                    )));
                }
                data.triangles += len - 2;
                if data.triangles > MAX_TRIANGLES {
                    return Err("the mesh is too large (more than a billion triangles)".to_owned());
                }
                data.faces.push(Face {
                    first,
                    len: u32::try_from(len).map_err(|_| at("the face is too large".into()))?,
                    material: current_material,
                    line: n as u32,
                });
            }
            "usemtl" => {
                let name = rest_of_line(line, keyword);
                current_material = if name.is_empty() {
                    NONE
                } else {
                    let next = data.material_names.len() as u32;
                    *names.entry(name.to_owned()).or_insert_with(|| {
                        data.material_names.push(name.to_owned());
                        next
                    })
                };
            }
            "mtllib" => {
                let rest = rest_of_line(line, keyword);
                if rest.is_empty() {
                    return Ok(());
                }
                // One file name with spaces, or several names separated by spaces.
                let files: Vec<&str> = if dir.join(rest).is_file() {
                    vec![rest]
                } else {
                    rest.split_ascii_whitespace().collect()
                };
                for f in files {
                    data.library.load(resolve(dir, f))?;
                }
            }
            _ => {}
        }
        Ok(())
    })?;
    build_mesh(data)
}

/// Checks every index, then turns the faces into an indexed triangle mesh: one vertex per
/// distinct (v, vt, vn) corner, fan triangulation, per-triangle material slots.
fn build_mesh(data: ObjData) -> Result<ObjModel, String> {
    let counts = [data.positions.len(), data.uvs.len(), data.normals.len()];
    for face in &data.faces {
        for c in &data.corners[face.first..face.first + face.len as usize] {
            for (k, what) in ["vertex", "texture coordinate", "normal"]
                .iter()
                .enumerate()
            {
                if c[k] != NONE && c[k] as usize >= counts[k] {
                    return Err(format!(
                        "line {}: {what} index {} is out of range (the file has {} {})",
                        face.line,
                        c[k] as u64 + 1,
                        counts[k],
                        ["`v`", "`vt`", "`vn`"][k],
                    ));
                }
            }
        }
    }

    let usable = |vn: u32| {
        vn != NONE && {
            let n = data.normals[vn as usize];
            n.is_finite() && n.length_squared() > 0.0
        }
    };
    let smooth_face = |face: &Face| {
        data.corners[face.first..face.first + face.len as usize]
            .iter()
            .all(|c| usable(c[2]))
    };
    let any_smooth = data.faces.iter().any(smooth_face);
    let any_uv = data.corners.iter().any(|c| c[1] != NONE);

    // Materials in order of first use; slot `used.len()` is "no material".
    let mut slot_of_name = vec![NONE; data.material_names.len()];
    let mut slot_of_library = vec![NONE; data.library.len()];
    let mut materials = Vec::new();
    for face in &data.faces {
        let m = face.material;
        if m == NONE || slot_of_name[m as usize] != NONE {
            continue;
        }
        let name = &data.material_names[m as usize];
        if let Some((lib, material)) = data.library.find(name) {
            if slot_of_library[lib] == NONE {
                slot_of_library[lib] = materials.len() as u32;
                materials.push(material.clone());
            }
            slot_of_name[m as usize] = slot_of_library[lib];
        }
    }
    let no_material = materials.len() as u32;

    let mut mesh = Mesh {
        indices: Vec::with_capacity(data.triangles),
        material_slots: Vec::with_capacity(data.triangles),
        ..Mesh::default()
    };
    // The output vertices made from each `v`, as a linked list through `next`, keyed by
    // (vt, vn).
    let mut head = vec![NONE; data.positions.len()];
    let mut next: Vec<u32> = Vec::new();
    let mut keys: Vec<(u32, u32)> = Vec::new();
    let mut face_vertices: Vec<u32> = Vec::new();
    for face in &data.faces {
        let smooth = any_smooth && smooth_face(face);
        face_vertices.clear();
        for &[v, vt, vn] in &data.corners[face.first..face.first + face.len as usize] {
            let key = (vt, if smooth { vn } else { NONE });
            let mut i = head[v as usize];
            while i != NONE && keys[i as usize] != key {
                i = next[i as usize];
            }
            if i == NONE {
                i = u32::try_from(mesh.positions.len())
                    .ok()
                    .filter(|&i| i != NONE)
                    .ok_or("the mesh is too large (more than four billion vertices)")?;
                mesh.positions.push(data.positions[v as usize]);
                if any_uv {
                    mesh.uvs.push(if vt == NONE {
                        Vec2::ZERO
                    } else {
                        data.uvs[vt as usize]
                    });
                }
                if any_smooth {
                    mesh.normals.push(if smooth {
                        data.normals[vn as usize]
                    } else {
                        Vec3::ZERO
                    });
                }
                keys.push(key);
                next.push(head[v as usize]);
                head[v as usize] = i;
            }
            face_vertices.push(i);
        }
        let slot = match face.material {
            NONE => no_material,
            m => match slot_of_name[m as usize] {
                NONE => no_material,
                s => s,
            },
        };
        for k in 1..face_vertices.len() - 1 {
            mesh.indices
                .push([face_vertices[0], face_vertices[k], face_vertices[k + 1]]);
            mesh.material_slots.push(slot);
        }
    }
    Ok(ObjModel { mesh, materials })
}

/// Parses one face corner `v`, `v/vt`, `v//vn` or `v/vt/vn` into 0-based indices, given how
/// many positions, texture coordinates and normals are defined so far (for negative indices).
fn parse_corner(word: &str, defined: [usize; 3]) -> Result<[u32; 3], String> {
    let mut out = [NONE; 3];
    let mut parts = word.split('/');
    for (k, slot) in out.iter_mut().enumerate() {
        let Some(part) = parts.next() else { break };
        if part.is_empty() {
            if k == 0 {
                return Err(format!("face corner \"{word}\" has no vertex index"));
            }
            continue;
        }
        let what = ["vertex", "texture coordinate", "normal"][k];
        let x: i64 = part
            .parse()
            .map_err(|_| format!("face corner \"{word}\": \"{part}\" is not an index"))?;
        let index = match x {
            0 => {
                return Err(format!(
                    "face corner \"{word}\": {what} index 0 is invalid (indices start at 1)"
                ))
            }
            x if x > 0 => x - 1,
            x => {
                let i = defined[k] as i64 + x;
                if i < 0 {
                    return Err(format!(
                        "face corner \"{word}\": relative {what} index {x} is out of range \
                         (only {} defined so far)",
                        defined[k]
                    ));
                }
                i
            }
        };
        *slot = u32::try_from(index)
            .ok()
            .filter(|&i| i != NONE)
            .ok_or_else(|| format!("face corner \"{word}\": {what} index {x} is out of range"))?;
    }
    if parts.next().is_some() {
        return Err(format!(
            "face corner \"{word}\" has more than three indices"
        ));
    }
    Ok(out)
}
