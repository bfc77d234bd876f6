//! The engine fogs in Python: `brume.Camera`, `brume.MatrixCamera`, and the requests of
//! `Renderer.distance_fog` (paper 001) and `Renderer.layered_fog` (paper 003) on a frame's
//! colour and depth buffer, through `brume::medium`, `brume::camera` and
//! `Headless::render_fog`, as `brume scene` builds them.

use super::arrays::{read_scalar_map, Colour, FsPath};
use super::{on_default_renderer, py_err, value_error, GlThread, ImageIn, ImageOut};
use brume::camera::{Camera, ClipDepth, FrameCamera, FrameInputs, MatrixCamera};
use brume::medium::{
    DensityTable, DistanceFog, FogNoise, HeightProfile, LayeredFog, Medium, ProfileValues,
};
use brume::raster::ScalarMap;
use brume::{Blur, FogBlur, GaussBlur, Precision, Scheme};
use glam::DMat4;
use numpy::{PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

// ---------------------------------------------------------------------------------------
// Cameras.

/// Camera(position=(0, 1.7, 0), yaw_deg=0, pitch_deg=0, fov_y_deg=60, near=0.1, far=1000)
///
/// brume's perspective camera of a rendered frame (`brume scene`'s): world y up; yaw 0
/// looks along −z and turns toward +x; pitch up; the vertical field of view in degrees;
/// OpenGL's projection with clip depth −1..1. Checked when built (ValueError naming the
/// parameter).
#[pyclass(module = "brume", name = "Camera", frozen)]
pub(crate) struct PyCamera {
    pub(crate) inner: Camera,
}

#[pymethods]
impl PyCamera {
    #[new]
    #[pyo3(
        signature = (position=(0.0, 1.7, 0.0), yaw_deg=0.0, pitch_deg=0.0, fov_y_deg=60.0, near=0.1, far=1000.0),
        text_signature = "(position=(0.0, 1.7, 0.0), yaw_deg=0.0, pitch_deg=0.0, fov_y_deg=60.0, near=0.1, far=1000.0)"
    )]
    fn new(
        position: (f64, f64, f64),
        yaw_deg: f64,
        pitch_deg: f64,
        fov_y_deg: f64,
        near: f64,
        far: f64,
    ) -> PyResult<Self> {
        let inner = Camera {
            position: [position.0, position.1, position.2],
            yaw_deg,
            pitch_deg,
            fov_y_deg,
            near,
            far,
        };
        inner.validate().map_err(|e| camera_error("Camera", e))?;
        Ok(PyCamera { inner })
    }

    #[getter]
    fn position(&self) -> (f64, f64, f64) {
        let [x, y, z] = self.inner.position;
        (x, y, z)
    }
    #[getter]
    fn yaw_deg(&self) -> f64 {
        self.inner.yaw_deg
    }
    #[getter]
    fn pitch_deg(&self) -> f64 {
        self.inner.pitch_deg
    }
    #[getter]
    fn fov_y_deg(&self) -> f64 {
        self.inner.fov_y_deg
    }
    #[getter]
    fn near(&self) -> f64 {
        self.inner.near
    }
    #[getter]
    fn far(&self) -> f64 {
        self.inner.far
    }

    fn __repr__(&self) -> String {
        let c = &self.inner;
        format!(
            "brume.Camera(position={:?}, yaw_deg={}, pitch_deg={}, fov_y_deg={}, near={}, far={})",
            self.position(),
            c.yaw_deg,
            c.pitch_deg,
            c.fov_y_deg,
            c.near,
            c.far
        )
    }
}

