//! Golden images: the example scenes under `scenes/`, rendered small, compared with committed
//! references in `tests/golden/`.
//!
//! Tolerance: every 8-bit channel within 2 levels and the mean absolute difference under 0.05
//! levels. Rendering is deterministic, so on one machine the images match exactly; the slack
//! only absorbs floating-point differences between compilers and CPUs.
//!
//! On a mismatch the test writes `<name>.actual.png` and `<name>.diff.png` (differences
//! amplified ×16) under `target/golden/`. When a change is meant to alter an image, regenerate
//! the references with
//!
//! ```text
//! PENUMBRA_BLESS=1 cargo test -p penumbra --test golden
//! ```
//!
//! and look at every changed PNG (for example with `git diff --stat` and an image viewer)
//! before committing it: a reference is only as good as the human look it got.

use std::path::{Path, PathBuf};

use image::RgbImage;
use penumbra::encode_8bit;
use penumbra::{render, RenderOptions, Scene, SceneFile, View};

const SIZE: u32 = 96;

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn render_scene(name: &str, camera: Option<&str>) -> RgbImage {
    render_file(
        &repo_root().join("scenes").join(format!("{name}.toml")),
        camera,
    )
}

fn render_file(path: &Path, camera: Option<&str>) -> RgbImage {
    // The shipped scenes read ../assets: allowed, as `--allow-path assets` allows it.
    let assets = vec![repo_root().join("assets")];
    let file = SceneFile::load_allowing(path, &[], assets).unwrap_or_else(|e| panic!("{e}"));
    let scene = file.build(0).unwrap_or_else(|e| panic!("{e}"));
    render_view(&scene, camera)
}

/// One view of a built scene at SIZE², through `camera` (default: the first).
fn render_view(scene: &Scene, camera: Option<&str>) -> RgbImage {
    let mut settings = scene.settings.clone();
    (settings.width, settings.height) = (SIZE, SIZE);
    if let Some(c) = camera {
        settings.view = View::Named(c.to_owned());
    }
    let (film, _) = render(&scene.world, &settings, &RenderOptions::default()).unwrap();
    let bytes = film
        .pixels
        .iter()
        .flat_map(|p| p.to_array().map(|c| encode_8bit(c, scene.gamma)))
        .collect();
    RgbImage::from_raw(film.width, film.height, bytes).unwrap()
}

fn check(name: &str, camera: Option<&str>) {
    check_image(name, camera, render_scene(name, camera));
}

fn check_image(name: &str, camera: Option<&str>, actual: RgbImage) {
    let id = match camera {
        Some(c) => format!("{name}_{c}"),
        None => name.to_owned(),
    };
    let reference_path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/golden")
        .join(format!("{id}.png"));
    if std::env::var_os("PENUMBRA_BLESS").is_some() {
        actual.save(&reference_path).unwrap();
        return;
    }
    let reference = image::open(&reference_path)
        .unwrap_or_else(|e| {
            panic!(
                "{}: {e}; run with PENUMBRA_BLESS=1 to create it",
                reference_path.display()
            )
        })
        .into_rgb8();
    assert_eq!(reference.dimensions(), actual.dimensions(), "{id}: size");
    let diffs: Vec<u8> = actual
        .as_raw()
        .iter()
        .zip(reference.as_raw())
        .map(|(a, b)| a.abs_diff(*b))
        .collect();
    let max = diffs.iter().copied().max().unwrap_or(0);
    let mean = diffs.iter().map(|&d| d as f64).sum::<f64>() / diffs.len() as f64;
    if max > 2 || mean > 0.05 {
        let out = repo_root().join("target/golden");
        std::fs::create_dir_all(&out).unwrap();
        actual.save(out.join(format!("{id}.actual.png"))).unwrap();
        let amplified = diffs.iter().map(|&d| d.saturating_mul(16)).collect();
        RgbImage::from_raw(SIZE, SIZE, amplified)
            .unwrap()
            .save(out.join(format!("{id}.diff.png")))
            .unwrap();
        panic!(
            "{id}: differs from {} (max {max} levels, mean {mean:.3}); see {}",
            reference_path.display(),
            out.display()
        );
    }
}

#[test]
fn cornell_white_light_three_cameras_from_one_world() {
    // One load and one BVH build; each camera is a per-call setting of the same world.
    let path = repo_root().join("scenes/cornell.toml");
    let scene = SceneFile::load(&path).unwrap().build(0).unwrap();
    let names: Vec<&str> = scene
        .world
        .cameras()
        .iter()
        .map(|(n, _)| n.as_str())
        .collect();
    assert_eq!(names, ["front", "left", "high"]);
    let mut images = Vec::new();
    for camera in ["front", "left", "high"] {
        let image = render_view(&scene, Some(camera));
        check_image("cornell", Some(camera), image.clone());
        images.push(image);
    }
    assert!(images[0] != images[1] && images[1] != images[2]);
    // The default view is the first camera.
    assert!(render_view(&scene, None) == images[0]);
}

#[test]
fn cornell_warm_light() {
    check("cornell_warm", None);
}

#[test]
fn cornell_cyan_light() {
    check("cornell_cyan", None);
}

#[test]
fn lens_models() {
    // An OpenCV fisheye beyond 90° and an equirectangular panorama of the seed's room.
    check("cornell_lenses", Some("fisheye"));
    check("cornell_lenses", Some("panorama"));
}

#[test]
fn texture_scenes() {
    check("texture_map", None);
    check("textured_room", None);
}

#[test]
fn mesh_scenes() {
    check("showcase", None);
    check("cornell_obj", None);
}

#[test]
fn json_and_toml_scenes_render_the_same_bits() {
    // scenes/cornell.json is scenes/cornell.toml converted key for key (Python's tomllib and
    // json); one schema, so the images must be identical, cameras in file order included.
    for camera in [None, Some("high")] {
        let toml = render_scene("cornell", camera);
        let json = render_file(&repo_root().join("scenes/cornell.json"), camera);
        assert!(json == toml, "camera {camera:?}");
    }
}
