//! Watertightness: rays from random directions outside closed meshes aimed exactly at points
//! of every shared edge (midpoint, a third, a tenth) and at every vertex never miss and never
//! leak to the far side, and count an even number of crossings (2 on convex meshes). Also
//! occupancy and signed distance against closed forms, and the pinhole ray layout.
//!
//! The same edge sets measure the renderer's `f32` Möller–Trumbore (printed with
//! `--nocapture`, not asserted): `PENUMBRA_EXTRA_MESH=path.obj` adds a mesh to the list (an
//! absolute path: cargo runs the tests in `crates/penumbra`).

use std::path::Path;

use glam::{Mat3, Vec3};

use super::*;
use crate::math::Ray;
use crate::sampling::Rng;
use crate::world::WorldBuilder;

use crate::accel::test_meshes::{
    aimed_rays, edges, icosphere, read_obj, subdivided_cube, targets, MeshData,
};

/// Misses and leaks (a first hit past the target) of the renderer's intersection and of
/// `cast_rays`; asserts the latter has none and that crossing counts are even (exactly
/// `convex_count` when given).
fn check_watertight(name: &str, mesh: &MeshData, convex_count: Option<i32>) {
    let rays = aimed_rays(mesh, &targets(mesh), 7);
    let closed = edges(mesh).values().all(|t| t.len() == 2);
    let mut scene = RaycastingScene::new();
    scene.add_triangles(&mesh.0, &mesh.1).unwrap();
    let options = QueryOptions {
        threads: 2,
        cancel: None,
    };
    let cast = scene.cast_rays(&rays, &options).unwrap();
    let leak = |t: f32| t > 1.0 + 1e-4;
    let bad: Vec<usize> = (0..rays.len()).filter(|&i| leak(cast.t_hit[i])).collect();
    let mut world = WorldBuilder::new();
    world.add_triangles(&mesh.0, &mesh.1, 0).unwrap();
    let world = world.build(2);
    let old: Vec<Option<f32>> = rays
        .iter()
        .map(|r| {
            let ray = Ray::new(Vec3::from_slice(&r[..3]), Vec3::from_slice(&r[3..]));
            world.intersect(&ray, 0.0, f32::INFINITY).map(|h| h.t)
        })
        .collect();
    let old_misses = old.iter().filter(|t| t.is_none()).count();
    let old_leaks = old.iter().filter(|t| t.is_some_and(leak)).count();
    let percent = |n: usize| 100.0 * n as f64 / rays.len() as f64;
    eprintln!(
        "{name} ({} triangles, {}): {} rays at edges and vertices; renderer's f32 \
         Möller–Trumbore: {old_misses} misses ({:.2} %), {old_leaks} leaks ({:.2} %); \
         watertight cast_rays: {} misses or leaks",
        mesh.1.len(),
        if closed { "closed" } else { "with holes" },
        rays.len(),
        percent(old_misses),
        percent(old_leaks),
        bad.len()
    );
    assert!(
        bad.is_empty(),
        "{name}: {} of {} rays missed, e.g. {:?}",
        bad.len(),
        rays.len(),
        rays[bad[0]]
    );
    assert!(scene
        .test_occlusions(&rays, 0.0, f32::INFINITY, &options)
        .unwrap()
        .iter()
        .all(|&o| o));
    if closed {
        let counts = scene.count_intersections(&rays, &options).unwrap();
        let odd: Vec<usize> = (0..rays.len()).filter(|&i| counts[i] % 2 != 0).collect();
        assert!(
            odd.is_empty(),
            "{name}: {} odd counts, e.g. {:?}",
            odd.len(),
            rays[odd[0]]
        );
        if let Some(n) = convex_count {
            assert!(
                counts.iter().all(|&c| c == n),
                "{name}: counts {:?}",
                &counts[..8]
            );
        }
    }
}

#[test]
fn rays_at_edges_and_vertices_of_closed_meshes_never_miss() {
    check_watertight("icosphere", &icosphere(4), Some(2));
    let rotation = Mat3::from_euler(glam::EulerRot::XYZ, 0.3, 0.7, 1.1);
    check_watertight(
        "rotated subdivided cube",
        &subdivided_cube(12, rotation),
        Some(2),
    );
    check_watertight(
        "subdivided cube",
        &subdivided_cube(8, Mat3::IDENTITY),
        Some(2),
    );
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/meshes");
    check_watertight(
        "spot",
        &read_obj(&assets.join("spot_triangulated.obj")),
        None,
    );
    if let Ok(extra) = std::env::var("PENUMBRA_EXTRA_MESH") {
        check_watertight(&extra, &read_obj(Path::new(&extra)), None);
    }
}

