//! Orders of query points that make neighbours in space neighbours in a batch, so that
//! their walks visit the same nodes one after the other: a Morton curve through the points
//! (closest points) and cells across a direction (occupancy's parallel rays).

use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// Query points per cell of [`across_order`]'s grid, about: a packet of 16 parallel rays
/// spans two by two cells.
const PER_CELL: usize = 4;

/// The indices of `points` by cells of a square grid across the direction `(1, 1, 1)`, the
/// cells along a Morton curve (in a cell, the given order; the non-finite points last): a
/// counting sort, as the keys are small. Rays along nearly that direction from points close
/// in this order run close together.
pub(super) fn across_order(points: &[[f32; 3]], pool: &rayon::ThreadPool) -> Vec<usize> {
    // Coordinates across (1, 1, 1), unnormalized: a Morton order needs no unit.
    let across = |&[x, y, z]: &[f32; 3]| Vec2::new(x - y, x + y - 2.0 * z);
    let (lo, hi) = pool.install(|| {
        points
            .par_iter()
            .map(across)
            .filter(|p| p.is_finite())
            .fold(
                || (Vec2::INFINITY, Vec2::NEG_INFINITY),
                |(lo, hi), p| (lo.min(p), hi.max(p)),
            )
            .reduce(
                || (Vec2::INFINITY, Vec2::NEG_INFINITY),
                |a, b| (a.0.min(b.0), a.1.max(b.1)),
            )
    });
    // Bits per axis: 4^bits cells, about `PER_CELL` points each (at most 2^20 cells).
    let cells = points.len().div_ceil(PER_CELL).max(1);
    let bits = (cells.ilog2().div_ceil(2)).clamp(1, 10);
    let side = ((1u32 << bits) - 1) as f32;
    // Cells per unit along each axis (0 for a flat extent or no finite point).
    let scale = (hi - lo).to_array().map(|e| {
        if e > 0.0 && e.is_finite() {
            side / e
        } else {
            0.0
        }
    });
    let scale = Vec2::from(scale);
    let last = 1usize << (2 * bits);
    let key = |p: &[f32; 3]| {
        let p = across(p);
        if !p.is_finite() {
            return last as u32;
        }
        let c = ((p - lo) * scale)
            .clamp(Vec2::ZERO, Vec2::splat(side))
            .as_uvec2();
        spread(c.x) | spread(c.y) << 1
    };
    let keys: Vec<u32> = pool.install(|| points.par_iter().map(key).collect());
    pool.install(|| counting_sort(&keys, last))
}

/// The indices `0..keys.len()` sorted by their key (each at most `last`), stably: a counting
/// sort on the current pool's threads. The cells' counts are summed over parts of the keys;
/// then the cells are cut into one run per thread, about as many points each, and each
/// thread scans every key and places those of its cells, in order, in its own part of the
/// result (a serial sort was a large serial part of occupancy at 2 threads; measured:
/// docs/benchmarks.md, «Design measurements», `counting_sort`).
fn counting_sort(keys: &[u32], last: usize) -> Vec<usize> {
    let threads = rayon::current_num_threads().max(1);
    let part = keys.len().div_ceil(threads).max(1);
    // `start[k]`: the first place of cell `k` (`start[last + 1]` is the end).
    let mut start = keys
        .par_chunks(part)
        .map(|keys| {
            let mut count = vec![0usize; last + 2];
            for &k in keys {
                count[k as usize + 1] += 1;
            }
            count
        })
        .reduce_with(|mut a, b| {
            a.iter_mut().zip(&b).for_each(|(a, b)| *a += b);
            a
        })
        .unwrap_or_else(|| vec![0; last + 2]);
    for k in 1..start.len() {
        start[k] += start[k - 1];
    }
    // Runs of cells `cells[t]..cells[t + 1]`, each a contiguous part of the result.
    let mut cells = vec![0usize];
    for t in 1..threads {
        let cut = start.partition_point(|&s| s < t * keys.len() / threads);
        cells.push(cut.clamp(cells[t - 1], last + 1));
    }
    cells.push(last + 1);
    let mut order = vec![0; keys.len()];
    let mut runs = Vec::with_capacity(threads);
    let mut rest = &mut order[..];
    for t in 0..threads {
        let (run, tail) = rest.split_at_mut(start[cells[t + 1]] - start[cells[t]]);
        runs.push((cells[t]..cells[t + 1], run));
        rest = tail;
    }
    runs.into_par_iter().for_each(|(cells, run)| {
        let base = start[cells.start];
        let mut next: Vec<usize> = start[cells.clone()].iter().map(|s| s - base).collect();
        for (i, &k) in keys.iter().enumerate() {
            if cells.contains(&(k as usize)) {
                let place = &mut next[k as usize - cells.start];
                run[*place] = i;
                *place += 1;
            }
        }
    });
    order
}

