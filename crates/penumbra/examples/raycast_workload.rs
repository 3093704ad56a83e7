//! One ray-casting workload (on one thread unless a thread count follows N; the best of
//! REPEAT runs when a count follows THREADS), for instruction counts under callgrind and
//! interleaved A/B runs of two builds (`benches/raycast.rs` and `tools/bench_raycast.py` are
//! the benchmarks).
//!
//! ```text
//! cargo build --release -p penumbra --example raycast_workload
//! valgrind --tool=callgrind target/release/examples/raycast_workload MESH.obj coherent 65536
//! ```
//!
//! The workloads are those of `tools/bench_raycast.py`: `coherent` (`cast_rays_rows` on a
//! square pinhole image of `n` rays framing the mesh; `rows` is the same rays through plain
//! `cast_rays`, as a flat batch; `miss`, not in the benchmark, is that image with every ray
//! turned around, so that none meets the mesh's box: what a query costs besides its walk),
//! `incoherent` (`cast_rays` between random points around and inside the mesh's box), `count`
//! (`count_intersections` on those rays), `occlusion` (`test_occlusions` on segments between
//! random points of the box, `t` in `[0, 1]`) and `none` (build only, to subtract). Prints a
//! checksum of the answers on stdout and the query's throughput on stderr.

use std::path::Path;

use glam::Vec3;
use penumbra::{create_rays_pinhole_fov, QueryOptions, RaycastingScene, Rng};

