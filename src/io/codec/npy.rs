//! NumPy `.npy` through the `npyz` crate: 2-D float32 or float64 arrays, read only (no
//! output is written as `.npy`).

use std::path::Path;

use crate::io::limits::check_size;
use crate::raster::{Grid, ScalarMap};
use crate::{Error, Result};

/// Reads a 2-D (or `h x w x 1`) float32 or float64 NumPy `.npy` array, C or Fortran order,
/// no larger than `io::limits` allows.
pub fn read_npy_scalar(path: &Path) -> Result<ScalarMap> {
    let bytes = crate::io::limits::read_file(path)?;
    parse_npy_scalar(&bytes, path)
}

pub(crate) fn parse_npy_scalar(bytes: &[u8], path: &Path) -> Result<ScalarMap> {
    check_header(bytes, path)?;
    let npy = npyz::NpyFile::new(bytes)
        .map_err(|e| Error::format(path, format!("not a valid .npy file: {e}")))?;
    let shape = npy.shape().to_vec();
    let (h, w) = match shape[..] {
        [h, w] | [h, w, 1] if h > 0 && w > 0 => (h, w),
        _ => {
            return Err(Error::format(
                path,
                format!("array shape is {shape:?}; expected (height, width)"),
            ))
        }
    };
    // Before anything is sized from the shape: a product of two 2^32 sides wraps to 0.
    check_size(path, "NPY", w, h)?;
    let (h, w) = (h as usize, w as usize);
    // The smallest accepted dtype takes 4 bytes a value: a shorter file cannot hold them,
    // and the reader would otherwise reserve room for all of them first.
    if bytes.len() < w * h * 4 {
        return Err(Error::format(
            path,
            format!(
                "array shape ({h}, {w}) needs at least {} bytes of float data, but the file has {}; it is truncated",
                w * h * 4,
                bytes.len()
            ),
        ));
    }
    let fortran = npy.order() == npyz::Order::Fortran;
    let dtype = npy.dtype().descr();
    let truncated = |e: std::io::Error| {
        Error::format(
            path,
            format!("cannot read {h}*{w} values of {dtype}: {e}; the file may be truncated"),
        )
    };
    let values: Vec<f32> = match npy.try_data::<f32>() {
        Ok(reader) => reader.collect::<std::io::Result<_>>().map_err(truncated)?,
        Err(npy) => match npy.try_data::<f64>() {
            Ok(reader) => reader
                .map(|v| v.map(|x| x as f32))
                .collect::<std::io::Result<_>>()
                .map_err(truncated)?,
            Err(_) => {
                return Err(Error::format(
                    path,
                    format!("array dtype is {dtype}; expected float32 or float64"),
                ))
            }
        },
    };
    if values.len() != w * h {
        return Err(Error::format(
            path,
            format!("expected {h}*{w} values, found {}", values.len()),
        ));
    }
    Ok(if fortran {
        Grid::from_fn(w, h, |x, y| values[x * h + y])
    } else {
        Grid::from_vec(w, h, values)
    })
}

/// Longest .npy header text accepted: numpy's own `max_header_size` default, for the
/// same reason (parsing a long Python literal is slow).
const MAX_HEADER: usize = 10_000;

/// Checks a header before `npyz` sees it. `npyz` allocates the header's stated length
/// before reading it, multiplies the shape's dimensions without checking for overflow (a
/// debug build panics, a release build wraps to a small count), and parses the header with
/// a Python-literal parser that takes exponential time on nested or unclosed brackets (16
/// `{` took longer than the fuzzer's 10 s). So the header must be the plain dictionary
/// numpy writes for an array, read here in linear time, and its shape within `io::limits`.
fn check_header(bytes: &[u8], path: &Path) -> Result<()> {
    if !bytes.starts_with(b"\x93NUMPY") || bytes.len() < 8 {
        return Ok(()); // npyz names what is wrong
    }
    // Version 1 gives the header length in 2 bytes, later versions in 4.
    let (text_at, len): (usize, _) = match bytes[6] {
        1 => (
            10,
            bytes
                .get(8..10)
                .map(|b| usize::from(u16::from_le_bytes([b[0], b[1]]))),
        ),
        _ => (
            12,
            bytes
                .get(8..12)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize),
        ),
    };
    let Some(len) = len else {
        return Ok(());
    };
    if len > MAX_HEADER {
        return Err(Error::format(
            path,
            format!(
                ".npy header claims {len} bytes; at most {MAX_HEADER} are accepted, as by numpy"
            ),
        ));
    }
    let Some(text) = bytes.get(text_at..text_at + len) else {
        return Err(Error::format(
            path,
            format!(
                ".npy header claims {len} bytes but the file has {} after its preamble; it is truncated",
                bytes.len().saturating_sub(text_at)
            ),
        ));
    };
    let shape = PlainHeader { text, pos: 0 }.shape().ok_or_else(|| {
        Error::format(
            path,
            format!(
                ".npy header `{}` is not the dictionary numpy writes for a plain array; expected \
                 {{'descr': '<f4', 'fortran_order': False, 'shape': (height, width), }}",
                String::from_utf8_lossy(&text[..text.len().min(120)]).trim_end()
            ),
        )
    })?;
    // Any other shape is refused here too: npyz would multiply its dimensions first.
    match shape[..] {
        [h, w] | [h, w, 1] => check_size(path, "NPY", w, h),
        _ => Err(Error::format(
            path,
            format!("array shape is {shape:?}; expected (height, width)"),
        )),
    }
}

