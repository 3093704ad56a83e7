//! Wavefront OBJ meshes: the reader of `.obj` files and the assembly of their faces into one
//! indexed triangle mesh. Their MTL material libraries are read by [`mtl`], and the line rules
//! both file kinds share (comments, continuations) live in [`lines`].
//!
//! Large files are read in parallel: cut into chunks at line ends, each chunk parsed on its own
//! (see [`chunk`]), then merged in file order, which resolves what a chunk cannot know alone
//! (relative indices reaching before it, the material current at its start, `mtllib` files,
//! which error comes first). The result, errors included, is the one a serial reading gives.
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

mod chunk;
mod info;
mod lines;
mod mtl;
#[cfg(test)]
mod tests;

use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::files::Files;
use crate::geometry::Mesh;

use chunk::{Chunk, Deferred, Face, INHERITED};
pub use info::{inspect_mtl, inspect_obj, inspect_obj_bytes, inspect_obj_in, ObjInfo};
pub(super) use info::{mesh_bounds, obj_bounds, summarize};
use lines::decode;
use mtl::Library;

/// A material from an MTL file.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct ObjMaterial {
    pub name: String,
    pub diffuse: Option<[f32; 3]>,
    pub ambient: Option<[f32; 3]>,
    pub specular: Option<[f32; 3]>,
    pub shininess: Option<f32>,
    /// `map_Kd`, resolved against the MTL file's folder.
    pub diffuse_texture: Option<PathBuf>,
    /// `map_d` (the dissolve texture foliage is cut out with), resolved likewise.
    pub dissolve_texture: Option<PathBuf>,
}

/// An OBJ file as one mesh. Triangle material slot `k < materials.len()` is `materials[k]`;
/// slot `materials.len()` marks faces without a (known) `usemtl` material.
#[derive(Clone, Debug)]
pub(crate) struct ObjModel {
    pub mesh: Mesh,
    pub materials: Vec<ObjMaterial>,
    /// The MTL files read for it.
    pub mtl_files: Vec<PathBuf>,
}

/// Largest OBJ file read: 4 GiB of text is some 100 million triangles, about what memory holds.
pub(super) const MAX_FILE_BYTES: u64 = 4 << 30;
/// The most triangles a mesh may have: indices are 32-bit.
const MAX_TRIANGLES: usize = (u32::MAX / 4) as usize;
/// "No index": a corner without `vt` or `vn`, a face without `usemtl`.
const NONE: u32 = u32::MAX;

/// Bytes of an OBJ file per chunk parsed in parallel: small enough that a few-megabyte mesh
/// keeps two threads busy, large enough that the per-chunk work is negligible.
const CHUNK_BYTES: usize = 512 << 10;

/// Everything read from an OBJ file, indices 0-based but not yet checked against the final
/// counts (a positive index may refer to a vertex defined further down).
#[derive(Default)]
struct ObjData {
    positions: Vec<Vec3>,
    uvs: Vec<Vec2>,
    normals: Vec<Vec3>,
    /// Linear colours, one per `v` once any has one (`v x y z r g b`; white where a `v` has
    /// none), else empty.
    colors: Vec<Vec3>,
    /// The faces, chunk by chunk in file order.
    parts: Vec<Part>,
    triangles: usize,
    /// Names given to `usemtl`, in order of first appearance.
    material_names: Vec<String>,
    library: Library,
}

/// The faces of one chunk, with what turns their materials into indices of `material_names`.
struct Part {
    corners: Vec<[u32; 3]>,
    faces: Vec<Face>,
    /// The file-wide index of each of the chunk's `usemtl` names.
    materials: Vec<u32>,
    /// The material current where the chunk starts.
    inherited: u32,
}

/// A face as [`build_mesh`] sees it: its (v, vt, vn) corners, its material (an index into the
/// names given to `usemtl`, or `NONE`) and its line.
struct FaceRef<'a> {
    corners: &'a [[u32; 3]],
    material: u32,
    line: u32,
}

