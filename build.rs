//! Fingerprints the sources this build of brume is compiled from (`src/` and `glsl/`) as
//! `BRUME_SOURCES`, 16 hex digits: the version alone does not tell two builds apart whose
//! outputs differ (between releases, or a clone's commits), and a batch resumed by another
//! build would put two kinds of fog in one dataset (`dataset::settings`).
//!
//! FNV-1a, written out here rather than taken from a crate or `std`'s hasher: a build
//! script's dependencies are built for every build of brume, and `std` leaves its hasher's
//! algorithm free to change between releases of Rust, which would change the fingerprint of
//! unchanged sources.

use std::path::{Path, PathBuf};

const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
const FNV_PRIME: u64 = 0x0000_0100_0000_01b3;

fn fnv1a(mut hash: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        hash = (hash ^ u64::from(b)).wrapping_mul(FNV_PRIME);
    }
    hash
}

/// The files under `dir`, every depth, in an order that does not depend on the file system.
fn files_under(dir: &Path, files: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            files_under(&path, files);
        } else {
            files.push(path);
        }
    }
}

fn main() {
    let root = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("set by Cargo"));
    let mut files = Vec::new();
    for dir in ["src", "glsl"] {
        // Cargo scans a directory named here for any change, at every depth.
        println!("cargo:rerun-if-changed={dir}");
        files_under(&root.join(dir), &mut files);
    }
    files.sort();
    let mut hash = FNV_OFFSET;
    for file in &files {
        let name = file.strip_prefix(&root).unwrap_or(file);
        // Separators as '/', so that one source tree has one fingerprint on every system.
        let name = name.to_string_lossy().replace('\\', "/");
        let text = std::fs::read(file).unwrap_or_default();
        hash = fnv1a(hash, name.as_bytes());
        hash = fnv1a(hash, &[0]);
        hash = fnv1a(hash, &(text.len() as u64).to_le_bytes());
        hash = fnv1a(hash, &text);
    }
    println!("cargo:rustc-env=BRUME_SOURCES={hash:016x}");
}
