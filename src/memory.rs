//! How much memory a render may still take, so that an image too large for the machine is
//! refused with a clear error before the large allocations, not by a driver's
//! `GL_OUT_OF_MEMORY` half-way or the allocator aborting the process.
//!
//! On a software renderer (llvmpipe) textures live in system memory, so the limit is the
//! smallest of: the kernel's `MemAvailable`, the cgroup's memory limit less its usage
//! (v2 `memory.max`, v1 `memory.limit_in_bytes`; its clean file cache, which the kernel
//! reclaims, not counted as used), and the address-space limit
//! (`ulimit -v`) less the process's current size. A GPU's own memory cannot be queried
//! portably in GLES; there brume reports `GL_OUT_OF_MEMORY` as [`Error::OutOfMemory`].

use crate::error::{Error, Result};
use std::fs;
use std::path::Path;
use std::sync::{Mutex, OnceLock, PoisonError};

/// Bytes the system can still give this process, if any limit is known (Linux).
pub fn available() -> Option<u64> {
    [
        meminfo_available(),
        cgroup_available(),
        address_space_available(),
    ]
    .into_iter()
    .flatten()
    .min()
}

/// Refuses `needed` bytes for `what` when more than the memory left ([`available`], less
/// what other threads' work has reserved) are needed, once the allocator has handed back
/// what it keeps of the memory freed ([`release_freed`]): the `brume` program keeps it for
/// speed, and a long run (a batch, a host's renderer) holds hundreds of megabytes so,
/// which it would reuse but the system counts as used.
pub fn check_available(what: &str, needed: u64, hint: &str) -> Result<()> {
    reserve(what, needed, hint).map(drop)
}

/// Bytes that work on some thread was let take by [`reserve`] and may not have allocated
/// yet.
static RESERVED: Mutex<u64> = Mutex::new(0);

/// Memory [`reserve`] let a piece of work take: every other check in the process counts it
/// as taken until this is dropped, at the end of the work that allocates it. (While the
/// work runs, what it has allocated is counted twice: checks on other threads err on the
/// safe side.)
#[must_use = "the memory is reserved until this is dropped"]
#[derive(Debug)]
pub struct Reservation {
    bytes: u64,
}

impl Drop for Reservation {
    fn drop(&mut self) {
        let mut reserved = RESERVED.lock().unwrap_or_else(PoisonError::into_inner);
        *reserved = reserved.saturating_sub(self.bytes);
    }
}

/// [`check_available`], and the memory reserved for the caller's work until the
/// [`Reservation`] is dropped: two threads whose checks pass at one moment (a batch's
/// loader and its GPU thread) cannot both take what is left.
pub fn reserve(what: &str, needed: u64, hint: &str) -> Result<Reservation> {
    let mut reserved = RESERVED.lock().unwrap_or_else(PoisonError::into_inner);
    let unreserved = |reserved: u64| available().map(|left| left.saturating_sub(reserved));
    let mut left = unreserved(*reserved);
    if left.is_some_and(|left| needed > left) && release_freed() {
        left = unreserved(*reserved);
    }
    check_fits(what, needed, left, hint)?;
    *reserved = reserved.saturating_add(needed);
    Ok(Reservation { bytes: needed })
}

/// Hands the memory this process has freed but its allocators keep (glibc's arenas, and a
/// host's own allocator given to [`set_allocator_release`]) back to the system; true where
/// that was done (Linux with glibc, or a host's release given).
pub fn release_freed() -> bool {
    let host = HOST_RELEASE.get().inspect(|release| release()).is_some();
    let glibc = trim_glibc();
    host || glibc
}

/// glibc's `malloc_trim`: true where it ran.
fn trim_glibc() -> bool {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: malloc_trim only returns free pages of glibc's arenas to the kernel.
        unsafe { libc::malloc_trim(0) };
        true
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    false
}

/// The host's way to hand back what its allocator keeps, if it gave one.
static HOST_RELEASE: OnceLock<fn()> = OnceLock::new();

/// Tells brume how a host's own global allocator hands its freed memory back to the system
/// (mimalloc's `mi_collect(true)`, jemalloc's purge): such allocators keep freed pages for a
/// while, which the system counts as used, so a check on a long run (a renderer kept for a
/// dataset's frames) would refuse memory the process already holds. [`release_freed`] calls
/// it when a check would refuse, beside glibc's `malloc_trim`. Only the first call takes
/// effect; false where a release was already set.
pub fn set_allocator_release(release: fn()) -> bool {
    HOST_RELEASE.set(release).is_ok()
}

