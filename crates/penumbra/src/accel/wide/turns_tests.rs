//! Tests of `turns`: walks in turn answer every query as the walks of one ray at a time.

use std::sync::Arc;

use glam::Vec3;

use super::tree::{SlotHit, Stack, WideBvh};
use super::turns::{prepare, stream, Turns, INTERLEAVED};
use crate::accel::prim::boundary::boundaries;
use crate::accel::prim::boundary::Boundary;
use crate::accel::prim::watertight::PreparedRay;
use crate::accel::test_meshes::{icosphere, subdivided_cube, MeshData};
use crate::accel::wide::kernels::Listing;
use crate::accel::wide::levels::{Borders, WideLevels};
use crate::accel::Bvh;
use crate::geometry::{Geometry, Triangle};
use crate::pool::test_pool;
use crate::sampling::Rng;
use crate::simd::Isa;
use crate::simd::{dispatch, supported_paths, Kernel};

/// A sphere and a cube of one tree, the cube's vertices on a grid that rays meet exactly.
fn tree() -> WideBvh {
    let (mut positions, mut triangles): MeshData = icosphere(3);
    let (cube, cube_triangles) = subdivided_cube(4, glam::Mat3::IDENTITY);
    let base = positions.len() as u32;
    positions.extend(
        cube.iter()
            .map(|p| [p[0] * 1.5 + 2.0, p[1] * 1.5, p[2] * 1.5]),
    );
    triangles.extend(cube_triangles.iter().map(|t| t.map(|i| i + base)));
    let geometry = Geometry {
        positions: positions.into_iter().map(Vec3::from).collect(),
        triangles: (triangles.into_iter().enumerate())
            .map(|(i, vertices)| Triangle {
                vertices,
                material: 0,
                object: u32::from(i >= 1280),
                smooth: false,
            })
            .collect(),
        ..Geometry::default()
    };
    let bvh = Bvh::build(&geometry);
    let ids: Vec<u32> = (0..geometry.triangles.len() as u32).collect();
    WideBvh::from_bvh(
        bvh,
        |i| geometry.corners(i),
        |i| [geometry.triangles[i].object, ids[i]],
    )
}

/// Rays between random points around the two shapes, one in four from a point of the
/// cube's grid toward another, through its edges and vertices.
fn rays(n: usize) -> Vec<PreparedRay> {
    let mut rng = Rng::new(11, &[]);
    let mut point = |grid: bool| {
        let p = Vec3::from_array([0; 3].map(|_| 8.0 * rng.uniform() - 3.0));
        if grid {
            (p * 2.0).round() / 2.0
        } else {
            p
        }
    };
    (0..n)
        .filter_map(|i| {
            let (a, b) = (point(i % 4 == 0), point(i % 4 == 0));
            PreparedRay::new(a, b - a)
        })
        .collect()
}

/// Each ray's closest hit, occlusion and sorted crossings, alone (`K` = 1, the plain
/// walk) or `K` walks in turn ([`WideBvh::walk_stream`]), on one SIMD path.
struct Answers<'a, const K: usize> {
    tree: &'a WideBvh,
    border: &'a [Boundary],
    rays: &'a [[f32; 6]],
}

type Answer = (Option<SlotHit>, bool, Vec<(u32, u32, u32)>);

impl<const K: usize> Kernel for Answers<'_, K> {
    type Output = Vec<Answer>;

    fn run<const N: usize, I: Isa>(self) -> Vec<Answer> {
        let (tree, border, rays) = (self.tree, self.border, self.rays);
        let range = (0.0, 1.0);
        let mut out: Vec<Answer> = vec![(None, false, Vec::new()); rays.len()];
        if K == 1 {
            let mut stack = Stack::default();
            for (ray, o) in rays.iter().zip(&mut out) {
                let Some(r) = prepare(ray) else { continue };
                o.0 = tree.closest::<I>(&r, range, None, &mut stack);
                o.1 = tree.occluded::<I>(&r, range, None, &mut stack);
                let f = &mut |h: SlotHit| o.2.push(key(h));
                tree.each_hit::<I>(&r, range, (border, None), &mut stack, f);
            }
        } else {
            let mut turns = Turns::<K>::new();
            // Chunks of 7 rays, for a stream that crosses them.
            let rays = || stream(rays, (0..rays.len().div_ceil(7), 7), || false);
            tree.closest_stream::<K, I>(rays(), range, None, turns.stacks(), |i, h| out[i].0 = h);
            tree.occluded_stream::<K, I>(rays(), range, None, turns.stacks(), |i, o| out[i].1 = o);
            let calls = (
                |_| Vec::new(),
                |found: &mut Vec<_>, h| found.push(key(h)),
                |i: usize, found| out[i].2 = found,
            );
            tree.each_hit_stream::<K, _, I>(rays(), range, (border, None), turns.stacks(), calls);
        }
        for o in &mut out {
            o.2.sort_unstable();
        }
        out
    }
}

