//! The benchmark suite's scenes (`scenes/bench/`, run by `tools/bench_vs_embree.sh suite`)
//! stay valid: each loads, builds and renders (here at 16×16), so the suite never rots between
//! benchmark runs.

use std::path::Path;

use penumbra::{render, RenderOptions, RenderSettings, SceneFile};

#[test]
fn every_suite_scene_loads_builds_and_renders() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/bench");
    let mut scenes: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 10, "{scenes:?}");
    // They read ../../assets: allowed, as `--allow-path assets` allows it.
    let assets = dir.join("../../assets");
    for path in &scenes {
        let scene = SceneFile::load_allowing(path, &[], vec![assets.clone()])
            .and_then(|f| f.build(2))
            .unwrap_or_else(|e| panic!("{e}"));
        let settings = RenderSettings {
            width: 16,
            height: 16,
            ..scene.settings.clone()
        };
        let (film, _) = render(&scene.world, &settings, &RenderOptions::default()).unwrap();
        let lit = film.pixels.iter().filter(|p| p.max_element() > 0.2).count();
        assert!(
            lit > 16,
            "{}: only {lit} of 256 pixels are lit",
            path.display()
        );
    }
}
