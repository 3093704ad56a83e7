//! Small glTF files written here: each feature and each bad input, read from bytes.

use std::path::Path;

use glam::{Vec2, Vec3};
use gltf::mesh::Mode;
use serde_json::{json, Value};

use super::meshes::triangles;
use super::{parse_gltf, GltfError, GltfLightKind, GltfModel};
use crate::files::Files;

/// Standard base64 with padding.
fn base64(bytes: &[u8]) -> String {
    const ABC: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in bytes.chunks(3) {
        let n = c
            .iter()
            .enumerate()
            .fold(0u32, |n, (i, &b)| n | (b as u32) << (16 - 8 * i));
        for k in 0..4 {
            match k <= c.len() {
                true => out.push(ABC[(n >> (18 - 6 * k) & 63) as usize] as char),
                false => out.push('='),
            }
        }
    }
    out
}

fn floats(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|f| f.to_le_bytes()).collect()
}

/// A file with one buffer (a data URI of `bin`), one mesh of one primitive whose attributes
/// and indices are `primitive`, over `accessors` and `views`, placed by one node.
fn file(bin: &[u8], views: Value, accessors: Value, primitive: Value) -> Value {
    json!({
        "asset": {"version": "2.0"},
        "buffers": [{
            "byteLength": bin.len(),
            "uri": format!("data:application/octet-stream;base64,{}", base64(bin)),
        }],
        "bufferViews": views,
        "accessors": accessors,
        "meshes": [{"primitives": [primitive]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    })
}

/// One triangle (0,0,0), (1,0,0), (0,1,0) with u8 indices 0 1 2.
pub(super) fn triangle() -> Value {
    let mut bin = floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    bin.extend([0u8, 1, 2, 0]);
    file(
        &bin,
        json!([
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 3},
        ]),
        json!([
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5121, "count": 3, "type": "SCALAR"},
        ]),
        json!({"attributes": {"POSITION": 0}, "indices": 1}),
    )
}

pub(super) fn read(v: &Value) -> Result<GltfModel, GltfError> {
    parse_gltf(
        v.to_string().as_bytes(),
        Path::new("/nonexistent"),
        &Files::disk(),
        None,
    )
}

