//! `brume.load_depth` and `brume.range_from_depth`: brume's depth loaders
//! (`brume::io::depth`) with every option of `brume render`'s depth flags as a keyword, and
//! the loaders' messages and notes naming those keywords.

use super::arrays::{grid_to_py, read_image, read_scalar_map, user_warning, FsPath};
use super::{keyword_of, photo_fog, py_err};
use brume::io::camera::Mount;
use brume::io::depth::{
    self, DepthFormat, DepthKind, DepthLayout, DepthOptions, LoadedDepth, PhotoGeometry, StereoView,
};
use brume::prep::stereo::mismatches_of_view;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// load_depth(path, camera=None, format=None, *, kind=None, scale=None, calib=None,
/// focal_px=None, baseline_mm=None, disparity_offset_px=None, near=None, far=None,
/// fov_y_deg=None, min_confidence=None, reversed_z=False, image=None, layout=None,
/// sky_beyond=None, camera_mount=None, stereo_view=None) -> (range_m, info)
///
/// Reads a depth, range or disparity file as range (float32 HxW, NaN where unknown) through
/// brume's loaders: PNG, PFM, EXR, TIFF, a phone's portrait JPEG, or NumPy .npy and .npz
/// (float16/32/64, or uint16 read as a 16-bit PNG; an .npz's only array or the one named
/// 'depth', as Depth Pro saves it). camera: a Cityscapes {name}_camera.json (else looked
/// for beside the file). format: 'auto' (default), 'kitti', 'nyu', 'tum', 'png16', 'float',
/// 'cityscapes', 'middlebury2014', 'middlebury2006', 'android-depth16', 'arcore', 'gdepth',
/// 'dynamic-depth' or 'apple-depth' (a phone's portrait JPEG with its depth map). kind:
/// 'depth', 'range', 'disparity', 'zbuffer', 'inverse' (a monocular estimator's relative
/// inverse depth d: depth = 1/(d + disparity_offset_px), 0 the sky) or 'affine' (its
/// affine-invariant depth d, Marigold: depth = near + d·(far − near), near and far the
/// scene's nearest and farthest depth, required; d = 1 the sky; a 16-bit PNG holds d·65535)
/// (default: the format's). scale: metres per unit of a 16-bit PNG, of a float map, of a
/// z-buffer's or affine depth's near and far (1 when they are in metres), the metres of
/// 1/(d + offset) of inverse depth, or a factor on a portrait JPEG's metres (an iPhone's
/// relative map rescaled); a float map, a z-buffer, inverse or affine depth or a portrait
/// JPEG then counts as metric. calib: a Middlebury 2014 calib.txt (else calib.txt beside
/// the file). focal_px and baseline_mm: a disparity's stereo geometry (disparity_offset_px
/// added to the disparity first), focal_px or fov_y_deg (vertical) the intrinsics that turn
/// depth along the optical axis into range (principal point at the centre). near, far and
/// fov_y_deg: a z-buffer's projection (an OpenGL window depth in [0, 1]; near and far in
/// the range's unit, far float('inf') for an infinite far plane); reversed_z: its depth is
/// 1 at near and 0 at far (Unreal, Bevy, Godot 4), nothing drawn at 0. min_confidence: the
/// lowest confidence in [0, 1] of an Android DEPTH16 sample that is kept (of a portrait
/// JPEG's sample, in its confidence map). image: the photo the map goes with (its header is
/// read, not its pixels): the map is turned upright by the photo's EXIF orientation, as
/// `brume render --image` turns both (read the photo upright too: PIL's
/// ImageOps.exif_transpose, OpenCV's imread), and the photo's EXIF 35 mm equivalent focal
/// length turns depth into range when neither focal_px nor fov_y_deg is given. layout: how
/// the map lies against that orientation, 'auto' (default), 'stored' or 'upright' (brume
/// render's --depth-layout). sky_beyond: range at or beyond which a value is unknown, the
/// sky, in the range's units (for a model that gives the sky a depth near its largest:
/// Depth Anything's metric models); by default a float map's largest value is unknown when
/// at least 1 % of its samples hold it exactly, 10 times beyond the mean of the others or
/// more (Depth Pro's sky clamped at 10 km, a renderer's background); float('inf') keeps
/// every value. camera_mount: (height_m, pitch_deg, roll_deg=0), the camera's mount over a
/// level road (pitch down, roll left side up; `brume render --camera-mount`) for a map
/// without a Cityscapes camera file, with intrinsics and metres: info's ground then gives
/// it. stereo_view: 'left' or 'right', the camera a disparity is aligned with (brume
/// render's --stereo-view; default: 'right' for a Middlebury 2014 disp1.pfm or 2006
/// disp5.png, else 'left').
/// info: format, kind, units, metric (whether the range is in trustworthy
/// metres, which fog with beta or visibility needs), notes, unknown_pixels,
/// stereo_focal_baseline (f·B in px·m of a disparity, else None) and stereo_view ('left'
/// or 'right' for a disparity, else None; give both to brume.fog as `brume render` uses
/// them), disparity_px (a stereo disparity's values in pixels as the file holds them,
/// float32 HxW, NaN where unknown: left_right_mismatches' input; else
/// None, also for a disparity turned upright by image), ground (a Cityscapes camera
/// file's mount over the road, or camera_mount's, a dict of height_m, pitch (down) and
/// roll in radians and fx, fy, cx, cy on the range's grid, else None: give it to
/// brume.fog too).
#[pyfunction]
#[pyo3(signature = (path, camera=None, format=None, *, kind=None, scale=None, calib=None, focal_px=None, baseline_mm=None, disparity_offset_px=None, near=None, far=None, fov_y_deg=None, min_confidence=None, reversed_z=false, image=None, layout=None, sky_beyond=None, camera_mount=None, stereo_view=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn load_depth<'py>(
    py: Python<'py>,
    path: FsPath,
    camera: Option<FsPath>,
    format: Option<&str>,
    kind: Option<&str>,
    scale: Option<f64>,
    calib: Option<FsPath>,
    focal_px: Option<f64>,
    baseline_mm: Option<f64>,
    disparity_offset_px: Option<f64>,
    near: Option<f64>,
    far: Option<f64>,
    fov_y_deg: Option<f64>,
    min_confidence: Option<f64>,
    reversed_z: bool,
    image: Option<FsPath>,
    layout: Option<&str>,
    sky_beyond: Option<f64>,
    camera_mount: Option<Vec<f64>>,
    stereo_view: Option<&str>,
) -> PyResult<(Py<PyAny>, Bound<'py, PyDict>)> {
    let photo = match image {
        Some(path) => Some(py.detach(|| PhotoGeometry::read(&path.0)).map_err(py_err)?),
        None => None,
    };
    let opts = DepthOptions {
        format: match format {
            Some(f) => f.parse::<DepthFormat>().map_err(py_err)?,
            None => DepthFormat::Auto,
        },
        calib: calib.map(|p| p.0),
        camera: camera.map(|p| p.0),
        min_confidence,
        photo,
        layout: match layout {
            Some(l) => l.parse::<DepthLayout>().map_err(py_err)?,
            None => DepthLayout::Auto,
        },
        // (height_m, pitch_deg, roll_deg = 0), checked as `--camera-mount` is.
        camera_mount: (camera_mount.map(|m| Mount::from_degrees(&m)))
            .transpose()
            .map_err(py_err)?,
        stereo_view: (stereo_view.map(str::parse::<StereoView>))
            .transpose()
            .map_err(py_err)?,
        ..geometry_options(
            kind,
            scale,
            [focal_px, baseline_mm, disparity_offset_px],
            [near, far, fov_y_deg],
            reversed_z,
            sky_beyond,
        )?
    };
    let (loaded, disparity) = py
        .detach(|| depth::load_range_and_disparity(&path.0, &opts))
        .map_err(py_err)?;
    let (range, info) = range_and_info(py, loaded)?;
    info.set_item("disparity_px", disparity.map(|d| grid_to_py(py, d)))?;
    Ok((range, info))
}

