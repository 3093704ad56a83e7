//! glTF end to end: `penumbra check` and `render` on the shared assets (skipped where
//! `../shared/assets/gltf/` is absent; the expected counts and bounds are trimesh's reading,
//! `trimesh.load(path, force="scene", process=False)` with node transforms applied), a glTF
//! file placed by a scene file, and bad files: exit 2 and a line naming the file and the JSON
//! path.

mod harness;
#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use std::path::{Path, PathBuf};

use harness::{error_line, ok, run_in};
use serde_json::{json, Value};
use support::TempDir;

/// A file of the shared glTF assets, or `None` with a message when this machine lacks it.
fn shared(name: &str) -> Option<PathBuf> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/assets/gltf")
        .join(name);
    if !path.is_file() {
        eprintln!("skipped: {} is absent", path.display());
        return None;
    }
    Some(path)
}

fn check_json(path: &Path) -> Value {
    let dir = path.parent().unwrap();
    let name = path.file_name().unwrap().to_str().unwrap();
    let r = ok(run_in(dir, ["check", name, "--json"]));
    serde_json::from_slice(&r.stdout).unwrap()
}

/// The bounds of a check, as (min, max).
fn bounds(v: &Value) -> ([f64; 3], [f64; 3]) {
    let read = |k: &str| -> [f64; 3] {
        let a = v["bounds"][k].as_array().unwrap();
        [0, 1, 2].map(|i| a[i].as_f64().unwrap())
    };
    (read("min"), read("max"))
}

