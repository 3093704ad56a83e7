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
//!   a silhouette fold), so that counting hits gives the crossing parity. Each point shared by
//!   triangles is given to the triangle that holds it after an infinitesimal displacement of
//!   the ray by `(ε, ε²)` in the sheared frame (a simulation of simplicity), which is the
//!   top-left rule of rasterization. On the border of the surface, where the displaced ray
//!   may leave it, the triangle owns its boundary edges, and one triangle owns each vertex of
//!   the border (see `boundary`): a ray there hits the surface once.

use glam::{Vec3, Vec3A};

use super::boundary::Boundary;
use super::Corners;
use crate::math::unit_cross;

/// The largest `t` of a hit: a `t` that overflows to infinity is beyond any distance `f32`
/// holds, and no hit, in every query alike.
pub(crate) const T_LIMIT: f32 = f32::MAX;

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
    /// `1 / direction`, per component (±∞ for a zero component).
    pub inv_dir: Vec3A,
    /// Origin.
    pub origin: Vec3A,
    /// Axis permutation: the direction's largest component is axis `k[2]`; `k[0]` and
    /// `k[1]` become the frame's x and y.
    k: [usize; 3],
    /// Shear: `x' = x + shear[0]·z`, `y' = y + shear[1]·z` in the permuted axes, with
    /// `shear = (−d_x/d_z, −d_y/d_z)`.
    shear: [f32; 2],
    /// `1/d_z`: scales the frame's z into ray parameters.
    inv_dz: f32,
}

/// A triangle's corners by coordinate, as the traversal stores them:
/// `x = (v0.x, v1.x, v2.x)`, and so on, so that the test runs on all three at once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct SoaTriangle {
    x: Vec3A,
    y: Vec3A,
    z: Vec3A,
}

impl SoaTriangle {
    /// The triangle with corners `c`.
    pub fn new(c: &Corners) -> SoaTriangle {
        SoaTriangle {
            x: Vec3A::new(c[0].x, c[1].x, c[2].x),
            y: Vec3A::new(c[0].y, c[1].y, c[2].y),
            z: Vec3A::new(c[0].z, c[1].z, c[2].z),
        }
    }

    /// Its corners.
    pub fn corners(&self) -> Corners {
        [0, 1, 2].map(|k| Vec3A::new(self.x[k], self.y[k], self.z[k]))
    }
}

/// A hit of [`PreparedRay::hit`]: the ray parameter and the barycentric weights of the
/// triangle's second and third vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Crossing {
    pub t: f32,
    pub b1: f32,
    pub b2: f32,
}

/// The sheared frame of a ray along `d` (finite, not zero) as a number, `2·kz + s`: `kz` is
/// the axis of the largest `|d|` (the first of equals) and `s` is 1 when `d` is negative
/// along it. Branch-free selects, so that a packet's lanes compute it side by side.
#[inline(always)]
pub(crate) fn frame_code(d: [f32; 3]) -> u32 {
    let (ax, ay, az) = (d[0].abs(), d[1].abs(), d[2].abs());
    let y_over_x = ay > ax;
    let z_top = az > if y_over_x { ay } else { ax };
    let kz = if z_top { 2 } else { u32::from(y_over_x) };
    let along = if z_top {
        d[2]
    } else if y_over_x {
        d[1]
    } else {
        d[0]
    };
    2 * kz + u32::from(along < 0.0)
}

/// The axis permutation `[kx, ky, kz]` of the frame [`frame_code`] numbers: `kz` last, and
/// the frame kept right-handed so that a triangle's winding keeps its sign.
#[inline(always)]
pub(crate) fn frame_axes(code: u32) -> [usize; 3] {
    let kz = (code / 2) as usize;
    let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
    if code % 2 == 1 {
        [ky, kx, kz]
    } else {
        [kx, ky, kz]
    }
}

/// The shear `(−d_x/d_z, −d_y/d_z)` and `1/d_z` of a direction whose components in the
/// frame's permuted axes are `(dx, dy, dz)`: written once for a ray and for a packet's
/// lanes, which compute them side by side with the same results.
#[inline(always)]
pub(crate) fn shear_lane(dx: f32, dy: f32, dz: f32) -> ([f32; 2], f32) {
    ([-dx / dz, -dy / dz], 1.0 / dz)
}

impl PreparedRay {
    /// Prepares `origin + t·direction`; `None` when a component is not finite or the
    /// direction is zero (such rays hit nothing).
    #[inline(always)]
    pub fn new(origin: Vec3, direction: Vec3) -> Option<PreparedRay> {
        if !origin.is_finite() || !direction.is_finite() || direction == Vec3::ZERO {
            return None;
        }
        let k = frame_axes(frame_code(direction.to_array()));
        let (shear, inv_dz) = shear_lane(direction[k[0]], direction[k[1]], direction[k[2]]);
        Some(PreparedRay {
            inv_dir: Vec3A::from(direction).recip(),
            origin: Vec3A::from(origin),
            k,
            shear,
            inv_dz,
        })
    }

