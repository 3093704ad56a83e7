//! `--aov`: passes beside the image on a closed-form scene (a quad facing the camera at a known
//! distance), as separate files (PNG output) or channels of one multi-layer EXR.

mod harness;
#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use std::path::Path;

use exr::prelude::{read_first_flat_layer_from_file, FlatSamples};
use harness::{error_line, ok, read_pfm, run_in};
use support::TempDir;

/// A 5×5 film looking down -z from (0, 0, 5) at a 2×2 quad in the plane z = 0 (object 1,
/// diffuse [0.5, 0.25, 1]); object 0 is a cube out of view. The 3×3 central pixels see the
/// quad, the border sees nothing; the center pixel's ray is the optical axis.
const SCENE: &str = r#"[film]
width = 5
height = 5

[camera]
position = [0, 0, 5]
look_at = [0, 0, 0]
fov = 45

[materials.paint]
diffuse = [0.5, 0.25, 1.0]

[[lights]]
type = "point"
position = [0, 0, 5]

[[objects]]
type = "cube"
material = "paint"
center = [100, 0, 0]
size = 1

[[objects]]
type = "quad"
material = "paint"
corner = [-1, -1, 0]
u = [2, 0, 0]
v = [0, 2, 0]
"#;

const MISS_ID: u32 = u32::MAX;

/// Whether pixel (x, y) of the 5×5 film sees the quad.
fn on_quad(x: usize, y: usize) -> bool {
    (1..4).contains(&x) && (1..4).contains(&y)
}

/// The channels of an EXR, by name.
fn read_exr(path: &Path) -> Vec<(String, FlatSamples)> {
    let image = read_first_flat_layer_from_file(path).unwrap();
    image
        .layer_data
        .channel_data
        .list
        .into_iter()
        .map(|c| (c.name.to_string(), c.sample_data))
        .collect()
}

fn check_depth(depth: &[f32]) {
    for y in 0..5 {
        for x in 0..5 {
            let d = depth[y * 5 + x];
            if on_quad(x, y) {
                // The distance along the ray: 5 / cos of the ray's angle to the axis.
                assert!((5.0..5.6).contains(&d), "({x}, {y}): {d}");
            } else {
                assert_eq!(d, f32::INFINITY, "({x}, {y})");
            }
        }
    }
    assert_eq!(
        depth[2 * 5 + 2],
        5.0,
        "the optical axis meets the quad at 5"
    );
    // Symmetric about the center.
    assert_eq!(depth[5 + 1], depth[3 * 5 + 3]);
}

fn check_object_ids(ids: &[u32]) {
    for (i, &id) in ids.iter().enumerate() {
        let want = if on_quad(i % 5, i / 5) { 1 } else { MISS_ID };
        assert_eq!(id, want, "pixel {i}");
    }
}

