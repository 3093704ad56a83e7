//! A camera with keys or a path sees through a lens as a still camera does: `K`, `model` and
//! its keys, and the aperture hold at every frame, each frame's camera being the still camera
//! of that frame's pose with the same lens keys; what does not go together is refused at its
//! key.

use penumbra::{Lens, Scene, SceneFile, SceneFormat};

const K: &str = "K = [[40, 0, 31.5], [0, 40, 23.5], [0, 0, 1]]";

fn scene(cameras: &str) -> Result<Scene, penumbra::SceneError> {
    let text = format!(
        "[film]\nwidth = 64\nheight = 48\n{cameras}\n\
         [[lights]]\ntype = \"point\"\nposition = [0, 3, 3]\n\
         [[objects]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n"
    );
    SceneFile::from_str(&text, SceneFormat::Toml, "moving.toml", ".")?.build(1)
}

#[test]
fn each_frame_is_the_still_camera_of_its_pose_with_the_same_lens() {
    let lens = format!("model = \"opencv\"\n{K}\ndistortion = [-0.2, 0.05, 0.001, 0, 0.01]");
    let moving = scene(&format!(
        "[cameras.walk]\n{lens}\n\
         [[cameras.walk.keys]]\nframe = 0\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\
         [[cameras.walk.keys]]\nframe = 4\nposition = [3, 1, 4]\nlook_at = [0, 0.5, 0]\n"
    ))
    .unwrap();
    let path = moving.path("walk").expect("a path");
    for (frame, position, look_at) in [
        (0, "[0, 0, 5]", "[0, 0, 0]"),
        (4, "[3, 1, 4]", "[0, 0.5, 0]"),
    ] {
        let still = scene(&format!(
            "[cameras.walk]\n{lens}\nposition = {position}\nlook_at = {look_at}\n"
        ))
        .unwrap();
        let want = still.world.camera("walk").copied();
        assert_eq!(path.camera(frame), want, "frame {frame}");
    }
    let between = path.camera(2).unwrap();
    assert!(matches!(between.lens(), Lens::OpenCv(_)) && between.intrinsics().is_some());
}

#[test]
fn an_orbit_sees_through_a_fisheye_and_a_thin_lens_keeps_to_its_frames() {
    let orbit = "path = { type = \"orbit\", center = [0, 0, 0], radius = 5, frames = 3 }";
    let s = scene(&format!(
        "[cameras.turn]\nmodel = \"fisheye\"\n{K}\ndistortion = [0.02, 0, 0, 0]\n\
         max_angle = 100\n{orbit}\n\
         [cameras.soft]\nfov = 40\naperture_radius = 0.05\nfocus_distance = 5\n{orbit}\n"
    ))
    .unwrap();
    let turn = s.path("turn").unwrap();
    for frame in 0..3 {
        let c = turn.camera(frame).unwrap();
        assert!(matches!(c.lens(), Lens::Fisheye(_)), "frame {frame}");
        let soft = s.path("soft").unwrap().camera(frame).unwrap();
        assert_eq!(soft.aperture().map(|a| a.radius), Some(0.05));
        assert_eq!(soft.fov_y_deg(), 40.0);
    }
}

#[test]
fn lens_keys_that_do_not_go_together_are_refused_at_their_key() {
    let key = "[[cameras.c.keys]]\nframe = 0\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]";
    let orbit = "path = { type = \"orbit\", center = [0, 0, 0], radius = 5, frames = 3 }";
    let cases = [
        (format!("[cameras.c]\n{K}\n{key}\nfov = 40\n"), "cameras.c.keys[0].fov", "no fov"),
        (format!("[cameras.c]\n{K}\nfov = 40\n{key}\n"), "cameras.c", "fov or K"),
        (format!("[cameras.c]\nmodel = \"fisheye\"\ndistortion = [0, 0, 0, 0]\n{orbit}\n"), "cameras.c", "K"),
        (format!("[cameras.c]\n{orbit}\n"), "cameras.c", "fov"),
        (
            format!("[cameras.c]\nmodel = \"opencv\"\nfov = 40\ndistortion = [1, 2]\n{orbit}\n"),
            "cameras.c.distortion",
            "4, 5, 8 or 12",
        ),
        (
            format!("[cameras.c]\ncamera_to_world = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]\nfov = 40\n{orbit}\n"),
            "cameras.c",
            "camera_to_world",
        ),
    ];
    for (cameras, at, words) in cases {
        let Err(e) = scene(&cameras) else {
            panic!("{cameras}: accepted");
        };
        let e = e.to_string();
        assert!(e.contains(at) && e.contains(words), "{cameras}: {e}");
    }
}
