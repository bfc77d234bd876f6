//! numpy arrays in and out: images (uint8 sRGB or float linear RGB, the encoding kept for
//! the output) and range maps, copied with the GIL and converted without it.

use super::value_error;
use brume::io::image::{linear_to_srgb, linear_to_srgb8_rgb, srgb8_rgb_to_linear, srgb_to_linear};
use brume::raster::{Grid, RgbImage, ScalarMap};
use numpy::ndarray::{Array2, Array3};
use numpy::{
    IntoPyArray, PyArrayDescrMethods, PyReadonlyArray2, PyReadonlyArray3, PyReadonlyArrayDyn,
    PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyTypeError, PyUserWarning};
use pyo3::prelude::*;
use pyo3::types::PyBool;
use std::ffi::CString;
use std::path::PathBuf;

/// A colour keyword as Python gives it: one number for a grey, or three linear RGB values
/// in any sequence (list, tuple, numpy array). The values are checked where the keyword is
/// read, which names it.
pub(crate) struct Colour(pub Vec<f64>);

impl<'a, 'py> FromPyObject<'a, 'py> for Colour {
    type Error = PyErr;

    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        match numbers(obj) {
            Some((grey, false)) => Ok(Colour(vec![grey[0]; 3])),
            Some((rgb, true)) => Ok(Colour(rgb)),
            None => Err(not_numbers(
                obj,
                "a colour: expected a number (a grey) or three linear RGB values",
            )),
        }
    }
}

/// One number as `([v], false)`, or a sequence of numbers (list, tuple, numpy array) as
/// `(values, true)`; `None` for anything else. A bool is an int to Python, but
/// `airlight=True` or `beta=True` is a mistake, not a value of 1: `None`.
pub(crate) fn numbers(obj: Borrowed<'_, '_, PyAny>) -> Option<(Vec<f64>, bool)> {
    if obj.is_instance_of::<PyBool>() {
        return None;
    }
    // The sequence first: numpy 2.2 still converts a one-element array to a number (with
    // a DeprecationWarning; 2.4 refuses), and `beta=np.array([0.01])` is a list of one.
    if let Ok(values) = obj.extract::<Vec<f64>>() {
        return Some((values, true));
    }
    obj.extract::<f64>().ok().map(|value| (vec![value], false))
}

/// The `TypeError` of a keyword that [`numbers`] could not read: its value, then "is not
/// {what}".
pub(crate) fn not_numbers(obj: Borrowed<'_, '_, PyAny>, what: &str) -> PyErr {
    let repr = obj.repr().map(|r| r.to_string()).unwrap_or_default();
    PyTypeError::new_err(format!("{repr} is not {what}"))
}

/// A path as Python's own file functions take it: str, bytes or os.PathLike, decoded
/// by `os.fsdecode` (PyO3's `PathBuf` refuses bytes, although its message lists them).
pub(crate) struct FsPath(pub(crate) PathBuf);

impl<'a, 'py> FromPyObject<'a, 'py> for FsPath {
    type Error = PyErr;

    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let os = obj.py().import("os")?;
        let decoded = os.call_method1("fsdecode", (obj,))?;
        Ok(FsPath(decoded.extract()?))
    }
}

/// The encoding of an image array, which the output keeps.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Pixels {
    /// uint8 sRGB code values.
    Srgb8,
    /// uint16 sRGB code values (a 16-bit PNG as OpenCV or imageio decode it).
    Srgb16,
    /// float32 linear RGB.
    Linear32,
    /// float64 linear RGB.
    Linear64,
    /// float16 linear RGB (a half-precision pipeline's tensors).
    Linear16,
}

/// An image copied out of numpy (with the GIL), converted to linear light later (without).
pub(crate) enum RawImage {
    Srgb8(Vec<u8>),
    Srgb16(Vec<u16>),
    Linear(Vec<f32>),
}

pub(crate) struct ImageIn {
    pub(crate) width: usize,
    pub(crate) height: usize,
    pub(crate) pixels: Pixels,
    pub(crate) raw: RawImage,
}

fn dtype_name(array: &Bound<'_, PyUntypedArray>) -> String {
    array
        .dtype()
        .str()
        .map(|s| s.to_string())
        .unwrap_or_else(|_| "?".into())
}

