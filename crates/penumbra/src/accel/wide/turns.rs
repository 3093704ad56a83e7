//! Rays walked in turns: the single-ray walk ([`WideBvh::walk`]) of a few rays at once, one
//! step of each in turn, for the incoherent queries on trees larger than the caches.
//!
//! An incoherent ray's walk through such a tree waits on memory more than it computes: each
//! node and leaf it visits is a cache miss whose address depends on the visit before.
//! [`INTERLEAVED`] independent walks side by side keep as many misses in flight. The visit of
//! each ray is exactly the one it makes alone (its own stack, `t_max` and hits), so every
//! answer is the single-ray query's, bit for bit, whatever `K`; only the order in which the
//! rays' steps run changes.

use glam::Vec3;

use super::group::TriangleGroup;
use super::tree::{found_hit, tie_bound, Found, Order, SlotHit, Stack, WideBvh};
use crate::accel::prim::boundary::Boundary;
use crate::accel::prim::watertight::{Crossing, EdgeRule, PreparedRay};
use crate::accel::AlphaTests;
use crate::simd::Isa;

/// The size of a tree past which its single-ray walks go [`INTERLEAVED`] rays at a time
/// ([`WideBvh::interleaves`]). Measured on an AMD EPYC with 2 MiB of L2 per core and a 32 MiB
/// L3, 1 M rays on 2 threads (`examples/raycast_workload`), four rays in turn against one:
/// the Stanford bunny (4.9 MiB of nodes and triangles) went 0.83–0.86× as fast and a 100k-
/// triangle skull (7.5 MiB) 0.75–0.88×: the caches serve them, and the turns' bookkeeping
/// has no misses to overlap. A 150k-triangle blob (10.7 MiB) was about even (occlusion
/// 0.91×, closest hits 1.07×, medians of 5 pairs); blobs of 250k, 450k and 1M triangles
/// (18, 32 and 72 MiB) went 1.05–1.2×, 1.1–1.4× and 1.24–1.27× as fast.
pub(crate) const INTERLEAVE_BYTES: usize = 16 << 20;

/// Rays whose walks go in turn through a tree larger than [`INTERLEAVE_BYTES`]. Eight
/// against four, on an AMD EPYC with AVX-512 (1 MiB of L2 per core), 2 threads, medians of 5
/// interleaved pairs: the 1M-triangle blob's occlusion 1.10–1.22×, closest hits 1.09–1.10×,
/// counting 0.98–1.06× (1.04× on 1 thread); a 250k-triangle blob 1.00–1.06×. Twelve and
/// sixteen were slower than eight (0.7–0.9× on counting and occlusion).
pub(crate) const INTERLEAVED: usize = 8;

impl WideBvh {
    /// True when a walk of this tree should interleave rays ([`WideBvh::walk_many`]): when
    /// its nodes and triangles take more than [`INTERLEAVE_BYTES`].
    pub(crate) fn interleaves(&self) -> bool {
        self.walked_bytes() > INTERLEAVE_BYTES
    }

    /// [`WideBvh::closest`] of `K` rays, their walks interleaved ([`WideBvh::walk_many`]).
    #[inline(always)]
    pub fn closest_many<const K: usize, I: Isa>(
        &self,
        rays: [&PreparedRay; K],
        range: (f32, f32),
        alpha: Option<&AlphaTests>,
        stacks: [&mut Stack; K],
    ) -> [Option<SlotHit>; K] {
        self.first_hits::<K, false, I>(rays, range, alpha, stacks)
            .map(|hit| hit.map(found_hit))
    }

    /// [`WideBvh::occluded`] of `K` rays, their walks interleaved ([`WideBvh::walk_many`]).
    #[inline(always)]
    pub fn occluded_many<const K: usize, I: Isa>(
        &self,
        rays: [&PreparedRay; K],
        range: (f32, f32),
        alpha: Option<&AlphaTests>,
        stacks: [&mut Stack; K],
    ) -> [bool; K] {
        self.first_hits::<K, true, I>(rays, range, alpha, stacks)
            .map(|hit| hit.is_some())
    }

