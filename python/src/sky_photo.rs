//! `brume.turbidity_from_sky`: paper 002's turbidity of a fisheye sky photo, as `brume
//! turbidity` estimates it (the photo read in its own primaries, a warning where its
//! codes are display-encoded).

use super::arrays::{user_warning, FsPath};
use super::py_err;
use brume::sky::TurbidityOptions;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// turbidity_from_sky(path, *, sun=None, seed=0, repeats=10) -> dict
///
/// The atmospheric turbidity T of the fisheye sky photo at path (paper 002, sec. 3.4),
/// as `brume turbidity` estimates it: an equidistant fisheye pointed at the zenith,
/// azimuth 0 at the image's top, clockwise. sun: (zenith, azimuth) in degrees, or None
/// to find it from the saturated disc. The luminance is the photo's own primaries'
/// (its colour profile's Y row). A display-encoded photo (JPEG, 8- or 16-bit PNG) warns
/// (UserWarning): a camera's tone curve biases T; give linear light (an EXR, or the RAW
/// developed to a linear TIFF or PNG). Returns turbidity, std, fit_std, repeats,
/// samples, inliers, sun_zenith_deg, sun_azimuth_deg, sun_source ('given' or
/// 'detected'), usable_pixels, colour_profile (None for sRGB), luminance_weights,
/// linear_light and image_circle ((x, y, side) of the square estimated when the frame
/// was a circular fisheye's, with black around its disc; None for a square image).
#[pyfunction]
#[pyo3(signature = (path, *, sun=None, seed=0, repeats=10))]
pub(crate) fn turbidity_from_sky<'py>(
    py: Python<'py>,
    path: FsPath,
    sun: Option<(f64, f64)>,
    seed: u64,
    repeats: usize,
) -> PyResult<Bound<'py, PyDict>> {
    if !(1..=brume::sky::turbidity::MAX_REPEATS).contains(&repeats) {
        return Err(PyValueError::new_err(format!(
            "invalid repeats = {repeats}: expected 1 to {} estimations",
            brume::sky::turbidity::MAX_REPEATS
        )));
    }
    let opts = TurbidityOptions {
        sun: sun.map(|(z, a)| [z.to_radians(), a.to_radians()]),
        seed,
        repeats,
        ..TurbidityOptions::default()
    };
    let sky = py
        .detach(|| brume::photo::estimate_sky_photo(&path.0, &opts))
        .map_err(py_err)?;
    if !sky.linear_light {
        user_warning(py, brume::photo::display_encoded_sky(&path.0))?;
    }
    let e = &sky.estimate;
    let out = PyDict::new(py);
    out.set_item("turbidity", e.turbidity)?;
    out.set_item("std", e.std)?;
    out.set_item("fit_std", e.fit_std)?;
    out.set_item("repeats", e.repeats)?;
    out.set_item("samples", e.samples)?;
    out.set_item("inliers", e.inliers)?;
    out.set_item("sun_zenith_deg", e.sun_zenith.to_degrees())?;
    out.set_item("sun_azimuth_deg", e.sun_azimuth.to_degrees())?;
    out.set_item("sun_source", e.sun_source.name())?;
    out.set_item("usable_pixels", e.usable_pixels)?;
    out.set_item("colour_profile", sky.colour_profile.as_deref())?;
    out.set_item("luminance_weights", sky.luminance.to_vec())?;
    out.set_item("linear_light", sky.linear_light)?;
    out.set_item("image_circle", sky.circle.map(|c| (c.x, c.y, c.side)))?;
    Ok(out)
}
