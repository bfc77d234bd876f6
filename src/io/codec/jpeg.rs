//! JPEG written (8-bit RGB, 4:4:4, with an ICC profile where the photo had one). JPEGs
//! are read by `io::image` (colour photos) and `io::depth` (the depth maps phones embed).

use std::io::Write;

/// The quality brume writes JPEGs at: high enough that the fog's smooth gradients show no
/// blocks, a fifth of a PNG's size on a phone photo.
pub const QUALITY: u8 = 95;

/// Encodes `bytes`, `w * h` RGB pixels of 8 bits each, row 0 at the top, carrying the
/// ICC profile `icc` (APP2) and the EXIF block `exif` (APP1) where given.
pub(crate) fn write_rgb8(
    mut out: impl Write,
    bytes: &[u8],
    w: u32,
    h: u32,
    icc: Option<&[u8]>,
    exif: Option<Vec<u8>>,
) -> std::io::Result<()> {
    // In memory first, as the PNG writer does, so that the OS's errors keep their kind.
    let mut jpeg = Vec::new();
    let encoder = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, QUALITY);
    super::encode_rgb8(encoder, bytes, (w, h), icc, exif)?;
    out.write_all(&jpeg)
}
