//! Writing results. Every writer goes through a temporary file in the destination's
//! directory that is renamed over the destination only once complete, so a crash or an
//! error never leaves a partial file and never damages an existing one.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

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
        "pfm" => write_atomically(path, |w| {
            write_pfm(w, img.width(), img.height(), 3, |x, y, c| img.get(x, y)[c])
        }),
        "exr" => {
            let channel = |c: usize| img.as_slice().iter().map(|p| p[c]).collect::<Vec<f32>>();
            let channels = [
                ("R", channel(0)),
                ("G", channel(1)),
                ("B", channel(2)),
                ("A", channel(3)),
            ];
            write_atomically(path, |w| write_exr(w, img.width(), img.height(), channels))
        }
        _ => check_image_output(path, "--out"),
    }
}

/// Writes a scalar map (range, depth, transmittance) by extension: `.pfm` (`Pf`,
/// little-endian, rows bottom to top) or `.exr` (one 32-bit channel named `Y`).
pub fn write_scalar(path: &Path, map: &ScalarMap) -> Result<()> {
    match extension_of(path).as_str() {
        "pfm" => write_atomically(path, |w| {
            write_pfm(w, map.width(), map.height(), 1, |x, y, _| *map.get(x, y))
        }),
        "exr" => {
            let channels = [("Y", map.as_slice().to_vec())];
            write_atomically(path, |w| write_exr(w, map.width(), map.height(), channels))
        }
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
    write_atomically(path, |out| {
        use image::ImageEncoder;
        image::codecs::png::PngEncoder::new(out)
            .write_image(&bytes, w, h, image::ExtendedColorType::Rgb8)
            .map_err(|e| std::io::Error::other(e.to_string()))
    })
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

/// PFM: header, then rows from the bottom of the image to the top, little-endian floats.
fn write_pfm(
    out: &mut impl Write,
    width: usize,
    height: usize,
    channels: usize,
    value: impl Fn(usize, usize, usize) -> f32,
) -> std::io::Result<()> {
    let magic = if channels == 3 { "PF" } else { "Pf" };
    write!(out, "{magic}\n{width} {height}\n-1.0\n")?;
    let mut row = Vec::with_capacity(width * channels * 4);
    for y in (0..height).rev() {
        row.clear();
        for x in 0..width {
            for c in 0..channels {
                row.extend_from_slice(&value(x, y, c).to_le_bytes());
            }
        }
        out.write_all(&row)?;
    }
    Ok(())
}

fn write_exr<const N: usize>(
    out: &mut BufWriter<&File>,
    width: usize,
    height: usize,
    channels: [(&str, Vec<f32>); N],
) -> std::io::Result<()> {
    use exr::prelude::{
        AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, SmallVec,
        WritableImage,
    };
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = channels
        .into_iter()
        .map(|(name, data)| AnyChannel::new(name, FlatSamples::F32(data)))
        .collect();
    let layer = Layer::new(
        (width, height),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(list),
    );
    Image::from_layer(layer)
        .write()
        .to_buffered(out)
        .map_err(|e| std::io::Error::other(format!("OpenEXR encoder: {e}")))
}
