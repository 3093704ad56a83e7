//! Placed geometries: a world's instances cast as its copies do, and
//! [`RaycastingScene::add_instance`] answers as the same triangles added transformed; its
//! errors, each leaving the scene unchanged.

use glam::{Mat4, Vec3};

use super::instances::checked_transform;
use super::*;
use crate::geometry::Mesh;
use crate::math::Transform;
use crate::world::{World, WorldBuilder};

fn on(threads: usize) -> QueryOptions<'static> {
    QueryOptions {
        threads,
        cancel: None,
    }
}

/// A small closed mesh: a tetrahedron around the origin, 4 triangles.
fn tetrahedron() -> Mesh {
    Mesh {
        positions: vec![
            Vec3::new(-0.5, -0.4, -0.3),
            Vec3::new(0.6, -0.5, -0.2),
            Vec3::new(0.1, 0.7, -0.1),
            Vec3::new(0.0, 0.1, 0.8),
        ],
        indices: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]],
        ..Mesh::default()
    }
}

/// Placements: rotated, scaled non-uniformly, mirrored (a negative scale), translated apart.
fn placements() -> Vec<Transform> {
    vec![
        Transform::from_srt(
            Vec3::ONE,
            Vec3::new(0.0, 30.0, 0.0),
            Vec3::new(-2.0, 0.0, 0.0),
        ),
        Transform::from_srt(
            Vec3::new(1.5, 0.5, 2.0),
            Vec3::new(10.0, 0.0, 70.0),
            Vec3::new(0.0, 1.5, 0.0),
        ),
        Transform::from_srt(
            Vec3::new(-1.0, 1.0, 1.0),
            Vec3::new(0.0, 0.0, 45.0),
            Vec3::new(2.0, -1.0, 0.5),
        ),
    ]
}

/// A world of its own mesh, then the placements of one shared mesh interleaved with own
/// objects, as instances (`instanced`) or as copies.
fn world(instanced: bool) -> World {
    let mut b = WorldBuilder::new();
    let own = Mesh {
        positions: vec![
            Vec3::new(-4.0, -4.0, -3.0),
            Vec3::new(4.0, -4.0, -3.0),
            Vec3::new(0.0, 4.0, -3.0),
        ],
        indices: vec![[0, 1, 2]],
        ..Mesh::default()
    };
    b.add_mesh(&own, &Transform::IDENTITY, &[0]).unwrap();
    let shared = b.add_shared_mesh(tetrahedron()).unwrap();
    for (i, t) in placements().iter().enumerate() {
        if instanced {
            b.add_instance(shared, t, &[0]).unwrap();
        } else {
            b.add_mesh(&tetrahedron(), t, &[0]).unwrap();
        }
        if i == 0 {
            b.add_mesh(&tetrahedron(), &Transform::IDENTITY, &[0])
                .unwrap();
        }
    }
    let world = b.build(1);
    assert_eq!(world.stats().instances, if instanced { 3 } else { 0 });
    world
}

/// Asserts that `a` (a scene with placements) answers as `b` (the same triangles copied):
/// the same triangles hit, `t` within 1e-5 relative, barycentrics within 1e-5 and normals
/// within 1e-5 (each placement's ray is mapped into its mesh's space, so the test rounds
/// differently); a ray through an edge may report either triangle when they are at the same
/// distance.
fn assert_close(a: &CastRays, b: &CastRays) {
    assert_eq!(a.geometry_ids, b.geometry_ids);
    for i in 0..a.t_hit.len() {
        let (ta, tb) = (a.t_hit[i], b.t_hit[i]);
        assert!(
            ta == tb || (ta - tb).abs() <= 1e-5 * tb.abs(),
            "ray {i}: t {ta} vs {tb}"
        );
        let on_edge = |uv: [f32; 2]| uv[0].min(uv[1]).min(1.0 - uv[0] - uv[1]) < 1e-5;
        if a.primitive_ids[i] != b.primitive_ids[i] {
            assert!(
                on_edge(b.primitive_uvs[i]),
                "ray {i}: another triangle, off its edges"
            );
            continue;
        }
        let near = |x: &[f32], y: &[f32]| x.iter().zip(y).all(|(x, y)| (x - y).abs() <= 1e-5);
        assert!(
            near(&a.primitive_uvs[i], &b.primitive_uvs[i]),
            "ray {i}: uv"
        );
        assert!(
            near(&a.primitive_normals[i], &b.primitive_normals[i]),
            "ray {i}: normal"
        );
    }
}