    /// The ray of origin `origin` whose direction's reciprocal is `inv_dir`, frame `k`
    /// ([`frame_axes`]) and shear ([`shear_lane`]): a packet's lane, prepared with its
    /// neighbours, as [`PreparedRay::new`] prepares it alone.
    #[inline(always)]
    pub(crate) fn from_parts(
        origin: [f32; 3],
        inv_dir: [f32; 3],
        k: [usize; 3],
        (shear, inv_dz): ([f32; 2], f32),
    ) -> PreparedRay {
        PreparedRay {
            inv_dir: Vec3A::from(inv_dir),
            origin: Vec3A::from(origin),
            k,
            shear,
            inv_dz,
        }
    }

    /// The axis permutation `[kx, ky, kz]` of the sheared frame.
    #[inline(always)]
    pub(crate) fn axes(&self) -> [usize; 3] {
        self.k
    }

    /// The shear `(−d_x/d_z, −d_y/d_z)` in the permuted axes.
    #[inline(always)]
    pub(crate) fn shear(&self) -> [f32; 2] {
        self.shear
    }

    /// `1/d_z` in the permuted axes.
    #[inline(always)]
    pub(crate) fn inv_dz(&self) -> f32 {
        self.inv_dz
    }

    /// Intersects the triangle `tri`, whose part of the surface's border is `boundary` (used
    /// by [`EdgeRule::Owned`] only), for `t` in `[t_min, t_max]` (and at most [`T_LIMIT`])
    /// under `rule`. Two-sided; degenerate triangles and triangles seen exactly edge-on are
    /// missed. Exact for corners and origins within
    /// ±[`MAX_COORDINATE`](crate::scale::MAX_COORDINATE): no product overflows there.
    #[inline(always)]
    pub fn hit(
        &self,
        tri: &SoaTriangle,
        boundary: Boundary,
        t_min: f32,
        t_max: f32,
        rule: EdgeRule,
    ) -> Option<Crossing> {
        let f = self.sheared(tri);
        let mut uvw = edge_functions(&f, |a, b, c, d| a * b - c * d);
        if uvw.contains(&0.0) {
            uvw = edge_functions(&f, edge_f64);
        }
        if uvw.iter().any(|&e| e < 0.0) && uvw.iter().any(|&e| e > 0.0) {
            return None;
        }
        let det = sum(uvw);
        if det == 0.0 || det.is_nan() {
            return None;
        }
        if rule == EdgeRule::Owned && uvw.contains(&0.0) {
            // Edge `k` in the frame, from corner `k + 1` to corner `k + 2`.
            let edge = |k: usize| {
                let (start, end) = (f[(k + 1) % 3], f[(k + 2) % 3]);
                (end.0 - start.0, end.1 - start.1)
            };
            let zeros = uvw.map(|e| e == 0.0);
            let top_left = |k: usize| {
                let (ex, ey) = edge(k);
                owned(ex, ey, det < 0.0)
            };
            if !owns(zeros, boundary, top_left) {
                return None;
            }
        }
        let inv_dz = self.inv_dz;
        let scaled_t = sum([0, 1, 2].map(|k| uvw[k] * (f[k].2 * inv_dz)));
        let inv_det = 1.0 / det;
        let mut t = scaled_t * inv_det;
        if overflows(t) {
            t = far_t(uvw, &f, inv_det, inv_dz);
        }
        if !(t >= t_min && t <= t_max.min(T_LIMIT)) {
            return None;
        }
        Some(Crossing {
            t,
            b1: uvw[1] * inv_det,
            b2: uvw[2] * inv_det,
        })
    }

    /// The corners of `tri` in the ray's sheared frame ([`sheared`]).
    #[inline(always)]
    fn sheared(&self, tri: &SoaTriangle) -> Sheared {
        let [kx, ky, kz] = self.k;
        let axes = [tri.x, tri.y, tri.z];
        let c = [0, 1, 2].map(|corner| [axes[kx][corner], axes[ky][corner], axes[kz][corner]]);
        let o = self.origin;
        sheared(c, [o[kx], o[ky], o[kz]], (self.shear[0], self.shear[1]))
    }
}

/// A triangle's corners in a ray's sheared frame: `(x, y, z)` each.
type Sheared = [(f32, f32, f32); 3];

/// The corners `c` (each by permuted axis) in the sheared frame of the ray whose origin by
/// permuted axis is `o` and whose shear is `(sx, sy)`. Each corner depends on its vertex
/// alone, so a vertex shared by two triangles lands on the same point.
#[inline(always)]
fn sheared(c: [[f32; 3]; 3], o: [f32; 3], (sx, sy): (f32, f32)) -> Sheared {
    c.map(|c| {
        let fz = c[2] - o[2];
        ((c[0] - o[0]) + sx * fz, (c[1] - o[1]) + sy * fz, fz)
    })
}

