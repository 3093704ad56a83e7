//! Random scenes of placed meshes (rotated, scaled non-uniformly, mirrored, placements of
//! placements) against the same triangles copied, for every ray query and on every SIMD path
//! this machine has: the same triangles hit and counted, `t` within 1e-5 relative (of the
//! segment's length when the hit is nearer).

use glam::{Mat4, Vec3};

use super::*;
use crate::accel::test_meshes::{icosphere, random_transform, subdivided_cube, MeshData};
use crate::accel::wide::kernels::{closest_hits, counts, occlusions, Nearests};
use crate::accel::wide::nearest::closest_f64;
use crate::accel::wide::packets::ClosestHit;
use crate::math::Transform;
use crate::pool::test_pool;
use crate::sampling::Rng;
use crate::simd::{dispatch, supported_paths};

/// `t`'s matrix by rows.
fn rows(t: &Transform) -> [[f32; 4]; 4] {
    t.world_from_object.transpose().to_cols_array_2d()
}

/// The scene of `seed` twice: with placements, and with the placed triangles copied.
fn scenes(seed: u64) -> (RaycastingScene, RaycastingScene) {
    let mut rng = Rng::new(seed, &[]);
    let meshes: [MeshData; 2] = [icosphere(1), subdivided_cube(2, glam::Mat3::IDENTITY)];
    let (mut placed, mut copied) = (RaycastingScene::new(), RaycastingScene::new());
    for (vertices, triangles) in &meshes {
        placed.add_triangles(vertices, triangles).unwrap();
        copied.add_triangles(vertices, triangles).unwrap();
    }
    // Each geometry's object-to-world map and mesh.
    let mut maps: Vec<(Mat4, usize)> = vec![(Mat4::IDENTITY, 0), (Mat4::IDENTITY, 1)];
    for _ in 0..12 {
        let of = (rng.uniform() * maps.len() as f32) as usize % maps.len();
        let t = random_transform(&mut rng);
        let id = placed.add_instance(of as u32, &rows(&t)).unwrap();
        let (map, mesh) = maps[of];
        let both = Transform::from_matrix(t.world_from_object * map);
        let (vertices, triangles) = &meshes[mesh];
        let moved: Vec<[f32; 3]> = vertices
            .iter()
            .map(|&v| both.point(Vec3::from(v)).to_array())
            .collect();
        assert_eq!(copied.add_triangles(&moved, triangles), Ok(id));
        maps.push((both.world_from_object, mesh));
    }
    (placed, copied)
}

/// Random rays between points within ±4 (half of them segments, `t` in `[0, 1]`).
fn random_rays(seed: u64, n: usize) -> Vec<[f32; 6]> {
    let mut rng = Rng::new(seed, &[1]);
    let mut p = || Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 8.0 - 4.0;
    (0..n)
        .map(|_| {
            let (a, b) = (p(), p());
            let d = b - a;
            [a.x, a.y, a.z, d.x, d.y, d.z]
        })
        .collect()
}

/// Each query's answers for `rays` on every SIMD path (all paths must agree bit for bit):
/// closest hits, occlusion of the segments, crossing counts.
fn answers(scene: &RaycastingScene, rays: &[[f32; 6]]) -> (Vec<ClosestHit>, Vec<bool>, Vec<i32>) {
    let options = QueryOptions::default();
    let (accel, _) = scene.prepare(&options).unwrap();
    let border = accel.borders(test_pool());
    let mut all = Vec::new();
    for path in supported_paths() {
        // The kernels as the queries run them: the own tree's, then the placements'.
        let run = (&*accel, &options);
        let mut hits = vec![None; rays.len()];
        let every = (0.0, f32::INFINITY);
        closest_hits(path, run, (rays, every), &mut hits);
        let mut occluded = vec![false; rays.len()];
        occlusions(path, run, rays, (0.0, 1.0), &mut occluded);
        let mut counted = vec![0; rays.len()];
        counts(path, run, (&border, every), rays, &mut counted);
        all.push((hits, occluded, counted));
    }
    for other in &all[1..] {
        assert!(other == &all[0], "the SIMD paths disagree");
    }
    all.swap_remove(0)
}

#[test]
fn placed_meshes_answer_as_their_copies_on_every_path() {
    let (mut hits, mut checked) = (0, 0);
    for seed in 0..6 {
        let (placed, copied) = scenes(seed);
        assert_eq!(placed.triangle_count(), copied.triangle_count());
        let rays = random_rays(seed, 3000);
        let (a, occluded_a, counts_a) = answers(&placed, &rays);
        let (b, occluded_b, counts_b) = answers(&copied, &rays);
        for (i, (a, b)) in a.iter().zip(&b).enumerate() {
            let key = |h: &ClosestHit| h.map(|h| (h.geometry, h.primitive));
            assert_eq!(key(a), key(b), "seed {seed}, ray {i}");
            if let (Some(a), Some(b)) = (a, b) {
                let (ta, tb) = (a.crossing.t, b.crossing.t);
                // Relative to the segment (`t` = 1), whose coordinates the maps round.
                let close = (ta - tb).abs() <= 1e-5 * tb.max(1.0);
                assert!(close, "seed {seed}, ray {i}: {ta} vs {tb}");
                hits += 1;
                // A segment ending within rounding of a surface may go either way.
                if (tb - 1.0).abs() < 1e-4 {
                    continue;
                }
            }
            assert_eq!(occluded_a[i], occluded_b[i], "seed {seed}, ray {i}");
            checked += 1;
        }
        assert_eq!(counts_a, counts_b, "seed {seed}");
    }
    assert!(
        hits > 5000 && checked > 15000,
        "{hits} hits, {checked} checked"
    );
}