/// range_from_depth(depth, *, kind, scale=None, focal_px=None, baseline_mm=None,
/// disparity_offset_px=None, near=None, far=None, fov_y_deg=None, reversed_z=False,
/// sky_beyond=None) -> (range_m, info)
///
/// Reads an HxW float32, float64 or float16 array already in memory (a depth camera's frame, a
/// monocular model's output, an engine's depth buffer) as range, exactly as load_depth
/// reads a float file of it: NaN or infinite unknown, float32 HxW range out, NaN where
/// unknown. kind (required: an array does not say what it holds): 'depth' (along the
/// optical axis; focal_px or fov_y_deg turn it into range), 'range', 'disparity'
/// (focal_px and baseline_mm), 'inverse' (a monocular estimator's relative inverse depth,
/// depth = 1/(d + disparity_offset_px)), 'affine' (its affine-invariant depth, Marigold's
/// prediction: depth = near + d·(far − near), d = 1 unknown) or 'zbuffer' (near, far,
/// fov_y_deg, reversed_z).
/// The other keywords are load_depth's. info: as load_depth's (format 'float').
#[pyfunction]
#[pyo3(signature = (depth, *, kind, scale=None, focal_px=None, baseline_mm=None, disparity_offset_px=None, near=None, far=None, fov_y_deg=None, reversed_z=false, sky_beyond=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn range_from_depth<'py>(
    py: Python<'py>,
    depth: &Bound<'py, PyAny>,
    kind: &str,
    scale: Option<f64>,
    focal_px: Option<f64>,
    baseline_mm: Option<f64>,
    disparity_offset_px: Option<f64>,
    near: Option<f64>,
    far: Option<f64>,
    fov_y_deg: Option<f64>,
    reversed_z: bool,
    sky_beyond: Option<f64>,
) -> PyResult<(Py<PyAny>, Bound<'py, PyDict>)> {
    let opts = geometry_options(
        Some(kind),
        scale,
        [focal_px, baseline_mm, disparity_offset_px],
        [near, far, fov_y_deg],
        reversed_z,
        sky_beyond,
    )?;
    let map = read_scalar_map(
        depth,
        "depth",
        "depth, range, disparity or window depth",
        "one value per pixel",
        "NaN or infinite where unknown",
    )?;
    let (loaded, disparity) = py
        .detach(|| {
            // A disparity's values, as load_depth gives a file's.
            let disparity =
                (opts.kind == Some(DepthKind::Disparity)).then(|| depth::known_disparities(&map));
            let loaded = depth::range_from_map(map, "depth", &opts)?;
            Ok::<_, brume::Error>((loaded, disparity))
        })
        .map_err(py_err)?;
    let (range, info) = range_and_info(py, loaded)?;
    info.set_item("disparity_px", disparity.map(|d| grid_to_py(py, d)))?;
    Ok((range, info))
}

