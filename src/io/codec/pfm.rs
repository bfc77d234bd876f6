//! PFM (Portable Float Map): `Pf` grey or `PF` colour, 32-bit floats stored from the
//! bottom row up. Read in either byte order and with either line ending, since other
//! tools write both; written little-endian.

use std::io::Write;
use std::path::Path;

use crate::io::limits::check_size;
use crate::raster::{Grid, RgbImage, RgbaImage, ScalarMap};
use crate::{Error, Result};

/// The content of a PFM file, rows already flipped to top-to-bottom.
#[derive(Clone, Debug, PartialEq)]
pub enum Pfm {
    /// A `Pf` file: one channel.
    Grey(ScalarMap),
    /// A `PF` file: three channels.
    Rgb(RgbImage),
}

/// Reads a PFM file (`Pf` or `PF`, either byte order).
pub fn read_pfm(path: &Path) -> Result<Pfm> {
    let bytes = crate::io::limits::read_file(path)?;
    parse_pfm(&bytes, path)
}

/// Parses PFM bytes; `path` names the file in errors. The header is `Pf` or `PF`, width,
/// height (within `io::limits`) and scale separated by whitespace, then one whitespace byte, then rows of
/// 32-bit floats from the BOTTOM row to the top, little-endian if scale < 0.
pub fn parse_pfm(bytes: &[u8], path: &Path) -> Result<Pfm> {
    let PfmHeader {
        channels,
        width,
        height,
        scale,
        data_start: start,
    } = parse_header(bytes, path)?;
    let data = &bytes[start.min(bytes.len())..];
    let expected = width
        .checked_mul(height)
        .and_then(|n| n.checked_mul(channels * 4))
        .ok_or_else(|| Error::format(path, format!("PFM size {width}x{height} is too large")))?;
    if data.len() != expected {
        return Err(Error::format(
            path,
            format!(
                "expected {width}*{height}*{}4 = {expected} bytes of data, found {}",
                if channels == 3 { "3*" } else { "" },
                data.len()
            ),
        ));
    }
    let little = scale < 0.0;
    let value = |i: usize| {
        let b: [u8; 4] = data[4 * i..4 * i + 4].try_into().expect("4 bytes");
        if little {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        }
    };
    let index = |x: usize, y: usize, c: usize| ((height - 1 - y) * width + x) * channels + c;
    Ok(if channels == 1 {
        Pfm::Grey(Grid::from_fn(width, height, |x, y| value(index(x, y, 0))))
    } else {
        Pfm::Rgb(Grid::from_fn(width, height, |x, y| {
            [0, 1, 2].map(|c| value(index(x, y, c)))
        }))
    })
}

/// What a PFM header says: the channels (1 for `Pf`, 3 for `PF`), the size (within
/// `io::limits`), the scale (negative: little-endian) and where the data starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PfmHeader {
    pub channels: usize,
    pub width: usize,
    pub height: usize,
    pub scale: f64,
    pub data_start: usize,
}

/// Parses the header at the start of `bytes` (the data after it is not looked at, so a
/// prefix of the file is enough); `path` names the file in errors.
pub(crate) fn parse_header(bytes: &[u8], path: &Path) -> Result<PfmHeader> {
    let mut header = HeaderTokens { bytes, pos: 0 };
    let magic = header.next(path, "the magic `Pf` or `PF`")?;
    let channels = match magic {
        "Pf" => 1,
        "PF" => 3,
        _ => {
            return Err(Error::format(
                path,
                format!(
                    "PFM header must start with `Pf` (grey) or `PF` (colour), found `{}`",
                    magic.escape_default()
                ),
            ))
        }
    };
    let width = header.positive_int(path, "width")?;
    let height = header.positive_int(path, "height")?;
    check_size(path, "PFM", width as u64, height as u64)?;
    let scale_text = header.next(path, "the scale")?;
    let scale = match scale_text.parse::<f64>() {
        Ok(s) if s.is_finite() && s != 0.0 => s,
        _ => {
            return Err(Error::format(
                path,
                format!(
                    "PFM scale is `{}`; expected a non-zero number (negative: little-endian)",
                    scale_text.escape_default()
                ),
            ))
        }
    };
    // Exactly one whitespace byte separates the header from the data; a writer on Windows
    // may have used "\r\n".
    let mut data_start = header.pos + 1;
    if bytes.get(header.pos..header.pos + 2) == Some(b"\r\n".as_slice()) {
        data_start += 1;
    }
    Ok(PfmHeader {
        channels,
        width,
        height,
        scale,
        data_start,
    })
}

struct HeaderTokens<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> HeaderTokens<'a> {
    /// Longest header token accepted: stops a binary file from being scanned as text.
    const MAX_TOKEN: usize = 32;

    fn next(&mut self, path: &Path, what: &str) -> Result<&'a str> {
        while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        let start = self.pos;
        while self.pos < self.bytes.len()
            && !self.bytes[self.pos].is_ascii_whitespace()
            && self.pos - start <= Self::MAX_TOKEN
        {
            self.pos += 1;
        }
        let token = &self.bytes[start..self.pos];
        if token.is_empty() {
            return Err(Error::format(
                path,
                format!("PFM header ends before {what}; the file is truncated or not a PFM"),
            ));
        }
        std::str::from_utf8(token).map_err(|_| {
            Error::format(
                path,
                format!("PFM header: expected {what}, found binary data"),
            )
        })
    }

    fn positive_int(&mut self, path: &Path, what: &str) -> Result<usize> {
        let token = self.next(path, what)?;
        match token.parse::<usize>() {
            Ok(v) if v > 0 => Ok(v),
            _ => Err(Error::format(
                path,
                format!(
                    "PFM {what} is `{}`; expected a positive integer",
                    token.escape_default()
                ),
            )),
        }
    }
}

/// Writes an RGBA image as a `PF` file; PFM has no alpha channel, so alpha is dropped.
pub(crate) fn write_rgba(out: &mut impl Write, img: &RgbaImage) -> std::io::Result<()> {
    write_pfm(out, img.width(), img.height(), 3, |x, y, c| {
        img.get(x, y)[c]
    })
}

/// Writes a scalar map as a `Pf` file.
pub(crate) fn write_scalar(out: &mut impl Write, map: &ScalarMap) -> std::io::Result<()> {
    write_pfm(out, map.width(), map.height(), 1, |x, y, _| *map.get(x, y))
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
