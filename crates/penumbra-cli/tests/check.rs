//! `penumbra check`: per-object triangles and bounds, a bare OBJ summarized on its own, and
//! warnings (stderr, exit 0) for area lights that cannot light anything, materials and
//! textures never used and objects no camera sees.

mod harness;
#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use harness::{error_line, ok, run_in, run_with};
use serde_json::Value;
use support::{TempDir, BASE_TOML};

fn json(r: &harness::Run) -> Value {
    serde_json::from_slice(&r.stdout).unwrap_or_else(|e| panic!("{e}: {}", r.out()))
}

#[test]
fn check_lists_each_object_with_its_triangles_and_bounds() {
    let dir = TempDir::new("check-objects");
    dir.write("s.toml", BASE_TOML);
    let r = ok(run_in(dir.path(), ["check", "s.toml", "--json"]));
    let v = json(&r);
    let objects = v["objects"].as_array().unwrap();
    assert_eq!(objects.len(), 2);
    // The floor quad: corner [-3, -0.5, 3], u = [6, 0, 0], v = [0, 0, -6].
    assert_eq!(objects[0]["type"], "quad");
    assert_eq!(objects[0]["triangles"], 2);
    assert_eq!(
        objects[0]["bounds"]["min"],
        serde_json::json!([-3.0, -0.5, -3.0])
    );
    assert_eq!(
        objects[0]["bounds"]["max"],
        serde_json::json!([3.0, -0.5, 3.0])
    );
    // The unit cube at the origin.
    assert_eq!(objects[1]["key"], "objects[1]");
    assert_eq!(objects[1]["triangles"], 12);
    assert_eq!(
        objects[1]["bounds"]["min"],
        serde_json::json!([-0.5, -0.5, -0.5])
    );
    assert_eq!(v["warnings"], serde_json::json!([]));
    assert!(r.stderr.is_empty(), "{}", r.stderr);
    let r = ok(run_in(dir.path(), ["check", "s.toml"]));
    assert!(r.out().contains("objects    2"), "{}", r.out());
    assert!(
        r.out().lines().any(|l| l.contains("objects[1]")
            && l.contains("cube")
            && l.contains("12 triangles")
            && l.contains("[-0.5000, -0.5000, -0.5000] to [0.5000, 0.5000, 0.5000]")),
        "{}",
        r.out()
    );
    // A named object is listed with its name.
    let named = BASE_TOML.replacen("type = \"cube\"", "name = \"box\"\ntype = \"cube\"", 1);
    dir.write("named.toml", named);
    let v = json(&ok(run_in(dir.path(), ["check", "named.toml", "--json"])));
    assert_eq!(v["objects"][1]["name"], "box");
    assert_eq!(v["objects"][0].get("name"), None);
    let r = ok(run_in(dir.path(), ["check", "named.toml"]));
    assert!(r.out().contains("objects[1] \"box\"  cube"), "{}", r.out());
}

const TETRA: &str = "mtllib t.mtl\nv 0 0 0\nv 2 0 0\nv 0 3 0\nv 0 0 4\nusemtl shiny\n\
                     f 1 3 2\nf 1 2 4\nusemtl dull\nf 1 4 3\nf 2 3 4\n";
const MTL: &str = "newmtl shiny\nKd 1 0 0\nmap_Kd wood.png\nnewmtl dull\nKd 0 1 0\n";

