//! The four ray queries agree on rays aimed exactly at edges and vertices, on the border of
//! open meshes as inside closed ones: a ray that `cast_rays` hits is occluded, and it crosses
//! the surface as many times as `count_intersections` counts and `list_intersections` lists,
//! with each edge and vertex counted once (Open3D counts a lone triangle's edge once).
//!
//! The meshes are height fields over a small grid (random heights, random diagonals, random
//! holes), open, or closed by a floor and walls; the rays come steeply from above or below,
//! so that the surface never folds along them: a ray that meets an open height field crosses
//! it exactly once. Coordinates are small dyadic numbers and the rays' vertical extent a
//! power of two, so that the watertight test's sheared frame is exact and most rays pass
//! exactly through the vertex or edge point they aim at; the same scenes scaled by powers of
//! two up to 2³⁶ (their rays then start up to 8e11 away; 1e12 is the largest coordinate
//! allowed) answer the same.

use glam::Vec3;
use proptest::prelude::*;

use super::*;
use crate::accel::test_meshes::MeshData;

/// A height field: `heights[j][i]` (in quarters) at grid point `(i, j)`, each cell's diagonal
/// from `diagonal`, and the cell triangles kept where `keep` says.
#[derive(Clone, Debug)]
struct Field {
    heights: Vec<Vec<u8>>,
    diagonal: Vec<bool>,
    keep: Vec<bool>,
}

fn arb_field() -> impl Strategy<Value = Field> {
    (2usize..5).prop_flat_map(|n| {
        let cells = n * n * 2;
        (
            prop::collection::vec(prop::collection::vec(0u8..3, n + 1), n + 1),
            prop::collection::vec(any::<bool>(), n * n),
            prop::collection::vec(prop::bool::weighted(0.8), cells),
        )
            .prop_map(|(heights, diagonal, keep)| Field {
                heights,
                diagonal,
                keep,
            })
    })
}

impl Field {
    fn n(&self) -> usize {
        self.heights.len() - 1
    }

    fn point(&self, i: usize, j: usize) -> [f32; 3] {
        [i as f32, j as f32, self.heights[j][i] as f32 * 0.25]
    }

    /// The surface; with `closed`, every cell is kept and a floor at z = −1 and walls close
    /// it (all wound the same way around the solid).
    fn mesh(&self, closed: bool) -> MeshData {
        let n = self.n();
        let mut v: Vec<[f32; 3]> = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                v.push(self.point(i, j));
            }
        }
        let floor = v.len() as u32;
        for j in 0..=n {
            for i in 0..=n {
                v.push([i as f32, j as f32, -1.0]);
            }
        }
        let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let mut t = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let q = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
                let cell = j * n + i;
                let pair = if self.diagonal[cell] {
                    [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
                } else {
                    [[q[0], q[1], q[3]], [q[1], q[2], q[3]]]
                };
                for (k, tri) in pair.into_iter().enumerate() {
                    if closed || self.keep[2 * cell + k] {
                        t.push(tri);
                    }
                    if closed {
                        t.push([tri[2] + floor, tri[1] + floor, tri[0] + floor]);
                    }
                }
            }
        }
        if closed {
            // The rim, counter-clockwise seen from above, and a wall under each rim edge.
            let rim: Vec<u32> = (0..n)
                .map(|i| at(i, 0))
                .chain((0..n).map(|j| at(n, j)))
                .chain((0..n).map(|i| at(n - i, n)))
                .chain((0..n).map(|j| at(0, n - j)))
                .collect();
            for k in 0..rim.len() {
                let (a, b) = (rim[k], rim[(k + 1) % rim.len()]);
                t.push([a, a + floor, b + floor]);
                t.push([a, b + floor, b]);
            }
        }
        (v, t)
    }

    /// Points to aim at: every vertex of the top, and points a half and a quarter along
    /// every grid edge and cell diagonal, whether or not a kept triangle has them.
    fn targets(&self) -> Vec<Vec3> {
        let n = self.n();
        let p = |i: usize, j: usize| Vec3::from(self.point(i, j));
        let mut segments = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                if i < n {
                    segments.push((p(i, j), p(i + 1, j)));
                }
                if j < n {
                    segments.push((p(i, j), p(i, j + 1)));
                }
                if i < n && j < n {
                    segments.push(if self.diagonal[j * n + i] {
                        (p(i, j), p(i + 1, j + 1))
                    } else {
                        (p(i + 1, j), p(i, j + 1))
                    });
                }
            }
        }
        let vertices = (0..=n).flat_map(|j| (0..=n).map(move |i| (i, j)));
        vertices
            .map(|(i, j)| p(i, j))
            .chain(
                segments
                    .into_iter()
                    .flat_map(|(a, b)| [0.5, 0.25].map(|s| a + s * (b - a))),
            )
            .collect()
    }
}

