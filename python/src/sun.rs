//! `brume.sun_position`: the sun's place in the sky from where and when (NREL's SPA, as
//! `brume sun` computes it), for `brume.aerial`'s and `brume.render_sky`'s `sun`.

use super::py_err;
use brume::sky::sun_position::Observer;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

/// sun_position(latitude_deg, longitude_deg, time, *, altitude_m=0.0, pressure_hpa=1013.25,
/// temperature_c=12.0, delta_t_s=None) -> dict
///
/// The sun seen from latitude_deg (north positive) and longitude_deg (east positive) at
/// time, an RFC 3339 string with its UTC offset ('2024-06-21T10:00:00+02:00') or a
/// timezone-aware datetime, as `brume sun` gives it (NREL's solar position algorithm, Reda
/// and Andreas 2004): apparent_zenith_deg (with the refraction of pressure_hpa and
/// temperature_c: what a camera sees), zenith_deg (geometric), azimuth_deg (clockwise from
/// north), right_ascension_deg, declination_deg, julian_day, delta_t_s (given, or estimated
/// for the year). altitude_m: above sea level. For brume.aerial's sun, (apparent_zenith_deg,
/// azimuth_deg − the image centre's heading); for brume.render_sky's, the fisheye's
/// azimuth_offset_deg is the heading at its top.
// The defaults are the library's DEFAULT_PRESSURE_HPA and DEFAULT_TEMPERATURE_C written
// out, so that Python's signature shows them; the test against `brume sun` holds them.
#[pyfunction]
#[pyo3(signature = (latitude_deg, longitude_deg, time, *, altitude_m=0.0, pressure_hpa=1013.25, temperature_c=12.0, delta_t_s=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn sun_position<'py>(
    py: Python<'py>,
    latitude_deg: f64,
    longitude_deg: f64,
    time: &Bound<'py, PyAny>,
    altitude_m: f64,
    pressure_hpa: f64,
    temperature_c: f64,
    delta_t_s: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let time = rfc3339_of(time)?;
    let observer = Observer {
        latitude_deg,
        longitude_deg,
        altitude_m,
        pressure_hpa,
        temperature_c,
    };
    let sun = observer.sun_at(&time, delta_t_s).map_err(py_err)?;
    let out = PyDict::new(py);
    out.set_item("apparent_zenith_deg", sun.apparent_zenith_deg)?;
    out.set_item("zenith_deg", sun.zenith_deg)?;
    out.set_item("azimuth_deg", sun.azimuth_deg)?;
    out.set_item("right_ascension_deg", sun.right_ascension_deg)?;
    out.set_item("declination_deg", sun.declination_deg)?;
    out.set_item("julian_day", sun.julian_day)?;
    out.set_item("delta_t_s", sun.delta_t_s)?;
    Ok(out)
}

/// `time` as RFC 3339: a string as given, a datetime with its UTC offset by its
/// `isoformat()`; a naive datetime names no instant and is refused.
fn rfc3339_of(time: &Bound<'_, PyAny>) -> PyResult<String> {
    if time.is_instance_of::<PyString>() {
        return time.extract();
    }
    let offset = time.call_method0("utcoffset").map_err(|_| {
        PyValueError::new_err(
            "time: expected an RFC 3339 string with its UTC offset or a datetime.datetime",
        )
    })?;
    if offset.is_none() {
        return Err(PyValueError::new_err(
            "time: a naive datetime names no instant: give it a tzinfo (e.g. \
             datetime.timezone.utc) or pass an RFC 3339 string with its UTC offset",
        ));
    }
    time.call_method0("isoformat")?.extract()
}