pub(crate) fn read_image(image: &Bound<'_, PyAny>) -> PyResult<ImageIn> {
    let untyped = image.cast::<PyUntypedArray>().map_err(|_| {
        value_error(format!(
            "image: expected a numpy array HxWx3 (uint8 or uint16 sRGB, or float32, float64 or \
             float16 linear RGB), got {}",
            image
                .get_type()
                .name()
                .map(|n| n.to_string())
                .unwrap_or_default()
        ))
    })?;
    let shape = untyped.shape().to_vec();
    if shape.len() != 3 || shape[2] != 3 || shape[0] == 0 || shape[1] == 0 {
        let hint = match shape.as_slice() {
            [3, _, _] => " (channels first, as torch holds images: image.transpose(1, 2, 0))",
            [_, _, 4] => " (RGBA: image[..., :3])",
            [_, _] => " (grey: np.repeat(image[..., None], 3, axis=2))",
            _ => "",
        };
        return Err(value_error(format!(
            "image: expected shape HxWx3 (RGB, H and W > 0), got {shape:?}{hint}"
        )));
    }
    let (height, width) = (shape[0], shape[1]);
    let dtype = untyped.dtype();
    let py = image.py();
    let code_values = if dtype.is_equiv_to(&numpy::dtype::<u8>(py)) {
        Some((Pixels::Srgb8, RawImage::Srgb8(copied(image)?)))
    } else if dtype.is_equiv_to(&numpy::dtype::<u16>(py)) {
        Some((Pixels::Srgb16, RawImage::Srgb16(copied(image)?)))
    } else {
        None
    };
    if let Some((pixels, raw)) = code_values {
        return Ok(ImageIn {
            width,
            height,
            pixels,
            raw,
        });
    }
    let (pixels, raw): (Pixels, Vec<f32>) = if dtype.is_equiv_to(&numpy::dtype::<f32>(py)) {
        (Pixels::Linear32, copied(image)?)
    } else if dtype.is_equiv_to(&numpy::dtype::<f64>(py)) {
        let a: PyReadonlyArray3<f64> = image.extract()?;
        (
            Pixels::Linear64,
            a.as_array().iter().map(|&v| v as f32).collect(),
        )
    } else if dtype.is_equiv_to(&numpy::dtype::<half::f16>(py)) {
        // Exact: every float16 is a float32.
        let a: PyReadonlyArray3<half::f16> = image.extract()?;
        (
            Pixels::Linear16,
            a.as_array().iter().map(|v| v.to_f32()).collect(),
        )
    } else {
        return Err(value_error(format!(
            "image: expected dtype uint8 or uint16 (sRGB code values), or float32, float64 \
             or float16 (linear RGB in [0, 1]), got {}",
            dtype_name(untyped)
        )));
    };
    if let Some(i) = raw.iter().position(|v| !v.is_finite()) {
        let (pixel, channel) = (i / 3, i % 3);
        return Err(value_error(format!(
            "image: value {} at pixel (x {}, y {}), channel {channel}: expected finite linear RGB in [0, 1]",
            raw[i],
            pixel % width,
            pixel / width
        )));
    }
    warn_if_code_values(py, &raw)?;
    Ok(ImageIn {
        width,
        height,
        pixels,
        raw: RawImage::Linear(raw),
    })
}

/// The values of an HxWx3 array of `T`, row by row.
fn copied<T: numpy::Element + Copy>(image: &Bound<'_, PyAny>) -> PyResult<Vec<T>> {
    let a: PyReadonlyArray3<T> = image.extract()?;
    Ok(a.as_array().iter().copied().collect())
}

/// Warns (Python's `UserWarning`) when a float image holds only whole numbers and some
/// above 1: 8-bit code values cast to float (`image.astype(np.float32)`), which would be
/// fogged as linear light hundreds of times too bright. Not an error: a float image above
/// 1 is HDR, which brume takes, and a whole-numbered one is only very likely a mistake.
fn warn_if_code_values(py: Python<'_>, raw: &[f32]) -> PyResult<()> {
    let max = raw.iter().copied().fold(0.0f32, f32::max);
    if max <= 1.0 || raw.iter().any(|v| v.fract() != 0.0) {
        return Ok(());
    }
    let message = format!(
        "image: a float image of whole numbers up to {max} looks like 8-bit code values; a \
         float image is taken as linear RGB in [0, 1] (above 1 as HDR): pass the uint8 array \
         itself, or linear light (the sRGB curve of image / 255)"
    );
    user_warning(py, message)
}

/// Raises Python's `UserWarning` with `message`, attributed to the caller's line.
pub(crate) fn user_warning(py: Python<'_>, message: String) -> PyResult<()> {
    let message = CString::new(message).expect("no NUL in the message");
    PyErr::warn(py, &py.get_type::<PyUserWarning>(), &message, 1)
}

