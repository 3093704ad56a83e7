//! A packet's bounds for culling a wide node's children for all its rays at once
//! ([`WideNode::enter_interval`](super::node::WideNode::enter_interval)): the box of the
//! origins and the range of `1/direction` per axis (interval arithmetic, Boulos et al. 2006);
//! and whether a packet misses the whole tree, tested on the rays before they are prepared.

use super::margins::{tie_bound, EXIT_SCALE};
use super::tree::WideBvh;
use crate::simd::{max, min, Isa};

/// The smallest and largest origin coordinates, and the smallest and largest `1/direction`,
/// per axis.
pub(super) type Bounds = (([f32; 3], [f32; 3]), ([f32; 3], [f32; 3]));

/// The bounds of the rays `(origin, inv)` (by axis and lane), when every `1/direction` is
/// finite and has one sign per axis (rays of one octant, as a pinhole image's neighbours):
/// then no product in the interval test is a NaN, and each axis's entry plane is the same
/// for every ray.
#[inline(always)]
pub(super) fn bounds<const N: usize>(
    origin: &[[f32; N]; 3],
    inv: &[[f32; N]; 3],
) -> Option<Bounds> {
    let mut b = (([0.0f32; 3], [0.0f32; 3]), ([0.0f32; 3], [0.0f32; 3]));
    for a in 0..3 {
        let ((o_lo, o_hi), (i_lo, i_hi)) = (extremes(&origin[a]), extremes(&inv[a]));
        let usable = i_lo.is_finite()
            && i_hi.is_finite()
            && i_lo.is_sign_negative() == i_hi.is_sign_negative();
        if !usable {
            return None;
        }
        (b.0 .0[a], b.0 .1[a], b.1 .0[a], b.1 .1[a]) = (o_lo, o_hi, i_lo, i_hi);
    }
    Some(b)
}

/// [`bounds`] of the `N` rays `rays` (`[ox, oy, oz, dx, dy, dz]`) taken from the rays
/// themselves, before any lane is prepared: the same bounds, since rounding `1/d` is monotone
/// in `d` on each side of 0 (the smallest `1/d` of the lanes is `1/d` of the largest `d`).
/// `None` when a coordinate is not finite or an axis's directions are not all of one sign.
/// A few vector instructions a packet: the rays are read as 24 floats (four rays) at a time.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
pub(super) fn ray_bounds<const N: usize>(rays: &[[f32; 6]]) -> Option<Bounds> {
    const ROW: usize = 24;
    let flat = rays.as_flattened();
    if rays.len() != N || !N.is_multiple_of(4) {
        return None;
    }
    let (mut lo, mut hi, mut nan) = ([f32::INFINITY; ROW], [f32::NEG_INFINITY; ROW], [0.0; ROW]);
    for row in flat.chunks_exact(ROW) {
        for j in 0..ROW {
            lo[j] = min(lo[j], row[j]);
            hi[j] = max(hi[j], row[j]);
            // 0 for a finite value, NaN for an infinity or a NaN: the sum stays NaN.
            nan[j] += row[j] * 0.0;
        }
    }
    let mut b = ([0.0f32; 6], [0.0f32; 6]);
    for c in 0..6 {
        let (mut l, mut h) = (lo[c], hi[c]);
        for k in [6, 12, 18] {
            (l, h) = (min(l, lo[c + k]), max(h, hi[c + k]));
        }
        (b.0[c], b.1[c]) = (l, h);
    }
    let finite = nan.iter().sum::<f32>() == 0.0;
    let one_sign = (3..6).all(|c| b.0[c] > 0.0 || b.1[c] < 0.0);
    if !(finite && one_sign) {
        return None;
    }
    let inv = |c: usize, end: [f32; 6]| 1.0 / end[c + 3];
    let (o_lo, o_hi) = ([0, 1, 2].map(|c| b.0[c]), [0, 1, 2].map(|c| b.1[c]));
    let (i_lo, i_hi) = (
        [0, 1, 2].map(|c| inv(c, b.1)),
        [0, 1, 2].map(|c| inv(c, b.0)),
    );
    // A direction so small that its reciprocal overflows: as in `bounds`, no usable interval.
    let usable = i_lo.iter().chain(&i_hi).all(|i| i.is_finite());
    usable.then_some(((o_lo, o_hi), (i_lo, i_hi)))
}

/// True when the `N` rays of `rays` enter none of the root's children of `accel` by the
/// packet's interval test with `t` in `[0, ∞]`, their bounds taken from the rays themselves
/// ([`ray_bounds`]): the packet walk and each ray alone would find nothing. Most of a pinhole
/// image's packets miss a model's box; they need no lanes prepared (callgrind, 1024² images:
/// 10 % fewer instructions for the bunny's, 6.5 % for the 1M-triangle blob's).
#[inline(always)]
pub(super) fn misses<const N: usize, I: Isa>(accel: &WideBvh, rays: &[[f32; 6]]) -> bool {
    let Some((origin, inv_dir)) = ray_bounds::<N>(rays) else {
        return false;
    };
    accel.wide().first().is_none_or(|root| {
        root.enter_interval::<I>(&origin, &inv_dir, 0.0, f32::INFINITY, EXIT_SCALE) == 0
    })
}

