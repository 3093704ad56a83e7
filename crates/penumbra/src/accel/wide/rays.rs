//! A packet's rays by lane: `N` rays prepared side by side for the packet walk (`packets`),
//! by the same operations as [`PreparedRay::new`] on one ray, in plain loops over lanes that
//! compile to vector instructions.

use crate::accel::lanes::lane;
use crate::accel::prim::watertight::{frame_axes, frame_code, shear_lane, PreparedRay};

/// `N` rays by lane, prepared side by side, in the watertight test's permuted axes (shared
/// by all lanes).
pub(super) struct Lanes<const N: usize> {
    /// The axis permutation `[kx, ky, kz]`.
    pub(super) k: [usize; 3],
    /// Origin and `1/direction` by world axis.
    pub(super) origin: [[f32; N]; 3],
    pub(super) inv_dir: [[f32; N]; 3],
    /// Origin by permuted axis, shear and `1/d_z`.
    pub(super) permuted: [[f32; N]; 3],
    pub(super) shear: [[f32; N]; 2],
    pub(super) inv_dz: [f32; N],
}

impl<const N: usize> Lanes<N> {
    /// Lane `i`'s ray, as [`PreparedRay::new`] prepares it: for the one-ray tests of a lane
    /// on an edge and of a leaf lane by lane.
    #[inline(always)]
    pub(super) fn ray(&self, i: usize) -> PreparedRay {
        let shear = ([self.shear[0][i], self.shear[1][i]], self.inv_dz[i]);
        PreparedRay::from_parts(lane(&self.origin, i), lane(&self.inv_dir, i), self.k, shear)
    }
}

/// The packet of `rays` when there are `N`, each one that [`PreparedRay::new`] prepares
/// (finite, with a direction), all with one axis permutation; prepared by the same
/// operations, lane by lane in plain loops that compile to vector instructions (six
/// divisions a ray, where preparing rays one by one cost a third as much as the walk).
#[allow(clippy::needless_range_loop)]
#[inline(always)]
pub(super) fn lanes<const N: usize>(rays: &[[f32; 6]]) -> Option<Lanes<N>> {
    if rays.len() != N {
        return None;
    }
    let (mut origin, mut dir) = ([[0.0f32; N]; 3], [[0.0f32; N]; 3]);
    for (i, r) in rays.iter().enumerate() {
        for a in 0..3 {
            origin[a][i] = r[a];
            dir[a][i] = r[3 + a];
        }
    }
    // Per lane, 0 when the ray is valid and in lane 0's frame; one vector pass, no branch.
    let code = frame_code(lane(&dir, 0));
    let mut off = [0u32; N];
    for i in 0..N {
        let d = lane(&dir, i);
        let mut finite = true;
        for a in 0..3 {
            finite &= (origin[a][i].abs() < f32::INFINITY) & (d[a].abs() < f32::INFINITY);
        }
        let moving = (d[0] != 0.0) | (d[1] != 0.0) | (d[2] != 0.0);
        off[i] = u32::from(!(finite & moving)) | (frame_code(d) ^ code);
    }
    if off.iter().fold(0, |a, &b| a | b) != 0 {
        return None;
    }
    let k = frame_axes(code);
    let mut lanes = Lanes {
        k,
        origin,
        inv_dir: [[0.0; N]; 3],
        permuted: [origin[k[0]], origin[k[1]], origin[k[2]]],
        shear: [[0.0; N]; 2],
        inv_dz: [0.0; N],
    };
    let (dx, dy, dz) = (&dir[k[0]], &dir[k[1]], &dir[k[2]]);
    for i in 0..N {
        for a in 0..3 {
            lanes.inv_dir[a][i] = 1.0 / dir[a][i];
        }
        let (shear, inv_dz) = shear_lane(dx[i], dy[i], dz[i]);
        (lanes.shear[0][i], lanes.shear[1][i]) = (shear[0], shear[1]);
        lanes.inv_dz[i] = inv_dz;
    }
    Some(lanes)
}

/// Each lane's ray of the packet of `rays`, as [`lanes`] prepares them (`None`: no packet).
#[cfg(test)]
pub(crate) fn lane_rays<const N: usize>(rays: &[[f32; 6]]) -> Option<Vec<PreparedRay>> {
    lanes::<N>(rays).map(|l| (0..N).map(|i| l.ray(i)).collect())
}
