//! Leaf triangles in groups of four, by coordinate, so that the watertight test of
//! `watertight` runs on four triangles at once (one SSE lane each).
//!
//! Exactness: each lane computes what [`PreparedRay::hit`] computes for its triangle,
//! operation for operation (the same differences, products and sums in the same order, no
//! fused multiply-add), and a lane whose edge function rounds to exactly zero is handed to
//! [`PreparedRay::hit`] itself (which recomputes it in `f64`). So a group gives each of its
//! triangles the very answer of the one-triangle test.

use glam::{Vec3A, Vec4};

use super::watertight::{Corners, Crossing, EdgeRule, PreparedRay, SoaTriangle};

/// Triangles per group.
pub(crate) const GROUP: usize = 4;

/// Up to four triangles of one leaf: `v[corner][axis]` holds that coordinate of each
/// triangle's corner, one lane per triangle. The triangles are the leaf slots
/// `first .. first + 4` (lanes past the leaf's end repeat its last triangle and are masked
/// out by the caller).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TriangleGroup {
    v: [[Vec4; 3]; 3],
    /// The leaf slot of lane 0.
    pub first: u32,
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
    /// The group of leaf slots `first .. first + count` (`1 <= count <= 4`) of `tris`.
    pub fn new(tris: &[SoaTriangle], first: usize, count: usize) -> TriangleGroup {
        let mut v = [[Vec4::ZERO; 3]; 3];
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
        }
    }
}

impl TriangleGroup {
    /// The corners of the triangle in lane `lane`.
    pub fn corners(&self, lane: usize) -> Corners {
        self.v
            .map(|c| Vec3A::new(c[0][lane], c[1][lane], c[2][lane]))
    }
}

impl PreparedRay {
    /// [`PreparedRay::hit`] on the lanes `valid` of `group` (whose triangles are `tris`,
    /// indexed by leaf slot).
    #[inline(always)]
    pub fn hit_group(
        &self,
        group: &TriangleGroup,
        valid: u32,
        tris: &[SoaTriangle],
        t_min: f32,
        t_max: f32,
        rule: EdgeRule,
    ) -> GroupHits {
        let [kx, ky, kz] = self.axes();
        let [sx, sy] = self.shear().map(Vec4::splat);
        let inv_dz = Vec4::splat(self.inv_dz());
        let o = self.origin.to_array().map(Vec4::splat);
        // Each corner in the ray's sheared frame, one lane per triangle: as in `hit`, each
        // depends on its vertex alone.
        let frame = |c: usize| {
            let d = [0, 1, 2].map(|a| group.v[c][a] - o[a]);
            let fz = d[kz];
            (d[kx] + sx * fz, d[ky] + sy * fz, fz)
        };
        let (f0, f1, f2) = (frame(0), frame(1), frame(2));
        // The edge functions `x2·y1 − y2·x1` of `hit`, lane by lane.
        let u = f2.0 * f1.1 - f2.1 * f1.0;
        let v = f0.0 * f2.1 - f0.1 * f2.0;
        let w = f1.0 * f0.1 - f1.1 * f0.0;
        let zero = Vec4::ZERO;
        let exact = (u.cmpeq(zero) | v.cmpeq(zero) | w.cmpeq(zero)).bitmask() & valid;
        let negative = u.cmplt(zero) | v.cmplt(zero) | w.cmplt(zero);
        let positive = u.cmpgt(zero) | v.cmpgt(zero) | w.cmpgt(zero);
        // `element_sum` of glam's `Vec3A`: `(x + y) + (z + 0)`.
        let det = (u + v) + (w + zero);
        let scaled_t = (u * (f0.2 * inv_dz) + v * (f1.2 * inv_dz)) + (w * (f2.2 * inv_dz) + zero);
        let inv_det = Vec4::ONE / det;
        let t = scaled_t * inv_det;
        // `det` is not 0 and not NaN; `t` in `[t_min, t_max]` (false for a NaN `t`).
        let inside = !(negative & positive) & det.cmpne(zero) & det.cmpeq(det);
        let in_range = t.cmpge(Vec4::splat(t_min)) & t.cmple(Vec4::splat(t_max));
        let mut hits = GroupHits {
            mask: (inside & in_range).bitmask() & valid & !exact,
            t: t.to_array(),
            b1: (v * inv_det).to_array(),
            b2: (w * inv_det).to_array(),
        };
        // Lanes on an edge function's zero: the one-triangle test, with its `f64` re-test.
        let mut rest = exact;
        while rest != 0 {
            let lane = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let slot = group.first as usize + lane;
            if let Some(c) = self.hit(&tris[slot], t_min, t_max, rule) {
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
    use glam::Vec3;

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
    fn every_lane_answers_as_the_one_triangle_test() {
        let mut rng = Rng::new(7, &[]);
        let tris: Vec<SoaTriangle> = (0..64)
            .map(|_| SoaTriangle::new(&[0; 3].map(|_| Vec3A::from(point(&mut rng)))))
            .collect();
        let (mut hits, mut exact) = (0, 0);
        for _ in 0..4000 {
            let (o, target) = (point(&mut rng), point(&mut rng));
            let Some(ray) = PreparedRay::new(o * 3.0, target - o * 3.0) else {
                continue;
            };
            for rule in [EdgeRule::Inclusive, EdgeRule::Owned] {
                for first in (0..tris.len()).step_by(3) {
                    let count = (tris.len() - first).min(GROUP);
                    let group = TriangleGroup::new(&tris, first, count);
                    let valid = (1 << count) - 1;
                    let got = ray.hit_group(&group, valid, &tris, 0.0, 10.0, rule);
                    for lane in 0..count {
                        let want = ray.hit(&tris[first + lane], 0.0, 10.0, rule);
                        let bits = want.map(|c| [c.t, c.b1, c.b2].map(f32::to_bits));
                        let mine = (got.mask >> lane & 1 == 1)
                            .then(|| [got.t[lane], got.b1[lane], got.b2[lane]].map(f32::to_bits));
                        assert_eq!(mine, bits, "lane {lane} of the group at {first}");
                        hits += usize::from(want.is_some());
                    }
                    exact += (got.mask & !valid).count_ones();
                }
            }
        }
        assert_eq!(exact, 0, "no hit outside the valid lanes");
        assert!(hits > 1000, "{hits} hits");
    }
}
