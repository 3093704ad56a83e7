//! Benchmarks of loading: the BVH build over a 200k-triangle soup, serial and on a pool of two
//! threads, and the reading of `assets/meshes/nefertiti_70k.obj` (parsing, merging and adding
//! it to a world, without the BVH) on one and two threads, and an environment map's sampling
//! distribution at 4096 × 2048.
//!
//! ```text
//! cargo bench -p penumbra --bench build
//! ```

use std::hint::black_box;
use std::path::Path;
use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion};
use glam::Vec3;
use penumbra::{Bvh, Geometry, Mesh, SceneFile, SceneFormat, Transform};

/// 200,000 small triangles scattered uniformly in a box, from a fixed seed.
fn soup() -> Geometry {
    let mut state = 1u64;
    let mut rnd = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 40) as f32 / (1u64 << 24) as f32 * 20.0 - 10.0
    };
    let mut mesh = Mesh::default();
    for i in 0..200_000u32 {
        let c = Vec3::new(rnd(), rnd(), rnd());
        for _ in 0..3 {
            mesh.positions
                .push(c + Vec3::new(rnd(), rnd(), rnd()) * 0.02);
        }
        mesh.indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    let mut g = Geometry::default();
    g.append(&mesh, &Transform::IDENTITY, &[0], 0);
    g
}

fn bench_bvh_build(c: &mut Criterion) {
    let g = soup();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let mut group = c.benchmark_group(format!("bvh_build_{}_tris", g.len()));
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    group.bench_function("serial", |b| b.iter(|| Bvh::build(black_box(&g))));
    group.bench_function("2_threads", |b| {
        b.iter(|| Bvh::build_parallel(black_box(&g), &pool))
    });
    group.finish();
}

fn bench_obj_parse(c: &mut Criterion) {
    let meshes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/meshes");
    let text =
        "[film]\nwidth = 8\nheight = 8\n[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov = 40\n\
                [[objects]]\ntype = \"mesh\"\nfile = \"nefertiti_70k.obj\"\n";
    let file = SceneFile::from_str(text, SceneFormat::Toml, "bench.toml", &meshes).unwrap();
    let mut group = c.benchmark_group("obj_parse_nefertiti_70k");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    for threads in [1, 2] {
        // The scene's own load time: the OBJ read into a world, without the BVH build.
        group.bench_function(format!("{threads}_threads"), |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    let start = Instant::now();
                    let scene = file.build(threads).unwrap();
                    let spent = start.elapsed();
                    total += scene.load_time.min(spent);
                    black_box(scene);
                }
                total
            })
        });
    }
    group.finish();
}

/// An environment map's sampling distribution at 4096 × 2048 (a "4k" HDRI): a smooth sky
/// with a small bright sun, so that the sums span many orders of magnitude.
fn bench_environment_map(c: &mut Criterion) {
    let (w, h) = (4096u32, 2048u32);
    let texels: Vec<glam::Vec3> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let sun = if x.abs_diff(3000) < 8 && y.abs_diff(700) < 8 {
                5e4
            } else {
                0.0
            };
            glam::Vec3::splat(0.2 + y as f32 / h as f32 + sun)
        })
        .collect();
    let mut group = c.benchmark_group("environment");
    group.sample_size(10);
    group.bench_function("distribution_4096x2048", |b| {
        b.iter_batched(
            || texels.clone(),
            |texels| penumbra::EnvironmentMap::new(w, h, texels).unwrap(),
            criterion::BatchSize::LargeInput,
        )
    });
    group.finish();
}

criterion_group!(
    benches,
    bench_bvh_build,
    bench_obj_parse,
    bench_environment_map
);
criterion_main!(benches);
