//! A stereo disparity file read back in pixels, as it was stored: what the left-right
//! check compares the two views with. The range [`super::load_range`] returns has lost the
//! disparity offset and the rounding of the file's values; the file itself has neither
//! problem, so it is read again rather than inverted.

use std::path::Path;

use super::raw::{decode_raw, Raw};
use super::{cityscapes, extension_of, png16, DepthFormat, DepthKind, DepthOptions, LoadedDepth};
use crate::raster::{Orientation, ScalarMap};
use crate::{Error, Result};

/// The disparity in pixels of the stereo depth file at `path`, which [`super::load_range`]
/// read with `opts` into `loaded`: a Cityscapes disparity ((p − 1)/256), a Middlebury 2014
/// PFM or 2006 PNG, a 16-bit PNG times `depth_scale` or a float map read as
/// [`DepthKind::Disparity`]. Row 0 at the top, on the file's grid; NaN where the file says
/// unknown (0 in a PNG, a non-finite float). A float map's values below 0 are kept: with a
/// disparity offset they give a depth (the left-right check takes them as unknown).
///
/// Errors name `depth` (the path) for a map that is not a stereo pair's disparity
/// ([`LoadedDepth::not_a_stereo_disparity`]), and the codec's errors.
pub fn load_disparity_px(
    path: &Path,
    opts: &DepthOptions,
    loaded: &LoadedDepth,
) -> Result<ScalarMap> {
    if let Some(why) = loaded.not_a_stereo_disparity() {
        return Err(Error::invalid(
            "depth",
            path.display(),
            format!("a stereo pair's disparity ({why})"),
        ));
    }
    let bytes = crate::io::limits::read_file(path)?;
    let raw = decode_raw(&bytes, path, &extension_of(path), loaded.format)?;
    disparity_of_samples(raw, path, opts, loaded)
}

/// [`super::load_range`] and, where the file holds a stereo pair's disparity, its pixels
/// as [`load_disparity_px`] reads them (`None` for other maps, as
/// [`LoadedDepth::not_a_stereo_disparity`] says), the file decoded once. The decoded
/// samples are held beside the range while it is computed: a 16-bit PNG's two bytes per
/// pixel, a float map's four.
pub fn load_range_and_disparity(
    path: &Path,
    opts: &DepthOptions,
) -> Result<(LoadedDepth, Option<ScalarMap>)> {
    let (loaded, samples) = super::load_file(path, opts, super::Keep::Samples)?;
    let disparity = match (loaded.not_a_stereo_disparity(), samples) {
        (None, Some(raw)) => Some(disparity_of_samples(raw, path, opts, &loaded)?),
        _ => None,
    };
    Ok((loaded, disparity))
}

/// The disparity in pixels of the samples decoded from `path`, which was read into
/// `loaded`: [`load_disparity_px`]'s conversions.
fn disparity_of_samples(
    raw: Raw,
    path: &Path,
    opts: &DepthOptions,
    loaded: &LoadedDepth,
) -> Result<ScalarMap> {
    // A PNG's 0 is its unknown.
    let known = |d: f64| if d > 0.0 { d as f32 } else { f32::NAN };
    match (loaded.format, raw) {
        (DepthFormat::Cityscapes, Raw::Grey16(p)) => {
            Ok(p.map(|&p| cityscapes::disparity_px(p).map_or(f32::NAN, |d| d as f32)))
        }
        (DepthFormat::Middlebury2006, Raw::Grey8(d)) => Ok(d.map(|&d| known(f64::from(d)))),
        (_, Raw::Grey16(v)) if loaded.kind == DepthKind::Disparity => {
            let scale = png16::given_scale(opts)?;
            Ok(v.map(|&v| known(f64::from(v) * scale)))
        }
        (_, Raw::Float { map, .. }) => Ok(known_disparities(&map)),
        (format, raw) => Err(Error::invalid(
            "depth",
            path.display(),
            format!(
                "a stereo pair's disparity, read as {format} ({} samples do not hold one)",
                raw.describe()
            ),
        )),
    }
}

/// A float disparity map as [`load_disparity_px`] returns one: NaN where a value is not
/// finite (a float map's unknown). For a disparity held in memory, as
/// [`super::range_from_map`] reads one.
pub fn known_disparities(map: &ScalarMap) -> ScalarMap {
    map.map(|&d| if d.is_finite() { d } else { f32::NAN })
}

impl LoadedDepth {
    /// Why this map holds no stereo pair's disparity that [`load_disparity_px`] can read
    /// back: another kind, or a disparity turned to lie on its photo (its pair is then no
    /// longer side by side); `None` for a disparity it reads.
    pub fn not_a_stereo_disparity(&self) -> Option<String> {
        if self.stereo_focal_baseline.is_some() {
            return None;
        }
        Some(
            if self.kind == DepthKind::Disparity && self.turned != Orientation::Upright {
                "this one was turned upright, so its pair is no longer side by side".to_string()
            } else {
                format!("this one was read as {} {}", self.format, self.kind)
            },
        )
    }
}
