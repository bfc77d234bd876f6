//! How much memory a render may still take, so that an image too large for the machine is
//! refused with a clear error before the large allocations, not by a driver's
//! `GL_OUT_OF_MEMORY` half-way or the allocator aborting the process.
//!
//! On a software renderer (llvmpipe) textures live in system memory, so the limit is the
//! smallest of: the kernel's `MemAvailable`, the cgroup's memory limit less its usage
//! (v2 `memory.max`, v1 `memory.limit_in_bytes`), and the address-space limit
//! (`ulimit -v`) less the process's current size. A GPU's own memory cannot be queried
//! portably in GLES; there brume reports `GL_OUT_OF_MEMORY` as [`Error::OutOfMemory`].

use crate::error::{Error, Result};
use std::fs;

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
    for line in cgroups.lines() {
        let mut parts = line.splitn(3, ':');
        let (_, controllers, path) = (parts.next()?, parts.next()?, parts.next()?);
        let (limit, usage) = if controllers.is_empty() {
            let dir = format!("/sys/fs/cgroup{path}");
            (
                read_number(&format!("{dir}/memory.max")),
                read_number(&format!("{dir}/memory.current")),
            )
        } else if controllers.split(',').any(|c| c == "memory") {
            let dir = format!("/sys/fs/cgroup/memory{path}");
            (
                read_number(&format!("{dir}/memory.limit_in_bytes")),
                read_number(&format!("{dir}/memory.usage_in_bytes")),
            )
        } else {
            continue;
        };
        // cgroup v1 writes "no limit" as a number near 2^63.
        if let Some(limit) = limit.filter(|&l| l < 1 << 60) {
            return Some(limit.saturating_sub(usage.unwrap_or(0)));
        }
    }
    None
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

fn read_number(path: &str) -> Option<u64> {
    fs::read_to_string(path).ok()?.trim().parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

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