    /// For each of `K` rays, the hit [`WideBvh::keep`] keeps: the closest, or when `ANY` the
    /// first found.
    #[inline(always)]
    fn first_hits<'a, const K: usize, const ANY: bool, I: Isa>(
        &'a self,
        rays: [&PreparedRay; K],
        (t_min, t_max): (f32, f32),
        alpha: Option<&AlphaTests>,
        stacks: [&mut Stack; K],
    ) -> [Option<Found<'a>>; K] {
        let mut best = [None; K];
        let bound = |t| if ANY { t } else { tie_bound(t) };
        let order = if ANY { Order::Lanes } else { Order::Nearest };
        let tests = (t_min, &bound, order, (EdgeRule::Inclusive, &[][..]));
        self.walk_many::<K, I>(rays, &mut [t_max; K], tests, stacks, |k, g, lane, c, t| {
            self.keep::<ANY>(&mut best[k], alpha, (g, lane, c), t)
        });
        best
    }

    /// The one walk of the wide tree for `K` rays at once ([`WideBvh::walk`] of each): ray
    /// `k` has its own `t_max[k]` and stack, and `hit(k, …)` gets its hits.
    ///
    /// The rays take one step each in turn, so that the loads of one ray's nodes and
    /// triangles overlap the others' tests: a walk through a tree larger than the caches waits
    /// on memory more than it computes. Each ray sees exactly the visit it would see alone.
    #[allow(clippy::type_complexity)]
    #[inline(always)]
    fn walk_many<'a, const K: usize, I: Isa>(
        &'a self,
        rays: [&PreparedRay; K],
        t_max: &mut [f32; K],
        tests: (f32, &impl Fn(f32) -> f32, Order, (EdgeRule, &[Boundary])),
        stacks: [&mut Stack; K],
        mut hit: impl FnMut(usize, &'a TriangleGroup, usize, Crossing, &mut f32) -> bool,
    ) {
        let mut k = 0;
        let mut walkers = stacks.map(|stack| {
            let ray = rays[k];
            k += 1;
            stack.start(self.wide());
            let [o, inv] = [ray.origin, ray.inv_dir].map(|v| v.to_array());
            (ray, o, inv, stack, true)
        });
        let mut live = K;
        while live != 0 {
            for (k, (ray, o, inv, stack, walking)) in walkers.iter_mut().enumerate() {
                if *walking {
                    let mut hit = |g, lane, c, t: &mut f32| hit(k, g, lane, c, t);
                    let ray = (*ray, &*o, &*inv);
                    *walking = self.step::<I>(ray, &mut t_max[k], tests, stack, &mut hit);
                    live -= usize::from(!*walking);
                }
            }
        }
    }

    /// [`WideBvh::each_hit`] of `K` rays, their walks interleaved ([`WideBvh::walk_many`]):
    /// `f(k, hit)` for each hit of ray `k`.
    #[inline(always)]
    pub fn each_hit_many<const K: usize, I: Isa>(
        &self,
        rays: [&PreparedRay; K],
        (t_min, t_max): (f32, f32),
        (border, alpha): (&[Boundary], Option<&AlphaTests>),
        stacks: [&mut Stack; K],
        f: &mut impl FnMut(usize, SlotHit),
    ) {
        let tests = (t_min, &|t| t, Order::Free, (EdgeRule::Owned, border));
        self.walk_many::<K, I>(rays, &mut [t_max; K], tests, stacks, |k, g, lane, c, _| {
            self.each(alpha, (g, lane, c), &mut |hit| f(k, hit));
            true
        });
    }
}

/// The ray `[ox, oy, oz, dx, dy, dz]` prepared for traversal; `None` hits nothing.
#[inline(always)]
pub(crate) fn prepare(ray: &[f32; 6]) -> Option<PreparedRay> {
    PreparedRay::new(
        Vec3::new(ray[0], ray[1], ray[2]),
        Vec3::new(ray[3], ray[4], ray[5]),
    )
}

