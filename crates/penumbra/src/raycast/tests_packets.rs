//! The packets against the single-ray queries, bit for bit, on every SIMD path this machine
//! has: closest hits of pinhole images of closed meshes (with exact ties on their shared edges)
//! and of rays from one eye aimed exactly at every shared edge and vertex; counts of parallel
//! rays through every shared edge and vertex; occupancy in any order; long lists.

use glam::{Mat3, Vec3};

use super::*;
use crate::accel::prim::watertight::PreparedRay;
use crate::accel::wide::packets::{CastPackets, ClosestHit};
use crate::accel::wide::rays::lane_rays;
use crate::simd::{dispatch, supported_paths, SimdPath};

use crate::accel::test_meshes::{icosphere, subdivided_cube, targets, MeshData};

/// A hit as comparable bits: t, b1, b2, ids and slot (the slot gives the normal).
fn bits(hit: &ClosestHit) -> Option<[u32; 6]> {
    hit.map(|h| {
        let c = h.crossing;
        [
            c.t.to_bits(),
            c.b1.to_bits(),
            c.b2.to_bits(),
            h.geometry,
            h.primitive,
            h.slot,
        ]
    })
}

/// Checks the packets against single rays on `rays`; returns the number of hits.
fn check(mesh: &MeshData, rays: &[[f32; 6]]) -> usize {
    let mut scene = RaycastingScene::new();
    scene.add_triangles(&mesh.0, &mesh.1).unwrap();
    let (accel, _) = scene.prepare(&QueryOptions::default()).unwrap();
    let accel = &*accel;
    // One ray per kernel run: never a packet, the single-ray query.
    let want: Vec<ClosestHit> = rays
        .iter()
        .map(|r| {
            let mut hit = [None];
            let rays = std::slice::from_ref(r);
            dispatch(
                SimdPath::Portable,
                CastPackets {
                    accel,
                    range: (0.0, f32::INFINITY),
                    options: &QueryOptions::default(),
                    rays,
                    hits: &mut hit,
                },
            );
            hit[0]
        })
        .collect();
    for path in supported_paths() {
        let mut hits = vec![None; rays.len()];
        let kernel = CastPackets {
            accel,
            range: (0.0, f32::INFINITY),
            options: &QueryOptions::default(),
            rays,
            hits: &mut hits,
        };
        dispatch(path, kernel);
        for (i, (got, want)) in hits.iter().zip(&want).enumerate() {
            assert_eq!(bits(got), bits(want), "ray {i} {:?} on {path:?}", rays[i]);
        }
    }
    want.iter().filter(|h| h.is_some()).count()
}

#[test]
fn packets_of_pinhole_images_answer_as_single_rays() {
    let cube = subdivided_cube(3, Mat3::from_rotation_y(0.3));
    for (mesh, eye) in [
        (subdivided_cube(4, Mat3::IDENTITY), [0.0, 0.0, 4.0]),
        (cube, [2.5, 1.5, 3.0]),
        (icosphere(2), [0.3, -0.2, 3.0]),
    ] {
        let rays = create_rays_pinhole_fov(50.0, [0.0; 3], eye, [0.0, 1.0, 0.0], 64, 48).unwrap();
        let hits = check(&mesh, &rays);
        assert!(hits > rays.len() / 4, "{hits} of {} rays hit", rays.len());
    }
}

#[test]
fn packets_of_rays_from_spread_origins_answer_as_single_rays() {
    // A packet's culling bounds its origins by a box (here an orthographic image, and rays
    // whose origins and directions both vary), not only by one eye.
    let mesh = subdivided_cube(3, Mat3::from_rotation_y(0.3));
    let mut rng = crate::Rng::new(3, &[]);
    let (w, h) = (48, 40);
    let mut rays = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let (u, v) = (
                x as f32 / w as f32 * 3.0 - 1.5,
                y as f32 / h as f32 * 3.0 - 1.5,
            );
            rays.push([u, v, 3.0, 0.1, -0.05, -1.0]);
            let wobble = 0.02 * (rng.uniform() - 0.5);
            rays.push([u + wobble, v, 3.0 + wobble, 0.1 + wobble, -0.05, -1.0]);
        }
    }
    let hits = check(&mesh, &rays);
    assert!(hits > rays.len() / 4, "{hits} of {} rays hit", rays.len());
}