/// A GLB of `json` and `bin`.
fn glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut j = json.to_string().into_bytes();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((j.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(j);
    out.extend((b.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(b);
    out
}

pub(super) fn read_bytes(bytes: &[u8]) -> Result<GltfModel, GltfError> {
    parse_gltf(bytes, Path::new("/nonexistent"), &Files::disk(), None)
}

#[test]
fn a_data_uri_buffer_with_u8_indices_gives_one_triangle() {
    let model = read(&triangle()).unwrap();
    assert_eq!(model.meshes.len(), 1);
    assert_eq!(model.meshes[0].mesh.indices, [[0, 1, 2]]);
    assert_eq!(model.meshes[0].mesh.positions[1], Vec3::X);
    assert_eq!(model.uses.len(), 1);
}

#[test]
fn a_glb_reads_its_bin_chunk_and_node_transforms_apply() {
    let mut v = triangle();
    let bin = {
        let mut b = floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
        b.extend([0u8, 1, 2]);
        b
    };
    v["buffers"] = json!([{"byteLength": bin.len()}]);
    v["nodes"] =
        json!([{"children": [1], "translation": [0, 0, 5]}, {"mesh": 0, "scale": [2, 2, 2]}]);
    let model = read_bytes(&glb(&v, &bin)).unwrap();
    let m = model.uses[0].matrix;
    assert_eq!(m.transform_point3(Vec3::X), Vec3::new(2.0, 0.0, 5.0));
}

#[test]
fn strips_and_fans_assemble_as_the_spec_says() {
    let c = [0, 1, 2, 3, 4];
    assert_eq!(
        triangles(Mode::TriangleStrip, &c),
        [[0, 1, 2], [1, 3, 2], [2, 3, 4]]
    );
    assert_eq!(
        triangles(Mode::TriangleFan, &c),
        [[1, 2, 0], [2, 3, 0], [3, 4, 0]]
    );
    assert_eq!(triangles(Mode::Triangles, &c), [[0, 1, 2]]);
    assert!(triangles(Mode::TriangleStrip, &c[..2]).is_empty());
}

#[test]
fn a_non_indexed_fan_reads_its_vertices_in_order() {
    let mut v = triangle();
    v["meshes"][0]["primitives"][0] = json!({"attributes": {"POSITION": 0}, "mode": 6});
    let model = read(&v).unwrap();
    assert_eq!(model.meshes[0].mesh.indices, [[1, 2, 0]]);
}

#[test]
fn lines_are_skipped_with_a_warning() {
    let mut v = triangle();
    let tri = v["meshes"][0]["primitives"][0].clone();
    v["meshes"][0]["primitives"] = json!([tri, {"attributes": {"POSITION": 0}, "mode": 1}]);
    let model = read(&v).unwrap();
    assert_eq!(model.meshes[0].mesh.len(), 1);
    assert!(
        model.warnings.iter().any(|w| w.contains("lines")),
        "{:?}",
        model.warnings
    );
}

#[test]
fn a_sparse_accessor_substitutes_its_values() {
    // Base positions as before; sparse: vertex 2 becomes (0, 3, 0).
    let mut bin = floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    bin.extend([2u8, 0, 0, 0]);
    bin.extend(floats(&[0.0, 3.0, 0.0]));
    let v = file(
        &bin,
        json!([
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 1},
            {"buffer": 0, "byteOffset": 40, "byteLength": 12},
        ]),
        json!([{
            "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
            "sparse": {
                "count": 1,
                "indices": {"bufferView": 1, "componentType": 5121},
                "values": {"bufferView": 2},
            },
        }]),
        json!({"attributes": {"POSITION": 0}}),
    );
    let model = read(&v).unwrap();
    assert_eq!(model.meshes[0].mesh.positions[2], Vec3::new(0.0, 3.0, 0.0));
}

#[test]
fn normalized_u8_texcoords_with_a_stride_are_read_and_flipped() {
    // Interleaved: position (12 bytes) + uv as normalized u8 (2 bytes) + 2 padding.
    let mut bin = Vec::new();
    for (p, uv) in [
        ([0.0, 0.0, 0.0], [0u8, 0]),
        ([1.0, 0.0, 0.0], [255, 0]),
        ([0.0, 1.0, 0.0], [0, 255]),
    ] {
        bin.extend(floats(&p));
        bin.extend(uv);
        bin.extend([0, 0]);
    }
    let v = file(
        &bin,
        json!([{"buffer": 0, "byteLength": 48, "byteStride": 16}]),
        json!([
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 0, "byteOffset": 12, "componentType": 5121, "normalized": true, "count": 3, "type": "VEC2"},
        ]),
        json!({"attributes": {"POSITION": 0, "TEXCOORD_0": 1}}),
    );
    let model = read(&v).unwrap();
    let uvs = &model.meshes[0].mesh.uvs;
    assert_eq!(uvs[1], Vec2::new(1.0, 1.0));
    assert_eq!(uvs[2], Vec2::new(0.0, 0.0));
    assert_eq!(model.meshes[0].mesh.positions[2], Vec3::Y);
}

#[test]
fn khr_texture_transform_becomes_scale_and_offset_with_t_up() {
    let mut v = triangle();
    v["extensionsUsed"] = json!(["KHR_texture_transform"]);
    v["images"] = json!([{"uri": "data:image/png;base64,AAAA"}]);
    v["textures"] = json!([{"source": 0}]);
    v["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {
        "index": 0,
        "extensions": {"KHR_texture_transform": {"offset": [0.25, 0.5], "scale": [2, 0.5]}},
    }}}]);
    v["meshes"][0]["primitives"][0]["material"] = json!(0);
    let model = read(&v).unwrap();
    let t = model.materials[0].texture.as_ref().unwrap();
    assert_eq!(t.uv_scale, Vec2::new(2.0, 0.5));
    // t' = s·t + (1 − s − o) = 0.5·t + 0.
    assert_eq!(t.uv_offset, Vec2::new(0.25, 0.0));
    assert!(model.images[0].is_some());
}

