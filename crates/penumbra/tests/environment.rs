//! Environment lights end to end: a uniform sky lights a floor to its albedo, the map's
//! orientation (which way +x, +z and +y are, and the rotation), shadows from a sky, the same
//! bytes for any thread count, and refusals with the key to blame.

mod support;

use penumbra::{render, Film, RenderOptions, RenderSettings, Scene, SceneFile};
use support::TempDir;

/// The scene `text` with its files in `dir`, built.
fn build(dir: &TempDir, text: &str) -> Result<Scene, penumbra::SceneError> {
    let path = dir.write("scene.toml", text);
    SceneFile::load(&path)?.build(0)
}

fn render_with(scene: &Scene, settings: &RenderSettings) -> Film {
    render(&scene.world, settings, &RenderOptions::default())
        .expect("render")
        .0
}

/// Writes a `w`×`h` linear EXR map with `radiance(column, row)`.
fn exr(dir: &TempDir, name: &str, w: u32, h: u32, radiance: impl Fn(u32, u32) -> [f32; 3]) {
    let img = image::Rgb32FImage::from_fn(w, h, |x, y| image::Rgb(radiance(x, y)));
    img.save(dir.join(name)).expect("write EXR");
}

/// A camera at the origin looking along `dir`, with `light` the only light and no geometry.
fn sky_view(light: &str, look: [f32; 3]) -> String {
    format!(
        "[film]\nwidth = 4\nheight = 4\n[camera]\nposition = [0, 0, 0]\nlook_at = \
         {look:?}\nup = [0, 1, 0.001]\nfov = 10\n[render]\nsampler = \"center\"\n\
         [[lights]]\n{light}\n"
    )
}

/// The mean red of a film.
fn mean_red(film: &Film) -> f32 {
    let n = (film.width * film.height) as f32;
    (0..film.height)
        .flat_map(|y| (0..film.width).map(move |x| (x, y)))
        .map(|(x, y)| film.get(x, y).x)
        .sum::<f32>()
        / n
}

#[test]
fn a_uniform_sky_lights_a_white_floor_to_one() {
    // Irradiance π under radiance 1, times albedo/π: 1, under the physical model.
    let dir = TempDir::new("env-uniform");
    let scene = build(
        &dir,
        "[film]\nwidth = 8\nheight = 8\n[camera]\nposition = [0, 3, 0.01]\nlook_at = \
         [0, 0, 0]\nfov = 20\n[render]\nlight_model = \"physical\"\nambient = 0\nsamples = 16\n\
         sampler = \"grid\"\n[materials.white]\ndiffuse = 1\n[[lights]]\ntype = \
         \"environment\"\ncolor = [1, 1, 1]\nsamples = 8\n[[objects]]\ntype = \"quad\"\n\
         material = \"white\"\ncorner = [-50, 0, -50]\nu = [100, 0, 0]\nv = [0, 0, 100]\n",
    )
    .unwrap();
    let film = render_with(&scene, &scene.settings);
    let mean = mean_red(&film);
    assert!((mean - 1.0).abs() < 0.02, "mean {mean}");
}

