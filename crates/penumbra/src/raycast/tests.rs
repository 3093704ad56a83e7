//! Every query against a brute-force reference (a loop over all triangles, and `f64`
//! Möller–Trumbore for the distances), on random soups and rays, on lattice scenes whose
//! rays run exactly through edges and vertices, and on closed meshes; shapes and miss values;
//! errors; thread-count independence and cancellation.

use std::sync::atomic::AtomicBool;

use glam::{DVec3, Vec3};
use proptest::prelude::*;

use super::*;
use crate::accel::prim::boundary::{boundaries, Boundary};
use crate::accel::prim::watertight::{EdgeRule, PreparedRay, SoaTriangle};
use crate::accel::test_meshes::MeshData;
use crate::accel::wide::nearest::closest_on_triangle;

/// Options with `threads` workers.
fn on(threads: usize) -> QueryOptions<'static> {
    QueryOptions {
        threads,
        cancel: None,
    }
}

/// A scene of one geometry per entry of `meshes`.
fn scene_of(meshes: &[MeshData]) -> RaycastingScene {
    let mut s = RaycastingScene::new();
    for (v, t) in meshes {
        s.add_triangles(v, t).unwrap();
    }
    s
}

/// Every triangle of the scene as (geometry, primitive, corners).
fn all_triangles(s: &RaycastingScene) -> Vec<(u32, u32, crate::accel::prim::Corners)> {
    (0..s.triangle_count() as u32)
        .map(|i| {
            let (g, p) = s.ids(i);
            (g, p, s.corners(i))
        })
        .collect()
}

/// The `f64` Möller–Trumbore distance of a ray to a triangle, edges inclusive.
fn hit_f64(ray: &[f32; 6], tri: &crate::accel::prim::Corners) -> Option<f64> {
    let o = DVec3::new(ray[0] as f64, ray[1] as f64, ray[2] as f64);
    let d = DVec3::new(ray[3] as f64, ray[4] as f64, ray[5] as f64);
    let [a, b, c] = tri.map(|p| Vec3::from(p).as_dvec3());
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let tv = o - a;
    let u = tv.dot(p) / det;
    let q = tv.cross(e1);
    let v = d.dot(q) / det;
    let t = e2.dot(q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t >= 0.0).then_some(t)
}

/// Closest hit by brute force with the same triangle test: (t, geometry, primitive).
fn closest_brute(s: &RaycastingScene, ray: &[f32; 6]) -> Option<(f32, u32, u32)> {
    let r = PreparedRay::new(Vec3::from_slice(&ray[..3]), Vec3::from_slice(&ray[3..]))?;
    let mut best: Option<(f32, u32, u32)> = None;
    for (g, p, tri) in all_triangles(s) {
        if let Some(c) = r.hit(
            &SoaTriangle::new(&tri),
            Boundary::default(),
            0.0,
            f32::INFINITY,
            EdgeRule::Inclusive,
        ) {
            if best.is_none_or(|b| c.t < b.0) {
                best = Some((c.t, g, p));
            }
        }
    }
    best
}

/// Crossings by brute force: sorted (t, geometry, primitive).
fn crossings_brute(s: &RaycastingScene, ray: &[f32; 6]) -> Vec<(f32, u32, u32)> {
    let Some(r) = PreparedRay::new(Vec3::from_slice(&ray[..3]), Vec3::from_slice(&ray[3..])) else {
        return Vec::new();
    };
    let tris = all_triangles(s);
    let corners: Vec<_> = tris.iter().map(|t| t.2).collect();
    let border = boundaries(&corners, None);
    let mut v: Vec<_> = tris
        .into_iter()
        .zip(border)
        .filter_map(|((g, p, tri), b)| {
            r.hit(
                &SoaTriangle::new(&tri),
                b,
                0.0,
                f32::INFINITY,
                EdgeRule::Owned,
            )
            .map(|c| (c.t, g, p))
        })
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0).then((a.1, a.2).cmp(&(b.1, b.2))));
    v
}

