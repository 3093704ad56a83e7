//! Rays whose `[tnear, tfar]` reaches behind the origin (`tnear < 0`), on every SIMD path this
//! machine has: flat (zero-thickness) boxes there must be entered, by the own tree's walks
//! (single rays and packets) and the placements' alike, and ties there must go to the smallest
//! id, as in front of the origin.

use super::*;
use crate::accel::wide::kernels::{closest_hits, counts, occlusions};
use crate::accel::wide::packets::ClosestHit;
use crate::pool::test_pool;
use crate::simd::supported_paths;

/// A grid of `n × n` unit squares (two triangles each) in the plane where coordinate `axis`
/// is `at`, the other two coordinates (in cyclic order) from 0 to `n`.
fn flat_grid(axis: usize, at: f32, n: u32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let mut vertices = Vec::new();
    for i in 0..=n {
        for j in 0..=n {
            let mut p = [0.0; 3];
            (p[axis], p[u], p[v]) = (at, i as f32, j as f32);
            vertices.push(p);
        }
    }
    let at = |i: u32, j: u32| i * (n + 1) + j;
    let triangles = (0..n)
        .flat_map(|i| (0..n).map(move |j| (i, j)))
        .flat_map(|(i, j)| {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            [[a, b, c], [a, c, d]]
        })
        .collect();
    (vertices, triangles)
}

/// Each query's answers for `rays` with `t` in `range` on every SIMD path (which must agree
/// bit for bit): closest hits, occlusion, crossing counts.
fn answers(
    scene: &RaycastingScene,
    rays: &[[f32; 6]],
    range: (f32, f32),
) -> (Vec<ClosestHit>, Vec<bool>, Vec<i32>) {
    let options = QueryOptions::default();
    let (accel, _) = scene.prepare(&options).unwrap();
    let border = accel.borders(test_pool());
    let mut all = Vec::new();
    for path in supported_paths() {
        let run = (&*accel, &options);
        let mut hits = vec![None; rays.len()];
        closest_hits(path, run, (rays, range), &mut hits);
        let mut occluded = vec![false; rays.len()];
        occlusions(path, run, rays, range, &mut occluded);
        let mut counted = vec![0; rays.len()];
        counts(path, run, (&border, range), rays, &mut counted);
        all.push((hits, occluded, counted));
    }
    for other in &all[1..] {
        assert!(other == &all[0], "the SIMD paths disagree");
    }
    all.swap_remove(0)
}

/// Rays that meet the plane `axis = at` at distance `t = −s` (`s` from the plane along the
/// `axis` direction `sign`, pointing away from it), through the interiors of the squares of
/// `u` and `v` in `0 .. 2n` and `0 .. n` (off the edges by a quarter): 32 parallel rays
/// per direction, so that the counts go as packets too.
fn rays_away(axis: usize, at: f32, s: f32, sign: f32, n: u32) -> Vec<[f32; 6]> {
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let mut rays = Vec::new();
    for slope in [[0.0, 0.0], [0.3, -0.2], [-0.75, 0.5]] {
        for k in 0..32u32 {
            let (pu, pv) = (0.25 + (k % (2 * n)) as f32, 0.75 + (k / (2 * n)) as f32);
            let mut d = [0.0; 3];
            (d[axis], d[u], d[v]) = (sign, slope[0], slope[1]);
            // o + (−s)·d lands on (pu, pv) in the plane.
            let mut o = [0.0; 3];
            (o[axis], o[u], o[v]) = (at + sign * s, pu + s * slope[0], pv + s * slope[1]);
            rays.push([o[0], o[1], o[2], d[0], d[1], d[2]]);
        }
    }
    rays
}

