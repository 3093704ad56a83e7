//! How much memory the process may still take, so that a scene too large for it is refused
//! with a message naming what is too large, before the allocation that would abort the process.
//!
//! On Linux the least of: the memory the system has available (`MemAvailable`), what the
//! process's cgroup still allows, and what its address-space limit (`ulimit -v`) still allows.
//! Elsewhere nothing is known, and only the fixed limits apply.

/// Address space kept free for what the estimates do not count: thread stacks, the allocator's
/// per-thread arenas, the film.
const ADDRESS_SPACE_HEADROOM: u64 = 256 << 20;

/// Bytes the process may still allocate, if known.
pub(crate) fn available() -> Option<u64> {
    let read = |path: &str| std::fs::read_to_string(path).ok();
    let system = read("/proc/meminfo").and_then(|t| meminfo_available(&t));
    let cgroup = match (
        read("/sys/fs/cgroup/memory.max"),
        read("/sys/fs/cgroup/memory.current"),
    ) {
        (Some(max), Some(current)) => cgroup_left(&max, &current),
        _ => None,
    };
    let address_space = match (read("/proc/self/limits"), read("/proc/self/status")) {
        (Some(limits), Some(status)) => address_space_left(&limits, &status),
        _ => None,
    };
    [system, cgroup, address_space].into_iter().flatten().min()
}

/// `MemAvailable` of `/proc/meminfo`, in bytes.
fn meminfo_available(meminfo: &str) -> Option<u64> {
    kib_field(meminfo, "MemAvailable:")
}

/// A `NAME:   123 kB` field of a `/proc` file, in bytes.
fn kib_field(text: &str, name: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(name))?;
    let kib: u64 = line[name.len()..].split_whitespace().next()?.parse().ok()?;
    Some(kib * 1024)
}

/// What a cgroup v2 `memory.max` (a number or `max`) leaves beyond `memory.current`.
fn cgroup_left(max: &str, current: &str) -> Option<u64> {
    let max: u64 = max.trim().parse().ok()?;
    let current: u64 = current.trim().parse().ok()?;
    Some(max.saturating_sub(current))
}

/// What the soft address-space limit of `/proc/self/limits` leaves beyond the process's
/// `VmSize` (`/proc/self/status`) and a headroom; `None` when unlimited.
fn address_space_left(limits: &str, status: &str) -> Option<u64> {
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    let soft: u64 = line["Max address space".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()?;
    let used = kib_field(status, "VmSize:")?;
    Some(soft.saturating_sub(used + ADDRESS_SPACE_HEADROOM))
}

/// `bytes` for a message: "2.8 GiB", "540 MiB".
pub(crate) fn human(bytes: u64) -> String {
    let gib = bytes as f64 / (1u64 << 30) as f64;
    if gib >= 1.0 {
        format!("{gib:.1} GiB")
    } else {
        format!("{} MiB", bytes >> 20)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_proc_files() {
        let meminfo = "MemTotal:       24000000 kB\nMemFree:  100 kB\nMemAvailable:    2000 kB\n";
        assert_eq!(meminfo_available(meminfo), Some(2000 * 1024));
        assert_eq!(cgroup_left("max\n", "100\n"), None);
        assert_eq!(cgroup_left("1000\n", "300\n"), Some(700));
        let limits = "Limit                     Soft Limit           Hard Limit           Units     \n\
                      Max stack size            8388608              unlimited            bytes     \n\
                      Max address space         2048000000           unlimited            bytes     \n";
        let status = "Name:\tpenumbra\nVmPeak:\t  200000 kB\nVmSize:\t  100000 kB\n";
        assert_eq!(
            address_space_left(limits, status),
            Some(2_048_000_000 - 100_000 * 1024 - ADDRESS_SPACE_HEADROOM)
        );
        let unlimited = limits.replace("2048000000", "unlimited ");
        assert_eq!(address_space_left(&unlimited, status), None);
        // This process: something is known on Linux, and it is more than nothing.
        if cfg!(target_os = "linux") {
            assert!(available().is_some_and(|b| b > 0));
        }
    }

    #[test]
    fn sizes_read_well() {
        assert_eq!(human(3 << 29), "1.5 GiB");
        assert_eq!(human(540 << 20), "540 MiB");
    }
}
