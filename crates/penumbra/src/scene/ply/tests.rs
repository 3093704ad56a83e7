use glam::{Vec2, Vec3};

use super::header::Scalar;
use super::roles::UV_NAMES;
use super::*;

/// A quad (two triangles after the fan) in the plane z = 0, as ASCII.
const QUAD: &str = "ply\nformat ascii 1.0\ncomment a unit square\nelement vertex 4\n\
property float x\nproperty float y\nproperty float z\nelement face 1\n\
property list uchar int vertex_indices\nend_header\n\
0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";

pub(super) fn parse(text: &str) -> Result<Mesh, PlyError> {
    parse_ply(text.as_bytes())
}

/// A binary PLY of the header `head` (without `ply`, `format` and `end_header`) and `body`.
pub(super) fn binary(big: bool, head: &str, body: &[u8]) -> Vec<u8> {
    let order = if big { "big" } else { "little" };
    let mut bytes =
        format!("ply\nformat binary_{order}_endian 1.0\n{head}end_header\n").into_bytes();
    bytes.extend_from_slice(body);
    bytes
}

/// Appends the bytes of `values`, each written as `ty` in the byte order `big`.
pub(super) fn put(out: &mut Vec<u8>, big: bool, values: &[(Scalar, f64)]) {
    for &(ty, v) in values {
        let le: Vec<u8> = match ty {
            Scalar::I8 => (v as i8).to_le_bytes().to_vec(),
            Scalar::U8 => (v as u8).to_le_bytes().to_vec(),
            Scalar::I16 => (v as i16).to_le_bytes().to_vec(),
            Scalar::U16 => (v as u16).to_le_bytes().to_vec(),
            Scalar::I32 => (v as i32).to_le_bytes().to_vec(),
            Scalar::U32 => (v as u32).to_le_bytes().to_vec(),
            Scalar::F32 => (v as f32).to_le_bytes().to_vec(),
            Scalar::F64 => v.to_le_bytes().to_vec(),
        };
        out.extend(
            le.iter()
                .rev()
                .filter(|_| big)
                .chain(le.iter().filter(|_| !big)),
        );
    }
}

#[test]
fn an_ascii_quad_is_fanned_into_two_triangles() {
    let mesh = parse(QUAD).unwrap();
    assert_eq!(mesh.indices, [[0, 1, 2], [0, 2, 3]]);
    assert_eq!(mesh.positions[2], Vec3::new(1.0, 1.0, 0.0));
    assert_eq!(mesh.material_slots, [0, 0]);
    assert!(mesh.normals.is_empty() && mesh.uvs.is_empty());
    // A pentagon gives three triangles, all from corner 0.
    let pentagon = QUAD
        .replace("element vertex 4", "element vertex 5")
        .replace("0 1 0\n4 0 1 2 3", "0 1 0\n0 2 0\n5 4 3 2 1 0");
    let mesh = parse(&pentagon).unwrap();
    assert_eq!(mesh.indices, [[4, 3, 2], [4, 2, 1], [4, 1, 0]]);
}

#[test]
fn binary_files_read_the_same_in_both_byte_orders() {
    use Scalar::*;
    let head = "element vertex 3\nproperty double x\nproperty float y\nproperty short z\n\
                property uchar red\nproperty float nx\nproperty float ny\nproperty float nz\n\
                property float u\nproperty float v\n\
                element face 1\nproperty ushort flags\nproperty list char uint vertex_index\n\
                property list int double junk\n";
    for big in [false, true] {
        let mut body = Vec::new();
        for (i, (x, y, z)) in [(0.5, 0.0, 0.0), (1.0, -2.0, 3.0), (0.0, 1.0, -7.0)]
            .into_iter()
            .enumerate()
        {
            let i = i as f64;
            let vertex = [(F64, x), (F32, y), (I16, z), (U8, 200.0)];
            let normal = [(F32, 0.0), (F32, 0.0), (F32, 1.0), (F32, i), (F32, 1.0 - i)];
            put(&mut body, big, &vertex);
            put(&mut body, big, &normal);
        }
        put(&mut body, big, &[(U16, 9.0), (I8, 3.0)]);
        put(&mut body, big, &[(U32, 0.0), (U32, 2.0), (U32, 1.0)]);
        put(&mut body, big, &[(I32, 2.0), (F64, 1.5), (F64, 2.5)]);
        let mesh = parse_ply(&binary(big, head, &body)).unwrap();
        assert_eq!(mesh.indices, [[0, 2, 1]], "big endian: {big}");
        assert_eq!(mesh.positions[1], Vec3::new(1.0, -2.0, 3.0));
        assert_eq!(mesh.positions[2], Vec3::new(0.0, 1.0, -7.0));
        assert_eq!(mesh.normals, [Vec3::Z; 3]);
        assert_eq!(mesh.uvs[2], Vec2::new(2.0, -1.0));
    }
}

