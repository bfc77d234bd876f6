//! `Renderer.aerial`: paper 002's aerial perspective on a photo with its range in metres,
//! through `brume::photo`'s aerial API, as `brume render --medium aerial` runs it
//! (pre-processing, refinement, the horizon's light from the sky, retargeting, the
//! diffusion blur, the capture).

use super::{on_default_renderer, py_err, value_error, GlThread, ImageIn};
use brume::atmosphere::Sensitivity;
use brume::camera::Camera;
use brume::medium::{Medium, Pixel};
use brume::photo::{
    self, pitch_for_horizon_row, AerialOptions, AerialPhoto, CaptureOptions, Photo, PrepareOptions,
    Retarget, DEFAULT_HORIZON_ZENITH_DEG, MAX_PITCH_DEG,
};
use brume::raster::{RgbImage, RgbaImage, ScalarMap};
use brume::sky::horizon_sectors::MAX_SECTORS;
use brume::{Blur, FrameInputs};
use numpy::ndarray::Array3;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::path::PathBuf;

/// The turbidities the model is fitted for (Preetham et al.'s), as `brume render` checks.
const TURBIDITY_RANGE: (f64, f64) = (1.0, 20.0);
/// The altitudes `brume render --altitude` takes, metres.
const ALTITUDE_RANGE_M: (f64, f64) = (-500.0, 20_000.0);

/// `Renderer.aerial`'s keywords.
pub(crate) struct AerialArgs {
    pub turbidity: f64,
    pub fov_y_deg: Option<f64>,
    pub focal_px: Option<f64>,
    pub pitch_deg: Option<f64>,
    pub horizon_row: Option<f64>,
    pub altitude_m: f64,
    pub metres_per_unit: f64,
    pub from_turbidity: Option<f64>,
    pub retarget: Option<String>,
    pub airlight: Option<[f32; 3]>,
    pub horizon_zenith_deg: f64,
    pub horizon_sectors: i64,
    pub sun: Option<(f64, f64)>,
    pub sensitivity: Option<PathBuf>,
    pub blur: bool,
    pub lambda_px: f64,
    pub sigma0: f64,
}

/// A value outside its range, named as the keyword.
fn out_of_range(name: &str, value: f64, expected: impl std::fmt::Display) -> PyErr {
    value_error(format!("invalid {name} = {value}: expected {expected}"))
}

impl AerialArgs {
    /// Checks the values as `brume render` checks its flags, naming the keywords.
    fn check(&self) -> PyResult<()> {
        let (t_lo, t_hi) = TURBIDITY_RANGE;
        for (name, t) in [
            ("turbidity", Some(self.turbidity)),
            ("from_turbidity", self.from_turbidity),
        ] {
            if let Some(t) = t.filter(|t| !(t_lo..=t_hi).contains(t)) {
                return Err(out_of_range(
                    name,
                    t,
                    format!("a turbidity in [{t_lo}, {t_hi}]"),
                ));
            }
        }
        if !(1..=MAX_SECTORS as i64).contains(&self.horizon_sectors) {
            return Err(out_of_range(
                "horizon_sectors",
                self.horizon_sectors as f64,
                format!("a number of azimuth sectors in [1, {MAX_SECTORS}]"),
            ));
        }
        if !(0.0..=90.0).contains(&self.horizon_zenith_deg) {
            return Err(out_of_range(
                "horizon_zenith_deg",
                self.horizon_zenith_deg,
                "a zenith angle in [0, 90] degrees (90 is the horizon)",
            ));
        }
        let (a_lo, a_hi) = ALTITUDE_RANGE_M;
        if !(a_lo..=a_hi).contains(&self.altitude_m) {
            return Err(out_of_range(
                "altitude_m",
                self.altitude_m,
                format!("an altitude above sea level in [{a_lo}, {a_hi}] m"),
            ));
        }
        if !(self.metres_per_unit.is_finite() && self.metres_per_unit > 0.0) {
            return Err(out_of_range(
                "metres_per_unit",
                self.metres_per_unit,
                "metres per unit of range_m, > 0 (1 for metres)",
            ));
        }
        if !(self.lambda_px.is_finite() && self.lambda_px >= 0.0) {
            return Err(out_of_range(
                "lambda_px",
                self.lambda_px,
                "a blur factor >= 0 px",
            ));
        }
        if !(self.sigma0.is_finite() && self.sigma0 > 0.0) {
            return Err(out_of_range("sigma0", self.sigma0, "an inner scale > 0 px"));
        }
        if let (Some(r), None) = (&self.retarget, self.from_turbidity) {
            return Err(value_error(format!(
                "invalid retarget = {r:?}: expected from_turbidity with it (only a photo taken \
                 at a known turbidity is retargeted)"
            )));
        }
        if let Some((z, a)) = self.sun {
            if !(z.is_finite() && (0.0..=180.0).contains(&z) && a.is_finite()) {
                return Err(value_error(format!(
                    "invalid sun = ({z}, {a}): expected (zenith_deg in [0, 180], azimuth_deg \
                     clockwise from the image centre's heading, finite)"
                )));
            }
        }
        Ok(())
    }

