//! `brume._brume`: the native part of the Python package `brume` (see `brume/__init__.py`
//! and the README's "Python" section). Everything here goes through brume's public library
//! API: `brume::photo` for the fog of a photo with range in metres, `brume::io::depth` for
//! depth files, `brume::Headless` for the EGL context; `engine` the engine fogs on a
//! frame and its depth buffer (`brume::medium`, `brume::camera`), `aerial_photo` paper
//! 002's aerial perspective (`brume::photo::aerial`), `photo_fog` `brume.fog`'s request and
//! labels, `prepare` `brume.prepare`, `depth` `brume.load_depth` and
//! `brume.left_right_mismatches`, `photo_io` photos read and written, `sky_photo`
//! `brume.turbidity_from_sky` and `brume.render_sky`, `sun` `brume.sun_position`, `metrics`
//! `brume.compare`, `arrays` numpy in and out, `gl_thread` the EGL context's own thread.
//!
//! **Threads.** A [`Renderer`] owns one GL thread (`gl_thread`), which opens brume's
//! headless EGL context and keeps it for the renderer's life; Python calls wait for it with
//! the GIL released. The module's functions (`brume.fog`, …) call the methods of a default
//! renderer opened on first use, with the methods' signatures.

// Why mimalloc: python/Cargo.toml, beside the dependency.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Hands back to the system the pages mimalloc keeps after a free (it purges them only some
/// time later), so that brume's memory checks do not count them as used: a renderer kept for
/// a dataset's frames was refused its third 2048x1024 frame under a 450 MB limit, with the
/// pages of the first two still held.
fn release_mimalloc_pages() {
    // SAFETY: mi_collect only frees mimalloc's own unused pages and segments; it is safe to
    // call from any thread at any time.
    unsafe { libmimalloc_sys::mi_collect(true) }
}

mod aerial_photo;
mod arrays;
mod depth;
mod engine;
mod gl_thread;
mod metrics;
mod photo_fog;
mod photo_io;
mod prepare;
mod sky_photo;
mod sun;

use arrays::{read_image, read_range, Colour, FsPath, ImageIn, ImageOut};
use brume::photo::BetaDistribution;
use gl_thread::GlThread;
use photo_fog::{
    capture_request, check_outputs_fit, fog_frame, fog_request, outputs_to_py, prepare_request,
    set_masks, Densities, Density,
};
use pyo3::exceptions::{PyMemoryError, PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::sync::OnceLock;

/// brume's errors as Python's: bad values and files as `ValueError`, files that cannot be
/// read as `OSError`, memory as `MemoryError`, the GL and EGL as `RuntimeError`; brume's
/// message kept whole (it names the value and what was expected), with the options it
/// names as this package's keywords.
fn py_err(e: brume::Error) -> PyErr {
    use brume::Error as E;
    let e = e.rename_options(keyword_of);
    let message = e.to_string();
    match e {
        E::InvalidParameter { .. }
        | E::SizeMismatch { .. }
        | E::NoValidDepth { .. }
        | E::Format { .. }
        | E::Prep(_)
        | E::TooLarge { .. } => PyValueError::new_err(message),
        E::Io { .. } => PyOSError::new_err(message),
        E::OutOfMemory { .. } => PyMemoryError::new_err(message),
        _ => PyRuntimeError::new_err(message),
    }
}

/// The library's fields whose keyword here has another name (the depth loaders' options
/// as `load_depth` takes them, the focal length, field of view and λ with their units,
/// the file save_photo writes).
const KEYWORDS: [(&str, &str); 10] = [
    ("depth_format", "format"),
    ("depth_kind", "kind"),
    ("depth_scale", "scale"),
    ("focal", "focal_px"),
    ("baseline", "baseline_mm"),
    ("disparity_offset", "disparity_offset_px"),
    ("fov", "fov_y_deg"),
    ("lambda", "lambda_px"),
    ("depth_layout", "layout"),
    // The file save_photo writes, which the library's writers call `out`.
    ("out", "path"),
];

/// The keyword that sets the library's field `field`: its name, or its entry in
/// [`KEYWORDS`].
fn keyword_of(field: &str) -> Option<String> {
    let keyword = KEYWORDS.iter().find(|(f, _)| *f == field);
    Some(keyword.map_or(field, |(_, k)| k).to_owned())
}

fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}