#[test]
fn check_summarizes_a_bare_obj() {
    let dir = TempDir::new("check-obj");
    dir.write("t.obj", TETRA);
    dir.write("t.mtl", MTL);
    let r = ok(run_in(dir.path(), ["check", "t.obj", "--json"]));
    let v = json(&r);
    assert_eq!(v["triangles"], 4);
    assert_eq!(v["bounds"]["max"], serde_json::json!([2.0, 3.0, 4.0]));
    assert_eq!(v["materials"], serde_json::json!(["shiny", "dull"]));
    assert!(v["textures"][0].as_str().unwrap().ends_with("wood.png"));
    assert_eq!(v["closed"], true);
    // An open mesh: one face fewer.
    dir.write("open.obj", "v 0 0 0\nv 2 0 0\nv 0 3 0\nf 1 2 3\n");
    let r = ok(run_in(dir.path(), ["check", "open.obj"]));
    assert!(r.out().contains("closed     no"), "{}", r.out());
    assert!(r.out().contains("triangles  1"), "{}", r.out());
    // A broken one is an input error naming the file.
    dir.write("bad.obj", "v 0 0 0\nf 1 2 3\n");
    let line = error_line(&run_in(dir.path(), ["check", "bad.obj"]), 2);
    assert!(
        line.contains("bad.obj") && line.contains("cannot load mesh"),
        "{line}"
    );
}

/// The base scene lit by one area light above the floor, under the physical model.
fn with_area_light(u: &str, v: &str) -> String {
    BASE_TOML.replace(
        "[[lights]]\ntype = \"point\"\nposition = [0, 5, 5]\n",
        &format!(
            "[render]\nlight_model = \"physical\"\n\n[[lights]]\ntype = \"area\"\n\
             center = [0, 3, 0]\nu = {u}\nv = {v}\n"
        ),
    )
}

#[test]
fn check_warns_about_lights_that_light_nothing() {
    let dir = TempDir::new("check-warn");
    // u × v = [0, -1, 0]: facing down at the scene, no warning.
    dir.write("down.toml", with_area_light("[1, 0, 0]", "[0, 0, 1]"));
    let r = ok(run_in(dir.path(), ["check", "down.toml"]));
    assert!(!r.stderr.contains("warning"), "{}", r.stderr);
    // Swapped: facing up, away from everything.
    dir.write("up.toml", with_area_light("[0, 0, 1]", "[1, 0, 0]"));
    let r = ok(run_in(dir.path(), ["check", "up.toml", "--json"]));
    assert!(
        r.stderr
            .starts_with("warning: up.toml: lights[0]: the physical area light faces away"),
        "{}",
        r.stderr
    );
    assert_eq!(json(&r)["warnings"].as_array().unwrap().len(), 1);
    // Under the phong model an area light shines both ways: no warning.
    dir.write(
        "phong.toml",
        with_area_light("[0, 0, 1]", "[1, 0, 0]").replace("physical", "phong"),
    );
    let r = ok(run_in(dir.path(), ["check", "phong.toml"]));
    assert!(r.stderr.is_empty(), "{}", r.stderr);
    // Zero area: parallel edges.
    dir.write("flat.toml", with_area_light("[1, 0, 0]", "[2, 0, 0]"));
    let r = ok(run_in(dir.path(), ["check", "flat.toml"]));
    assert!(
        r.stderr.contains("lights[0]: the area light has zero area"),
        "{}",
        r.stderr
    );
    assert!(r.out().contains("flat.toml: ok"));
}

#[test]
fn check_reads_a_scene_from_stdin() {
    let dir = TempDir::new("check-stdin");
    let r = ok(run_with(
        dir.path(),
        ["check", "-"],
        Some(BASE_TOML.as_bytes()),
    ));
    assert!(r.out().starts_with("<stdin>: ok"), "{}", r.out());
    assert!(r.out().contains("triangles  14"), "{}", r.out());
}

/// The `warning:` lines of a run, without the `warning: FILE: ` prefix.
fn warnings(r: &harness::Run, file: &str) -> Vec<String> {
    let prefix = format!("warning: {file}: ");
    r.stderr
        .lines()
        .filter_map(|l| l.strip_prefix(&prefix).map(str::to_owned))
        .collect()
}

