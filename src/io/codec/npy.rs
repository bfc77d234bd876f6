//! NumPy `.npy` through the `npyz` crate: 2-D float32 or float64 arrays, read only (no
//! output is written as `.npy`).

use std::path::Path;

use crate::raster::{Grid, ScalarMap};
use crate::{Error, Result};

/// Reads a 2-D (or `h x w x 1`) float32 or float64 NumPy `.npy` array, C or Fortran order.
pub fn read_npy_scalar(path: &Path) -> Result<ScalarMap> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_npy_scalar(&bytes, path)
}

pub(crate) fn parse_npy_scalar(bytes: &[u8], path: &Path) -> Result<ScalarMap> {
    let npy = npyz::NpyFile::new(bytes)
        .map_err(|e| Error::format(path, format!("not a valid .npy file: {e}")))?;
    let shape = npy.shape().to_vec();
    let (h, w) = match shape[..] {
        [h, w] | [h, w, 1] if h > 0 && w > 0 => (h as usize, w as usize),
        _ => {
            return Err(Error::format(
                path,
                format!("array shape is {shape:?}; expected (height, width)"),
            ))
        }
    };
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
