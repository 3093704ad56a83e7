//! Benchmarks: BVH against brute force on a scene of over 10,000 triangles, BVH build, and a
//! render of the seed's scene.
//!
//! ```text
//! cargo bench -p penumbra --bench render
//! ```

use std::hint::black_box;
use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};
use glam::Vec3;
use penumbra::bench::intersect_brute_force;
use penumbra::{render, RenderOptions, SceneFile};
use penumbra::{shapes, Bvh, Geometry, Ray, Transform};

/// Two tessellated spheres and a floor: 18,050 triangles.
fn spheres() -> Geometry {
    let mut g = Geometry::default();
    let ball = shapes::sphere(1.0);
    for x in [-1.2f32, 1.2] {
        let t = Transform::from_srt(Vec3::ONE, Vec3::ZERO, Vec3::new(x, 1.0, 0.0));
        g.append(&ball, &t, &[0], 0);
    }
    let floor = shapes::quad(Vec3::new(-5.0, 0.0, 5.0), Vec3::X * 10.0, Vec3::Z * -10.0);
    g.append(&floor, &Transform::IDENTITY, &[0], 1);
    g
}

/// A 32×32 fan of rays from a camera in front of the spheres.
fn rays() -> Vec<Ray> {
    let eye = Vec3::new(0.0, 1.5, 6.0);
    (0..32 * 32)
        .map(|i| {
            let (x, y) = ((i % 32) as f32 / 31.0 - 0.5, (i / 32) as f32 / 31.0 - 0.5);
            Ray::new(eye, Vec3::new(x * 1.6, y * 1.2 - 0.2, -1.0).normalize())
        })
        .collect()
}

fn bench_intersect(c: &mut Criterion) {
    let g = spheres();
    let bvh = Bvh::build(&g);
    let rays = rays();
    let mut group = c.benchmark_group(format!("closest_hit_1024_rays_{}_tris", g.len()));
    group.bench_function("bvh", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|r| bvh.intersect(r, 1e-4, f32::INFINITY).is_some())
                .count()
        })
    });
    group.sample_size(10);
    group.bench_function("brute_force", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|r| intersect_brute_force(&g, r, 1e-4, f32::INFINITY).is_some())
                .count()
        })
    });
    group.finish();
    c.bench_function("bvh_build_18k_tris", |b| {
        b.iter(|| Bvh::build(black_box(&g)))
    });
}

fn bench_render(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell.toml");
    let file = SceneFile::load(path).expect("scenes/cornell.toml");
    let scene = file.build(0).unwrap();
    let mut settings = scene.settings.clone();
    (settings.width, settings.height) = (128, 128);
    let mut group = c.benchmark_group("render_cornell_128x128_rgss4_light25");
    group.sample_size(10);
    for threads in [1, 2] {
        let options = RenderOptions {
            threads,
            ..RenderOptions::default()
        };
        group.bench_function(format!("{threads}_threads"), |b| {
            b.iter(|| render(black_box(&scene.world), &settings, &options).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, bench_intersect, bench_render);
criterion_main!(benches);
