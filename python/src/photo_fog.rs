//! `brume.fog`: a photo with its range fogged through `brume::photo` (pre-processing on
//! the calling thread, refinement and fog on the GL thread, the capture after it), the
//! keywords checked into brume's options, and `return_info`'s labels.

use super::arrays::{grid_to_py, not_numbers, numbers, read_mask, Colour, ImageOut};
use super::gl_thread::GlThread;
use super::{py_err, value_error};
use brume::compat;
use brume::io::camera::{Intrinsics, Mount};
use brume::io::depth::StereoView;
use brume::io::image::srgb_to_linear;
use brume::medium::physical::{self, VISIBILITY_OPTICAL_DEPTH};
use brume::photo::{
    self, CaptureOptions, Conventions, Extinction, FogOptions, FoggedPhoto, Photo, PrepareOptions,
    PreparedPhoto,
};
use brume::prep::Ground;
use brume::raster::{RgbImage, RgbaImage, ScalarMap};
use brume::refine::RefineMode;
use brume::Headless;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// `brume.fog`'s keywords, checked, as brume's options: one fog per output, from one
/// pre-processing.
pub(crate) struct FogRequest {
    fogs: Vec<FogOptions>,
    pub(crate) prepare: PrepareOptions,
    capture: CaptureOptions,
    conventions: Conventions,
}

/// The keywords of the capture after the fog, as brume's [`CaptureOptions`], checked.
pub(crate) fn capture_request(
    exposure_stops: f64,
    shot_noise_gain: Option<f64>,
    read_noise: Option<f64>,
    jpeg_quality: Option<i64>,
    seed: i128,
) -> PyResult<CaptureOptions> {
    CaptureOptions::from_parts(
        exposure_stops,
        shot_noise_gain,
        read_noise,
        jpeg_quality,
        super::arrays::seed_of("seed", seed)?,
    )
    .map_err(py_err)
}

fn refine_mode(refine: &Bound<'_, PyAny>) -> PyResult<RefineMode> {
    if let Ok(b) = refine.extract::<bool>() {
        return Ok(if b {
            RefineMode::Repair
        } else {
            RefineMode::None
        });
    }
    if let Ok(s) = refine.extract::<String>() {
        return match s.trim().to_ascii_lowercase().as_str() {
            "none" => Ok(RefineMode::None),
            "guided" => Ok(RefineMode::Guided),
            "unreliable" => Ok(RefineMode::Unreliable),
            "repair" => Ok(RefineMode::Repair),
            _ => Err(value_error(format!(
                "invalid refine = {s:?}: expected True (repair), False (none) or one of 'none', 'guided', 'unreliable', 'repair'"
            ))),
        };
    }
    Err(value_error(format!(
        "invalid refine = {}: expected True (repair), False (none) or one of 'none', 'guided', 'unreliable', 'repair'",
        refine.repr().map(|r| r.to_string()).unwrap_or_default()
    )))
}

/// `airlight` (None, a grey or three linear RGB values) and `refine` as brume's
/// pre-processing options.
pub(crate) fn prepare_request(
    airlight: Option<Colour>,
    refine: &Bound<'_, PyAny>,
) -> PyResult<PrepareOptions> {
    let airlight = match airlight.map(|c| c.0) {
        None => None,
        Some(a) if a.len() == 3 => Some([a[0] as f32, a[1] as f32, a[2] as f32]),
        Some(a) => {
            return Err(value_error(format!(
                "invalid airlight = {a:?}: expected None (estimated from the sky), a number \
                 (a grey) or three linear RGB values"
            )))
        }
    };
    let mut prepare = PrepareOptions {
        airlight,
        ..PrepareOptions::default()
    };
    prepare.refine.mode = refine_mode(refine)?;
    Ok(prepare)
}

/// A disparity's f·B (px·m) and view, as the Python keywords give them.
pub(crate) type Stereo<'a> = (Option<f64>, Option<&'a str>);

