//! Kernel benchmarks on the seed's room (`scenes/cornell.toml`): the shadow rays of one
//! shading point (the 25 segments to its 5×5 light samples) traced as packets on every SIMD
//! path this machine has, against the same segments traced one ray at a time; the shadow rays
//! of 64 neighbouring points (a patch of 8×8 pixels' worth) as fans and as bundles (one light
//! sample, 16 or 8 points per packet: `Bvh::occlude_segments`); and camera
//! rays through the closest-hit traversal, in packets of 16 sharing the camera's origin on
//! every path, and one at a time.
//!
//! ```text
//! cargo bench -p penumbra --bench kernels
//! ```

use std::hint::black_box;
use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};
use glam::Vec3;
use penumbra::bench::{Pairs, Segments};
use penumbra::{supported_paths, FilmCamera, Light, Ray, Rng, SceneFile, World};

/// The seed's room, built once.
fn world() -> std::sync::Arc<World> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell.toml");
    SceneFile::load(path).unwrap().build(1).unwrap().world
}

/// 64 points just above the floor (under the cubes, beside them, in the open) and the 25
/// sample points of the room's light.
fn shadow_setup(world: &World) -> (Vec<Vec3>, Vec<Vec3>) {
    let origins = (0..64)
        .map(|i| {
            let (x, z) = ((i % 8) as f32 / 7.0, (i / 8) as f32 / 7.0);
            Vec3::new(-2.8 + 5.6 * x, 1e-3, -0.2 - 5.6 * z)
        })
        .collect();
    let Light::Area(light) = &world.lights()[0] else {
        panic!("the room has an area light")
    };
    let mut ends = Vec::new();
    light.sample_points(&mut Rng::new(0, &[]), &mut ends);
    (origins, ends)
}

fn bench_shadow(c: &mut Criterion) {
    let world = world();
    let bvh = world.accel();
    let (origins, ends) = shadow_setup(&world);
    let t_max = 1.0 - 1e-4;
    let mut group = c.benchmark_group("shadow_64_points_x_25_segments");
    for path in supported_paths() {
        group.bench_function(format!("packets_{}", path.name()), |b| {
            let mut blocked = vec![false; ends.len()];
            b.iter(|| {
                let mut occluded = 0;
                for &o in &origins {
                    blocked.fill(false);
                    bvh.occlude_from_on(path, o, &ends, t_max, &mut blocked);
                    occluded += blocked.iter().filter(|&&b| b).count();
                }
                black_box(occluded)
            })
        });
    }
    group.bench_function("single_rays", |b| {
        b.iter(|| {
            let mut occluded = 0;
            for &o in &origins {
                for &e in &ends {
                    occluded += bvh.occluded(&Ray::new(o, e - o), 0.0, t_max) as usize;
                }
            }
            black_box(occluded)
        })
    });
    group.finish();
}

/// The segments from 64 points of a small patch (8×8, a millimetre apart, under the middle of
/// the light) to the 25 light samples, traced as fans (one packet kind per point) and as
/// bundles (one light sample, neighbouring points per packet), as segments and as pairs.
fn bench_bundles(c: &mut Criterion) {
    let world = world();
    let bvh = world.accel();
    let (_, ends) = shadow_setup(&world);
    let origins: Vec<Vec3> = (0..64)
        .map(|i| {
            Vec3::new(
                0.3 + 1e-3 * (i % 8) as f32,
                1e-3,
                -3.0 - 1e-3 * (i / 8) as f32,
            )
        })
        .collect();
    let t_max = 1.0 - 1e-4;
    // Sample-major: the 64 segments toward sample j are consecutive.
    let axis = |f: &dyn Fn(usize, usize) -> f32| -> Vec<f32> {
        (0..ends.len() * 64).map(|k| f(k % 64, k / 64)).collect()
    };
    let from: [Vec<f32>; 3] = [0, 1, 2].map(|a| axis(&|i, _| origins[i][a]));
    let to: [Vec<f32>; 3] = [0, 1, 2].map(|a| axis(&|_, j| ends[j][a]));
    let mut group = c.benchmark_group("shadow_patch_64_points_x_25_segments");
    for path in supported_paths() {
        group.bench_function(format!("fans_{}", path.name()), |b| {
            let mut blocked = vec![false; ends.len()];
            b.iter(|| {
                let mut occluded = 0;
                for &o in &origins {
                    blocked.fill(false);
                    bvh.occlude_from_on(path, o, &ends, t_max, &mut blocked);
                    occluded += blocked.iter().filter(|&&b| b).count();
                }
                black_box(occluded)
            })
        });
        group.bench_function(format!("bundles_{}", path.name()), |b| {
            let mut blocked = vec![false; from[0].len()];
            let segments = Segments {
                origin: [0, 1, 2].map(|a| &from[a][..]),
                end: [0, 1, 2].map(|a| &to[a][..]),
            };
            b.iter(|| {
                blocked.fill(false);
                bvh.occlude_segments_on(path, segments, t_max, &mut blocked);
                black_box(blocked.iter().filter(|&&b| b).count())
            })
        });
        // The same segments as pairs: the 64 points and the 25 samples, each given once.
        let points: [Vec<f32>; 3] = [0, 1, 2].map(|a| origins.iter().map(|o| o[a]).collect());
        let samples: [Vec<f32>; 3] = [0, 1, 2].map(|a| ends.iter().map(|e| e[a]).collect());
        group.bench_function(format!("pairs_{}", path.name()), |b| {
            let mut blocked = vec![false; from[0].len()];
            let pairs = Pairs {
                origins: points.each_ref().map(|axis| &axis[..]),
                ends: samples.each_ref().map(|axis| &axis[..]),
            };
            b.iter(|| {
                blocked.fill(false);
                bvh.occlude_pairs_on(path, pairs, t_max, &mut blocked);
                black_box(blocked.iter().filter(|&&b| b).count())
            })
        });
    }
    group.finish();
}

fn bench_camera(c: &mut Criterion) {
    let world = world();
    let camera = FilmCamera::new(&world.cameras()[0].1, 64, 64);
    // Rows of pixels, as the renderer batches them: 16 rays of neighbouring pixels at a time.
    let rays: Vec<Ray> = (0..64 * 64)
        .map(|i| {
            camera
                .ray((i % 64) as f32 + 0.5, (i / 64) as f32 + 0.5)
                .expect("a pinhole")
        })
        .collect();
    let dirs: Vec<Vec3> = rays.iter().map(|r| r.direction).collect();
    let mut group = c.benchmark_group("closest_hit_4096_camera_rays");
    for path in supported_paths() {
        group.bench_function(format!("packets_of_16_{}", path.name()), |b| {
            let mut hits = vec![None; 16];
            b.iter(|| {
                let mut count = 0;
                for batch in dirs.chunks(16) {
                    let hits = &mut hits[..batch.len()];
                    world.accel().intersect_from_on(
                        path,
                        camera.eye(),
                        batch,
                        1e-4,
                        f32::INFINITY,
                        hits,
                    );
                    count += hits.iter().filter(|h| h.is_some()).count();
                }
                black_box(count)
            })
        });
    }
    group.bench_function("single_rays", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|r| world.intersect(r, 1e-4, f32::INFINITY).is_some())
                .count()
        })
    });
    group.finish();
}

criterion_group!(benches, bench_shadow, bench_bundles, bench_camera);
criterion_main!(benches);
