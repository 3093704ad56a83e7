//! Wavefront OBJ meshes and their MTL material libraries.
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
//! - In an MTL file: `newmtl`, `Kd`, `Ka`, `Ks` (one number means grey), `Ns` and `map_Kd`
//!   (relative to the MTL file's folder; options such as `-s` or `-clamp` are skipped and the
//!   rest of the line is the file name, spaces included). Everything else (`illum`, `Ni`, `d`,
//!   `Tr`, `Tf`, `Ke`, other maps) is ignored.
//! - `#` starts a comment anywhere on a line; a line ending in `\` continues on the next one;
//!   CRLF line endings, tabs, a UTF-8 byte-order mark and bytes that are not UTF-8 are fine.

use std::borrow::Cow;
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use crate::geometry::Mesh;

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

/// The materials of every `mtllib`, later definitions of a name replacing earlier ones.
#[derive(Default)]
struct Library {
    materials: Vec<ObjMaterial>,
    by_name: HashMap<String, usize>,
    loaded: HashSet<PathBuf>,
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
                    let mtl = resolve(dir, f);
                    if data.library.loaded.insert(mtl.clone()) {
                        load_mtl(&mtl, &mut data.library)?;
                    }
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
    let mut slot_of_library = vec![NONE; data.library.materials.len()];
    let mut materials = Vec::new();
    for face in &data.faces {
        let m = face.material;
        if m == NONE || slot_of_name[m as usize] != NONE {
            continue;
        }
        let name = &data.material_names[m as usize];
        if let Some(&lib) = data.library.by_name.get(name) {
            if slot_of_library[lib] == NONE {
                slot_of_library[lib] = materials.len() as u32;
                materials.push(data.library.materials[lib].clone());
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

/// Reads an MTL file into `library`. Errors name the MTL file.
fn load_mtl(path: &Path, library: &mut Library) -> Result<(), String> {
    let bytes = std::fs::read(path)
        .map_err(|e| format!("cannot load material library \"{}\": {e}", path.display()))?;
    let text = String::from_utf8_lossy(&bytes);
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut current: Option<usize> = None;
    for_each_line(&text, |n, line| {
        let at = |message: &str| {
            format!(
                "material library \"{}\", line {n}: {message}",
                path.display()
            )
        };
        let mut words = line.split_ascii_whitespace();
        let Some(keyword) = words.next() else {
            return Ok(());
        };
        if keyword == "newmtl" {
            let name = rest_of_line(line, keyword).to_owned();
            let index = library.materials.len();
            library.by_name.insert(name.clone(), index);
            library.materials.push(ObjMaterial {
                name,
                diffuse: None,
                ambient: None,
                specular: None,
                shininess: None,
                diffuse_texture: None,
            });
            current = Some(index);
            return Ok(());
        }
        // Statements before the first `newmtl` belong to no material.
        let Some(m) = current.map(|i| &mut library.materials[i]) else {
            return Ok(());
        };
        match keyword {
            "Kd" | "Ka" | "Ks" => {
                // The `spectral` and `xyz` forms are not RGB; leave the default.
                if matches!(words.clone().next(), Some("spectral" | "xyz")) {
                    return Ok(());
                }
                let given = words.clone().count();
                let c = numbers::<3>(&mut words, 1)
                    .filter(|c| c.iter().all(|x| x.is_finite()))
                    .ok_or_else(|| at(&format!("`{keyword}` needs one or three numbers")))?;
                // `Kd r` means grey.
                let c = if given < 3 { [c[0]; 3] } else { c };
                match keyword {
                    "Kd" => m.diffuse = Some(c),
                    "Ka" => m.ambient = Some(c),
                    _ => m.specular = Some(c),
                }
            }
            "Ns" => {
                let [p] = numbers::<1>(&mut words, 1)
                    .filter(|p| p[0].is_finite())
                    .ok_or_else(|| at("`Ns` needs a number"))?;
                m.shininess = Some(p);
            }
            "map_Kd" => {
                if let Some(file) = texture_file_name(line, words) {
                    m.diffuse_texture = Some(resolve(dir, file));
                }
            }
            _ => {}
        }
        Ok(())
    })
}

/// Calls `f(line number, line)` for every logical line of `text`, comments removed and
/// `\`-continued lines joined (numbered by their first line).
fn for_each_line(
    text: &str,
    mut f: impl FnMut(usize, &str) -> Result<(), String>,
) -> Result<(), String> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut pending = String::new();
    let mut pending_line = 0;
    for (i, raw) in text.split('\n').enumerate() {
        let line = raw.find('#').map_or(raw, |k| &raw[..k]).trim_end();
        if let Some(head) = line.strip_suffix('\\') {
            if pending.is_empty() {
                pending_line = i + 1;
            }
            pending.push_str(head);
            pending.push(' ');
            continue;
        }
        let (n, line) = if pending.is_empty() {
            (i + 1, Cow::Borrowed(line))
        } else {
            pending.push_str(line);
            (pending_line, Cow::Owned(std::mem::take(&mut pending)))
        };
        f(n, &line)?;
    }
    if !pending.is_empty() {
        f(pending_line, &pending)?;
    }
    Ok(())
}

/// The first `N` numbers of `words`, at least `min` of them present; missing ones are 0.
/// Words after the first `N` are ignored (`v x y z w`, `v x y z r g b`).
fn numbers<const N: usize>(
    words: &mut std::str::SplitAsciiWhitespace<'_>,
    min: usize,
) -> Option<[f32; N]> {
    let mut out = [0.0; N];
    let mut count = 0;
    for (slot, word) in out.iter_mut().zip(words) {
        *slot = word.parse().ok()?;
        count += 1;
    }
    (count >= min).then_some(out)
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

/// The text after `keyword` on `line`, trimmed (names may contain spaces).
fn rest_of_line<'a>(line: &'a str, keyword: &str) -> &'a str {
    line.trim_start()[keyword.len()..].trim()
}

/// The file name of a `map_Kd` statement: what follows its options, to the end of the line.
fn texture_file_name<'a>(
    line: &'a str,
    mut words: std::str::SplitAsciiWhitespace<'a>,
) -> Option<&'a str> {
    while let Some(word) = words.next() {
        if !word.starts_with('-') || word.len() == 1 {
            // `word` is a slice of `line`: the name runs from it to the end of the line.
            let start = word.as_ptr() as usize - line.as_ptr() as usize;
            return Some(line[start..].trim_end());
        }
        match word {
            "-blendu" | "-blendv" | "-cc" | "-clamp" | "-texres" | "-bm" | "-boost"
            | "-imfchan" | "-type" => {
                words.next();
            }
            "-mm" => {
                words.next();
                words.next();
            }
            // `-o`, `-s`, `-t` (and options unknown here): up to three numbers.
            _ => {
                for _ in 0..3 {
                    let mut peek = words.clone();
                    match peek.next() {
                        Some(w) if w.parse::<f32>().is_ok() => words = peek,
                        _ => break,
                    }
                }
            }
        }
    }
    None
}

/// `name` relative to `dir`. Names written with Windows separators are tried with `/` when
/// the name as written does not exist.
fn resolve(dir: &Path, name: &str) -> PathBuf {
    let path = dir.join(name);
    if name.contains('\\') && !path.exists() {
        let alt = dir.join(name.replace('\\', "/"));
        if alt.exists() {
            return alt;
        }
    }
    path
}
