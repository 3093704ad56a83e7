//! The node hierarchy and the messages of JSON that does not deserialize: the same error
//! whether or not the file has scenes, at a JSON path rather than a line and column; and what
//! a node's transform does to an orthographic camera.

use glam::{Mat4, Vec3};
use serde_json::json;

use super::tests::{read, read_bytes, triangle};

#[test]
fn a_cycle_is_the_same_error_with_or_without_scenes() {
    let cycles = [
        json!([{"mesh": 0, "children": [1]}, {"children": [0]}]),
        json!([{"mesh": 0}, {"children": [2]}, {"children": [3]}, {"children": [1]}]),
        json!([{"mesh": 0, "children": [0]}]),
    ];
    for nodes in cycles {
        let mut with = triangle();
        with["nodes"] = nodes.clone();
        let mut without = with.clone();
        without.as_object_mut().unwrap().remove("scenes");
        without.as_object_mut().unwrap().remove("scene");
        let (a, b) = (read(&with).unwrap_err(), read(&without).unwrap_err());
        assert_eq!(a, b, "{nodes}");
        assert!(a.message.contains("cycle"), "{nodes}: {a}");
        assert!(!a.message.contains("no node uses a mesh"), "{a}");
    }
    // The cycle of nodes 1 → 2 → 3 → 1 is named from its lowest node.
    let mut v = triangle();
    v["nodes"] = json!([{"mesh": 0}, {"children": [2]}, {"children": [3]}, {"children": [1]}]);
    let e = read(&v).unwrap_err();
    assert_eq!(e.at, "nodes[1]");
    assert!(
        e.message
            .contains("nodes[1] → nodes[2] → nodes[3] → nodes[1]"),
        "{e}"
    );
}

#[test]
fn a_node_with_two_parents_is_refused_and_a_forest_without_scenes_loads() {
    let mut v = triangle();
    v["nodes"] = json!([{"mesh": 0}, {"children": [0]}, {"children": [0]}]);
    v.as_object_mut().unwrap().remove("scenes");
    v.as_object_mut().unwrap().remove("scene");
    let e = read(&v).unwrap_err();
    assert_eq!(e.at, "nodes[0]");
    assert!(e.message.contains("nodes[1] and nodes[2]"), "{e}");
    // Two trees, no scenes: every root is rendered.
    v["nodes"] = json!([{"mesh": 0}, {"children": [0]}, {"mesh": 0}]);
    let model = read(&v).unwrap();
    assert_eq!(model.uses.len(), 2);
}

#[test]
fn json_that_does_not_deserialize_names_its_json_path() {
    let mut v = triangle();
    v["accessors"][0].as_object_mut().unwrap().remove("type");
    let e = read(&v).unwrap_err();
    assert_eq!(e.at, "accessors[0].type", "{e}");
    assert!(!e.to_string().contains("column"), "{e}");
    // Pretty-printed, on many lines; and inside a GLB.
    let text = serde_json::to_string_pretty(&v).unwrap();
    let e = read_bytes(text.as_bytes()).unwrap_err();
    assert_eq!(e.at, "accessors[0].type", "{e}");
    let mut v = triangle();
    v["meshes"][0]["primitives"][0]["mode"] = json!("TRIANGLES");
    let e = read(&v).unwrap_err();
    assert_eq!(e.at, "meshes[0].primitives[0].mode", "{e}");
}

#[test]
fn a_uri_with_control_characters_is_named_on_one_line() {
    let mut v = triangle();
    v["buffers"][0]["uri"] = json!("no\tsuch\nfile\u{1b}[31m.bin");
    let e = read(&v).unwrap_err();
    let text = e.to_string();
    assert!(!text.chars().any(char::is_control), "{text:?}");
    assert!(text.contains(r"no\tsuch\nfile\u{1b}[31m.bin"), "{text}");
}

#[test]
fn an_orthographic_camera_sees_twice_its_ymag_scaled_with_its_node() {
    let mut v = triangle();
    v["cameras"] = json!([
        {"type": "orthographic", "name": "plan", "orthographic": {"xmag": 3, "ymag": 2, "znear": 0, "zfar": 9}},
        {"type": "orthographic", "name": "flat", "orthographic": {"xmag": 3, "ymag": 0, "znear": 0, "zfar": 9}},
        {"type": "perspective", "name": "cam", "perspective": {"yfov": 0.5, "znear": 0.1}},
    ]);
    v["nodes"] = json!([
        {"mesh": 0},
        {"translation": [0, 5, 0], "scale": [1, 1.5, 1], "camera": 0},
        {"camera": 1},
        {"camera": 2},
    ]);
    v["scenes"] = json!([{"nodes": [0, 1, 2, 3]}]);
    let model = read(&v).unwrap();
    // 2·ymag, scaled with the node's (and the placing object's) up axis; one with a ymag of 0
    // is left out, with a warning; a perspective camera has none.
    let names: Vec<&str> = model.cameras.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["plan", "cam"]);
    let plan = &model.cameras[0];
    assert_eq!(plan.orthographic_height(Mat4::IDENTITY), Some(6.0));
    let twice = Mat4::from_scale(Vec3::splat(2.0));
    assert_eq!(plan.orthographic_height(twice), Some(12.0));
    assert_eq!(model.cameras[1].orthographic_height(Mat4::IDENTITY), None);
    let warned = model.warnings.iter().any(|w| w.contains("ymag of 0"));
    assert!(warned, "{:?}", model.warnings);
}