#[test]
fn check_warns_about_materials_and_textures_never_used() {
    let dir = TempDir::new("check-unused");
    let scene = format!(
        "{BASE_TOML}\n[materials.blue]\ndiffuse = [0.1, 0.1, 0.8]\n\
         [materials.boarded]\ntexture = \"board\"\n\
         [textures.board]\ntype = \"checker\"\n\
         [textures.spare]\ntype = \"checker\"\n"
    );
    dir.write("s.toml", &scene);
    let r = ok(run_in(dir.path(), ["check", "s.toml", "--json"]));
    let w = warnings(&r, "s.toml");
    // `red` is the cube's; `board` is named by `boarded`, itself unused.
    assert_eq!(
        w,
        [
            "materials.blue: the material is never used (no object's `material` names it)",
            "materials.boarded: the material is never used (no object's `material` names it)",
            "textures.spare: the texture is never used (no material's `texture` names it)",
        ],
        "{}",
        r.stderr
    );
    assert_eq!(json(&r)["warnings"], serde_json::json!(w));

    // Once an object uses `boarded`, it and its texture are used.
    dir.write(
        "used.toml",
        scene.replace("material = \"red\"", "material = \"boarded\""),
    );
    let r = ok(run_in(dir.path(), ["check", "used.toml"]));
    let w = warnings(&r, "used.toml");
    assert!(w.iter().any(|l| l.starts_with("materials.red:")), "{w:?}");
    assert!(
        w.iter()
            .all(|l| !l.contains("boarded") && !l.contains("board:")),
        "{w:?}"
    );
    assert!(r.out().contains("used.toml: ok"));
}

/// The base scene (camera at (0, 1, 5) looking at the origin, fov 45, 16×12) with a red cube
/// of side 1 at `center`, as objects[2].
fn with_cube_at(center: &str) -> String {
    format!(
        "{BASE_TOML}\n[[objects]]\ntype = \"cube\"\nmaterial = \"red\"\ncenter = {center}\nsize = 1\n"
    )
}

#[test]
fn check_warns_about_objects_no_camera_sees() {
    let dir = TempDir::new("check-view");
    let cases = [
        // Behind the camera.
        ("[0, 1, 9]", true),
        // Far to the right, left, above and below the view.
        ("[40, 0, 0]", true),
        ("[-40, 0, 0]", true),
        ("[0, 40, 0]", true),
        ("[0, -40, 0]", true),
        // In view, at the edge of the view (the right side at z = 0 is at x ≈ 2.75 for the
        // 16:12 film), and straddling the camera's plane.
        ("[1, 0, -2]", false),
        ("[3, 0, 0]", false),
        ("[0, 1, 5]", false),
    ];
    for (center, outside) in cases {
        dir.write("s.toml", with_cube_at(center));
        let r = ok(run_in(dir.path(), ["check", "s.toml", "--json"]));
        let w = warnings(&r, "s.toml");
        let want: Vec<String> = if outside {
            vec!["objects[2]: the object is outside the view of every camera (camera)".into()]
        } else {
            vec![]
        };
        assert_eq!(w, want, "cube at {center}");
        assert_eq!(
            json(&r)["warnings"],
            serde_json::json!(want),
            "cube at {center}"
        );
    }
}

#[test]
fn an_object_one_camera_sees_is_not_outside() {
    let dir = TempDir::new("check-view-cams");
    // Two cameras: the first looks at the origin, the second behind itself at z = 9.
    let scene = with_cube_at("[0, 1, 9]").replace(
        "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\nup = [0, 1, 0]\nfov = 45\n",
        "[cameras.front]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\nfov = 45\n\
         [cameras.back]\nposition = [0, 1, 5]\nlook_at = [0, 1, 10]\nfov = 45\n",
    );
    dir.write("two.toml", &scene);
    let r = ok(run_in(dir.path(), ["check", "two.toml"]));
    assert!(r.stderr.is_empty(), "{}", r.stderr);
    // Without the second camera the cube is out of view.
    let one = scene.replace("look_at = [0, 1, 10]", "look_at = [0, 0, 0]");
    dir.write("one.toml", one);
    let r = ok(run_in(dir.path(), ["check", "one.toml"]));
    assert_eq!(
        warnings(&r, "one.toml"),
        ["objects[2]: the object is outside the view of every camera (front, back)"]
    );
}