impl ObjData {
    /// Every face in file order.
    fn faces(&self) -> impl Iterator<Item = FaceRef<'_>> {
        self.parts.iter().flat_map(|part| {
            part.faces.iter().map(move |f| FaceRef {
                corners: &part.corners[f.first..f.first + f.len as usize],
                material: match f.material {
                    NONE => NONE,
                    INHERITED => part.inherited,
                    m => part.materials[m as usize],
                },
                line: f.line,
            })
        })
    }
}

/// Loads `path`, parsing its chunks on the threads of `pool` when there is one. Errors are
/// messages that do not repeat the OBJ file's path (the caller adds it) but do name any other
/// file involved.
pub(crate) fn load_obj(
    files: &Files,
    path: &Path,
    pool: Option<&rayon::ThreadPool>,
) -> Result<ObjModel, String> {
    let bytes = files
        .read(path, MAX_FILE_BYTES)
        .map_err(|e| e.to_string())?;
    let dir = path.parent().unwrap_or(Path::new(""));
    parse_obj(&bytes, dir, Library::new(files.clone(), path, dir), pool)
}

/// [`load_obj`] for the bytes of an OBJ file whose `mtllib` names are relative to `dir` and
/// read into `library`.
fn parse_obj(
    bytes: &[u8],
    dir: &Path,
    library: Library,
    pool: Option<&rayon::ThreadPool>,
) -> Result<ObjModel, String> {
    lines::check_text(bytes, "an OBJ")?;
    let data = read(bytes, dir, library, pool, CHUNK_BYTES)?;
    if data.triangles == 0 {
        // Nothing to render: most likely not the file meant (any text without `f` lines
        // parses, since unknown statements are ignored).
        return Err("no faces (`f` lines): nothing to render; is it an OBJ file?".into());
    }
    build_mesh(data)
}

/// Parses the OBJ file `bytes`, whose `mtllib` names are relative to `dir` and read into
/// `library`, in chunks of about `chunk_bytes` bytes (in parallel on `pool` when there is
/// one), and merges them.
fn read(
    bytes: &[u8],
    dir: &Path,
    library: Library,
    pool: Option<&rayon::ThreadPool>,
    chunk_bytes: usize,
) -> Result<ObjData, String> {
    // A byte-order mark, once converted, is U+FEFF at the start of the text.
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let ranges = chunk::split(bytes, chunk_bytes.max(1));
    let lines = |r: &Range<usize>| bytes[r.clone()].iter().filter(|&&b| b == b'\n').count();
    let parse = |(r, first_line): (&Range<usize>, usize)| {
        chunk::parse(&decode(&bytes[r.clone()]), first_line)
    };
    // The line each chunk starts on.
    let first_lines = |counts: Vec<usize>| -> Vec<usize> {
        counts
            .iter()
            .scan(1, |line, &n| Some(std::mem::replace(line, *line + n)))
            .collect()
    };
    let chunks: Vec<Chunk> = match pool {
        Some(pool) if ranges.len() > 1 => pool.install(|| {
            let starts = first_lines(ranges.par_iter().map(lines).collect());
            ranges.par_iter().zip(starts).map(parse).collect()
        }),
        _ => {
            let starts = first_lines(ranges.iter().map(lines).collect());
            ranges.iter().zip(starts).map(parse).collect()
        }
    };
    merge(chunks, dir, library)
}