    fn retarget(&self) -> PyResult<Retarget> {
        match self.retarget.as_deref().map(str::trim) {
            None | Some("normalised") | Some("normalized") => Ok(Retarget::Normalised),
            Some("radiance") => Ok(Retarget::Radiance),
            Some(other) => Err(value_error(format!(
                "invalid retarget = {other:?}: expected 'normalised' (eq. 26, the default) or \
                 'radiance'"
            ))),
        }
    }

    /// The camera whose rays give each pixel's zenith angle, for an image `height` rows
    /// tall, as `brume render`'s `aerial_camera` builds it.
    fn camera(&self, height: usize) -> PyResult<Camera> {
        let fov_y_deg =
            match (self.fov_y_deg, self.focal_px) {
                (Some(fov), None) => fov,
                (None, Some(f)) if f.is_finite() && f > 0.0 => {
                    (2.0 * (height as f64 / (2.0 * f)).atan()).to_degrees()
                }
                (None, Some(f)) => {
                    return Err(out_of_range("focal_px", f, "a focal length in px, > 0"));
                }
                (Some(fov), Some(f)) => {
                    return Err(value_error(format!(
                        "fov_y_deg = {fov} and focal_px = {f} both given: expected one of them"
                    )))
                }
                (None, None) => return Err(value_error(
                    "neither fov_y_deg nor focal_px given: expected the camera's vertical field \
                     of view in degrees or its focal length in px (each pixel's zenith angle \
                     depends on it)",
                )),
            };
        let pitch_deg = match (self.pitch_deg, self.horizon_row) {
            (Some(_), Some(_)) => {
                return Err(value_error(
                    "pitch_deg and horizon_row both given: expected one of them",
                ))
            }
            (None, Some(row)) => {
                let pitch = pitch_for_horizon_row(row, height, fov_y_deg);
                if !row.is_finite() || pitch.is_nan() || pitch.abs() > MAX_PITCH_DEG {
                    return Err(out_of_range(
                        "horizon_row",
                        row,
                        format!(
                            "a row (0 at the top) that puts the camera's pitch within \
                             ±{MAX_PITCH_DEG}° with this {height}-row image"
                        ),
                    ));
                }
                pitch
            }
            (pitch, None) => pitch.unwrap_or(0.0),
        };
        if pitch_deg.is_nan() || pitch_deg.abs() > MAX_PITCH_DEG {
            return Err(out_of_range(
                "pitch_deg",
                pitch_deg,
                format!("a pitch in [-{MAX_PITCH_DEG}, {MAX_PITCH_DEG}] degrees"),
            ));
        }
        let camera = Camera {
            pitch_deg,
            fov_y_deg,
            ..Camera::default()
        };
        camera
            .validate()
            .map_err(|e| value_error(format!("fov_y_deg/focal_px give an invalid camera: {e}")))?;
        Ok(camera)
    }

