//! Scale and distance from the origin (issue "Hardening", class 5): the seed's room moved far
//! from the origin or scaled up or down renders the image of the room where it is, within the
//! conformance tolerance. Shadow rays leave each surface by a bound on the hit point's rounding
//! error (see `Surface::error`), which follows the scene wherever it is. Beyond the scales where
//! 32-bit ray-triangle products stay exact (issue 30, class 2), a scene is refused at its key
//! instead of rendering black.

mod room;

use room::{build_room, psnr, render_room, render_scene, room};

#[test]
fn the_room_far_from_the_origin_or_scaled_renders_the_same() {
    let base = render_room(1.0, 0.0);
    for (s, t) in [
        (1.0, 1e3),
        (1.0, 1e4),
        (1.0, 1e5),
        (1e-3, 0.0),
        (1e-3, 10.0),
        (1e4, 0.0),
    ] {
        let db = psnr(&base, &render_room(s, t));
        assert!(
            db >= 45.0,
            "scale {s}, offset {t}: {db:.1} dB against the room at the origin"
        );
    }
}

#[test]
fn the_room_renders_the_same_from_1e_minus_9_to_1e11() {
    let base = render_room(1.0, 0.0);
    for exponent in [-9, -6, 6, 9, 11] {
        let film = render_room(10f32.powi(exponent), 0.0);
        let worst = film
            .pixels
            .iter()
            .zip(&base.pixels)
            .map(|(a, b)| (*a - *b).abs().max_element())
            .fold(0.0f32, f32::max);
        assert!(
            worst < 1e-4,
            "scale 1e{exponent}: a pixel differs by {worst}"
        );
    }
}

#[test]
fn scales_beyond_are_refused_at_their_key() {
    for (s, key, words) in [
        (1e13, "objects[0]", "within ±1e12"),
        (1e-12, "objects", "at least 1e-9 across"),
    ] {
        let e = build_room(&room(s, 0.0)).err();
        let e = e.unwrap_or_else(|| panic!("the room at scale {s} was accepted"));
        let text = e.to_string();
        assert!(
            text.contains(key) && text.contains(words),
            "scale {s}: {text}"
        );
    }
    // A camera 1e20 from small triangles is fine; 1e17 from huge ones is not.
    let near = with_camera_at(&room(1.0, 0.0), "[0, 3, 1e20]");
    assert!(render_scene(&build_room(&near).unwrap())
        .pixels
        .iter()
        .all(|p| p.is_finite()));
    let far = with_camera_at(&room(1e11, 0.0), "[0, 3e11, 1e17]");
    let Err(e) = build_room(&far) else {
        panic!("a camera too far was accepted")
    };
    let e = e.to_string();
    assert!(
        e.contains("cameras.front.position") && e.contains("too far"),
        "{e}"
    );
}

/// `text` with its first `position = ` line (the camera's) set to `position`.
fn with_camera_at(text: &str, position: &str) -> String {
    let (before, after) = text.split_once("position = ").unwrap();
    let rest = after.split_once('\n').unwrap().1;
    format!("{before}position = {position}\n{rest}")
}
