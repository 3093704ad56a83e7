//! `penumbra check model.ply`: a bare PLY file summarized as a bare OBJ is, and its errors.

mod harness;
#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use harness::{error_line, ok, run_in};
use serde_json::Value;
use support::TempDir;

/// A tetrahedron, two faces as one quad: closed, 4 triangles, ASCII with a skipped property.
const TETRA: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n\
property float y\nproperty float z\nproperty uchar red\nelement face 3\n\
property list uchar int vertex_indices\nend_header\n\
0 0 0 1\n2 0 0 1\n0 3 0 1\n0 0 4 1\n3 0 2 1\n3 0 1 3\n4 2 0 3 1\n";

#[test]
fn check_summarizes_a_bare_ply() {
    let dir = TempDir::new("check-ply");
    dir.write("t.Ply", TETRA);
    let r = ok(run_in(dir.path(), ["check", "t.Ply", "--json"]));
    let v: Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(v["triangles"], 4);
    assert_eq!(v["vertices"], 4);
    assert_eq!(v["bounds"]["max"], serde_json::json!([2.0, 3.0, 4.0]));
    assert_eq!(
        (v["normals"].clone(), v["uvs"].clone()),
        (false.into(), false.into())
    );
    assert_eq!(v["materials"], serde_json::json!([]));
    assert_eq!(v["closed"], true);
    let r = ok(run_in(dir.path(), ["check", "t.Ply"]));
    assert!(r.out().contains("triangles  4"), "{}", r.out());
    // A broken one is an input error naming the file, the line and the property.
    dir.write("bad.ply", TETRA.replace("3 0 1 3\n", "3 0 1 9\n"));
    let line = error_line(&run_in(dir.path(), ["check", "bad.ply"]), 2);
    assert!(
        line.contains("bad.ply: cannot load mesh: line 16")
            && line.contains("`vertex_indices`")
            && line.contains("index 9 is out of range"),
        "{line}"
    );
    let line = error_line(
        &run_in(dir.path(), ["check", "t.ply", "--set", "film.width=2"]),
        2,
    );
    assert!(line.contains("a mesh file has none"), "{line}");
}