    /// The library's options for an image `height` rows tall.
    fn options(&self, height: usize) -> PyResult<AerialOptions> {
        let sensitivity = match &self.sensitivity {
            Some(path) => Sensitivity::from_csv(path).map_err(py_err)?,
            None => Sensitivity::cie_srgb(),
        };
        Ok(AerialOptions {
            from_turbidity: self.from_turbidity,
            altitude_m: self.altitude_m,
            metres_per_unit: self.metres_per_unit,
            sensitivity,
            lambda: if self.blur { self.lambda_px } else { 0.0 },
            horizon_zenith_deg: self.horizon_zenith_deg,
            horizon_light: self.airlight,
            // `brume render`'s blur: coarse to fine from 2 px.
            blur: Blur {
                sigma0: self.sigma0,
                ..Blur::photo()
            },
            horizon_sectors: self.horizon_sectors as usize,
            retarget: self.retarget()?,
            sun: self.sun.map(|(z, a)| [z.to_radians(), a.to_radians()]),
            ..AerialOptions::new(self.turbidity, self.camera(height)?)
        })
    }
}

/// `return_info`'s labels of an aerial frame, per pixel and channel: I = J·t + A·(1 − t)
/// before the blur and the capture, A the light the veil tends to at each pixel (paper
/// 002's medium has no single airlight: it follows the view direction).
pub(crate) struct AerialInfo {
    /// J: the photo the medium veils (linear RGB; with `from_turbidity` its haze removed).
    clear: RgbImage,
    /// t per channel (HxWx3).
    transmittance: Vec<f32>,
    /// A per pixel and channel (HxWx3, linear RGB): the medium's L∞.
    airlight: Vec<f32>,
    turbidity: f64,
    sigma_max: f64,
}

impl AerialInfo {
    /// The medium's τ and L∞ (A) at every pixel of `job` (its CPU side, which the GPU's
    /// `medium_sample` matches), top row first.
    fn of(job: &AerialPhoto) -> AerialInfo {
        let (w, h) = (job.range.width(), job.range.height());
        let frame = FrameInputs::default();
        let mut transmittance = Vec::with_capacity(w * h * 3);
        let mut airlight = Vec::with_capacity(w * h * 3);
        for row in 0..h {
            for x in 0..w {
                let pixel = Pixel {
                    x,
                    // The medium sees GL's rows, the bottom one first.
                    y: h - 1 - row,
                    width: w,
                    height: h,
                    depth: f64::from(*job.range.get(x, row)),
                    sigma0: job.blur.sigma0,
                };
                let s = job.medium.sample(pixel, &frame);
                transmittance.extend(s.transmission.map(|v| v as f32));
                airlight.extend(s.inscatter.map(|v| v as f32));
            }
        }
        AerialInfo {
            clear: job.image.clone(),
            transmittance,
            airlight,
            turbidity: job.medium.table.turbidity(),
            sigma_max: job.medium.sigma_max(job.blur.sigma0),
        }
    }

    pub(crate) fn into_py<'py>(self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (w, h) = (self.clear.width(), self.clear.height());
        let rgb = |v: Vec<f32>| {
            Array3::from_shape_vec((h, w, 3), v)
                .expect("shape")
                .into_pyarray(py)
        };
        let clear = self.clear.into_vec().into_flattened();
        let info = PyDict::new(py);
        info.set_item("clear", rgb(clear))?;
        info.set_item("transmittance", rgb(self.transmittance))?;
        info.set_item("airlight", rgb(self.airlight))?;
        info.set_item("turbidity", self.turbidity)?;
        info.set_item("sigma_max_px", self.sigma_max)?;
        Ok(info)
    }
}