#[test]
fn lights_and_a_camera_are_read_at_their_nodes() {
    let mut v = triangle();
    v["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    v["extensions"] = json!({"KHR_lights_punctual": {"lights": [
        {"type": "point", "color": [1, 0.5, 0.25], "intensity": 20},
        {"type": "spot", "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.4}, "range": 5},
        {"type": "directional", "intensity": 3},
    ]}});
    v["cameras"] =
        json!([{"type": "perspective", "name": "cam", "perspective": {"yfov": 0.5, "znear": 0.1}}]);
    // The directional light's node turns −z down to −y (−90° about x).
    let s = std::f32::consts::FRAC_1_SQRT_2;
    v["nodes"] = json!([
        {"mesh": 0},
        {"translation": [1, 2, 3], "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"translation": [0, 0, 4], "camera": 0},
        {"extensions": {"KHR_lights_punctual": {"light": 1}}},
        {"rotation": [-s, 0, 0, s], "extensions": {"KHR_lights_punctual": {"light": 2}}},
    ]);
    v["scenes"] = json!([{"nodes": [0, 1, 2, 3, 4]}]);
    let model = read(&v).unwrap();
    assert_eq!(model.lights.len(), 3);
    assert_eq!(model.lights[0].position, Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(model.lights[0].intensity, 20.0);
    assert_eq!(model.lights[0].kind, GltfLightKind::Point);
    assert_eq!(
        model.lights[1].kind,
        GltfLightKind::Spot {
            inner: 0.1,
            outer: 0.4
        }
    );
    assert_eq!(model.lights[1].direction, Vec3::NEG_Z);
    assert_eq!(model.lights[2].kind, GltfLightKind::Directional);
    assert!((model.lights[2].direction - Vec3::NEG_Y).length() < 1e-6);
    assert!(
        model.warnings.iter().any(|w| w.contains("range")),
        "{:?}",
        model.warnings
    );
    let c = &model.cameras[0];
    assert_eq!(c.name, "cam");
    assert!((c.fov_y_deg - 0.5f32.to_degrees()).abs() < 1e-4);
    let (position, look_at, up) = c.view(glam::Mat4::IDENTITY);
    assert_eq!(
        (position, look_at, up),
        (Vec3::new(0.0, 0.0, 4.0), Vec3::new(0.0, 0.0, 3.0), Vec3::Y)
    );
}

#[test]
fn a_mesh_used_by_two_nodes_is_read_once() {
    let mut v = triangle();
    v["nodes"] = json!([{"mesh": 0}, {"mesh": 0, "translation": [3, 0, 0]}]);
    v["scenes"] = json!([{"nodes": [0, 1]}]);
    let model = read(&v).unwrap();
    assert_eq!((model.meshes.len(), model.uses.len()), (1, 2));
}

/// The error of reading `v`, as `at: message`.
fn error(v: &Value) -> String {
    read(v).unwrap_err().to_string()
}

#[test]
fn a_required_compression_extension_is_refused_by_name() {
    let mut v = triangle();
    v["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    v["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    let e = error(&v);
    assert!(e.starts_with("extensionsRequired[0]: "), "{e}");
    assert!(
        e.contains("KHR_draco_mesh_compression") && e.contains("uncompressed"),
        "{e}"
    );
}

#[test]
fn bad_inputs_name_their_json_path() {
    type Edit = fn(&mut Value);
    let cases: Vec<(Edit, &str)> = vec![
        (
            |v| v["accessors"][0]["count"] = json!(4),
            "meshes[0].primitives[0].attributes.POSITION",
        ),
        (
            |v| v["bufferViews"][0]["byteLength"] = json!(400),
            "bufferViews[0]",
        ),
        (
            |v| v["accessors"][1]["count"] = json!(4),
            "meshes[0].primitives[0].indices",
        ),
        (
            |v| v["meshes"][0]["primitives"][0]["indices"] = json!(7),
            "meshes[0].primitives[0].indices",
        ),
        (
            |v| v["meshes"][0]["primitives"][0]["attributes"] = json!({}),
            "meshes[0].primitives[0].attributes",
        ),
        (
            |v| v["buffers"][0]["uri"] = json!("missing.bin"),
            "buffers[0].uri",
        ),
        (
            |v| v["buffers"][0]["byteLength"] = json!(100),
            "buffers[0].byteLength",
        ),
        (
            |v| v["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(9),
            "meshes[0].primitives[0].attributes.POSITION",
        ),
        (
            |v| v["nodes"] = json!([{"mesh": 0, "children": [0]}]),
            "nodes[0]",
        ),
    ];
    for (edit, at) in cases {
        let mut v = triangle();
        edit(&mut v);
        let e = error(&v);
        assert!(e.starts_with(at), "expected {at}: {e}");
    }
}

#[test]
fn an_index_past_the_vertices_and_a_nan_position_are_refused() {
    let mut bin = floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, f32::NAN, 0.0]);
    bin.extend([0u8, 1, 3, 0]);
    let v = file(
        &bin,
        json!([{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 3}]),
        json!([
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5121, "count": 3, "type": "SCALAR"},
        ]),
        json!({"attributes": {"POSITION": 0}, "indices": 1}),
    );
    let e = error(&v);
    assert!(
        e.starts_with("meshes[0].primitives[0].attributes.POSITION: vertex 2"),
        "{e}"
    );
    let mut v = v;
    v["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(0);
    let good = floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let mut bin = good;
    bin.extend([0u8, 1, 3, 0]);
    v["buffers"][0]["uri"] = json!(format!(
        "data:application/octet-stream;base64,{}",
        base64(&bin)
    ));
    let e = error(&v);
    assert!(
        e.starts_with("meshes[0].primitives[0].indices: index 2 is 3"),
        "{e}"
    );
}

#[test]
fn broken_containers_are_errors_not_panics() {
    let v = triangle();
    let good = glb(&v, &[]);
    let mut wrong_version = good.clone();
    wrong_version[4] = 1;
    let mut short_length = good.clone();
    short_length[8..12].copy_from_slice(&3u32.to_le_bytes());
    let cases: Vec<(Vec<u8>, &str)> = vec![
        (good[..good.len() - 5].to_vec(), "truncated GLB"),
        (good[..7].to_vec(), "truncated GLB"),
        (wrong_version, "version 1"),
        (short_length, "no JSON chunk"),
        (b"PK\x03\x04zip".to_vec(), "not a glTF file"),
        (b"{\"asset\": ".to_vec(), "JSON cannot be read"),
    ];
    for (bytes, message) in cases {
        let e = read_bytes(&bytes).unwrap_err().to_string();
        assert!(e.contains(message), "expected {message}: {e}");
    }
    assert!(read_bytes(&good).is_ok());
}

#[test]
fn a_file_without_triangles_is_refused() {
    let mut v = triangle();
    v["nodes"] = json!([{}]);
    assert!(error(&v).contains("no triangles"));
}

#[test]
fn an_unused_missing_image_is_never_looked_for() {
    let mut v = triangle();
    v["images"] = json!([{"uri": "absent.png"}]);
    v["textures"] = json!([{"source": 0}]);
    v["materials"] = json!([{"normalTexture": {"index": 0}}]);
    v["meshes"][0]["primitives"][0]["material"] = json!(0);
    let model = read(&v).unwrap();
    assert!(model.images[0].is_none());
    assert!(model.warnings.iter().any(|w| w.contains("normal map")));
    // As a base colour texture it is needed, and its absence names the file and the path.
    v["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
    let e = error(&v);
    assert!(
        e.starts_with("images[0].uri: ") && e.contains("absent.png"),
        "{e}"
    );
}

#[test]
fn color_0_as_normalized_u8_rgba_becomes_vertex_colours() {
    let mut bin = floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    bin.extend([255u8, 0, 0, 128, 0, 255, 0, 255, 0, 0, 51, 0]);
    let v = file(
        &bin,
        json!([{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 12}]),
        json!([
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5121, "normalized": true, "count": 3, "type": "VEC4"},
        ]),
        json!({"attributes": {"POSITION": 0, "COLOR_0": 1}}),
    );
    let colors = &read(&v).unwrap().meshes[0].mesh.colors;
    assert_eq!(colors.len(), 3);
    assert_eq!(colors[0], Vec3::X);
    assert_eq!(colors[1], Vec3::Y);
    assert!((colors[2] - Vec3::new(0.0, 0.0, 0.2)).length() < 1e-6);
}

#[test]
fn an_image_in_a_buffer_view_needs_no_mime_type_and_an_image_needs_a_source() {
    let mut v = triangle();
    v["bufferViews"]
        .as_array_mut()
        .unwrap()
        .push(json!({"buffer": 0, "byteLength": 8}));
    v["images"] = json!([{"bufferView": 2}]);
    v["textures"] = json!([{"source": 0}]);
    v["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
    v["meshes"][0]["primitives"][0]["material"] = json!(0);
    let model = read(&v).unwrap();
    assert!(matches!(model.images[0], Some(super::ImageSource::Bytes(ref b)) if b.len() == 8));
    v["images"] = json!([{"name": "nothing"}]);
    let e = error(&v);
    assert!(
        e.starts_with("images[0].uri: ") && e.contains("neither"),
        "{e}"
    );
}