#[test]
fn flat_boxes_behind_the_origin_are_entered_on_every_path() {
    // Planes at 0 (where the boxes' padding is tiny) and away from it, seen from up to 1000
    // behind: the exit scale of the box test must widen a negative exit distance too.
    let n = 4;
    let mut checked = 0;
    for axis in 0..3 {
        for at in [0.0, -1.0, 2.0] {
            let mut scene = RaycastingScene::new();
            let (vertices, triangles) = flat_grid(axis, at, n);
            scene.add_triangles(&vertices, &triangles).unwrap();
            // A placed copy beside it (u from n to 2n), in the same plane.
            let mut shift = [
                [1.0, 0.0, 0.0, 0.0],
                [0.0, 1.0, 0.0, 0.0],
                [0.0, 0.0, 1.0, 0.0],
            ];
            shift[(axis + 1) % 3][3] = n as f32;
            let move_by = [shift[0], shift[1], shift[2], [0.0, 0.0, 0.0, 1.0]];
            assert_eq!(scene.add_instance(0, &move_by), Ok(1));
            for s in [1.0, 10.0, 1000.0] {
                for sign in [1.0, -1.0] {
                    let rays = rays_away(axis, at, s, sign, n);
                    let case = format!("axis {axis}, plane at {at}, {s} behind, sign {sign}");
                    for range in [
                        (-2000.0, f32::INFINITY),
                        (-2000.0, 0.0),
                        (-s * 1.001, -s * 0.999),
                    ] {
                        let (hits, occluded, counted) = answers(&scene, &rays, range);
                        for (i, ray) in rays.iter().enumerate() {
                            let hit = hits[i].unwrap_or_else(|| {
                                panic!("{case}, {range:?}: ray {i} {ray:?} missed")
                            });
                            let u = ray[(axis + 1) % 3] - s * ray[3 + (axis + 1) % 3];
                            let geometry = u32::from(u > n as f32);
                            assert_eq!(hit.geometry, geometry, "{case}: ray {i}");
                            let t = hit.crossing.t;
                            assert!((t + s).abs() <= 1e-5 * s, "{case}: ray {i} at {t}");
                            assert!(occluded[i], "{case}, {range:?}: ray {i} not occluded");
                            assert_eq!(counted[i], 1, "{case}, {range:?}: ray {i}");
                            checked += 1;
                        }
                    }
                    // In front of the origin there is nothing.
                    let (hits, occluded, counted) = answers(&scene, &rays, (0.0, f32::INFINITY));
                    assert!(hits.iter().all(Option::is_none), "{case}");
                    assert!(!occluded.iter().any(|&o| o) && counted.iter().all(|&c| c == 0));
                }
            }
        }
    }
    assert_eq!(checked, 3 * 3 * 3 * 2 * 3 * 96);
}

#[test]
fn ties_behind_the_origin_go_to_the_smallest_id_on_every_path() {
    // Two identical flat grids: every hit is a tie at exactly the same t, which the smallest
    // geometry id wins wherever the walk finds the other one first, behind the origin as in
    // front of it.
    let n = 4;
    for at in [0.0, 3.0] {
        let mut scene = RaycastingScene::new();
        let (vertices, triangles) = flat_grid(2, at, 2 * n);
        for _ in 0..2 {
            scene.add_triangles(&vertices, &triangles).unwrap();
        }
        for (s, sign) in [(1.0, 1.0), (50.0, -1.0), (1000.0, 1.0)] {
            for (rays, range) in [
                (rays_away(2, at, s, sign, n), (-2000.0, f32::INFINITY)),
                (rays_away(2, at, -s, sign, n), (0.0, f32::INFINITY)),
            ] {
                let (hits, _, counted) = answers(&scene, &rays, range);
                for (i, hit) in hits.iter().enumerate() {
                    let hit = hit.unwrap_or_else(|| panic!("plane {at}, {s}: ray {i} missed"));
                    assert_eq!(hit.geometry, 0, "plane {at}, {s}, {range:?}: ray {i}");
                    assert_eq!(counted[i], 2, "plane {at}, {s}, {range:?}: ray {i}");
                }
            }
        }
    }
}