/// One photo with aerial perspective (call with the GIL released): pre-processing on the
/// calling thread, the refinement on the GL thread, the aerial medium (and retargeting) on
/// the calling thread, the render on the GL thread, the capture here.
pub(crate) fn aerial_frame(
    gl: &GlThread,
    image: ImageIn,
    range: ScalarMap,
    args: &AerialArgs,
    prepare: PrepareOptions,
    capture: &CaptureOptions,
    want_info: bool,
) -> PyResult<(RgbaImage, Option<AerialInfo>)> {
    args.check()?;
    let opts = args.options(image.height)?;
    let photo = Photo::from_range(image.linear(), range).map_err(py_err)?;
    let prepared = photo::preprocess(&photo, &prepare).map_err(py_err)?;
    let refine = prepare.refine;
    let (photo, prepared) = gl
        .run(move |h| {
            let mut prepared = prepared;
            let refined = h
                .renderer()
                .and_then(|r| prepared.refine(&photo, &refine, r));
            refined.map(|_| (photo, prepared))
        })?
        .map_err(py_err)?;
    let job = photo::aerial(&photo, &prepared, &opts).map_err(py_err)?;
    let info = want_info.then(|| AerialInfo::of(&job));
    let blur = job.fog_blur();
    let mut rendered = gl
        .run(move |h| {
            h.render_fog(
                &job.image,
                &job.range,
                &job.medium,
                &FrameInputs::default(),
                &blur,
            )
        })?
        .map_err(py_err)?;
    photo::capture(&mut rendered.image, capture).map_err(py_err)?;
    Ok((rendered.image, info))
}

/// The default of `horizon_zenith_deg` (degrees).
pub(crate) const HORIZON_ZENITH_DEG: f64 = DEFAULT_HORIZON_ZENITH_DEG;

/// aerial(image, range_m, *, turbidity, fov_y_deg=None, focal_px=None, pitch_deg=None,
/// horizon_row=None, altitude_m=0.0, metres_per_unit=1.0, from_turbidity=None,
/// retarget=None, airlight=None, horizon_zenith_deg=85.0, horizon_sectors=8, sun=None,
/// sensitivity=None, blur=True, lambda_px=8.0, sigma0=1.0, refine=True, sky_mask=None,
/// ego_mask=None, exposure_stops=0.0, shot_noise_gain=None, read_noise=None,
/// jpeg_quality=None, seed=0, return_info=False) -> ndarray, or (ndarray, dict)
///
/// Paper 002's aerial perspective from the turbidity T (1-20) on a photo with its range
/// in metres (`brume render --medium aerial`). image and range_m as for brume.fog. One of
/// fov_y_deg (vertical field of view) or focal_px gives each pixel's zenith angle, with
/// pitch_deg (default 0) or horizon_row (the image row of the horizon, 0 at the top).
/// altitude_m: above sea level. from_turbidity: the photo's own turbidity, its haze
/// removed first (retargeting, retarget 'normalised' (eq. 26) or 'radiance'). airlight:
/// the horizon's linear RGB (default: from the sky pre-processing finds), taken at
/// horizon_zenith_deg; horizon_sectors azimuth sectors of it; sun (zenith_deg,
/// azimuth_deg clockwise from the image centre's heading) shapes them without a sky.
/// sensitivity: a CSV lambda_nm,r,g,b (default CIE 1931 to linear sRGB). blur: the
/// diffusion blur (lambda_px, sigma0); refine, the masks and the capture keywords as
/// brume.fog. return_info=True also returns the labels of I = J·t + A·(1 - t) (before
/// the blur and the capture), per pixel and channel: clear (J, float32 HxWx3 linear RGB:
/// the photo the medium veiled, its haze removed with from_turbidity), transmittance (t,
/// HxWx3), airlight (A, HxWx3 linear RGB: the light the veil tends to, which follows the
/// view direction), turbidity and sigma_max_px.
#[pyfunction]
#[pyo3(
    signature = (*args, **kwargs),
    text_signature = "(image, range_m, *, turbidity, fov_y_deg=None, focal_px=None, pitch_deg=None, horizon_row=None, altitude_m=0.0, metres_per_unit=1.0, from_turbidity=None, retarget=None, airlight=None, horizon_zenith_deg=85.0, horizon_sectors=8, sun=None, sensitivity=None, blur=True, lambda_px=8.0, sigma0=1.0, refine=None, sky_mask=None, ego_mask=None, exposure_stops=0.0, shot_noise_gain=None, read_noise=None, jpeg_quality=None, seed=0, return_info=False)"
)]
pub(crate) fn aerial(
    py: Python<'_>,
    args: &Bound<'_, PyTuple>,
    kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    on_default_renderer(py, "aerial", args, kwargs)
}
