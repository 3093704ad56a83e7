//! Coverage alpha (`film.alpha`, `--alpha`): each pixel's alpha is the fraction of its samples
//! whose camera ray hits geometry, counted here ray by ray; what camera rays miss (the
//! background, a visible environment) adds nothing to the colour, which is premultiplied; the
//! colour with alpha off is today's; PNG holds straight alpha and EXR premultiplied.

mod support;

use std::path::Path;

use glam::Vec2;
use penumbra::{
    render, render_with_aovs, write_image, Aov, AovValues, Film, FilmCamera, ImageError,
    PixelBounds, RenderOptions, RenderSettings, Rgb, Scene, SceneFile, SceneFormat,
};

const W: u32 = 40;
const H: u32 = 30;

/// A cube and a sphere in front of a red background, off the film's centre so that edges
/// cross pixels at odd places; `extra` adds keys to `[render]`.
fn scene(sampler: &str, extra: &str) -> Scene {
    let text = format!(
        "[film]\nwidth = {W}\nheight = {H}\nalpha = true\n\
         [camera]\nposition = [0.3, 0.4, 5]\nlook_at = [0.1, 0, 0]\nfov = 40\n\
         [render]\nsampler = \"{sampler}\"\nbackground = [1, 0, 0]\n{extra}\n\
         [[lights]]\ntype = \"point\"\nposition = [2, 3, 4]\n\
         [[objects]]\ntype = \"cube\"\ncenter = [-0.6, -0.1, 0]\nsize = 1.1\nrotate = [10, 35, 5]\n\
         [[objects]]\ntype = \"sphere\"\ncenter = [0.9, 0.35, -0.4]\nradius = 0.6\n"
    );
    SceneFile::from_str(&text, SceneFormat::Toml, "alpha.toml", ".")
        .unwrap()
        .build(1)
        .unwrap()
}

fn render_film(scene: &Scene, settings: &RenderSettings) -> Film {
    render(&scene.world, settings, &RenderOptions::default())
        .unwrap()
        .0
}

/// The offsets of rgss 4 as the scene format defines them: the 2×2 grid's cell centres
/// turned by arctan(1/2) about the pixel centre, wrapped into the pixel.
fn rgss4() -> Vec<Vec2> {
    let (sin, cos) = (1.0 / 5f32.sqrt(), 2.0 / 5f32.sqrt());
    let wrap = |x: f32| {
        if x >= 0.5 {
            x - 1.0
        } else if x < -0.5 {
            x + 1.0
        } else {
            x
        }
    };
    let cells = [
        (-0.25f32, -0.25f32),
        (-0.25, 0.25),
        (0.25, -0.25),
        (0.25, 0.25),
    ];
    cells
        .iter()
        .map(|&(x, y)| Vec2::new(wrap(x * cos - y * sin), wrap(x * sin + y * cos)))
        .collect()
}

/// How many of `offsets` from pixel (x, y)'s centre see geometry, each ray traced alone.
fn hits(scene: &Scene, settings: &RenderSettings, offsets: &[Vec2], x: u32, y: u32) -> usize {
    let camera = FilmCamera::new(&settings.check(&scene.world).unwrap(), W, H);
    let accel = scene.world.accel();
    let seen = |o: &Vec2| {
        let ray = camera
            .ray(x as f32 + 0.5 + o.x, y as f32 + 0.5 + o.y)
            .unwrap();
        accel.intersect(&ray, 0.0, f32::INFINITY).is_some()
    };
    offsets.iter().filter(|o| seen(o)).count()
}

#[test]
fn alpha_is_the_hit_mask_with_one_sample_and_the_hit_fraction_with_rgss() {
    let center = scene("center", "");
    let (film, aovs, _) =
        render_with_aovs(&center.world, &center.settings, &Default::default()).unwrap();
    let AovValues::Floats(depth) = aovs.values(Aov::Depth).unwrap() else {
        panic!("depth is floats")
    };
    let alpha = film.alpha.as_ref().expect("alpha");
    let mask: Vec<f32> = depth.iter().map(|d| d.is_finite() as u8 as f32).collect();
    assert_eq!(alpha, &mask);
    assert!(mask.contains(&0.0) && mask.contains(&1.0));

    let rgss = scene("rgss", "");
    let film = render_film(&rgss, &rgss.settings);
    let alpha = film.alpha.as_ref().expect("alpha");
    let offsets = rgss4();
    let mut partial = 0;
    for y in 0..H {
        for x in 0..W {
            let n = hits(&rgss, &rgss.settings, &offsets, x, y);
            let a = alpha[(y * W + x) as usize];
            assert_eq!(a, n as f32 / 4.0, "pixel ({x}, {y})");
            partial += !n.is_multiple_of(4) as usize;
        }
    }
    assert!(partial > 20, "edges cross {partial} pixels");
}