/// Refuses `needed` bytes for `what` when more than `available` are left.
pub fn check_fits(what: &str, needed: u64, available: Option<u64>, hint: &str) -> Result<()> {
    match available {
        Some(left) if needed > left => Err(Error::OutOfMemory {
            what: what.to_string(),
            detail: format!(
                "needs about {}, but only {} can be had",
                human(needed),
                human(left)
            ),
            hint: hint.to_string(),
        }),
        _ => Ok(()),
    }
}

/// `3.07 GB`, `48 MB`.
pub fn human(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= 1e9 {
        format!("{:.2} GB", b / 1e9)
    } else {
        format!("{:.0} MB", (b / 1e6).max(1.0))
    }
}

fn meminfo_available() -> Option<u64> {
    let text = fs::read_to_string("/proc/meminfo").ok()?;
    kib_field(&text, "MemAvailable:")
}

/// A `Key:   123 kB` line of a /proc file, in bytes.
fn kib_field(text: &str, key: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(key))?;
    let kib: u64 = line[key.len()..].split_whitespace().next()?.parse().ok()?;
    Some(kib * 1024)
}

fn cgroup_available() -> Option<u64> {
    let cgroups = fs::read_to_string("/proc/self/cgroup").ok()?;
    cgroup_available_under(Path::new("/sys/fs/cgroup"), &cgroups)
}

/// What the memory cgroup that `cgroups` (the text of `/proc/self/cgroup`) names has left,
/// its files under `root` (v2 or v1): its limit less its usage, where the usage counts the
/// file cache as used. The kernel reclaims clean cache before it fails an allocation (as
/// LXCFS counts it available): in a container whose reads had filled 957 MB of cache
/// under a 2 GB limit, a 1.15 GB job was refused ("only 1.02 GB can be had") with nothing
/// of brume's running. Cache that processes map (their code) or that waits to be written
/// is counted as used.
fn cgroup_available_under(root: &Path, cgroups: &str) -> Option<u64> {
    for line in cgroups.lines() {
        let mut parts = line.splitn(3, ':');
        let (_, controllers, path) = (parts.next()?, parts.next()?, parts.next()?);
        let path = path.trim_start_matches('/');
        let (dir, v1) = if controllers.is_empty() {
            (root.join(path), false)
        } else if controllers.split(',').any(|c| c == "memory") {
            (root.join("memory").join(path), true)
        } else {
            continue;
        };
        let [limit, usage] = if v1 {
            ["memory.limit_in_bytes", "memory.usage_in_bytes"]
        } else {
            ["memory.max", "memory.current"]
        };
        // cgroup v1 writes "no limit" as a number near 2^63, v2 as "max".
        let Some(limit) = read_number(&dir.join(limit)).filter(|&l| l < 1 << 60) else {
            continue;
        };
        let usage = read_number(&dir.join(usage)).unwrap_or(0);
        let stat = fs::read_to_string(dir.join("memory.stat")).unwrap_or_default();
        return Some(limit.saturating_sub(usage.saturating_sub(reclaimable_cache(&stat, v1))));
    }
    None
}

/// The clean file cache that is not mapped, from a cgroup's `memory.stat` (v1's
/// hierarchical `total_` fields, or v2's).
fn reclaimable_cache(stat: &str, v1: bool) -> u64 {
    let field = |v1_key: &str, v2_key: &str| {
        let key = if v1 { v1_key } else { v2_key };
        stat_field(stat, key).unwrap_or(0)
    };
    let cache =
        field("total_active_file", "active_file") + field("total_inactive_file", "inactive_file");
    let kept = field("total_mapped_file", "file_mapped")
        + field("total_dirty", "file_dirty")
        + field("total_writeback", "file_writeback");
    cache.saturating_sub(kept)
}

/// A `key value` line of a cgroup's `memory.stat`.
fn stat_field(text: &str, key: &str) -> Option<u64> {
    text.lines().find_map(|line| {
        let (k, v) = line.split_once(' ')?;
        (k == key).then(|| v.trim().parse().ok())?
    })
}

/// `ulimit -v` less the current virtual size (a conservative bound: llvmpipe reserves
/// address space it does not touch).
fn address_space_available() -> Option<u64> {
    let limits = fs::read_to_string("/proc/self/limits").ok()?;
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    let soft: u64 = line
        .trim_start_matches("Max address space")
        .split_whitespace()
        .next()?
        .parse()
        .ok()?; // "unlimited" does not parse: no limit
    let status = fs::read_to_string("/proc/self/status").ok()?;
    let size = kib_field(&status, "VmSize:").unwrap_or(0);
    Some(soft.saturating_sub(size))
}