/// MatrixCamera(view, projection, clip='minus_one_to_one', sky_depth=None)
///
/// An engine's camera as it is: `view` (world → eye) and `projection` (eye → clip), 4x4
/// arrays **row-major as numpy holds them**, for column vectors: clip = projection @ view
/// @ (x, y, z, 1), so `m[r, c]` is row r, column c of the matrix in the usual notation.
/// A column-major engine matrix (OpenGL's and GLM's `float[16]`, glam's
/// `to_cols_array()`, a Bevy `Mat4`) flattened to 16 numbers maps as
/// `np.asarray(flat).reshape(4, 4, order='F')` (equivalently `.reshape(4, 4).T`); a
/// row-vector engine's matrices (Unreal, D3DX: v' = v @ M) are the transpose too.
/// `clip`: how the API that drew the depth buffer maps clip depth to window depth,
/// 'minus_one_to_one' (OpenGL's default, brume's own Camera) or 'zero_to_one' (Direct3D,
/// Vulkan, Metal, wgpu/Bevy, Unreal, GL with glClipControl). Reversed-Z and an infinite
/// far plane are read off the projection. `sky_depth`: the eye depth (world units) that
/// pixels at an infinite far plane get (default 10 km).
#[pyclass(module = "brume", name = "MatrixCamera", frozen)]
pub(crate) struct PyMatrixCamera {
    pub(crate) inner: MatrixCamera,
}

#[pymethods]
impl PyMatrixCamera {
    #[new]
    #[pyo3(signature = (view, projection, clip="minus_one_to_one", sky_depth=None))]
    fn new(
        view: &Bound<'_, PyAny>,
        projection: &Bound<'_, PyAny>,
        clip: &str,
        sky_depth: Option<f64>,
    ) -> PyResult<Self> {
        let view = read_matrix("view", view)?;
        check_affine_view(&view)?;
        let projection = read_matrix("projection", projection)?;
        let clip = match clip.trim().to_ascii_lowercase().replace('-', "_").as_str() {
            "minus_one_to_one" => ClipDepth::MinusOneToOne,
            "zero_to_one" => ClipDepth::ZeroToOne,
            _ => {
                return Err(value_error(format!(
                    "invalid clip = {clip:?}: expected 'minus_one_to_one' (OpenGL's default) or \
                     'zero_to_one' (Direct3D, Vulkan, Metal, wgpu/Bevy, Unreal)"
                )))
            }
        };
        let mut inner = MatrixCamera::new(view, projection, clip)
            .map_err(|e| camera_error("MatrixCamera", e))?;
        if let Some(s) = sky_depth {
            inner = inner
                .with_sky_depth(s)
                .map_err(|e| camera_error("MatrixCamera", e))?;
        }
        Ok(PyMatrixCamera { inner })
    }

    /// The near plane read off the projection (world units).
    #[getter]
    fn near(&self) -> f64 {
        self.inner.near()
    }
    /// The far plane read off the projection (inf for an infinite one).
    #[getter]
    fn far(&self) -> f64 {
        self.inner.far()
    }
    /// Whether the projection is reversed-Z (depth 1 at near).
    #[getter]
    fn reversed(&self) -> bool {
        self.inner.reversed()
    }
    /// The largest eye depth a pixel gets (the far plane, or the sky depth).
    #[getter]
    fn sky_depth(&self) -> f64 {
        self.inner.sky_depth()
    }

    fn __repr__(&self) -> String {
        format!(
            "brume.MatrixCamera(near={}, far={}, reversed={}, clip={:?})",
            self.inner.near(),
            self.inner.far(),
            self.inner.reversed(),
            self.inner.clip()
        )
    }
}

/// A camera's error as a ValueError naming the class.
fn camera_error(class: &str, e: brume::Error) -> PyErr {
    value_error(format!("{class}: {e}"))
}

/// A 4x4 numpy matrix (row-major as numpy holds it) as glam's column-major `DMat4`.
fn read_matrix(name: &str, m: &Bound<'_, PyAny>) -> PyResult<DMat4> {
    let numpy = m.py().import("numpy")?;
    let array = numpy.call_method1("asarray", (m, "float64")).map_err(|e| {
        value_error(format!(
            "{name}: expected a 4x4 numeric array (row-major, as numpy holds it), got {e}"
        ))
    })?;
    let a: PyReadonlyArray2<f64> = array.extract().map_err(|_| {
        value_error(format!(
            "{name}: expected a 4x4 array, got shape {:?}",
            array
                .getattr("shape")
                .map(|s| s.to_string())
                .unwrap_or_default()
        ))
    })?;
    let a = a.as_array();
    if a.shape() != [4, 4] {
        return Err(value_error(format!(
            "{name}: expected a 4x4 array, got shape {:?}",
            a.shape()
        )));
    }
    let rows: [[f64; 4]; 4] = std::array::from_fn(|r| std::array::from_fn(|c| a[[r, c]]));
    // glam takes columns: the rows as columns, transposed.
    Ok(DMat4::from_cols_array_2d(&rows).transpose())
}