/// A linear-time reader of the header numpy writes for a plain (not structured) dtype: a
/// dictionary of quoted keys whose values are quoted strings, `True`, `False`, or tuples or
/// lists of integers. Anything else is refused before the slow Python-literal parser sees
/// it; a plain float array never needs more.
struct PlainHeader<'a> {
    text: &'a [u8],
    pos: usize,
}

impl<'a> PlainHeader<'a> {
    /// The last `shape` entry (the one npyz keeps), if the whole header is plain.
    fn shape(mut self) -> Option<Vec<u64>> {
        let mut shape = None;
        self.expect(b'{')?;
        loop {
            if self.eat(b'}') {
                break;
            }
            let key = self.string()?;
            self.expect(b':')?;
            if key == b"shape" {
                shape = Some(self.integers()?);
            } else {
                self.scalar()?;
            }
            if !self.eat(b',') {
                self.expect(b'}')?;
                break;
            }
        }
        self.skip_space();
        (self.pos == self.text.len()).then_some(shape).flatten()
    }

    fn skip_space(&mut self) {
        while self.text.get(self.pos).is_some_and(u8::is_ascii_whitespace) {
            self.pos += 1;
        }
    }

    fn eat(&mut self, c: u8) -> bool {
        self.skip_space();
        let found = self.text.get(self.pos) == Some(&c);
        self.pos += usize::from(found);
        found
    }

    fn expect(&mut self, c: u8) -> Option<()> {
        self.eat(c).then_some(())
    }

    /// A quoted string without escapes.
    fn string(&mut self) -> Option<&'a [u8]> {
        self.skip_space();
        let quote = *self
            .text
            .get(self.pos)
            .filter(|&&q| q == b'\'' || q == b'"')?;
        let start = self.pos + 1;
        let text = self.text;
        let len = text[start..]
            .iter()
            .position(|&c| c == quote || c == b'\\')?;
        if text[start + len] != quote {
            return None;
        }
        self.pos = start + len + 1;
        Some(&text[start..start + len])
    }

    /// A quoted string, `True` or `False`.
    fn scalar(&mut self) -> Option<()> {
        self.skip_space();
        for word in [&b"True"[..], b"False"] {
            if self.text[self.pos..].starts_with(word) {
                self.pos += word.len();
                return Some(());
            }
        }
        self.string().map(|_| ())
    }

    /// `(a, b, ...)` or `[a, b, ...]` of non-negative integers, trailing comma allowed.
    fn integers(&mut self) -> Option<Vec<u64>> {
        let close = if self.eat(b'(') {
            b')'
        } else {
            self.expect(b'[')?;
            b']'
        };
        let mut v = Vec::new();
        loop {
            if self.eat(close) {
                return Some(v);
            }
            self.skip_space();
            let digits = self.text[self.pos..]
                .iter()
                .take_while(|c| c.is_ascii_digit())
                .count();
            // More than 20 digits cannot be a u64; refused without parsing them.
            if digits == 0 || digits > 20 {
                return None;
            }
            let n = std::str::from_utf8(&self.text[self.pos..self.pos + digits])
                .ok()?
                .parse()
                .ok()?;
            v.push(n);
            self.pos += digits;
            if !self.eat(b',') {
                self.expect(close)?;
                return Some(v);
            }
        }
    }
}