/// A crossing as bits: its `t` and its triangle.
fn key(h: SlotHit) -> (u32, u32, u32) {
    (h.crossing.t.to_bits(), h.geometry, h.primitive)
}

#[test]
fn rays_in_turns_answer_as_each_ray_alone() {
    let tree = tree();
    let corners: Vec<_> = tree.tris().iter().map(|t| t.corners()).collect();
    let by_triangle = boundaries(&corners, None);
    let mut rays: Vec<[f32; 6]> = rays(4001).iter().map(as_array).collect();
    // Rays that hit nothing by definition, amid the others.
    rays[5] = [0.0; 6];
    rays[402][4] = f32::NAN;
    let (mut hits, mut occluded, mut crossings) = (0, 0, 0);
    for path in supported_paths() {
        let (border, rays) = (&by_triangle[..], &rays[..]);
        let tree = &tree;
        let alone = dispatch(path, Answers::<1> { tree, border, rays });
        let four = dispatch(path, Answers::<4> { tree, border, rays });
        let turns = dispatch(path, Answers::<INTERLEAVED> { tree, border, rays });
        assert_eq!(alone.len(), rays.len());
        for (i, a) in alone.iter().enumerate() {
            assert_eq!(a, &four[i], "ray {i} on {path:?}");
            assert_eq!(a, &turns[i], "ray {i} on {path:?}");
            hits += usize::from(a.0.is_some());
            occluded += usize::from(a.1);
            crossings += a.2.len();
        }
        assert_eq!(
            (&alone[5], &alone[402]),
            (&(None, false, vec![]), &(None, false, vec![]))
        );
    }
    assert!(
        hits > 1000 && occluded == hits && crossings > 2000,
        "{hits} hits, {occluded} occluded, {crossings} crossings"
    );
}

/// A prepared ray as `[ox, oy, oz, dx, dy, dz]`.
fn as_array(r: &PreparedRay) -> [f32; 6] {
    let (o, d) = (r.origin, r.inv_dir.recip());
    [o.x, o.y, o.z, d.x, d.y, d.z]
}

/// `list_intersections`' kernel with `K` rays a turn, on one SIMD path.
struct Lists<'a, const K: usize> {
    levels: &'a WideLevels,
    border: &'a Borders<'a>,
    rays: &'a [[f32; 6]],
}

impl<const K: usize> Kernel for Lists<'_, K> {
    type Output = (Vec<u32>, Vec<SlotHit>);

    fn run<const N: usize, I: Isa>(self) -> (Vec<u32>, Vec<SlotHit>) {
        let options = Flag::never();
        let (accel, border, rays) = (self.levels, self.border, self.rays);
        let listing = Listing {
            accel,
            border,
            rays,
            options: &options,
        };
        listing
            .list::<K, I>()
            .expect("not cancelled, and memory enough")
    }
}

#[test]
fn crossings_listed_in_turns_are_those_listed_one_ray_at_a_time() {
    let levels = WideLevels::new(Arc::new(tree()), None, Vec::new(), Vec::new(), None);
    let border = levels.borders(test_pool());
    let mut rays: Vec<[f32; 6]> = rays(1001).iter().map(as_array).collect();
    rays[6] = [f32::NAN; 6];
    for path in supported_paths() {
        let (border, rays) = (&border, &rays[..]);
        let one = dispatch(
            path,
            Lists::<1> {
                levels: &levels,
                border,
                rays,
            },
        );
        let four = dispatch(
            path,
            Lists::<4> {
                levels: &levels,
                border,
                rays,
            },
        );
        assert_eq!(one, four, "{path:?}");
        assert_eq!((one.0.len(), one.0[6]), (rays.len(), 0));
        assert!(one.1.len() > 500, "{} crossings", one.1.len());
    }
}