/// Rays from `eye` to each point of `mesh` aimed at by [`targets`] (its shared edges and
/// vertices), `t = 1` at the point.
fn rays_from(eye: Vec3, mesh: &MeshData) -> Vec<[f32; 6]> {
    targets(mesh)
        .iter()
        .map(|t| {
            let d = t.point - eye;
            [eye.x, eye.y, eye.z, d.x, d.y, d.z]
        })
        .collect()
}

#[test]
fn packets_aimed_at_every_edge_and_vertex_answer_as_single_rays() {
    for mesh in [subdivided_cube(3, Mat3::IDENTITY), icosphere(1)] {
        let rays = rays_from(Vec3::new(0.7, 0.4, 3.5), &mesh);
        let hits = check(&mesh, &rays);
        assert!(hits > rays.len() / 2, "{hits} of {} rays hit", rays.len());
    }
}

/// `cast_rays_rows` and `cast_rays` give the same bits on `rays` with row length `w`.
fn same_by_rows(scene: &RaycastingScene, rays: &[[f32; 6]], w: usize) {
    let options = QueryOptions::default();
    let flat = scene.cast_rays(rays, &options).unwrap();
    let tiled = scene.cast_rays_rows(rays, w, &options).unwrap();
    let bits = |c: &CastRays| {
        let t: Vec<u32> = c.t_hit.iter().map(|x| x.to_bits()).collect();
        let uv: Vec<[u32; 2]> = c
            .primitive_uvs
            .iter()
            .map(|x| x.map(f32::to_bits))
            .collect();
        let n: Vec<[u32; 3]> = c
            .primitive_normals
            .iter()
            .map(|x| x.map(f32::to_bits))
            .collect();
        (t, c.geometry_ids.clone(), c.primitive_ids.clone(), uv, n)
    };
    assert!(
        bits(&flat) == bits(&tiled),
        "{} rays, rows of {w}",
        rays.len()
    );
}

#[test]
fn images_cast_by_rows_answer_as_flat_batches() {
    for (mesh, eye) in [
        (subdivided_cube(4, Mat3::IDENTITY), [0.0, 0.0, 4.0]),
        (icosphere(2), [0.3, -0.2, 3.0]),
    ] {
        let mut scene = RaycastingScene::new();
        scene.add_triangles(&mesh.0, &mesh.1).unwrap();
        for (w, h) in [(64, 48), (37, 23), (5, 3), (1, 9), (4, 4)] {
            let rays = create_rays_pinhole_fov(50.0, [0.0; 3], eye, [0.0, 1.0, 0.0], w, h).unwrap();
            // The image's own rows, rows that do not divide the batch, and the plain query.
            for row in [w as usize, 7, 3, 0, 5000] {
                same_by_rows(&scene, &rays, row);
            }
        }
        // Rays aimed exactly at every shared edge and vertex, as rows of 16.
        let aimed = rays_from(Vec3::from(eye.map(|x: f64| x as f32)), &mesh);
        same_by_rows(&scene, &aimed, 16);
    }
}

#[test]
fn tile_order_visits_each_ray_of_a_band_once() {
    for (len, w) in [
        (0, 4),
        (16, 4),
        (15, 4),
        (40, 10),
        (7, 3),
        (4096, 1024),
        (9, 1),
        (6, 7),
    ] {
        let mut seen: Vec<usize> = super::queries::tile_order(len, w);
        seen.sort_unstable();
        assert_eq!(
            seen,
            (0..len).collect::<Vec<_>>(),
            "{len} rays, rows of {w}"
        );
    }
}