#[test]
fn uvs_are_read_under_each_of_their_names_and_normals_with_them() {
    for [u, v] in UV_NAMES {
        let text = QUAD.replace(
            "property float z\n",
            &format!(
                "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
                 property float {u}\nproperty float {v}\n"
            ),
        );
        let text = text.replace(
            "0 0 0\n1 0 0\n1 1 0\n0 1 0\n",
            "0 0 0 0 0 1 0.25 0.5\n1 0 0 0 0 1 1 0\n1 1 0 0 0 1 1 1\n0 1 0 0 0 nan 0 1\n",
        );
        let mesh = parse(&text).unwrap();
        assert_eq!(mesh.uvs[0], Vec2::new(0.25, 0.5), "{u}/{v}");
        assert_eq!(mesh.normals[0], Vec3::Z);
        // A normal that is not finite is none.
        assert_eq!(mesh.normals[3], Vec3::ZERO);
    }
    // Half a pair is no uvs.
    let text = QUAD.replace("property float z\n", "property float z\nproperty float u\n");
    let text = text.replace(
        "0 0 0\n1 0 0\n1 1 0\n0 1 0\n",
        "0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1\n",
    );
    assert!(parse(&text).unwrap().uvs.is_empty());
}

#[test]
fn unknown_elements_and_properties_are_skipped() {
    let text = "ply\r\nformat ascii 1.0\r\nobj_info scanned\r\nelement camera 1\r\n\
                property float view_px\r\nproperty list uchar float stuff\r\n\
                element vertex 3\r\nproperty uchar red\r\nproperty float x\r\nproperty float y\r\n\
                property float z\r\nproperty float confidence\r\nelement empty 99999999999\r\n\
                element face 1\r\nproperty list uchar float texcoord\r\n\
                property list uint uint vertex_indices\r\nproperty int flags\r\n\
                element edge 1\r\nproperty int vertex1\r\nproperty int vertex2\r\nend_header\r\n\
                1.5 3 7 8 9\r\n255 0 0 0 0.5\r\n255 1 0 0 0.5\r\n255 0 1 0 0.5\r\n\
                6 0 0 1 0 0 1 3 2 1 0 7\r\n0 1\r\n";
    let ply = read_ply(text.as_bytes()).unwrap();
    let mesh = &ply.mesh;
    // The face's `texcoord` list gives its corners (vertices 2, 1, 0) their uvs; the vertices
    // are numbered anew in the order the corners use them.
    assert_eq!(mesh.indices, [[0, 1, 2]]);
    assert_eq!(mesh.positions, [Vec3::Y, Vec3::X, Vec3::ZERO]);
    assert_eq!(mesh.uvs, [Vec2::ZERO, Vec2::X, Vec2::Y]);
    // `red` alone is no colour.
    assert!(mesh.colors.is_empty());
    assert_eq!(
        ply.warnings,
        [
            "element `camera` (1 rows) is read but ignored",
            "element `vertex`: properties `red`, `confidence` are read but ignored",
            "element `empty` (99999999999 rows) is read but ignored",
            "element `face`: property `flags` is read but ignored",
            "element `edge` (1 rows) is read but ignored",
        ]
    );
}

/// A triangle with colours `red`, `green`, `blue` (and `alpha`) of type `ty`, in `format`.
fn colored(ty: &str, format: &str, rows: [[f64; 4]; 3]) -> Vec<u8> {
    let head = format!(
        "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
         property {ty} red\nproperty {ty} green\nproperty {ty} blue\nproperty {ty} alpha\n\
         element face 1\nproperty list uchar int vertex_indices\n"
    );
    let scalar = if ty == "uchar" {
        Scalar::U8
    } else {
        Scalar::F32
    };
    let corners = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    if format == "ascii" {
        let mut text = format!("ply\nformat ascii 1.0\n{head}end_header\n");
        for (p, c) in corners.iter().zip(rows) {
            let values: Vec<String> = p.iter().chain(&c).map(f64::to_string).collect();
            text += &format!("{}\n", values.join(" "));
        }
        return (text + "3 0 1 2\n").into_bytes();
    }
    let big = format == "big";
    let mut body = Vec::new();
    for (p, c) in corners.iter().zip(rows) {
        put(&mut body, big, &p.map(|v| (Scalar::F32, v)));
        put(&mut body, big, &c.map(|v| (scalar, v)));
    }
    put(&mut body, big, &[(Scalar::U8, 3.0)]);
    put(
        &mut body,
        big,
        &[(Scalar::I32, 0.0), (Scalar::I32, 1.0), (Scalar::I32, 2.0)],
    );
    binary(big, &head, &body)
}