/// Joins the chunks in file order: loads the `mtllib` files, resolves relative indices and
/// materials against the chunks before, checks the mesh size, and returns the first error a
/// serial reading meets.
fn merge(chunks: Vec<Chunk>, dir: &Path, library: Library) -> Result<ObjData, String> {
    let too_large = || "the mesh is too large (more than a billion triangles)".to_owned();
    let mut data = ObjData {
        library,
        ..ObjData::default()
    };
    let total = |f: fn(&Chunk) -> usize| chunks.iter().map(f).sum::<usize>();
    data.positions.reserve(total(|c| c.positions.len()));
    data.uvs.reserve(total(|c| c.uvs.len()));
    data.normals.reserve(total(|c| c.normals.len()));
    let mut names: HashMap<String, u32> = HashMap::new();
    let mut current_material = NONE;
    for mut chunk in chunks {
        let before = [data.positions.len(), data.uvs.len(), data.normals.len()];
        for deferred in std::mem::take(&mut chunk.deferred) {
            match deferred {
                Deferred::Mtllib { triangles, rest } => {
                    if data.triangles + triangles > MAX_TRIANGLES {
                        return Err(too_large());
                    }
                    // One file name with spaces, or several names separated by spaces.
                    let files: Vec<&str> = if data.library.is_file(&dir.join(&rest)) {
                        vec![&rest]
                    } else {
                        rest.split_ascii_whitespace().collect()
                    };
                    for f in files {
                        let path = data
                            .library
                            .resolve(dir, f)
                            .map_err(|e| format!("`mtllib` {e}"))?;
                        data.library.load(path)?;
                    }
                }
                Deferred::Relative {
                    triangles,
                    line,
                    word,
                    corner,
                    kind,
                    x,
                    defined,
                } => {
                    if data.triangles + triangles > MAX_TRIANGLES {
                        return Err(too_large());
                    }
                    let defined = before[kind] + defined;
                    let Ok(index) = u32::try_from(defined as i64 + x) else {
                        let what = ["vertex", "texture coordinate", "normal"][kind];
                        return Err(format!(
                            "line {line}: face corner \"{word}\": relative {what} index {x} is \
                             out of range (only {defined} defined so far)"
                        ));
                    };
                    chunk.corners[corner][kind] = index;
                }
            }
        }
        if data.triangles + chunk.triangles > MAX_TRIANGLES {
            return Err(too_large());
        }
        if let Some(error) = chunk.error {
            return Err(error);
        }
        data.triangles += chunk.triangles;
        // The sums stay below the element counts, themselves far below 2³² (MAX_FILE_BYTES).
        for &(corner, kind) in &chunk.rebase {
            chunk.corners[corner as usize][kind as usize] += before[kind as usize] as u32;
        }
        let materials: Vec<u32> = chunk
            .material_names
            .into_iter()
            .map(|name| {
                let next = data.material_names.len() as u32;
                *names.entry(name).or_insert_with_key(|name| {
                    data.material_names.push(name.clone());
                    next
                })
            })
            .collect();
        let inherited = current_material;
        current_material = match chunk.last_material {
            INHERITED => current_material,
            NONE => NONE,
            m => materials[m as usize],
        };
        if !chunk.colors.is_empty() || !data.colors.is_empty() {
            let end = data.positions.len() + chunk.positions.len();
            data.colors.resize(data.positions.len(), Vec3::ONE);
            data.colors.extend_from_slice(&chunk.colors);
            data.colors.resize(end, Vec3::ONE);
        }
        data.positions.extend_from_slice(&chunk.positions);
        data.uvs.extend_from_slice(&chunk.uvs);
        data.normals.extend_from_slice(&chunk.normals);
        data.parts.push(Part {
            corners: chunk.corners,
            faces: chunk.faces,
            materials,
            inherited,
        });
    }
    Ok(data)
}

/// Checks every index, then turns the faces into an indexed triangle mesh: one vertex per
/// distinct (v, vt, vn) corner, fan triangulation, per-triangle material slots.
fn build_mesh(data: ObjData) -> Result<ObjModel, String> {
    let counts = [data.positions.len(), data.uvs.len(), data.normals.len()];
    for face in data.faces() {
        for c in face.corners {
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
    let smooth_face = |face: &FaceRef| face.corners.iter().all(|c| usable(c[2]));
    let any_smooth = data.faces().any(|f| smooth_face(&f));
    let any_uv = data.faces().any(|f| f.corners.iter().any(|c| c[1] != NONE));

    // Materials in order of first use; slot `used.len()` is "no material".
    let mut slot_of_name = vec![NONE; data.material_names.len()];
    let mut slot_of_library = vec![NONE; data.library.len()];
    let mut materials = Vec::new();
    for face in data.faces() {
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
    for face in data.faces() {
        let smooth = any_smooth && smooth_face(&face);
        face_vertices.clear();
        for &[v, vt, vn] in face.corners {
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
                if let Some(&color) = data.colors.get(v as usize) {
                    mesh.colors.push(color);
                }
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
    let mtl_files = data.library.files_read().cloned().collect();
    Ok(ObjModel {
        mesh,
        materials,
        mtl_files,
    })
}
