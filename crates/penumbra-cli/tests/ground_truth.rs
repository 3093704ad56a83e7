//! Ground truth that decodes (issue 28, part 4): an EXR with every pass and its
//! `OUT.meta.json` (`--meta`) read back: ids name `[[objects]]` entries, `z` is the forward
//! coordinate of `position` under `world_to_camera`, and K puts each position on its pixel.

mod harness;
#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use std::collections::HashMap;

use exr::prelude::{read_first_flat_layer_from_file, FlatSamples};
use harness::{ok, run_in};
use serde_json::Value;
use support::{TempDir, BASE_TOML};

#[test]
fn an_exr_and_its_meta_record_decode_back_to_the_scene() {
    let dir = TempDir::new("ground-truth");
    // The base scene (objects[0] a floor quad, objects[1] a cube) from an off-axis camera.
    dir.write(
        "s.toml",
        BASE_TOML.replace("position = [0, 1, 5]", "position = [1.5, 2.5, 4]"),
    );
    ok(run_in(
        dir.path(),
        [
            "render", "s.toml", "--width", "32", "--height", "24", "--aov", "all", "--meta", "-o",
            "gt.exr",
        ],
    ));
    let meta: Value =
        serde_json::from_slice(&std::fs::read(dir.join("gt.meta.json")).unwrap()).unwrap();
    assert_eq!(meta["image"], "gt.exr");
    assert_eq!(meta["files"], serde_json::json!(["gt.exr"]));
    assert_eq!(meta["settings"]["penumbra"], env!("CARGO_PKG_VERSION"));
    assert_eq!(
        meta["settings"]["scene_digest"].as_str().map(str::len),
        Some(16)
    );
    let names: Vec<(String, String, u64, u64)> = meta["objects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| {
            let ids = o["ids"].as_array().unwrap();
            let id = |i: usize| ids[i].as_u64().unwrap();
            (
                o["key"].as_str().unwrap().into(),
                o["type"].as_str().unwrap().into(),
                id(0),
                id(1),
            )
        })
        .collect();
    assert_eq!(
        names,
        [
            ("objects[0]".into(), "quad".into(), 0, 1),
            ("objects[1]".into(), "cube".into(), 1, 2)
        ]
    );

    let layer = read_first_flat_layer_from_file(dir.join("gt.exr")).unwrap();
    let channels: HashMap<String, FlatSamples> = layer
        .layer_data
        .channel_data
        .list
        .into_iter()
        .map(|c| (c.name.to_string(), c.sample_data))
        .collect();
    let floats = |name: &str| match &channels[name] {
        FlatSamples::F32(v) => v.clone(),
        other => panic!("{name}: {other:?}"),
    };
    let FlatSamples::U32(ids) = &channels["object_id"] else {
        panic!("object ids are u32")
    };
    let (z, depth) = (floats("z.Z"), floats("depth.Z"));
    let p = [
        floats("position.X"),
        floats("position.Y"),
        floats("position.Z"),
    ];
    let m: Vec<Vec<f64>> = serde_json::from_value(meta["world_to_camera"].clone()).unwrap();
    let k: Vec<Vec<f64>> = serde_json::from_value(meta["K"].clone()).unwrap();
    let (w, h) = (32, 24);
    let mut seen = [0; 2];
    for j in 0..h {
        for i in 0..w {
            let n = j * w + i;
            if ids[n] == u32::MAX {
                assert_eq!((z[n], depth[n]), (f32::INFINITY, f32::INFINITY));
                continue;
            }
            seen[ids[n] as usize] += 1;
            let world = [p[0][n] as f64, p[1][n] as f64, p[2][n] as f64];
            let cam: Vec<f64> = (0..3)
                .map(|r| (0..3).map(|c| m[r][c] * world[c]).sum::<f64>() + m[r][3])
                .collect();
            assert!(
                (cam[2] - z[n] as f64).abs() < 1e-4,
                "pixel {i},{j}: {} vs {}",
                cam[2],
                z[n]
            );
            assert!(depth[n] >= z[n] * 0.999_99);
            let (u, v) = (
                k[0][0] * cam[0] / cam[2] + k[0][2],
                k[1][1] * cam[1] / cam[2] + k[1][2],
            );
            assert!(
                (u - i as f64).abs() < 0.01 && (v - j as f64).abs() < 0.01,
                "{i},{j}: {u},{v}"
            );
        }
    }
    assert!(seen[0] > 0 && seen[1] > 0, "both objects in view: {seen:?}");
}
