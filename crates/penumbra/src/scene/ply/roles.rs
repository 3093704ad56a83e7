//! What each property of the `vertex` and `face` elements is read into, and what the reader
//! passes over (named in `check`'s warnings).

use super::header::{Element, Kind, Scalar};
use super::quoted;

/// What a property is read into.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Role {
    /// Component `k` of the position.
    Position(usize),
    Normal(usize),
    Uv(usize),
    /// Channel `k` of the vertex colour.
    Color(usize),
    /// A face's corner list.
    Corners,
    /// A face's list of texture coordinates, two per corner (MeshLab, VCGlib).
    Texcoords,
    Skip,
}

/// The roles of the `vertex` element's properties and which attributes it has.
pub(super) struct VertexRoles {
    pub roles: Vec<Role>,
    pub normals: bool,
    pub uvs: bool,
    pub colors: bool,
}

/// The names uvs go by, as (u, v) pairs in order of preference.
pub(super) const UV_NAMES: [[&str; 2]; 4] = [
    ["u", "v"],
    ["s", "t"],
    ["texture_u", "texture_v"],
    ["texture_s", "texture_t"],
];

/// The names vertex colours go by, in order of preference.
const COLOR_NAMES: [[&str; 3]; 2] = [
    ["red", "green", "blue"],
    ["diffuse_red", "diffuse_green", "diffuse_blue"],
];

/// The role of each property of the `vertex` element.
pub(super) fn vertex_roles(e: &Element) -> Result<VertexRoles, String> {
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
    let mut colors = false;
    for triple in COLOR_NAMES {
        if assign(&triple, Role::Color)? {
            colors = true;
            break;
        }
    }
    Ok(VertexRoles {
        roles,
        normals,
        uvs,
        colors,
    })
}

/// The role of each property of the `face` element: its first `vertex_indices` or
/// `vertex_index` list gives the corners, a `texcoord` list their texture coordinates.
pub(super) fn face_roles(e: &Element) -> Result<Vec<Role>, String> {
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
    let texcoords = e.properties.iter().position(|p| p.name == "texcoord");
    if let Some(i) = texcoords.filter(|&i| matches!(e.properties[i].kind, Kind::List { .. })) {
        roles[i] = Role::Texcoords;
    }
    Ok(roles)
}

/// The warning for what of `element` (whose properties have `roles`; `None` for an element
/// the reader does not know) is read but ignored, if anything is: each name once.
pub(super) fn ignored(element: &Element, roles: Option<&[Role]>) -> Option<String> {
    let name = quoted(&element.name);
    let Some(roles) = roles else {
        return Some(format!(
            "element {name} ({} rows) is read but ignored",
            element.count
        ));
    };
    let skipped: Vec<String> = element
        .properties
        .iter()
        .zip(roles)
        .filter(|(_, &r)| r == Role::Skip)
        .map(|(p, _)| quoted(&p.name))
        .collect();
    let alpha = element.properties.iter().any(|p| p.name == "alpha");
    match skipped.len() {
        0 => None,
        1 => Some(format!(
            "element {name}: property {} is read but ignored{}",
            skipped[0],
            if alpha {
                " (penumbra has no vertex transparency)"
            } else {
                ""
            }
        )),
        _ => Some(format!(
            "element {name}: properties {} are read but ignored{}",
            skipped.join(", "),
            if alpha {
                " (`alpha`: penumbra has no vertex transparency)"
            } else {
                ""
            }
        )),
    }
}

/// What an integer colour channel of type `ty` is divided by to give [0, 1] (1 for floats).
pub(super) fn color_range(ty: Scalar) -> f64 {
    match ty {
        Scalar::U8 => u8::MAX.into(),
        Scalar::I8 => i8::MAX.into(),
        Scalar::U16 => u16::MAX.into(),
        Scalar::I16 => i16::MAX.into(),
        Scalar::U32 => u32::MAX.into(),
        Scalar::I32 => i32::MAX.into(),
        Scalar::F32 | Scalar::F64 => 1.0,
    }
}
