//! PLY bad input: every error names where (line, element, byte) and what, and reservations
//! follow the bytes present, not the header's counts.

use super::header::Scalar;
use super::tests::{binary, parse, put};
use super::*;

#[test]
fn bad_files_are_errors_naming_where_and_what() {
    let tri = |vertex_count: &str, face: &str| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex {vertex_count}\nproperty float x\n\
             property float y\nproperty float z\nelement face 1\n\
             property list char int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n{face}\n"
        )
    };
    let cases: Vec<(String, &[&str])> = vec![
        ("".into(), &["not a PLY file"]),
        (
            "PLY\nformat ascii 1.0\n".into(),
            &["line 1", "not a PLY file"],
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex 1\n".into(),
            &["line 4", "no `end_header`"],
        ),
        (
            "ply\nformat xml 1.0\nend_header\n".into(),
            &["line 2", "unknown format `xml`"],
        ),
        (
            "ply\nformat ascii 2.0\nend_header\n".into(),
            &["line 2", "version `2.0`"],
        ),
        (
            "ply\nelement vertex 1\nend_header\n".into(),
            &["line 3", "no `format`"],
        ),
        (
            "ply\nformat ascii 1.0\nproperty float x\n".into(),
            &["line 3", "before any `element`"],
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex -1\n".into(),
            &["line 3", "not a whole number"],
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\n".into(),
            &["line 4", "`vertex`", "unknown property type `quad`"],
        ),
        (
            "ply\nformat ascii 1.0\nelement face 1\nproperty list float int vertex_indices\n"
                .into(),
            &["line 4", "count type must be an integer"],
        ),
        (
            "ply\nformat ascii 1.0\nbogus\n".into(),
            &["line 3", "`bogus`"],
        ),
        (
            tri("3", "3 0 1 3"),
            &[
                "line 13",
                "`face` row 0",
                "`vertex_indices`",
                "index 3 is out of range",
                "3 vertices",
            ],
        ),
        (
            tri("3", "3 0 1 -1"),
            &["line 13", "index -1 is out of range"],
        ),
        (tri("3", "-3 0 1 2"), &["line 13", "negative list count"]),
        (
            tri("3", "2 0 1"),
            &["line 13", "at least 3 vertices, this one has 2"],
        ),
        (tri("3", "3 0 1"), &["line 14", "the file ends early"]),
        (
            tri("3", "3 0 1 x"),
            &["line 13", "`x` is not a whole number"],
        ),
        (tri("3", "3 0 1 2.0"), &["not a whole number"]),
        (
            tri("3", "300 0 1 2"),
            &["`300` is not in the range of its type (-128..127)"],
        ),
        (
            tri("1000000000000", "3 0 1 2"),
            &["the file ends early", "`vertex` row 4"],
        ),
        (
            tri("3", "3 0 1 2").replace("0 1 0\n", "0 nan 0\n"),
            &[
                "line 12",
                "`vertex` row 2, property `y`",
                "not a finite number",
            ],
        ),
        (
            tri("3", "3 0 1 2").replace("0 1 0\n", "0 1e39 0\n"),
            &["line 12", "not a finite number (in 32 bits)"],
        ),
        (
            tri("3", "3 0 1 2").replace("0 1 0\n", "0 inf 0\n"),
            &["not a finite number"],
        ),
        (
            tri("3", "3 0 1 2").replace("element face 1", "element face 0"),
            &["no triangles"],
        ),
        (
            tri("3", "3 0 1 2").replace("property float z\n", ""),
            &["lacks one of the properties `x`, `y`, `z`"],
        ),
        (
            tri("3", "3 0 1 2").replace("property float y\n", "property list uchar float y\n"),
            &["property `y` is a list"],
        ),
        (
            tri("3", "3 0 1 2").replace("vertex_indices", "corners"),
            &["no `vertex_indices`"],
        ),
        (
            tri("3", "3 0 1 2").replace("char int vertex_indices", "char float vertex_indices"),
            &["must be a list of integers"],
        ),
        (
            "ply\nformat ascii 1.0\nelement face 1\nend_header\n".into(),
            &["no `vertex` element"],
        ),
        (
            tri("3", "3 0 1 2").replace("end_header", "element vertex 1\nend_header"),
            &["more than one `vertex`"],
        ),
        (
            tri("3", "3 0 1 2").replace("end_header", "element face 1\nend_header"),
            &["more than one `face`"],
        ),
        (
            tri("3", "3 0 1 2").replace("element face", "element \u{1b}[31m"),
            &["no triangles"],
        ),
    ];
    for (text, words) in &cases {
        let message = parse(text).unwrap_err().to_string();
        for word in *words {
            assert!(
                message.contains(word),
                "{text:?}: {message:?} lacks {word:?}"
            );
        }
        assert!(!message.chars().any(char::is_control), "{message:?}");
    }
}