/// The options both functions take: what the values are, their scale, the stereo
/// geometry (focal, baseline, offset) and the projection (near, far, field of view).
fn geometry_options(
    kind: Option<&str>,
    scale: Option<f64>,
    [focal, baseline, disparity_offset]: [Option<f64>; 3],
    [near, far, fov]: [Option<f64>; 3],
    reversed_z: bool,
    sky_beyond: Option<f64>,
) -> PyResult<DepthOptions> {
    Ok(DepthOptions {
        kind: kind
            .map(|k| k.parse::<DepthKind>())
            .transpose()
            .map_err(py_err)?,
        scale,
        focal,
        baseline,
        disparity_offset,
        near,
        far,
        reversed_z,
        fov,
        sky_beyond,
        ..DepthOptions::default()
    })
}

/// The range as a numpy array and the info dict (format, kind, units, metric, notes
/// naming this package's keywords, unknown_pixels, stereo_focal_baseline, stereo_view,
/// ground).
fn range_and_info(py: Python<'_>, loaded: LoadedDepth) -> PyResult<(Py<PyAny>, Bound<'_, PyDict>)> {
    warn_of_depth_warnings(py, &loaded)?;
    let notes: Vec<String> = (loaded.notes.iter())
        .map(|n| brume::error::rename_options(n, keyword_of))
        .collect();
    let info = PyDict::new(py);
    info.set_item("format", loaded.format.to_string())?;
    info.set_item("kind", loaded.kind.to_string())?;
    info.set_item("units", loaded.units.clone())?;
    info.set_item("metric", loaded.metric)?;
    info.set_item("notes", notes)?;
    info.set_item("unknown_pixels", loaded.unknown_pixels)?;
    info.set_item("stereo_focal_baseline", loaded.stereo_focal_baseline)?;
    let view = (loaded.stereo_focal_baseline).map(|_| loaded.stereo_view.to_string());
    info.set_item("stereo_view", view)?;
    // The level road as `brume render` takes it from the file.
    let ground = brume::prep::PrepOptions::default()
        .for_depth(&loaded)
        .ground;
    let ground = ground
        .map(|g| photo_fog::ground_to_py(py, &g))
        .transpose()?;
    info.set_item("ground", ground)?;
    Ok((grid_to_py(py, loaded.range), info))
}