/// A world-to-eye matrix keeps w: its last row is (0, 0, 0, 1). A column-major matrix read
/// row by row has its translation there instead, the commonest mistake: said so.
fn check_affine_view(view: &DMat4) -> PyResult<()> {
    let last = view.row(3);
    if last.to_array() != [0.0, 0.0, 0.0, 1.0] {
        return Err(value_error(format!(
            "view: last row {:?}, expected (0, 0, 0, 1) for a world-to-eye matrix (a \
             column-major matrix read row by row has its translation there: pass \
             np.asarray(flat).reshape(4, 4, order='F'), or the transpose)",
            last.to_array()
        )));
    }
    Ok(())
}

/// `camera` as the frame's camera: a `brume.Camera` or a `brume.MatrixCamera`.
fn frame_camera(camera: &Bound<'_, PyAny>) -> PyResult<FrameCamera> {
    if let Ok(c) = camera.cast::<PyCamera>() {
        return Ok(c.get().inner.into());
    }
    if let Ok(c) = camera.cast::<PyMatrixCamera>() {
        return Ok(c.get().inner.into());
    }
    Err(value_error(format!(
        "camera: expected a brume.Camera(position=…, yaw_deg=…, …) or a \
         brume.MatrixCamera(view, projection, clip=…), got {}",
        camera
            .get_type()
            .name()
            .map(|n| n.to_string())
            .unwrap_or_default()
    )))
}

// ---------------------------------------------------------------------------------------
// The depth buffer.

/// `depth` (HxW window depth in [0, 1], the image's size) as brume's map, top row first.
fn read_depth(depth: &Bound<'_, PyAny>, width: usize, height: usize) -> PyResult<ScalarMap> {
    let map = read_scalar_map(
        depth,
        "depth",
        "window depth in [0, 1]",
        &format!("{height}x{width}, the image's"),
        "window depth in [0, 1]",
    )?;
    if (map.width(), map.height()) != (width, height) {
        return Err(value_error(format!(
            "depth: expected shape {height}x{width} (HxW, the image's), got [{}, {}]",
            map.height(),
            map.width()
        )));
    }
    let data = map.as_slice();
    if let Some(i) = data.iter().position(|v| !(0.0..=1.0).contains(v)) {
        return Err(value_error(format!(
            "depth: value {} at pixel (x {}, y {}): expected window depth in [0, 1] (a depth \
             buffer with the default depth range; 1 is the far plane)",
            data[i],
            i % width,
            i / width
        )));
    }
    Ok(map)
}

// ---------------------------------------------------------------------------------------
// Blur.

/// The blur keywords both engine fogs take.
pub(crate) struct BlurArgs<'a> {
    pub blur: &'a str,
    pub sigma0: f64,
    pub scheme: &'a str,
    pub precision: &'a str,
    pub rho_max: f64,
    pub blur_distance: f64,
    pub blur_falloff: f64,
    pub blur_max: f64,
}

impl BlurArgs<'_> {
    /// The `FogBlur` they describe, as `brume scene --blur …` builds it.
    fn fog_blur(&self) -> PyResult<FogBlur> {
        let precision: Precision = self.precision.parse().map_err(|_| {
            value_error(format!(
                "invalid precision = {:?}: expected 'f32' or 'f16'",
                self.precision
            ))
        })?;
        let scheme: Scheme = self.scheme.parse().map_err(|_| {
            value_error(format!(
                "invalid scheme = {:?}: expected 'matched', 'invariant' or 'euler'",
                self.scheme
            ))
        })?;
        let gauss = GaussBlur {
            distance: self.blur_distance,
            falloff: self.blur_falloff,
            maximum: self.blur_max,
            precision,
        };
        let diffusion = Blur {
            scheme,
            sigma0: self.sigma0,
            rho_max: self.rho_max,
            precision,
            ..Blur::default()
        };
        let name = self.blur.trim().to_ascii_lowercase().replace('_', "-");
        FogBlur::chosen(&name, gauss, diffusion).map_err(py_err)
    }
}

// ---------------------------------------------------------------------------------------
// Media.

