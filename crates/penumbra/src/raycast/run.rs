//! How a batch query runs: on a pool of the scene's own (never rayon's global pool), in
//! chunks of rays, with a cancel flag checked between chunks (and by the kernels every few
//! rays, see `accel::wide::kernels`); results allocated fallibly within the memory the
//! process may take; ray origins checked against the largest coordinate.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use rayon::prelude::*;

use super::RaycastError;
use crate::accel::wide::control::Control;
use crate::pool::thread_pool;
use crate::scale::MAX_COORDINATE;

/// Rays (or points) per parallel work item: large enough that scheduling costs nothing,
/// small enough that two threads share a small batch and a cancel is seen within
/// microseconds.
pub(crate) const CHUNK: usize = 1024;

/// How a batch query runs: its worker count and an optional cancel flag.
///
/// ```
/// use std::sync::atomic::AtomicBool;
/// use penumbra::QueryOptions;
///
/// let cancel = AtomicBool::new(false);
/// let options = QueryOptions { threads: 2, cancel: Some(&cancel) };
/// assert_eq!(QueryOptions::default().threads, 0);
/// # let _ = options;
/// ```
#[derive(Clone, Copy, Debug, Default)]
pub struct QueryOptions<'a> {
    /// Worker threads: 0 for one per core this process may use. The work runs on a pool of
    /// the scene's own, kept between calls with the same count.
    pub threads: usize,
    /// When set to true (from another thread, a signal handler…), the query stops within 8
    /// rays per thread (or while it waits for the BVH's build) and returns
    /// [`RaycastError::Cancelled`].
    pub cancel: Option<&'a AtomicBool>,
}

impl QueryOptions<'_> {
    /// True when the caller asked the query to stop.
    pub(crate) fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
    }
}

/// The engine's batch kernels stop, and grow their results, as the options say.
impl Control for QueryOptions<'_> {
    type Error = RaycastError;

    fn cancelled(&self) -> bool {
        QueryOptions::cancelled(self)
    }

    fn cancel_error(&self) -> RaycastError {
        RaycastError::Cancelled
    }

    fn grow<T>(
        &self,
        v: &mut Vec<T>,
        additional: usize,
        what: &'static str,
    ) -> Result<(), RaycastError> {
        grow(v, additional, what)
    }
}

/// The scene's worker pool, rebuilt only when the requested thread count changes.
#[derive(Debug, Default)]
pub(crate) struct Pools {
    pool: Mutex<Option<(usize, Arc<rayon::ThreadPool>)>>,
}

impl Pools {
    /// A pool of `threads` workers (0: one per core).
    pub fn get(&self, threads: usize) -> Result<Arc<rayon::ThreadPool>, RaycastError> {
        let mut slot = self.pool.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((n, pool)) = slot.as_ref() {
            if *n == threads {
                return Ok(pool.clone());
            }
        }
        let (pool, _) = thread_pool(threads).map_err(RaycastError::Threads)?;
        let pool = Arc::new(pool);
        *slot = Some((threads, pool.clone()));
        Ok(pool)
    }
}

/// Runs `f` on every item of `items` on `pool`, skipping the rest once `options` is
/// cancelled; `Err(Cancelled)` then.
pub(crate) fn run<I, F>(
    pool: &rayon::ThreadPool,
    options: &QueryOptions,
    items: I,
    f: F,
) -> Result<(), RaycastError>
where
    I: IndexedParallelIterator,
    F: Fn(I::Item) + Sync + Send,
{
    pool.install(|| {
        items.for_each(|item| {
            if !options.cancelled() {
                f(item)
            }
        })
    });
    if options.cancelled() {
        Err(RaycastError::Cancelled)
    } else {
        Ok(())
    }
}

/// True when a coordinate of `point` is beyond ±[`MAX_COORDINATE`] (NaN and infinities are
/// not: such rays miss).
#[inline]
pub(crate) fn beyond(point: &[f32]) -> bool {
    point
        .iter()
        .any(|c| c.is_finite() && c.abs() > MAX_COORDINATE)
}