/// The queries' kernels on a tree whose walks go in turn give each ray the answers they
/// give one ray at a time: rays that cannot hit (amid a stream) included.
#[test]
fn the_kernels_answer_alike_in_turns_and_one_ray_at_a_time() {
    use crate::accel::wide::kernels::{closest_hits, counts, occlusions};
    let one = WideLevels::new(Arc::new(tree()), None, Vec::new(), Vec::new(), None);
    let turns = WideLevels::new(
        Arc::new(tree().interleaved()),
        None,
        Vec::new(),
        Vec::new(),
        None,
    );
    assert!(turns.own().interleaves() && !one.own().interleaves());
    let mut rays: Vec<[f32; 6]> = rays(3001).iter().map(as_array).collect();
    rays[7] = [0.0; 6];
    rays[1500][3] = f32::NAN;
    let options = Flag::never();
    for path in supported_paths() {
        let answers = |levels: &WideLevels| {
            let border = levels.borders(test_pool());
            let range = (0.0, f32::INFINITY);
            let mut hits = vec![None; rays.len()];
            closest_hits(path, (levels, &options), (&rays, range), &mut hits);
            let mut short = vec![None; rays.len()];
            closest_hits(path, (levels, &options), (&rays, (0.0, 0.5)), &mut short);
            let mut occluded = vec![false; rays.len()];
            occlusions(path, (levels, &options), &rays, (0.0, 0.5), &mut occluded);
            let mut counted = vec![0; rays.len()];
            counts(
                path,
                (levels, &options),
                (&border, range),
                &rays,
                &mut counted,
            );
            let listing = Listing {
                accel: levels,
                border: &border,
                rays: &rays,
                options: &options,
            };
            let listed = dispatch(path, listing).expect("not cancelled");
            (hits, short, occluded, counted, listed)
        };
        let (a, b) = (answers(&one), answers(&turns));
        assert_eq!(a, b, "{path:?}");
        let hits = a.0.iter().filter(|h| h.is_some()).count();
        let occluded = a.2.iter().filter(|&&o| o).count();
        assert!(
            hits > 1000 && occluded > 300,
            "{hits} hits, {occluded} occluded"
        );
        assert_eq!((a.0[7], a.3[7], a.4 .0[1500]), (None, 0, 0));
        assert_eq!(a.3.iter().sum::<i32>() as usize, a.4 .1.len());
    }
}

#[test]
fn only_trees_larger_than_the_caches_interleave() {
    assert!(!tree().interleaves());
}

/// A query's flag, raised from look `.1` on (counting from 1): `usize::MAX` never.
struct Flag(std::cell::Cell<usize>, usize);

/// What a cancelled query gives.
#[derive(Debug, PartialEq)]
struct Cancelled;

impl Flag {
    fn never() -> Flag {
        Flag(std::cell::Cell::new(0), usize::MAX)
    }

    fn from_second_look() -> Flag {
        Flag(std::cell::Cell::new(0), 2)
    }
}

impl crate::accel::wide::control::Control for Flag {
    type Error = Cancelled;

    fn cancelled(&self) -> bool {
        self.0.set(self.0.get() + 1);
        self.0.get() >= self.1
    }

    fn cancel_error(&self) -> Cancelled {
        Cancelled
    }

    fn grow<T>(&self, v: &mut Vec<T>, n: usize, _: &'static str) -> Result<(), Cancelled> {
        v.reserve(n);
        Ok(())
    }
}

/// A listing whose walks go in turn stops at the first look at the flag past the start of
/// a cancelled query, and says it was cancelled; so does a count, which leaves the rays past
/// that look uncounted.
#[test]
fn a_stream_stops_when_its_query_is_cancelled() {
    use crate::accel::wide::kernels::Counts;
    let levels = WideLevels::new(
        Arc::new(tree().interleaved()),
        None,
        Vec::new(),
        Vec::new(),
        None,
    );
    let border = levels.borders(test_pool());
    let rays: Vec<[f32; 6]> = rays(2001).iter().map(as_array).collect();
    for path in supported_paths() {
        let options = Flag::from_second_look();
        let listing = Listing {
            accel: &levels,
            border: &border,
            rays: &rays,
            options: &options,
        };
        let listed = dispatch(path, listing);
        assert!(listed == Err(Cancelled), "{path:?}");
        let (mut out, options) = (vec![-1; rays.len()], Flag::from_second_look());
        let counts = Counts::<_, false> {
            accel: &levels,
            range: (0.0, f32::INFINITY),
            border: &border,
            options: &options,
            rays: &rays,
            out: &mut out,
        };
        dispatch(path, counts);
        let counted = out.iter().filter(|&&n| n >= 0).count();
        assert!(
            counted < rays.len() / 4,
            "{counted} rays counted on {path:?}"
        );
    }
}
