//! Property tests of scale and position (issue "Hardening", class 5): random scenes of random
//! size and distance from the origin render finite pixels, and the seed's room scaled and moved
//! by random factors renders the image of the room where it is (`scale.rs` checks fixed ones).

mod room;

use penumbra::{render, RenderOptions, RenderSettings, SceneFile, SceneFormat};
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use room::{psnr, render_room};

/// A number 10^e for e uniform in `[lo, hi)`.
fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo..hi).prop_map(|e| 10f64.powf(e))
}

fn vec3(range: std::ops::Range<f64>) -> impl Strategy<Value = [f64; 3]> {
    [range.clone(), range.clone(), range]
}

fn fmt3(v: [f64; 3]) -> String {
    format!("[{}, {}, {}]", v[0], v[1], v[2])
}

/// One object of a random kind, place, size and orientation, in a scene of scale `s` around
/// `origin`.
fn object(s: f64, origin: [f64; 3]) -> impl Strategy<Value = String> {
    (0..3usize, vec3(-3.0..3.0), vec3(0.2..2.0), vec3(0.0..360.0)).prop_map(
        move |(kind, at, size, rotate)| {
            let at = fmt3(std::array::from_fn(|i| origin[i] + s * at[i]));
            let shape = match kind {
                0 => "type = \"cube\"\ncenter = [0, 0, 0]\nsize = 1".to_owned(),
                1 => "type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 0.7".to_owned(),
                _ => {
                    "type = \"quad\"\ncorner = [-1, -1, 0]\nu = [2, 0, 0]\nv = [0, 2, 0]".to_owned()
                }
            };
            let scale = fmt3(size.map(|x| x * s));
            format!(
                "[[objects]]\n{shape}\nscale = {scale}\nrotate = {}\ntranslate = {at}\n",
                fmt3(rotate)
            )
        },
    )
}

/// A scene of 1 to 4 objects of scale 10⁻³..10⁴ at up to 10⁵ from the origin, an area light
/// of random size (10⁻³ to 10 times the scene's scale) and a point light, seen from a camera
/// 10 scales away.
fn scene() -> impl Strategy<Value = String> {
    (log_uniform(-3.0, 4.0), vec3(-1e5..1e5)).prop_flat_map(|(s, origin)| {
        (
            prop::collection::vec(object(s, origin), 1..5),
            log_uniform(-3.0, 1.0),
            vec3(-4.0..4.0),
        )
            .prop_map(move |(objects, light_size, point)| {
                let p = |x: f64, y: f64, z: f64| fmt3([origin[0] + s * x, origin[1] + s * y, origin[2] + s * z]);
                let side = s * light_size;
                format!(
                    "[film]\nwidth = 16\nheight = 16\n\
                     [camera]\nposition = {}\nlook_at = {}\nfov = 50\n\
                     [render]\nambient = 0.05\nlight_samples = 2\n\
                     [[lights]]\ntype = \"area\"\ncenter = {}\nu = [{side}, 0, 0]\nv = [0, 0, {side}]\n\
                     [[lights]]\ntype = \"point\"\nposition = {}\n\
                     {}",
                    p(0.0, 2.0, 10.0),
                    p(0.0, 0.0, 0.0),
                    p(0.0, 5.0, 0.0),
                    p(point[0], point[1], point[2]),
                    objects.join("")
                )
            })
    })
}

#[test]
fn random_scenes_at_any_scale_and_place_render_finite_pixels() {
    let mut runner = TestRunner::new(Config {
        cases: 256,
        failure_persistence: None,
        ..Config::default()
    });
    let options = RenderOptions {
        threads: 1,
        ..RenderOptions::default()
    };
    runner
        .run(&scene(), |text| {
            let scene = SceneFile::from_str(&text, SceneFormat::Toml, "random.toml", ".")
                .and_then(|f| f.build(1))
                .map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
            let settings = RenderSettings {
                spp: 1,
                ..scene.settings.clone()
            };
            let (film, _) = render(&scene.world, &settings, &options).unwrap();
            prop_assert!(
                film.pixels.iter().all(|p| p.is_finite()),
                "a pixel is not finite\n{text}"
            );
            Ok(())
        })
        .unwrap();
}

#[test]
fn the_room_scaled_and_moved_at_random_renders_the_same() {
    let base = render_room(1.0, 0.0);
    let mut runner = TestRunner::new(Config {
        cases: 32,
        failure_persistence: None,
        ..Config::default()
    });
    // The offset is at most 10⁵ and at most 10⁴ times the scale: further out, f32 rounds the
    // room's corners by more than 10⁻³ of its unit (at 10⁵ times, ~1%), which moves its edges
    // visibly whatever the renderer does (`scale.rs` checks 10⁵ at scale 1).
    let factors = (log_uniform(-3.0, 4.0), -1e4f64..1e4);
    runner
        .run(&factors, |(s, u)| {
            let t = (s * u).clamp(-1e5, 1e5);
            let db = psnr(&base, &render_room(s as f32, t as f32));
            prop_assert!(db >= 45.0, "scale {s}, offset {t}: {db:.1} dB");
            Ok(())
        })
        .unwrap();
}
