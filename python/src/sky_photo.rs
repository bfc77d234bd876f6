//! `brume.turbidity_from_sky`: paper 002's turbidity of a fisheye sky photo, as `brume
//! turbidity` estimates it (the photo read in its own primaries, a warning where its
//! codes are display-encoded); `brume.render_sky`: the synthetic sky photo `brume sky`
//! draws.

use super::arrays::{seed_of, user_warning, FsPath, ImageOut, Pixels};
use super::py_err;
use brume::sky::clouds::CloudOptions;
use brume::sky::{render_sky_photo, Fisheye, Lens, SkyExposure, SkyPhotoOptions, TurbidityOptions};
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
    seed: i128,
    repeats: i64,
) -> PyResult<Bound<'py, PyDict>> {
    let seed = seed_of("seed", seed)?;
    let max = brume::sky::turbidity::MAX_REPEATS;
    let Some(repeats) = usize::try_from(repeats)
        .ok()
        .filter(|r| (1..=max).contains(r))
    else {
        return Err(PyValueError::new_err(format!(
            "invalid repeats = {repeats}: expected 1 to {max} estimations"
        )));
    };
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

/// render_sky(turbidity, *, sun, size=500, lens='equidistant', counter_clockwise=False,
/// azimuth_offset_deg=0.0, sun_disc_deg=None, clouds=None, cloud_seed=0, dtype='float32')
/// -> (image, info)
///
/// A synthetic fisheye sky photo, as `brume sky` draws it: the Preetham sky of turbidity T
/// in [1, 20] under the sun at sun = (zenith, azimuth) in degrees, zenith in [0, 90),
/// through a square fisheye of size px (the sky on its inscribed circle, black outside;
/// lens 'equidistant', 'equisolid', 'orthographic' or 'stereographic'; azimuth 0 at the
/// image's top plus azimuth_offset_deg, clockwise unless counter_clockwise). sun_disc_deg:
/// also a white disc of this angular radius in [0, 45] around the sun (0.27 is the real
/// sun's), brighter than any exposure shows. clouds: also cover this fraction of the sky,
/// in [0, 0.9], with synthetic clouds seeded by cloud_seed. dtype: 'float32', HxWx3 linear
/// sRGB in kcd/m² (a pixel's Rec. 709 luminance is the model's Y; what brume sky writes to
/// an EXR or PFM), or 'uint8', sRGB code values exposed so that the brightest channel of
/// the sky more than 2 degrees beyond the sun is 0.9 (its PNG). info: exposure (the factor
/// applied for uint8, else None), sun_disc_pixels, clouds (coverage, pixels, opaque; or
/// None), zenith_luminance_kcd_m2, zenith_chromaticity (x, y). save_photo writes it, and
/// turbidity_from_sky estimates T back from the file.
#[pyfunction]
#[pyo3(signature = (turbidity, *, sun, size=500, lens="equidistant", counter_clockwise=false, azimuth_offset_deg=0.0, sun_disc_deg=None, clouds=None, cloud_seed=0, dtype="float32"))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn render_sky<'py>(
    py: Python<'py>,
    turbidity: f64,
    sun: (f64, f64),
    size: i64,
    lens: &str,
    counter_clockwise: bool,
    azimuth_offset_deg: f64,
    sun_disc_deg: Option<f64>,
    clouds: Option<f64>,
    cloud_seed: i128,
    dtype: &str,
) -> PyResult<(Py<PyAny>, Bound<'py, PyDict>)> {
    // Signed, so that a negative value reaches an error that names its keyword.
    let size = usize::try_from(size)
        .map_err(|_| PyValueError::new_err(format!("invalid size = {size}: expected px ≥ 1")))?;
    let cloud_seed = seed_of("cloud_seed", cloud_seed)?;
    let (pixels, exposure) = match dtype {
        "float32" => (Pixels::Linear32, SkyExposure::Physical),
        "uint8" => (Pixels::Srgb8, SkyExposure::Display),
        other => {
            return Err(PyValueError::new_err(format!(
                "dtype: expected 'float32' (linear, kcd/m²) or 'uint8' (sRGB, exposed for \
                 display), got {other:?}"
            )))
        }
    };
    if !azimuth_offset_deg.is_finite() {
        return Err(PyValueError::new_err(format!(
            "invalid azimuth_offset_deg = {azimuth_offset_deg}: expected degrees, finite"
        )));
    }
    let opts = SkyPhotoOptions {
        turbidity,
        sun_zenith: sun.0.to_radians(),
        sun_azimuth: sun.1.to_radians(),
        size,
        fisheye: Fisheye {
            lens: (lens.parse::<Lens>())
                .map_err(|e| PyValueError::new_err(format!("lens: {e}")))?,
            counter_clockwise,
            azimuth_offset: azimuth_offset_deg.to_radians(),
        },
        sun_disc: sun_disc_deg.map(f64::to_radians),
        clouds: clouds.map(|coverage| CloudOptions {
            coverage,
            seed: cloud_seed,
            ..CloudOptions::default()
        }),
        exposure,
    };
    // The library names its fields; here the keywords (the angles in degrees, as the
    // library's messages show them).
    let keyword = |field: &str| match field {
        "sun_zenith" | "sun_azimuth" => Some("sun".to_owned()),
        "sun_disc" => Some("sun_disc_deg".to_owned()),
        _ => None,
    };
    let photo =
        (py.detach(|| render_sky_photo(&opts))).map_err(|e| py_err(e.rename_options(keyword)))?;
    let image = py
        .detach(|| ImageOut::encode(&photo.image, pixels))
        .into_py(py);
    let info = PyDict::new(py);
    info.set_item("exposure", photo.exposure)?;
    info.set_item("sun_disc_pixels", photo.sun_disc_pixels)?;
    let clouds = match &photo.clouds {
        Some(c) => {
            let d = PyDict::new(py);
            d.set_item("coverage", c.coverage)?;
            d.set_item("pixels", c.pixels)?;
            d.set_item("opaque", c.opaque)?;
            Some(d)
        }
        None => None,
    };
    info.set_item("clouds", clouds)?;
    info.set_item("zenith_luminance_kcd_m2", photo.zenith_luminance)?;
    let [x, y] = photo.zenith_chromaticity;
    info.set_item("zenith_chromaticity", (x, y))?;
    Ok((image, info))
}
