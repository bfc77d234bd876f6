//! `brume.prepare`: a photo's range pre-processed and refined as `brume.fog` would read it,
//! without the fog (`brume prep` with an image), CPU only: no GL context.

use super::arrays::{grid_to_py, read_image, read_range, Colour};
use super::photo_fog::{self, prepare_request, set_masks};
use super::py_err;
use brume::photo::{self, Photo};
use brume::refine::CpuFilter;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict};

/// prepare(image, range_m, *, refine=True, sky_mask=None, ego_mask=None, airlight=None,
/// monocular=False, stereo_focal_baseline=None, stereo_view=None, ground=None)
/// -> (range_m, info)
///
/// The range brume.fog reads for this image, without the fog: pre-processed (holes and
/// stereo occlusions filled, the sky found, outliers dropped) and refined at the image's
/// size, as `brume prep --image` makes it, on the CPU (no GL context). The keywords are
/// brume.fog's. Returns float32 HxW (the image's size), finite everywhere, in range_m's
/// units, the sky at 1.5 times the farthest range (paper 000's convention: what fog with ka
/// and ks reads), and info: physical_range_m (what fog with beta or visibility reads, its
/// labels' range_m: the sky at 1 km and the scene beyond the sensor's reach receding toward
/// it), sky, filled and beyond_reach (bool HxW masks: the sky, the holes filled, the scene
/// beyond the sensor's reach), airlight (linear RGB) and airlight_source, refine (the mode
/// that ran), upsampled, and the pre-processing's counts
/// (holes, hole_pixels, colour_regions, occluded, sky_pixels, sky_components,
/// margin_pixels, far_outliers, local_outliers, below_ground, border_filled, border_sky,
/// scan_gaps, scan_unlike).
/// A depth-completion label for a dataset, or a check of what the fog will see.
#[pyfunction]
#[pyo3(signature = (image, range_m, *, refine=None, sky_mask=None, ego_mask=None, airlight=None, monocular=false, stereo_focal_baseline=None, stereo_view=None, ground=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn prepare<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    range_m: &Bound<'py, PyAny>,
    refine: Option<&Bound<'py, PyAny>>,
    sky_mask: Option<&Bound<'py, PyAny>>,
    ego_mask: Option<&Bound<'py, PyAny>>,
    airlight: Option<Colour>,
    monocular: bool,
    stereo_focal_baseline: Option<f64>,
    stereo_view: Option<&str>,
    ground: Option<&Bound<'py, PyDict>>,
) -> PyResult<(Py<PyAny>, Bound<'py, PyDict>)> {
    let default_refine = PyBool::new(py, true);
    let mut opts = prepare_request(airlight, refine.unwrap_or(default_refine.as_any()))?;
    let origin = (monocular, (stereo_focal_baseline, stereo_view), ground);
    photo_fog::set_depth_origin(&mut opts, origin)?;
    let image = read_image(image)?.linear();
    let range = read_range(range_m)?;
    set_masks(&mut opts, &range, sky_mask, ego_mask)?;
    let prepared = py
        .detach(|| {
            let photo = Photo::from_range(image, range)?;
            let mut prepared = photo::preprocess(&photo, &opts)?;
            prepared.refine(&photo, &opts.refine, &mut CpuFilter)?;
            let physical = prepared.metres()?;
            Ok::<_, brume::Error>((prepared, physical))
        })
        .map_err(py_err)?;
    let (prepared, physical) = prepared;
    let info = PyDict::new(py);
    info.set_item("physical_range_m", grid_to_py(py, physical))?;
    info.set_item("airlight", prepared.airlight.map(f64::from).to_vec())?;
    info.set_item("airlight_source", prepared.airlight_from.name())?;
    info.set_item("refine", opts.refine.mode.name())?;
    info.set_item("upsampled", prepared.refined.is_some_and(|p| p.upsample))?;
    if let Some(p) = prepared.prepared {
        let s = &p.stats;
        let counts = [
            ("holes", s.holes),
            ("hole_pixels", s.hole_pixels),
            ("colour_regions", s.colour_regions),
            ("occluded", s.occluded),
            ("sky_pixels", s.sky_pixels),
            ("sky_components", s.sky_components),
            ("margin_pixels", s.margin_pixels),
            ("far_outliers", s.far_outliers),
            ("local_outliers", s.local_outliers),
            ("below_ground", s.below_ground),
            ("border_filled", s.border_filled),
            ("border_sky", s.border_sky),
            ("scan_gaps", s.scan_gaps),
            ("scan_unlike", s.scan_unlike),
        ];
        for (key, n) in counts {
            info.set_item(key, n)?;
        }
        info.set_item("sky", grid_to_py(py, p.sky))?;
        info.set_item("filled", grid_to_py(py, p.filled))?;
        info.set_item("beyond_reach", grid_to_py(py, p.beyond_reach))?;
    }
    Ok((grid_to_py(py, prepared.range), info))
}
