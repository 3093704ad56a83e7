//! A scene with cut-outs (leaf cards whose RGBA atlas gives their shape, and an OBJ card cut
//! by its MTL's `map_d` mask) renders to the same bytes on every SIMD path and thread count,
//! and its cut-outs show.

#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use std::path::Path;
use std::process::{Command, Stdio};

use support::TempDir;

/// Leaf cards over a floor under an area light; `alpha` is the cut-out keys of the leaves.
fn scene(alpha: &str) -> String {
    let mut text = format!(
        "[film]\nwidth = 40\nheight = 30\n\n\
         [camera]\nposition = [0, 4, 6]\nlook_at = [0, 0.5, 0]\nup = [0, 1, 0]\nfov = 50\n\n\
         [render]\nsampler = \"rgss\"\nlight_samples = 3\n\n\
         [[lights]]\ntype = \"area\"\ncenter = [1, 5, 1]\nu = [1, 0, 0]\nv = [0, 0, 1]\n\n\
         [textures.atlas]\ntype = \"image\"\nfile = \"atlas.png\"\n\n\
         [materials.leaf]\ndiffuse = [0.2, 0.7, 0.2]\ntexture = \"atlas\"\n{alpha}\n\n\
         [[objects]]\ntype = \"quad\"\ncorner = [-5, 0, -5]\nu = [10, 0, 0]\nv = [0, 0, 10]\n\n\
         [[objects]]\ntype = \"mesh\"\nfile = \"card.obj\"\ntranslate = [1.5, 1, 0]\n\n"
    );
    for (i, (x, z, turn)) in [(-1.5, 0.0, 10), (-0.5, 0.5, 40), (0.5, -0.5, 70)]
        .iter()
        .enumerate()
    {
        let y = 1.0 + 0.4 * i as f32;
        text += &format!(
            "[[objects]]\ntype = \"quad\"\nmaterial = \"leaf\"\ncorner = [-0.6, 0, -0.6]\n\
             u = [1.2, 0, 0]\nv = [0, 0, 1.2]\nrotate = [0, {turn}, 20]\n\
             translate = [{x}, {y}, {z}]\n\n"
        );
    }
    text
}

/// Writes the atlas (an RGBA image of round leaves on transparent texels), and an OBJ card
/// whose MTL cuts it with a grey `map_d` mask (a ring).
fn write_assets(dir: &TempDir) {
    let atlas = image::RgbaImage::from_fn(32, 32, |x, y| {
        let (u, v) = ((x % 16) as f32 - 7.5, (y % 16) as f32 - 7.5);
        let alpha = if u * u + v * v < 36.0 { 255 } else { 0 };
        image::Rgba([60 + 6 * x as u8, 200, 40, alpha])
    });
    atlas.save(dir.join("atlas.png")).unwrap();
    let mask = image::GrayImage::from_fn(16, 16, |x, y| {
        let (u, v) = (x as f32 - 7.5, y as f32 - 7.5);
        let r = u * u + v * v;
        image::Luma([if (9.0..49.0).contains(&r) { 255 } else { 0 }])
    });
    mask.save(dir.join("mask.png")).unwrap();
    dir.write(
        "card.mtl",
        "newmtl ring\nKd 0.8 0.3 0.2\nmap_d -clamp on mask.png\n",
    );
    dir.write(
        "card.obj",
        "mtllib card.mtl\nv -1 0 0\nv 1 0 0\nv 1 2 0\nv -1 2 0\n\
         vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl ring\nf 1/1 2/2 3/3 4/4\n",
    );
}

/// Renders `scene` in `dir` on SIMD path `path` with `threads` threads; returns the PFM's
/// bytes.
fn render(dir: &Path, scene: &str, path: &str, threads: &str) -> Vec<u8> {
    let out = dir.join(format!("{scene}-{path}-{threads}.pfm"));
    let status = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(["render", scene, "-o"])
        .arg(&out)
        .args(["-t", threads, "--quiet"])
        .current_dir(dir)
        .env("PENUMBRA_SIMD", path)
        .stdin(Stdio::null())
        .status()
        .expect("run the penumbra binary");
    assert!(status.success(), "{scene} on {path} with {threads} threads");
    std::fs::read(&out).unwrap()
}

#[test]
fn cut_out_scenes_give_the_same_bytes_on_every_path_and_thread_count() {
    let dir = TempDir::new("cutouts");
    write_assets(&dir);
    let cut = "alpha_texture = \"atlas\"\nalpha_cutoff = 0.5";
    dir.write("leaves.toml", scene(cut));
    dir.write("cards.toml", scene(""));
    let reference = render(dir.path(), "leaves.toml", "portable", "1");
    for path in penumbra::supported_paths().iter().map(|p| p.name()) {
        for threads in ["1", "3"] {
            let bytes = render(dir.path(), "leaves.toml", path, threads);
            assert!(bytes == reference, "{path} with {threads} threads differs");
        }
    }
    // The cut-outs show: without the alpha keys the cards are whole.
    assert!(render(dir.path(), "cards.toml", "portable", "1") != reference);
}