/// Warns (Python's `UserWarning`) of what the loader says a user must see: depth along the
/// axis taken as range for want of intrinsics, keywords given and ignored. The loaders
/// accept both with a note, but a Python caller rarely reads `info`.
fn warn_of_depth_warnings(py: Python<'_>, loaded: &LoadedDepth) -> PyResult<()> {
    for warning in loaded.warnings() {
        let message = format!(
            "depth: {}",
            brume::error::rename_options(&warning, keyword_of)
        );
        user_warning(py, message)?;
    }
    Ok(())
}

/// left_right_mismatches(image, other, disparity_px, *, stereo_view='left', threshold=None)
/// -> ndarray
///
/// Foggy Cityscapes' left-right photoconsistency check (brume render's --right): the
/// pixels of image whose disparity points to a colour of other, the stereo pair's other
/// image, that differs by more than threshold (in sRGB code values, [0, 1]; default 12/255)
/// in some channel. image and other as brume.fog takes an image (uint8/uint16 sRGB or float
/// linear, HxWx3), of one size; disparity_px: float HxW in pixels, aligned with image, NaN
/// or <= 0 where unknown (a Cityscapes disparity PNG p: (p - 1) / 256 where p > 0).
/// stereo_view: the view image and disparity_px belong to, 'left' (other is the right
/// image, the match at x - d) or 'right' (other is the left image, the match at x + d).
/// Returns a bool HxW array, True where the disparity is unreliable: set the range there to
/// NaN and brume.fog fills it from reliable neighbours. Unknown disparities, and matches
/// outside other, are False.
#[pyfunction]
#[pyo3(signature = (image, other, disparity_px, *, stereo_view="left", threshold=None))]
pub(crate) fn left_right_mismatches(
    py: Python<'_>,
    image: &Bound<'_, PyAny>,
    other: &Bound<'_, PyAny>,
    disparity_px: &Bound<'_, PyAny>,
    stereo_view: &str,
    threshold: Option<f32>,
) -> PyResult<Py<PyAny>> {
    let threshold = threshold.unwrap_or(brume::prep::stereo::DEFAULT_THRESHOLD);
    let view = stereo_view.parse::<StereoView>().map_err(py_err)?;
    let image = read_image(image)?.linear();
    let (w, h) = (image.width(), image.height());
    let other = read_image(other)?.linear();
    let disparity = read_scalar_map(
        disparity_px,
        "disparity_px",
        "disparities in pixels",
        "the image's",
        "pixels; NaN or <= 0 where unknown",
    )?;
    for (name, size) in [
        ("other", (other.width(), other.height())),
        ("disparity_px", (disparity.width(), disparity.height())),
    ] {
        if size != (w, h) {
            return Err(PyValueError::new_err(format!(
                "{name}: expected the image's size, {h}x{w} (HxW), got {}x{}",
                size.1, size.0
            )));
        }
    }
    let check = || mismatches_of_view(&image, &other, &disparity, view, threshold);
    let bad = py.detach(check).map_err(py_err)?;
    Ok(grid_to_py(py, bad))
}