impl ImageIn {
    /// Linear RGB, as brume's PNG loader makes it (the exact sRGB curve for 8-bit values;
    /// negative linear values clamped to 0, as brume does for float files).
    pub(crate) fn linear(self) -> RgbImage {
        let data = match self.raw {
            RawImage::Srgb8(raw) => srgb8_rgb_to_linear(&raw),
            // As brume's loader decodes a 16-bit PNG: code / 65535, then the sRGB curve.
            RawImage::Srgb16(raw) => raw
                .chunks_exact(3)
                .map(|p| [0, 1, 2].map(|k| srgb_to_linear(f32::from(p[k]) / 65535.0)))
                .collect(),
            RawImage::Linear(raw) => raw
                .chunks_exact(3)
                .map(|p| [p[0].max(0.0), p[1].max(0.0), p[2].max(0.0)])
                .collect(),
        };
        Grid::from_vec(self.width, self.height, data)
    }
}

pub(crate) fn read_range(range: &Bound<'_, PyAny>) -> PyResult<ScalarMap> {
    read_scalar_map(
        range,
        "range_m",
        "ranges in metres",
        "the image's size or smaller by one factor",
        "metres; NaN or <= 0 where unknown",
    )
}

/// An HxW float32, float64 or float16 array argument named `what` (holding `holds`, its shape
/// `shape_is`, its values `values`: said when it is not) as a float map.
pub(crate) fn read_scalar_map(
    array: &Bound<'_, PyAny>,
    what: &str,
    holds: &str,
    shape_is: &str,
    values: &str,
) -> PyResult<ScalarMap> {
    let untyped = array.cast::<PyUntypedArray>().map_err(|_| {
        value_error(format!(
            "{what}: expected a numpy array HxW of {holds} (float32)"
        ))
    })?;
    let shape = untyped.shape().to_vec();
    let Some((height, width)) = map_size(&shape) else {
        let hint = match shape.as_slice() {
            [1, _, 1] => " (which axis is the height? pass the HxW array itself)",
            _ => "",
        };
        return Err(value_error(format!(
            "{what}: expected shape HxW ({shape_is}; HxWx1 and 1xHxW are taken too), got \
             {shape:?}{hint}"
        )));
    };
    let py = array.py();
    let dtype = untyped.dtype();
    // Row by row whatever the axes: the singleton axis adds no values.
    let data: Vec<f32> = if dtype.is_equiv_to(&numpy::dtype::<f32>(py)) {
        let a: PyReadonlyArrayDyn<f32> = array.extract()?;
        a.as_array().iter().copied().collect()
    } else if dtype.is_equiv_to(&numpy::dtype::<f64>(py)) {
        let a: PyReadonlyArrayDyn<f64> = array.extract()?;
        a.as_array().iter().map(|&v| v as f32).collect()
    } else if dtype.is_equiv_to(&numpy::dtype::<half::f16>(py)) {
        // Exact: every float16 is a float32.
        let a: PyReadonlyArrayDyn<half::f16> = array.extract()?;
        a.as_array().iter().map(|v| v.to_f32()).collect()
    } else {
        return Err(value_error(format!(
            "{what}: expected dtype float32, float64 or float16 ({values}), got {}",
            dtype_name(untyped)
        )));
    };
    Ok(Grid::from_vec(width, height, data))
}

/// The (height, width) of a map's array shape: HxW, or with a channel axis of one, last
/// (HxWx1: numpy's and albumentations' masks) or first (1xHxW: a torch depth tensor's
/// `.numpy()`); `None` for any other shape, an empty one, or 1xNx1 (either could be the
/// height).
fn map_size(shape: &[usize]) -> Option<(usize, usize)> {
    let (h, w) = match *shape {
        [h, w] => (h, w),
        [1, _, 1] => return None,
        [h, w, 1] => (h, w),
        [1, h, w] => (h, w),
        _ => return None,
    };
    (h > 0 && w > 0).then_some((h, w))
}

/// A mask argument (`sky_mask`, `ego_mask`): an HxW numpy array of bool or integers
/// (non-zero = set) of `shape` (the range's), not set everywhere (`all_set` says what such
/// a mask probably is).
pub(crate) fn read_mask(
    mask: &Bound<'_, PyAny>,
    name: &str,
    shape: (usize, usize),
    all_set: &str,
) -> PyResult<Grid<bool>> {
    let expected = format!(
        "an HxW numpy array of bool or integers (non-zero = set) of the range's shape {}x{}",
        shape.0, shape.1
    );
    let untyped = mask
        .cast::<PyUntypedArray>()
        .map_err(|_| value_error(format!("{name}: expected {expected}")))?;
    let got = untyped.shape().to_vec();
    if got != [shape.0, shape.1] {
        return Err(value_error(format!(
            "{name}: expected {expected}, got shape {got:?}"
        )));
    }
    let py = mask.py();
    let dtype = untyped.dtype();
    let set = if dtype.is_equiv_to(&numpy::dtype::<bool>(py)) {
        nonzero::<bool>(mask)?
    } else if dtype.is_equiv_to(&numpy::dtype::<u8>(py)) {
        nonzero::<u8>(mask)?
    } else if dtype.is_equiv_to(&numpy::dtype::<i32>(py)) {
        nonzero::<i32>(mask)?
    } else if dtype.is_equiv_to(&numpy::dtype::<i64>(py)) {
        nonzero::<i64>(mask)?
    } else {
        return Err(value_error(format!(
            "{name}: expected {expected}, got dtype {}",
            dtype_name(untyped)
        )));
    };
    if set.iter().all(|&s| s) {
        return Err(value_error(format!(
            "{name}: every pixel is set: expected {all_set}"
        )));
    }
    Ok(Grid::from_vec(shape.1, shape.0, set))
}

