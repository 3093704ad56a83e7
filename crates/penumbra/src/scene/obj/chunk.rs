//! One chunk of an OBJ file, parsed on its own: the file is cut at line ends (never inside a
//! `\`-continued line) and every chunk is read in parallel into arrays of its own. What a chunk
//! cannot know alone (how many elements earlier chunks define, which material is current at
//! its start, the `mtllib` files) is left for the merge in `mod.rs`, which visits the chunks
//! in file order and so finds exactly what a reader of the whole file would.

use std::collections::HashMap;

use glam::{Vec2, Vec3};

use super::lines::{continues, find, for_each_line_from, numbers, rest_of_line};
use super::NONE;
use crate::texture::srgb_to_linear;

/// The material of faces before a chunk's first `usemtl`: the one current where it starts.
pub(super) const INHERITED: u32 = u32::MAX - 1;

/// One polygon: `corners[first..first + len]` of its chunk, its material (an index into its
/// chunk's `usemtl` names, `NONE` or `INHERITED`) and the line it was read from.
pub(super) struct Face {
    pub first: usize,
    pub len: u32,
    pub material: u32,
    pub line: u32,
}

/// A statement whose effect depends on the chunks before it, kept in file order with the
/// number of triangles the chunk had read before it (the mesh-size check comes first).
pub(super) enum Deferred {
    /// `mtllib` and the rest of its line.
    Mtllib { triangles: usize, rest: String },
    /// A relative index reaching back before the chunk: `x` counted back from the
    /// `defined`-th element of kind `kind` of the chunk, for component `kind` of corner
    /// `corner` (an index into the chunk's corners).
    Relative {
        triangles: usize,
        line: usize,
        word: String,
        corner: usize,
        kind: usize,
        x: i64,
        defined: usize,
    },
}

/// What a chunk read. Indices are 0-based; positive ones are final, relative ones are counted
/// from the chunk's start and listed in `rebase` (or `deferred` when they reach back before it).
#[derive(Default)]
pub(super) struct Chunk {
    pub positions: Vec<Vec3>,
    /// Linear vertex colours, one per `v` once a `v` of the chunk has one (white before and
    /// where one has none), else empty.
    pub colors: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub normals: Vec<Vec3>,
    /// (v, vt, vn) per face corner; `NONE` for a missing vt or vn.
    pub corners: Vec<[u32; 3]>,
    pub faces: Vec<Face>,
    pub triangles: usize,
    /// Names given to `usemtl` in this chunk, in order of first appearance.
    pub material_names: Vec<String>,
    /// The material current at the chunk's end, as in [`Face::material`].
    pub last_material: u32,
    /// (corner, component) of the indices to shift by the elements defined before the chunk.
    pub rebase: Vec<(u32, u8)>,
    pub deferred: Vec<Deferred>,
    /// The first error, after which the chunk was not read further.
    pub error: Option<String>,
}

/// Byte ranges of `bytes` of about `size` bytes each (at least one), each ending after a `\n`
/// (the last one at the end) that does not end a `\`-continued line.
pub(super) fn split(bytes: &[u8], size: usize) -> Vec<std::ops::Range<usize>> {
    let mut ranges = Vec::new();
    let mut start = 0;
    while bytes.len() - start > size {
        let Some(end) = line_end_after(bytes, start + size) else {
            break;
        };
        ranges.push(start..end);
        start = end;
    }
    ranges.push(start..bytes.len());
    ranges
}

/// The position just past the first `\n` at or after `from` that ends a logical line.
fn line_end_after(bytes: &[u8], from: usize) -> Option<usize> {
    let mut from = from;
    loop {
        let nl = from + bytes[from..].iter().position(|&b| b == b'\n')?;
        let start = bytes[..nl]
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |k| k + 1);
        // `\n` never occurs inside a UTF-8 sequence, so the line converts as in the whole file.
        if !continues(&String::from_utf8_lossy(&bytes[start..nl])) {
            return Some(nl + 1);
        }
        from = nl + 1;
    }
}