#[test]
fn check_counts_instances_and_a_placement_material_is_used() {
    let dir = TempDir::new("check-instances");
    // A strip of 1,025 triangles placed 1,025 times (more than 2^20 triangles in all):
    // instanced, not copied.
    let k = 1025;
    let mut obj = String::new();
    for i in 0..k + 2 {
        obj += &format!("v {} {} 0\n", i / 2, i % 2);
    }
    for i in 1..=k {
        obj += &format!("f {} {} {}\n", i, i + 1, i + 2);
    }
    dir.write("tri.obj", obj);
    let n = 1025;
    let mut list = vec!["{ translate = [0, 0, 0], material = \"blue\" }".to_owned()];
    list.extend((1..n).map(|i| format!("{{ translate = [{}, 0, -20] }}", i as f32 * 0.001)));
    let scene = format!(
        "{BASE_TOML}\n[materials.blue]\ndiffuse = [0.1, 0.1, 0.8]\n\n[[objects]]\n\
         type = \"instances\"\nfile = \"tri.obj\"\ntransforms = [{}]\n",
        list.join(", ")
    );
    dir.write("s.toml", &scene);
    let r = ok(run_in(dir.path(), ["check", "s.toml", "--json"]));
    let v = json(&r);
    assert_eq!(v["triangles"], 14 + k * n);
    assert_eq!(v["unique_triangles"], 14 + k);
    assert_eq!(
        (v["meshes"].clone(), v["instances"].clone()),
        (1.into(), n.into())
    );
    let objects = v["objects"].as_array().unwrap();
    assert_eq!(objects[2]["type"], "instances tri.obj");
    assert_eq!(objects[2]["triangles"], k * n);
    // "blue" is named by a placement only: not reported unused.
    assert_eq!(v["warnings"], serde_json::json!([]));
    let r = ok(run_in(dir.path(), ["check", "s.toml"]));
    let line = format!("({} in memory: {n} instances of 1 mesh)", 14 + k);
    assert!(r.out().contains(&line), "{}", r.out());
}

#[test]
fn check_reports_an_environment_map_and_warns_when_it_is_black() {
    let dir = TempDir::new("check-environment");
    // A 4×2 map: radiance 2 on the top row, 0 on the bottom. Bilinear between them, the mean
    // over the sphere is 1.
    let img = image::Rgb32FImage::from_fn(4, 2, |_, y| image::Rgb([2.0 - 2.0 * y as f32; 3]));
    img.save(dir.join("sky.exr")).unwrap();
    let sky = "[[lights]]\ntype = \"environment\"\nfile = \"sky.exr\"\nintensity = 0.5\n";
    dir.write("s.toml", format!("{BASE_TOML}\n{sky}"));
    let v = json(&ok(run_in(dir.path(), ["check", "s.toml", "--json"])));
    let env = &v["environments"][0];
    assert_eq!(
        (env["width"].as_u64(), env["height"].as_u64()),
        (Some(4), Some(2))
    );
    let mean = env["mean_radiance"][0].as_f64().unwrap();
    assert!((mean - 0.5).abs() < 1e-6, "{mean}");
    assert_eq!(env["peak_radiance"][0].as_f64(), Some(1.0));
    let black = "[[lights]]\ntype = \"environment\"\ncolor = [0, 0, 0]\n";
    dir.write("b.toml", format!("{BASE_TOML}\n{black}"));
    let r = ok(run_in(dir.path(), ["check", "b.toml"]));
    assert!(r.stderr.contains("black everywhere"), "{}", r.stderr);
    assert!(r.out().contains("environment 2x2"), "{}", r.out());
}