/// Three numbers from a keyword, checked finite (and ≥ 0 for a colour).
fn triple(name: &str, v: Option<Vec<f64>>, colour: bool) -> PyResult<Option<[f64; 3]>> {
    let Some(v) = v else { return Ok(None) };
    let ok = v.len() == 3 && v.iter().all(|x| x.is_finite() && (!colour || *x >= 0.0));
    if !ok {
        let what = if colour {
            "a number (a grey) or three linear RGB values, each finite and >= 0"
        } else {
            "three finite numbers (x, y, z)"
        };
        return Err(value_error(format!(
            "invalid {name} = {v:?}: expected {what}"
        )));
    }
    Ok(Some([v[0], v[1], v[2]]))
}

fn rgb(name: &str, v: Option<Colour>) -> PyResult<Option<[f32; 3]>> {
    Ok(triple(name, v.map(|c| c.0), true)?.map(|c| c.map(|x| x as f32)))
}

/// A medium's error with its field named as the Python keyword that sets it (`noise
/// size` is `noise_size`; `py_err` renames the others).
fn keyword_error(e: brume::Error) -> PyErr {
    py_err(e.rename_options(|name| name.contains(' ').then(|| name.replace(' ', "_"))))
}

/// The distance fog's keywords (`None`: the library's default).
pub(crate) struct DistanceArgs<'py> {
    pub start_distance: Option<f64>,
    pub distance: Option<f64>,
    pub exponent: Option<f64>,
    pub max_density: Option<f64>,
    pub colour: Option<Colour>,
    pub light_direction: Option<Vec<f64>>,
    pub scatter_start: Option<f64>,
    pub scatter_exponent: Option<f64>,
    pub scatter_colour: Option<Colour>,
    pub noise: Option<&'py Bound<'py, PyAny>>,
    pub noise_seed: u64,
    pub noise_size: Option<f64>,
    pub noise_speed: Option<Vec<f64>>,
    pub noise_low: Option<f64>,
    pub noise_high: Option<f64>,
    pub noise_colour_strength: Option<f64>,
    pub lambda_px: Option<f64>,
    pub range_unit: Option<f64>,
}

impl DistanceArgs<'_> {
    /// Paper 001's fog, as `brume scene --fog distance` builds it, the range unit the
    /// camera's far plane (or sky depth) unless given.
    fn medium(self, camera: &FrameCamera) -> PyResult<DistanceFog> {
        let d = DistanceFog::default();
        let noise = self.noise()?;
        let fog = DistanceFog {
            start_distance: self.start_distance.unwrap_or(d.start_distance),
            distance: self.distance.unwrap_or(d.distance),
            exponent: self.exponent.unwrap_or(d.exponent),
            max_density: self.max_density.unwrap_or(d.max_density),
            colour: rgb("colour", self.colour)?.unwrap_or(d.colour),
            light_direction: triple("light_direction", self.light_direction, false)?
                .unwrap_or(d.light_direction),
            scatter_start: self.scatter_start.unwrap_or(d.scatter_start),
            scatter_exponent: self.scatter_exponent.unwrap_or(d.scatter_exponent),
            scatter_colour: rgb("scatter_colour", self.scatter_colour)?.unwrap_or(d.scatter_colour),
            noise,
            lambda: self.lambda_px.unwrap_or(d.lambda),
            range_unit: self.range_unit.unwrap_or(camera.max_depth()),
        };
        fog.validate().map_err(keyword_error)?;
        Ok(fog)
    }

    /// `noise`: None or 'generated' (from noise_seed), 'none' or False, or a tiling
    /// greyscale PNG.
    fn noise(&self) -> PyResult<Option<FogNoise>> {
        let generated = || match self.noise_seed {
            0 => Ok(FogNoise::default()),
            seed => FogNoise::generate(256, seed).map_err(keyword_error),
        };
        let mut noise = match self.noise {
            None => generated()?,
            Some(n) => match n.extract::<String>() {
                Ok(s) if s == "none" => return Ok(None),
                Ok(s) if s == "generated" => generated()?,
                _ if n.extract::<bool>().is_ok_and(|b| !b) => return Ok(None),
                _ => {
                    let FsPath(path) = n.extract().map_err(|_| {
                        value_error(format!(
                            "invalid noise = {}: expected 'generated' (or None), 'none' (or \
                             False) or the path of a greyscale PNG that tiles",
                            n.repr().map(|r| r.to_string()).unwrap_or_default()
                        ))
                    })?;
                    FogNoise::from_png(&path).map_err(|e| match e {
                        brume::Error::Io { path, source } => value_error(format!(
                            "noise: cannot read the noise texture {}: {source}",
                            path.display()
                        )),
                        e => py_err(e),
                    })?
                }
            },
        };
        noise.size = self.noise_size.unwrap_or(noise.size);
        noise.speed =
            triple("noise_speed", self.noise_speed.clone(), false)?.unwrap_or(noise.speed);
        noise.low = self.noise_low.unwrap_or(noise.low);
        noise.high = self.noise_high.unwrap_or(noise.high);
        noise.colour_strength = self.noise_colour_strength.unwrap_or(noise.colour_strength);
        Ok(Some(noise))
    }
}

