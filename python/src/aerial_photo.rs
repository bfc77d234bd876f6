//! `Renderer.aerial`: paper 002's aerial perspective on a photo with its range in metres,
//! through `brume::photo`'s aerial API, as `brume render --medium aerial` runs it
//! (pre-processing, refinement, the horizon's light from the sky, retargeting, the
//! diffusion blur, the capture).

use super::photo_fog::Labels;
use super::{on_default_renderer, py_err, value_error, GlThread, ImageIn};
use brume::atmosphere::Sensitivity;
use brume::camera::Camera;
use brume::io::colour_profile::ColourProfile;
use brume::medium::{Medium, Pixel};
use brume::photo::{
    self, AerialOptions, AerialPhoto, CaptureOptions, Photo, PhotoView, PrepareOptions, Retarget,
    DEFAULT_HORIZON_ZENITH_DEG,
};
use brume::raster::{RgbImage, RgbaImage, ScalarMap};
use brume::sky::horizon_sectors::MAX_SECTORS;
use brume::{Blur, FrameInputs};
use numpy::ndarray::Array3;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::path::PathBuf;

/// `Renderer.aerial`'s keywords.
pub(crate) struct AerialArgs {
    /// One output each (a list when `turbidity` was a sequence).
    pub turbidities: Vec<f64>,
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
    /// The photo's ICC profile (load_photo's `info["icc_profile"]`), whose primaries the
    /// attenuation is integrated for.
    pub icc_profile: Option<Vec<u8>>,
    pub blur: bool,
    pub lambda_px: f64,
    pub sigma0: f64,
}

/// Bytes per pixel that one output holds until the call returns, counted from its
/// buffers (not measured): its linear RGBA image (16), the encoded result (up to 12 as
/// float32) and, with `return_info`, the labels (clear, transmittance, airlight: 12 each)
/// and their numpy copies (36).
pub(crate) const OUTPUT_BYTES_PER_PIXEL: u64 = 100;

/// A value outside its range, named as the keyword.
fn out_of_range(name: &str, value: f64, expected: impl std::fmt::Display) -> PyErr {
    value_error(format!("invalid {name} = {value}: expected {expected}"))
}

