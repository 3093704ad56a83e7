//! Finite inputs whose products overflow f32 (issue 10, class 2) that are not errors: they
//! render, and every pixel of the image is finite. (Those refused at their key are rows of
//! `errors.rs`.)

mod support;

use std::path::Path;

use penumbra::{render, write_image, Film, RenderOptions, SceneFile, SceneFormat};
use support::{edit, TempDir, BASE_TOML as BASE};

fn render_in(text: &str, dir: &Path) -> Film {
    let scene = SceneFile::from_str(text, SceneFormat::Toml, "test.toml", dir)
        .and_then(|f| f.build(0))
        .unwrap_or_else(|e| panic!("{e}\n--- scene ---\n{text}"));
    render(&scene.world, &scene.settings, &RenderOptions::default())
        .expect("render")
        .0
}

/// Asserts that every channel of every pixel is finite, and that the film can be written as
/// EXR and PFM.
fn assert_finite(film: &Film, what: &str) {
    for (i, p) in film.pixels.iter().enumerate() {
        assert!(
            p.is_finite(),
            "{what}: pixel ({}, {}) is {p}",
            i as u32 % film.width,
            i as u32 / film.width
        );
    }
    let dir = TempDir::new("overflow-write");
    for ext in ["exr", "pfm"] {
        write_image(film, &dir.join(format!("out.{ext}")), None)
            .unwrap_or_else(|e| panic!("{what}: {e}"));
    }
}

#[test]
fn a_camera_far_from_its_target_is_not_degenerate() {
    let dir = TempDir::new("overflow-camera");
    // |look_at − position|² overflows f32 at 1e20 and underflows to zero at 1e-25.
    for position in [
        "[1e20, 1, 5]",
        "[1e20, 1e20, 1e20]",
        "[2e-25, 1e-25, 3e-25]",
    ] {
        let text = edit(
            BASE,
            "position = [0, 1, 5]",
            &format!("position = {position}"),
        );
        let film = render_in(&text, dir.path());
        assert_finite(&film, position);
    }
    // That the view is the right one is tested on the camera itself (camera.rs).
}

#[test]
fn a_huge_uv_scale_gives_finite_texels() {
    let dir = TempDir::new("overflow-uv");
    dir.png("t.png", 4, 4, |x, y| [(x * 60) as u8, (y * 60) as u8, 200]);
    let textured = edit(
        BASE,
        "specular = 0.3\n",
        "specular = 0.3\ntexture = \"t\"\n",
    );
    for (filter, wrap) in [
        ("bilinear", "repeat"),
        ("bilinear", "clamp"),
        ("nearest", "repeat"),
    ] {
        for scale in ["[3e38, 3e38]", "[-3e38, 3e38]"] {
            let text = format!(
                "{textured}\n[textures.t]\ntype = \"image\"\nfile = \"t.png\"\n\
                 filter = \"{filter}\"\nwrap = \"{wrap}\"\nuv_scale = {scale}\n\
                 uv_offset = [3e38, -3e38]\n"
            );
            let film = render_in(&text, dir.path());
            assert_finite(&film, &format!("{filter} {wrap} uv_scale {scale}"));
        }
    }
    let text = format!(
        "{textured}\n[textures.t]\ntype = \"checker\"\nuv_scale = [3e38, 3e38]\nchecks = 3e38\n"
    );
    assert_finite(&render_in(&text, dir.path()), "checker");
}