#[test]
fn the_map_faces_as_mitsubas_and_turns_with_rotation() {
    // A 16×8 map bright only in the column centred on u = ¼ (+x) at the horizon rows.
    let dir = TempDir::new("env-orientation");
    exr(&dir, "x.exr", 16, 9, |x, y| match (x, y) {
        (3..=4, 3..=5) => [10.0, 10.0, 10.0],
        _ => [0.0, 0.0, 0.0],
    });
    let see = |rotation: f32, look: [f32; 3]| {
        let light = format!("type = \"environment\"\nfile = \"x.exr\"\nrotation = {rotation}");
        let scene = build(&dir, &sky_view(&light, look)).unwrap();
        mean_red(&render_with(&scene, &scene.settings))
    };
    assert!(see(0.0, [1.0, 0.0, 0.0]) > 5.0, "+x is u = 1/4");
    for look in [
        [-1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
        [0.0, 1.0, 0.0],
    ] {
        assert!(see(0.0, look) < 0.01, "{look:?} is dark");
    }
    // rotate(+y, 90°) takes +x to −z.
    assert!(see(90.0, [0.0, 0.0, -1.0]) > 5.0);
    assert!(see(90.0, [1.0, 0.0, 0.0]) < 0.01);
}

#[test]
fn the_top_row_is_up_and_an_invisible_map_shows_the_background() {
    let dir = TempDir::new("env-up");
    exr(&dir, "up.exr", 8, 5, |_, y| {
        if y == 0 {
            [3.0; 3]
        } else {
            [0.0; 3]
        }
    });
    let light = "type = \"environment\"\nfile = \"up.exr\"";
    let scene = build(&dir, &sky_view(light, [0.0, 1.0, 0.0])).unwrap();
    assert!(mean_red(&render_with(&scene, &scene.settings)) > 2.0);
    let hidden = format!("{light}\nvisible = false");
    let scene = build(&dir, &sky_view(&hidden, [0.0, 1.0, 0.0])).unwrap();
    let settings = RenderSettings {
        background: glam::Vec3::new(0.25, 0.0, 0.0),
        ..scene.settings.clone()
    };
    assert_eq!(mean_red(&render_with(&scene, &settings)), 0.25);
}

/// A floor seen from straight above, under a sky bright only in a patch 45° up toward +x,
/// with a small roof 1 above the origin: its shadow falls about 1 toward −x.
fn roofed(dir: &TempDir) -> Scene {
    exr(dir, "patch.exr", 32, 17, |x, y| match (x, y) {
        (6..=9, 3..=5) => [4.0; 3],
        _ => [0.0; 3],
    });
    build(
        dir,
        "[film]\nwidth = 32\nheight = 32\n[camera]\nposition = [0, 8, 0]\nlook_at = \
         [0, 0, 0]\nup = [0, 0, -1]\nfov = 40\n[render]\nlight_model = \"physical\"\n\
         ambient = 0\n[[lights]]\ntype = \"environment\"\nfile = \"patch.exr\"\nsamples = 6\n\
         visible = false\n[[objects]]\ntype = \"quad\"\ncorner = [-5, 0, -5]\nu = [10, 0, 0]\n\
         v = [0, 0, 10]\n[[objects]]\ntype = \"quad\"\ncorner = [-0.5, 1, -0.5]\nu = [1, 0, 0]\n\
         v = [0, 0, 1]\n",
    )
    .unwrap()
}

#[test]
fn a_sky_casts_shadows_away_from_its_bright_side() {
    let dir = TempDir::new("env-shadow");
    let scene = roofed(&dir);
    let film = render_with(&scene, &scene.settings);
    // The view spans about ±2.9 units: x = ∓1 at columns 16 ∓ 5.5 (+x to the right).
    let (shadowed, lit) = (film.get(10, 16).x, film.get(21, 16).x);
    assert!(lit > 0.05, "the floor toward the light is lit: {lit}");
    assert!(
        shadowed < 0.5 * lit,
        "the floor behind the roof is in shadow: {shadowed} vs {lit}"
    );
}

#[test]
fn the_same_bytes_for_any_thread_count() {
    let dir = TempDir::new("env-threads");
    let scene = roofed(&dir);
    let one = render(
        &scene.world,
        &scene.settings,
        &RenderOptions {
            threads: 1,
            ..RenderOptions::default()
        },
    )
    .unwrap()
    .0;
    let two = render(
        &scene.world,
        &scene.settings,
        &RenderOptions {
            threads: 2,
            ..RenderOptions::default()
        },
    )
    .unwrap()
    .0;
    let bits = |f: &Film| -> Vec<[u32; 3]> {
        f.pixels
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect()
    };
    assert_eq!(bits(&one), bits(&two));
}

#[test]
fn bad_environments_name_their_key() {
    let dir = TempDir::new("env-bad");
    let message = |light: &str| {
        build(&dir, &sky_view(light, [1.0, 0.0, 0.0]))
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    };
    let both = message("type = \"environment\"\nfile = \"a.exr\"\ncolor = [1, 1, 1]");
    assert!(
        both.contains("lights[0].color") && both.contains("not both"),
        "{both}"
    );
    let neither = message("type = \"environment\"");
    assert!(neither.contains("needs `file`"), "{neither}");
    let missing = message("type = \"environment\"\nfile = \"nowhere.hdr\"");
    assert!(
        missing.contains("lights[0].file") && missing.contains("nowhere.hdr"),
        "{missing}"
    );
    exr(&dir, "thin.exr", 1, 4, |_, _| [1.0; 3]);
    let thin = message("type = \"environment\"\nfile = \"thin.exr\"");
    assert!(thin.contains("at least 2×2"), "{thin}");
    exr(&dir, "nan.exr", 4, 4, |x, _| {
        [if x == 2 { f32::NAN } else { 1.0 }; 3]
    });
    let nan = message("type = \"environment\"\nfile = \"nan.exr\"");
    assert!(nan.contains("texel (2, 0)"), "{nan}");
    let zero = message("type = \"environment\"\ncolor = [1, 1, 1]\nsamples = 0");
    assert!(zero.contains("lights[0].samples"), "{zero}");
    let negative = message("type = \"environment\"\ncolor = [1, 1, 1]\nintensity = -1");
    assert!(negative.contains("lights[0].intensity"), "{negative}");
}

/// A white floor seen from straight above, lit by `light` alone (physical model, no ambient).
fn floor_under(dir: &TempDir, light: &str, model: &str) -> Film {
    let scene = build(
        dir,
        &format!(
            "[film]\nwidth = 33\nheight = 33\n[camera]\nposition = [0, 10, 0]\nlook_at = \
             [0, 0, 0]\nup = [0, 0, -1]\nfov = 60\n[render]\nlight_model = \"{model}\"\n\
             ambient = 0\nsampler = \"center\"\n[materials.white]\ndiffuse = 1\n[[lights]]\n\
             {light}\n[[objects]]\ntype = \"quad\"\nmaterial = \"white\"\ncorner = \
             [-20, 0, -20]\nu = [40, 0, 0]\nv = [0, 0, 40]\n"
        ),
    )
    .unwrap();
    render_with(&scene, &scene.settings)
}

#[test]
fn a_sun_gives_its_irradiance() {
    let dir = TempDir::new("sun");
    // Straight down, irradiance π: a white floor looks 1 under the physical model.
    let sun = "type = \"directional\"\ndirection = [0, -1, 0]\nintensity = 3.14159265";
    let film = floor_under(&dir, sun, "physical");
    assert!(
        (film.get(16, 16).x - 1.0).abs() < 1e-5,
        "{}",
        film.get(16, 16).x
    );
    assert!(
        (film.get(2, 30).x - 1.0).abs() < 1e-5,
        "no falloff with distance"
    );
    // At 60° from the normal, half of that.
    let slanted =
        "type = \"directional\"\ndirection = [0.8660254, -0.5, 0]\nintensity = 3.14159265";
    assert!((floor_under(&dir, slanted, "physical").get(16, 16).x - 0.5).abs() < 1e-5);
    // Under phong it is a point light infinitely far away: k_d·cos.
    let phong = floor_under(
        &dir,
        "type = \"directional\"\ndirection = [0, -1, 0]",
        "phong",
    );
    assert!((phong.get(16, 16).x - 1.0).abs() < 1e-6);
    // A wide sun from the same direction gives the same light, its samples spread over
    // the cone (cos 2.5° ≈ 0.999).
    let wide = format!("{sun}\nangle = 5\nsamples = 4");
    assert!((floor_under(&dir, &wide, "physical").get(16, 16).x - 1.0).abs() < 2e-3);
}

#[test]
fn a_spot_lights_its_cone_only() {
    let dir = TempDir::new("spot");
    // 4 above the floor, pointing down, intensity 16π: I/d²·(1/π) = 1 right under it.
    let spot = "type = \"spot\"\nposition = [0, 4, 0]\ndirection = [0, -1, 0]\n\
                inner_angle = 20\nouter_angle = 30\nintensity = 50.2654825";
    let film = floor_under(&dir, spot, "physical");
    assert!(
        (film.get(16, 16).x - 1.0).abs() < 1e-4,
        "{}",
        film.get(16, 16).x
    );
    // The view spans about ±5.77 units: 4·tan 30° ≈ 2.31 from the centre is the cone's edge,
    // about 6.4 pixels out. Beyond it, dark; well inside, lit.
    assert_eq!(film.get(16 + 9, 16).x, 0.0);
    assert!(film.get(16 + 3, 16).x > 0.5);
}

#[test]
fn bad_suns_and_spots_name_their_key() {
    let dir = TempDir::new("sun-bad");
    let message = |light: &str| {
        build(&dir, &sky_view(light, [1.0, 0.0, 0.0]))
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    };
    let zero = message("type = \"directional\"\ndirection = [0, 0, 0]");
    assert!(
        zero.contains("lights[0].direction") && zero.contains("zero"),
        "{zero}"
    );
    let wide = message("type = \"directional\"\ndirection = [0, -1, 0]\nangle = 120");
    assert!(wide.contains("lights[0].angle"), "{wide}");
    let crossed = message(
        "type = \"spot\"\nposition = [0, 1, 0]\ndirection = [0, -1, 0]\ninner_angle = 30\n\
         outer_angle = 20",
    );
    assert!(crossed.contains("lights[0].outer_angle"), "{crossed}");
    let missing = message("type = \"spot\"\nposition = [0, 1, 0]");
    assert!(missing.contains("direction"), "{missing}");
}

/// A file of the shared assets' HDRIs (`../shared/assets/hdri/` beside the repository), or
/// `None` (the test is skipped) in a checkout without them.
fn shared_hdri(name: &str) -> Option<std::path::PathBuf> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/assets/hdri")
        .join(name);
    path.exists().then_some(path)
}

