//! The closest-hit packets (`packet`) against the single-ray query, bit for bit, on every SIMD
//! path this machine has: pinhole images of closed meshes (with exact ties on their shared
//! edges) and rays from one eye aimed exactly at every shared edge and vertex.

use glam::{Mat3, Vec3};

use super::*;
use crate::accel::prim::watertight::PreparedRay;
use crate::accel::wide::packets::{CastPackets, ClosestHit};
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
    let prepared: Vec<Option<PreparedRay>> = rays
        .iter()
        .map(|r| PreparedRay::new(Vec3::from_slice(&r[..3]), Vec3::from_slice(&r[3..])))
        .collect();
    // One ray per kernel run: never a packet, the single-ray query.
    let want: Vec<ClosestHit> = prepared
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
            rays: &prepared,
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
