//! AOVs through the public API: the colour of a render with AOVs is the colour without them,
//! bit for bit; AOVs do not depend on threads or regions; a quad at a known distance gives
//! closed-form depth, normal, position, albedo and ids.

use glam::Vec3;
use penumbra::{
    render, render_with_aovs, PixelBounds, RenderOptions, Scene, SceneFile, SceneFormat, NO_ID,
};

const SCENE: &str = r#"
[film]
width = 40
height = 30
[camera]
position = [0, 0, 4]
look_at = [0, 0, 0]
fov = 40
[render]
sampler = "jittered"
samples = 4
light_samples = 2
[materials.red]
diffuse = [0.6, 0.2, 0.1]
[[lights]]
type = "area"
center = [0, 3, 3]
u = [1, 0, 0]
v = [0, 0, 1]
[[objects]]
type = "quad"
corner = [-1, -1, 0]
u = [2, 0, 0]
v = [0, 2, 0]
material = "red"
[[objects]]
type = "sphere"
center = [1.2, 0.8, 0.5]
radius = 0.4
"#;

fn scene() -> Scene {
    SceneFile::from_str(SCENE, SceneFormat::Toml, "aovs.toml", ".")
        .and_then(|f| f.build(1))
        .expect("scene")
}

#[test]
fn the_colour_is_unchanged_and_threads_and_regions_agree() {
    let s = scene();
    let plain = render(&s.world, &s.settings, &RenderOptions::default())
        .unwrap()
        .0;
    let one = RenderOptions {
        threads: 1,
        ..RenderOptions::default()
    };
    let (film, aovs, _) = render_with_aovs(&s.world, &s.settings, &one).unwrap();
    assert_eq!(film, plain);
    let (_, aovs3, _) = render_with_aovs(
        &s.world,
        &s.settings,
        &RenderOptions {
            threads: 3,
            ..RenderOptions::default()
        },
    )
    .unwrap();
    assert_eq!(aovs, aovs3);
    let region = PixelBounds {
        x0: 7,
        x1: 29,
        y0: 3,
        y1: 21,
    };
    let (part, part_aovs, _) = render_with_aovs(
        &s.world,
        &s.settings,
        &RenderOptions {
            region: Some(region),
            ..RenderOptions::default()
        },
    )
    .unwrap();
    for y in 0..part.height {
        for x in 0..part.width {
            assert_eq!(part.get(x, y), film.get(x + 7, y + 3));
            assert_eq!(part_aovs.get(x, y), aovs.get(x + 7, y + 3));
        }
    }
}

#[test]
fn a_quad_facing_the_camera_gives_closed_form_aovs() {
    let s = scene();
    let (_, aovs, _) = render_with_aovs(&s.world, &s.settings, &RenderOptions::default()).unwrap();
    let (w, h) = (aovs.width as f32, aovs.height as f32);
    let half = (20f32).to_radians().tan();
    let (mut quad, mut miss) = (0, 0);
    for y in 0..aovs.height {
        for x in 0..aovs.width {
            let px = aovs.get(x, y);
            // The pixel center's ray, from SPEC §3.
            let sx = (2.0 * (x as f32 + 0.5) / w - 1.0) * (w / h) * half;
            let sy = (1.0 - 2.0 * (y as f32 + 0.5) / h) * half;
            let dir = Vec3::new(sx, sy, -1.0).normalize();
            let t = 4.0 / -dir.z;
            let p = Vec3::new(0.0, 0.0, 4.0) + t * dir;
            let on_quad = p.x.abs() < 0.99 && p.y.abs() < 0.99;
            let near_sphere = (p - Vec3::new(1.2, 0.8, 0.5)).length() < 0.9;
            if on_quad && !near_sphere {
                quad += 1;
                assert!(
                    (px.depth - t).abs() < 1e-5 * t,
                    "{x},{y}: {} vs {t}",
                    px.depth
                );
                assert!((px.position - p).length() < 1e-5, "{x},{y}");
                assert_eq!(px.normal, Vec3::Z);
                assert_eq!(px.object_id, 0);
                assert!(px.primitive_id < 2);
                // Every sample of an inner pixel hits the quad.
                assert!((px.albedo - Vec3::new(0.6, 0.2, 0.1)).length() < 1e-6);
            } else if (p.x.abs() > 1.05 || p.y.abs() > 1.05)
                && (p - Vec3::new(1.2, 0.8, 0.5)).length() > 1.5
            {
                miss += 1;
                assert_eq!(px.depth, f32::INFINITY);
                assert_eq!((px.object_id, px.primitive_id), (NO_ID, NO_ID));
                assert_eq!(px.normal, Vec3::ZERO);
            }
        }
    }
    assert!(quad > 300 && miss > 100, "{quad} {miss}");
}