#[test]
fn bounds_on_t_keep_the_hits_and_crossings_within_them() {
    // Placed and copied scenes alike: the closest hit within [tnear, tfar] is the first
    // crossing the unbounded list has there, and the bounded count is the list's crossings
    // within the bounds.
    let options = QueryOptions::default();
    for scene in <[RaycastingScene; 2]>::from(scenes(3)) {
        let rays = random_rays(3, 400);
        let listed = scene.list_intersections(&rays, &options).unwrap();
        for (tnear, tfar) in [(0.0, f32::INFINITY), (0.3, 0.8), (0.5, 0.5), (0.9, 0.1)] {
            let cast = scene
                .cast_rays_between(&rays, 0, (tnear, tfar), &options)
                .unwrap();
            let counted = scene
                .count_intersections_between(&rays, (tnear, tfar), &options)
                .unwrap();
            for (i, (&count, &t)) in counted.iter().zip(&cast.t_hit).enumerate() {
                let span = listed.ray_splits[i] as usize..listed.ray_splits[i + 1] as usize;
                let within: Vec<f32> = listed.t_hit[span]
                    .iter()
                    .copied()
                    .filter(|&t| (tnear..=tfar).contains(&t))
                    .collect();
                assert_eq!(count as usize, within.len(), "ray {i} in {tnear}..{tfar}");
                let first = within.first().copied().unwrap_or(f32::INFINITY);
                assert_eq!(t, first, "ray {i} in {tnear}..{tfar}");
            }
        }
        // The default bounds are the plain queries', bit for bit (packets and all).
        let plain = scene.cast_rays_rows(&rays, 20, &options).unwrap();
        let bounded = scene.cast_rays_between(&rays, 20, (0.0, f32::INFINITY), &options);
        assert_eq!(plain, bounded.unwrap());
    }
}

/// The closest point to `q` of every triangle of `tris` (geometry id, primitive id, corners),
/// computed as the walk computes it, and the rule for ties: the smallest squared distance,
/// then geometry id, then primitive id. Returns the ids, the point and its weights.
fn nearest_of_all(tris: &[(u32, u32, [Vec3; 3])], q: Vec3) -> (u32, u32, Vec3, f32, f32) {
    let q = q.as_dvec3();
    let mut best = (f64::INFINITY, u32::MAX, u32::MAX, Vec3::NAN, 0.0, 0.0);
    for &(g, p, tri) in tris {
        let (point, b1, b2) = closest_f64(q, tri.map(|c| c.as_dvec3()));
        let d = (point - q).length_squared();
        if (d, g, p) < (best.0, best.1, best.2) {
            best = (d, g, p, point.as_vec3(), b1 as f32, b2 as f32);
        }
    }
    (best.1, best.2, best.3, best.4, best.5)
}

#[test]
fn closest_points_are_those_of_testing_every_triangle() {
    // The walk skips boxes and triangles by lower bounds of their distance in `f32`: they
    // must never skip the answer, nor one of the triangles tied with it. Query points at
    // corners and on edges are ties between neighbours; far ones see every box at once.
    for seed in 0..3 {
        let (placed, copied) = scenes(seed);
        let tris: Vec<(u32, u32, [Vec3; 3])> = (0..copied.triangle_count() as u32)
            .map(|i| {
                let (g, p) = copied.ids(i);
                (g, p, copied.corners(i).map(Vec3::from))
            })
            .collect();
        let mut rng = Rng::new(seed, &[7]);
        let mut points: Vec<[f32; 3]> = Vec::new();
        for k in 0..600 {
            let tri = tris[(rng.uniform() * tris.len() as f32) as usize % tris.len()].2;
            let random = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 8.0 - 4.0;
            let p = match k % 5 {
                0 => tri[k % 3],
                1 => (tri[0] + tri[1]) * 0.5,
                2 => random * 20.0,
                _ => random,
            };
            points.push(p.to_array());
        }
        let options = QueryOptions::default();
        for scene in [&placed, &copied] {
            let (accel, _) = scene.prepare(&options).unwrap();
            for path in supported_paths() {
                let mut out = vec![None; points.len()];
                let (accel, options, points) = (&*accel, &options, &points[..]);
                let out_ = &mut out[..];
                dispatch(
                    path,
                    Nearests {
                        accel,
                        options,
                        points,
                        out: out_,
                    },
                );
                for (q, near) in points.iter().zip(&out) {
                    let near = near.expect("a closest point");
                    let got = (near.geometry, near.primitive, near.point, near.b1, near.b2);
                    let want = nearest_of_all(&tris, Vec3::from(*q));
                    assert_eq!(got, want, "query {q:?} on {path:?}");
                }
            }
        }
    }
}