/// Counts `rays` in one kernel run on `path` (runs of parallel rays go as packets).
fn counted(scene: &RaycastingScene, rays: &[[f32; 6]], path: SimdPath) -> Vec<i32> {
    use crate::accel::wide::kernels::counts;
    let options = QueryOptions::default();
    let (accel, pool) = scene.prepare(&options).unwrap();
    let border = super::lazy::borders(&accel, &pool, &options).unwrap();
    let mut out = vec![0; rays.len()];
    let range = (0.0, f32::INFINITY);
    counts(path, (&*accel, &options), (&border, range), rays, &mut out);
    out
}

#[test]
fn packets_of_parallel_rays_count_as_single_rays() {
    for mesh in [subdivided_cube(3, Mat3::IDENTITY), icosphere(1)] {
        let mut scene = RaycastingScene::new();
        scene.add_triangles(&mesh.0, &mesh.1).unwrap();
        let points: Vec<Vec3> = targets(&mesh).iter().map(|t| t.point).collect();
        // Occupancy's first vote direction (through vertices and edges exactly where the
        // mesh is axis-aligned) and a skewed one.
        for d in [Vec3::ONE, Vec3::new(1.0003, 0.9995, 1.0001)] {
            let ray = |p: Vec3, s: f32| {
                let o = p - s * d;
                [o.x, o.y, o.z, d.x, d.y, d.z]
            };
            let mut rays = Vec::new();
            // Thirty-two rays on the line through each point (a packet's lanes enter the same
            // nodes: the triangle-by-triangle test), from outside, inside and beyond the mesh.
            let starts = (0..32).map(|k| k as f32 * 0.125 - 1.5);
            for &p in &points {
                rays.extend(starts.clone().map(|s| ray(p, s)));
            }
            // The points one after the other (a lane or two per leaf: lane by lane).
            rays.extend(points.iter().map(|&p| ray(p, 3.0)));
            // One ray alone: the single-ray walk.
            let want: Vec<i32> = rays
                .iter()
                .map(|r| counted(&scene, std::slice::from_ref(r), SimdPath::Portable)[0])
                .collect();
            for path in supported_paths() {
                let got = counted(&scene, &rays, path);
                for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                    assert_eq!(g, w, "ray {i} {:?} on {path:?}", rays[i]);
                }
            }
            assert!(want.iter().filter(|&&n| n > 0).count() > rays.len() / 2);
        }
    }
}

/// A query cancelled from its second look at the flag on: the first, before the first
/// packet, lets it start.
#[derive(Default)]
struct CancelledOnSecondLook(std::cell::Cell<usize>);

impl crate::accel::wide::control::Control for CancelledOnSecondLook {
    type Error = RaycastError;

    fn cancelled(&self) -> bool {
        self.0.set(self.0.get() + 1);
        self.0.get() > 1
    }

    fn cancel_error(&self) -> RaycastError {
        RaycastError::Cancelled
    }

    fn grow<T>(&self, v: &mut Vec<T>, n: usize, what: &'static str) -> Result<(), RaycastError> {
        super::run::grow(v, n, what)
    }
}