#[test]
fn bad_binary_files_name_the_byte() {
    use Scalar::*;
    let head = "element vertex 2\nproperty float x\nproperty float y\nproperty float z\n\
                element face 1\nproperty list char ushort vertex_indices\n";
    let start = binary(false, head, &[]).len();
    let vertices = |body: &mut Vec<u8>| {
        put(body, false, &[(F32, 0.0); 5]);
        put(body, false, &[(F32, f64::INFINITY)]);
    };
    let mut infinite = Vec::new();
    vertices(&mut infinite);
    let e = parse_ply(&binary(false, head, &infinite)).unwrap_err();
    assert_eq!(e.at, At::Byte(start + 20), "{e}");
    assert!(e.message.contains("`vertex` row 1, property `z`"), "{e}");

    let mut negative = Vec::new();
    put(&mut negative, false, &[(F32, 0.0); 6]);
    put(&mut negative, false, &[(I8, -1.0)]);
    let e = parse_ply(&binary(false, head, &negative)).unwrap_err();
    assert_eq!(e.at, At::Byte(start + 24), "{e}");
    assert!(e.message.contains("negative list count"), "{e}");

    // A header that announces a billion vertices in 24 bytes: the body ends early, and
    // nothing the header announces is reserved.
    let lying = head.replace("vertex 2", "vertex 1000000000");
    let mut short = Vec::new();
    put(&mut short, false, &[(F32, 0.0); 6]);
    let e = parse_ply(&binary(false, &lying, &short)).unwrap_err();
    let start = binary(false, &lying, &[]).len();
    assert_eq!(e.at, At::Byte(start + 24), "{e}");
    assert!(
        e.message.contains("ends early") && e.message.contains("row 2"),
        "{e}"
    );

    // A skipped list longer than the file.
    let skipped = head.replace(
        "element face",
        "element junk 1\nproperty list uint double d\nelement face",
    );
    let mut body = Vec::new();
    put(&mut body, false, &[(F32, 0.0); 6]);
    put(&mut body, false, &[(U32, 4e9)]);
    let e = parse_ply(&binary(false, &skipped, &body)).unwrap_err();
    assert!(
        e.message.contains("`junk` row 0, property `d`") && e.message.contains("ends early"),
        "{e}"
    );
}

#[test]
fn reservations_follow_the_bytes_not_the_header() {
    let element = Element {
        name: "vertex".into(),
        count: u64::MAX,
        properties: vec![Property {
            name: "x".into(),
            kind: Kind::Scalar(Scalar::F64),
        }],
    };
    let bytes = [0u8; 100];
    assert_eq!(
        reservable(&element, &Body::new(&bytes, Format::BigEndian, 4, 1)),
        12
    );
    assert_eq!(
        reservable(&element, &Body::new(&bytes, Format::Ascii, 0, 1)),
        50
    );
}

#[test]
fn ascii_rows_are_lines_whose_extra_values_are_dropped_with_a_warning() {
    // VCGlib writes values after each face's list; a row may still run over several lines.
    let text = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
                property float z\nelement face 2\nproperty list uchar int vertex_indices\n\
                end_header\n0 0 0 9 9\n1 0\n0\n1 1 0\n0 1 0\n3 0 1 2 0 0 0\n3 0 2 3 7\n";
    let ply = read_ply(text.as_bytes()).unwrap();
    assert_eq!(ply.mesh.indices, [[0, 1, 2], [0, 2, 3]]);
    assert_eq!(ply.mesh.positions[1], glam::Vec3::X);
    assert_eq!(
        ply.warnings,
        [
            "2 value(s) at the ends of 1 `vertex` row(s), beyond the header's properties, are \
             ignored (the first on line 10)",
            "4 value(s) at the ends of 2 `face` row(s), beyond the header's properties, are \
             ignored (the first on line 15)"
        ]
    );
    // A row cut short is still an error.
    let short = text.replace("3 0 2 3 7\n", "3 0 2\n");
    let e = read_ply(short.as_bytes()).unwrap_err();
    assert!(e.message.contains("ends early"), "{e}");
}