/// Checks every ray query on `rays` against the brute-force references.
fn check_rays(s: &RaycastingScene, rays: &[[f32; 6]]) {
    let cast = s.cast_rays(rays, &on(2)).unwrap();
    let occluded = s.test_occlusions(rays, 0.0, f32::INFINITY, &on(2)).unwrap();
    let counts = s.count_intersections(rays, &on(2)).unwrap();
    let list = s.list_intersections(rays, &on(2)).unwrap();
    assert_eq!(list.ray_splits.len(), rays.len() + 1);
    let tris = all_triangles(s);
    for (i, ray) in rays.iter().enumerate() {
        let want = closest_brute(s, ray);
        match want {
            None => {
                assert_eq!(cast.t_hit[i], f32::INFINITY, "ray {ray:?}");
                assert_eq!(
                    (cast.geometry_ids[i], cast.primitive_ids[i]),
                    (INVALID_ID, INVALID_ID)
                );
                assert_eq!(cast.primitive_uvs[i], [0.0; 2]);
                assert_eq!(cast.primitive_normals[i], [0.0; 3]);
            }
            Some((t, g, p)) => {
                assert_eq!(cast.t_hit[i], t, "ray {ray:?}");
                let hit_tri = tris
                    .iter()
                    .find(|x| (x.0, x.1) == (cast.geometry_ids[i], cast.primitive_ids[i]))
                    .unwrap();
                // Equal ids except exact ties, where the triangle hit must give the same t.
                if (g, p) != (hit_tri.0, hit_tri.1) {
                    let r =
                        PreparedRay::new(Vec3::from_slice(&ray[..3]), Vec3::from_slice(&ray[3..]));
                    let c = r.unwrap().hit(
                        &SoaTriangle::new(&hit_tri.2),
                        Boundary::default(),
                        0.0,
                        f32::INFINITY,
                        EdgeRule::Inclusive,
                    );
                    assert_eq!(c.map(|c| c.t), Some(t), "ray {ray:?}");
                }
                // The f64 distance agrees within rounding wherever f64 sees a hit.
                if let Some(t64) = hit_f64(ray, &hit_tri.2) {
                    assert!((t64 - t as f64).abs() <= 1e-4 * (1.0 + t64), "{t64} vs {t}");
                }
                let [u, v] = cast.primitive_uvs[i];
                let [a, b, c] = hit_tri.2.map(Vec3::from);
                let point = (1.0 - u - v) * a + u * b + v * c;
                let along = Vec3::from_slice(&ray[..3]) + t * Vec3::from_slice(&ray[3..]);
                assert!(
                    point.distance(along) <= 1e-3 * (1.0 + point.length()),
                    "{point} {along}"
                );
                let n = Vec3::from(cast.primitive_normals[i]);
                assert!((n.length() - 1.0).abs() < 1e-5);
                assert!(n.dot((b - a).cross(c - a)) > 0.0);
            }
        }
        assert_eq!(occluded[i], want.is_some(), "ray {ray:?}");
        let crossings = crossings_brute(s, ray);
        assert_eq!(counts[i] as usize, crossings.len(), "ray {ray:?}");
        let (lo, hi) = (list.ray_splits[i] as usize, list.ray_splits[i + 1] as usize);
        let listed: Vec<_> = (lo..hi)
            .map(|k| {
                assert_eq!(list.ray_ids[k], i as u32);
                (list.t_hit[k], list.geometry_ids[k], list.primitive_ids[k])
            })
            .collect();
        assert_eq!(listed, crossings, "ray {ray:?}");
    }
    // Results do not depend on the thread count.
    assert_eq!(s.cast_rays(rays, &on(1)).unwrap(), cast);
    assert_eq!(s.count_intersections(rays, &on(3)).unwrap(), counts);
}