/// The edge functions `x2·y1 − y2·x1`, by `diff(x2, y1, y2, x1)`: `u` of edge B→C (the
/// weight of A), `v` of C→A, `w` of A→B, edge `k` running from corner `k + 1` (`x1, y1`) to
/// corner `k + 2` (`x2, y2`).
#[inline(always)]
fn edge_functions(f: &Sheared, diff: impl Fn(f32, f32, f32, f32) -> f32) -> [f32; 3] {
    [0, 1, 2].map(|k| {
        let (start, end) = (f[(k + 1) % 3], f[(k + 2) % 3]);
        diff(end.0, start.1, end.1, start.0)
    })
}

/// `(x + y) + (z + 0)`: the sum of glam's `Vec3A::element_sum`, kept for its answers.
#[inline(always)]
fn sum(v: [f32; 3]) -> f32 {
    (v[0] + v[1]) + (v[2] + 0.0)
}

/// One SIMD lane of [`PreparedRay::hit`], operation for operation (the same differences,
/// products and sums in the same order, no fused multiply-add), without its exact re-tests:
/// the triangle with corners `c` (each by permuted axis, `[c[kx], c[ky], c[kz]]`) against the
/// ray whose origin by permuted axis is `o`, with shear `(sx, sy)` and `1/d_z` `inv_dz`.
/// Callers run it with a lane per triangle (a leaf's group) or a lane per ray (a packet).
///
/// Returns `(exact, inside, t, b1, b2)`: `exact` when an edge function rounds to zero, or
/// when the lane is inside but its `t` overflowed (then [`PreparedRay::hit`] itself must
/// answer, with its `f64` re-test or its other order for `t`); `inside` when the ray meets
/// the triangle (not edge-on, not degenerate), `t` still to be bounded by the caller.
#[inline(always)]
pub(crate) fn hit_lane(
    c: [[f32; 3]; 3],
    o: [f32; 3],
    (sx, sy): (f32, f32),
    inv_dz: f32,
) -> (bool, bool, f32, f32, f32) {
    let f = sheared(c, o, (sx, sy));
    let [u, v, w] = edge_functions(&f, |a, b, c, d| a * b - c * d);
    let zero = (u == 0.0) | (v == 0.0) | (w == 0.0);
    let negative = (u < 0.0) | (v < 0.0) | (w < 0.0);
    let positive = (u > 0.0) | (v > 0.0) | (w > 0.0);
    let det = sum([u, v, w]);
    let scaled_t = sum([
        u * (f[0].2 * inv_dz),
        v * (f[1].2 * inv_dz),
        w * (f[2].2 * inv_dz),
    ]);
    let inv_det = 1.0 / det;
    let t = scaled_t * inv_det;
    // `det` is not 0 and not NaN.
    #[allow(clippy::eq_op)]
    let inside = !(negative & positive) & (det != 0.0) & (det == det);
    let exact = zero | (inside & overflows(t));
    (exact, inside, t, v * inv_det, w * inv_det)
}

/// True when a hit's `t` came out infinite or NaN: for a short direction far from the
/// triangle, the products `uvw·(fz/d_z)` overflow (the group and packet tests hand such
/// lanes to [`PreparedRay::hit`], which recomputes `t` with [`far_t`]).
#[inline(always)]
pub(crate) fn overflows(t: f32) -> bool {
    !t.is_finite()
}

/// `t = Σ uvw·fz / det / d_z`, dividing by `d_z` last: each product `uvw·fz` is at most 64·R³
/// for corners and origins within ±R (`MAX_COORDINATE`), whatever the direction's length.
/// The usual order (`fz/d_z` first) is kept where it does not overflow, so that ordinary
/// answers stay bit for bit what they were.
#[inline(never)]
fn far_t(uvw: [f32; 3], f: &Sheared, inv_det: f32, inv_dz: f32) -> f32 {
    sum([0, 1, 2].map(|k| uvw[k] * f[k].2)) * inv_det * inv_dz
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

/// Whether a triangle whose edge functions are zero where `zeros` says (one: the ray is on
/// that edge; two: on the vertex they share) counts the hit: the border's own rule on its
/// edges and vertices (see `boundary`), else the displaced ray's, `top_left(k)` for edge `k`.
#[inline(never)]
fn owns(zeros: [bool; 3], boundary: Boundary, top_left: impl Fn(usize) -> bool) -> bool {
    let all_top_left = || (0..3).all(|k| !zeros[k] || top_left(k));
    match zeros {
        // On a vertex: the two zero edges share the corner opposite the third edge.
        [true, true, false] | [true, false, true] | [false, true, true] => {
            let corner = zeros.iter().position(|z| !z).unwrap_or(0);
            boundary.vertex(corner).unwrap_or_else(all_top_left)
        }
        _ => match zeros.iter().position(|&z| z) {
            Some(k) if boundary.edge(k) => true,
            _ => all_top_left(),
        },
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
pub(crate) fn unit_normal(tri: &Corners) -> Vec3 {
    let [a, b, c] = tri.map(Vec3::from);
    unit_cross(b - a, c - a)
}
