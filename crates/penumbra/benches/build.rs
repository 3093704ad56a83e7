//! Benchmarks of loading: the BVH build over a 200k-triangle soup, serial and on a pool of two
//! threads, and the reading of `assets/meshes/nefertiti_70k.obj` (parsing, merging and adding
//! it to a world, without the BVH) on one and two threads.
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

criterion_group!(benches, bench_bvh_build, bench_obj_parse);
criterion_main!(benches);
