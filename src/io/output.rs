//! Writing results. Every writer goes through a temporary file in the destination's
//! directory that is renamed over the destination only once complete, so a crash or an
//! error never leaves a partial file and never damages an existing one.
//!
//! This module owns the path checks, that atomic write and the choice of format by
//! extension; the bytes of each format come from its codec in `io::codec`, next to the
//! reader of the same format.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use crate::io::codec::{exr, pfm, png};
use crate::io::image::linear_to_srgb;
use crate::raster::{RgbaImage, ScalarMap};
use crate::{Error, Result};

/// Extensions [`write_rgba`] accepts.
pub const IMAGE_EXTENSIONS: [&str; 3] = ["png", "pfm", "exr"];
/// Extensions [`write_scalar`] accepts.
pub const SCALAR_EXTENSIONS: [&str; 2] = ["pfm", "exr"];

/// Checks, before any work is done, that `path` can take an image output: a known
/// extension and an existing directory. `option` names the flag in the error.
pub fn check_image_output(path: &Path, option: &str) -> Result<()> {
    check_output(path, option, &IMAGE_EXTENSIONS)
}

/// Like [`check_image_output`] for scalar maps (`.pfm`, `.exr`).
pub fn check_scalar_output(path: &Path, option: &str) -> Result<()> {
    check_output(path, option, &SCALAR_EXTENSIONS)
}

fn check_output(path: &Path, option: &str, extensions: &[&str]) -> Result<()> {
    if !extensions.contains(&extension_of(path).as_str()) {
        return Err(Error::invalid(
            option,
            path.display(),
            format!("a path ending in {}", list_extensions(extensions)),
        ));
    }
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() && !dir.is_dir() => Err(Error::invalid(
            option,
            path.display(),
            format!(
                "a path in an existing directory ({} does not exist)",
                dir.display()
            ),
        )),
        _ => Ok(()),
    }
}

/// Writes `bytes` to `path` atomically (temporary file, then rename), with the same
/// permissions as every other output: for text reports, CSV tables and plots.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomically(path, |w| w.write_all(bytes))
}

/// `.png, .pfm or .exr`.
fn list_extensions(extensions: &[&str]) -> String {
    let dotted: Vec<String> = extensions.iter().map(|e| format!(".{e}")).collect();
    match dotted.split_last() {
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
        None => String::new(),
    }
}

/// Writes a linear-light RGBA image, choosing the format by extension:
/// `.png` 8-bit sRGB RGB (alpha dropped, values clamped to `[0, 1]` and rounded),
/// `.pfm` float RGB `PF` (linear, little-endian, rows bottom to top),
/// `.exr` float RGBA (linear, 32-bit).
pub fn write_rgba(path: &Path, img: &RgbaImage) -> Result<()> {
    match extension_of(path).as_str() {
        "png" => {
            let rgb: Vec<[u8; 3]> = img
                .as_slice()
                .iter()
                .map(|p| [p[0], p[1], p[2]].map(linear_to_srgb8))
                .collect();
            write_png_rgb8(path, img.width(), img.height(), &rgb)
        }
        "pfm" => write_atomically(path, |w| pfm::write_rgba(w, img)),
        "exr" => write_atomically(path, |w| exr::write_rgba(w, img)),
        _ => check_image_output(path, "out"),
    }
}

/// Writes a scalar map (range, depth, transmittance) by extension: `.pfm` (`Pf`,
/// little-endian, rows bottom to top) or `.exr` (one 32-bit channel named `Y`).
pub fn write_scalar(path: &Path, map: &ScalarMap) -> Result<()> {
    match extension_of(path).as_str() {
        "pfm" => write_atomically(path, |w| pfm::write_scalar(w, map)),
        "exr" => write_atomically(path, |w| exr::write_scalar(w, map)),
        _ => check_scalar_output(path, "scalar output"),
    }
}

/// Writes an 8-bit RGB PNG from pixels already encoded (a visualisation), row 0 at the
/// top. `rgb` must hold `width * height` pixels.
pub fn write_png_rgb8(path: &Path, width: usize, height: usize, rgb: &[[u8; 3]]) -> Result<()> {
    if rgb.len() != width * height {
        return Err(Error::invalid(
            "pixel count",
            rgb.len(),
            format!("{width}*{height} pixels for {}", path.display()),
        ));
    }
    let (w, h) = match (u32::try_from(width), u32::try_from(height)) {
        (Ok(w), Ok(h)) => (w, h),
        _ => {
            return Err(Error::invalid(
                "PNG size",
                format!("{width}x{height}"),
                "at most 2^32-1 per side",
            ))
        }
    };
    let bytes: Vec<u8> = rgb.iter().flatten().copied().collect();
    write_atomically(path, |out| png::write_rgb8(out, &bytes, w, h))
}

/// True if `a` and `b` name the same existing file (after resolving links and `..`), so
/// that an output never overwrites an input. False if either does not exist.
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b || same_inode(&a, &b),
        _ => false,
    }
}

#[cfg(unix)]
fn same_inode(a: &Path, b: &Path) -> bool {
    // Hard links have different canonical paths but are the same file.
    use std::os::unix::fs::MetadataExt;
    match (a.metadata(), b.metadata()) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn same_inode(_a: &Path, _b: &Path) -> bool {
    false
}

fn extension_of(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

fn linear_to_srgb8(v: f32) -> u8 {
    // NaN would otherwise survive the clamp; treat it as black.
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    (linear_to_srgb(v) * 255.0).round() as u8
}

/// Runs `write` on a buffered temporary file next to `path`, then renames it to `path`.
/// On any error the temporary file is removed and `path` is left as it was.
fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<&File>) -> std::io::Result<()>,
) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    builder.prefix(".brume-").suffix(".tmp");
    #[cfg(unix)]
    {
        // NamedTempFile defaults to 0600; an output image should be readable like any
        // other file the user creates (the umask still applies).
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let tmp = builder.tempfile_in(dir).map_err(|e| Error::io(path, e))?;
    {
        let mut out = BufWriter::new(tmp.as_file());
        write(&mut out).map_err(|e| Error::io(path, e))?;
        out.flush().map_err(|e| Error::io(path, e))?;
    }
    tmp.as_file().sync_all().map_err(|e| Error::io(path, e))?;
    tmp.persist(path).map_err(|e| Error::io(path, e.error))?;
    Ok(())
}