/// Where `range_m` came from, as `brume render` knows it from the file: `monocular=True`, a
/// monocular model's relative depth, whose sky may lie in its far tail
/// (`brume::prep::PrepOptions::sky_in_far_tail`, as for `--depth-kind inverse` and
/// `affine`); `stereo_focal_baseline`, a stereo-matched disparity with f·B (px·m), whose
/// occlusions are filled from their background, on the side of nearer surfaces that
/// `stereo_view` says ('left', the default, or 'right'; `load_depth`'s info gives both);
/// `ground`, `load_depth`'s info['ground'] (the level road under a Cityscapes camera,
/// [`ground_from_py`]). Checked with pre-processing's options.
pub(crate) fn set_depth_origin(
    prepare: &mut PrepareOptions,
    (monocular, stereo, ground): (bool, Stereo<'_>, Option<&Bound<'_, PyDict>>),
) -> PyResult<()> {
    let ground = ground_from_py(ground)?;
    let (stereo_focal_baseline, view) = stereo;
    let view = view
        .map(str::parse::<StereoView>)
        .transpose()
        .map_err(py_err)?;
    if let Some(prep) = prepare.prep.as_mut() {
        if monocular {
            prep.sky_in_far_tail = Some(brume::prep::MONOCULAR_SKY_FACTOR);
        }
        prep.stereo_focal_baseline = stereo_focal_baseline;
        prep.stereo_view = view;
        prep.ground = ground;
    }
    Ok(())
}

/// The keys of `ground`, in the order of [`ground_values`].
const GROUND_KEYS: [&str; 7] = ["height_m", "pitch", "roll", "fx", "fy", "cx", "cy"];

/// `ground`'s numbers in the order of [`GROUND_KEYS`].
fn ground_values(g: &Ground) -> [f64; 7] {
    let (m, k) = (&g.mount, &g.intrinsics);
    [m.height_m, m.pitch, m.roll, k.fx, k.fy, k.cx, k.cy]
}

/// `ground` as `load_depth`'s info gives it ([`ground_to_py`]) as brume's [`Ground`]; a
/// missing key or a value that is not a number is an error naming it.
fn ground_from_py(ground: Option<&Bound<'_, PyDict>>) -> PyResult<Option<Ground>> {
    let Some(dict) = ground else {
        return Ok(None);
    };
    let mut v = [0.0; 7];
    for (value, key) in v.iter_mut().zip(GROUND_KEYS) {
        let item = dict.get_item(key)?.ok_or_else(|| {
            value_error(format!(
                "ground: missing '{key}': expected load_depth's info['ground'], a dict of {}",
                GROUND_KEYS.join(", ")
            ))
        })?;
        *value = (item.extract::<f64>())
            .map_err(|_| value_error(format!("ground['{key}'] = {item}: expected a number")))?;
    }
    let [height_m, pitch, roll, fx, fy, cx, cy] = v;
    Ok(Some(Ground {
        mount: Mount {
            height_m,
            pitch,
            roll,
        },
        intrinsics: Intrinsics { fx, fy, cx, cy },
    }))
}

/// `ground` as the dict `load_depth`'s info holds ([`GROUND_KEYS`]).
pub(crate) fn ground_to_py<'py>(py: Python<'py>, ground: &Ground) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    for (key, value) in GROUND_KEYS.into_iter().zip(ground_values(ground)) {
        dict.set_item(key, value)?;
    }
    Ok(dict)
}

/// `return_info`'s labels of one output, as the dict Python gets.
pub(crate) trait Labels {
    fn into_py<'py>(self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>>;
}

/// A call's outputs as Python gets them: each the image, or `(image, info)` with
/// `return_info`; a list when the density or turbidity was given as a sequence (`many`),
/// else the one output.
pub(crate) fn outputs_to_py<L: Labels>(
    py: Python<'_>,
    outputs: Vec<(ImageOut, Option<L>)>,
    many: bool,
) -> PyResult<Py<PyAny>> {
    let mut results = outputs.into_iter().map(|(image, info)| {
        let image = image.into_py(py);
        match info {
            Some(info) => Ok((image, info.into_py(py)?)
                .into_pyobject(py)?
                .into_any()
                .unbind()),
            None => Ok(image),
        }
    });
    if many {
        let list = results.collect::<PyResult<Vec<_>>>()?;
        return Ok(PyList::new(py, list)?.into_any().unbind());
    }
    results.next().expect("one value, one output")
}