impl AerialArgs {
    /// Checks what the library's [`AerialOptions::validate`] cannot see: the keywords'
    /// own forms (an integer count, a retarget name, the sun in degrees).
    fn check(&self) -> PyResult<()> {
        if self.horizon_sectors < 1 {
            return Err(out_of_range(
                "horizon_sectors",
                self.horizon_sectors as f64,
                format!("a number of azimuth sectors in [1, {MAX_SECTORS}]"),
            ));
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
    /// tall ([`PhotoView::camera`], whose fields are these keywords); one of fov_y_deg
    /// and focal_px.
    fn camera(&self, height: usize) -> PyResult<Camera> {
        if let (Some(fov), Some(f)) = (self.fov_y_deg, self.focal_px) {
            return Err(value_error(format!(
                "fov_y_deg = {fov} and focal_px = {f} both given: expected one of them"
            )));
        }
        let view = PhotoView {
            fov_y_deg: self.fov_y_deg,
            focal_px: self.focal_px,
            pitch_deg: self.pitch_deg,
            horizon_row: self.horizon_row,
        };
        view.camera(height).map_err(py_err)
    }

    /// The library's options for an image `height` rows tall, one per turbidity (the
    /// sensitivity read once).
    fn options(&self, height: usize) -> PyResult<Vec<AerialOptions>> {
        let sensitivity = match &self.sensitivity {
            Some(path) => Sensitivity::from_csv(path).map_err(py_err)?,
            None => Sensitivity::cie_srgb(),
        };
        let opts = AerialOptions {
            from_turbidity: self.from_turbidity,
            altitude_m: self.altitude_m,
            metres_per_unit: Some(self.metres_per_unit),
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
            ..AerialOptions::new(self.turbidities[0], self.camera(height)?)
        };
        let each = self.turbidities.iter().map(|&turbidity| AerialOptions {
            turbidity,
            ..opts.clone()
        });
        each.map(validated).collect()
    }
}

/// `opts` once [`AerialOptions::validate`] passed them, its error named as the keyword.
fn validated(opts: AerialOptions) -> PyResult<AerialOptions> {
    // The library names its fields as the keywords are named, but for λ.
    opts.validate().map_err(|e| match e {
        brume::Error::InvalidParameter {
            name,
            value,
            expected,
        } if name == "lambda" => {
            value_error(format!("invalid lambda_px = {value}: expected {expected}"))
        }
        e => py_err(e),
    })?;
    Ok(opts)
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

impl Labels for AerialInfo {
    fn into_py<'py>(self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
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
}

/// One photo with aerial perspective at each of `args`' turbidities (call with the GIL
/// released): pre-processing on the calling thread and the refinement on the GL thread,
/// once; then for each turbidity the aerial medium (and retargeting) on the calling
/// thread, the render on the GL thread, the capture here. Each output equals the call
/// with that turbidity alone.
pub(crate) fn aerial_frame(
    gl: &GlThread,
    image: ImageIn,
    range: ScalarMap,
    args: &AerialArgs,
    prepare: PrepareOptions,
    capture: &CaptureOptions,
    want_info: bool,
) -> PyResult<Vec<(RgbaImage, Option<AerialInfo>)>> {
    args.check()?;
    let each = args.options(image.height)?;
    let mut photo = Photo::from_range(image.linear(), range).map_err(py_err)?;
    photo.metadata.profile =
        (args.icc_profile.clone()).and_then(|icc| ColourProfile::from_icc(icc, "icc_profile"));
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
    let mut outputs = Vec::with_capacity(each.len());
    for opts in &each {
        let job = photo::aerial(&photo, &prepared, opts).map_err(py_err)?;
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
        outputs.push((rendered.image, info));
    }
    Ok(outputs)
}

/// The default of `horizon_zenith_deg` (degrees).
pub(crate) const HORIZON_ZENITH_DEG: f64 = DEFAULT_HORIZON_ZENITH_DEG;

/// aerial(image, range_m, *, turbidity, fov_y_deg=None, focal_px=None, pitch_deg=None,
/// horizon_row=None, altitude_m=0.0, metres_per_unit=1.0, from_turbidity=None, retarget=None,
/// airlight=None, horizon_zenith_deg=85.0, horizon_sectors=8, sun=None, sensitivity=None,
/// icc_profile=None, blur=True, lambda_px=8.0, sigma0=1.0, refine=True, sky_mask=None,
/// ego_mask=None, exposure_stops=0.0, shot_noise_gain=None, read_noise=None, jpeg_quality=None,
/// seed=0, return_info=False, monocular=False, stereo_focal_baseline=None, stereo_view=None,
/// ground=None) -> ndarray, or (ndarray, dict), or a list of those
///
/// Paper 002's aerial perspective from the turbidity T (1-20) on a photo with its range in metres
/// (`brume render --medium aerial`). turbidity may be a sequence: a list, one output each, from one
/// pre-processing and refinement of the frame. image and range_m as for brume.fog. One of fov_y_deg
/// (vertical field of view) or focal_px gives each pixel's zenith angle, with pitch_deg (default 0)
/// or horizon_row (the image row of the horizon, 0 at the top). altitude_m: above sea level.
/// from_turbidity: the photo's own turbidity, its haze removed first (retargeting, retarget
/// 'normalised' (eq. 26) or 'radiance'). airlight: the horizon's linear RGB or a grey (default:
/// from the sky pre-processing finds), taken at horizon_zenith_deg; horizon_sectors azimuth sectors
/// of it; sun (zenith_deg, azimuth_deg clockwise from the image centre's heading) shapes them
/// without a sky. sensitivity: a CSV lambda_nm,r,g,b (default CIE 1931 to linear sRGB, or to the
/// primaries of icc_profile: the photo's profile, bytes, as load_photo's info gives it). blur: the
/// diffusion blur (lambda_px, sigma0); refine, the masks, the capture keywords, monocular,
/// stereo_focal_baseline, stereo_view and ground as brume.fog. return_info=True also returns the
/// labels of I = J·t + A·(1 - t) (before the blur and the capture), per pixel and channel: clear
/// (J, float32 HxWx3 linear RGB: the photo the medium veiled, its haze removed with
/// from_turbidity), transmittance (t, HxWx3), airlight (A, HxWx3 linear RGB: the light the veil
/// tends to, which follows the view direction), turbidity and sigma_max_px.
#[pyfunction]
#[pyo3(
    signature = (*args, **kwargs),
    text_signature = "(image, range_m, *, turbidity, fov_y_deg=None, focal_px=None, pitch_deg=None, horizon_row=None, altitude_m=0.0, metres_per_unit=1.0, from_turbidity=None, retarget=None, airlight=None, horizon_zenith_deg=85.0, horizon_sectors=8, sun=None, sensitivity=None, icc_profile=None, blur=True, lambda_px=8.0, sigma0=1.0, refine=None, sky_mask=None, ego_mask=None, exposure_stops=0.0, shot_noise_gain=None, read_noise=None, jpeg_quality=None, seed=0, return_info=False, monocular=False, stereo_focal_baseline=None, stereo_view=None, ground=None)"
)]
pub(crate) fn aerial(
    py: Python<'_>,
    args: &Bound<'_, PyTuple>,
    kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    on_default_renderer(py, "aerial", args, kwargs)
}