/// Checks the closest points of `points` against the brute-force minimum distance.
fn check_points(s: &RaycastingScene, points: &[[f32; 3]]) {
    let closest = s.compute_closest_points(points, &on(2)).unwrap();
    let distance = s.compute_distance(points, &on(2)).unwrap();
    let tris = all_triangles(s);
    for (i, q) in points.iter().enumerate() {
        let q = Vec3::from(*q);
        let best = tris
            .iter()
            .map(|(_, _, t)| {
                closest_on_triangle(q, t.map(Vec3::from))
                    .0
                    .distance_squared(q)
            })
            .fold(f32::INFINITY, f32::min);
        let got = Vec3::from(closest.points[i]);
        if tris.is_empty() {
            assert!(got.is_nan() && distance[i] == f32::INFINITY);
            assert_eq!(closest.geometry_ids[i], INVALID_ID);
            continue;
        }
        // The closest triangle is chosen in f64; its rounded point is as close, to rounding.
        let d = got.distance_squared(q);
        assert!(d <= best * (1.0 + 1e-5) + 1e-30, "query {q}: {d} > {best}");
        assert!(
            (distance[i] - got.distance(q)).abs() <= 1e-6 * distance[i],
            "query {q}"
        );
        let (g, p) = (closest.geometry_ids[i], closest.primitive_ids[i]);
        let tri = tris.iter().find(|x| (x.0, x.1) == (g, p)).unwrap().2;
        let [a, b, c] = tri.map(Vec3::from);
        let [u, v] = closest.primitive_uvs[i];
        assert!(((1.0 - u - v) * a + u * b + v * c).distance(got) < 1e-4 * (1.0 + got.length()));
    }
}

fn arb_point() -> impl Strategy<Value = [f32; 3]> {
    prop::array::uniform3(-4.0f32..4.0)
}

/// Up to 4 geometries of up to 40 small triangles each over shared vertices.
fn arb_meshes() -> impl Strategy<Value = Vec<MeshData>> {
    let mesh = prop::collection::vec(arb_point(), 3..30).prop_flat_map(|v| {
        let n = v.len() as u32;
        let tris = prop::collection::vec(prop::array::uniform3(0..n), 0..40);
        (Just(v), tris)
    });
    prop::collection::vec(mesh, 0..4)
}

