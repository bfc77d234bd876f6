//! NumPy `.npy` through the `npyz` crate: 2-D float32 or float64 arrays, read only (no
//! output is written as `.npy`).

use std::path::Path;

use crate::io::limits::check_size;
use crate::raster::{Grid, ScalarMap};
use crate::{Error, Result};

/// Reads a 2-D (or `h x w x 1`) float32 or float64 NumPy `.npy` array, C or Fortran order,
/// no larger than `io::limits` allows.
pub fn read_npy_scalar(path: &Path) -> Result<ScalarMap> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
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

/// Checks what `npyz` trusts in a header: it allocates the header's stated length before
/// reading it, and multiplies the shape's dimensions without checking for overflow (a
/// debug build panics, a release build wraps to a small count). Headers this cannot make
/// sense of are left to `npyz` to report.
fn check_header(bytes: &[u8], path: &Path) -> Result<()> {
    use py_literal::Value;
    if !bytes.starts_with(b"\x93NUMPY") || bytes.len() < 8 {
        return Ok(());
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
    let Some(text) = bytes.get(text_at..text_at.saturating_add(len)) else {
        return Err(Error::format(
            path,
            format!(
                ".npy header claims {len} bytes but the file has {} after its preamble; it is truncated",
                bytes.len().saturating_sub(text_at)
            ),
        ));
    };
    // Parsed as npyz parses it, so that both read the same shape.
    let text = text.strip_suffix(b"\n").unwrap_or(text);
    let Some(Value::Dict(entries)) = std::str::from_utf8(text)
        .ok()
        .and_then(|t| t.parse::<Value>().ok())
    else {
        return Ok(());
    };
    let dims = |v: &Value| -> Option<Vec<u64>> {
        match v {
            Value::Tuple(d) | Value::List(d) => d
                .iter()
                .map(|n| match n {
                    Value::Integer(n) => n.to_string().parse::<u64>().ok(),
                    _ => None,
                })
                .collect(),
            _ => None,
        }
    };
    for (key, value) in &entries {
        if key.as_string().map(String::as_str) != Some("shape") {
            continue;
        }
        match dims(value).as_deref() {
            Some(&[h, w]) | Some(&[h, w, 1]) => check_size(path, "NPY", w, h)?,
            _ => {
                return Err(Error::format(
                    path,
                    format!("array shape is {value}; expected (height, width)"),
                ))
            }
        }
    }
    Ok(())
}