/// The layered fog's keywords (`None`: the profile's or the library's default).
pub(crate) struct LayeredArgs<'py> {
    pub profile: &'py str,
    pub density: Option<f64>,
    pub base: Option<f64>,
    pub scale_height: Option<f64>,
    pub thickness: Option<f64>,
    pub top: Option<f64>,
    pub table: Option<&'py Bound<'py, PyAny>>,
    pub colour: Option<Colour>,
    pub albedo: Option<f64>,
    pub lambda_px: Option<f64>,
    pub range_unit: Option<f64>,
}

impl LayeredArgs<'_> {
    /// Paper 003's fog, as `brume scene --fog layered` builds it.
    fn medium(self, camera: &FrameCamera) -> PyResult<LayeredFog> {
        let mut fog = LayeredFog::for_camera(*camera, self.profile()?);
        fog.colour = rgb("colour", self.colour)?.unwrap_or(fog.colour);
        fog.albedo = self.albedo.unwrap_or(fog.albedo);
        fog.lambda = self.lambda_px.unwrap_or(fog.lambda);
        fog.range_unit = self.range_unit.unwrap_or(fog.range_unit);
        fog.validate().map_err(keyword_error)?;
        Ok(fog)
    }

    /// The profile named, or the table, with the values given (the library refuses one
    /// the profile does not have).
    fn profile(&self) -> PyResult<HeightProfile> {
        let kind = self.profile.trim().to_ascii_lowercase();
        let profile = match (kind.as_str(), self.table) {
            ("table", Some(table)) => HeightProfile::Table(density_table(table)?),
            ("table", None) => {
                return Err(value_error(
                    "profile = 'table' without table: expected table= the path of a CSV \
                     (header height_m,extinction_per_m) or an Nx2 array of (height_m, \
                     extinction_per_m) rows",
                ))
            }
            (_, Some(t)) => {
                return Err(value_error(format!(
                    "invalid table = {}: expected profile='table' with it (the analytic \
                     profiles take no table)",
                    t.repr().map(|r| r.to_string()).unwrap_or_default()
                )))
            }
            ("exponential", None) => HeightProfile::EXPONENTIAL,
            ("band", None) => HeightProfile::SINE_BAND,
            ("ramp", None) => HeightProfile::LINEAR_RAMP,
            _ => {
                return Err(value_error(format!(
                    "invalid profile = {:?}: expected 'exponential', 'band', 'ramp' or 'table'",
                    self.profile
                )))
            }
        };
        let values = ProfileValues {
            density: self.density,
            base: self.base,
            scale_height: self.scale_height,
            thickness: self.thickness,
            top: self.top,
        };
        profile.with_checked(&values).map_err(py_err)
    }
}

/// `table`: a CSV path or an Nx2 array of (height_m, extinction_per_m) rows.
fn density_table(table: &Bound<'_, PyAny>) -> PyResult<DensityTable> {
    if let Ok(FsPath(path)) = table.extract::<FsPath>() {
        return DensityTable::from_csv(&path).map_err(py_err);
    }
    let numpy = table.py().import("numpy")?;
    let rows: Option<PyReadonlyArray2<f64>> = numpy
        .call_method1("asarray", (table, "float64"))
        .ok()
        .and_then(|a| a.extract().ok());
    let rows = rows
        .filter(|a| a.shape().len() == 2 && a.shape()[1] == 2)
        .ok_or_else(|| {
            value_error(
                "table: expected the path of a CSV (header height_m,extinction_per_m) or an \
                 Nx2 array of (height_m, extinction_per_m) rows",
            )
        })?;
    let rows: Vec<(f64, f64)> = rows
        .as_array()
        .rows()
        .into_iter()
        .map(|r| (r[0], r[1]))
        .collect();
    DensityTable::from_rows(&rows).map_err(|e| value_error(format!("table: {e}")))
}