/// A 41 × 41 fan of rays from in front of the scene, and the same from behind.
fn rays() -> Vec<[f32; 6]> {
    let mut rays = Vec::new();
    for z in [6.0f32, -6.0] {
        for i in 0..41 {
            for j in 0..41 {
                let target = Vec3::new(-4.0 + 0.2 * i as f32, -4.0 + 0.2 * j as f32, 0.0);
                let origin = Vec3::new(0.3, 0.2, z);
                let d = target - origin;
                rays.push([origin.x, origin.y, origin.z, d.x, d.y, d.z]);
            }
        }
    }
    rays
}

#[test]
fn a_world_with_instances_casts_as_the_same_world_with_copies() {
    let instanced = RaycastingScene::from_world(&world(true)).unwrap();
    let copied = RaycastingScene::from_world(&world(false)).unwrap();
    assert_eq!(instanced.geometry_count(), 5);
    assert_eq!(instanced.triangle_count(), copied.triangle_count());
    let rays = rays();
    let a = instanced.cast_rays(&rays, &on(2)).unwrap();
    let b = copied.cast_rays(&rays, &on(2)).unwrap();
    assert_close(&a, &b);
    // Every instance and object is hit, and primitive ids index the tetrahedron's triangles.
    for id in 0..5 {
        assert!(a.geometry_ids.contains(&id), "geometry {id} is never hit");
    }
    assert!(a
        .primitive_ids
        .iter()
        .zip(&a.geometry_ids)
        .all(|(&p, &g)| g == INVALID_ID || p < 4));
    let la = instanced.list_intersections(&rays, &on(2)).unwrap();
    let lb = copied.list_intersections(&rays, &on(2)).unwrap();
    assert_eq!(la.ray_splits, lb.ray_splits);
    assert_eq!(la.geometry_ids, lb.geometry_ids);
    let near = la.t_hit.iter().zip(&lb.t_hit);
    assert!(near.clone().all(|(a, b)| (a - b).abs() <= 1e-5 * b.abs()));
}

/// `mesh`'s positions as `[f32; 3]` and its indices.
fn arrays(mesh: &Mesh) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    (
        mesh.positions.iter().map(|p| p.to_array()).collect(),
        mesh.indices.clone(),
    )
}

/// `t`'s matrix by rows.
fn rows(t: &Transform) -> [[f32; 4]; 4] {
    t.world_from_object.transpose().to_cols_array_2d()
}

#[test]
fn an_instance_answers_as_its_triangles_added_transformed() {
    let (vertices, triangles) = arrays(&tetrahedron());
    let mut instanced = RaycastingScene::new();
    let mut added = RaycastingScene::new();
    assert_eq!(instanced.add_triangles(&vertices, &triangles), Ok(0));
    assert_eq!(added.add_triangles(&vertices, &triangles), Ok(0));
    for (i, t) in placements().iter().enumerate() {
        let id = instanced.add_instance(0, &rows(t)).unwrap();
        assert_eq!(id, i as u32 + 1);
        let moved: Vec<[f32; 3]> = vertices
            .iter()
            .map(|&v| {
                t.world_from_object
                    .transform_point3(Vec3::from(v))
                    .to_array()
            })
            .collect();
        assert_eq!(added.add_triangles(&moved, &triangles), Ok(id));
    }
    // An instance of an instance: the copy of geometry 3 (the mirrored one), moved up.
    let up = Transform::from_matrix(Mat4::from_translation(Vec3::new(0.0, 0.0, 1.5)));
    assert_eq!(instanced.add_instance(3, &rows(&up)), Ok(4));
    let (mirrored, _) = arrays(&Mesh {
        positions: vertices
            .iter()
            .map(|&v| up.point(placements()[2].point(Vec3::from(v))))
            .collect(),
        ..Mesh::default()
    });
    assert_eq!(added.add_triangles(&mirrored, &triangles), Ok(4));
    assert_eq!(instanced.triangle_count(), 20);
    let rays = rays();
    let a = instanced.cast_rays(&rays, &on(1)).unwrap();
    assert_close(&a, &added.cast_rays(&rays, &on(1)).unwrap());
    // Packets of an image's rows answer as the rays one by one.
    assert_eq!(a, instanced.cast_rays_rows(&rays, 41, &on(2)).unwrap());
    for id in 0..5 {
        assert!(a.geometry_ids.contains(&id), "geometry {id} is never hit");
    }
    assert_eq!(
        instanced.count_intersections(&rays, &on(2)).unwrap(),
        added.count_intersections(&rays, &on(2)).unwrap()
    );
    let points: Vec<[f32; 3]> = rays
        .iter()
        .map(|r| [r[0] + r[3] * 0.5, r[1] + r[4] * 0.5, 0.0])
        .collect();
    // Closest points are found in world space, on the placed corners: exactly the copy's.
    assert_eq!(
        instanced.compute_closest_points(&points, &on(2)).unwrap(),
        added.compute_closest_points(&points, &on(2)).unwrap()
    );
}

