//! PNG through the `image` crate: one grey channel of 8 or 16 bits read as integer
//! samples (depth and disparity maps keep their raw values; what they mean is decided by
//! `io::depth`), and 8-bit RGB written. Colour photographs are read by `io::image`, which
//! also converts them to linear light.

use std::io::Write;
use std::path::Path;

use image::DynamicImage;

use crate::raster::Grid;
use crate::{Error, Result};

/// The samples of a grey PNG, at the bit depth of the file.
pub(crate) enum GreyPng {
    /// 8-bit samples.
    Grey8(Grid<u8>),
    /// 16-bit samples.
    Grey16(Grid<u16>),
}

/// Decodes a PNG with one grey channel (and optionally alpha, which is dropped).
pub(crate) fn decode_grey(bytes: &[u8], path: &Path) -> Result<GreyPng> {
    let name = path.display().to_string();
    match crate::io::image::decode_any(bytes, &name)? {
        DynamicImage::ImageLuma8(g) => Ok(GreyPng::Grey8(to_grid(g))),
        DynamicImage::ImageLuma16(g) => Ok(GreyPng::Grey16(to_grid(g))),
        // Alpha on a depth PNG carries nothing we use.
        DynamicImage::ImageLumaA8(g) => Ok(GreyPng::Grey8(first_channel(g))),
        DynamicImage::ImageLumaA16(g) => Ok(GreyPng::Grey16(first_channel(g))),
        other => Err(Error::format(
            path,
            format!(
                "depth PNG has colour type {:?}; expected one grey channel (8- or 16-bit)",
                other.color()
            ),
        )),
    }
}

fn to_grid<T: image::Primitive>(img: image::ImageBuffer<image::Luma<T>, Vec<T>>) -> Grid<T> {
    let (w, h) = (img.width() as usize, img.height() as usize);
    Grid::from_vec(w, h, img.into_raw())
}

fn first_channel<T: image::Primitive>(img: image::ImageBuffer<image::LumaA<T>, Vec<T>>) -> Grid<T> {
    let (w, h) = (img.width() as usize, img.height() as usize);
    Grid::from_vec(w, h, img.pixels().map(|p| p.0[0]).collect())
}

/// Encodes `bytes`, `w * h` RGB pixels of 8 bits each, row 0 at the top, carrying the
/// ICC profile `icc` and the EXIF block `exif` where given (`iCCP` and `eXIf` chunks).
pub(crate) fn write_rgb8(
    mut out: impl Write,
    bytes: &[u8],
    w: u32,
    h: u32,
    icc: Option<&[u8]>,
    exif: Option<Vec<u8>>,
) -> std::io::Result<()> {
    // Encoded in memory, then written: the png crate turns the OS's errors into text
    // ("No space left on device (os error 28)" of kind `Other`), and a full disk must
    // stay a full disk for a long run to stop on it (`output::is_out_of_space`).
    let mut png = Vec::new();
    let encoder = image::codecs::png::PngEncoder::new(&mut png);
    super::encode_rgb8(encoder, bytes, (w, h), icc, exif)?;
    out.write_all(&png)
}