/// The stacks of the rays of a turn ([`in_turns`]), made by the first turn: a query on a
/// tree that walks one ray at a time never needs them.
#[derive(Default)]
pub(crate) struct Turns(Vec<Stack>);

impl Turns {
    /// The stacks of a turn of `K` rays (`None` past [`INTERLEAVED`]).
    pub(crate) fn of<const K: usize>(&mut self) -> Option<[&mut Stack; K]> {
        const { assert!(K >= 1 && K <= INTERLEAVED) };
        if self.0.is_empty() {
            self.0 = (0..INTERLEAVED).map(|_| Stack::default()).collect();
        }
        let (stacks, _) = self.0.split_first_chunk_mut::<K>()?;
        Some(stacks.each_mut())
    }
}

/// A single-ray query of each ray of `rays` into its slot of `out`: with `K` of 1 one ray
/// at a time (`one`, given `None` for a ray that hits nothing), else `K` rays at a time with
/// their walks interleaved ([`WideBvh::walk_many`], through `many`) where all `K` are rays.
#[inline(always)]
pub(crate) fn in_turns<const K: usize, T>(
    (rays, out): (&[[f32; 6]], &mut [T]),
    (stack, turns): (&mut Stack, &mut Turns),
    mut many: impl FnMut([&PreparedRay; K], [&mut Stack; K], &mut [T]),
    mut one: impl FnMut(Option<PreparedRay>, &mut Stack, &mut T),
) {
    if K == 1 {
        for (ray, o) in rays.iter().zip(out) {
            one(prepare(ray), stack, o);
        }
        return;
    }
    let Some(mut stacks) = turns.of::<K>() else {
        return;
    };
    for (rays, out) in rays.chunks(K).zip(out.chunks_mut(K)) {
        let prepared: [Option<PreparedRay>; K] =
            std::array::from_fn(|i| rays.get(i).and_then(prepare));
        let refs = prepared.each_ref().map(Option::as_ref);
        match refs[0] {
            Some(first) if refs.iter().all(Option::is_some) => {
                many(
                    refs.map(|r| r.unwrap_or(first)),
                    stacks.each_mut().map(|s| &mut **s),
                    out,
                );
            }
            _ => {
                for (r, o) in prepared.into_iter().zip(out) {
                    one(r, stack, o);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::prim::boundary::boundaries;
    use crate::accel::test_meshes::{icosphere, subdivided_cube, MeshData};
    use crate::accel::wide::kernels::Listing;
    use crate::accel::wide::levels::{Borders, WideLevels};
    use crate::accel::Bvh;
    use crate::geometry::{Geometry, Triangle};
    use crate::pool::test_pool;
    use crate::raycast::QueryOptions;
    use crate::sampling::Rng;
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
    /// walk) and four at a time (`walk_many`), on one SIMD path.
    struct Answers<'a> {
        tree: &'a WideBvh,
        border: &'a [Boundary],
        rays: &'a [PreparedRay],
        many: bool,
    }

    type Answer = (Option<SlotHit>, bool, Vec<(u32, u32, u32)>);

    impl Kernel for Answers<'_> {
        type Output = Vec<Answer>;

        fn run<const N: usize, I: Isa>(self) -> Vec<Answer> {
            let (tree, border) = (self.tree, self.border);
            let range = (0.0, 1.0);
            let mut stacks: [Stack; 4] = std::array::from_fn(|_| Stack::default());
            let mut out = Vec::new();
            for rays in self.rays.chunks_exact(4) {
                let r = [&rays[0], &rays[1], &rays[2], &rays[3]];
                let mut each = vec![Vec::new(); 4];
                let (closest, occluded) = if self.many {
                    let closest = tree.closest_many::<4, I>(r, range, None, stacks.each_mut());
                    let occluded = tree.occluded_many::<4, I>(r, range, None, stacks.each_mut());
                    let f = &mut |k: usize, h: SlotHit| each[k].push(key(h));
                    let rule = (border, None);
                    tree.each_hit_many::<4, I>(r, range, rule, stacks.each_mut(), f);
                    (closest, occluded)
                } else {
                    let stack = &mut stacks[0];
                    let closest = r.map(|r| tree.closest::<I>(r, range, None, stack));
                    let occluded = r.map(|r| tree.occluded::<I>(r, range, None, stack));
                    for (k, r) in r.iter().enumerate() {
                        let f = &mut |h: SlotHit| each[k].push(key(h));
                        tree.each_hit::<I>(r, range, (border, None), stack, f);
                    }
                    (closest, occluded)
                };
                for (k, mut hits) in each.into_iter().enumerate() {
                    hits.sort_unstable();
                    out.push((closest[k], occluded[k], hits));
                }
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
        let rays = rays(4000);
        let (mut hits, mut crossings) = (0, 0);
        for path in supported_paths() {
            let answers = |many| Answers {
                tree: &tree,
                border: &by_triangle,
                rays: &rays,
                many,
            };
            let (alone, turns) = (
                dispatch(path, answers(false)),
                dispatch(path, answers(true)),
            );
            assert_eq!(alone.len(), turns.len());
            for (i, (a, t)) in alone.iter().zip(&turns).enumerate() {
                assert_eq!(a, t, "ray {i} on {path:?}");
                hits += usize::from(a.0.is_some());
                crossings += a.2.len();
            }
        }
        assert!(
            hits > 1000 && crossings > 2000,
            "{hits} hits, {crossings} crossings"
        );
    }

    /// [`in_turns`] of occlusion with `K` rays a turn, on one SIMD path.
    struct Occlusions<'a, const K: usize> {
        tree: &'a WideBvh,
        rays: &'a [[f32; 6]],
    }

    impl<const K: usize> Kernel for Occlusions<'_, K> {
        type Output = Vec<bool>;

        fn run<const N: usize, I: Isa>(self) -> Vec<bool> {
            let (tree, range) = (self.tree, (0.0, 1.0));
            let mut out = vec![false; self.rays.len()];
            let (mut stack, mut turns) = (Stack::default(), Turns::default());
            in_turns::<K, _>(
                (self.rays, &mut out),
                (&mut stack, &mut turns),
                |r, stacks, out| {
                    out.copy_from_slice(&tree.occluded_many::<K, I>(r, range, None, stacks))
                },
                |r, stack, o| *o = r.is_some_and(|r| tree.occluded::<I>(&r, range, None, stack)),
            );
            out
        }
    }

    #[test]
    fn a_batch_in_turns_answers_every_ray_as_one_at_a_time() {
        let tree = tree();
        let mut rays: Vec<[f32; 6]> = rays(1003)
            .iter()
            .map(|r| {
                let (o, d) = (r.origin, r.inv_dir.recip());
                [o.x, o.y, o.z, d.x, d.y, d.z]
            })
            .collect();
        // Rays that hit nothing by definition, amid the others (a turn then goes one by one).
        rays[5] = [0.0; 6];
        rays[402][4] = f32::NAN;
        for path in supported_paths() {
            let one = dispatch(
                path,
                Occlusions::<1> {
                    tree: &tree,
                    rays: &rays,
                },
            );
            let four = dispatch(
                path,
                Occlusions::<4> {
                    tree: &tree,
                    rays: &rays,
                },
            );
            let interleaved = dispatch(
                path,
                Occlusions::<INTERLEAVED> {
                    tree: &tree,
                    rays: &rays,
                },
            );
            assert_eq!(one, four, "{path:?}");
            assert_eq!(one, interleaved, "{path:?}");
            assert!(!one[5] && !one[402]);
            assert!(one.iter().filter(|&&b| b).count() > 200);
        }
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
            let options = QueryOptions::default();
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
        let levels = WideLevels::new(tree(), None, Vec::new(), Vec::new(), None);
        let border = levels.borders(test_pool());
        let mut rays: Vec<[f32; 6]> = (rays(1001).iter())
            .map(|r| {
                let (o, d) = (r.origin, r.inv_dir.recip());
                [o.x, o.y, o.z, d.x, d.y, d.z]
            })
            .collect();
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

    #[test]
    fn only_trees_larger_than_the_caches_interleave() {
        assert!(!tree().interleaves());
    }
}