/// Reads `text`, the part of an OBJ file that starts on line `first_line`.
pub(super) fn parse(text: &str, first_line: usize) -> Chunk {
    let mut chunk = Chunk {
        last_material: INHERITED,
        ..Chunk::default()
    };
    let mut names: HashMap<String, u32> = HashMap::new();
    let result = for_each_line_from(text, first_line, |n, line| {
        let at = |message: String| format!("line {n}: {message}");
        let mut words = line.split_ascii_whitespace();
        let Some(keyword) = words.next() else {
            return Ok(());
        };
        let c = &mut chunk;
        match keyword {
            "v" => {
                let p = numbers::<3>(&mut words, 3)
                    .ok_or_else(|| at("a vertex `v` needs three numbers (x y z)".into()))?;
                if !p.iter().all(|c| c.is_finite()) {
                    return Err(at("a vertex coordinate is not a finite number".into()));
                }
                // `v x y z r g b` (MeshLab, trimesh, Open3D); a lone fourth number is a `w`.
                let rgb = numbers::<3>(&mut words, 3);
                if rgb.is_some_and(|rgb| !rgb.iter().all(|c| c.is_finite())) {
                    return Err(at("a vertex colour is not a finite number".into()));
                }
                c.positions.push(Vec3::from(p));
                match rgb {
                    Some(rgb) => {
                        c.colors.resize(c.positions.len() - 1, Vec3::ONE);
                        c.colors.push(vertex_color(rgb));
                    }
                    None if !c.colors.is_empty() => c.colors.push(Vec3::ONE),
                    None => {}
                }
            }
            "vt" => {
                let t = numbers::<2>(&mut words, 1)
                    .ok_or_else(|| at("a texture coordinate `vt` needs numbers (u [v])".into()))?;
                if !t.iter().all(|c| c.is_finite()) {
                    return Err(at("a texture coordinate is not a finite number".into()));
                }
                c.uvs.push(Vec2::from(t));
            }
            "vn" => {
                let v = numbers::<3>(&mut words, 3)
                    .ok_or_else(|| at("a normal `vn` needs three numbers (x y z)".into()))?;
                // A non-finite normal is kept and makes its faces flat (see `build_mesh`).
                c.normals.push(Vec3::from(v));
            }
            "f" | "fo" => {
                let first = c.corners.len();
                let defined = [c.positions.len(), c.uvs.len(), c.normals.len()];
                for word in words {
                    let corner = c.corners.len();
                    let indices = parse_corner(word, |kind, x| {
                        let local = defined[kind] as i64 + x;
                        if local >= 0 {
                            c.rebase.push((corner as u32, kind as u8));
                            local as u32
                        } else {
                            c.deferred.push(Deferred::Relative {
                                triangles: c.triangles,
                                line: n,
                                word: word.to_owned(),
                                corner,
                                kind,
                                x,
                                defined: defined[kind],
                            });
                            NONE
                        }
                    })
                    .map_err(at)?;
                    c.corners.push(indices);
                }
                let len = c.corners.len() - first;
                if len < 3 {
                    return Err(at(format!(
                        "a face needs at least 3 vertices, this one has {len}"
                    )));
                }
                // The mesh-size limit is checked by the merge, which knows the earlier chunks.
                c.triangles += len - 2;
                c.faces.push(Face {
                    first,
                    len: u32::try_from(len).map_err(|_| at("the face is too large".into()))?,
                    material: c.last_material,
                    line: n as u32,
                });
            }
            "usemtl" => {
                let name = rest_of_line(line, keyword);
                c.last_material = if name.is_empty() {
                    NONE
                } else {
                    let next = c.material_names.len() as u32;
                    *names.entry(name.to_owned()).or_insert_with(|| {
                        c.material_names.push(name.to_owned());
                        next
                    })
                };
            }
            "mtllib" => {
                let rest = rest_of_line(line, keyword);
                if !rest.is_empty() {
                    c.deferred.push(Deferred::Mtllib {
                        triangles: c.triangles,
                        rest: rest.to_owned(),
                    });
                }
            }
            _ => {}
        }
        Ok(())
    });
    chunk.error = result.err();
    chunk
}

/// Parses one face corner `v`, `v/vt`, `v//vn` or `v/vt/vn` into 0-based indices. A relative
/// (negative) index `x` of component `kind` becomes `relative(kind, x)`, called in order of
/// the components.
fn parse_corner(
    word: &str,
    mut relative: impl FnMut(usize, i64) -> u32,
) -> Result<[u32; 3], String> {
    let mut out = [NONE; 3];
    // The parts as `word.split('/')` gives them, found by a byte scan.
    let mut start = 0;
    for (k, slot) in out.iter_mut().enumerate() {
        if start > word.len() {
            break;
        }
        let end = find(word.as_bytes(), start, b'/', b'/');
        let part = &word[start..end];
        start = end + 1;
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
        *slot = match x {
            0 => {
                return Err(format!(
                    "face corner \"{word}\": {what} index 0 is invalid (indices start at 1)"
                ))
            }
            x if x > 0 => u32::try_from(x - 1)
                .ok()
                .filter(|&i| i != NONE)
                .ok_or_else(|| {
                    format!("face corner \"{word}\": {what} index {x} is out of range")
                })?,
            x => relative(k, x),
        };
    }
    if start <= word.len() {
        return Err(format!(
            "face corner \"{word}\" has more than three indices"
        ));
    }
    Ok(out)
}

/// The linear colour of a `v` line's `r g b`: sRGB-encoded display values (as MeshLab, trimesh
/// and Open3D write them, and Blender reads them), clamped to [0, 1] and decoded.
fn vertex_color(rgb: [f32; 3]) -> Vec3 {
    Vec3::from(rgb.map(|c| srgb_to_linear(c.clamp(0.0, 1.0))))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Face corners split as `str::split('/')` splits them: one to three parts, empty parts
    /// skipped after the vertex, a fourth part refused.
    #[test]
    fn corners_split_on_slashes() {
        let absolute = |_: usize, _: i64| unreachable!("no relative indices here");
        let ok = |word: &str| parse_corner(word, absolute).unwrap();
        assert_eq!(ok("7"), [6, NONE, NONE]);
        assert_eq!(ok("7/8"), [6, 7, NONE]);
        assert_eq!(ok("7//9"), [6, NONE, 8]);
        assert_eq!(ok("7/8/9"), [6, 7, 8]);
        assert_eq!(ok("7//"), [6, NONE, NONE]);
        for bad in ["7/8/9/", "7/8/9/10", "/8/9", "", "7/x", "7/8/ 9"] {
            assert!(parse_corner(bad, absolute).is_err(), "{bad:?}");
        }
        let relative: Vec<(usize, i64)> = {
            let mut seen = Vec::new();
            parse_corner("-1/-2/-3", |k, x| {
                seen.push((k, x));
                0
            })
            .unwrap();
            seen
        };
        assert_eq!(relative, [(0, -1), (1, -2), (2, -3)]);
    }
}
