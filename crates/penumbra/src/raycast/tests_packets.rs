//! The closest-hit packets (`packet`) against the single-ray query, bit for bit, on every SIMD
//! path this machine has: pinhole images of closed meshes (with exact ties on their shared
//! edges) and rays from one eye aimed exactly at every shared edge and vertex.

use glam::{Mat3, Vec3};

use super::packet::{CastPackets, ClosestHit};
use super::watertight::PreparedRay;
use super::*;
use crate::simd::{dispatch, supported_paths, SimdPath};

use super::tests_meshes::{icosphere, subdivided_cube, targets, MeshData};

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

#[test]
fn packets_aimed_at_every_edge_and_vertex_answer_as_single_rays() {
    for mesh in [subdivided_cube(3, Mat3::IDENTITY), icosphere(1)] {
        let eye = Vec3::new(0.7, 0.4, 3.5);
        let rays: Vec<[f32; 6]> = targets(&mesh)
            .iter()
            .map(|t| {
                let d = t.point - eye;
                [eye.x, eye.y, eye.z, d.x, d.y, d.z]
            })
            .collect();
        let hits = check(&mesh, &rays);
        assert!(hits > rays.len() / 2, "{hits} of {} rays hit", rays.len());
    }
}