#[test]
fn an_instance_of_a_world_object_copies_that_object() {
    let mut s = RaycastingScene::from_world(&world(true)).unwrap();
    // Geometry 2 is the world's tetrahedron at the origin (object 2, between instances).
    // Moved behind the world's large triangle at z = -3, and cast at from there.
    let back = Transform::from_matrix(Mat4::from_translation(Vec3::new(0.0, 0.0, -6.0)));
    assert_eq!(s.add_instance(2, &rows(&back)), Ok(5));
    let ray = [[0.1, 0.1, -9.0, 0.0, 0.0, 1.0]];
    let hit = s.cast_rays(&ray, &on(1)).unwrap();
    assert_eq!(hit.geometry_ids, [5]);
    assert!(hit.primitive_ids[0] < 4);
}

#[test]
fn bad_instances_are_refused_and_add_nothing() {
    let (vertices, triangles) = arrays(&tetrahedron());
    let mut s = RaycastingScene::new();
    s.add_triangles(&vertices, &triangles).unwrap();
    let identity = rows(&Transform::IDENTITY);
    let unknown = s.add_instance(1, &identity);
    assert_eq!(
        unknown,
        Err(RaycastError::UnknownGeometry {
            id: 1,
            geometries: 1
        })
    );
    let mut nan = identity;
    nan[1][2] = f32::NAN;
    assert_eq!(
        s.add_instance(0, &nan),
        Err(RaycastError::TransformNotFinite { row: 1, column: 2 })
    );
    let mut projective = identity;
    projective[3][2] = 0.5;
    assert_eq!(
        s.add_instance(0, &projective),
        Err(RaycastError::TransformNotAffine)
    );
    let flat = rows(&Transform::from_srt(
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::ZERO,
        Vec3::ZERO,
    ));
    assert_eq!(
        s.add_instance(0, &flat),
        Err(RaycastError::SingularTransform)
    );
    let far = rows(&Transform::from_srt(
        Vec3::ONE,
        Vec3::ZERO,
        Vec3::new(2e12, 0.0, 0.0),
    ));
    let beyond = || RaycastError::Beyond {
        what: "placed vertex",
        index: 0,
    };
    assert_eq!(s.add_instance(0, &far), Err(beyond()));
    // Factors that overflow f32 once applied (an invertible matrix) are beyond too.
    let big = [[1e11, 0.0, 0.0], [0.0, 1e11, 0.0], [0.0, 0.0, 1e11]];
    assert_eq!(s.add_triangles(&big, &[[0, 1, 2]]), Ok(1));
    let huge = rows(&Transform::from_srt(
        Vec3::new(1e30, 1e-30, 1.0),
        Vec3::ZERO,
        Vec3::ZERO,
    ));
    assert_eq!(s.add_instance(1, &huge), Err(beyond()));
    assert_eq!((s.geometry_count(), s.triangle_count()), (2, 5));
    // The scene still answers as before.
    let hit = s
        .cast_rays(&[[0.0, 0.0, 5.0, 0.0, 0.0, -1.0]], &on(1))
        .unwrap();
    assert_eq!(hit.geometry_ids, [0]);
}

#[test]
fn sizes_past_the_limits_are_refused() {
    assert_eq!(fits(3, MAX_TRIANGLES), Ok(()));
    assert_eq!(
        fits(3, MAX_TRIANGLES + 1),
        Err(RaycastError::TooManyTriangles)
    );
    assert_eq!(
        fits(u32::MAX as usize + 1, 1),
        Err(RaycastError::TooManyTriangles)
    );
}

#[test]
fn a_transform_is_read_by_rows() {
    let rows = [
        [1.0, 0.0, 0.0, 5.0],
        [0.0, 2.0, 0.0, 6.0],
        [0.0, 0.0, -1.0, 7.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    let t = checked_transform(&rows).unwrap();
    assert_eq!(t.point(Vec3::new(1.0, 1.0, 1.0)), Vec3::new(6.0, 8.0, 6.0));
}

#[test]
fn geometries_added_to_a_world_are_numbered_after_all_its_objects() {
    // Objects 1 and 3 have no triangles (empty meshes), 3 the last one: every object is a
    // geometry, so the ids of geometries added later name no object (Python's `object_id`
    // attribute tells them apart by that).
    let mut b = WorldBuilder::new();
    let tri = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]];
    let moved = tri.map(|p| [p[0], p[1], p[2] - 2.0]);
    for (vertices, triangles) in [(&tri, 1), (&tri, 0), (&moved, 1), (&tri, 0)] {
        let indices = &[[0, 1, 2]][..triangles];
        b.add_triangles(vertices, indices, 0).unwrap();
    }
    let world = b.build(1);
    assert_eq!(world.stats().objects, 4);
    let mut s = RaycastingScene::from_world(&world).unwrap();
    assert_eq!(s.geometry_count(), 4);
    let down = |z: f32| [0.0, 0.0, z, 0.0, 0.0, -1.0];
    let cast = s.cast_rays(&[down(1.0), down(-1.0)], &on(1)).unwrap();
    assert_eq!(cast.geometry_ids, [0, 2]);
    let further = tri.map(|p| [p[0], p[1], p[2] - 4.0]);
    assert_eq!(s.add_triangles(&further, &[[0, 1, 2]]), Ok(4));
    let below = Transform::from_matrix(Mat4::from_translation(Vec3::new(0.0, 0.0, -6.0)));
    assert_eq!(s.add_instance(0, &rows(&below)), Ok(5));
    let rays = [down(1.0), down(-1.0), down(-3.0), down(-5.0)];
    let cast = s.cast_rays(&rays, &on(1)).unwrap();
    assert_eq!(cast.geometry_ids, [0, 2, 4, 5]);
    assert_eq!(cast.t_hit, [1.0; 4]);
}