#[test]
fn misses_add_nothing_to_the_colour_and_alpha_off_keeps_it() {
    let s = scene("rgss", "");
    let with = render_film(&s, &s.settings);
    let opaque = RenderSettings {
        alpha: false,
        ..s.settings.clone()
    };
    let without = render_film(&s, &opaque);
    assert_eq!(without.alpha, None);
    let alpha = with.alpha.as_ref().unwrap();
    let red = Rgb::new(1.0, 0.0, 0.0);
    for (i, (&c, &a)) in with.pixels.iter().zip(alpha).enumerate() {
        // The opaque image is the premultiplied one over the background.
        let over = c + (1.0 - a) * red;
        assert!(
            (over - without.pixels[i]).abs().max_element() < 1e-5,
            "pixel {i}"
        );
        if a == 0.0 {
            assert_eq!(c, Rgb::ZERO);
        }
    }
}

#[test]
fn a_visible_environment_is_background() {
    let env = "[[lights]]\ntype = \"environment\"\ncolor = [0.2, 0.3, 0.9]\n";
    let text = format!(
        "[film]\nwidth = {W}\nheight = {H}\nalpha = true\n\
         [camera]\nposition = [0.3, 0.4, 5]\nlook_at = [0.1, 0, 0]\nfov = 40\n\
         [render]\nsampler = \"center\"\n{env}\
         [[objects]]\ntype = \"sphere\"\ncenter = [0.9, 0.35, -0.4]\nradius = 0.6\n"
    );
    let lit = SceneFile::from_str(&text, SceneFormat::Toml, "env.toml", ".")
        .unwrap()
        .build(1)
        .unwrap();
    let f = render_film(&lit, &lit.settings);
    let alpha = f.alpha.as_ref().unwrap();
    let (mut holes, mut lit_points) = (0, 0);
    for (&c, &a) in f.pixels.iter().zip(alpha) {
        match a {
            0.0 => {
                assert_eq!(c, Rgb::ZERO);
                holes += 1;
            }
            1.0 => lit_points += (c.max_element() > 0.0) as usize,
            _ => panic!("one sample: alpha {a}"),
        }
    }
    // The environment still lights the sphere.
    assert!(holes > 0 && lit_points > 0, "{holes} {lit_points}");
}

#[test]
fn passes_and_regions_give_the_alpha_of_one_render() {
    let s = scene("jittered", "samples = 9");
    let whole = render_film(&s, &s.settings);
    let keep = std::sync::Mutex::new(Vec::new());
    let sink = |p: &penumbra::Pass| keep.lock().unwrap().push(p.film.alpha.clone());
    let options = RenderOptions {
        passes: Some(&sink),
        ..RenderOptions::default()
    };
    let progressive = render(&s.world, &s.settings, &options).unwrap().0;
    assert_eq!(progressive, whole);
    assert!(keep.lock().unwrap().iter().all(|a| a.is_some()));

    let region = PixelBounds {
        x0: 7,
        x1: 29,
        y0: 3,
        y1: 20,
    };
    let options = RenderOptions {
        region: Some(region),
        threads: 1,
        ..RenderOptions::default()
    };
    let part = render(&s.world, &s.settings, &options).unwrap().0;
    for y in region.y0..region.y1 {
        for x in region.x0..region.x1 {
            let at = (x - region.x0, y - region.y0);
            assert_eq!(part.alpha_at(at.0, at.1), whole.alpha_at(x, y));
            assert_eq!(part.get(at.0, at.1), whole.get(x, y));
        }
    }
}

#[test]
fn png_holds_straight_alpha_and_exr_premultiplied() {
    let s = scene("rgss", "");
    let f = render_film(&s, &s.settings);
    let dir = support::TempDir::new("alpha");
    let png = dir.path().join("a.png");
    write_image(&f, &png, None).unwrap();
    let img = image::open(&png).unwrap();
    let rgba = img.as_rgba8().expect("an RGBA8 PNG");
    let alpha = f.alpha.as_ref().unwrap();
    for (i, p) in rgba.pixels().enumerate() {
        let a = alpha[i];
        assert_eq!(p[3], (a * 255.0).round() as u8, "pixel {i}");
        let straight = if a > 0.0 { f.pixels[i] / a } else { Rgb::ZERO };
        let want = straight.to_array().map(|c| penumbra::encode_8bit(c, None));
        assert_eq!([p[0], p[1], p[2]], want, "pixel {i}");
    }

    let exr = dir.path().join("a.exr");
    write_image(&f, &exr, None).unwrap();
    let img = image::open(&exr).unwrap().into_rgba32f();
    for (i, p) in img.pixels().enumerate() {
        assert_eq!(p.0, f.pixels[i].extend(alpha[i]).to_array(), "pixel {i}");
    }

    for name in ["a.jpg", "a.pfm"] {
        let path = dir.path().join(name);
        let e = write_image(&f, &path, None).unwrap_err();
        assert!(matches!(e, ImageError::NoAlpha { .. }), "{e}");
        assert!(e.to_string().contains("no alpha channel"), "{e}");
        assert!(!Path::new(&path).exists());
    }
}
