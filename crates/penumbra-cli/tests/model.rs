//! A model is a scene: `penumbra render model.obj` (or `.ply`) renders a bare mesh with a
//! camera framing its bounds and the default light rig, and `--set` works on it as on a
//! scene file.

mod harness;
#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use harness::{error_line, image, ok, run_in};
use support::TempDir;

/// A unit cube centred at (5, 5, 5), far from the origin so that only a camera that frames
/// the bounds sees it, using the material `red` of `cube.mtl`.
const CUBE_OBJ: &str = "mtllib cube.mtl\n\
    v 4.5 4.5 4.5\nv 5.5 4.5 4.5\nv 5.5 5.5 4.5\nv 4.5 5.5 4.5\n\
    v 4.5 4.5 5.5\nv 5.5 4.5 5.5\nv 5.5 5.5 5.5\nv 4.5 5.5 5.5\n\
    usemtl red\n\
    f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6\n";

const CUBE_MTL: &str = "newmtl red\nKd 0.9 0.1 0.1\n";

/// The same cube as an ASCII PLY (no materials).
const CUBE_PLY: &str = "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\n\
    property float y\nproperty float z\nelement face 6\n\
    property list uchar int vertex_indices\nend_header\n\
    4.5 4.5 4.5\n5.5 4.5 4.5\n5.5 5.5 4.5\n4.5 5.5 4.5\n\
    4.5 4.5 5.5\n5.5 4.5 5.5\n5.5 5.5 5.5\n4.5 5.5 5.5\n\
    4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 3 7 6 2\n4 0 4 7 3\n4 1 2 6 5\n";

fn cube_dir(name: &str) -> TempDir {
    let dir = TempDir::new(name);
    dir.write("cube.obj", CUBE_OBJ);
    dir.write("cube.mtl", CUBE_MTL);
    dir.write("cube.ply", CUBE_PLY);
    dir
}

/// Pixels that are not the black background.
fn lit_pixels(img: &image::RgbImage) -> usize {
    img.pixels().filter(|p| p.0 != [0, 0, 0]).count()
}

#[test]
fn an_obj_renders_directly_framed_lit_and_with_its_materials() {
    let dir = cube_dir("model-obj");
    ok(run_in(
        dir.path(),
        [
            "render",
            "cube.obj",
            "--set",
            "film.width=64",
            "--set",
            "film.height=48",
            "-q",
        ],
    ));
    let img = image(&dir.join("cube.png"));
    assert_eq!(img.dimensions(), (64, 48));
    // Framed: the centre pixel is the cube, and the cube fills a good part of the picture
    // without touching its corners.
    let centre = img.get_pixel(32, 24).0;
    assert_ne!(centre, [0, 0, 0]);
    let lit = lit_pixels(&img);
    assert!(lit > 64 * 48 / 10, "{lit} lit pixels");
    for (x, y) in [(0, 0), (63, 0), (0, 47), (63, 47)] {
        assert_eq!(img.get_pixel(x, y).0, [0, 0, 0], "corner ({x}, {y})");
    }
    // The MTL's red material: red dominates wherever the cube is seen.
    assert!(centre[0] > 2 * centre[1].max(centre[2]), "{centre:?}");
}

#[test]
fn a_ply_renders_directly_with_the_default_material() {
    let dir = cube_dir("model-ply");
    ok(run_in(
        dir.path(),
        [
            "render",
            "cube.ply",
            "--set",
            "film.width=40",
            "--set",
            "film.height=30",
            "-q",
        ],
    ));
    let img = image(&dir.join("cube.png"));
    assert_eq!(img.dimensions(), (40, 30));
    let centre = img.get_pixel(20, 15).0;
    // Default material: grey, so the channels agree.
    assert_ne!(centre, [0, 0, 0]);
    assert_eq!(centre[0], centre[1]);
    assert_eq!(centre[1], centre[2]);
    assert!(lit_pixels(&img) > 40 * 30 / 10);
}

#[test]
fn overrides_work_on_a_model_as_on_a_scene_file() {
    let dir = cube_dir("model-set");
    let r = ok(run_in(
        dir.path(),
        [
            "render",
            "cube.ply",
            "--set",
            "film.width=16",
            "--set",
            "film.height=12",
            "--set",
            "render.samples=1",
            "--set",
            "render.background=[0, 0, 1]",
            "-o",
            "blue.png",
        ],
    ));
    assert!(r.stderr.contains("16x12, 1 spp rgss,"), "{}", r.stderr);
    let img = image(&dir.join("blue.png"));
    assert_eq!(img.get_pixel(0, 0).0, [0, 0, 255]);
    // A bad override is refused naming it, as for a scene file.
    let r = run_in(
        dir.path(),
        [
            "render",
            "cube.obj",
            "--set",
            "film.width=0",
            "-o",
            "bad.png",
        ],
    );
    let line = error_line(&r, 2);
    assert!(line.contains("--set film.width=0"), "{line}");
    assert!(!dir.join("bad.png").exists());
}

#[test]
fn the_default_is_the_documented_rig_800_by_600_rgss_4() {
    let dir = cube_dir("model-default");
    // A 1-pixel region keeps the run short while the settings stay the model's defaults.
    let r = ok(run_in(
        dir.path(),
        [
            "render",
            "cube.ply",
            "--pixelbounds",
            "0,1,0,1",
            "-o",
            "d.png",
        ],
    ));
    assert!(
        r.stderr.contains("800x600, 4 spp rgss, 16 light samples"),
        "{}",
        r.stderr
    );
}

#[test]
fn a_bad_or_missing_mesh_is_one_line_naming_the_file() {
    let dir = cube_dir("model-bad");
    dir.write("empty.obj", "v 0 0 0\n");
    for (file, want) in [("empty.obj", "no faces"), ("missing.ply", "cannot read")] {
        let r = run_in(dir.path(), ["render", file]);
        let line = error_line(&r, 2);
        assert!(line.starts_with(&format!("error: {file}: ")), "{line}");
        assert!(line.contains(want), "{line}");
        assert!(!dir
            .join(file.replace(".obj", ".png").replace(".ply", ".png"))
            .exists());
    }
}