/// The four queries on `rays`: for each ray, whether `cast_rays` hits and its `t`, whether
/// it is occluded, its count, and its listed `t`s.
struct Answers {
    hit: Vec<Option<f32>>,
    occluded: Vec<bool>,
    counts: Vec<i32>,
    listed: Vec<Vec<f32>>,
}

fn ask(scene: &RaycastingScene, rays: &[[f32; 6]]) -> Answers {
    let options = QueryOptions {
        threads: 2,
        cancel: None,
    };
    let cast = scene.cast_rays(rays, &options).unwrap();
    let list = scene.list_intersections(rays, &options).unwrap();
    Answers {
        hit: (0..rays.len())
            .map(|i| (cast.geometry_ids[i] != INVALID_ID).then_some(cast.t_hit[i]))
            .collect(),
        occluded: scene
            .test_occlusions(rays, 0.0, f32::INFINITY, &options)
            .unwrap(),
        counts: scene.count_intersections(rays, &options).unwrap(),
        listed: (0..rays.len())
            .map(|i| {
                let (lo, hi) = (list.ray_splits[i], list.ray_splits[i + 1]);
                list.t_hit[lo as usize..hi as usize].to_vec()
            })
            .collect(),
    }
}

/// Rays through each target, steeply from above (and from below when `both`), their `t = 1`
/// at the target and their vertical extent 8 (so the shear is exact); `offsets` shift the
/// origin sideways by half units, at most 3.
fn aimed(targets: &[Vec3], offsets: &[(i8, i8)], both: bool, scale: f32) -> Vec<[f32; 6]> {
    let mut rays = Vec::new();
    for (k, p) in targets.iter().enumerate() {
        let (a, b) = offsets[k % offsets.len()];
        for dz in [8.0f32, -8.0] {
            if dz < 0.0 && !both {
                continue;
            }
            let o = *p + Vec3::new(a as f32 * 0.5, b as f32 * 0.5, dz);
            let d = *p - o;
            rays.push([o.x, o.y, o.z, d.x, d.y, d.z].map(|c| c * scale));
        }
    }
    rays
}

/// What every scene's answers must satisfy: the queries agree with one another.
fn check_agreement(a: &Answers, rays: &[[f32; 6]]) {
    for (i, ray) in rays.iter().enumerate() {
        let (hit, count, listed) = (a.hit[i], a.counts[i], &a.listed[i]);
        assert_eq!(a.occluded[i], hit.is_some(), "occlusion of {ray:?}");
        assert_eq!(count as usize, listed.len(), "count and list of {ray:?}");
        assert!(listed.windows(2).all(|w| w[0] <= w[1]), "{listed:?}");
        match hit {
            None => assert_eq!(count, 0, "a miss that crosses: {ray:?}"),
            Some(t) => {
                if let Some(&first) = listed.first() {
                    assert!(t <= first * (1.0 + 1e-6), "{t} after {first}: {ray:?}");
                }
            }
        }
    }
}

/// Rays that pass exactly through an edge or vertex of the closed `mesh`: more than one
/// triangle holds a hit under the inclusive rule.
fn on_edges(mesh: &MeshData, rays: &[[f32; 6]]) -> usize {
    use crate::accel::prim::watertight::{EdgeRule, PreparedRay, SoaTriangle};
    let tris: Vec<SoaTriangle> = mesh
        .1
        .iter()
        .map(|t| SoaTriangle::new(&t.map(|v| glam::Vec3A::from(mesh.0[v as usize]))))
        .collect();
    rays.iter()
        .filter(|r| {
            let Some(ray) = PreparedRay::new(Vec3::from_slice(&r[..3]), Vec3::from_slice(&r[3..]))
            else {
                return false;
            };
            let inclusive = |t: &SoaTriangle| {
                ray.hit(t, Default::default(), 0.0, 2.0, EdgeRule::Inclusive)
                    .is_some()
            };
            tris.iter().filter(|t| inclusive(t)).count() > 1
        })
        .count()
}

fn scaled(mesh: &MeshData, scale: f32) -> MeshData {
    let v = mesh.0.iter().map(|p| p.map(|c| c * scale)).collect();
    (v, mesh.1.clone())
}

