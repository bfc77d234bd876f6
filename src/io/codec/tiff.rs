//! TIFF through the `tiff` crate: one-channel 32- or 64-bit float maps, read only (no
//! output is written as TIFF).

use std::io::Cursor;
use std::path::Path;

use crate::io::limits::check_size;
use crate::raster::{Grid, ScalarMap};
use crate::{Error, Result};

/// Reads a one-channel 32- or 64-bit float TIFF no larger than `io::limits` allows.
pub fn read_tiff_scalar(path: &Path) -> Result<ScalarMap> {
    let bytes = crate::io::limits::read_file(path)?;
    parse_tiff_scalar(&bytes, path)
}

pub(crate) fn parse_tiff_scalar(bytes: &[u8], path: &Path) -> Result<ScalarMap> {
    use tiff::decoder::{Decoder, DecodingResult};
    let bad = |e: tiff::TiffError| Error::format(path, format!("cannot read as TIFF: {e}"));
    let mut decoder = Decoder::new(Cursor::new(bytes)).map_err(bad)?;
    let (w, h) = decoder.dimensions().map_err(bad)?;
    check_size(path, "TIFF", u64::from(w), u64::from(h))?;
    let colour = decoder.colortype().map_err(bad)?;
    if !matches!(colour, tiff::ColorType::Gray(_)) {
        return Err(Error::format(
            path,
            format!("TIFF colour type is {colour:?}; expected one float channel"),
        ));
    }
    let data: Vec<f32> = match decoder.read_image().map_err(bad)? {
        DecodingResult::F32(v) => v,
        DecodingResult::F64(v) => v.into_iter().map(|x| x as f32).collect(),
        _ => {
            return Err(Error::format(
                path,
                format!("TIFF samples are {colour:?} integers; expected 32- or 64-bit floats"),
            ))
        }
    };
    let (w, h) = (w as usize, h as usize);
    if data.len() != w * h {
        return Err(Error::format(
            path,
            format!("TIFF holds {} samples; expected {w}*{h}", data.len()),
        ));
    }
    Ok(Grid::from_vec(w, h, data))
}
