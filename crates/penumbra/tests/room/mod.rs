//! The seed's room (`scenes/cornell.toml`) mapped by a scale and an offset, rendered, and
//! compared by PSNR: shared by `scale.rs` (fixed factors) and `random_scenes.rs` (random ones).

use penumbra::{render, Film, RenderOptions, Scene, SceneError, SceneFile, SceneFormat};

/// The seed's room (`scenes/cornell.toml`) with every point mapped to `s·p + t` (t on all three
/// axes), at 96×96 with 4 samples per pixel.
pub fn room(s: f32, t: f32) -> String {
    let p = |x: f32, y: f32, z: f32| format!("[{}, {}, {}]", s * x + t, s * y + t, s * z + t);
    let v = |x: f32, y: f32, z: f32| format!("[{}, {}, {}]", s * x, s * y, s * z);
    let quad = |material: &str, corner: String, u: String, w: String| {
        format!("[[objects]]\ntype = \"quad\"\nmaterial = \"{material}\"\ncorner = {corner}\nu = {u}\nv = {w}\n")
    };
    let cube = |center: String, size: String, rotate: f32| {
        format!(
            "[[objects]]\ntype = \"cube\"\nmaterial = \"box\"\ncenter = [0, 0, 0]\nsize = {size}\n\
             rotate = [0, {rotate}, 0]\nscale = {s}\ntranslate = {center}\n"
        )
    };
    [
        "[film]\nwidth = 96\nheight = 96\n".to_string(),
        format!(
            "[cameras.front]\nposition = {}\nlook_at = {}\nup = [0, 1, 0]\nfov = 40\n",
            p(0.0, 3.0, 10.5),
            p(0.0, 3.0, 0.0)
        ),
        "[render]\nsampler = \"rgss\"\nsamples = 4\nlight_samples = 3\nambient = 0.1\n".into(),
        format!(
            "[[lights]]\ntype = \"area\"\ncenter = {}\nu = {}\nv = {}\ncolor = [1, 1, 1]\nintensity = 1.0\n",
            p(0.0, 5.9, -3.0),
            v(2.0, 0.0, 0.0),
            v(0.0, 0.0, 2.0)
        ),
        "[materials.white]\ndiffuse = 0.75\n[materials.red]\ndiffuse = [0.75, 0.12, 0.1]\n\
         [materials.green]\ndiffuse = [0.15, 0.6, 0.15]\n\
         [materials.box]\ndiffuse = [0.7, 0.7, 0.65]\nspecular = 0.35\nshininess = 40\n"
            .into(),
        quad("white", p(-3.0, 0.0, 0.0), v(6.0, 0.0, 0.0), v(0.0, 0.0, -6.0)),
        quad("white", p(-3.0, 6.0, -6.0), v(6.0, 0.0, 0.0), v(0.0, 0.0, 6.0)),
        quad("white", p(-3.0, 0.0, -6.0), v(6.0, 0.0, 0.0), v(0.0, 6.0, 0.0)),
        quad("red", p(-3.0, 0.0, 0.0), v(0.0, 0.0, -6.0), v(0.0, 6.0, 0.0)),
        quad("green", p(3.0, 0.0, -6.0), v(0.0, 0.0, 6.0), v(0.0, 6.0, 0.0)),
        cube(p(-1.1, 1.7, -3.9), "[1.6, 3.4, 1.6]".into(), 22.0),
        cube(p(1.15, 0.85, -2.2), "1.7".into(), 0.0),
    ]
    .join("\n")
}

/// The room of [`room`] loaded and built, or why not.
pub fn build_room(text: &str) -> Result<Scene, SceneError> {
    SceneFile::from_str(text, SceneFormat::Toml, "room.toml", ".")?.build(2)
}

pub fn render_room(s: f32, t: f32) -> Film {
    render_scene(&build_room(&room(s, t)).unwrap())
}

pub fn render_scene(scene: &Scene) -> Film {
    let options = RenderOptions {
        threads: 2,
        ..RenderOptions::default()
    };
    render(&scene.world, &scene.settings, &options).unwrap().0
}

/// Peak signal-to-noise ratio of `b` against `a`, peak 1.
pub fn psnr(a: &Film, b: &Film) -> f64 {
    let mut sum = 0.0;
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        for c in 0..3 {
            let d = (p[c] - q[c]) as f64;
            assert!(q[c].is_finite(), "a pixel is not finite");
            sum += d * d;
        }
    }
    let mse = sum / (a.pixels.len() * 3) as f64;
    if mse == 0.0 {
        f64::INFINITY
    } else {
        -10.0 * mse.log10()
    }
}
