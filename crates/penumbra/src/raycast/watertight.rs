//! The watertight ray–triangle test of Woop, Benthin and Wald ("Watertight Ray/Triangle
//! Intersection", JCGT 2013), as pbrt-v3 and pbrt-v4 describe it.
//!
//! The ray is made the +z axis of a sheared frame (a permutation of the axes so that the
//! direction's largest component is z, then a shear that maps the direction onto z). Each
//! triangle vertex is moved into that frame on its own, so a vertex shared by two triangles
//! lands on exactly the same 2-D point in both. The three 2-D edge functions then decide
//! inside or outside; for an edge shared by two triangles the two computed values are exact
//! negatives of each other (the same two rounded products, subtracted in the other order), so
//! a ray can never pass between two triangles: it is inside at least one of them. Values that
//! round to exactly zero are recomputed in `f64`, where the products of `f32` are exact and
//! the sign is right.
//!
//! Two edge rules:
//! - [`EdgeRule::Inclusive`]: a ray on an edge or vertex hits every triangle there (closest
//!   hit, occlusion: never a miss).
//! - [`EdgeRule::Owned`]: a ray on an edge or vertex hits exactly one of the triangles that
//!   meet there when the surface crosses the ray (and none or two where it only touches it, at
//!   a silhouette fold), so that counting hits gives the crossing parity. Each boundary point
//!   is given to the triangle that holds it after an infinitesimal displacement of the ray by
//!   `(ε, ε²)` in the sheared frame (a simulation of simplicity), which is the top-left rule of
//!   rasterization.

use glam::{Vec3, Vec3A};

/// How a ray exactly on a triangle's edge or vertex counts; see the module docs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum EdgeRule {
    /// Every triangle that holds the point counts it.
    Inclusive,
    /// One triangle of a crossing counts it.
    Owned,
}

/// A ray prepared for the watertight test and for the conservative box test.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PreparedRay {
    /// Origin.
    pub origin: Vec3,
    /// `1 / direction`, per component (±∞ for a zero component).
    pub inv_dir: Vec3A,
    /// Origin, for the box test.
    pub origin_a: Vec3A,
    /// Axis permutation: the direction's largest component is `k[2]`.
    k: [usize; 3],
    /// Shear: `(−d_x/d_z, −d_y/d_z, 1/d_z)` in the permuted axes.
    shear: [f32; 3],
}

/// A hit of [`PreparedRay::hit`]: the ray parameter and the barycentric weights of the
/// triangle's second and third vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Crossing {
    pub t: f32,
    pub b1: f32,
    pub b2: f32,
}

impl PreparedRay {
    /// Prepares `origin + t·direction`; `None` when a component is not finite or the
    /// direction is zero (such rays hit nothing).
    pub fn new(origin: Vec3, direction: Vec3) -> Option<PreparedRay> {
        if !origin.is_finite() || !direction.is_finite() || direction == Vec3::ZERO {
            return None;
        }
        let kz = direction.abs().max_position();
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        // Keep the frame right-handed so that a triangle's winding keeps its sign.
        if direction[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let dz = direction[kz];
        Some(PreparedRay {
            origin,
            inv_dir: Vec3A::from(direction).recip(),
            origin_a: Vec3A::from(origin),
            k: [kx, ky, kz],
            shear: [-direction[kx] / dz, -direction[ky] / dz, 1.0 / dz],
        })
    }

    /// The vertex `p` in the ray's sheared frame: `(x, y)` in the plane across the ray and
    /// the unscaled depth `z`.
    #[inline(always)]
    fn in_frame(&self, p: &[f32; 3]) -> (f32, f32, f32) {
        let [kx, ky, kz] = self.k;
        let (x, y, z) = (
            p[kx] - self.origin[kx],
            p[ky] - self.origin[ky],
            p[kz] - self.origin[kz],
        );
        (x + self.shear[0] * z, y + self.shear[1] * z, z)
    }

    /// Intersects the triangle `tri` (its three corners) for `t` in `[t_min, t_max]` under
    /// `rule`. Two-sided; degenerate triangles and triangles seen exactly edge-on are missed.
    #[inline(always)]
    pub fn hit(
        &self,
        tri: &[[f32; 3]; 3],
        t_min: f32,
        t_max: f32,
        rule: EdgeRule,
    ) -> Option<Crossing> {
        let (ax, ay, az) = self.in_frame(&tri[0]);
        let (bx, by, bz) = self.in_frame(&tri[1]);
        let (cx, cy, cz) = self.in_frame(&tri[2]);
        // Edge functions: `u` of edge B→C (the weight of A), `v` of C→A, `w` of A→B.
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            u = edge_f64(cx, by, cy, bx);
            v = edge_f64(ax, cy, ay, cx);
            w = edge_f64(bx, ay, by, ax);
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 || det.is_nan() {
            return None;
        }
        if rule == EdgeRule::Owned && (u == 0.0 || v == 0.0 || w == 0.0) {
            let flip = det < 0.0;
            let owns = |zero: bool, ex: f32, ey: f32| !zero || owned(ex, ey, flip);
            if !(owns(u == 0.0, cx - bx, cy - by)
                && owns(v == 0.0, ax - cx, ay - cy)
                && owns(w == 0.0, bx - ax, by - ay))
            {
                return None;
            }
        }
        let s = self.shear[2];
        let scaled_t = u * (s * az) + v * (s * bz) + w * (s * cz);
        let inv_det = 1.0 / det;
        let t = scaled_t * inv_det;
        if !(t >= t_min && t <= t_max) {
            return None;
        }
        Some(Crossing {
            t,
            b1: v * inv_det,
            b2: w * inv_det,
        })
    }
}

/// `a·b − c·d` in `f64` (exact products of `f32`), rounded to `f32` keeping its sign: a
/// non-zero value never becomes zero.
#[inline(never)]
fn edge_f64(a: f32, b: f32, c: f32, d: f32) -> f32 {
    let e = a as f64 * b as f64 - c as f64 * d as f64;
    let r = e as f32;
    if r == 0.0 && e != 0.0 {
        f32::MIN_POSITIVE.copysign(e.signum() as f32)
    } else {
        r
    }
}

/// Whether the triangle owns its edge with 2-D direction `(ex, ey)` (in its A→B→C cycle) when
/// the ray passes exactly through that edge: true when the ray, moved by `(ε, ε²)`, is on the
/// triangle's side. Every triangle here has its inside on the right of its cycle after
/// flipping the edges of those whose determinant is negative (`flip`).
#[inline]
fn owned(ex: f32, ey: f32, flip: bool) -> bool {
    let (ex, ey) = if flip { (-ex, -ey) } else { (ex, ey) };
    ey > 0.0 || (ey == 0.0 && ex < 0.0)
}

/// The unit normal `(v1 − v0) × (v2 − v0)` of a triangle (zero for a degenerate one).
pub(crate) fn unit_normal(tri: &[[f32; 3]; 3]) -> Vec3 {
    let [a, b, c] = tri.map(Vec3::from);
    (b - a).cross(c - a).normalize_or_zero()
}
