//! The relative margins of the box tests. The exit distance is Ize's ("Robust BVH Ray
//! Traversal", JCGT 2013): raised by a relative `2γ₃` (scaled by `1 + 2γ₃`, or by `1 − 2γ₃`
//! behind the origin: [`raised`]), which covers the rounding of the slab distances, so a box
//! is never skipped by a ray that meets it; the closest-hit walks prune by [`tie_bound`].

use crate::simd::max;

/// `1 + 2⁻¹⁶`: see [`tie_bound`].
const TIE_SCALE: f32 = 1.0 + 1.0 / 65536.0;

/// The distance past which the closest-hit visits prune a box, for a closest hit so far at
/// `t_max`. The computed entry distance of a box and the computed `t` of a triangle in it may
/// disagree by a few ulps (the boxes are padded by 2⁻²⁰ of their coordinates, but by almost
/// nothing at a coordinate 0), so boxes are pruned only past `t_max·(1 + 2⁻¹⁶)`, a margin far
/// above that: a triangle hit at exactly the closest `t` is then tested whatever the order of
/// the visit, and the rule for ties does not depend on that order.
#[inline(always)]
pub(crate) fn tie_bound(t_max: f32) -> f32 {
    raised(t_max, TIE_SCALE)
}

/// `t` raised by the relative margin `scale − 1` (`scale ≥ 1`): `t·scale` where `t ≥ 0` (bit
/// for bit), `t·(2 − scale)` where `t < 0`. The box tests widen their bounds this way, the
/// exit distance by [`EXIT_SCALE`] and the closest hit by [`tie_bound`]'s margin: behind the
/// origin (a query's `tnear < 0`) multiplying by `scale` would move a negative bound down,
/// narrowing the interval, and a flat box there (its entry and exit a few ulps apart) would
/// be skipped. `2 − scale` is exact for both scales.
#[inline(always)]
pub(crate) fn raised(t: f32, scale: f32) -> f32 {
    max(t * scale, t * (2.0 - scale))
}

/// `1 + 2γ₃` with `γₙ = nε / (1 − nε)` and `ε = 2⁻²⁴`: the exit-distance scale that keeps
/// the `f32` slab test conservative (Ize 2013).
pub(crate) const EXIT_SCALE: f32 = 1.0 + 2.0 * (3.0 * EPS / (1.0 - 3.0 * EPS));
const EPS: f32 = f32::EPSILON * 0.5;