/// The `sky_mask` and `ego_mask` keywords, read on `range`'s grid, into `prepare`.
pub(crate) fn set_masks(
    prepare: &mut PrepareOptions,
    range: &ScalarMap,
    sky_mask: Option<&Bound<'_, PyAny>>,
    ego_mask: Option<&Bound<'_, PyAny>>,
) -> PyResult<()> {
    let shape = (range.height(), range.width());
    if let Some(mask) = sky_mask {
        let all_set = "a mask with ground in it (is it inverted?)";
        prepare.sky_mask = Some(read_mask(mask, "sky_mask", shape, all_set)?);
    }
    if let Some(mask) = ego_mask {
        let all_set = "a mask with the scene in it (is it inverted?)";
        prepare.ego_mask = Some(read_mask(mask, "ego_mask", shape, all_set)?);
    }
    Ok(())
}

/// `beta` or `visibility` as Python gives it: one number, or a sequence of them (one
/// output each, from one pre-processing and refinement of the frame, as `brume batch
/// --beta 0.005,0.01,0.02` makes them).
pub(crate) struct Densities {
    values: Vec<f64>,
    many: bool,
}

impl<'a, 'py> FromPyObject<'a, 'py> for Densities {
    type Error = PyErr;

    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let what = "a number: expected a number, or a sequence of numbers for one output each";
        let (values, many) = numbers(obj).ok_or_else(|| not_numbers(obj, what))?;
        Ok(Densities { values, many })
    }
}

impl Densities {
    /// True when given as a sequence: the call returns a list.
    pub(crate) fn many(&self) -> bool {
        self.many
    }

    /// The values, refused by `name` when the sequence is empty.
    pub(crate) fn non_empty(&self, name: &str) -> PyResult<&[f64]> {
        if self.values.is_empty() {
            return Err(value_error(format!(
                "invalid {name} = []: expected a number, or a non-empty sequence of numbers"
            )));
        }
        Ok(&self.values)
    }

    /// The fog options of each value, `make` checking it and naming `name`.
    fn fogs(
        &self,
        name: &str,
        make: fn(f64) -> brume::Result<FogOptions>,
    ) -> PyResult<Vec<FogOptions>> {
        self.non_empty(name)?
            .iter()
            .map(|&v| make(v).map_err(py_err))
            .collect()
    }
}

/// How dense the fog of `brume.fog` is, as its keywords give it: exactly one of β,
/// the visibility, or paper 000's normalised κa and κs.
pub(crate) struct Density {
    pub(crate) beta: Option<Densities>,
    pub(crate) visibility: Option<Densities>,
    pub(crate) ka: Option<f64>,
    pub(crate) ks: Option<f64>,
}

/// Bytes per pixel that one output holds until the call returns, counted from its
/// buffers (not measured): its linear RGBA image (16), the range the medium read (4), the
/// encoded result (up to 12 as float32) and, with `return_info`, the labels and their
/// numpy copies (16).
const OUTPUT_BYTES_PER_PIXEL: u64 = 48;

impl Density {
    /// True when β or the visibility was given as a sequence: the call returns a list.
    pub(crate) fn many(&self) -> bool {
        [&self.beta, &self.visibility]
            .into_iter()
            .any(|d| d.as_ref().is_some_and(|d| d.many))
    }

    /// Refuses, before any work, more outputs of `pixels` each than the memory left can
    /// hold at once: a list's outputs are all held until the call returns.
    pub(crate) fn check_outputs_fit(&self, pixels: usize) -> PyResult<()> {
        let outputs = [&self.beta, &self.visibility]
            .into_iter()
            .flatten()
            .map(|d| d.values.len())
            .max()
            .unwrap_or(1);
        check_outputs_fit(
            outputs,
            pixels,
            OUTPUT_BYTES_PER_PIXEL,
            "give fewer betas or visibilities in one call: every output is held until it returns",
        )
    }

