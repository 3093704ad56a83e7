//! The file itself: a GLB container (12-byte header, a JSON chunk, an optional BIN chunk) or
//! plain JSON; the JSON parsed by the `gltf` crate (its errors located at their JSON path),
//! its required extensions checked against those penumbra reads, then every index validated.

use super::{GltfError, Result};

/// Extensions penumbra reads; a file may require these and still load.
pub(super) const READ_EXTENSIONS: [&str; 2] = ["KHR_lights_punctual", "KHR_texture_transform"];

/// The parsed document and the GLB's BIN chunk, if any.
pub(super) struct Parsed {
    pub document: gltf::Document,
    pub blob: Option<Vec<u8>>,
}

/// Parses `bytes` as GLB (when they start with `glTF`) or JSON.
pub(super) fn parse(bytes: &[u8]) -> Result<Parsed> {
    let (json, blob) = match bytes.starts_with(b"glTF") {
        true => {
            let (json, blob) = split_glb(bytes)?;
            (json, blob.map(<[u8]>::to_vec))
        }
        false => (bytes, None),
    };
    // A UTF-8 byte order mark is allowed before the JSON.
    let json = json.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(json);
    let first = json.iter().find(|b| !b.is_ascii_whitespace());
    if first.is_some_and(|&b| b != b'{') {
        let shown = bytes.iter().take(4).map(|b| b.escape_ascii().to_string());
        return Err(GltfError::new(
            "",
            format!(
                "not a glTF file: it starts with \"{}\", neither the GLB magic \"glTF\" nor \
                 a JSON object",
                shown.collect::<String>()
            ),
        ));
    }
    let root: gltf::json::Root = gltf::json::deserialize::from_slice(json)
        .map_err(|e| super::json_path::located(json, &e))?;
    check_required(&root)?;
    validate(&root)?;
    let document = gltf::Document::from_json_without_validation(root);
    Ok(Parsed { document, blob })
}

/// The JSON chunk and the BIN chunk of a GLB file.
fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>)> {
    let word = |at: usize| -> Option<u32> {
        let b = bytes.get(at..at + 4)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let truncated = |what: &str| {
        GltfError::new(
            "",
            format!(
                "truncated GLB: the file ends ({} bytes) inside {what}",
                bytes.len()
            ),
        )
    };
    let version = word(4).ok_or_else(|| truncated("the 12-byte header"))?;
    if version != 2 {
        return Err(GltfError::new(
            "",
            format!("GLB version {version}: only glTF 2.0 (version 2) is read"),
        ));
    }
    let length = word(8).ok_or_else(|| truncated("the 12-byte header"))? as usize;
    if length > bytes.len() {
        return Err(GltfError::new(
            "",
            format!(
                "truncated GLB: the header says {length} bytes, the file has {}",
                bytes.len()
            ),
        ));
    }
    let body = &bytes[..length.max(12)];
    let (json, rest) = chunk(body, 12, *b"JSON")?;
    let json = json.ok_or_else(|| GltfError::new("", "the GLB has no JSON chunk"))?;
    let (bin, _) = chunk(body, rest, *b"BIN\0")?;
    Ok((json, bin))
}

/// The chunk of type `kind` at byte `at` of `body` (`None` at the end of the body), and the
/// offset after it.
fn chunk(body: &[u8], at: usize, kind: [u8; 4]) -> Result<(Option<&[u8]>, usize)> {
    if at >= body.len() {
        return Ok((None, at));
    }
    let header = body.get(at..at + 8).ok_or_else(|| {
        GltfError::new(
            "",
            format!("truncated GLB: a chunk header at byte {at} is cut off"),
        )
    })?;
    let length = u32::from_le_bytes([header[0], header[1], header[2], header[3]]) as usize;
    if header[4..8] != kind {
        return Err(GltfError::new(
            "",
            format!(
                "the GLB chunk at byte {at} is of type \"{}\", expected \"{}\"",
                header[4..8].escape_ascii(),
                kind.escape_ascii()
            ),
        ));
    }
    let start = at + 8;
    let data = body
        .get(start..start.saturating_add(length))
        .ok_or_else(|| {
            GltfError::new(
                "",
                format!(
                    "truncated GLB: the {} chunk at byte {at} claims {length} bytes, {} are left",
                    kind.escape_ascii(),
                    body.len() - start
                ),
            )
        })?;
    Ok((Some(data), start + length))
}

/// Refuses a file that requires an extension penumbra does not read.
fn check_required(root: &gltf::json::Root) -> Result<()> {
    for (i, ext) in root.extensions_required.iter().enumerate() {
        if READ_EXTENSIONS.contains(&ext.as_str()) {
            continue;
        }
        let why = match ext.as_str() {
            "KHR_draco_mesh_compression" | "EXT_meshopt_compression" => {
                "compressed geometry is not read: re-export the file uncompressed (without Draco \
                 or meshopt compression)"
            }
            "KHR_texture_basisu" | "EXT_texture_webp" | "EXT_texture_avif" | "MSFT_texture_dds" => {
                "only PNG and JPEG images are read: re-export the file with PNG or JPEG textures"
            }
            "KHR_mesh_quantization" => {
                "quantized geometry is not read: re-export the file without quantization"
            }
            _ => "re-export the file without it (uncompressed, core glTF 2.0)",
        };
        return Err(GltfError::new(
            format!("extensionsRequired[{i}]"),
            format!("the file requires the extension {ext}, which penumbra does not read; {why}"),
        ));
    }
    Ok(())
}

/// Refuses a POSITION attribute naming an accessor the file does not have: the `gltf`
/// crate's validation looks that accessor up without checking (gltf-json 1.4.1,
/// `primitive_validate_hook`) and would panic; found by fuzzing.
fn check_positions(root: &gltf::json::Root) -> Result<()> {
    use gltf::json::mesh::Semantic;
    use gltf::json::validation::Checked;
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = primitive
                .attributes
                .get(&Checked::Valid(Semantic::Positions));
            if let Some(i) = position.filter(|i| i.value() >= root.accessors.len()) {
                return Err(GltfError::new(
                    format!("meshes[{m}].primitives[{p}].attributes.POSITION"),
                    format!(
                        "accessor {} does not exist (the file has {})",
                        i.value(),
                        root.accessors.len()
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Checks every index of the document (the `gltf` crate's validation), so that no lookup
/// can fail later. POSITION accessors without `min` and `max` (which the spec asks for and
/// penumbra does not use) are let through.
fn validate(root: &gltf::json::Root) -> Result<()> {
    use gltf::json::validation::{Error, Validate};
    check_positions(root)?;
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| {
        let path = path().to_string();
        let bounds = path.ends_with(".min") || path.ends_with(".max");
        if !(bounds && error == Error::Missing) {
            errors.push((path, error));
        }
    });
    let more = errors.len().saturating_sub(1);
    let Some((path, error)) = errors.into_iter().next() else {
        return Ok(());
    };
    let what = match error {
        Error::IndexOutOfBounds => "index out of range (it names an entry the file does not have)",
        Error::Invalid => "invalid value",
        Error::Missing => "missing value",
        Error::Oversize => "value too large",
        Error::Unsupported => "unsupported extension",
    };
    let more = match more {
        0 => String::new(),
        n => format!(" (and {n} more problem{})", if n == 1 { "" } else { "s" }),
    };
    Err(GltfError::new(path, format!("{what}{more}")))
}