// ---------------------------------------------------------------------------------------
// The render.

/// What an engine fog renders: a checked medium, its blur, the frame and the buffers.
pub(crate) struct EngineRequest<M> {
    medium: M,
    blur: FogBlur,
    frame: FrameInputs,
    image: ImageIn,
    depth: ScalarMap,
}

/// The common checks of both engine fogs: the arrays, the camera, the time, the blur
/// (and `lambda_px`, the medium's, which only the diffusion blur reads).
fn request<M>(
    image: &Bound<'_, PyAny>,
    depth: &Bound<'_, PyAny>,
    camera: &Bound<'_, PyAny>,
    time: f64,
    (blur, lambda_px): (&BlurArgs, Option<f64>),
    medium: impl FnOnce(&FrameCamera) -> PyResult<M>,
) -> PyResult<EngineRequest<M>> {
    let image = super::read_image(image)?;
    let depth = read_depth(depth, image.width, image.height)?;
    let camera = frame_camera(camera)?;
    if !time.is_finite() {
        return Err(value_error(format!(
            "invalid time = {time}: expected a finite time in seconds"
        )));
    }
    let blur = blur.fog_blur()?;
    blur.check_lambda(lambda_px).map_err(py_err)?;
    Ok(EngineRequest {
        blur,
        medium: medium(&camera)?,
        frame: FrameInputs::new(camera, time),
        image,
        depth,
    })
}

/// `Renderer.distance_fog`'s request, checked (with the GIL).
pub(crate) fn distance_request(
    image: &Bound<'_, PyAny>,
    depth: &Bound<'_, PyAny>,
    camera: &Bound<'_, PyAny>,
    time: f64,
    blur: &BlurArgs,
    fog: DistanceArgs,
) -> PyResult<EngineRequest<DistanceFog>> {
    request(image, depth, camera, time, (blur, fog.lambda_px), |c| {
        fog.medium(c)
    })
}

/// `Renderer.layered_fog`'s request, checked (with the GIL).
pub(crate) fn layered_request(
    image: &Bound<'_, PyAny>,
    depth: &Bound<'_, PyAny>,
    camera: &Bound<'_, PyAny>,
    time: f64,
    blur: &BlurArgs,
    fog: LayeredArgs,
) -> PyResult<EngineRequest<LayeredFog>> {
    request(image, depth, camera, time, (blur, fog.lambda_px), |c| {
        fog.medium(c)
    })
}

/// Renders the request on the GL thread (call with the GIL released): the image in
/// linear light, fogged through `Headless::render_fog`, in the input's encoding.
pub(crate) fn render<M: Medium + Send + 'static>(
    gl: &GlThread,
    request: EngineRequest<M>,
) -> PyResult<ImageOut> {
    let EngineRequest {
        medium,
        blur,
        frame,
        image,
        depth,
    } = request;
    let pixels = image.pixels;
    let linear = image.linear();
    let rendered = gl
        .run(move |h| h.render_fog(&linear, &depth, &medium, &frame, &blur))?
        .map_err(py_err)?;
    Ok(ImageOut::encode(&rendered.image, pixels))
}

// ---------------------------------------------------------------------------------------
// The module-level functions, on the default renderer.