    /// The fog options of each density given (the other options brume's defaults).
    fn fog_options(&self) -> PyResult<Vec<FogOptions>> {
        let normalised = self.ka.is_some() || self.ks.is_some();
        match (&self.beta, &self.visibility, normalised) {
            (Some(b), None, false) => b.fogs("beta", FogOptions::beta),
            (None, Some(v), false) => v.fogs("visibility", FogOptions::visibility),
            (None, None, true) => Ok(vec![FogOptions {
                extinction: Extinction::Normalised {
                    ka: self.ka.unwrap_or(brume::medium::haze::DEFAULT_KA),
                    ks: self.ks.unwrap_or(brume::medium::haze::DEFAULT_KS),
                },
                ..FogOptions::default()
            }]),
            (None, None, false) => Err(value_error(
                "neither beta, visibility nor ka/ks given: expected exactly one of beta (extinction, 1/m, e.g. 0.02), visibility (metres, e.g. 150) or ka and/or ks (paper 000's absorption and scattering per unit of range normalised by its largest value, e.g. ks=0.75)",
            )),
            _ => Err(value_error(format!(
                "{} given together: expected exactly one of beta (1/m), visibility (m) or ka/ks (normalised range)",
                [
                    ("beta", self.beta.is_some()),
                    ("visibility", self.visibility.is_some()),
                    ("ka/ks", normalised),
                ]
                .iter()
                .filter(|(_, given)| *given)
                .map(|(name, _)| *name)
                .collect::<Vec<_>>()
                .join(" and ")
            ))),
        }
    }
}

/// Refuses, before any work, `outputs` outputs of `pixels` each, `bytes_per_pixel` each
/// held until the call returns, that the memory left cannot hold; `hint` says what to do.
pub(crate) fn check_outputs_fit(
    outputs: usize,
    pixels: usize,
    bytes_per_pixel: u64,
    hint: &str,
) -> PyResult<()> {
    brume::memory::check_available(
        &format!("{outputs} outputs of {pixels} px each"),
        (outputs as u64)
            .saturating_mul(pixels as u64)
            .saturating_mul(bytes_per_pixel),
        hint,
    )
    .map_err(py_err)
}

/// `compat`: None or 'brume' (brume's fog), or 'foggy-cityscapes' (Foggy Cityscapes'
/// blend), refused with what its blend cannot take, as `brume render --compat` refuses it:
/// κa and κs (it needs β), λ (it has no blur) and the capture.
fn conventions(
    compat: Option<&str>,
    density: &Density,
    lambda_px: Option<f64>,
    capture: &CaptureOptions,
) -> PyResult<Conventions> {
    let name = compat.map(|c| c.trim().to_ascii_lowercase().replace('_', "-"));
    match name.as_deref() {
        None | Some("brume") => return Ok(Conventions::Brume),
        Some("foggy-cityscapes") => {}
        Some(_) => {
            return Err(value_error(format!(
                "invalid compat = '{}': expected None or 'brume' (brume's fog in linear \
                 light, with its blur), or 'foggy-cityscapes' (Foggy Cityscapes' blend in sRGB \
                 code values, no blur)",
                compat.unwrap_or_default()
            )))
        }
    }
    let refused = if density.ka.is_some() || density.ks.is_some() {
        Some("ka/ks: expected beta or visibility with it (its fog is exp(-beta R) on range in metres)")
    } else if lambda_px.is_some() {
        Some("lambda_px: expected no lambda_px with it (its blend has no blur)")
    } else if !capture.is_off() {
        Some("the capture (exposure_stops, shot_noise_gain, read_noise, jpeg_quality): expected none with it (Foggy Cityscapes' images have none)")
    } else {
        None
    };
    match refused {
        Some(what) => Err(value_error(format!(
            "compat = 'foggy-cityscapes' and {what}"
        ))),
        None => Ok(Conventions::FoggyCityscapes),
    }
}