/// Renderer(): one EGL context (brume's headless one) kept for many frames.
///
/// Its methods release the GIL while brume works. A frame's pre-processing and capture
/// run on the calling thread and only its GPU work on the renderer's own GL thread, so
/// two threads feeding one renderer overlap one frame's CPU work with another's GPU work
/// (as `brume batch` does).
#[pyclass(module = "brume", frozen)]
struct Renderer {
    gl: GlThread,
}

impl Renderer {
    /// Runs `check` (of the memory a call's outputs need); where it refuses, frees the
    /// textures the renderer keeps from the last frame (in system memory on a software
    /// renderer, which the check counts as used although the next frame would reuse them)
    /// and runs it again.
    fn check_or_free_kept(&self, py: Python<'_>, check: impl Fn() -> PyResult<()>) -> PyResult<()> {
        if check().is_ok() {
            return Ok(());
        }
        py.detach(|| {
            self.gl
                .run(|h| h.renderer().map(|r| r.free_kept_textures()))
        })?
        .map_err(py_err)?;
        check()
    }
}

#[pymethods]
impl Renderer {
    #[new]
    fn new(py: Python<'_>) -> PyResult<Self> {
        let gl = py.detach(GlThread::start)?;
        Ok(Renderer { gl })
    }

    /// fog(image, range_m, *, beta=None, visibility=None, ka=None, ks=None, airlight=None,
    /// blur=True, lambda_px=None, refine=True, sky_mask=None, ego_mask=None, exposure_stops=0.0,
    /// shot_noise_gain=None, read_noise=None, jpeg_quality=None, seed=0, compat=None,
    /// return_info=False, monocular=False, stereo_focal_baseline=None, stereo_view=None,
    /// ground=None) -> ndarray, or (ndarray, dict) with return_info, or a list of those for a
    /// sequence of betas or visibilities: as brume.fog, on this renderer's context.
    #[pyo3(signature = (image, range_m, *, beta=None, visibility=None, ka=None, ks=None, airlight=None, blur=true, lambda_px=None, refine=None, sky_mask=None, ego_mask=None, exposure_stops=0.0, shot_noise_gain=None, read_noise=None, jpeg_quality=None, seed=0, compat=None, return_info=false, monocular=false, stereo_focal_baseline=None, stereo_view=None, ground=None))]
    #[allow(clippy::too_many_arguments)]
    fn fog(
        &self,
        py: Python<'_>,
        image: &Bound<'_, PyAny>,
        range_m: &Bound<'_, PyAny>,
        beta: Option<Densities>,
        visibility: Option<Densities>,
        ka: Option<f64>,
        ks: Option<f64>,
        airlight: Option<Colour>,
        blur: bool,
        lambda_px: Option<f64>,
        refine: Option<&Bound<'_, PyAny>>,
        sky_mask: Option<&Bound<'_, PyAny>>,
        ego_mask: Option<&Bound<'_, PyAny>>,
        exposure_stops: f64,
        shot_noise_gain: Option<f64>,
        read_noise: Option<f64>,
        jpeg_quality: Option<i64>,
        seed: i128,
        compat: Option<&str>,
        return_info: bool,
        monocular: bool,
        stereo_focal_baseline: Option<f64>,
        stereo_view: Option<&str>,
        ground: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Py<PyAny>> {
        let default_refine = pyo3::types::PyBool::new(py, true);
        let refine = refine.unwrap_or(default_refine.as_any());
        let capture = capture_request(
            exposure_stops,
            shot_noise_gain,
            read_noise,
            jpeg_quality,
            seed,
        )?;
        let density = Density {
            beta,
            visibility,
            ka,
            ks,
        };
        let many = density.many();
        let image = read_image(image)?;
        let area = image.width * image.height;
        self.check_or_free_kept(py, || density.check_outputs_fit(area))?;
        let blur = (blur, lambda_px);
        let mut request = fog_request(density, airlight, blur, refine, capture, compat)?;
        let origin = (monocular, (stereo_focal_baseline, stereo_view), ground);
        photo_fog::set_depth_origin(&mut request.prepare, origin)?;
        let range = read_range(range_m)?;
        set_masks(&mut request.prepare, &range, sky_mask, ego_mask)?;
        let pixels = image.pixels;
        let outputs = py.detach(|| {
            let frames = fog_frame(&self.gl, image.linear(), range, request, return_info)?;
            let encode = |(rendered, info)| (ImageOut::encode(&rendered, pixels), info);
            Ok::<_, PyErr>(frames.into_iter().map(encode).collect::<Vec<_>>())
        })?;
        outputs_to_py(py, outputs, many)
    }

    /// distance_fog(image, depth, *, camera, time=0.0, start_distance=None, distance=None,
    /// exponent=None, max_density=None, colour=None, light_direction=None,
    /// scatter_start=None, scatter_exponent=None, scatter_colour=None, noise=None,
    /// noise_seed=0, noise_size=None, noise_speed=None, noise_low=None, noise_high=None,
    /// noise_colour_strength=None, blur='diffusion', lambda_px=None, range_unit=None,
    /// sigma0=1.0, scheme='matched', precision='f32', rho_max=0.25, blur_distance=100.0,
    /// blur_falloff=1.0, blur_max=1.0) -> ndarray: as brume.distance_fog, on this
    /// renderer's context.
    #[pyo3(signature = (image, depth, *, camera, time=0.0, start_distance=None, distance=None, exponent=None, max_density=None, colour=None, light_direction=None, scatter_start=None, scatter_exponent=None, scatter_colour=None, noise=None, noise_seed=0, noise_size=None, noise_speed=None, noise_low=None, noise_high=None, noise_colour_strength=None, blur="diffusion", lambda_px=None, range_unit=None, sigma0=1.0, scheme="matched", precision="f32", rho_max=0.25, blur_distance=100.0, blur_falloff=1.0, blur_max=1.0))]
    #[allow(clippy::too_many_arguments)]
    fn distance_fog<'py>(
        &self,
        py: Python<'py>,
        image: &Bound<'py, PyAny>,
        depth: &Bound<'py, PyAny>,
        camera: &Bound<'py, PyAny>,
        time: f64,
        start_distance: Option<f64>,
        distance: Option<f64>,
        exponent: Option<f64>,
        max_density: Option<f64>,
        colour: Option<Colour>,
        light_direction: Option<Vec<f64>>,
        scatter_start: Option<f64>,
        scatter_exponent: Option<f64>,
        scatter_colour: Option<Colour>,
        noise: Option<&Bound<'py, PyAny>>,
        noise_seed: i128,
        noise_size: Option<f64>,
        noise_speed: Option<Vec<f64>>,
        noise_low: Option<f64>,
        noise_high: Option<f64>,
        noise_colour_strength: Option<f64>,
        blur: &str,
        lambda_px: Option<f64>,
        range_unit: Option<f64>,
        sigma0: f64,
        scheme: &str,
        precision: &str,
        rho_max: f64,
        blur_distance: f64,
        blur_falloff: f64,
        blur_max: f64,
    ) -> PyResult<Py<PyAny>> {
        let blur = engine::BlurArgs {
            blur,
            sigma0,
            scheme,
            precision,
            rho_max,
            blur_distance,
            blur_falloff,
            blur_max,
        };
        let fog = engine::DistanceArgs {
            start_distance,
            distance,
            exponent,
            max_density,
            colour,
            light_direction,
            scatter_start,
            scatter_exponent,
            scatter_colour,
            noise,
            noise_seed: arrays::seed_of("noise_seed", noise_seed)?,
            noise_size,
            noise_speed,
            noise_low,
            noise_high,
            noise_colour_strength,
            lambda_px,
            range_unit,
        };
        let request = engine::distance_request(image, depth, camera, time, &blur, fog)?;
        let out = py.detach(|| engine::render(&self.gl, request))?;
        Ok(out.into_py(py))
    }