#[test]
fn the_shared_files_have_trimeshs_triangles_and_bounds() {
    // (file, triangles, min, max) as trimesh reads them.
    let expected: [(&str, u64, [f64; 3], [f64; 3]); 5] = [
        ("BoxTextured.glb", 12, [-0.5; 3], [0.5; 3]),
        (
            "Duck.glb",
            4212,
            [-0.692985, 0.0992937, -0.613282],
            [0.961799, 1.6397, 0.539252],
        ),
        (
            "CesiumMilkTruck.glb",
            3624,
            [-2.43091, 0.00145189, -1.396],
            [2.438, 2.58437, 1.396],
        ),
        (
            "balloon/scene.gltf",
            35698,
            [-0.141432, 0.213395, -0.285986],
            [0.438397, 0.908105, 0.291778],
        ),
        (
            "smallpine/scene.gltf",
            1650,
            [-29.2166, 0.0168803, -29.1038],
            [29.1307, 75.0142, 28.1634],
        ),
    ];
    for (name, triangles, min, max) in expected {
        let Some(path) = shared(name) else { continue };
        let v = check_json(&path);
        assert_eq!(v["triangles"], triangles, "{name}");
        let (lo, hi) = bounds(&v);
        let diagonal = (0..3)
            .map(|i| (max[i] - min[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        for i in 0..3 {
            assert!(
                (lo[i] - min[i]).abs() < 1e-4 * diagonal,
                "{name}: min {lo:?}"
            );
            assert!(
                (hi[i] - max[i]).abs() < 1e-4 * diagonal,
                "{name}: max {hi:?}"
            );
        }
    }
}

#[test]
fn the_milk_truck_stores_its_wheel_mesh_once() {
    let Some(path) = shared("CesiumMilkTruck.glb") else {
        return;
    };
    let v = check_json(&path);
    // Two meshes (truck, wheels); the wheels placed by two nodes: three uses.
    assert_eq!(
        (v["meshes"].as_u64(), v["instances"].as_u64()),
        (Some(2), Some(3))
    );
    assert!(v["unique_triangles"].as_u64() < v["triangles"].as_u64());
    assert!(v["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .any(|w| w.as_str().unwrap().contains("animation")));
}

#[test]
fn a_scene_placing_the_milk_truck_builds_its_wheel_mesh_once() {
    // The project's own copy, so this runs wherever the repository does.
    let truck = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/gltf/CesiumMilkTruck.glb");
    let dir = TempDir::new("gltf-truck");
    dir.write(
        "s.toml",
        format!(
            "[film]\nwidth = 8\nheight = 8\n\n[camera]\nposition = [0, 2, 8]\n\
             look_at = [0, 1, 0]\nfov = 40\n\n[[objects]]\ntype = \"mesh\"\nfile = {:?}\n",
            truck.to_str().unwrap()
        ),
    );
    // The truck is outside the scene's folder: allowed.
    let assets = truck.parent().unwrap().to_str().unwrap();
    let args = ["check", "s.toml", "--json", "--allow-path", assets];
    let r = ok(run_in(dir.path(), args));
    let s: Value = serde_json::from_slice(&r.stdout).unwrap();
    let file = check_json(&truck);
    // The world, not only the file: the wheel mesh is built once and placed by both wheel
    // nodes as instances; the body, used once, is copied in.
    assert_eq!(s["triangles"], file["triangles"]);
    assert_eq!(s["unique_triangles"], file["unique_triangles"]);
    assert_eq!(
        (s["meshes"].as_u64(), s["instances"].as_u64()),
        (Some(1), Some(2))
    );
}

#[test]
fn the_pine_loads_without_its_absent_normal_maps() {
    let Some(path) = shared("smallpine/scene.gltf") else {
        return;
    };
    let v = check_json(&path);
    assert_eq!(v["textures"], 2);
    let warnings = v["warnings"].to_string();
    assert!(warnings.contains("normal map"), "{warnings}");
}

#[test]
fn the_ducks_camera_is_the_view_of_the_bare_model() {
    let Some(path) = shared("Duck.glb") else {
        return;
    };
    let v = check_json(&path);
    assert_eq!(v["cameras"].as_array().map(Vec::len), Some(1));
    let dir = TempDir::new("gltf-duck");
    let out = dir.join("duck.png");
    let r = ok(run_in(
        path.parent().unwrap(),
        [
            "render".as_ref(),
            "Duck.glb".as_ref(),
            "--set".as_ref(),
            "film.width=40".as_ref(),
            "--set".as_ref(),
            "film.height=30".as_ref(),
            "-o".as_ref(),
            out.as_os_str(),
        ],
    ));
    assert!(out.is_file(), "{}", r.out());
    let image = harness::image(&out);
    // The duck is yellow somewhere in the frame seen through its camera.
    assert!(image.pixels().any(|p| p[0] > 100 && p[1] > 80 && p[2] < 60));
}

/// A glTF file of one triangle (0,0,0), (1,0,0), (0,1,0) in a data URI, u8 indices.
fn triangle() -> Value {
    let mut bin: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    bin.extend([0u8, 1, 2, 0]);
    json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": 40, "uri": format!("data:application/octet-stream;base64,{}", base64(&bin))}],
        "bufferViews": [
            {"buffer": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 3},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5121, "count": 3, "type": "SCALAR"},
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "nodes": [{"mesh": 0}, {"mesh": 0, "translation": [5, 0, 0]}],
        "scenes": [{"nodes": [0, 1]}],
    })
}

fn base64(bytes: &[u8]) -> String {
    const ABC: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in bytes.chunks(3) {
        let n = c
            .iter()
            .enumerate()
            .fold(0u32, |n, (i, &b)| n | ((b as u32) << (16 - 8 * i)));
        for k in 0..4 {
            match k <= c.len() {
                true => out.push(ABC[((n >> (18 - 6 * k)) & 63) as usize] as char),
                false => out.push('='),
            }
        }
    }
    out
}

#[test]
fn a_scene_places_a_gltf_file_with_its_point_light_and_camera() {
    let dir = TempDir::new("gltf-scene");
    let mut v = triangle();
    v["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    v["extensions"] =
        json!({"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 5}]}});
    v["cameras"] = json!([{"type": "perspective", "name": "front", "perspective": {"yfov": 0.7, "znear": 0.1}}]);
    v["nodes"] = json!([
        {"mesh": 0}, {"mesh": 0, "translation": [5, 0, 0]},
        {"translation": [0, 0, 4], "camera": 0},
        {"translation": [0, 2, 2], "extensions": {"KHR_lights_punctual": {"light": 0}}},
    ]);
    v["scenes"] = json!([{"nodes": [0, 1, 2, 3]}]);
    dir.write("t.gltf", v.to_string());
    dir.write(
        "s.toml",
        "[film]\nwidth = 8\nheight = 8\n\n[[objects]]\ntype = \"mesh\"\nfile = \"t.gltf\"\n\
         cameras = true\nlights = true\ntranslate = [0, 10, 0]\n",
    );
    let r = ok(run_in(dir.path(), ["check", "s.toml", "--json"]));
    let s: Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(s["triangles"], 2);
    assert_eq!(s["lights"], 1);
    assert_eq!(s["cameras"], json!(["front"]));
    assert_eq!(s["bounds"]["min"], json!([0.0, 10.0, 0.0]));
    assert_eq!(s["bounds"]["max"], json!([6.0, 11.0, 0.0]));
    // Without `cameras = true` a scene needs its own.
    dir.write(
        "no.toml",
        "[film]\nwidth = 8\nheight = 8\n\n[[objects]]\ntype = \"mesh\"\nfile = \"t.gltf\"\n",
    );
    let line = error_line(&run_in(dir.path(), ["check", "no.toml"]), 2);
    assert!(line.contains("missing key `camera`"), "{line}");
    // The bare model uses the file's camera and light.
    let r = ok(run_in(dir.path(), ["check", "t.gltf", "--json"]));
    let m: Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(
        (m["triangles"].as_u64(), m["instances"].as_u64()),
        (Some(2), Some(2))
    );
    assert_eq!(m["lights"], 1);
}

#[test]
fn bad_files_exit_2_naming_the_file_and_the_json_path() {
    let dir = TempDir::new("gltf-bad");
    type Edit = fn(&mut Value);
    let cases: [(Edit, &str); 4] = [
        (
            |v| v["accessors"][1]["count"] = json!(9),
            "meshes[0].primitives[0].indices",
        ),
        (
            |v| v["buffers"][0]["uri"] = json!("gone.bin"),
            "buffers[0].uri",
        ),
        (
            |v| v["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]),
            "KHR_draco_mesh_compression",
        ),
        (
            |v| v["meshes"][0]["primitives"][0]["indices"] = json!(5),
            "meshes[0].primitives[0].indices",
        ),
    ];
    for (edit, expected) in cases {
        let mut v = triangle();
        edit(&mut v);
        dir.write("bad.gltf", v.to_string());
        for command in ["check", "render"] {
            let line = error_line(&run_in(dir.path(), [command, "bad.gltf"]), 2);
            assert!(
                line.contains("bad.gltf") && line.contains(expected),
                "{command}: {line}"
            );
        }
    }
    dir.write("short.glb", b"glTF\x02\x00\x00\x00\xff\x00\x00\x00");
    let line = error_line(&run_in(dir.path(), ["check", "short.glb"]), 2);
    assert!(
        line.contains("short.glb") && line.contains("truncated GLB"),
        "{line}"
    );
}

#[test]
fn instances_of_a_gltf_file_place_its_node_graph_under_each_transform() {
    let dir = TempDir::new("gltf-instances");
    dir.write("t.gltf", triangle().to_string());
    dir.write(
        "s.toml",
        "[film]\nwidth = 8\nheight = 8\n[camera]\nposition = [0, 0, 30]\nlook_at = [0, 0, 0]\n\
         fov = 40\n\n[materials.red]\ndiffuse = [0.9, 0.1, 0.1]\n\n[[objects]]\n\
         type = \"instances\"\nfile = \"t.gltf\"\nmaterial = \"red\"\ntransforms = [\n\
         { translate = [0, 0, 0] },\n{ translate = [0, 5, 0] },\n{ translate = [0, 10, 0] },\n]\n",
    );
    let r = ok(run_in(dir.path(), ["check", "s.toml", "--json"]));
    let s: Value = serde_json::from_slice(&r.stdout).unwrap();
    // Two nodes place the triangle, under each of three transforms.
    assert_eq!(s["triangles"], 6);
    assert_eq!(s["bounds"]["min"], json!([0.0, 0.0, 0.0]));
    assert_eq!(s["bounds"]["max"], json!([6.0, 11.0, 0.0]));
    assert_eq!(s["objects"][0]["triangles"], 6);
    // `cameras` is a key of `type = "mesh"` only, and of glTF files only.
    dir.write(
        "obj.toml",
        "[film]\nwidth = 8\nheight = 8\n[camera]\nposition = [0, 0, 30]\nlook_at = [0, 0, 0]\n\
         fov = 40\n[[objects]]\ntype = \"mesh\"\nfile = \"t.obj\"\ncameras = true\n",
    );
    dir.write("t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let line = error_line(&run_in(dir.path(), ["check", "obj.toml"]), 2);
    assert!(
        line.contains("objects[0].cameras") && line.contains("glTF files"),
        "{line}"
    );
}

#[test]
fn a_masked_material_below_its_cutoff_is_cut_away() {
    let dir = TempDir::new("gltf-mask");
    let scene = "[film]\nwidth = 8\nheight = 8\n[camera]\nposition = [0.25, 0.25, 2]\n\
                 look_at = [0.25, 0.25, 0]\nfov = 10\n[[lights]]\ntype = \"point\"\n\
                 position = [0, 0, 3]\n[[objects]]\ntype = \"mesh\"\nfile = \"t.gltf\"\n";
    dir.write("s.toml", scene);
    let centre = |alpha: Value| {
        let mut v = triangle();
        v["materials"] = json!([{
            "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.2]},
            "alphaMode": alpha,
        }]);
        v["meshes"][0]["primitives"][0]["material"] = json!(0);
        dir.write("t.gltf", v.to_string());
        let out = dir.join("o.png");
        ok(run_in(
            dir.path(),
            [
                "render".as_ref(),
                "s.toml".as_ref(),
                "-o".as_ref(),
                out.as_os_str(),
            ],
        ));
        harness::image(&out).get_pixel(4, 4)[0]
    };
    // Opaque, the triangle is lit; masked at the default cutoff 0.5, alpha 0.2 is cut away
    // and the background shows.
    assert!(centre(json!("OPAQUE")) > 50);
    assert_eq!(centre(json!("MASK")), 0);
    assert_eq!(centre(json!("BLEND")), 0);
}