pub(crate) fn fog_request(
    density: Density,
    airlight: Option<Colour>,
    (blur, lambda_px): (bool, Option<f64>),
    refine: &Bound<'_, PyAny>,
    capture: CaptureOptions,
    compat: Option<&str>,
) -> PyResult<FogRequest> {
    let conventions = conventions(compat, &density, lambda_px, &capture)?;
    let mut fogs = density.fog_options()?;
    let lambda = match (blur, lambda_px) {
        (false, Some(l)) => {
            return Err(value_error(format!(
                "blur = False and lambda_px = {l} both given: expected lambda_px only with blur"
            )))
        }
        (false, None) => Some(0.0),
        (true, Some(l)) if !(l.is_finite() && l >= 0.0) => {
            return Err(value_error(format!(
                "invalid lambda_px = {l}: expected the blur's strength, a number >= 0 (brume's default 8; 0 for no blur)"
            )))
        }
        (true, l) => l,
    };
    if let Some(l) = lambda {
        fogs.iter_mut().for_each(|fog| fog.lambda = l);
    }
    let prepare = prepare_request(airlight, refine)?;
    Ok(FogRequest {
        fogs,
        prepare,
        capture,
        conventions,
    })
}

/// What the GL thread hands back for one frame: the prepared photo and each fog (its
/// image, and what the labels of `return_info` are made from).
struct GpuFog {
    prepared: PreparedPhoto,
    outputs: Vec<FoggedPhoto>,
}

/// The GPU's share of one frame, on the GL thread: the refinement of the pre-processed
/// range, once, and each fog (`brume::photo`'s refine and fog_each: one upload for all).
fn fog_on_gpu(
    headless: &mut Headless,
    photo: &Photo,
    mut prepared: PreparedPhoto,
    request: &FogRequest,
) -> brume::Result<GpuFog> {
    prepared.refine(photo, &request.prepare.refine, headless.renderer()?)?;
    let mut outputs = Vec::with_capacity(request.fogs.len());
    let renderer = headless.renderer()?;
    photo::fog_each(renderer, photo, &prepared, &request.fogs, |_, fogged| {
        outputs.push(fogged);
        Ok(())
    })?;
    Ok(GpuFog { prepared, outputs })
}

/// `return_info`'s labels of one frame, the ones a dehazing dataset keeps beside the
/// foggy image (the atmospheric scattering model I = J·t + A·(1 − t)).
pub(crate) struct FogInfo {
    /// t = exp(−β·R) at each pixel of the image, of the range the fog read.
    transmittance: ScalarMap,
    /// That range at the image's size (m, or the caller's unit with κa and κs):
    /// pre-processed, refined, unknown pixels the farthest, as `brume batch
    /// --transmittance` and the render take it.
    range_m: ScalarMap,
    airlight: [f32; 3],
    airlight_source: &'static str,
    beta: f64,
    visibility_m: f64,
    sigma_max: f64,
}

impl Labels for FogInfo {
    fn into_py<'py>(self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let info = PyDict::new(py);
        info.set_item("transmittance", grid_to_py(py, self.transmittance))?;
        info.set_item("range_m", grid_to_py(py, self.range_m))?;
        info.set_item("airlight", self.airlight.map(f64::from).to_vec())?;
        info.set_item("airlight_source", self.airlight_source)?;
        info.set_item("beta", self.beta)?;
        info.set_item("visibility_m", self.visibility_m)?;
        info.set_item("sigma_max_px", self.sigma_max)?;
        Ok(info)
    }
}