#[test]
fn png_output_gets_one_file_per_pass_with_exact_values() {
    let dir = TempDir::new("aov-png");
    dir.write("quad.toml", SCENE);
    ok(run_in(
        dir.path(),
        [
            "render",
            "quad.toml",
            "-o",
            "out/shot.png",
            "--aov",
            "all",
            "-q",
        ],
    ));
    let mut names: Vec<String> = std::fs::read_dir(dir.join("out"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "shot.albedo.pfm",
            "shot.depth.pfm",
            "shot.normal.pfm",
            "shot.object_id.exr",
            "shot.png",
            "shot.position.pfm",
            "shot.primitive_id.exr",
            "shot.z.pfm",
        ],
        "no temporary file is left"
    );

    let (w, h, c, depth) = read_pfm(&dir.join("out/shot.depth.pfm"));
    assert_eq!((w, h, c), (5, 5, 1));
    check_depth(&depth);
    // z is planar: 5 across the whole quad facing the camera, where depth grows to its edges.
    let (_, _, c, z) = read_pfm(&dir.join("out/shot.z.pfm"));
    assert_eq!(c, 1);
    for i in 0..25 {
        if on_quad(i % 5, i / 5) {
            assert!(
                (z[i] - 5.0).abs() < 1e-5 && z[i] <= depth[i],
                "pixel {i}: {}",
                z[i]
            );
        } else {
            assert_eq!(z[i], f32::INFINITY, "pixel {i}");
        }
    }
    assert!(depth[6] > 5.1, "a corner pixel's depth is not its z");

    let (_, _, c, normal) = read_pfm(&dir.join("out/shot.normal.pfm"));
    assert_eq!(c, 3);
    let (_, _, _, albedo) = read_pfm(&dir.join("out/shot.albedo.pfm"));
    let (_, _, _, position) = read_pfm(&dir.join("out/shot.position.pfm"));
    for i in 0..25 {
        let px = |v: &[f32]| [v[3 * i], v[3 * i + 1], v[3 * i + 2]];
        if on_quad(i % 5, i / 5) {
            assert_eq!(px(&normal), [0.0, 0.0, 1.0], "pixel {i}");
            // Filtered like the colour: the quad covers part of the outer pixels.
            let [r, g, b] = px(&albedo);
            assert!(
                b > 0.0 && b <= 1.0 && r == b / 2.0 && g == b / 4.0,
                "pixel {i}"
            );
            let p = px(&position);
            assert!(
                p[2].abs() < 1e-5 && p[0].abs() < 1.0 && p[1].abs() < 1.0,
                "{p:?}"
            );
        } else {
            for v in [&normal, &albedo, &position] {
                assert_eq!(px(v), [0.0; 3], "pixel {i}");
            }
        }
    }
    assert_eq!(
        albedo[36..39],
        [0.5, 0.25, 1.0],
        "the center pixel is covered"
    );
    let center = [position[36], position[37], position[38]];
    assert!(center.iter().all(|c| c.abs() < 1e-5), "{center:?}");

    let ids = read_exr(&dir.join("out/shot.object_id.exr"));
    assert_eq!(ids.len(), 1);
    let FlatSamples::U32(object) = &ids[0].1 else {
        panic!("ids are 32-bit unsigned integers: {:?}", ids[0].1)
    };
    check_object_ids(object);
    let prims = read_exr(&dir.join("out/shot.primitive_id.exr"));
    let FlatSamples::U32(prims) = &prims[0].1 else {
        panic!("ids are 32-bit unsigned integers")
    };
    for (i, &p) in prims.iter().enumerate() {
        if on_quad(i % 5, i / 5) {
            assert!(p < 2, "a quad has two triangles: {p}");
        } else {
            assert_eq!(p, MISS_ID);
        }
    }
}

#[test]
fn exr_output_holds_the_colour_and_the_passes_as_channels() {
    let dir = TempDir::new("aov-exr");
    dir.write("quad.toml", SCENE);
    ok(run_in(
        dir.path(),
        [
            "render",
            "quad.toml",
            "-o",
            "layers.exr",
            "--aov",
            "object_id,depth",
            "-q",
        ],
    ));
    ok(run_in(
        dir.path(),
        ["render", "quad.toml", "-o", "plain.exr", "-q"],
    ));
    let channels = read_exr(&dir.join("layers.exr"));
    let names: Vec<&str> = channels.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["B", "G", "R", "depth.Z", "object_id"]);
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        3,
        "one file per render beside the scene"
    );

    // The colour is the one a render without passes writes.
    let plain = image::open(dir.join("plain.exr")).unwrap().into_rgb32f();
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        let FlatSamples::F32(v) = &channels.iter().find(|(n, _)| n == name).unwrap().1 else {
            panic!("colour is float")
        };
        let want: Vec<f32> = plain.pixels().map(|p| p.0[c]).collect();
        assert_eq!(v, &want, "channel {name}");
    }
    let FlatSamples::F32(depth) = &channels[3].1 else {
        panic!("depth is float")
    };
    check_depth(depth);
    let FlatSamples::U32(ids) = &channels[4].1 else {
        panic!("ids are 32-bit unsigned integers")
    };
    check_object_ids(ids);
}

#[test]
fn passes_need_a_file_and_known_names() {
    let dir = TempDir::new("aov-bad");
    dir.write("quad.toml", SCENE);
    let r = run_in(
        dir.path(),
        [
            "render",
            "quad.toml",
            "-o",
            "-",
            "--format",
            "png",
            "--aov",
            "depth",
        ],
    );
    assert!(r.stdout.is_empty(), "nothing on stdout");
    let e = error_line(&r, 2);
    assert!(e.contains("--aov") && e.contains("standard output"), "{e}");

    let r = run_in(dir.path(), ["render", "quad.toml", "--aov", "depth,zdepth"]);
    assert_eq!(r.code, Some(2), "{r:#?}");
    assert!(r.stderr.contains("unknown pass `zdepth`"), "{}", r.stderr);
    assert!(!dir.join("quad.png").exists(), "nothing rendered");
}