#[test]
fn a_packet_of_parallel_rays_stops_within_its_walk_when_cancelled() {
    // 2000 stacked squares: 32 parallel rays up through them cross each once, in hundreds of
    // leaves (with 50 000 squares a packet took 30-180 ms, too long for Ctrl-C).
    let squares = 2000;
    let mut v = Vec::new();
    let mut t = Vec::new();
    for k in 0..squares {
        let z = k as f32 * 1e-3;
        let n = v.len() as u32;
        v.extend([
            [-1.0, -1.0, z],
            [1.0, -1.0, z],
            [1.0, 1.0, z],
            [-1.0, 1.0, z],
        ]);
        t.extend([[n, n + 1, n + 2], [n, n + 2, n + 3]]);
    }
    let mut scene = RaycastingScene::new();
    scene.add_triangles(&v, &t).unwrap();
    let rays: Vec<[f32; 6]> = (0..32)
        .map(|i| [i as f32 / 40.0 - 0.4, 0.3, -1.0, 0.0, 0.0, 1.0])
        .collect();
    let options = QueryOptions::default();
    let (accel, pool) = scene.prepare(&options).unwrap();
    let border = super::lazy::borders(&accel, &pool, &options).unwrap();
    let range = (0.0, f32::INFINITY);
    use crate::accel::wide::kernels::counts;
    for path in supported_paths() {
        let mut all = vec![0; rays.len()];
        counts(path, (&*accel, &options), (&border, range), &rays, &mut all);
        assert_eq!(all, [squares; 32], "{path:?}");
        let (cancel, mut some) = (CancelledOnSecondLook::default(), vec![0; rays.len()]);
        counts(path, (&*accel, &cancel), (&border, range), &rays, &mut some);
        assert!(some.iter().all(|&n| n < squares / 10), "{path:?}: {some:?}");
    }
}

#[test]
fn occupancy_is_the_parity_of_each_points_count_in_any_order() {
    let mesh = icosphere(2);
    let mut scene = RaycastingScene::new();
    scene.add_triangles(&mesh.0, &mesh.1).unwrap();
    let options = QueryOptions::default();
    // A shuffled grid around the sphere, its vertices, and points that are not finite.
    let mut points: Vec<[f32; 3]> = (0..4096)
        .map(|i| {
            let k = (i * 2654435761u64 as usize) % 4096;
            let c = |j: usize| (k >> (4 * j) & 15) as f32 / 7.5 - 1.0;
            [c(0), c(1), c(2)]
        })
        .collect();
    points.extend(mesh.0.iter().copied());
    points.insert(100, [f32::NAN, 0.0, 0.0]);
    points.insert(7, [0.0, f32::INFINITY, 0.0]);
    let rays: Vec<[f32; 6]> = points
        .iter()
        .map(|p| [p[0], p[1], p[2], 1.0, 1.0, 1.0])
        .collect();
    let counts = scene.count_intersections(&rays, &options).unwrap();
    let occupancy = scene.compute_occupancy(&points, 1, &options).unwrap();
    for (i, (n, o)) in counts.iter().zip(&occupancy).enumerate() {
        assert_eq!(*o, (n % 2) as f32, "point {i} {:?}", points[i]);
    }
    let inside = occupancy.iter().filter(|&&o| o == 1.0).count();
    assert!(inside > 1000 && inside < 3000, "{inside} inside");
}

#[test]
fn a_list_of_many_chunks_is_each_rays_own_list() {
    let mesh = icosphere(2);
    let mut scene = RaycastingScene::new();
    scene.add_triangles(&mesh.0, &mesh.1).unwrap();
    let options = QueryOptions {
        threads: 2,
        ..QueryOptions::default()
    };
    // Rays through the sphere and past it, three chunks and a part.
    let rays: Vec<[f32; 6]> = (0..3500)
        .map(|i| {
            let a = i as f32 * 0.618;
            let o = [3.0 * a.cos(), 3.0 * a.sin(), (i % 7) as f32 * 0.3 - 1.0];
            [o[0], o[1], o[2], -o[0] + 0.3 * a.sin(), -o[1], 0.2]
        })
        .collect();
    let all = scene.list_intersections(&rays, &options).unwrap();
    let mut start = 0;
    for (i, ray) in rays.iter().enumerate() {
        let one = scene
            .list_intersections(std::slice::from_ref(ray), &options)
            .unwrap();
        let n = one.t_hit.len();
        let (a, b) = (all.ray_splits[i] as usize, all.ray_splits[i + 1] as usize);
        assert_eq!((a, b), (start, start + n), "ray {i}");
        assert!(all.ray_ids[a..b].iter().all(|&r| r == i as u32), "ray {i}");
        let bits = |t: &[f32]| t.iter().map(|t| t.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&all.t_hit[a..b]), bits(&one.t_hit), "ray {i}");
        assert_eq!(all.primitive_ids[a..b], one.primitive_ids[..], "ray {i}");
        assert_eq!(all.geometry_ids[a..b], one.geometry_ids[..], "ray {i}");
        assert_eq!(all.primitive_uvs[a..b], one.primitive_uvs[..], "ray {i}");
        start += n;
    }
    assert_eq!(start, all.t_hit.len());
    assert!(start > rays.len(), "{start} crossings");
}

