//! Worker threads: every parallel step runs on a rayon pool of the library's own, never on
//! rayon's global pool, so that callers (a Python process, a Ray worker) keep control of their
//! threads.

/// A pool of `threads` workers (0: one per available core), and how many that is.
pub(crate) fn thread_pool(
    threads: usize,
) -> Result<(rayon::ThreadPool, usize), rayon::ThreadPoolBuildError> {
    let threads = if threads == 0 {
        std::thread::available_parallelism().map_or(1, |n| n.get())
    } else {
        threads
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?;
    Ok((pool, threads))
}