#[test]
fn occupancy_and_signed_distance_match_closed_forms() {
    let mut scene = RaycastingScene::new();
    let cube = subdivided_cube(3, Mat3::IDENTITY);
    scene.add_triangles(&cube.0, &cube.1).unwrap();
    let options = QueryOptions::default();
    let mut rng = Rng::new(3, &[]);
    let points: Vec<[f32; 3]> = (0..2000)
        .map(|_| [0; 3].map(|_| 3.0 * rng.uniform() - 1.5))
        .collect();
    let occupancy = scene.compute_occupancy(&points, 1, &options).unwrap();
    let voted = scene.compute_occupancy(&points, 5, &options).unwrap();
    let signed = scene.compute_signed_distance(&points, 1, &options).unwrap();
    for (i, p) in points.iter().enumerate() {
        let p = Vec3::from(*p);
        // Signed distance to the box [-1, 1]³.
        let q = p.abs() - Vec3::ONE;
        let sdf = q.max(Vec3::ZERO).length() + q.max_element().min(0.0);
        let inside = sdf < 0.0;
        assert_eq!(occupancy[i], if inside { 1.0 } else { 0.0 }, "{p}");
        assert_eq!(voted[i], occupancy[i]);
        assert!(
            (signed[i] - sdf).abs() < 1e-5,
            "{p}: {} vs {sdf}",
            signed[i]
        );
    }
    // Lattice points of the cube's own subdivision lie on edges and vertices of its
    // triangles along the (1, 1, 1) vote ray: still exact.
    let grid: Vec<[f32; 3]> = (-4..=4)
        .flat_map(|i| {
            (-4..=4).flat_map(move |j| (-4..=4).map(move |k| [i, j, k].map(|x| x as f32 / 3.0)))
        })
        .filter(|p| p.iter().all(|x| x.abs() < 0.9 || x.abs() > 1.1))
        .collect();
    let occ = scene.compute_occupancy(&grid, 1, &options).unwrap();
    for (p, o) in grid.iter().zip(occ) {
        assert_eq!(
            o,
            if p.iter().all(|x| x.abs() < 1.0) {
                1.0
            } else {
                0.0
            },
            "{p:?}"
        );
    }
    // A sphere: distance |p| − 1 up to the tessellation error.
    let mut sphere = RaycastingScene::new();
    let s = icosphere(4);
    sphere.add_triangles(&s.0, &s.1).unwrap();
    let signed = sphere
        .compute_signed_distance(&points, 1, &options)
        .unwrap();
    for (p, d) in points.iter().zip(signed) {
        let exact = Vec3::from(*p).length() - 1.0;
        assert!(
            (d - exact).abs() < 2e-3 || (d - exact).abs() < 1e-5,
            "{p:?}: {d} vs {exact}"
        );
    }
}

#[test]
fn pinhole_rays_follow_open3d_layout() {
    let (w, h) = (8u32, 6u32);
    let rays = create_rays_pinhole_fov(
        90.0,
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 5.0],
        [0.0, 1.0, 0.0],
        w,
        h,
    )
    .unwrap();
    assert_eq!(rays.len(), (w * h) as usize);
    for r in &rays {
        assert_eq!(&r[..3], &[0.0, 0.0, 5.0]);
        // Camera z is the unit forward axis: t_hit is depth.
        assert!((r[5] + 1.0).abs() < 1e-6);
    }
    let dir = |x: u32, y: u32| Vec3::from_slice(&rays[(y * w + x) as usize][3..]);
    // Row index grows toward `up`, column index toward up × forward (−x here).
    assert!(dir(0, h - 1).y > dir(0, 0).y && dir(w - 1, 0).x < dir(0, 0).x);
    // 90° horizontal field of view: the outer pixel edges are at ±1 across; pixel centers.
    assert!(
        (dir(0, 0).x - (1.0 - 1.0 / w as f32)).abs() < 1e-6,
        "{}",
        dir(0, 0)
    );
    assert!((dir(0, 0).y - -(h as f32 / w as f32 - 1.0 / w as f32)).abs() < 1e-6);
    // The intrinsic form with an identity extrinsic looks along +z from the origin.
    let k = [[2.0, 0.0, 1.0], [0.0, 2.0, 1.0], [0.0, 0.0, 1.0]];
    let id = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    let r = create_rays_pinhole(k, id, 2, 2).unwrap();
    assert_eq!(r[0], [0.0, 0.0, 0.0, -0.25, -0.25, 1.0]);
    assert_eq!(r[3], [0.0, 0.0, 0.0, 0.25, 0.25, 1.0]);
    // A translated camera: the extrinsic is world-to-camera, so the origin is −Rᵀt.
    let mut moved = id;
    moved[0][3] = -3.0;
    assert_eq!(
        &create_rays_pinhole(k, moved, 1, 1).unwrap()[0][..3],
        &[3.0, 0.0, 0.0]
    );
    // Invalid cameras are errors, never panics: a singular intrinsic matrix, an all-zero,
    // flat or non-finite extrinsic one.
    let zero = [[0.0; 3]; 3];
    assert!(create_rays_pinhole(zero, id, 2, 2).is_err());
    let mut flat = id;
    flat[2] = [1.0, 0.0, 0.0, 0.0];
    let mut tiny = id;
    tiny[1][1] = 1e-12;
    for bad in [[[0.0; 4]; 4], flat, tiny] {
        let err = create_rays_pinhole(k, bad, 2, 2).unwrap_err();
        assert!(err.to_string().contains("singular"), "{err}");
    }
    // A scaled rotation is a camera still.
    let mut scaled = id;
    (scaled[0][0], scaled[1][1], scaled[2][2]) = (1e-6, 1e-6, 1e-6);
    assert!(create_rays_pinhole(k, scaled, 2, 2).is_ok());
    // Too many rays for memory is an error, not an abort.
    let huge = create_rays_pinhole(k, id, 65535, 65535);
    assert!(
        matches!(huge, Err(RaycastError::OutOfMemory { .. })),
        "{huge:?}"
    );
    assert!(
        create_rays_pinhole_fov(0.0, [0.0; 3], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0], 2, 2).is_err()
    );
    assert!(create_rays_pinhole_fov(60.0, [0.0; 3], [0.0; 3], [0.0, 1.0, 0.0], 2, 2).is_err());
    assert!(
        create_rays_pinhole_fov(60.0, [0.0; 3], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0], 2, 2).is_err()
    );
    assert!(
        create_rays_pinhole_fov(60.0, [0.0; 3], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0], 0, 2)
            .unwrap()
            .is_empty()
    );
}
