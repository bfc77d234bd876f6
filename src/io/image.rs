//! Colour images: PNG or JPEG in sRGB, decoded to linear light.
//!
//! Embedded ICC profiles, PNG `gAMA` chunks and EXIF orientation are ignored: inputs are
//! taken as sRGB and as stored, so that the colour image stays aligned with a depth map
//! that knows nothing of the orientation tag.

use std::path::Path;

use image::{DynamicImage, ImageDecoder, ImageFormat, ImageReader};

use crate::io::limits::check_size;
use crate::raster::RgbImage;
use crate::{Error, Result};

/// sRGB-encoded value in `[0, 1]` to linear light, with the exact piecewise curve of
/// IEC 61966-2-1 (linear segment below 0.04045).
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear-light value in `[0, 1]` to sRGB encoding, the exact inverse of
/// [`srgb_to_linear`] (linear segment below 0.0031308).
pub fn linear_to_srgb(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        v * 12.92
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// Loads a PNG or JPEG (8- or 16-bit, grey or RGB, alpha dropped) and converts it from
/// sRGB to linear light. Errors name the file; sizes beyond `io::limits` are refused.
pub fn load_linear_rgb(path: &Path) -> Result<RgbImage> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    decode_linear_rgb(&bytes, &path.display().to_string())
}

/// Same as [`load_linear_rgb`] for bytes already in memory (an embedded asset); `name`
/// stands for the file in error messages.
pub fn decode_linear_rgb(bytes: &[u8], name: &str) -> Result<RgbImage> {
    let decoded = decode_any(bytes, name)?;
    Ok(to_linear_rgb(&decoded))
}

/// Decodes PNG or JPEG bytes without any colour conversion; shared with the depth loaders
/// so that 8- and 16-bit PNG depth maps keep their raw values.
pub(crate) fn decode_any(bytes: &[u8], name: &str) -> Result<DynamicImage> {
    let reader = ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| Error::io(name, e))?;
    let Some(format) = reader.format() else {
        return Err(Error::format(
            name,
            format!(
                "unrecognised image data (starts with {}); expected a PNG or JPEG file",
                hex_prefix(bytes)
            ),
        ));
    };
    if format == ImageFormat::Jpeg && !jpeg_reaches_end_marker(bytes) {
        // The JPEG decoder pads a truncated scan with grey instead of failing.
        return Err(Error::format(
            name,
            "JPEG data ends before its end-of-image marker; the file is truncated",
        ));
    }
    let cannot = |e: image::ImageError| {
        Error::format(
            name,
            format!("cannot decode as {format:?}: {e}; the file may be truncated or corrupt"),
        )
    };
    // The size is checked from the header, before the pixel buffer is allocated.
    let decoder = reader.into_decoder().map_err(cannot)?;
    let (w, h) = decoder.dimensions();
    check_size(
        Path::new(name),
        &format!("{format:?}"),
        u64::from(w),
        u64::from(h),
    )?;
    if format == ImageFormat::Jpeg {
        check_jpeg_holds(bytes.len(), w, h, name)?;
    }
    // The budget `ImageReader::decode` applies, which `into_decoder` leaves to its caller.
    image::Limits::default()
        .reserve(decoder.total_bytes())
        .map_err(cannot)?;
    DynamicImage::from_decoder(decoder).map_err(cannot)
}

/// Fewest pixels per byte a JPEG can hold, with a margin: every 8x8 block of every scan
/// costs at least one bit (a DC difference; progressive AC scans can skip blocks in runs),
/// so 512 pixels a byte at most, halved for safety.
const JPEG_MAX_PIXELS_PER_BYTE: u64 = 1024;

/// Refuses a JPEG too short for the size it claims. The decoder fills what the scan data
/// does not cover instead of failing, so a 1 kB file claiming 10280x10280 took 10 s and
/// 1.9 GB to decode into a grey picture.
fn check_jpeg_holds(len: usize, w: u32, h: u32, name: &str) -> Result<()> {
    let pixels = u64::from(w) * u64::from(h);
    let needed = pixels / JPEG_MAX_PIXELS_PER_BYTE;
    if (len as u64) < needed {
        return Err(Error::format(
            name,
            format!(
                "JPEG header claims {w}x{h} pixels, which need at least {needed} bytes, but the \
                 file has {len}; it is truncated or corrupt"
            ),
        ));
    }
    Ok(())
}

/// Walks the JPEG marker segments from SOI and the entropy-coded data after each SOS, and
/// says whether an EOI marker is reached before the bytes run out. Segments are skipped by
/// their length, so an EXIF thumbnail's own EOI does not count.
fn jpeg_reaches_end_marker(b: &[u8]) -> bool {
    if !b.starts_with(&[0xFF, 0xD8]) {
        return false;
    }
    let mut i = 2;
    while i < b.len() {
        if b[i] != 0xFF {
            i += 1;
            continue;
        }
        while i < b.len() && b[i] == 0xFF {
            i += 1; // fill bytes
        }
        let Some(&marker) = b.get(i) else {
            return false;
        };
        i += 1;
        match marker {
            0xD9 => return true,
            // Stuffed zero, restart markers and TEM carry no length.
            0x00 | 0x01 | 0xD0..=0xD7 => {}
            _ => {
                let Some(len) = b.get(i..i + 2) else {
                    return false;
                };
                i += usize::from(u16::from_be_bytes([len[0], len[1]]));
                if marker == 0xDA {
                    i = skip_entropy_coded_data(b, i);
                }
            }
        }
    }
    false
}

/// Index of the first marker after a scan's entropy-coded data (or `b.len()`).
fn skip_entropy_coded_data(b: &[u8], mut i: usize) -> usize {
    while i + 1 < b.len() {
        if b[i] == 0xFF && !matches!(b[i + 1], 0x00 | 0xD0..=0xD7) {
            return i;
        }
        i += 1;
    }
    b.len()
}

fn hex_prefix(bytes: &[u8]) -> String {
    if bytes.is_empty() {
        return "nothing: the file is empty".to_string();
    }
    bytes
        .iter()
        .take(8)
        .map(|b| format!("{b:02x}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn to_linear_rgb(img: &DynamicImage) -> RgbImage {
    let (w, h) = (img.width() as usize, img.height() as usize);
    let is_8bit = matches!(
        img,
        DynamicImage::ImageLuma8(_)
            | DynamicImage::ImageLumaA8(_)
            | DynamicImage::ImageRgb8(_)
            | DynamicImage::ImageRgba8(_)
    );
    if is_8bit {
        // 256 exact curve values instead of one powf per channel.
        let lut: Vec<f32> = (0..=255u8)
            .map(|v| srgb_to_linear(f32::from(v) / 255.0))
            .collect();
        let data = img
            .to_rgb8()
            .pixels()
            .map(|p| p.0.map(|c| lut[usize::from(c)]))
            .collect();
        RgbImage::from_vec(w, h, data)
    } else {
        let data = img
            .to_rgb32f()
            .pixels()
            .map(|p| p.0.map(srgb_to_linear))
            .collect();
        RgbImage::from_vec(w, h, data)
    }
}
