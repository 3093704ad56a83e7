//! Benchmarks of moving placements after the build: a world of N placements of
//! `assets/meshes/spot_triangulated.obj` (5,856 triangles) moved all at once
//! (`World::set_transforms`: the top level built again, the mesh trees untouched), and a
//! ray-casting scene whose 1,000 placements are moved one call at a time
//! (`RaycastingScene::set_transform`) before a one-ray query, which builds the top level
//! again, against the same query alone.
//!
//! ```text
//! cargo bench -p penumbra --bench moves
//! ```

use std::hint::black_box;
use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use glam::Vec3;
use penumbra::{QueryOptions, RaycastingScene, SceneFile, SceneFormat, Transform, World};

/// Placement `k` of a 64-wide grid, turned by `turn` degrees.
fn placement(k: usize, turn: f32) -> Transform {
    let (x, z) = ((k % 64) as f32 * 3.0, (k / 64) as f32 * 3.0);
    Transform::from_srt(
        Vec3::ONE,
        Vec3::new(0.0, 7.0 * k as f32 + turn, 0.0),
        Vec3::new(x, 0.0, z),
    )
}

/// A world of `n` placements of spot (more triangles than a world copies: instanced).
fn world(n: usize) -> World {
    let meshes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/meshes");
    let rows: Vec<String> = (0..n)
        .map(|k| {
            let m = placement(k, 0.0)
                .world_from_object
                .transpose()
                .to_cols_array_2d();
            format!("{{ matrix = {m:?} }}")
        })
        .collect();
    let text = format!(
        "[film]\nwidth = 8\nheight = 8\n[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\
         fov = 40\n[[objects]]\ntype = \"instances\"\nfile = \"spot_triangulated.obj\"\n\
         transforms = [{}]\n",
        rows.join(", ")
    );
    let file = SceneFile::from_str(&text, SceneFormat::Toml, "moves.toml", &meshes).unwrap();
    let world = Arc::try_unwrap(file.build(2).unwrap().world).unwrap();
    assert_eq!(world.stats().instances, n);
    world
}

fn bench_world_moves(c: &mut Criterion) {
    let mut group = c.benchmark_group("world_set_transforms");
    group
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    for n in [1000, 4096] {
        let mut world = world(n);
        let moves =
            [0.0, 45.0].map(|turn| (0..n).map(|k| (k, placement(k, turn))).collect::<Vec<_>>());
        let mut flip = 0;
        group.bench_function(format!("{n}_spots"), |b| {
            b.iter(|| {
                flip ^= 1;
                world.set_transforms(black_box(&moves[flip])).unwrap();
            })
        });
    }
    group.finish();
}

fn bench_raycast_moves(c: &mut Criterion) {
    // Enough placements that the world instances spot rather than copying it.
    let spot = world(200);
    let mesh = &spot.meshes()[0];
    let vertices: Vec<[f32; 3]> = mesh.positions.iter().map(|p| p.to_array()).collect();
    let mut scene = RaycastingScene::new();
    scene.add_triangles(&vertices, &mesh.indices).unwrap();
    let rows = |k: usize, turn: f32| {
        placement(k, turn)
            .world_from_object
            .transpose()
            .to_cols_array_2d()
    };
    for k in 0..1000 {
        scene.add_instance(0, &rows(k, 0.0)).unwrap();
    }
    let options = QueryOptions {
        threads: 2,
        cancel: None,
    };
    let ray = [[30.0, 20.0, 30.0, 0.1, -1.0, 0.05]];
    scene.cast_rays(&ray, &options).unwrap();
    let mut group = c.benchmark_group("raycast_1000_spots");
    group
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    group.bench_function("query_alone", |b| {
        b.iter(|| scene.cast_rays(black_box(&ray), &options).unwrap())
    });
    let mut turn = 0.0;
    group.bench_function("all_moved_then_query", |b| {
        b.iter(|| {
            turn = 45.0 - turn;
            for k in 0..1000 {
                scene.set_transform(k as u32 + 1, &rows(k, turn)).unwrap();
            }
            scene.cast_rays(black_box(&ray), &options).unwrap()
        })
    });
    group.finish();
}

criterion_group!(moves, bench_world_moves, bench_raycast_moves);
criterion_main!(moves);
