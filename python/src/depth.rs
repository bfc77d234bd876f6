//! `brume.load_depth`: brume's depth loaders (`brume::io::depth`) with every option of
//! `brume render`'s depth flags as a keyword, and the loaders' messages and notes naming
//! those keywords.

use super::arrays::{scalar_map_to_py, FsPath};
use super::{keyword_of, py_err};
use brume::io::depth::{self, DepthFormat, DepthKind, DepthOptions};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// load_depth(path, camera=None, format=None, *, kind=None, scale=None, calib=None,
/// focal_px=None, baseline_mm=None, disparity_offset_px=None, near=None, far=None,
/// fov_y_deg=None, min_confidence=None, reversed_z=False) -> (range_m, info)
///
/// Reads a depth, range or disparity file as range (float32 HxW, NaN where unknown)
/// through brume's loaders. camera: a Cityscapes {name}_camera.json (else looked for
/// beside the file). format: 'auto' (default), 'kitti', 'nyu', 'tum', 'png16', 'float',
/// 'cityscapes', 'middlebury2014', 'middlebury2006', 'android-depth16', 'arcore'. kind:
/// 'depth', 'range', 'disparity', 'zbuffer' or 'inverse' (a monocular estimator's
/// relative inverse depth d: depth = 1/(d + disparity_offset_px), 0 the sky) (default:
/// the format's). scale: metres per unit of a 16-bit PNG, of a float map, of a z-buffer's
/// near and far (1 when they are in metres), or the metres of 1/(d + offset) of inverse
/// depth; a float map, a z-buffer or inverse depth then counts as metric. calib: a
/// Middlebury 2014 calib.txt (else calib.txt beside the file). focal_px and baseline_mm:
/// a disparity's stereo geometry (disparity_offset_px added to the disparity first),
/// focal_px or fov_y_deg (vertical) the intrinsics that turn depth along the optical axis
/// into range (principal point at the centre). near, far and fov_y_deg: a z-buffer's
/// projection (an OpenGL window depth in [0, 1]; near and far in the range's unit, far
/// float('inf') for an infinite far plane); reversed_z: its depth is 1 at near and 0 at
/// far (Unreal, Bevy, Godot 4), nothing drawn at 0. min_confidence: the lowest
/// confidence in [0, 1] of an Android DEPTH16 sample that is kept. info: format, kind,
/// units, metric (whether the range is in trustworthy metres, which fog with beta or
/// visibility needs), notes, unknown_pixels.
#[pyfunction]
#[pyo3(signature = (path, camera=None, format=None, *, kind=None, scale=None, calib=None, focal_px=None, baseline_mm=None, disparity_offset_px=None, near=None, far=None, fov_y_deg=None, min_confidence=None, reversed_z=false))]
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
) -> PyResult<(Py<PyAny>, Bound<'py, PyDict>)> {
    let opts = DepthOptions {
        format: match format {
            Some(f) => f.parse::<DepthFormat>().map_err(py_err)?,
            None => DepthFormat::Auto,
        },
        kind: kind
            .map(|k| k.parse::<DepthKind>())
            .transpose()
            .map_err(py_err)?,
        calib: calib.map(|p| p.0),
        camera: camera.map(|p| p.0),
        scale,
        focal: focal_px,
        baseline: baseline_mm,
        disparity_offset: disparity_offset_px,
        near,
        far,
        reversed_z,
        fov: fov_y_deg,
        min_confidence,
    };
    let loaded = py
        .detach(|| depth::load_range(&path.0, &opts))
        .map_err(py_err)?;
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
    Ok((scalar_map_to_py(py, loaded.range), info))
}
