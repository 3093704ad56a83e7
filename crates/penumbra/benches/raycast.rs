//! Throughput of the ray-casting queries ([`RaycastingScene`]) on one mesh with two worker
//! threads, the workloads of Open3D's `RaycastingScene` comparison: (a) 1024² coherent
//! pinhole rays framing the mesh (`cast_rays`), (b) 1 M incoherent rays from random points of
//! twice the mesh's box in random directions (`cast_rays`, `count_intersections`), (c) 1 M
//! occlusion segments between random points of the box (`test_occlusions`, `tfar = 1`).
//! Criterion reports elements per second = rays per second.
//!
//! The mesh is `assets/meshes/nefertiti_70k.obj` unless `PENUMBRA_BENCH_MESH` names another
//! OBJ file (the Stanford bunny is not in the repository):
//!
//! ```text
//! cargo bench -p penumbra --bench raycast
//! PENUMBRA_BENCH_MESH=/path/to/bunny.obj cargo bench -p penumbra --bench raycast
//! ```

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec3;
use penumbra::{
    create_rays_pinhole_fov, QueryOptions, RaycastingScene, Rng, SceneFile, SceneFormat,
};

/// Rays of the incoherent and occlusion workloads.
const RAYS: usize = 1 << 20;

/// The mesh to trace and its name.
fn mesh_path() -> PathBuf {
    std::env::var_os("PENUMBRA_BENCH_MESH")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/meshes/nefertiti_70k.obj")
        })
}

/// The mesh as a one-geometry scene, through a scene file so that the library's OBJ reader
/// is used.
fn scene() -> RaycastingScene {
    let path = mesh_path()
        .canonicalize()
        .expect("the benchmark mesh exists");
    let text = format!(
        "[film]\nwidth = 1\nheight = 1\n[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\n\
         fov = 40\n[[objects]]\ntype = \"mesh\"\nfile = {:?}\n",
        path.to_str().unwrap()
    );
    let file = SceneFile::from_str(&text, SceneFormat::Toml, "bench.toml", ".").unwrap();
    let scene = RaycastingScene::from_world(&file.build(2).unwrap().world).unwrap();
    scene.commit(2).unwrap();
    scene
}

/// Bounds of the scene's closest points to far-away probes: the box of the mesh.
fn bounds(scene: &RaycastingScene) -> (Vec3, Vec3) {
    let probes: Vec<[f32; 3]> = (0..6)
        .map(|k| {
            let mut p = [0.0; 3];
            p[k % 3] = if k < 3 { 1e4 } else { -1e4 };
            p
        })
        .collect();
    let near = scene
        .compute_closest_points(&probes, &QueryOptions::default())
        .unwrap()
        .points;
    let lo = Vec3::new(near[3][0], near[4][1], near[5][2]);
    let hi = Vec3::new(near[0][0], near[1][1], near[2][2]);
    (lo, hi)
}

fn random_point(rng: &mut Rng, lo: Vec3, hi: Vec3) -> Vec3 {
    lo + (hi - lo) * Vec3::new(rng.uniform(), rng.uniform(), rng.uniform())
}

fn bench_raycast(c: &mut Criterion) {
    let scene = scene();
    let (lo, hi) = bounds(&scene);
    let (center, size) = (0.5 * (lo + hi), hi - lo);
    let options = QueryOptions {
        threads: 2,
        cancel: None,
    };
    let name = mesh_path()
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut group = c.benchmark_group(format!("raycast_{name}_2_threads"));
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));

    // (a) Coherent: a 1024² camera framing the mesh from the front.
    let eye = center + Vec3::new(0.0, 0.0, 1.6 * size.max_element());
    let coherent = create_rays_pinhole_fov(
        45.0,
        center.as_dvec3().into(),
        eye.as_dvec3().into(),
        [0.0, 1.0, 0.0],
        1024,
        1024,
    )
    .unwrap();
    group.throughput(Throughput::Elements(coherent.len() as u64));
    group.bench_function("cast_rays_coherent_1024x1024", |b| {
        b.iter(|| black_box(scene.cast_rays(&coherent, &options).unwrap()))
    });

    // (b) Incoherent: random origins in twice the box, random directions.
    let mut rng = Rng::new(1, &[]);
    let incoherent: Vec<[f32; 6]> = (0..RAYS)
        .map(|_| {
            let o = random_point(&mut rng, center - size, center + size);
            let d = random_point(&mut rng, -Vec3::ONE, Vec3::ONE);
            [o.x, o.y, o.z, d.x, d.y, d.z]
        })
        .collect();
    group.throughput(Throughput::Elements(RAYS as u64));
    group.bench_function("cast_rays_incoherent_1M", |b| {
        b.iter(|| black_box(scene.cast_rays(&incoherent, &options).unwrap()))
    });
    group.bench_function("count_intersections_incoherent_1M", |b| {
        b.iter(|| black_box(scene.count_intersections(&incoherent, &options).unwrap()))
    });

    // (c) Occlusion: segments between two random points of the box.
    let segments: Vec<[f32; 6]> = (0..RAYS)
        .map(|_| {
            let (a, b) = (
                random_point(&mut rng, lo, hi),
                random_point(&mut rng, lo, hi),
            );
            let d = b - a;
            [a.x, a.y, a.z, d.x, d.y, d.z]
        })
        .collect();
    group.bench_function("test_occlusions_segments_1M", |b| {
        b.iter(|| {
            black_box(
                scene
                    .test_occlusions(&segments, 0.0, 1.0, &options)
                    .unwrap(),
            )
        })
    });
    group.finish();
}

criterion_group!(benches, bench_raycast);
criterion_main!(benches);
