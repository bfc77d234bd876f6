//! TIFF maps through the `tiff` crate: one channel of 32- or 64-bit floats, or of 16-bit
//! integers (as a 16-bit PNG holds), read only (no output is written as TIFF). A TIFF
//! photo is read by `io::image`, through the `image` crate.

use std::io::Cursor;
use std::path::Path;

use super::MapSamples;
use crate::io::limits::check_size;
use crate::raster::{Grid, ScalarMap};
use crate::{Error, Result};

/// Reads a one-channel 32- or 64-bit float TIFF no larger than `io::limits` allows.
pub fn read_tiff_scalar(path: &Path) -> Result<ScalarMap> {
    let bytes = crate::io::limits::read_file(path)?;
    parse_tiff(&bytes, path)?.floats(
        path,
        "a TIFF of 16-bit integers; expected 32- or 64-bit floats",
    )
}

/// A one-channel float or 16-bit TIFF's samples.
pub(crate) fn parse_tiff(bytes: &[u8], path: &Path) -> Result<MapSamples> {
    use tiff::decoder::{Decoder, DecodingResult};
    let bad = |e: tiff::TiffError| Error::format(path, format!("cannot read as TIFF: {e}"));
    let mut decoder = Decoder::new(Cursor::new(bytes))
        .map_err(bad)?
        .with_limits(decoder_limits(bytes.len()));
    let (w, h) = decoder.dimensions().map_err(bad)?;
    check_size(path, "TIFF", u64::from(w), u64::from(h))?;
    let colour = decoder.colortype().map_err(bad)?;
    if !matches!(colour, tiff::ColorType::Gray(_)) {
        return Err(Error::format(
            path,
            format!("TIFF colour type is {colour:?}; expected one float channel"),
        ));
    }
    let (w, h) = (w as usize, h as usize);
    match decoder.read_image().map_err(bad)? {
        DecodingResult::F32(v) => Ok(MapSamples::Float(grid(v, w, h, path)?)),
        DecodingResult::F64(v) => {
            let v = v.into_iter().map(|x| x as f32).collect();
            Ok(MapSamples::Float(grid(v, w, h, path)?))
        }
        DecodingResult::U16(v) => Ok(MapSamples::Uint16(grid(v, w, h, path)?)),
        _ => Err(Error::format(
            path,
            format!(
                "TIFF samples are {colour:?}; expected 32- or 64-bit floats (or 16-bit \
                 integers, as a 16-bit PNG holds)"
            ),
        )),
    }
}

/// The decoder's limits for a file of `file_len` bytes. Its defaults (256 MiB decoded,
/// 128 MiB in one strip) refused an 8000x6000 float map stored as one strip, as PIL writes
/// it, with "decoder limits exceeded"; `io::limits`' check of the size comes first instead.
fn decoder_limits(file_len: usize) -> tiff::decoder::Limits {
    let mut limits = tiff::decoder::Limits::default();
    // The largest map `check_size` lets through, in 64-bit floats.
    limits.decoding_buffer_size = crate::io::limits::MAX_PIXELS * 8;
    // No strip or tile holds more than the file.
    limits.intermediate_buffer_size = file_len;
    limits
}

/// The width and height of the TIFF file `bytes`, from its first directory alone, if it
/// can be read (else the decoder's error).
pub(crate) fn tiff_size(bytes: &[u8]) -> Option<(usize, usize)> {
    let mut decoder = tiff::decoder::Decoder::new(Cursor::new(bytes)).ok()?;
    let (w, h) = decoder.dimensions().ok()?;
    Some((w as usize, h as usize))
}

fn grid<T>(data: Vec<T>, w: usize, h: usize, path: &Path) -> Result<Grid<T>> {
    if data.len() != w * h {
        return Err(Error::format(
            path,
            format!("TIFF holds {} samples; expected {w}*{h}", data.len()),
        ));
    }
    Ok(Grid::from_vec(w, h, data))
}

/// The largest ICC profile read from a TIFF: an RGB photo's is a few kB (a matrix and
/// curves), a lookup-table profile's up to a few hundred.
pub const MAX_TIFF_ICC_BYTES: usize = 2 << 20;

/// The ICC profile (tag 34675) of the TIFF photo `name`, where it has one that can be
/// read; one over [`MAX_TIFF_ICC_BYTES`] is passed over with a warning.
pub(crate) fn icc_profile(bytes: &[u8], name: &str) -> Option<Vec<u8>> {
    use tiff::decoder::{ifd::Value, Decoder, Limits};
    // The crate reserves a `Value` (tens of bytes) for each byte of a tag before reading
    // it: bounded by the profile's size, not by its default 256 MiB.
    let mut limits = Limits::default();
    limits.decoding_buffer_size = MAX_TIFF_ICC_BYTES * std::mem::size_of::<Value>();
    let decoder = Decoder::new(Cursor::new(bytes)).ok()?;
    match decoder
        .with_limits(limits)
        .get_tag_u8_vec(tiff::tags::Tag::IccProfile)
    {
        Ok(icc) => Some(icc),
        Err(tiff::TiffError::LimitsExceeded) => {
            log::warn!(
                "{name}: its ICC colour profile is larger than {} MiB; taken as sRGB",
                MAX_TIFF_ICC_BYTES >> 20
            );
            None
        }
        Err(_) => None,
    }
}
