//! Shadow-ray packets over the four-wide tree: like `packet`, but each visit tests the
//! packet against all four children of a wide node, tests the triangles of the leaf children
//! at once, and descends into the nearest interior child (by the first live lane's entry
//! distance), keeping the others on the stack with the lanes that entered them.
//!
//! Before the per-lane slab tests, the four children are tested at once against the whole
//! packet (`Spread`): with the origin shared, a lane's slab distances are `(corner − o)·inv`,
//! and rounding is monotonic, so the products with the smallest and largest `inv` of the packet
//! bound every lane's computed distances. A child this test rejects is one that every lane's
//! own test rejects too; it only saves work, and the lane masks stay the same.
//!
//! Exactness: the triangle test is `packet`'s lane for lane, and the boxes are the binary
//! tree's padded boxes, so a lane is occluded exactly when [`Bvh::occluded`] says so.

use glam::{Vec3, Vec4};

use super::packet::{slab_box, triangle};
use super::wide::{WideNode, WIDTH};
use super::{Bvh, STACK_SIZE};
use crate::simd::Isa;

/// The packet's inverse directions per axis: smallest and largest over its live lanes, and
/// whether the axis bounds anything (all lanes finite and of one sign).
struct Spread {
    lo: [f32; 3],
    hi: [f32; 3],
    bounded: [bool; 3],
}

impl Spread {
    #[allow(clippy::needless_range_loop)]
    #[inline(always)]
    fn new<const N: usize>(inv: &[[f32; N]; 3], active: u32) -> Spread {
        let mut spread = Spread {
            lo: [f32::INFINITY; 3],
            hi: [f32::NEG_INFINITY; 3],
            bounded: [false; 3],
        };
        let live: [bool; N] = std::array::from_fn(|i| active & (1 << i) != 0);
        for a in 0..3 {
            // Dead lanes as ±∞, then one reduction per bound: vector code.
            let lows: [f32; N] =
                std::array::from_fn(|i| if live[i] { inv[a][i] } else { f32::INFINITY });
            let highs: [f32; N] = std::array::from_fn(|i| {
                if live[i] {
                    inv[a][i]
                } else {
                    f32::NEG_INFINITY
                }
            });
            spread.lo[a] = lows.into_iter().fold(f32::INFINITY, f32::min);
            spread.hi[a] = highs.into_iter().fold(f32::NEG_INFINITY, f32::max);
            let (lo, hi) = (spread.lo[a], spread.hi[a]);
            spread.bounded[a] = lo.is_finite() && hi.is_finite() && (lo > 0.0 || hi < 0.0);
        }
        spread
    }

    /// The children of `node` that some lane may enter within `(0, t_max)`: the others every
    /// lane's slab test rejects.
    #[inline(always)]
    fn may_enter(&self, node: &WideNode, o: &[f32; 3], t_max: f32) -> u32 {
        let (min, max) = node.corners();
        let mut near = Vec4::ZERO;
        let mut far = Vec4::splat(t_max);
        for a in 0..3 {
            if !self.bounded[a] {
                continue;
            }
            let origin = Vec4::splat(o[a]);
            let (lo, hi) = (Vec4::from(min[a]) - origin, Vec4::from(max[a]) - origin);
            // The near plane is `lo` for positive directions, `hi` for negative ones.
            let (entry, exit) = if self.lo[a] > 0.0 { (lo, hi) } else { (hi, lo) };
            let (i0, i1) = (Vec4::splat(self.lo[a]), Vec4::splat(self.hi[a]));
            near = near.max((entry * i0).min(entry * i1));
            far = far.min((exit * i0).max(exit * i1));
        }
        !near.cmpgt(far).bitmask() & node.used_mask()
    }
}

/// Marks `blocked[i]` for each segment from `origin` to `ends[i]` (`ends.len() <= N`) that is
/// not blocked yet and that a triangle meets for `t` in `(0, t_max)`.
#[inline(always)]
pub(super) fn occlude_packet<const N: usize, I: Isa>(
    bvh: &Bvh,
    origin: Vec3,
    ends: &[Vec3],
    t_max: f32,
    blocked: &mut [bool],
) {
    debug_assert!(N <= 32 && !ends.is_empty() && ends.len() <= N && ends.len() == blocked.len());
    let count = ends.len();
    // Lanes past `count` repeat the last segment and start inactive, as do blocked lanes.
    let mut dir = [[0.0f32; N]; 3];
    // Lane i is bit i.
    let mut active: u32 = 0;
    for i in 0..N {
        let d = ends[i.min(count - 1)] - origin;
        for a in 0..3 {
            dir[a][i] = d[a];
        }
        active |= ((i < count && !blocked[i]) as u32) << i;
    }
    let mut inv = [[0.0f32; N]; 3];
    for a in 0..3 {
        for i in 0..N {
            inv[a][i] = 1.0 / dir[a][i];
        }
    }
    let o = origin.to_array();
    let far = [t_max; N];
    let root = &bvh.nodes[0];
    if slab_box::<N, I>(&root.min, &root.max, &o, &inv, 0.0, &far).0 & active == 0 {
        return;
    }
    let spread = Spread::new(&inv, active);

    // Waiting interior children: wide index and the lanes that entered.
    let mut stack = [(0u32, 0u32); 3 * STACK_SIZE];
    let mut sp = 0;
    let mut current = 0usize;
    'nodes: loop {
        let node = &bvh.wide[current];
        let mut inner = [(0u32, 0u32, 0.0f32); WIDTH];
        let mut inner_len = 0;
        let mut candidates = spread.may_enter(node, &o, t_max);
        while candidates != 0 {
            let lane = candidates.trailing_zeros() as usize;
            candidates &= candidates - 1;
            let (min, max) = node.bounds(lane);
            let (mask, entry) = slab_box::<N, I>(&min, &max, &o, &inv, 0.0, &far);
            let mask = mask & active;
            if mask == 0 {
                continue;
            }
            let (child, tris) = node.child(lane);
            if tris == 0 {
                let first_lane = active.trailing_zeros() as usize;
                inner[inner_len] = (child, mask, entry[first_lane]);
                inner_len += 1;
                continue;
            }
            let first = child as usize;
            for tri in &bvh.tris[first..first + tris as usize] {
                active &= !triangle::<N, I>(tri, origin, &dir, t_max);
                if active == 0 {
                    break 'nodes;
                }
            }
        }
        // The nearest interior child next, the others on the stack, far to near.
        let inner = &mut inner[..inner_len];
        inner.sort_unstable_by(|a, b| b.2.total_cmp(&a.2));
        let mut next = None;
        for &(child, mask, _) in inner.iter() {
            if mask & active != 0 {
                if let Some(prev) = next.replace((child, mask)) {
                    stack[sp] = prev;
                    sp += 1;
                }
            }
        }
        if let Some((child, _)) = next {
            current = child as usize;
            continue;
        }
        // The next waiting subtree that a lane still live entered.
        loop {
            if sp == 0 {
                break 'nodes;
            }
            sp -= 1;
            let (index, mask) = stack[sp];
            if mask & active != 0 {
                current = index as usize;
                break;
            }
        }
    }
    for (i, b) in blocked.iter_mut().enumerate() {
        *b |= active & (1 << i) == 0;
    }
}