#[test]
fn importance_sampling_beats_uniform_sampling_tenfold_on_a_sunset() {
    // The irradiance on an upward surface under venice_sunset (a small, bright sun): the mean
    // squared error of 64-sample stratified estimates over 200 seeds, by the map's importance
    // sampling and by uniform sampling of the sphere, against a 256²-sample reference.
    let Some(path) = shared_hdri("venice_sunset_1k.hdr") else {
        eprintln!("skipped: ../shared/assets/hdri is absent");
        return;
    };
    let img = image::open(&path).unwrap().into_rgb32f();
    let texels = img.pixels().map(|p| glam::Vec3::from(p.0)).collect();
    let map = penumbra::EnvironmentMap::new(img.width(), img.height(), texels).unwrap();
    let estimate = |n: u32, seed: u64, importance: bool| {
        let mut rng = penumbra::Rng::new(seed, &[]);
        let mut sum = 0.0f64;
        for k in 0..n {
            for l in 0..n {
                let xi = rng.uniform2();
                let u = glam::Vec2::new((k as f32 + xi.x) / n as f32, (l as f32 + xi.y) / n as f32);
                let (d, radiance, pdf) = if importance {
                    let s = map.sample(u);
                    (s.direction, s.radiance, s.pdf)
                } else {
                    let c = 1.0 - 2.0 * u.x;
                    let r = (1.0 - c * c).max(0.0).sqrt();
                    let phi = 2.0 * std::f32::consts::PI * u.y;
                    let d = glam::Vec3::new(r * phi.sin(), c, -r * phi.cos());
                    (d, map.radiance(d), 1.0 / (4.0 * std::f32::consts::PI))
                };
                let lum = 0.2126 * radiance.x + 0.7152 * radiance.y + 0.0722 * radiance.z;
                sum += f64::from(lum * d.y.max(0.0) / pdf);
            }
        }
        sum / f64::from(n * n)
    };
    let reference = estimate(256, 12345, true);
    let mse = |importance: bool| {
        (0..200)
            .map(|seed| (estimate(8, seed, importance) - reference).powi(2))
            .sum::<f64>()
            / 200.0
    };
    let (importance, uniform) = (mse(true), mse(false));
    eprintln!(
        "MSE: importance {importance:.4e}, uniform {uniform:.4e}, ratio {:.1}",
        uniform / importance
    );
    assert!(uniform >= 10.0 * importance, "{importance} vs {uniform}");
}