    /// layered_fog(image, depth, *, camera, time=0.0, profile='exponential', density=None,
    /// base=None, scale_height=None, thickness=None, top=None, table=None, colour=None,
    /// albedo=None, blur='diffusion', lambda_px=None, range_unit=None, sigma0=1.0,
    /// scheme='matched', precision='f32', rho_max=0.25, blur_distance=100.0,
    /// blur_falloff=1.0, blur_max=1.0) -> ndarray: as brume.layered_fog, on this
    /// renderer's context.
    #[pyo3(signature = (image, depth, *, camera, time=0.0, profile="exponential", density=None, base=None, scale_height=None, thickness=None, top=None, table=None, colour=None, albedo=None, blur="diffusion", lambda_px=None, range_unit=None, sigma0=1.0, scheme="matched", precision="f32", rho_max=0.25, blur_distance=100.0, blur_falloff=1.0, blur_max=1.0))]
    #[allow(clippy::too_many_arguments)]
    fn layered_fog<'py>(
        &self,
        py: Python<'py>,
        image: &Bound<'py, PyAny>,
        depth: &Bound<'py, PyAny>,
        camera: &Bound<'py, PyAny>,
        time: f64,
        profile: &str,
        density: Option<f64>,
        base: Option<f64>,
        scale_height: Option<f64>,
        thickness: Option<f64>,
        top: Option<f64>,
        table: Option<&Bound<'py, PyAny>>,
        colour: Option<Colour>,
        albedo: Option<f64>,
        blur: &str,
        lambda_px: Option<f64>,
        range_unit: Option<f64>,
        sigma0: f64,
        scheme: &str,
        precision: &str,
        rho_max: f64,
        blur_distance: f64,
        blur_falloff: f64,
        blur_max: f64,
    ) -> PyResult<Py<PyAny>> {
        let blur = engine::BlurArgs {
            blur,
            sigma0,
            scheme,
            precision,
            rho_max,
            blur_distance,
            blur_falloff,
            blur_max,
        };
        let fog = engine::LayeredArgs {
            profile,
            density,
            base,
            scale_height,
            thickness,
            top,
            table: table.filter(|t| !t.is_none()),
            colour,
            albedo,
            lambda_px,
            range_unit,
        };
        let request = engine::layered_request(image, depth, camera, time, &blur, fog)?;
        let out = py.detach(|| engine::render(&self.gl, request))?;
        Ok(out.into_py(py))
    }

    /// aerial(image, range_m, *, turbidity, fov_y_deg=None, focal_px=None, pitch_deg=None,
    /// horizon_row=None, altitude_m=0.0, metres_per_unit=1.0, from_turbidity=None, retarget=None,
    /// airlight=None, horizon_zenith_deg=85.0, horizon_sectors=8, sun=None, sensitivity=None,
    /// icc_profile=None, blur=True, lambda_px=8.0, sigma0=1.0, refine=True, sky_mask=None,
    /// ego_mask=None, exposure_stops=0.0, shot_noise_gain=None, read_noise=None, jpeg_quality=None,
    /// seed=0, return_info=False, monocular=False, stereo_focal_baseline=None, stereo_view=None,
    /// ground=None) -> ndarray, or (ndarray, dict), or a list of those: as brume.aerial, on this
    /// renderer's context.
    #[pyo3(
        signature = (image, range_m, *, turbidity, fov_y_deg=None, focal_px=None, pitch_deg=None, horizon_row=None, altitude_m=0.0, metres_per_unit=1.0, from_turbidity=None, retarget=None, airlight=None, horizon_zenith_deg=aerial_photo::HORIZON_ZENITH_DEG, horizon_sectors=8, sun=None, sensitivity=None, icc_profile=None, blur=true, lambda_px=8.0, sigma0=1.0, refine=None, sky_mask=None, ego_mask=None, exposure_stops=0.0, shot_noise_gain=None, read_noise=None, jpeg_quality=None, seed=0, return_info=false, monocular=false, stereo_focal_baseline=None, stereo_view=None, ground=None),
        text_signature = "($self, image, range_m, *, turbidity, fov_y_deg=None, focal_px=None, pitch_deg=None, horizon_row=None, altitude_m=0.0, metres_per_unit=1.0, from_turbidity=None, retarget=None, airlight=None, horizon_zenith_deg=85.0, horizon_sectors=8, sun=None, sensitivity=None, icc_profile=None, blur=True, lambda_px=8.0, sigma0=1.0, refine=None, sky_mask=None, ego_mask=None, exposure_stops=0.0, shot_noise_gain=None, read_noise=None, jpeg_quality=None, seed=0, return_info=False, monocular=False, stereo_focal_baseline=None, stereo_view=None, ground=None)"
    )]
    #[allow(clippy::too_many_arguments)]
    fn aerial<'py>(
        &self,
        py: Python<'py>,
        image: &Bound<'py, PyAny>,
        range_m: &Bound<'py, PyAny>,
        turbidity: Densities,
        fov_y_deg: Option<f64>,
        focal_px: Option<f64>,
        pitch_deg: Option<f64>,
        horizon_row: Option<f64>,
        altitude_m: f64,
        metres_per_unit: f64,
        from_turbidity: Option<f64>,
        retarget: Option<String>,
        airlight: Option<Colour>,
        horizon_zenith_deg: f64,
        horizon_sectors: i64,
        sun: Option<(f64, f64)>,
        sensitivity: Option<FsPath>,
        icc_profile: Option<Vec<u8>>,
        blur: bool,
        lambda_px: f64,
        sigma0: f64,
        refine: Option<&Bound<'py, PyAny>>,
        sky_mask: Option<&Bound<'py, PyAny>>,
        ego_mask: Option<&Bound<'py, PyAny>>,
        exposure_stops: f64,
        shot_noise_gain: Option<f64>,
        read_noise: Option<f64>,
        jpeg_quality: Option<i64>,
        seed: i128,
        return_info: bool,
        monocular: bool,
        stereo_focal_baseline: Option<f64>,
        stereo_view: Option<&str>,
        ground: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Py<PyAny>> {
        let default_refine = pyo3::types::PyBool::new(py, true);
        let refine = refine.unwrap_or(default_refine.as_any());
        let capture = capture_request(
            exposure_stops,
            shot_noise_gain,
            read_noise,
            jpeg_quality,
            seed,
        )?;
        let mut prepare = prepare_request(airlight, refine)?;
        let origin = (monocular, (stereo_focal_baseline, stereo_view), ground);
        photo_fog::set_depth_origin(&mut prepare, origin)?;
        let args = aerial_photo::AerialArgs {
            turbidities: turbidity.non_empty("turbidity")?.to_vec(),
            fov_y_deg,
            focal_px,
            pitch_deg,
            horizon_row,
            altitude_m,
            metres_per_unit,
            from_turbidity,
            retarget,
            airlight: prepare.airlight,
            horizon_zenith_deg,
            horizon_sectors,
            sun,
            sensitivity: sensitivity.map(|p| p.0),
            icc_profile,
            blur,
            lambda_px,
            sigma0,
        };
        let image = read_image(image)?;
        self.check_or_free_kept(py, || {
            check_outputs_fit(
                args.turbidities.len(),
                image.width * image.height,
                aerial_photo::OUTPUT_BYTES_PER_PIXEL,
                "give fewer turbidities in one call: every output is held until it returns",
            )
        })?;
        let range = read_range(range_m)?;
        set_masks(&mut prepare, &range, sky_mask, ego_mask)?;
        let pixels = image.pixels;
        let outputs = py.detach(|| {
            let frames = aerial_photo::aerial_frame(
                &self.gl,
                image,
                range,
                &args,
                prepare,
                &capture,
                return_info,
            )?;
            let encode = |(rendered, info)| (ImageOut::encode(&rendered, pixels), info);
            Ok::<_, PyErr>(frames.into_iter().map(encode).collect::<Vec<_>>())
        })?;
        outputs_to_py(py, outputs, turbidity.many())
    }

    /// GL_RENDERER of the context, e.g. 'llvmpipe (LLVM 15.0.6, 256 bits)'.
    #[getter]
    fn gl_renderer(&self) -> String {
        self.gl.renderer_name.clone()
    }

    fn __repr__(&self) -> String {
        let closed = if self.gl.is_closed() { ", closed" } else { "" };
        format!("brume.Renderer({:?}{closed})", self.gl.renderer_name)
    }

    /// close(): ends the renderer's GL thread after the calls already queued and destroys
    /// its context (its GPU memory is freed when this returns); later calls raise
    /// RuntimeError. Also what `with brume.Renderer() as r:` does at the end of the block.
    fn close(&self, py: Python<'_>) -> PyResult<()> {
        py.detach(|| self.gl.close())
    }

    /// Whether close() has been called.
    #[getter]
    fn closed(&self) -> bool {
        self.gl.is_closed()
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    /// Closes the renderer; an exception in the block goes on.
    fn __exit__(
        &self,
        py: Python<'_>,
        _kind: Option<&Bound<'_, PyAny>>,
        _value: Option<&Bound<'_, PyAny>>,
        _traceback: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<bool> {
        self.close(py)?;
        Ok(false)
    }

    /// Pickled as a new renderer: a context belongs to its process, so a transform that
    /// holds one (`RandomFog(renderer=…)`) can go to spawned worker processes, each of
    /// which opens its own on unpickling.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> (Bound<'py, pyo3::types::PyType>, ()) {
        (slf.get_type(), ())
    }
}