/// distance_fog(image, depth, *, camera, time=0.0, start_distance=None, distance=None,
/// exponent=None, max_density=None, colour=None, light_direction=None, scatter_start=None,
/// scatter_exponent=None, scatter_colour=None, noise=None, noise_seed=0,
/// noise_size=None, noise_speed=None, noise_low=None, noise_high=None,
/// noise_colour_strength=None, blur='diffusion', lambda_px=None, range_unit=None,
/// sigma0=1.0, scheme='matched', precision='f32', rho_max=0.25, blur_distance=100.0,
/// blur_falloff=1.0, blur_max=1.0) -> ndarray
///
/// Paper 001's distance fog on a rendered frame, as an engine applies it (`brume scene
/// --fog distance`). image: HxWx3 uint8 (sRGB) or float32 (linear RGB), the same out.
/// depth: HxW float32 window depth in [0, 1] (the depth buffer, default depth range), row 0
/// at the top as the image. camera: a brume.Camera or a brume.MatrixCamera (the frame's).
/// time: seconds (the noise drifts). None takes the library's default (brume::medium::
/// DistanceFog): start_distance 0, distance 100, exponent 0.55, max_density 0.5, colour
/// (0.45, 0.64, 1.0), light_direction (0.3, 0.2, -1.0) (toward the light), scatter_start
/// 10, scatter_exponent 4, scatter_colour (1.0, 0.65, 0.28); noise 'generated' (the
/// default: periodic Perlin noise from noise_seed), 'none' or False (a uniform fog), or a
/// tiling greyscale PNG's path, with
/// noise_size 100 (m per tile), noise_speed (2, 0, 0.25) (m/s), noise_low 0.12, noise_high
/// 0.18, noise_colour_strength 0; lambda_px 8 (the diffusion blur's λ), range_unit the
/// camera's far plane (or sky depth). blur: 'none', 'gauss-single', 'gauss-separate' (paper
/// 001's 5x5 Gaussian: blur_distance, blur_falloff, blur_max) or 'diffusion' (brume's:
/// sigma0, scheme, precision, rho_max).
#[pyfunction]
#[pyo3(
    signature = (*args, **kwargs),
    text_signature = "(image, depth, *, camera, time=0.0, start_distance=None, distance=None, exponent=None, max_density=None, colour=None, light_direction=None, scatter_start=None, scatter_exponent=None, scatter_colour=None, noise=None, noise_seed=0, noise_size=None, noise_speed=None, noise_low=None, noise_high=None, noise_colour_strength=None, blur='diffusion', lambda_px=None, range_unit=None, sigma0=1.0, scheme='matched', precision='f32', rho_max=0.25, blur_distance=100.0, blur_falloff=1.0, blur_max=1.0)"
)]
pub(crate) fn distance_fog(
    py: Python<'_>,
    args: &Bound<'_, PyTuple>,
    kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    on_default_renderer(py, "distance_fog", args, kwargs)
}

/// layered_fog(image, depth, *, camera, time=0.0, profile='exponential', density=None,
/// base=None, scale_height=None, thickness=None, top=None, table=None, colour=None,
/// albedo=None, blur='diffusion', lambda_px=None, range_unit=None, sigma0=1.0,
/// scheme='matched', precision='f32', rho_max=0.25, blur_distance=100.0, blur_falloff=1.0,
/// blur_max=1.0) -> ndarray
///
/// Paper 003's layered (height) fog on a rendered frame (`brume scene --fog layered`):
/// image, depth, camera, time and the blur as for distance_fog. profile: 'exponential'
/// (density 0.01 /m at base 0, scale_height 20), 'band' (sea mist: density 0.01, base 0,
/// thickness 5), 'ramp' (dry ice: density 1 below base 0, none above top 1) or 'table'
/// (table: a CSV path with the header height_m,extinction_per_m, or an Nx2 array of
/// those rows; linear between rows). colour: the fog's linear RGB or a grey (0.8); albedo
/// 1 (the scattering fraction, which blurs); lambda_px 8; range_unit the camera's far
/// plane.
#[pyfunction]
#[pyo3(
    signature = (*args, **kwargs),
    text_signature = "(image, depth, *, camera, time=0.0, profile='exponential', density=None, base=None, scale_height=None, thickness=None, top=None, table=None, colour=None, albedo=None, blur='diffusion', lambda_px=None, range_unit=None, sigma0=1.0, scheme='matched', precision='f32', rho_max=0.25, blur_distance=100.0, blur_falloff=1.0, blur_max=1.0)"
)]
pub(crate) fn layered_fog(
    py: Python<'_>,
    args: &Bound<'_, PyTuple>,
    kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    on_default_renderer(py, "layered_fog", args, kwargs)
}