fn read_number(path: &Path) -> Option<u64> {
    fs::read_to_string(path).ok()?.trim().parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A host's allocator is asked to hand back its freed pages when a check would refuse
    /// (a Python renderer kept for three frames was refused the third under a 450 MB limit
    /// while mimalloc still held the first two's pages).
    #[test]
    fn a_check_that_would_refuse_asks_the_hosts_allocator_first() {
        use std::sync::atomic::{AtomicUsize, Ordering};
        static CALLS: AtomicUsize = AtomicUsize::new(0);
        fn count() {
            CALLS.fetch_add(1, Ordering::SeqCst);
        }
        assert!(set_allocator_release(count));
        assert!(
            !set_allocator_release(count),
            "only the first release is taken"
        );
        if available().is_none() {
            return; // no limit known on this system: no check refuses
        }
        // (Other tests' refusals may call it too, on their threads: only a rise is asserted.)
        let before = CALLS.load(Ordering::SeqCst);
        check_available("everything", u64::MAX, "").unwrap_err();
        assert!(CALLS.load(Ordering::SeqCst) > before);
    }

    /// What one thread reserved, another's check counts as taken until it is dropped (a
    /// batch's loader and GPU thread both passed their checks at one moment and together
    /// took more than a cgroup's limit: 2 runs of about 110 were killed).
    #[test]
    fn a_reservation_is_taken_from_other_checks_until_dropped() {
        let Some(left) = available() else {
            return; // no limit known on this system: nothing to reserve from
        };
        let most = left / 5 * 3;
        let first = reserve("first", most, "").unwrap();
        let e = check_available("second", most, "").unwrap_err();
        assert!(matches!(e, Error::OutOfMemory { .. }), "{e}");
        drop(first);
        check_available("second", most, "").unwrap();
    }

    #[test]
    fn too_large_is_refused_with_sizes_and_hint() {
        let err = check_fits(
            "a 8000x6000 render",
            3_200_000_000,
            Some(2_900_000_000),
            "f16",
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("8000x6000") && err.contains("3.20 GB") && err.contains("2.90 GB"));
        assert!(err.contains("f16"), "{err}");
        assert!(check_fits("x", 10, Some(10), "").is_ok());
        assert!(check_fits("x", 10, None, "").is_ok());
    }

    /// The cgroup's usage less its clean, unmapped file cache, in both layouts.
    #[test]
    fn a_cgroup_leaves_its_reclaimable_file_cache_out_of_its_usage() {
        let root = tempfile::tempdir().unwrap();
        let write = |dir: &str, files: &[(&str, &str)]| {
            let dir = root.path().join(dir);
            fs::create_dir_all(&dir).unwrap();
            for (name, text) in files {
                fs::write(dir.join(name), text).unwrap();
            }
        };
        // As measured in a v1 cgroup under a 2 GB limit after reading 1 GB of files twice
        // (the second read made the cache active), with 10 MB mapped and 2 MB dirty added.
        let stat = "cache 973676544\nactive_file 5\ntotal_cache 973676544\n\
                    total_inactive_file 983040\ntotal_active_file 972693504\n\
                    total_mapped_file 10000000\ntotal_dirty 2000000\ntotal_writeback 0\n";
        write(
            "memory/box",
            &[
                ("memory.limit_in_bytes", "2000000000\n"),
                ("memory.usage_in_bytes", "974000000\n"),
                ("memory.stat", stat),
            ],
        );
        let v1 = "4:memory:/box\n0::/\n";
        let cache = 983_040 + 972_693_504 - 10_000_000 - 2_000_000;
        let left = 2_000_000_000 - (974_000_000 - cache);
        assert_eq!(cgroup_available_under(root.path(), v1), Some(left));
        let stat = "anon 100000000\nfile 500000000\nactive_file 100000000\n\
                    inactive_file 400000000\nfile_mapped 50000000\nfile_dirty 0\n";
        write(
            "box2",
            &[
                ("memory.max", "1000000000\n"),
                ("memory.current", "600000000\n"),
                ("memory.stat", stat),
            ],
        );
        let v2 = "0::/box2\n";
        assert_eq!(cgroup_available_under(root.path(), v2), Some(850_000_000));
        // No limit; a limit without a stat: the usage alone.
        write(
            "box3",
            &[("memory.max", "max\n"), ("memory.current", "1\n")],
        );
        assert_eq!(cgroup_available_under(root.path(), "0::/box3\n"), None);
        write(
            "box4",
            &[("memory.max", "100\n"), ("memory.current", "30\n")],
        );
        assert_eq!(cgroup_available_under(root.path(), "0::/box4\n"), Some(70));
    }

    #[test]
    fn proc_fields_parse() {
        let text = "MemTotal:       24684092 kB\nMemAvailable:   23342688 kB\n";
        assert_eq!(kib_field(text, "MemAvailable:"), Some(23_342_688 * 1024));
        assert_eq!(kib_field(text, "Missing:"), None);
        // On Linux this machine reports something.
        if cfg!(target_os = "linux") {
            assert!(available().is_some());
        }
    }
}
