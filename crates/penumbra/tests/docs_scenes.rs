//! The complete scenes of docs/scene-format.md ("Two complete scenes") load, build and render:
//! the reference cannot show a scene that does not work.

use penumbra::{render, RenderOptions, RenderSettings, SceneFile, SceneFormat};

/// The TOML blocks of the section "Two complete scenes".
fn doc_scenes() -> Vec<String> {
    let doc = include_str!("../../../docs/scene-format.md");
    let start = doc.find("## Two complete scenes").expect("the section");
    let section = &doc[start..];
    let section = &section[..section[3..].find("\n## ").map_or(section.len(), |i| i + 3)];
    section
        .split("```toml\n")
        .skip(1)
        .map(|block| block[..block.find("```").expect("a closed block")].to_owned())
        .collect()
}

#[test]
fn the_complete_scenes_in_the_docs_render() {
    let scenes = doc_scenes();
    assert_eq!(scenes.len(), 2);
    for (i, text) in scenes.iter().enumerate() {
        let file = SceneFile::from_str(text, SceneFormat::Toml, format!("doc{i}.toml"), ".")
            .unwrap_or_else(|e| panic!("scene {i}: {e}"));
        let scene = file.build(1).unwrap_or_else(|e| panic!("scene {i}: {e}"));
        let settings = RenderSettings {
            width: 32,
            height: 24,
            spp: 1,
            ..scene.settings.clone()
        };
        let (film, _) = render(&scene.world, &settings, &RenderOptions::default()).unwrap();
        // Lit: the image on average is well above black.
        let mean = film.pixels.iter().map(|p| p.x + p.y + p.z).sum::<f32>() / (3.0 * 32.0 * 24.0);
        assert!(mean > 0.05, "scene {i}: mean {mean}");
    }
    // The first uses every kind of object and both light types.
    let first = SceneFile::from_str(&scenes[0], SceneFormat::Toml, "doc0.toml", ".").unwrap();
    assert_eq!(first.desc.objects.len(), 4);
    assert_eq!(first.desc.lights.len(), 2);
    assert_eq!(first.build(1).unwrap().world.cameras().len(), 2);
}

#[test]
fn the_physical_intensity_example_holds() {
    // "a 0.2 × 0.2 area light of intensity 25π, 1 unit above a white floor, lights the floor
    // under it to about 1".
    let text = "[film]\nwidth = 9\nheight = 9\n[camera]\nposition = [0, 0.5, 0.01]\n\
                look_at = [0, 0, 0]\nfov = 10\n[render]\nlight_model = \"physical\"\nambient = 0\n\
                light_samples = 32\n[materials.white]\ndiffuse = 1\n[[lights]]\ntype = \"area\"\n\
                center = [0, 1, 0]\nu = [0.2, 0, 0]\nv = [0, 0, 0.2]\nintensity = 78.5398163\n\
                [[objects]]\ntype = \"quad\"\ncorner = [-5, 0, 5]\nu = [10, 0, 0]\nv = [0, 0, -10]\n\
                material = \"white\"\n";
    let scene = SceneFile::from_str(text, SceneFormat::Toml, "units.toml", ".")
        .unwrap()
        .build(1)
        .unwrap();
    let (film, _) = render(&scene.world, &scene.settings, &RenderOptions::default()).unwrap();
    let c = film.get(4, 4).x;
    // L·A/d² = 25π·0.04 = π, times k_d/π: 1 for a point-small light; this one's finite size
    // takes off about 2 %.
    assert!((0.95..1.0).contains(&c), "{c}");
}