/// The renderer `brume.fog` uses, opened on its first call.
static DEFAULT_RENDERER: OnceLock<Py<Renderer>> = OnceLock::new();

fn default_renderer(py: Python<'_>) -> PyResult<&'static Py<Renderer>> {
    if let Some(r) = DEFAULT_RENDERER.get() {
        return Ok(r);
    }
    let renderer = Py::new(py, Renderer::new(py)?)?;
    // Two threads may race here; the loser's renderer is dropped.
    Ok(DEFAULT_RENDERER.get_or_init(|| renderer))
}

/// fog(image, range_m, *, beta=None, visibility=None, ka=None, ks=None, airlight=None, blur=True,
/// lambda_px=None, refine=True, sky_mask=None, ego_mask=None, exposure_stops=0.0,
/// shot_noise_gain=None, read_noise=None, jpeg_quality=None, seed=0, compat=None,
/// return_info=False, monocular=False, stereo_focal_baseline=None, stereo_view=None, ground=None)
/// -> ndarray, or (ndarray, dict), or a list of those
///
/// Fogs a photo with its range in metres (paper 000's haze in physical units, with the
/// diffusion blur). image: HxWx3 uint8 or uint16 (sRGB code values) or float32, float64
/// or float16 (linear RGB); the result has the same dtype and encoding. range_m: HxW
/// (or HxWx1, 1xHxW) metres from the camera centre (NaN or <= 0 unknown), the image's
/// size or smaller by one factor. Exactly one of beta (extinction, 1/m), visibility (m) — either may be a
/// sequence: one output each, in a list, from one pre-processing and refinement of the
/// frame, each equal to the call with that value alone — or ka and/or ks: paper 000's
/// absorption and scattering per unit of range normalised by its largest value (`brume render`'s
/// default; the range in any unit, e.g. a relative depth; the other one 0.25 or 0.75 when
/// only one is given). airlight: None (estimated from the sky), a grey (0.8) or linear RGB
/// (0.8, 0.82, 0.85). blur: False for none (lambda 0); lambda_px: the blur's strength
/// (default 8, as `--lambda`).
/// refine: True ('repair'), False ('none') or 'none' | 'guided' | 'unreliable' | 'repair'.
/// sky_mask, ego_mask: HxW arrays of range_m's shape, bool or integers (non-zero = set),
/// e.g. `labels == 23` of a Cityscapes labelIds image: the sky instead of its detection
/// (its range the farthest, its colour the airlight's), and the car's hood (never fogged).
/// monocular=True: range_m is a monocular model's relative depth (range_from_depth or
/// load_depth with kind 'inverse' or 'affine'), whose sky has a depth, the farthest: its
/// far tail (beyond 10 times the lower quartile) may be sky where the image says so, as
/// `brume render` reads those kinds. stereo_focal_baseline: f·B (focal length in px times
/// baseline in m) when range_m comes from a stereo-matched disparity (load_depth's info
/// gives it for a Cityscapes disparity): a run of unknown range beside a nearer surface,
/// the background the other camera could not see, is filled from that background, not the
/// near surface (no clear halo beside a pole), as `brume render` fills a Cityscapes
/// disparity. stereo_view: 'left' (default) or 'right', the view the disparity is of
/// (load_depth's info gives it): those runs lie left of nearer surfaces in a left view,
/// right of them in a right view. ground: load_depth's info['ground'] (a dict of height_m,
/// pitch, roll: the camera's mount over the road, from a Cityscapes camera file, and fx,
/// fy, cx, cy: its intrinsics on range_m's grid): values below the horizon beyond the
/// road falling 5 % away from the camera's level, in small patches, are false matches and
/// are filled, as `brume render` does.
///
/// The camera after the fog (all off by default): exposure_stops (the linear image times
/// 2^stops), shot_noise_gain K (the linear value of one photo-electron: Poisson noise of
/// variance K·v) and read_noise (Gaussian, standard deviation in linear units), seeded by
/// seed, then jpeg_quality (1-100, an encode-decode round trip); clipped to [0, 1].
///
/// compat='foggy-cityscapes' follows Foggy Cityscapes' conventions instead, as `brume
/// render --compat foggy-cityscapes`: I = R·t + L·(1 - t) blended in sRGB code values, L
/// the dark channel's (or airlight, encoded), no blur; with beta or visibility only, no
/// lambda_px and no capture. Its labels' airlight is L decoded to linear RGB.
///
/// return_info=True also returns the labels of a dehazing dataset (the scattering model
/// I = J·t + A·(1 - t), before the capture): transmittance (float32 HxW, t = exp(-beta R)
/// at the image's size), range_m (float32 HxW, the range R the fog read: pre-processed,
/// refined, unknown pixels the farthest, the sky at least 1 km away with beta or
/// visibility), airlight (A, three linear RGB floats),
/// airlight_source ('given', 'sky', 'neutral' or 'default'), beta, visibility_m and
/// sigma_max_px (the blur's largest scale). With ka/ks, range_m is in the caller's units
/// and beta is (ka + ks) / the largest range, per that unit.
#[pyfunction]
#[pyo3(
    signature = (*args, **kwargs),
    text_signature = "(image, range_m, *, beta=None, visibility=None, ka=None, ks=None, airlight=None, blur=True, lambda_px=None, refine=None, sky_mask=None, ego_mask=None, exposure_stops=0.0, shot_noise_gain=None, read_noise=None, jpeg_quality=None, seed=0, compat=None, return_info=False, monocular=False, stereo_focal_baseline=None, stereo_view=None, ground=None)"
)]
fn fog(
    py: Python<'_>,
    args: &Bound<'_, PyTuple>,
    kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    on_default_renderer(py, "fog", args, kwargs)
}