/// The first ray of a batch whose origin is beyond ±[`MAX_COORDINATE`], found by the
/// workers chunk by chunk (where the rays are read anyway) rather than by a pass of its own.
#[derive(Debug)]
pub(crate) struct FarOrigins(AtomicUsize);

impl FarOrigins {
    pub fn new() -> FarOrigins {
        FarOrigins(AtomicUsize::new(usize::MAX))
    }

    /// Notes the first far origin of `rays`, the rays from index `base` on.
    #[inline]
    pub fn check(&self, base: usize, rays: &[[f32; 6]]) {
        // A branch-free pass first (vectorized, a microsecond per chunk), the search only when
        // it finds something (an infinite origin passes it, and then the search finds none).
        let large = |c: f32| c.abs() > MAX_COORDINATE;
        let any = rays.iter().fold(false, |any, r| {
            any | large(r[0]) | large(r[1]) | large(r[2])
        });
        if !any {
            return;
        }
        if let Some(i) = rays.iter().position(|r| beyond(&r[..3])) {
            self.0.fetch_min(base + i, Ordering::Relaxed);
        }
    }

    /// `Err(Beyond)` naming the first far origin noted.
    pub fn result(&self) -> Result<(), RaycastError> {
        match self.0.load(Ordering::Relaxed) {
            usize::MAX => Ok(()),
            index => Err(RaycastError::Beyond { what: "ray", index }),
        }
    }
}

/// Sizes below this are only asked of the allocator; above, also checked against what the
/// process may still take (`memory::available`, a few file reads).
const CHECKED: u64 = 64 << 20;

/// An empty vector with room for `n` values of `what`, or `Err(OutOfMemory)` when that is
/// more than the process may take or the allocator refuses: never an abort.
pub(crate) fn room<T>(n: usize, what: &'static str) -> Result<Vec<T>, RaycastError> {
    budget(&[(n, size_of::<T>())], what)?;
    let mut v = Vec::new();
    v.try_reserve_exact(n)
        .map_err(|_| RaycastError::OutOfMemory {
            what,
            bytes: bytes(n, size_of::<T>()),
        })?;
    Ok(v)
}

/// Makes room in `v` for `additional` more values (doubling, as `push` does), fallibly and
/// within the budget of [`budget`]: for results that grow as they are found.
pub(crate) fn grow<T>(
    v: &mut Vec<T>,
    additional: usize,
    what: &'static str,
) -> Result<(), RaycastError> {
    let need = v.len().saturating_add(additional);
    if need <= v.capacity() {
        return Ok(());
    }
    let more = need.max(2 * v.capacity()) - v.len();
    budget(&[(more, size_of::<T>())], what)?;
    v.try_reserve_exact(more)
        .map_err(|_| RaycastError::OutOfMemory {
            what,
            bytes: bytes(need, size_of::<T>()),
        })
}

/// `n` values of `size` bytes, in bytes.
fn bytes(n: usize, size: usize) -> u64 {
    (n as u64).saturating_mul(size as u64)
}

/// `Err(OutOfMemory)` when arrays of `(count, size of one)` together are more than the
/// process may still take.
pub(crate) fn budget(arrays: &[(usize, usize)], what: &'static str) -> Result<(), RaycastError> {
    let total = arrays
        .iter()
        .fold(0u64, |sum, &(n, size)| sum.saturating_add(bytes(n, size)));
    let too_much = total > CHECKED && crate::memory::available().is_some_and(|a| total > a);
    if too_much || total > isize::MAX as u64 {
        return Err(RaycastError::OutOfMemory { what, bytes: total });
    }
    Ok(())
}