/// Where a 2D array of `T` is not zero (false), row by row.
fn nonzero<T: numpy::Element + Copy + Default + PartialEq>(
    mask: &Bound<'_, PyAny>,
) -> PyResult<Vec<bool>> {
    let a: PyReadonlyArray2<T> = mask.extract()?;
    Ok(a.as_array().iter().map(|&v| v != T::default()).collect())
}

/// A seed keyword `name` as brume's u64. Taken from Python as a wider signed int, so that a
/// negative or too large one is a ValueError naming the keyword (pyo3's own conversion to an
/// unsigned int raises an OverflowError that names nothing).
pub(crate) fn seed_of(name: &str, value: i128) -> PyResult<u64> {
    u64::try_from(value).map_err(|_| {
        value_error(format!(
            "invalid {name} = {value}: expected a whole number from 0 to 2^64 - 1"
        ))
    })
}

/// A map (range and transmittance as float32, a mask as bool) as an HxW array, row 0 at
/// the top as brume keeps it.
pub(crate) fn grid_to_py<T: numpy::Element>(py: Python<'_>, map: Grid<T>) -> Py<PyAny> {
    let (w, h) = (map.width(), map.height());
    Array2::from_shape_vec((h, w), map.into_vec())
        .expect("shape")
        .into_pyarray(py)
        .into_any()
        .unbind()
}

/// What a fogged frame goes back to Python as.
pub(crate) enum ImageOut {
    Srgb8(Array3<u8>),
    Srgb16(Array3<u16>),
    Linear32(Array3<f32>),
    Linear64(Array3<f64>),
    Linear16(Array3<half::f16>),
}

impl ImageOut {
    /// brume's linear RGB or RGBA in the input's encoding: 8-bit sRGB exactly as brume's
    /// PNG writer rounds it (clamped to [0, 1], NaN as 0), 16-bit sRGB likewise to the
    /// nearest of 65535 codes, or linear floats as rendered.
    pub(crate) fn encode<const N: usize>(
        image: &brume::raster::Grid<[f32; N]>,
        pixels: Pixels,
    ) -> ImageOut {
        let shape = (image.height(), image.width(), 3);
        let rgb = image.as_slice().iter().flat_map(|p| [p[0], p[1], p[2]]);
        match pixels {
            Pixels::Srgb8 => ImageOut::Srgb8(
                Array3::from_shape_vec(
                    shape,
                    linear_to_srgb8_rgb(image.as_slice()).into_flattened(),
                )
                .expect("shape"),
            ),
            Pixels::Srgb16 => ImageOut::Srgb16(
                Array3::from_shape_vec(shape, rgb.map(linear_to_srgb16).collect()).expect("shape"),
            ),
            Pixels::Linear32 => {
                ImageOut::Linear32(Array3::from_shape_vec(shape, rgb.collect()).expect("shape"))
            }
            Pixels::Linear64 => ImageOut::Linear64(
                Array3::from_shape_vec(shape, rgb.map(f64::from).collect()).expect("shape"),
            ),
            // To the nearest float16 (ties to even); above 65504 it is infinite.
            Pixels::Linear16 => ImageOut::Linear16(
                Array3::from_shape_vec(shape, rgb.map(half::f16::from_f32).collect())
                    .expect("shape"),
            ),
        }
    }

    pub(crate) fn into_py(self, py: Python<'_>) -> Py<PyAny> {
        match self {
            ImageOut::Srgb8(a) => a.into_pyarray(py).into_any().unbind(),
            ImageOut::Srgb16(a) => a.into_pyarray(py).into_any().unbind(),
            ImageOut::Linear32(a) => a.into_pyarray(py).into_any().unbind(),
            ImageOut::Linear64(a) => a.into_pyarray(py).into_any().unbind(),
            ImageOut::Linear16(a) => a.into_pyarray(py).into_any().unbind(),
        }
    }
}

/// A linear value as a 16-bit sRGB code: clamped to [0, 1] (NaN as 0), the sRGB curve,
/// rounded to the nearest of 65535 steps.
fn linear_to_srgb16(v: f32) -> u16 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    (linear_to_srgb(v) * 65535.0).round() as u16
}
