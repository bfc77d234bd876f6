//! `brume.compare`: how alike two images are, as `brume compare` says (paper 002's SSIM
//! and HSV-histogram correlation, `brume::metrics`).

use super::arrays::read_image;
use super::py_err;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// compare(a, b) -> dict
///
/// How alike two images of one size are, as `brume compare A B` says (paper 002, sec.
/// 7.2.3): ssim, the mean of ssim_rgb, the structural similarity (Wang et al. 2004) of each
/// channel's sRGB values in [0, 1] with an 11x11 Gaussian window of sigma 1.5 px, K1 0.01,
/// K2 0.03, over the windows wholly inside the image; hsv_correlation, the mean of
/// hsv_correlation_hsv, the correlation (OpenCV's HISTCMP_CORREL) of 64-bin histograms of
/// hue, saturation and value. a and b as brume.fog takes an image (uint8/uint16 sRGB or
/// float linear, HxWx3), at least 11x11 px. 1 is identical for both.
#[pyfunction]
pub(crate) fn compare<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyDict>> {
    let (a, b) = (read_image(a)?.linear(), read_image(b)?.linear());
    let similarity = py
        .detach(|| brume::metrics::compare(&a, "a", &b, "b"))
        .map_err(py_err)?;
    let out = PyDict::new(py);
    out.set_item("ssim", similarity.ssim)?;
    out.set_item("ssim_rgb", similarity.ssim_rgb.to_vec())?;
    out.set_item("hsv_correlation", similarity.hsv_correlation)?;
    out.set_item(
        "hsv_correlation_hsv",
        similarity.hsv_correlation_hsv.to_vec(),
    )?;
    Ok(out)
}