/// Vertices and triangles of an OBJ file (polygons fanned), enough for benchmark meshes.
fn read_obj(path: &Path) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let text = std::fs::read_to_string(path).expect("the mesh is readable");
    let (mut vertices, mut triangles) = (Vec::new(), Vec::new());
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let v: Vec<f32> = words.take(3).map(|w| w.parse().unwrap()).collect();
                vertices.push([v[0], v[1], v[2]]);
            }
            Some("f") => {
                let n = vertices.len() as i64;
                let idx: Vec<u32> = words
                    .map(|w| {
                        let i: i64 = w.split('/').next().unwrap().parse().unwrap();
                        (if i > 0 { i - 1 } else { n + i }) as u32
                    })
                    .collect();
                for k in 1..idx.len() - 1 {
                    triangles.push([idx[0], idx[k], idx[k + 1]]);
                }
            }
            _ => {}
        }
    }
    (vertices, triangles)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (mesh, workload, n, threads, repeat) = match &args[..] {
        [_, mesh, workload, n] => (mesh, workload, n, "1", "1"),
        [_, mesh, workload, n, threads] => (mesh, workload, n, threads.as_str(), "1"),
        [_, mesh, workload, n, threads, repeat] => {
            (mesh, workload, n, threads.as_str(), repeat.as_str())
        }
        _ => {
            eprintln!(
                "usage: raycast_workload MESH.obj coherent|rows|miss|incoherent|count|list|occlusion|closest|occupancy|none N [THREADS [REPEAT]]"
            );
            std::process::exit(2);
        }
    };
    let n: usize = n.parse().expect("N is a number");
    let threads: usize = threads.parse().expect("THREADS is a number");
    let repeat: usize = repeat.parse().expect("REPEAT is a number");
    let (vertices, triangles) = read_obj(Path::new(mesh));
    let mut scene = RaycastingScene::new();
    scene.add_triangles(&vertices, &triangles).unwrap();
    scene.commit(threads).unwrap();
    let options = QueryOptions {
        threads,
        cancel: None,
    };

    let (lo, hi) = vertices.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &v| (lo.min(v.into()), hi.max(v.into())),
    );
    let (center, size) = (0.5 * (lo + hi), (hi - lo).length());
    let mut rng = Rng::new(1, &[]);
    let mut random_in =
        |a: Vec3, b: Vec3| a + (b - a) * Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
    let mut rays: Vec<[f32; 6]> = match workload.as_str() {
        "coherent" | "rows" | "miss" => {
            let side = (n as f64).sqrt() as u32;
            let eye = center + size * Vec3::new(0.3, 0.4, 1.1);
            create_rays_pinhole_fov(
                50.0,
                center.as_dvec3().into(),
                eye.as_dvec3().into(),
                [0.0, 1.0, 0.0],
                side,
                side,
            )
            .unwrap()
        }
        "incoherent" | "count" | "list" => (0..n)
            .map(|_| {
                let a = random_in(center - 0.75 * size, center + 0.75 * size);
                let b = random_in(lo, hi);
                let d = b - a;
                [a.x, a.y, a.z, d.x, d.y, d.z]
            })
            .collect(),
        "occlusion" => (0..n)
            .map(|_| {
                let (a, b) = (random_in(lo, hi), random_in(lo, hi));
                let d = b - a;
                [a.x, a.y, a.z, d.x, d.y, d.z]
            })
            .collect(),
        // Query points: in the box grown by 10 % (closest), in the box (occupancy), as rays
        // with a zero direction.
        "closest" | "occupancy" => (0..n)
            .map(|_| {
                let grow = if workload == "closest" { 0.05 } else { 0.0 };
                let a = random_in(lo - grow * (hi - lo), hi + grow * (hi - lo));
                [a.x, a.y, a.z, 0.0, 0.0, 0.0]
            })
            .collect(),
        _ => Vec::new(),
    };
    if workload == "miss" {
        for r in &mut rays {
            r[3..].iter_mut().for_each(|d| *d = -*d);
        }
    }
    let points: Vec<[f32; 3]> = rays.iter().map(|r| [r[0], r[1], r[2]]).collect();
    let query = || -> u64 {
        match workload.as_str() {
            "coherent" | "rows" | "incoherent" | "miss" => {
                let hits = match workload.as_str() {
                    "coherent" | "miss" => {
                        let side = (rays.len() as f64).sqrt() as usize;
                        scene.cast_rays_rows(&rays, side, &options).unwrap()
                    }
                    _ => scene.cast_rays(&rays, &options).unwrap(),
                };
                hits.primitive_ids
                    .iter()
                    .zip(&hits.t_hit)
                    .map(|(&p, &t)| p as u64 ^ t.to_bits() as u64)
                    .fold(0, |a, x| a.wrapping_mul(31).wrapping_add(x))
            }
            "count" => scene
                .count_intersections(&rays, &options)
                .unwrap()
                .iter()
                .map(|&c| c as u64)
                .sum(),
            "occlusion" => scene
                .test_occlusions(&rays, 0.0, 1.0, &options)
                .unwrap()
                .iter()
                .map(|&o| o as u64)
                .sum(),
            "list" => {
                let list = scene.list_intersections(&rays, &options).unwrap();
                list.t_hit
                    .iter()
                    .zip(&list.primitive_ids)
                    .fold(0, |a: u64, (t, &p)| {
                        a.wrapping_mul(31)
                            .wrapping_add(t.to_bits() as u64 ^ p as u64)
                    })
            }
            "closest" => scene
                .compute_closest_points(&points, &options)
                .unwrap()
                .points
                .iter()
                .flatten()
                .fold(0, |a: u64, x| {
                    a.wrapping_mul(31).wrapping_add(x.to_bits() as u64)
                }),
            "occupancy" => scene
                .compute_occupancy(&points, 1, &options)
                .unwrap()
                .iter()
                .map(|&o| o as u64)
                .sum(),
            "none" => 0,
            other => {
                eprintln!("unknown workload {other:?}");
                std::process::exit(2);
            }
        }
    };
    // The best of `repeat` runs: from the second on, the allocator reuses the results' memory
    // (as in a loop of calls from Python) instead of faulting in fresh pages.
    let (mut seconds, mut checksum) = (f64::INFINITY, 0);
    for _ in 0..repeat.max(1) {
        let start = std::time::Instant::now();
        checksum = query();
        seconds = seconds.min(start.elapsed().as_secs_f64());
    }
    println!("{workload} {} rays: checksum {checksum}", rays.len());
    eprintln!("{:.2} Mrays/s", rays.len() as f64 / seconds / 1e6);
}
