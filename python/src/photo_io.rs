//! Photos read and written as brume's own commands read and write them: upright by their
//! EXIF orientation, decoded by their colour profile's curves (an Adobe RGB photo's gamma,
//! a PNG's `gAMA`), and written with that profile and their EXIF block, atomically.

use std::sync::Arc;

use super::arrays::{read_image, FsPath, ImageOut, Pixels};
use super::py_err;
use brume::io::colour_profile::ColourProfile;
use brume::io::metadata::PhotoMetadata;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

/// load_photo(path, *, dtype='uint8') -> (image, info)
///
/// Reads a photo (PNG, JPEG, WebP, TIFF, OpenEXR or colour PFM) as `brume render` reads
/// it: turned upright by its EXIF orientation, decoded by its colour profile's own curves
/// (an ICC profile, a PNG's cICP, gAMA or cHRM), to an HxWx3 array of dtype 'uint8' or 'uint16'
/// (encoded by the sRGB curve, in the photo's primaries: what brume.fog takes and gives
/// back) or 'float32' (linear light; an EXR's values above 1 kept). info: orientation
/// (the EXIF orientation applied, 1 to 8), focal_length_35mm (or None), colour_profile
/// (its description, or None for sRGB), icc_profile and exif (bytes, or None): pass info
/// to save_photo so that the fogged photo keeps its colours, date and camera.
#[pyfunction]
#[pyo3(signature = (path, *, dtype="uint8"))]
pub(crate) fn load_photo<'py>(
    py: Python<'py>,
    path: FsPath,
    dtype: &str,
) -> PyResult<(Py<PyAny>, Bound<'py, PyDict>)> {
    let pixels = match dtype {
        "uint8" => Pixels::Srgb8,
        "uint16" => Pixels::Srgb16,
        "float32" => Pixels::Linear32,
        other => {
            return Err(PyValueError::new_err(format!(
                "dtype: expected 'uint8', 'uint16' (sRGB code values) or 'float32' (linear \
                 light), got {other:?}"
            )))
        }
    };
    let photo = py
        .detach(|| brume::io::image::load_upright_rgb(&path.0))
        .map_err(py_err)?;
    let image = py
        .detach(|| ImageOut::encode(&photo.image, pixels))
        .into_py(py);
    let info = PyDict::new(py);
    info.set_item("orientation", photo.exif.orientation.exif())?;
    info.set_item("focal_length_35mm", photo.exif.focal_35mm)?;
    let profile = photo.metadata.profile();
    info.set_item("colour_profile", profile.map(ColourProfile::description))?;
    info.set_item("icc_profile", profile.map(|p| PyBytes::new(py, p.icc())))?;
    let exif = photo.metadata.exif.as_deref();
    info.set_item("exif", exif.map(|e| PyBytes::new(py, e)))?;
    Ok((image, info))
}

/// save_photo(path, image, info=None)
///
/// Writes an HxWx3 image (uint8 or uint16 sRGB code values, or float32 or float64 linear
/// light, as brume.fog takes them) by its extension: .png and .jpg (quality 95) carry
/// info's icc_profile and exif (from load_photo; the EXIF's orientation set to 1, as the
/// image is upright, and its pixel size to the image's), .exr its primaries in its
/// chromaticities, .pfm neither. Written to a temporary file and renamed, so that a
/// failure leaves no partial file; an existing file at path is replaced.
#[pyfunction]
#[pyo3(signature = (path, image, info=None))]
pub(crate) fn save_photo(
    py: Python<'_>,
    path: FsPath,
    image: &Bound<'_, PyAny>,
    info: Option<&Bound<'_, PyDict>>,
) -> PyResult<()> {
    let image = read_image(image)?;
    let metadata = match info {
        Some(info) => metadata_of(info, &path.0.display().to_string())?,
        None => PhotoMetadata::default(),
    };
    py.detach(|| brume::io::output::write_photo(&path.0, &image.linear().opaque(), &metadata))
        .map_err(py_err)
}

/// The colour profile and EXIF block of load_photo's `info`; either may be absent or
/// None. A profile that cannot be read is ignored with brume's warning, as a photo's is.
fn metadata_of(info: &Bound<'_, PyDict>, name: &str) -> PyResult<PhotoMetadata> {
    let bytes_of = |key: &str| -> PyResult<Option<Vec<u8>>> {
        match info.get_item(key)? {
            Some(v) if !v.is_none() => v.extract::<Vec<u8>>().map(Some).map_err(|_| {
                PyValueError::new_err(format!(
                    "info[{key:?}]: expected bytes (as load_photo gives) or None"
                ))
            }),
            _ => Ok(None),
        }
    };
    Ok(PhotoMetadata {
        profile: bytes_of("icc_profile")?.and_then(|icc| ColourProfile::from_icc(icc, name)),
        exif: bytes_of("exif")?.map(Arc::new),
    })
}