/// Powers of two from 2⁻⁶ to 2³⁶ (the rays' origins then reach 8e11, near the largest
/// coordinate, 1e12): scaling is exact, so the answers must not change.
const SCALES: [f32; 4] = [1.0, 1.0 / 64.0, 8_589_934_592.0, 68_719_476_736.0];

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn queries_agree_at_the_edges_of_open_height_fields(
        field in arb_field(),
        offsets in prop::collection::vec((-6i8..=6, -6i8..=6), 1..8),
    ) {
        let mesh = field.mesh(false);
        let rays = aimed(&field.targets(), &offsets, true, 1.0);
        // Most rays pass exactly through an edge or vertex of the whole grid.
        let exact = on_edges(&field.mesh(true), &rays);
        prop_assert!(exact * 4 >= rays.len(), "{} of {} rays on edges", exact, rays.len());
        let mut first: Option<Vec<bool>> = None;
        for scale in SCALES {
            let mut scene = RaycastingScene::new();
            scene.add_triangles(&scaled(&mesh, scale).0, &mesh.1).unwrap();
            let rays = aimed(&field.targets(), &offsets, true, scale);
            let a = ask(&scene, &rays);
            check_agreement(&a, &rays);
            for (i, ray) in rays.iter().enumerate() {
                // A height field seen steeply is met once or not at all.
                let want = i32::from(a.hit[i].is_some());
                prop_assert_eq!(a.counts[i], want, "scale {}, ray {:?}", scale, ray);
            }
            // The same answers at every scale.
            let hits: Vec<bool> = a.hit.iter().map(Option::is_some).collect();
            match &first {
                None => first = Some(hits),
                Some(h) => prop_assert_eq!(h, &hits, "scale {}", scale),
            }
        }
    }

    #[test]
    fn queries_agree_at_the_edges_of_closed_height_fields(
        field in arb_field(),
        offsets in prop::collection::vec((-6i8..=6, -6i8..=6), 1..8),
    ) {
        let mesh = field.mesh(true);
        let targets = field.targets();
        for scale in SCALES {
            let mut scene = RaycastingScene::new();
            scene.add_triangles(&scaled(&mesh, scale).0, &mesh.1).unwrap();
            let rays = aimed(&targets, &offsets, false, scale);
            let a = ask(&scene, &rays);
            check_agreement(&a, &rays);
            let n = field.n() as f32;
            for (i, ray) in rays.iter().enumerate() {
                prop_assert!(a.counts[i] % 2 == 0, "odd count {} of {:?}", a.counts[i], ray);
                // Aimed at the top away from the rim, a ray enters there and leaves by the
                // floor.
                let p = targets[i];
                if p.x > 0.0 && p.x < n && p.y > 0.0 && p.y < n {
                    prop_assert_eq!(a.counts[i], 2, "scale {}, ray {:?}", scale, ray);
                    let t = a.hit[i].unwrap();
                    prop_assert!((t - 1.0).abs() < 1e-5, "t {} of {:?}", t, ray);
                }
            }
        }
    }
}

#[test]
fn a_lone_triangle_and_a_fan_count_their_border_once() {
    // (vertices, triangles, points aimed at): a lone triangle's corners and edges, a square's
    // corners, sides and diagonal, and the tip of a fan of three triangles spanning 300°.
    let fan: Vec<[f32; 3]> = std::iter::once([0.0, 0.0, 0.0])
        .chain((0..4).map(|k| {
            let a = (k as f32 * 100.0).to_radians();
            [a.cos(), a.sin(), 0.0]
        }))
        .collect();
    // (name, vertices, triangles, points aimed at)
    type Case = (&'static str, Vec<[f32; 3]>, Vec<[u32; 3]>, Vec<[f32; 3]>);
    let cases: [Case; 3] = [
        (
            "lone triangle",
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0, 1, 2]],
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.5, 0.0, 0.0],
                [0.0, 0.5, 0.0],
                [0.5, 0.5, 0.0],
            ],
        ),
        (
            "square",
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            vec![[0, 1, 2], [0, 2, 3]],
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.5, 0.0, 0.0],
                [0.5, 0.5, 0.0],
                [0.25, 0.25, 0.0],
            ],
        ),
        (
            "fan",
            fan,
            vec![[0, 1, 2], [0, 2, 3], [0, 3, 4]],
            vec![[0.0; 3]],
        ),
    ];
    // Straight down, oblique, and from below.
    let dirs = [[0.0, 0.0, -1.0], [0.25, -0.5, -1.0], [-0.125, 0.25, 2.0]];
    for (name, v, t, points) in cases {
        let mut scene = RaycastingScene::new();
        scene.add_triangles(&v, &t).unwrap();
        let rays: Vec<[f32; 6]> = points
            .iter()
            .flat_map(|p| {
                dirs.map(|d| {
                    let o = Vec3::from(*p) - Vec3::from(d);
                    [o.x, o.y, o.z, d[0], d[1], d[2]]
                })
            })
            .collect();
        let a = ask(&scene, &rays);
        for (i, ray) in rays.iter().enumerate() {
            let near_one = |t: f32| (t - 1.0).abs() < 1e-6;
            assert!(a.hit[i].is_some_and(near_one), "{name}: {ray:?}");
            assert!(a.occluded[i], "{name}: {ray:?}");
            assert_eq!(a.counts[i], 1, "{name}: {ray:?}");
            assert!(a.listed[i].len() == 1 && near_one(a.listed[i][0]));
        }
    }
}