#[test]
fn a_moved_placement_answers_as_one_added_there() {
    let (vertices, triangles) = arrays(&tetrahedron());
    let t = placements();
    let up = |z: f32| rows(&Transform::from_matrix(Mat4::from_translation(Vec3::Z * z)));
    // Placements 1 and 2 of geometry 0, and 3 a placement of placement 1.
    let scene = |first: &Transform, lift: f32| {
        let mut s = RaycastingScene::new();
        s.add_triangles(&vertices, &triangles).unwrap();
        s.add_instance(0, &rows(first)).unwrap();
        s.add_instance(0, &rows(&t[1])).unwrap();
        s.add_instance(1, &up(lift)).unwrap();
        s
    };
    let rays = rays();
    let mut moved = scene(&t[0], 1.5);
    let before = moved.cast_rays(&rays, &on(2)).unwrap();
    moved.set_transform(1, &rows(&t[2])).unwrap();
    moved.set_transform(3, &up(-1.0)).unwrap();
    let fresh = scene(&t[2], -1.0);
    let after = moved.cast_rays(&rays, &on(2)).unwrap();
    assert_ne!(after, before, "the move shows");
    assert_eq!(after, fresh.cast_rays(&rays, &on(2)).unwrap());
    assert_eq!(
        moved.count_intersections(&rays, &on(2)).unwrap(),
        fresh.count_intersections(&rays, &on(2)).unwrap()
    );
    let points: Vec<[f32; 3]> = rays.iter().map(|r| [r[0], r[1], 0.5]).collect();
    assert_eq!(
        moved.compute_closest_points(&points, &on(2)).unwrap(),
        fresh.compute_closest_points(&points, &on(2)).unwrap()
    );
    // Refused moves change nothing: an own geometry, an id past the last, a singular matrix.
    let not = |id| RaycastError::NotAPlacement { id, geometries: 4 };
    assert_eq!(moved.set_transform(0, &up(2.0)), Err(not(0)));
    assert_eq!(moved.set_transform(4, &up(2.0)), Err(not(4)));
    let mut flat = up(2.0);
    flat[2][2] = 0.0;
    assert_eq!(
        moved.set_transform(1, &flat),
        Err(RaycastError::SingularTransform)
    );
    assert_eq!(moved.cast_rays(&rays, &on(1)).unwrap(), after);
}

#[test]
fn a_placement_is_checked_on_every_vertex_and_as_composed() {
    // Vertex 3 is used by no triangle, and still placed beyond the limit by a shift of 2e11.
    let mut s = RaycastingScene::new();
    let vertices = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [9e11, 0.0, 0.0],
    ];
    s.add_triangles(&vertices, &[[0, 1, 2]]).unwrap();
    let shift = |x: f32| rows(&Transform::from_matrix(Mat4::from_translation(Vec3::X * x)));
    let beyond = || RaycastError::Beyond {
        what: "placed vertex",
        index: 3,
    };
    assert_eq!(s.add_instance(0, &shift(2e11)), Err(beyond()));
    assert_eq!(s.add_instance(0, &shift(1e11)), Ok(1));
    assert_eq!(s.set_transform(1, &shift(2e11)), Err(beyond()));
    // Two small scales, each invertible, whose product is not.
    let small = rows(&Transform::from_matrix(Mat4::from_scale(Vec3::splat(
        1e-12,
    ))));
    assert_eq!(s.add_instance(0, &small), Ok(2));
    let singular = RaycastError::SingularTransform;
    assert_eq!(
        s.add_instance(2, &small),
        Err(RaycastError::SingularTransform)
    );
    assert_eq!(s.add_instance(2, &rows(&Transform::IDENTITY)), Ok(3));
    assert_eq!(s.set_transform(3, &small), Err(singular));
    assert_eq!(s.geometry_count(), 4);
}
