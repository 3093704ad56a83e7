//! Worker threads: every parallel step runs on a rayon pool of the library's own, never on
//! rayon's global pool, so that callers (a Python process, a Ray worker) keep control of their
//! threads.

/// Most worker threads a pool may have: far beyond any core count, and small enough that
/// starting them takes no noticeable time.
pub const MAX_THREADS: usize = 1024;

/// A pool of `threads` workers (0: one per available core), and how many that is. More than
/// [`MAX_THREADS`] is refused; more than the cores this process may use (its CPU affinity and
/// quota, as `std::thread::available_parallelism` reads them) get one worker per core: the
/// work is CPU-bound, so extra workers only compete for the cores, and idle rayon workers spin
/// before they sleep (1,024 workers on 2 cores made a BVH build and a render many times
/// slower; measured: docs/benchmarks.md, «Design measurements», `thread_pool`).
pub(crate) fn thread_pool(threads: usize) -> Result<(rayon::ThreadPool, usize), String> {
    if threads > MAX_THREADS {
        return Err(format!(
            "at most {MAX_THREADS} worker threads, not {threads}"
        ));
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads = if threads == 0 {
        cores
    } else {
        threads.min(cores)
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| e.to_string())?;
    Ok((pool, threads))
}

/// One 2-thread pool shared by the unit tests that need a pool.
#[cfg(test)]
pub(crate) fn test_pool() -> &'static rayon::ThreadPool {
    static POOL: std::sync::OnceLock<rayon::ThreadPool> = std::sync::OnceLock::new();
    POOL.get_or_init(|| thread_pool(2).expect("a 2-thread pool").0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn absurd_thread_counts_are_refused_without_starting_threads() {
        let start = std::time::Instant::now();
        let e = thread_pool(MAX_THREADS + 1).err().unwrap();
        assert!(e.contains("1024") && e.contains("1025"), "{e}");
        assert!(start.elapsed().as_millis() < 100);
    }

    #[test]
    fn a_pool_has_no_more_workers_than_cores() {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        assert_eq!(thread_pool(0).unwrap().1, cores);
        assert_eq!(thread_pool(1).unwrap().1, 1);
        let (pool, n) = thread_pool(MAX_THREADS).unwrap();
        assert_eq!((n, pool.current_num_threads()), (cores, cores));
    }
}