/// Rays between random points, and rays from random points toward random vertices.
fn arb_rays() -> impl Strategy<Value = Vec<[f32; 6]>> {
    prop::collection::vec((arb_point(), arb_point(), 0.1f32..3.0), 1..40).prop_map(|v| {
        v.into_iter()
            .map(|(o, e, s)| {
                let d = (Vec3::from(e) - Vec3::from(o)) * s;
                [o[0], o[1], o[2], d.x, d.y, d.z]
            })
            .collect()
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn random_soups_agree_with_brute_force(meshes in arb_meshes(), rays in arb_rays()) {
        let s = scene_of(&meshes);
        check_rays(&s, &rays);
        // Rays aimed exactly at vertices of the scene.
        let at_vertices: Vec<[f32; 6]> = meshes
            .iter()
            .flat_map(|(v, _)| v.iter())
            .zip(&rays)
            .map(|(p, r)| [r[0], r[1], r[2], p[0] - r[0], p[1] - r[1], p[2] - r[2]])
            .collect();
        check_rays(&s, &at_vertices);
        let points: Vec<[f32; 3]> = rays.iter().map(|r| [r[0], r[1], r[2]]).collect();
        check_points(&s, &points);
    }

    #[test]
    fn lattice_scenes_agree_with_brute_force(
        cells in prop::collection::vec((prop::array::uniform3(-2i32..2), 0usize..3), 1..30),
        rays in prop::collection::vec(
            (prop::array::uniform3(-6i32..=6), prop::array::uniform3(-3i32..=3)), 1..60),
    ) {
        // Unit squares on a lattice (two triangles each) hit by rays with small integer
        // coordinates: many run exactly through edges, vertices and box faces.
        let mut v = Vec::new();
        let mut t = Vec::new();
        for (c, axis) in cells {
            let base = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32);
            let (du, dv) = [(Vec3::X, Vec3::Y), (Vec3::Y, Vec3::Z), (Vec3::Z, Vec3::X)][axis];
            let k = v.len() as u32;
            v.extend([base, base + du, base + du + dv, base + dv].map(|p| p.to_array()));
            t.extend([[k, k + 1, k + 2], [k, k + 2, k + 3]]);
        }
        let s = scene_of(&[(v, t)]);
        let rays: Vec<[f32; 6]> = rays
            .into_iter()
            .map(|(o, d)| {
                let o = o.map(|x| x as f32 * 0.5);
                let d = d.map(|x| x as f32);
                [o[0], o[1], o[2], d[0], d[1], d[2]]
            })
            .collect();
        check_rays(&s, &rays);
        let points: Vec<[f32; 3]> = rays.iter().map(|r| [r[0], r[1], r[2]]).collect();
        check_points(&s, &points);
    }
}

#[test]
fn misses_and_empty_scenes_have_open3d_values() {
    let empty = RaycastingScene::new();
    let rays = [
        [0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
        [f32::NAN, 0.0, 0.0, 1.0, 0.0, 0.0],
    ];
    let cast = empty.cast_rays(&rays, &on(1)).unwrap();
    assert_eq!(cast.t_hit, [f32::INFINITY; 2]);
    assert_eq!(cast.geometry_ids, [INVALID_ID; 2]);
    assert_eq!(cast.primitive_ids, [u32::MAX; 2]);
    assert_eq!(empty.count_intersections(&rays, &on(1)).unwrap(), [0, 0]);
    let list = empty.list_intersections(&rays, &on(1)).unwrap();
    assert_eq!(list.ray_splits, [0, 0, 0]);
    let d = empty
        .compute_distance(&[[0.0; 3], [f32::NAN, 0.0, 0.0]], &on(1))
        .unwrap();
    assert!(d[0] == f32::INFINITY && d[1].is_nan());
    assert!(empty.cast_rays(&[], &on(1)).unwrap().t_hit.is_empty());
    // Zero and non-finite directions miss in a non-empty scene too.
    let s = scene_of(&[(
        vec![[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]],
        vec![[0, 1, 2]],
    )]);
    let bad = [
        [0.0, 0.0, 1.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0, 0.0, f32::INFINITY],
    ];
    assert_eq!(s.cast_rays(&bad, &on(1)).unwrap().t_hit, [f32::INFINITY; 2]);
    assert_eq!(
        s.test_occlusions(&bad, 0.0, f32::INFINITY, &on(1)).unwrap(),
        [false; 2]
    );
}

#[test]
fn occlusion_respects_tnear_and_tfar() {
    let s = scene_of(&[(
        vec![[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]],
        vec![[0, 1, 2]],
    )]);
    let ray = [[0.0, 0.0, 2.0, 0.0, 0.0, -1.0]];
    let occ = |near, far| s.test_occlusions(&ray, near, far, &on(1)).unwrap()[0];
    assert!(occ(0.0, f32::INFINITY));
    assert!(occ(0.0, 2.0) && occ(2.0, 3.0));
    assert!(!occ(0.0, 1.999) && !occ(2.001, 9.0));
}

#[test]
fn add_triangles_checks_its_input_and_numbers_geometries() {
    let mut s = RaycastingScene::new();
    let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    assert_eq!(s.add_triangles(&v, &[[0, 1, 2]]), Ok(0));
    assert_eq!(
        s.add_triangles(&v, &[[0, 1, 2], [0, 3, 1]]),
        Err(RaycastError::IndexOutOfRange {
            triangle: 1,
            index: 3,
            vertices: 3
        })
    );
    let bad = [[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]];
    assert_eq!(
        s.add_triangles(&bad, &[[0, 1, 2]]),
        Err(RaycastError::NotFinite { vertex: 1 })
    );
    // Failed calls add nothing; ids continue in order.
    assert_eq!(s.add_triangles(&v, &[]), Ok(1));
    assert_eq!(s.add_triangles(&v, &[[2, 1, 0]]), Ok(2));
    assert_eq!((s.geometry_count(), s.triangle_count()), (3, 2));
    let hit = s
        .cast_rays(&[[0.2, 0.2, -1.0, 0.0, 0.0, 1.0]], &on(1))
        .unwrap();
    assert_eq!(hit.primitive_ids, [0]);
    // Same t on both triangles: either geometry, and its normal faces its own way.
    let n = hit.primitive_normals[0][2];
    assert_eq!(n, if hit.geometry_ids[0] == 0 { 1.0 } else { -1.0 });
    assert_eq!(
        s.count_intersections(&[[0.2, 0.2, -1.0, 0.0, 0.0, 1.0]], &on(1))
            .unwrap(),
        [2]
    );
    assert!(matches!(
        s.compute_occupancy(&[[0.0; 3]], 2, &on(1)),
        Err(RaycastError::InvalidSamples(2))
    ));
}

#[test]
fn a_cancelled_query_stops_with_an_error() {
    let s = scene_of(&[(
        vec![[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]],
        vec![[0, 1, 2]],
    )]);
    let cancel = AtomicBool::new(true);
    let options = QueryOptions {
        threads: 2,
        cancel: Some(&cancel),
    };
    let rays = vec![[0.0, 0.0, 2.0, 0.0, 0.0, -1.0]; 5000];
    assert_eq!(s.cast_rays(&rays, &options), Err(RaycastError::Cancelled));
    assert_eq!(
        s.list_intersections(&rays, &options),
        Err(RaycastError::Cancelled)
    );
    assert_eq!(
        s.compute_distance(&[[0.0; 3]], &options),
        Err(RaycastError::Cancelled)
    );
}

#[test]
fn oblique_rays_at_a_flat_box_boundary_edge_hit() {
    // The renderer's slab test misses some of these (see the ignored
    // `accel::tests::edges::oblique_hits_on_a_flat_box_boundary_edge`): the triangle's box is
    // flat in z and the rays meet the edge y = 0 on the box's boundary. The exit distance
    // scaled by 1 + 2γ₃ keeps the box test conservative.
    let s = scene_of(&[(
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        vec![[0, 1, 2]],
    )]);
    let rays: Vec<[f32; 6]> = (1..40)
        .flat_map(|i| (1..40).map(move |j| (i as f32 * 0.37, j as f32 * 1.13)))
        .map(|(a, b)| [0.25, -a, -b, 0.0, a, b])
        .collect();
    // The box test must never skip what the triangle test alone accepts. (On an unshared
    // boundary edge the sheared ray may fall just outside; that is not a gap between
    // triangles, so the triangle test is the reference here.)
    let cast = s.cast_rays(&rays, &on(2)).unwrap();
    let mut hits = 0;
    for (ray, t) in rays.iter().zip(&cast.t_hit) {
        let want = closest_brute(&s, ray);
        assert_eq!(t.is_finite(), want.is_some(), "{ray:?}");
        if want.is_some() {
            hits += 1;
            assert!((t - 1.0).abs() < 1e-6, "{ray:?}: {t}");
        }
    }
    assert!(hits > rays.len() / 4, "{hits} of {}", rays.len());
    check_rays(&s, &rays);
}

#[test]
fn a_world_becomes_one_geometry_per_object() {
    let mut builder = crate::world::WorldBuilder::new();
    let tri = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]];
    builder.add_triangles(&tri, &[[0, 1, 2]], 0).unwrap();
    let far = tri.map(|p| [p[0], p[1], p[2] - 5.0]);
    builder
        .add_triangles(&far, &[[0, 1, 2], [2, 1, 0]], 0)
        .unwrap();
    let s = RaycastingScene::from_world(&builder.build(1)).unwrap();
    assert_eq!((s.geometry_count(), s.triangle_count()), (2, 3));
    let rays = [
        [0.0, 0.0, 1.0, 0.0, 0.0, -1.0],
        [0.0, 0.0, -9.0, 0.0, 0.0, 1.0],
    ];
    let cast = s.cast_rays(&rays, &on(1)).unwrap();
    assert_eq!(cast.geometry_ids, [0, 1]);
    assert_eq!(cast.t_hit, [1.0, 4.0]);
    assert!(cast.primitive_ids[1] < 2);
    let list = s.list_intersections(&rays[..1], &on(1)).unwrap();
    assert_eq!(list.geometry_ids, [0, 1, 1]);
    assert_eq!(list.primitive_ids[0], 0);
    assert_eq!(list.t_hit, [1.0, 6.0, 6.0]);
}

#[test]
fn a_scene_can_be_shared_between_threads() {
    fn shareable<T: Send + Sync>() {}
    shareable::<RaycastingScene>();
    // Queries from two threads at once on one scene (the first builds the BVH).
    let s = scene_of(&[(
        vec![[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]],
        vec![[0, 1, 2]],
    )]);
    let rays = vec![[0.0, 0.0, 2.0, 0.0, 0.0, -1.0]; 3000];
    std::thread::scope(|scope| {
        let a = scope.spawn(|| s.cast_rays(&rays, &on(1)).unwrap());
        let b = scope.spawn(|| s.cast_rays(&rays, &on(2)).unwrap());
        assert_eq!(a.join().unwrap(), b.join().unwrap());
    });
}