#[test]
fn colours_are_read_as_srgb_bytes_or_floats_in_every_format() {
    let bytes = [
        [255.0, 0.0, 128.0, 7.0],
        [0.0, 255.0, 0.0, 7.0],
        [0.0, 0.0, 255.0, 7.0],
    ];
    let floats = bytes.map(|r| r.map(|v| v / 255.0));
    let mut meshes = Vec::new();
    for format in ["ascii", "little", "big"] {
        for (ty, rows) in [("uchar", bytes), ("float", floats)] {
            let ply = read_ply(&colored(ty, format, rows)).unwrap();
            assert_eq!(
                ply.warnings,
                [
                    "element `vertex`: property `alpha` is read but ignored (penumbra has no \
                  vertex transparency)"
                ]
            );
            meshes.push(ply.mesh);
        }
    }
    let red = meshes[0].colors[0];
    // 128/255 in sRGB is about 0.216 in linear.
    assert_eq!((red.x, red.y), (1.0, 0.0));
    assert!((red.z - 0.2158).abs() < 1e-3, "{red}");
    assert_eq!(meshes[0].colors[1..], [Vec3::Y, Vec3::Z]);
    for m in &meshes[1..] {
        assert_eq!(m.positions, meshes[0].positions);
        assert!(m
            .colors
            .iter()
            .zip(&meshes[0].colors)
            .all(|(a, b)| (*a - *b).length() < 1e-6));
    }
    let nan = [[f64::NAN, 0.0, 0.0, 1.0], [0.0; 4], [0.0; 4]];
    let e = read_ply(&colored("float", "little", nan)).unwrap_err();
    assert!(
        e.message
            .contains("row 0, property `red`: colour NaN is not a finite"),
        "{e}"
    );
}

#[test]
fn texture_files_and_face_texcoords_make_a_textured_mesh() {
    let text = QUAD
        .replace(
            "comment a unit square",
            "comment TextureFile my tex.png\ncomment TextureFile b.png",
        )
        .replace(
            "vertex_indices",
            "vertex_indices\nproperty list uchar float texcoord",
        )
        .replace("4 0 1 2 3", "4 0 1 2 3 8 0 0 1 0 1 1 0 1");
    let ply = read_ply(text.as_bytes()).unwrap();
    assert_eq!(ply.texture_file.as_deref(), Some("my tex.png"));
    assert_eq!(ply.mesh.uvs[2], Vec2::ONE);
    assert_eq!(
        ply.warnings,
        ["only the first `comment TextureFile` is used; ignored: `b.png`"]
    );
    let short = text.replace("8 0 0 1 0 1 1 0 1", "3 0 0 1");
    let e = read_ply(short.as_bytes()).unwrap_err();
    assert!(e.message.contains("has 3 values for 4 corners"), "{e}");
    let untextured = QUAD.replace("comment a unit square", "comment TextureFile t.png");
    let w = read_ply(untextured.as_bytes()).unwrap().warnings;
    assert_eq!(
        w,
        ["the texture file `t.png` is named but the mesh has no texture coordinates"]
    );
}

#[test]
fn bulk_binary_reads_hand_polygons_and_bad_rows_to_the_value_reader() {
    let head = "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
                element face 3\nproperty list uchar int vertex_indices\n";
    let mut body = Vec::new();
    for p in [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ] {
        put(&mut body, false, &p.map(|v| (Scalar::F32, v)));
    }
    let face = |corners: &[f64]| {
        let mut out = Vec::new();
        put(&mut out, false, &[(Scalar::U8, corners.len() as f64)]);
        put(
            &mut out,
            false,
            &corners
                .iter()
                .map(|&c| (Scalar::I32, c))
                .collect::<Vec<_>>(),
        );
        out
    };
    let mut good = body.clone();
    for f in [
        &[0.0, 1.0, 2.0][..],
        &[0.0, 1.0, 2.0, 3.0],
        &[3.0, 2.0, 1.0],
    ] {
        good.extend(face(f));
    }
    let mesh = parse_ply(&binary(false, head, &good)).unwrap();
    assert_eq!(mesh.indices, [[0, 1, 2], [0, 1, 2], [0, 2, 3], [3, 2, 1]]);
    let mut bad = body;
    for f in [&[0.0, 1.0, 2.0][..], &[0.0, -1.0, 2.0], &[0.0, 1.0, 2.0]] {
        bad.extend(face(f));
    }
    let e = parse_ply(&binary(false, head, &bad)).unwrap_err();
    assert!(
        e.message
            .contains("`face` row 1, property `vertex_indices`: vertex index -1"),
        "{e}"
    );
}

#[test]
fn ply_paths_are_known_by_their_extension_in_any_case() {
    assert!(is_ply(Path::new("a/b.ply")) && is_ply(Path::new("B.PLY")));
    assert!(!is_ply(Path::new("b.obj")) && !is_ply(Path::new("ply")));
}