/// A prepared ray as comparable bits: `1/d`, origin, axes, shear and `1/d_z`.
fn ray_bits(r: &PreparedRay) -> Vec<u32> {
    let floats = [r.inv_dir.to_array(), r.origin.to_array()].concat();
    let frame = [r.shear()[0], r.shear()[1], r.inv_dz()];
    let axes = r.axes().map(|a| a as u32);
    (floats.iter().chain(&frame).map(|x| x.to_bits()))
        .chain(axes)
        .collect()
}

#[test]
fn a_packets_lanes_are_prepared_as_single_rays() {
    let mut rng = crate::sampling::Rng::new(11, &[]);
    let mut coordinate = |scale: f32| scale * (2.0 * rng.uniform() - 1.0);
    // Directions near (±1, ±1, ±1)·(a, b, c) with exact ties of |d| between axes half the
    // time, and zero components: every way the largest axis and its sign are chosen.
    for sign in [
        [1.0, 1.0, 1.0],
        [-1.0, 1.0, -1.0],
        [1.0, -1.0, 1.0],
        [-1.0, -1.0, -1.0],
    ] {
        for &(a, b, c) in &[
            (1.0, 1.0, 1.0),
            (1.0, 1.0, 0.5),
            (0.5, 1.0, 1.0),
            (1.0, 0.0, 0.0),
        ] {
            let rays: Vec<[f32; 6]> = (0..16)
                .map(|i| {
                    let tie = i % 2 == 0;
                    let jitter = |x: f32, s: f32| if tie || x == 0.0 { x } else { x + s };
                    let d = [
                        sign[0] * jitter(a, 0.01 * coordinate(1.0).abs()),
                        sign[1] * b,
                        sign[2] * c,
                    ];
                    let o = [coordinate(10.0), coordinate(10.0), coordinate(1e-3)];
                    [o[0], o[1], o[2], d[0], d[1], d[2]]
                })
                .collect();
            let single: Vec<Option<PreparedRay>> = rays
                .iter()
                .map(|r| PreparedRay::new(Vec3::from_slice(&r[..3]), Vec3::from_slice(&r[3..])))
                .collect();
            let one_frame = single
                .iter()
                .all(|r| r.unwrap().axes() == single[0].unwrap().axes());
            let packet = lane_rays::<16>(&rays);
            assert_eq!(packet.is_some(), one_frame, "{sign:?} {a} {b} {c}");
            for (lane, one) in packet.iter().flatten().zip(&single) {
                assert_eq!(
                    ray_bits(lane),
                    ray_bits(&one.unwrap()),
                    "{sign:?} {a} {b} {c}"
                );
            }
        }
    }
    // A lane that `PreparedRay::new` refuses, or with another frame, makes no packet.
    let good = [0.0, 0.0, 0.0, 0.1, 0.2, 1.0];
    for bad in [
        [0.0, 0.0, 0.0, 0.1, 1.0, 1.0],
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [f32::NAN, 0.0, 0.0, 0.1, 0.2, 1.0],
        [0.0, 0.0, 0.0, 0.1, f32::INFINITY, 1.0],
        [0.0, 0.0, 0.0, 0.1, 0.2, -1.0],
    ] {
        let mut rays = vec![good; 16];
        rays[9] = bad;
        assert!(lane_rays::<16>(&rays).is_none(), "{bad:?}");
        assert!(lane_rays::<16>(&vec![good; 16]).is_some());
    }
}
