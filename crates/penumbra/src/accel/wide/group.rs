//! Leaf triangles in groups of eight, by coordinate, so that the watertight test of
//! `prim::watertight` runs on eight triangles at once: one AVX2 vector per value, two SSE ones on
//! the baseline (the lanes are plain loops over `[f32; 8]`, compiled per instruction set by
//! the kernels of `kernels` and `packets` that inline them). A wide leaf holds at most eight
//! triangles, so it is one group and one pass; with groups of four (SSE) the bunny's
//! incoherent rays tested 1.9 groups per leaf.
//!
//! Exactness: each lane computes what [`PreparedRay::hit`] computes for its triangle,
//! operation for operation (the same differences, products and sums in the same order, no
//! fused multiply-add), and a lane whose edge function rounds to exactly zero, or whose `t`
//! overflows, is handed to [`PreparedRay::hit`] itself (which recomputes it in `f64`, or in
//! another order). So a group gives each of its
//! triangles the very answer of the one-triangle test.

use glam::Vec3A;

use super::node::{box_distances, SHRINK};
use crate::accel::prim::boundary::Boundary;
use crate::accel::prim::watertight::{
    hit_lane, Crossing, EdgeRule, PreparedRay, SoaTriangle, T_LIMIT,
};
use crate::accel::prim::Corners;
use crate::simd::{max, min, Isa};

/// Triangles per group.
pub(crate) const GROUP: usize = 8;

/// Up to eight triangles of one leaf: `v[corner][axis]` holds that coordinate of each
/// triangle's corner, one lane per triangle. The triangles are the leaf slots
/// `first .. first + 8` (lanes past the leaf's end repeat its last triangle and are masked
/// out by the caller). Six cache lines, aligned to them.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct TriangleGroup {
    v: [[[f32; GROUP]; 3]; 3],
    /// The leaf slot of lane 0.
    pub first: u32,
    /// Each lane's geometry id and primitive id. A closest hit's ids are read when its ray
    /// is done, from a group still in the caches: read from a separate array indexed by
    /// slot, they were a cache miss at the end of each incoherent ray.
    ids: [[u32; 2]; GROUP],
}

/// What a group test finds: the lanes hit (bit `i` for lane `i`) and each lane's crossing
/// (meaningful where hit).
pub(crate) struct GroupHits {
    pub mask: u32,
    pub t: [f32; GROUP],
    pub b1: [f32; GROUP],
    pub b2: [f32; GROUP],
}

impl GroupHits {
    /// The crossing of lane `lane`.
    #[inline(always)]
    pub fn crossing(&self, lane: usize) -> Crossing {
        Crossing {
            t: self.t[lane],
            b1: self.b1[lane],
            b2: self.b2[lane],
        }
    }
}

impl TriangleGroup {
    /// The group of leaf slots `first .. first + count` (`1 <= count <= 8`) of `tris`, whose
    /// geometry and primitive ids are `ids`.
    pub fn new(
        tris: &[SoaTriangle],
        ids: &[[u32; 2]],
        first: usize,
        count: usize,
    ) -> TriangleGroup {
        let mut v = [[[0.0; GROUP]; 3]; 3];
        let ids = std::array::from_fn(|lane| ids[first + lane.min(count - 1)]);
        for lane in 0..GROUP {
            let corners = tris[first + lane.min(count - 1)].corners();
            for (corner, c) in corners.iter().enumerate() {
                for axis in 0..3 {
                    v[corner][axis][lane] = c[axis];
                }
            }
        }
        TriangleGroup {
            v,
            first: first as u32,
            ids,
        }
    }

    /// The geometry id and primitive id of the triangle in lane `lane`.
    #[inline(always)]
    pub fn ids(&self, lane: usize) -> [u32; 2] {
        self.ids[lane]
    }

    /// The lanes whose triangle may hold a point within squared distance `limit` of `q`, and
    /// a lower bound of each triangle's squared distance: the larger of the distance to its
    /// box ([`box_distances`]) and to its plane ([`plane_distances`]). The closest-point
    /// walk's cheap test before the exact one.
    #[inline(always)]
    pub fn nearer<I: Isa>(&self, q: &[f32; 3], pad: f32, limit: f32) -> (u32, [f32; GROUP]) {
        let [a, b, c] = &self.v;
        let mut lo = [[0.0f32; GROUP]; 3];
        let mut hi = [[0.0f32; GROUP]; 3];
        for axis in 0..3 {
            for i in 0..GROUP {
                lo[axis][i] = min(min(a[axis][i], b[axis][i]), c[axis][i]);
                hi[axis][i] = max(max(a[axis][i], b[axis][i]), c[axis][i]);
            }
        }
        let boxes = box_distances(&lo, &hi, q, pad);
        let planes = plane_distances(&self.v, q, pad);
        // A NaN plane bound (a degenerate triangle) leaves the box's.
        let d: [f32; GROUP] = std::array::from_fn(|i| max(planes[i], boxes[i]));
        (I::mask(&d.map(|d| -i32::from(d <= limit))), d)
    }