#[test]
fn passes_of_a_region_match_the_full_film() {
    let dir = TempDir::new("aov-region");
    dir.write("quad.toml", SCENE);
    ok(run_in(
        dir.path(),
        [
            "render",
            "quad.toml",
            "-o",
            "full.pfm",
            "--aov",
            "depth",
            "-q",
        ],
    ));
    ok(run_in(
        dir.path(),
        [
            "render",
            "quad.toml",
            "-o",
            "part.pfm",
            "--aov",
            "depth,object_id",
            "--pixelbounds",
            "2,4,1,3",
            "-q",
        ],
    ));
    let (_, _, _, full) = read_pfm(&dir.join("full.depth.pfm"));
    let (w, h, _, part) = read_pfm(&dir.join("part.depth.pfm"));
    assert_eq!((w, h), (2, 2));
    assert_eq!(part, [full[7], full[8], full[12], full[13]]);
    let ids = read_exr(&dir.join("part.object_id.exr"));
    assert_eq!(ids[0].1, FlatSamples::U32(vec![1, 1, 1, 1]));
}

#[test]
fn the_summary_names_every_file_written() {
    let dir = TempDir::new("aov-summary");
    dir.write("quad.toml", SCENE);
    // Once for people (the line on stderr), once for programs (--json on stdout, and then
    // no line on stderr).
    let render = |out: &str, aov: &str, json: bool| {
        let mut args = vec!["render", "quad.toml", "-o", out, "--aov", aov];
        if json {
            args.push("--json");
        }
        ok(run_in(dir.path(), args))
    };
    let passes = [
        "depth.pfm",
        "normal.pfm",
        "albedo.pfm",
        "position.pfm",
        "object_id.exr",
        "primitive_id.exr",
        "z.pfm",
    ];
    let files: Vec<String> = passes.iter().map(|p| format!("out/shot.{p}")).collect();
    let line = format!("-> out/shot.png + 7 AOV files: {}\n", files.join(", "));
    let r = render("out/shot.png", "all", false);
    assert!(r.stderr.ends_with(&line), "{}", r.stderr);
    let r = render("out/shot.png", "all", true);
    assert!(!r.stderr.contains("AOV files"), "{}", r.stderr);
    let summary: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(summary["output"], "out/shot.png");
    assert_eq!(summary["aovs"], serde_json::json!(files));
    for f in &files {
        assert!(dir.join(f).is_file(), "{f} was named but not written");
    }
    // An EXR holds the passes itself: one file, and the summary names just it.
    let r = render("shot.exr", "depth", false);
    assert!(r.stderr.ends_with("-> shot.exr\n"), "{}", r.stderr);
    let r = render("shot.exr", "depth", true);
    let summary: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(summary["aovs"], serde_json::json!([]));
}

#[test]
fn the_image_and_its_passes_are_written_together_or_not_at_all() {
    let dir = TempDir::new("aov-together");
    dir.write("quad.toml", SCENE);
    dir.write("q.png", "old image");
    dir.write("q.depth.pfm", "old depth");
    // The normal pass cannot be written: a folder has its name.
    std::fs::create_dir(dir.join("q.normal.pfm")).unwrap();
    let args = [
        "render",
        "quad.toml",
        "-o",
        "q.png",
        "--aov",
        "depth,normal,albedo",
    ];
    let r = run_in(dir.path(), args);
    let e = error_line(&r, 1);
    assert!(e.contains("q.normal.pfm"), "{e}");
    let mut left: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(left, ["q.depth.pfm", "q.normal.pfm", "q.png", "quad.toml"]);
    assert_eq!(std::fs::read(dir.join("q.png")).unwrap(), b"old image");
    assert_eq!(
        std::fs::read(dir.join("q.depth.pfm")).unwrap(),
        b"old depth"
    );

    std::fs::remove_dir(dir.join("q.normal.pfm")).unwrap();
    ok(run_in(dir.path(), args));
    for f in ["q.png", "q.depth.pfm", "q.normal.pfm", "q.albedo.pfm"] {
        assert!(
            std::fs::read(dir.join(f)).unwrap().len() > 20,
            "{f} written"
        );
    }
}
