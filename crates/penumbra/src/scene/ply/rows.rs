//! The rows of an element, value by value: any format, any layout, every value checked and
//! every problem located (the element row and property, the line or byte). `fast` reads the
//! common binary layouts in bulk and leaves the rest, and every row it cannot take, to this.

use glam::{Vec2, Vec3};

use super::body::Body;
use super::color::Decoder;
use super::header::{Element, Kind, Scalar};
use super::roles::Role;
use super::{quoted, PlyError, MAX_TRIANGLES};
use crate::geometry::Mesh;

/// What the rows are read into.
pub(super) struct Sink {
    pub mesh: Mesh,
    /// Each triangle's corner texture coordinates, parallel to the mesh's triangles, when the
    /// faces carry `texcoord` lists.
    pub texcoords: Vec<[Vec2; 3]>,
    pub decoder: Decoder,
}

/// One vertex row's values, filled property by property.
#[derive(Default)]
pub(super) struct Vertex {
    p: [f32; 3],
    n: [f32; 3],
    uv: [f32; 2],
    color: [f32; 3],
}

/// Values found at the ends of an element's ASCII rows beyond its properties, dropped.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct Extra {
    /// How many values, over all rows.
    pub values: u64,
    /// How many rows had some.
    pub rows: u64,
    /// The line of the first.
    pub first_line: usize,
}

/// Reads the rows of `element` from `first` on, each property into its role; returns the
/// values an ASCII row had beyond its properties (VCGlib writes some after each face), which
/// are dropped.
pub(super) fn read_rows(
    body: &mut Body,
    element: &Element,
    roles: &[Role],
    vertex_count: u64,
    first: u64,
    out: &mut Sink,
) -> Result<Extra, PlyError> {
    let mut extra = Extra::default();
    let mut corners: Vec<u32> = Vec::new();
    let mut texcoords: Vec<f32> = Vec::new();
    let mut v = Vertex::default();
    let [vertex, normals, uvs, colors, faces, with_texcoords] = [
        Role::Position(0),
        Role::Normal(0),
        Role::Uv(0),
        Role::Color(0),
        Role::Corners,
        Role::Texcoords,
    ]
    .map(|r| roles.contains(&r));
    for row in first..element.count {
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
            let fail = |body: &Body, m: String| locate(PlyError::new(body.at(), m));
            let (ty, count_ty) = match property.kind {
                Kind::Scalar(t) => (t, None),
                Kind::List { count, item } => (item, Some(count)),
            };
            let Some(count_ty) = count_ty else {
                let value = body.scalar(ty).map_err(locate)?;
                scalar(&mut v, role, value, ty, &out.decoder).map_err(|m| fail(body, m))?;
                continue;
            };
            let len = body.count(count_ty).map_err(locate)?;
            match role {
                Role::Corners => {
                    corners.clear();
                    for _ in 0..len {
                        let i = body.scalar(ty).map_err(locate)?;
                        if i < 0.0 || i >= vertex_count as f64 {
                            let m = format!(
                                "vertex index {i} is out of range (the file has \
                                 {vertex_count} vertices)"
                            );
                            return Err(fail(body, m));
                        }
                        corners.push(i as u32);
                    }
                    if len < 3 {
                        let m = format!("a face needs at least 3 vertices, this one has {len}");
                        return Err(fail(body, m));
                    }
                    if (out.mesh.indices.len() + corners.len() - 2) as u64 > MAX_TRIANGLES {
                        let m = "the mesh is too large (more than a billion triangles)";
                        return Err(fail(body, m.into()));
                    }
                }
                Role::Texcoords => {
                    texcoords.clear();
                    for _ in 0..len {
                        let t = body.scalar(ty).map_err(locate)?;
                        if !(t as f32).is_finite() {
                            let m = format!("texture coordinate {t} is not a finite number");
                            return Err(fail(body, m));
                        }
                        texcoords.push(t as f32);
                    }
                }
                _ => body.skip(ty, len).map_err(locate)?,
            }
        }
        if faces {
            if with_texcoords {
                let at = body.at();
                let face = |m: String| {
                    let m = format!("element {} row {row}: {m}", quoted(&element.name));
                    PlyError::new(at, m)
                };
                push_texcoords(&corners, &texcoords, &mut out.texcoords).map_err(face)?;
            }
            for k in 1..corners.len() - 1 {
                out.mesh
                    .indices
                    .push([corners[0], corners[k], corners[k + 1]]);
            }
        }
        if vertex {
            push_vertex(&mut out.mesh, &v, normals, uvs, colors);
        }
        let (values, line) = body.end_row();
        if values > 0 {
            if extra.rows == 0 {
                extra.first_line = line;
            }
            extra.values += values;
            extra.rows += 1;
        }
    }
    Ok(extra)
}

/// Stores a scalar `value` of type `ty` in its `role`; the error says what is wrong with it.
#[inline]
pub(super) fn scalar(
    v: &mut Vertex,
    role: Role,
    value: f64,
    ty: Scalar,
    d: &Decoder,
) -> Result<(), String> {
    let narrow = value as f32;
    let finite = narrow.is_finite();
    match role {
        Role::Position(_) if !finite => {
            return Err(format!("{value} is not a finite number (in 32 bits)"))
        }
        Role::Uv(_) if !finite => {
            return Err(format!("texture coordinate {value} is not a finite number"))
        }
        Role::Color(_) if !finite => return Err(format!("colour {value} is not a finite number")),
        Role::Position(k) => v.p[k] = narrow,
        Role::Normal(k) => v.n[k] = narrow,
        Role::Uv(k) => v.uv[k] = narrow,
        Role::Color(k) => v.color[k] = d.decode(value, ty),
        Role::Corners | Role::Texcoords | Role::Skip => {}
    }
    Ok(())
}

/// Appends one vertex's attributes (those the element has) to `mesh`.
#[inline]
pub(super) fn push_vertex(mesh: &mut Mesh, v: &Vertex, normals: bool, uvs: bool, colors: bool) {
    mesh.positions.push(Vec3::from(v.p));
    if normals {
        let n = Vec3::from(v.n);
        mesh.normals
            .push(if n.is_finite() { n } else { Vec3::ZERO });
    }
    if uvs {
        mesh.uvs.push(Vec2::from(v.uv));
    }
    if colors {
        mesh.colors.push(Vec3::from(v.color));
    }
}

/// Appends the corner texture coordinates of a face's fan triangles: two values per corner,
/// or none (then (0, 0)).
fn push_texcoords(corners: &[u32], t: &[f32], out: &mut Vec<[Vec2; 3]>) -> Result<(), String> {
    let n = corners.len();
    if !t.is_empty() && t.len() != 2 * n {
        return Err(format!(
            "its `texcoord` list has {} values for {n} corners (two per corner, or none)",
            t.len()
        ));
    }
    let uv = |k: usize| match t.is_empty() {
        true => Vec2::ZERO,
        false => Vec2::new(t[2 * k], t[2 * k + 1]),
    };
    out.extend((1..n - 1).map(|k| [uv(0), uv(k), uv(k + 1)]));
    Ok(())
}