/// The largest bound [`tie_bound`] makes of `t_max` on the lanes of `mask`: at least every
/// such lane's own, so a child no lane enters below it is one no lane's test lets through.
#[inline(always)]
pub(super) fn furthest<const N: usize>(t_max: &[f32; N], mask: u32) -> f32 {
    let mut far = [0.0f32; N];
    for i in 0..N {
        far[i] = if mask >> i & 1 == 1 { t_max[i] } else { 0.0 };
    }
    tie_bound(extremes(&far).1)
}

/// The smallest and largest of `v` (no NaN; `N` a power of two), by a pairwise reduction:
/// plain loops over lanes with the vector instructions' `min`/`max`, which compile to a few
/// vector instructions per level (kept inside the kernel compiled per instruction set). A
/// sequential fold runs lane after lane (a packet's bounds were 15 instructions a ray), and
/// `f32::min` folded from lane 1 on left out the last three of 16 lanes in the dev
/// profile's AVX2 kernel.
#[inline(always)]
fn extremes<const N: usize>(v: &[f32; N]) -> (f32, f32) {
    debug_assert!(N.is_power_of_two());
    let (mut lo, mut hi) = (*v, *v);
    let mut width = N;
    while width > 1 {
        width /= 2;
        for i in 0..width {
            lo[i] = min(lo[i], lo[i + width]);
            hi[i] = max(hi[i], hi[i + width]);
        }
    }
    (lo[0], hi[0])
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::accel::lanes::slab;
    use crate::accel::wide::margins::EXIT_SCALE;
    use crate::accel::wide::node::{collapse, WideNode, WIDTH};
    use crate::accel::Bvh;
    use crate::geometry::{Geometry, Triangle};
    use crate::simd::{dispatch, supported_paths, Isa, Kernel};
    use crate::Rng;

    /// 400 small random triangles in the unit cube: a tree of boxes of every size.
    fn nodes() -> Vec<WideNode> {
        let mut rng = Rng::new(7, &[]);
        let mut g = Geometry::default();
        for i in 0..400u32 {
            let p = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
            let d = |rng: &mut Rng| 0.05 * Vec3::new(rng.uniform(), rng.uniform(), rng.uniform());
            let (b, c) = (p + d(&mut rng), p - d(&mut rng));
            g.positions.extend([p, b, c]);
            g.triangles.push(Triangle {
                vertices: [3 * i, 3 * i + 1, 3 * i + 2],
                material: 0,
                object: 0,
                smooth: false,
            });
        }
        collapse(Bvh::build(&g).nodes(), 8, &mut |first, _| first)
    }

    /// 8 rays by axis: origins spread by `spread` around a point, directions by `cone`
    /// around one, each with its own bound `t_max` (some infinite).
    fn packet(rng: &mut Rng, spread: f32, cone: f32) -> ([[f32; 8]; 3], [[f32; 8]; 3], [f32; 8]) {
        let mut u = || rng.uniform() * 2.0 - 1.0;
        let (o0, d0) = ([u() * 2.0, u() * 2.0, u() * 2.0], [u(), u(), u()]);
        let (mut o, mut inv, mut t_max) = ([[0.0; 8]; 3], [[0.0; 8]; 3], [0.0; 8]);
        for i in 0..8 {
            for a in 0..3 {
                o[a][i] = o0[a] + spread * u();
                inv[a][i] = 1.0 / (d0[a] + cone * u());
            }
            t_max[i] = if u() > 0.5 {
                f32::INFINITY
            } else {
                3.0 * u().abs()
            };
        }
        (o, inv, t_max)
    }

    /// Per path: how many (node, packet) pairs some lane enters a child that the interval
    /// test culls (must be none), and how many children it culls in all.
    struct Check<'a>(&'a [WideNode]);

    impl Kernel for Check<'_> {
        type Output = (usize, usize, usize);

        fn run<const N: usize, I: Isa>(self) -> (usize, usize, usize) {
            let mut rng = Rng::new(11, &[]);
            let (mut wrong, mut culled, mut entered) = (0, 0, 0);
            for k in 0..3000 {
                let (spread, cone) = [(0.0, 0.05), (0.02, 0.02), (0.3, 0.3)][k % 3];
                let (o, inv, t_max) = packet(&mut rng, spread, cone);
                let Some((ob, ib)) = bounds(&o, &inv) else {
                    continue;
                };
                for node in self.0 {
                    let some =
                        node.enter_interval::<I>(&ob, &ib, 0.0, furthest(&t_max, 255), EXIT_SCALE);
                    for c in (0..WIDTH).filter(|&c| node.used(c)) {
                        let (lo, hi) = node.bounds(c);
                        let rel = |a: usize, i: usize| (lo[a] - o[a][i], hi[a] - o[a][i]);
                        let (lanes, _) = slab::<8, I>(rel, &inv, 0.0, &t_max, EXIT_SCALE);
                        let kept = some >> c & 1 == 1;
                        wrong += usize::from(lanes != 0 && !kept);
                        culled += usize::from(!kept);
                        entered += usize::from(lanes != 0);
                    }
                }
            }
            (wrong, culled, entered)
        }
    }

    #[test]
    fn the_interval_test_culls_only_children_no_ray_enters() {
        let nodes = nodes();
        for path in supported_paths() {
            let (wrong, culled, entered) = dispatch(path, Check(&nodes));
            assert_eq!(wrong, 0, "{path:?}: children culled that a ray enters");
            // It culls: a test that let every child through would pass the line above.
            assert!(
                culled > 4 * entered,
                "{path:?}: {culled} culled, {entered} entered"
            );
        }
    }

    /// The bounds of packets of 8, 16 and 32 lanes of distinct values, on the path that runs:
    /// whether each bounds every lane (the largest value in each lane in turn).
    struct Every;

    impl Kernel for Every {
        type Output = bool;

        fn run<const N: usize, I: Isa>(self) -> bool {
            fn all<const M: usize>() -> bool {
                (0..M).all(|top| {
                    let value = |i: usize| if i == top { 9.0 } else { 1.0 + i as f32 * 0.01 };
                    let v: [[f32; M]; 3] = [0, 1, 2].map(|_| std::array::from_fn(value));
                    let neg = v.map(|axis| axis.map(|x| -x));
                    let ok = |b: Option<Bounds>, lo: f32, hi: f32| {
                        b.is_some_and(|(o, i)| {
                            o.0 == [lo; 3] && o.1 == [hi; 3] && i.0 == [lo; 3] && i.1 == [hi; 3]
                        })
                    };
                    // The smallest value is lane 0's, unless lane 0 holds the largest.
                    let least = if top == 0 { value(1) } else { value(0) };
                    ok(bounds(&v, &v), least, 9.0) && ok(bounds(&neg, &neg), -9.0, -least)
                })
            }
            all::<8>() && all::<16>() && all::<32>()
        }
    }

    #[test]
    fn a_packets_bounds_hold_every_lane() {
        for path in supported_paths() {
            assert!(dispatch(path, Every), "{path:?}");
        }
    }

    #[test]
    fn bounds_taken_from_the_rays_are_their_lanes_bounds() {
        let mut rng = Rng::new(13, &[]);
        for k in 0..4000 {
            let mut u = || rng.uniform() * 2.0 - 1.0;
            let (spread, cone) = [(0.0, 0.05), (0.02, 0.02), (0.3, 0.3), (1.0, 2.0)][k % 4];
            let (o0, d0) = ([u() * 2.0, u() * 2.0, u() * 2.0], [u(), u(), u()]);
            let mut rays: [[f32; 6]; 32] = std::array::from_fn(|_| {
                let o = o0.map(|c| c + spread * u());
                let d = d0.map(|c| c + cone * u());
                [o[0], o[1], o[2], d[0], d[1], d[2]]
            });
            // A lane spoilt in one coordinate: not finite, no direction on an axis, a
            // reciprocal that overflows, the other sign.
            let (i, c) = (k / 8 % 32, k / 256 % 6);
            let spoilt = [f32::NAN, f32::INFINITY, 0.0, -0.0, 1e-40, -rays[i][c]];
            if k % 8 < spoilt.len() {
                rays[i][c] = spoilt[k % 8];
            }
            let origin = std::array::from_fn(|a| std::array::from_fn(|i| rays[i][a]));
            let inv = std::array::from_fn(|a| std::array::from_fn(|i| 1.0 / rays[i][3 + a]));
            let finite = rays.as_flattened().iter().all(|x| x.is_finite());
            let want = if finite {
                bounds::<32>(&origin, &inv)
            } else {
                None
            };
            assert_eq!(ray_bounds::<32>(&rays), want, "packet {k}: {rays:?}");
        }
    }

    /// `furthest` over packets of 8, 16 and 32 lanes, on the path that runs: the bound of
    /// the largest `t` among the lanes of each mask (one lane, two lanes, every other lane,
    /// all of them), never of a lane out of the mask.
    struct Furthest;

    impl Kernel for Furthest {
        type Output = bool;

        fn run<const N: usize, I: Isa>(self) -> bool {
            fn all<const M: usize>() -> bool {
                let t: [f32; M] = std::array::from_fn(|i| 1.0 + ((i * 7) % M) as f32);
                let full = if M == 32 { u32::MAX } else { (1 << M) - 1 };
                let masks =
                    (0..M as u32).flat_map(|i| [1 << i, (1 << i) | 1, 0x5555_5555 & full, full]);
                masks.into_iter().all(|mask| {
                    let lanes = (0..M).filter(|&i| mask >> i & 1 == 1);
                    let want = lanes.map(|i| t[i]).fold(0.0, f32::max);
                    furthest(&t, mask) == tie_bound(want)
                })
            }
            all::<8>() && all::<16>() && all::<32>()
        }
    }

    #[test]
    fn the_furthest_bound_is_over_the_masks_lanes_only() {
        for path in supported_paths() {
            assert!(dispatch(path, Furthest), "{path:?}");
        }
    }
}