/// The low 16 bits of `x` spread to the even bits (a 2-D Morton code's x).
fn spread(x: u32) -> u32 {
    let x = x & 0xffff;
    let x = (x | x << 8) & 0x00ff_00ff;
    let x = (x | x << 4) & 0x0f0f_0f0f;
    let x = (x | x << 2) & 0x3333_3333;
    (x | x << 1) & 0x5555_5555
}

/// The indices of `points` along a Morton curve through their box (10 bits per axis; the
/// non-finite ones last), and the inverse: `rank[order[k]] = k`. More than 2³² points keep
/// their order.
pub(super) fn morton_order(
    points: &[[f32; 3]],
    pool: &rayon::ThreadPool,
) -> (Vec<usize>, Vec<usize>) {
    let (lo, hi) = points
        .iter()
        .map(|&p| Vec3::from(p))
        .filter(|p| p.is_finite())
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        });
    // Cells per unit along each axis (0 for a flat extent or no finite point).
    let scale = (hi - lo).to_array().map(|e| {
        if e > 0.0 && e.is_finite() {
            1023.0 / e
        } else {
            0.0
        }
    });
    let scale = Vec3::from(scale);
    // Each axis' 10 bits spread to every third bit.
    let spread = |x: u32| (0..10).fold(0u64, |code, b| code | (((x as u64 >> b) & 1) << (3 * b)));
    let key = |(i, p): (usize, &[f32; 3])| {
        let p = Vec3::from(*p);
        let code = if p.is_finite() {
            let c = ((p - lo) * scale)
                .clamp(Vec3::ZERO, Vec3::splat(1023.0))
                .as_uvec3();
            spread(c.x) | spread(c.y) << 1 | spread(c.z) << 2
        } else {
            1 << 30
        };
        (code << 32) | i as u64
    };
    let order: Vec<usize> = if u32::try_from(points.len()).is_ok() {
        let mut keys: Vec<u64> = pool.install(|| points.par_iter().enumerate().map(key).collect());
        pool.install(|| keys.par_sort_unstable());
        keys.iter().map(|&k| k as u32 as usize).collect()
    } else {
        (0..points.len()).collect()
    };
    let mut rank = vec![0; order.len()];
    for (k, &i) in order.iter().enumerate() {
        rank[i] = k;
    }
    (order, rank)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn across_order_is_a_permutation_with_the_non_finite_points_last() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        for n in [0, 1, 5, 1000] {
            let mut points: Vec<[f32; 3]> = (0..n)
                .map(|i| {
                    let x = (i * 37 % 101) as f32;
                    [x, (i % 7) as f32, -(i as f32)]
                })
                .collect();
            if n > 3 {
                points[2] = [f32::NAN, 0.0, 0.0];
                points[3] = [0.0, 0.0, f32::NEG_INFINITY];
            }
            let order = across_order(&points, &pool);
            let mut seen = order.clone();
            seen.sort_unstable();
            assert_eq!(seen, (0..n).collect::<Vec<_>>());
            if n > 3 {
                assert_eq!(
                    &order[n - 2..],
                    &[2, 3],
                    "non-finite last, in the given order"
                );
            }
        }
    }

    #[test]
    fn the_counting_sort_is_a_stable_sort_on_any_number_of_threads() {
        let mut rng = crate::sampling::Rng::new(5, &[]);
        for (n, last) in [(0, 4), (1, 4), (7, 4), (1000, 16), (5000, 1 << 12)] {
            let keys: Vec<u32> = (0..n)
                .map(|_| ((rng.uniform() * (last + 1) as f32) as u32).min(last as u32))
                .collect();
            let mut want: Vec<usize> = (0..n).collect();
            want.sort_by_key(|&i| keys[i]);
            for threads in [1, 2, 3, 8] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let got = pool.install(|| counting_sort(&keys, last));
                assert_eq!(got, want, "{n} keys up to {last}, {threads} threads");
            }
        }
    }

    #[test]
    fn points_on_one_line_along_the_rays_share_a_cell() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        // Points on two lines along (1, 1, 1), interleaved: each line's points come together.
        let points: Vec<[f32; 3]> = (0..64)
            .map(|i| {
                let s = (i / 2) as f32;
                let base = if i % 2 == 0 { 0.0 } else { 10.0 };
                [base + s, s, s]
            })
            .collect();
        let order = across_order(&points, &pool);
        let first: Vec<usize> = order[..32].iter().map(|i| i % 2).collect();
        assert!(first.iter().all(|&l| l == first[0]), "{order:?}");
    }
}