#[test]
fn far_scenes_answer_as_near_ones_or_are_refused() {
    // Two triangles at each scale up to 1e12, rays of short, unit and long directions from about
    // the scale away: cast_rays and count_intersections agree, and the closest points are
    // the points below, not a corner (f32 products overflowed from 1e10 on).
    let options = QueryOptions::default();
    for s in [1.0f32, 1e8, 1e10, 1e11, 1e12] {
        let mut scene = RaycastingScene::new();
        let v = [
            [0.0, 0.0, 0.0],
            [s, 0.0, 0.0],
            [0.0, s, 0.0],
            [s, s, 0.25 * s],
        ];
        scene.add_triangles(&v, &[[0, 1, 2], [1, 3, 2]]).unwrap();
        let o = Vec3::new(0.3, 0.2, 0.9) * s;
        let mut rays = Vec::new();
        for i in 1..20 {
            for j in 1..20 {
                let d = Vec3::new(i as f32 / 20.0 * s, j as f32 / 20.0 * s, 0.0) - o;
                let unit = d.normalize();
                rays.push([o.x, o.y, o.z, d.x, d.y, d.z]);
                rays.push([o.x, o.y, o.z, unit.x, unit.y, unit.z]);
                let short = unit * 1e-3;
                rays.push([o.x, o.y, o.z, short.x, short.y, short.z]);
            }
        }
        let cast = scene.cast_rays(&rays, &options).unwrap();
        let counts = scene.count_intersections(&rays, &options).unwrap();
        for (i, ray) in rays.iter().enumerate() {
            assert!(cast.t_hit[i].is_finite(), "scale {s:e}: {ray:?} missed");
            assert_eq!(counts[i], 1, "scale {s:e}: {ray:?}");
        }
        let q = [
            [0.25, 0.25, 1.0],
            [0.25, 0.25, -0.5],
            [0.5, -1.0, 0.0],
            [9.0, 9.0, 0.0],
        ]
        .map(|p| p.map(|c| c * s));
        let want = [
            [0.25, 0.25, 0.0],
            [0.25, 0.25, 0.0],
            [0.5, 0.0, 0.0],
            [1.0, 1.0, 0.25],
        ];
        let closest = scene.compute_closest_points(&q, &options).unwrap();
        for (got, want) in closest.points.iter().zip(want) {
            let (got, want) = (Vec3::from(*got), Vec3::from(want) * s);
            assert!(
                got.distance(want) <= 1e-5 * s,
                "scale {s:e}: {got} for {want}"
            );
        }
        // Query points far beyond the scene still find it.
        let far = scene
            .compute_distance(&[[0.0, 0.0, 1e30]], &options)
            .unwrap();
        assert!((far[0] - 1e30).abs() <= 1e24, "{}", far[0]);
    }
    // Beyond 1e12: vertices, ray origins and vote points are refused, naming which.
    let mut scene = RaycastingScene::new();
    let big = [[0.0, 0.0, 0.0], [2e12, 0.0, 0.0], [0.0, 1.0, 0.0]];
    fn beyond<T>(what: &'static str, index: usize) -> Result<T, RaycastError> {
        Err(RaycastError::Beyond { what, index })
    }
    assert_eq!(scene.add_triangles(&big, &[[0, 1, 2]]), beyond("vertex", 1));
    scene
        .add_triangles(
            &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            &[[0, 1, 2]],
        )
        .unwrap();
    let mut rays = vec![[0.25, 0.25, 1.0, 0.0, 0.0, -1.0]; 3000];
    rays[2500][2] = -3e12;
    rays[2900][0] = 3e12;
    assert_eq!(
        scene.cast_rays(&rays, &options).map(|_| ()),
        beyond("ray", 2500)
    );
    assert_eq!(
        scene.cast_rays_rows(&rays, 100, &options).map(|_| ()),
        beyond("ray", 2500)
    );
    let occluded = scene.test_occlusions(&rays, 0.0, f32::INFINITY, &options);
    assert_eq!(occluded.map(|_| ()), beyond("ray", 2500));
    assert_eq!(
        scene.count_intersections(&rays, &options).map(|_| ()),
        beyond("ray", 2500)
    );
    assert_eq!(
        scene.list_intersections(&rays, &options).map(|_| ()),
        beyond("ray", 2500)
    );
    let points = [[0.0; 3], [0.0, 5e12, 0.0]];
    let occupancy = scene.compute_occupancy(&points, 1, &options);
    assert_eq!(occupancy.map(|_| ()), beyond("query point", 1));
    // Non-finite rays still just miss.
    let nan = [[f32::NAN, 0.0, 1.0, 0.0, 0.0, -1.0]];
    assert_eq!(scene.count_intersections(&nan, &options), Ok(vec![0]));
}