/// Calls `method` of the default renderer with the arguments given.
fn on_default_renderer(
    py: Python<'_>,
    method: &str,
    args: &Bound<'_, PyTuple>,
    kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    let renderer = default_renderer(py)?.bind(py);
    Ok(renderer.call_method(method, args, kwargs)?.unbind())
}

/// beta_quantile(dist, p) -> float
///
/// The extinction β (1/m) below which a fraction p in (0, 1) of the draws of dist fall:
/// dist as `brume batch --beta-dist` takes it, '0.02', 'uniform:LOW,HIGH' or
/// 'lognormal:MU,SIGMA' (ln β normal). A uniform p gives a draw (RandomFog does so).
#[pyfunction]
fn beta_quantile(dist: &str, p: f64) -> PyResult<f64> {
    let dist: BetaDistribution = dist.parse().map_err(py_err)?;
    if !(p > 0.0 && p < 1.0) {
        return Err(value_error(format!(
            "invalid p = {p}: expected a probability strictly between 0 and 1"
        )));
    }
    Ok(dist.quantile(p))
}

#[pymodule]
fn _brume(m: &Bound<'_, PyModule>) -> PyResult<()> {
    brume::memory::set_allocator_release(release_mimalloc_pages);
    m.add_class::<Renderer>()?;
    m.add_class::<engine::PyCamera>()?;
    m.add_class::<engine::PyMatrixCamera>()?;
    m.add_function(wrap_pyfunction!(engine::distance_fog, m)?)?;
    m.add_function(wrap_pyfunction!(engine::layered_fog, m)?)?;
    m.add_function(wrap_pyfunction!(aerial_photo::aerial, m)?)?;
    m.add_function(wrap_pyfunction!(fog, m)?)?;
    m.add_function(wrap_pyfunction!(prepare::prepare, m)?)?;
    m.add_function(wrap_pyfunction!(depth::load_depth, m)?)?;
    m.add_function(wrap_pyfunction!(depth::range_from_depth, m)?)?;
    m.add_function(wrap_pyfunction!(depth::left_right_mismatches, m)?)?;
    m.add_function(wrap_pyfunction!(photo_io::load_photo, m)?)?;
    m.add_function(wrap_pyfunction!(photo_io::save_photo, m)?)?;
    m.add_function(wrap_pyfunction!(sky_photo::turbidity_from_sky, m)?)?;
    m.add_function(wrap_pyfunction!(sky_photo::render_sky, m)?)?;
    m.add_function(wrap_pyfunction!(sun::sun_position, m)?)?;
    m.add_function(wrap_pyfunction!(beta_quantile, m)?)?;
    m.add_function(wrap_pyfunction!(metrics::compare, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // The version alone does not tell two builds apart whose outputs differ.
    m.add("__sources__", brume::SOURCES)?;
    Ok(())
}