impl FogInfo {
    /// The labels of a frame fogged with `opts`. With normalised κa and κs the range
    /// stays in the caller's units, and β is (κa + κs) per largest range.
    fn of(prepared: &PreparedPhoto, fogged: &FoggedPhoto, opts: &FogOptions) -> FogInfo {
        let transmittance = fogged.transmittance();
        let divisor = fogged.range_divisor;
        let (range, beta) = match opts.extinction {
            Extinction::Physical(fog) => (fogged.range.clone(), fog.beta),
            Extinction::Normalised { ka, ks } => (
                fogged.range.map(|&r| (f64::from(r) * divisor) as f32),
                (ka + ks) / divisor,
            ),
        };
        FogInfo {
            transmittance,
            range_m: range,
            airlight: prepared.airlight,
            airlight_source: prepared.airlight_from.name(),
            beta,
            visibility_m: VISIBILITY_OPTICAL_DEPTH / beta,
            sigma_max: fogged.rendered.schedule.sigma_max,
        }
    }
}

/// One frame fogged, once per fog of `request`: pre-processing on the calling thread (the GIL released, so that
/// another Python thread's frame can use the GL thread meanwhile, as `brume batch`
/// overlaps its loader with the GPU), the refinement and the fog on the GL thread, the
/// capture (and, with `want_info`, the labels) on the calling thread again.
pub(crate) fn fog_frame(
    gl: &GlThread,
    image: RgbImage,
    range: ScalarMap,
    request: FogRequest,
    want_info: bool,
) -> PyResult<Vec<(RgbaImage, Option<FogInfo>)>> {
    let photo = Photo::from_range(image, range).map_err(py_err)?;
    let prepared = photo::preprocess(&photo, &request.prepare).map_err(py_err)?;
    if request.conventions == Conventions::FoggyCityscapes {
        return foggy_cityscapes_frame(gl, photo, prepared, &request, want_info);
    }
    let (capture, fogs) = (request.capture, request.fogs.clone());
    let GpuFog { prepared, outputs } = gl
        .run(move |h| fog_on_gpu(h, &photo, prepared, &request))?
        .map_err(py_err)?;
    outputs
        .into_iter()
        .zip(&fogs)
        .map(|(mut fogged, fog)| {
            let info = want_info.then(|| FogInfo::of(&prepared, &fogged, fog));
            let image = &mut fogged.rendered.image;
            photo::capture(image, &capture).map_err(py_err)?;
            Ok((fogged.rendered.image, info))
        })
        .collect()
}

/// One frame under Foggy Cityscapes' conventions, as `brume render --compat
/// foggy-cityscapes` makes it: the range refined on the GL thread, then each β's blend in
/// sRGB code values with the dark-channel airlight (or the one given) on the calling
/// thread, no blur ([`brume::compat::foggy_cityscapes`]). Its labels: the τ the blend used,
/// the range, and the airlight the blend used, decoded to linear RGB.
fn foggy_cityscapes_frame(
    gl: &GlThread,
    photo: Photo,
    mut prepared: PreparedPhoto,
    request: &FogRequest,
    want_info: bool,
) -> PyResult<Vec<(RgbaImage, Option<FogInfo>)>> {
    let refine = request.prepare.refine;
    let (photo, prepared) = gl
        .run(move |h| -> brume::Result<_> {
            prepared.refine(&photo, &refine, h.renderer()?)?;
            Ok((photo, prepared))
        })?
        .map_err(py_err)?;
    let (metres, _) = physical::metric_range(&prepared.range).map_err(py_err)?;
    let (airlight, source) =
        compat::foggy_cityscapes_airlight(&photo.image, request.prepare.airlight);
    let beta_of = |fog: &FogOptions| match fog.extinction {
        Extinction::Physical(f) => f.beta,
        Extinction::Normalised { .. } => unreachable!("refused: foggy-cityscapes needs beta"),
    };
    Ok(request
        .fogs
        .iter()
        .map(|fog| {
            let beta = beta_of(fog);
            let tau = compat::foggy_cityscapes_transmittance(&metres, beta);
            let image = compat::foggy_cityscapes_at(&photo.image, &tau, airlight);
            let info = want_info.then(|| FogInfo {
                transmittance: tau,
                range_m: metres.clone(),
                airlight: airlight.map(srgb_to_linear),
                airlight_source: source,
                beta,
                visibility_m: VISIBILITY_OPTICAL_DEPTH / beta,
                sigma_max: 0.0,
            });
            (image, info)
        })
        .collect())
}
