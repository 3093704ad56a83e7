//! Scale and distance from the origin (issue "Hardening", class 5): the seed's room moved far
//! from the origin or scaled up or down renders the image of the room where it is, within the
//! conformance tolerance. Shadow rays leave each surface by a bound on the hit point's rounding
//! error (see `Surface::error`), which follows the scene wherever it is.

mod room;

use room::{psnr, render_room};

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
