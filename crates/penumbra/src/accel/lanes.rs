//! SIMD lanes of rays, by axis (`[[f32; N]; 3]`, lane `i` of axis `a` at `[a][i]`), and the
//! one slab test of a box against `N` such rays that every packet uses: the renderer's fans
//! and bundles on the binary tree and ray casting's packets on the wide tree's children.
//!
//! The lanes are plain loops over fixed-size arrays, which the compiler turns into vector
//! instructions when they are inlined into a kernel that `crate::simd` compiles per
//! instruction set.

use super::wide::{raised, tie_bound};
use crate::simd::{max, min, Isa};

/// Lane `i` of `v` by axis.
#[inline(always)]
pub(crate) fn lane<const N: usize>(v: &[[f32; N]; 3], i: usize) -> [f32; 3] {
    [v[0][i], v[1][i], v[2][i]]
}

/// The lanes (bit `i` for lane `i`) whose ray enters a box with `t` in `[t_min, t_max[i]]`,
/// and each lane's entry distance (at least `t_min`). `rel(a, i)` is the box's smallest and
/// largest coordinates along axis `a` less lane `i`'s origin, `inv` the rays' reciprocal
/// directions; the exit distance is raised by the margin `exit_scale` ([`raised`]: ray
/// casting's `1 + 2γ₃`, Ize 2013; the renderer passes 1, which the compiler removes).
///
/// The bound `t_max[i]` is widened by [`tie_bound`], as ray casting widens it: a box whose
/// computed entry is a few ulps past a lane's closest hit may still hold a triangle at
/// exactly that `t` (a ray through the edge two triangles share), and the closest-hit rule
/// takes the smaller index among equal `t`s. Pruning such a box would make the answer depend
/// on the order of the visit, which differs between packets of different sizes. Widening
/// only adds visits: every triangle test keeps its own exact bound.
///
/// On padded boxes (see `build`) `bound − origin` is zero only for rays outside the true box,
/// so a NaN from `0·∞` only turns a miss into a miss: `min`/`max` need no NaN care, and the
/// test only prunes.
// Lane loops index several arrays by lane; that is what vectorizes.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
pub(crate) fn slab<const N: usize, I: Isa>(
    rel: impl Fn(usize, usize) -> (f32, f32),
    inv: &[[f32; N]; 3],
    t_min: f32,
    t_max: &[f32; N],
    exit_scale: f32,
) -> (u32, [f32; N]) {
    let mut inside = [0i32; N];
    let mut entry = [0.0; N];
    for i in 0..N {
        let t = [0, 1, 2].map(|a| {
            let (lo, hi) = rel(a, i);
            (lo * inv[a][i], hi * inv[a][i])
        });
        let [(x0, x1), (y0, y1), (z0, z1)] = t;
        let near = max(max(max(min(x0, x1), min(y0, y1)), min(z0, z1)), t_min);
        let far = min(
            raised(min(min(max(x0, x1), max(y0, y1)), max(z0, z1)), exit_scale),
            tie_bound(t_max[i]),
        );
        inside[i] = -((near <= far) as i32);
        entry[i] = near;
    }
    (I::mask(&inside), entry)
}
