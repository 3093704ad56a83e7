//! Calibrated still cameras: an intrinsic matrix `K` (fx ≠ fy, an off-centre principal point,
//! skew) and a `camera_to_world` pose in OpenCV's axes. K scales with the film; `--poses`
//! gives back the K and the pose the file gave; bad values are refused at their keys (that
//! every hit projects back through K onto its pixel centre: tests/camera_models.rs).

use glam::{DMat3, DVec3};
use penumbra::{render_with_aovs, CameraPose, RenderOptions, Scene, SceneFile, SceneFormat, View};

/// A room of quads around the origin, seen by `camera` (a `[camera]` table's keys).
fn scene(camera: &str, film: (u32, u32)) -> Result<Scene, penumbra::SceneError> {
    let text = format!(
        "[film]\nwidth = {}\nheight = {}\n[camera]\n{camera}\n[render]\nsampler = \"center\"\n\
         [[lights]]\ntype = \"point\"\nposition = [0, 2, 2]\n\
         [[objects]]\ntype = \"quad\"\ncorner = [-4, -2, -3]\nu = [8, 0, 0]\nv = [0, 5, 0]\n\
         [[objects]]\ntype = \"quad\"\ncorner = [-4, -2, 4]\nu = [8, 0, 0]\nv = [0, 0, -7]\n\
         [[objects]]\ntype = \"sphere\"\ncenter = [0.7, -0.5, 0]\nradius = 0.8\n",
        film.0, film.1
    );
    SceneFile::from_str(&text, SceneFormat::Toml, "k.toml", ".")?.build(1)
}

/// A turn of 20° about y and 10° about x, then a shift: camera to world in OpenCV's axes
/// (x right, y down, z forward), looking along about −z of the world.
fn pose() -> [[f64; 4]; 4] {
    let (a, b) = (20f64.to_radians(), 10f64.to_radians());
    // Looking down −z with y down and x right is a half turn about x.
    let flip = DMat3::from_cols(DVec3::X, -DVec3::Y, -DVec3::Z);
    let r = DMat3::from_rotation_y(a) * DMat3::from_rotation_x(b) * flip;
    let t = DVec3::new(0.5, 0.3, 6.0);
    let c = |j: usize| r.col(j);
    [
        [c(0).x, c(1).x, c(2).x, t.x],
        [c(0).y, c(1).y, c(2).y, t.y],
        [c(0).z, c(1).z, c(2).z, t.z],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

fn rows<const N: usize>(m: &[[f64; N]]) -> String {
    let row = |r: &[f64; N]| format!("[{}]", r.map(|v| format!("{v:?}")).join(", "));
    format!("[{}]", m.iter().map(row).collect::<Vec<_>>().join(", "))
}

const K: [[f64; 3]; 3] = [[70.0, 0.8, 51.3], [0.0, 64.5, 33.9], [0.0, 0.0, 1.0]];

#[test]
fn the_poses_give_back_the_k_and_the_pose_of_the_file() {
    // That every hit projects back through K onto its pixel: tests/camera_models.rs.
    let m = pose();
    let camera = format!("K = {}\ncamera_to_world = {}", rows(&K), rows(&m));
    let s = scene(&camera, (96, 64)).unwrap();
    // The poses give back the K and the pose of the file.
    let c = View::First.camera(&s.world).unwrap();
    let p = CameraPose::new(&c, 96, 64, (0, 0));
    assert_eq!(p.k, K);
    for (a, b) in p.camera_to_world.iter().flatten().zip(m.iter().flatten()) {
        assert!((a - b).abs() < 1e-6, "{:?} vs {m:?}", p.camera_to_world);
    }
}

#[test]
fn k_scales_with_the_film_about_its_pixel_corners() {
    let s = scene(
        &format!(
            "K = {}\nposition = [0, 0, 6]\nlook_at = [0, 0, 0]",
            rows(&K)
        ),
        (96, 64),
    );
    let c = View::First.camera(&s.unwrap().world).unwrap();
    // Half the film: focal lengths and skew halve, and (c + ½) halves.
    let p = CameraPose::new(&c, 48, 32, (0, 0));
    assert_eq!(
        p.k,
        [[35.0, 0.4, 25.4], [0.0, 32.25, 16.7], [0.0, 0.0, 1.0]]
    );
}

#[test]
fn a_k_that_is_the_fovs_renders_the_fovs_view() {
    // f = H / (2·tan(fov/2)) and a centred principal point: the fov's own camera.
    let f = 64.0 / (2.0 * 20f64.to_radians().tan());
    let k = [[f, 0.0, 47.5], [0.0, f, 31.5], [0.0, 0.0, 1.0]];
    let at = "position = [0, 0, 6]\nlook_at = [0, 0, 0]";
    let by_k = scene(&format!("K = {}\n{at}", rows(&k)), (96, 64)).unwrap();
    let by_fov = scene(&format!("fov = 40\n{at}"), (96, 64)).unwrap();
    let run = |s: &Scene| render_with_aovs(&s.world, &s.settings, &RenderOptions::default());
    let (a, b) = (run(&by_k).unwrap().1, run(&by_fov).unwrap().1);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        assert_eq!(p.object_id, q.object_id);
        assert!((p.position - q.position).length() < 1e-4, "{p:?} vs {q:?}");
    }
}

#[test]
fn bad_intrinsics_and_poses_are_refused_at_their_keys() {
    let at = "position = [0, 0, 6]\nlook_at = [0, 0, 0]";
    let mut scaled = pose();
    scaled[0][0] *= 2.0;
    let mut mirrored = pose();
    for row in &mut mirrored[..3] {
        row[0] = -row[0];
    }
    let cases = [
        (
            format!("fov = 40\nK = {}\n{at}", rows(&K)),
            "camera",
            "fov or K, not both",
        ),
        (
            format!("K = [[0, 0, 5], [0, 60, 5], [0, 0, 1]]\n{at}"),
            "camera.K",
            "greater than 0",
        ),
        (
            format!("K = [[60, 0, 5], [0, 60, 5], [0, 1, 1]]\n{at}"),
            "camera.K",
            "[0, 0, 1]",
        ),
        (
            format!("K = [[60, 0, 5], [0, 60, nan], [0, 0, 1]]\n{at}"),
            "camera.K",
            "NaN",
        ),
        (
            format!("fov = 40\ncamera_to_world = {}", rows(&scaled)),
            "camera.camera_to_world",
            "rigid",
        ),
        (
            format!("fov = 40\ncamera_to_world = {}", rows(&mirrored)),
            "camera.camera_to_world",
            "rigid",
        ),
        (
            format!("fov = 40\ncamera_to_world = {}\n{at}", rows(&pose())),
            "camera",
            "not both",
        ),
    ];
    for (camera, key, words) in cases {
        let Err(e) = scene(&camera, (96, 64)) else {
            panic!("{camera}: accepted");
        };
        let e = e.to_string();
        assert!(e.contains(key) && e.contains(words), "{camera}: {e}");
    }
}
