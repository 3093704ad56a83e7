//! Bulk reads of binary bodies: vertex rows of scalars only (a fixed row size, so each row is
//! one slice read at fixed offsets) and face rows that are triangles of 32-bit indices (a
//! count byte of 3 and twelve bytes). Each stops at the first row it cannot take whole (a
//! polygon, a value out of range, the end of the file) and leaves it, and the rest, to
//! `rows`, which reads them value by value and locates any error; both give the same mesh.

use super::body::{load, Body};
use super::header::{Element, Format, Kind, Scalar};
use super::roles::Role;
use super::rows::{push_vertex, scalar, Sink, Vertex};
use super::MAX_TRIANGLES;

/// A property of a fixed-size row that is read: where in the row, its type, its role.
struct Field {
    offset: usize,
    ty: Scalar,
    role: Role,
}

/// Reads the leading rows of the vertex `element` that a binary body holds whole and valid;
/// returns how many (0 when its rows are not all scalars, or the body is ASCII).
pub(super) fn vertex_rows(
    body: &mut Body,
    element: &Element,
    roles: &[Role],
    out: &mut Sink,
) -> u64 {
    let big = match body.format() {
        Format::Ascii => return 0,
        Format::LittleEndian => false,
        Format::BigEndian => true,
    };
    let mut fields = Vec::new();
    let mut stride = 0;
    for (property, &role) in element.properties.iter().zip(roles) {
        let Kind::Scalar(ty) = property.kind else {
            return 0;
        };
        if role != Role::Skip {
            fields.push(Field {
                offset: stride,
                ty,
                role,
            });
        }
        stride += ty.size();
    }
    let has = |r: Role| roles.contains(&r);
    let (normals, uvs, colors) = (has(Role::Normal(0)), has(Role::Uv(0)), has(Role::Color(0)));
    let whole = (body.left() / stride) as u64;
    let mut done = 0;
    let mut v = Vertex::default();
    'rows: for row in body
        .rest()
        .chunks_exact(stride)
        .take(whole.min(element.count) as usize)
    {
        for f in &fields {
            let value = load(&row[f.offset..f.offset + f.ty.size()], f.ty, big);
            if scalar(&mut v, f.role, value, f.ty, &out.decoder).is_err() {
                break 'rows;
            }
        }
        push_vertex(&mut out.mesh, &v, normals, uvs, colors);
        done += 1;
    }
    body.advance(done as usize * stride);
    done
}

/// Reads the leading rows of the face `element` that are triangles, when its only property is
/// a list of 32-bit indices with a one-byte count (what most writers give); returns how many.
pub(super) fn face_rows(
    body: &mut Body,
    element: &Element,
    vertex_count: u64,
    out: &mut Sink,
) -> u64 {
    let big = match body.format() {
        Format::Ascii => return 0,
        Format::LittleEndian => false,
        Format::BigEndian => true,
    };
    match element.properties.as_slice() {
        [p] if matches!(
            p.kind,
            Kind::List {
                count: Scalar::U8 | Scalar::I8,
                item: Scalar::I32 | Scalar::U32
            }
        ) => {}
        _ => return 0,
    }
    let room = (MAX_TRIANGLES as usize).saturating_sub(out.mesh.indices.len());
    let rows = (element.count.min(room as u64)) as usize;
    let mut done = 0;
    for row in body.rest().chunks_exact(13).take(rows) {
        let index = |k: usize| {
            let b: [u8; 4] = row[1 + 4 * k..5 + 4 * k].try_into().unwrap_or_default();
            let i = if big {
                u32::from_be_bytes(b)
            } else {
                u32::from_le_bytes(b)
            };
            // A negative 32-bit index reads as one of at least 2^31: out of range too.
            (u64::from(i) < vertex_count).then_some(i)
        };
        let (Some(a), Some(b), Some(c)) = (index(0), index(1), index(2)) else {
            break;
        };
        if row[0] != 3 {
            break;
        }
        out.mesh.indices.push([a, b, c]);
        done += 1;
    }
    body.advance(done * 13);
    done as u64
}