/// `n` copies of `value`, written by the workers of `pool` (in blocks of [`BLOCK`] values),
/// so that the pages of a large result are first touched in parallel rather than by the
/// caller alone, a serial part of a two-thread query on coherent rays (with this, coherent
/// `cast_rays` got faster on two threads and stayed the same on one). Zero-filled results come
/// here too: `vec![0; n]` is `calloc`, which takes fresh pages when the allocator maps new
/// memory, but clears memory it reuses with a `memset` on the calling thread alone. In a loop
/// of calls from Python, which reuses it, that made coherent `cast_rays` on two threads swing
/// widely in speed; with every result filled here, it swings less and mostly runs near the top
/// of that range (measured: docs/benchmarks.md, «Design measurements», `filled`).
///
/// The values are written [`SEGMENT`] at a time, with `options`' cancel flag checked before
/// each segment: the five results of 24 million rays are 770 MB, a third of a second or more
/// of page faults, which a Ctrl-C must not wait for. `Err(Cancelled)` then.
pub(crate) fn filled<T: Copy + Send + Sync>(
    pool: &rayon::ThreadPool,
    options: &QueryOptions,
    n: usize,
    value: T,
) -> Result<Vec<T>, RaycastError> {
    let count = n.div_ceil(BLOCK);
    let mut blocks: Vec<[T; BLOCK]> = room(count, "the result")?;
    if n <= ALONE {
        // Handing a few blocks to the pool's threads costs more than writing them here.
        blocks.resize(count, [value; BLOCK]);
    }
    while blocks.len() < count {
        if options.cancelled() {
            return Err(RaycastError::Cancelled);
        }
        let segment = (count - blocks.len()).min(SEGMENT / BLOCK);
        // An indexed iterator: rayon writes it in place, into the capacity reserved above.
        pool.install(|| {
            blocks.par_extend(
                rayon::iter::repeat_n([value; BLOCK], segment).with_min_len(CHUNK / BLOCK),
            )
        });
    }
    let mut out = blocks.into_flattened();
    out.truncate(n);
    Ok(out)
}

/// At most this many values [`filled`] writes on the calling thread (256 KB to 768 KB, tens
/// of microseconds: about what waking the pool's threads costs).
const ALONE: usize = 1 << 16;

/// Values per block of [`filled`].
const BLOCK: usize = 256;

/// Values [`filled`] writes between two looks at the cancel flag: 4 to 12 MB, milliseconds.
const SEGMENT: usize = 1 << 20;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pool::test_pool;

    #[test]
    fn filled_holds_exactly_n_copies() {
        let options = QueryOptions::default();
        for n in [0, 1, BLOCK - 1, BLOCK + 1, 3 * CHUNK + 7, SEGMENT + 1] {
            let v = filled(test_pool(), &options, n, [n as u32, 7]).unwrap();
            assert_eq!(v.len(), n);
            assert!(v.iter().all(|&x| x == [n as u32, 7]), "{n}");
        }
        let nan = filled(test_pool(), &options, 9, f32::NAN).unwrap();
        assert!(nan.iter().all(|x| x.is_nan()));
    }

    #[test]
    fn sizes_beyond_memory_are_errors_not_aborts() {
        // (count, what) of results no process can hold.
        let too_much = |r: Result<Vec<[f32; 6]>, RaycastError>| {
            matches!(r, Err(RaycastError::OutOfMemory { .. }))
        };
        for n in [usize::MAX / 24, usize::MAX / 48 + 1, 1 << 50] {
            assert!(too_much(room(n, "the rays")), "{n}");
        }
        let options = QueryOptions::default();
        let huge = filled(test_pool(), &options, 1 << 52, 0u64);
        assert!(matches!(huge, Err(RaycastError::OutOfMemory { .. })));
        assert!(budget(&[(usize::MAX, 8), (usize::MAX, 8)], "x").is_err());
        assert_eq!(room::<u8>(16, "x").map(|v| v.capacity() >= 16), Ok(true));
    }

    #[test]
    fn filled_stops_when_cancelled() {
        let cancel = AtomicBool::new(true);
        let options = QueryOptions {
            threads: 0,
            cancel: Some(&cancel),
        };
        let v = filled(test_pool(), &options, 3 * SEGMENT, 0u32);
        assert!(matches!(v, Err(RaycastError::Cancelled)));
        // An empty result has nothing to write, so nothing to stop.
        assert!(filled(test_pool(), &options, 0, 0u32).unwrap().is_empty());
    }
}