    /// The corners of the triangle in lane `lane`.
    pub fn corners(&self, lane: usize) -> Corners {
        self.v
            .map(|c| Vec3A::new(c[0][lane], c[1][lane], c[2][lane]))
    }
}

/// `2⁻¹⁸`: the error allowance of [`plane_distances`], in units of `|e₁||e₂||w|` and
/// `|e₁||e₂|`, above the 12 and 7 units of `2⁻²⁴` its sums and products can lose.
const PLANE_SLACK: f32 = 1.0 / 262_144.0;

/// A lower bound of the squared distance from `q` to the plane of each triangle of `v`
/// (`v[corner][axis][lane]`), which no point of the triangle is nearer than; NaN for a
/// degenerate triangle. With `e₁`, `e₂` the edges from the first corner `a` and `w = q − a`,
/// the distance is `|n·w| / |n|` for `n = e₁ × e₂`. In `f32`, `n·w` is off by at most
/// `12·2⁻²⁴ |e₁||e₂||w|` and `|n|` by `7·2⁻²⁴ |e₁||e₂|` (each difference, product and sum
/// rounds once): the bound takes [`PLANE_SLACK`] of each off the numerator and onto the
/// denominator, and `2·pad·|n|` off the numerator for a `q` off by `pad` per coordinate.
#[inline(always)]
pub(crate) fn plane_distances(v: &[[[f32; GROUP]; 3]; 3], q: &[f32; 3], pad: f32) -> [f32; GROUP] {
    let [a, b, c] = v;
    let mut d = [0.0f32; GROUP];
    for i in 0..GROUP {
        let e1 = [0, 1, 2].map(|k| b[k][i] - a[k][i]);
        let e2 = [0, 1, 2].map(|k| c[k][i] - a[k][i]);
        let w = [0, 1, 2].map(|k| q[k] - a[k][i]);
        let n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        let dot = |x: [f32; 3], y: [f32; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
        let edges = (dot(e1, e1) * dot(e2, e2)).sqrt();
        let s = dot(n, w).abs();
        let den = dot(n, n).sqrt() + PLANE_SLACK * edges;
        let num = s - PLANE_SLACK * edges * dot(w, w).sqrt() - 2.0 * pad * den;
        let lb = max(num, 0.0) / den;
        d[i] = lb * lb * SHRINK;
    }
    d
}

impl PreparedRay {
    /// [`PreparedRay::hit`] on the lanes `valid` of `group` (whose triangles are `tris` and
    /// parts of the surface's border `border`, indexed by leaf slot; `border` may be empty
    /// for [`EdgeRule::Inclusive`]).
    #[allow(clippy::needless_range_loop, clippy::too_many_arguments)]
    #[inline(always)]
    pub fn hit_group<I: Isa>(
        &self,
        group: &TriangleGroup,
        valid: u32,
        tris: &[SoaTriangle],
        border: &[Boundary],
        t_min: f32,
        t_max: f32,
        rule: EdgeRule,
    ) -> GroupHits {
        let t_max = t_max.min(T_LIMIT);
        let [kx, ky, kz] = self.axes();
        let [sx, sy] = self.shear();
        let inv_dz = self.inv_dz();
        let o = self.origin.to_array();
        let o = [o[kx], o[ky], o[kz]];
        // Each corner's coordinates by permuted axis.
        let rows = [0, 1, 2].map(|c| (&group.v[c][kx], &group.v[c][ky], &group.v[c][kz]));
        let (mut zero, mut inside) = ([0i32; GROUP], [0i32; GROUP]);
        let mut hits = GroupHits {
            mask: 0,
            t: [0.0; GROUP],
            b1: [0.0; GROUP],
            b2: [0.0; GROUP],
        };
        for i in 0..GROUP {
            let c = rows.map(|(x, y, z)| [x[i], y[i], z[i]]);
            let (exact, ok, t, b1, b2) = hit_lane(c, o, (sx, sy), inv_dz);
            inside[i] = -i32::from(ok & (t >= t_min) & (t <= t_max));
            zero[i] = -i32::from(exact);
            (hits.t[i], hits.b1[i], hits.b2[i]) = (t, b1, b2);
        }
        let exact = I::mask(&zero) & valid;
        hits.mask = I::mask(&inside) & valid & !exact;
        // Lanes on an edge function's zero: the one-triangle test, with its `f64` re-test.
        let mut rest = exact;
        while rest != 0 {
            let lane = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let slot = group.first as usize + lane;
            let boundary = border.get(slot).copied().unwrap_or_default();
            if let Some(c) = self.hit(&tris[slot], boundary, t_min, t_max, rule) {
                hits.mask |= 1 << lane;
                (hits.t[lane], hits.b1[lane], hits.b2[lane]) = (c.t, c.b1, c.b2);
            }
        }
        hits
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use crate::simd::{dispatch, supported_paths, Kernel};
    use glam::Vec3;

    /// The group test with `t` in `[0, 10]` as a kernel, to run on each instruction set.
    struct GroupTest<'a> {
        ray: &'a PreparedRay,
        group: &'a TriangleGroup,
        valid: u32,
        tris: &'a [SoaTriangle],
        border: &'a [Boundary],
        rule: EdgeRule,
    }

    impl Kernel for GroupTest<'_> {
        type Output = GroupHits;

        #[inline(always)]
        fn run<const N: usize, I: Isa>(self) -> GroupHits {
            let GroupTest {
                ray,
                group,
                valid,
                tris,
                border,
                rule,
            } = self;
            ray.hit_group::<I>(group, valid, tris, border, 0.0, 10.0, rule)
        }
    }

    /// A random point of the cube `[-1, 1]³`, on a coarse grid one time in four so that rays
    /// meet edges and vertices exactly.
    fn point(rng: &mut Rng) -> Vec3 {
        let coarse = rng.uniform() < 0.25;
        Vec3::from_array([0; 3].map(|_| {
            let x = 2.0 * rng.uniform() - 1.0;
            if coarse {
                (x * 4.0).round() / 4.0
            } else {
                x
            }
        }))
    }

    #[test]
    fn a_group_is_six_cache_lines() {
        assert_eq!(std::mem::size_of::<TriangleGroup>(), 6 * 64);
    }

    #[test]
    fn every_lane_answers_as_the_one_triangle_test() {
        let mut rng = Rng::new(7, &[]);
        let tris: Vec<SoaTriangle> = (0..64)
            .map(|_| SoaTriangle::new(&[0; 3].map(|_| Vec3A::from(point(&mut rng)))))
            .collect();
        let corners: Vec<Corners> = tris.iter().map(SoaTriangle::corners).collect();
        let boundary = crate::accel::prim::boundary::boundaries(&corners, None);
        let (mut hits, mut exact) = (0, 0);
        for _ in 0..4000 {
            let (o, target) = (point(&mut rng), point(&mut rng));
            let Some(ray) = PreparedRay::new(o * 3.0, target - o * 3.0) else {
                continue;
            };
            for rule in [EdgeRule::Inclusive, EdgeRule::Owned] {
                for first in (0..tris.len()).step_by(3) {
                    let count = (tris.len() - first).min(GROUP);
                    let ids: Vec<[u32; 2]> = (0..tris.len() as u32).map(|i| [0, i]).collect();
                    let group = TriangleGroup::new(&tris, &ids, first, count);
                    for lane in 0..count {
                        assert_eq!(group.ids(lane), [0, (first + lane) as u32]);
                    }
                    let valid = (1 << count) - 1;
                    for path in supported_paths() {
                        let (ray, group, tris) = (&ray, &group, &tris[..]);
                        let test = GroupTest {
                            ray,
                            group,
                            valid,
                            tris,
                            border: &boundary,
                            rule,
                        };
                        let got = dispatch(path, test);
                        for lane in 0..count {
                            let slot = first + lane;
                            let want = ray.hit(&tris[slot], boundary[slot], 0.0, 10.0, rule);
                            let bits = want.map(|c| [c.t, c.b1, c.b2].map(f32::to_bits));
                            let mine = (got.mask >> lane & 1 == 1).then(|| {
                                [got.t[lane], got.b1[lane], got.b2[lane]].map(f32::to_bits)
                            });
                            assert_eq!(mine, bits, "lane {lane} of the group at {first}, {path:?}");
                            hits += usize::from(want.is_some());
                        }
                        exact += (got.mask & !valid).count_ones();
                    }
                }
            }
        }
        assert_eq!(exact, 0, "no hit outside the valid lanes");
        assert!(hits > 1000, "{hits} hits");
    }
}
