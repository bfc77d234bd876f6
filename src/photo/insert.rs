//! Virtual objects in foggy photos (paper 002, sec. 6-7, mixed reality): an object
//! rendered with the photo's camera (colour, coverage and distance per pixel, as Blender
//! writes an OpenEXR with its Combined RGBA and Z passes) is composited into the photo
//! where it is nearer than the photo's own surface, before the fog, so that the one
//! medium fogs object and background alike.
//!
//! Per pixel, with the object's premultiplied colour C and coverage α (OpenEXR's
//! convention) and its range R_o against the photo's range R_p:
//!
//! - the object is in front where α > 0 and R_o < R_p (an unknown R_p counts as
//!   infinitely far; the ego vehicle's R_p = 0 hides every object): the colour becomes
//!   C + (1 − α)·J_p;
//! - the range becomes R_o where the object covers at least half the pixel (α ≥ 0.5),
//!   else it stays R_p. One range per pixel cannot hold both surfaces of an edge pixel:
//!   taking the majority's keeps edges sharp in the range (no surface floating between
//!   the two) and mis-fogs only the minority's share, at most half a pixel's colour.
//!
//! Elsewhere the photo is left as it was. The object's range is in the photo's units
//! (metres for metric depth), along each pixel's ray; a depth along the optical axis
//! (Blender's Z pass) is stretched to range by the camera's intrinsics
//! ([`VirtualObject::from_depth`]).

use std::path::Path;

use super::{Photo, PreparedPhoto};
use crate::error::{Error, Result};
use crate::io::camera::Intrinsics;
use crate::io::depth::DepthKind;
use crate::medium::haze::at_known_range;
use crate::raster::{Grid, RgbImage, RgbaImage, ScalarMap};

/// An object rendered with the photo's camera.
#[derive(Clone, Debug)]
pub struct VirtualObject {
    /// Linear colour premultiplied by coverage, and the coverage α in [0, 1], row 0 at
    /// the top.
    pub rgba: RgbaImage,
    /// Range from the camera centre, in the photo's units; NaN (or ≤ 0, infinite) where
    /// the object is absent.
    pub range: ScalarMap,
    /// Its name in messages (its path).
    pub name: String,
}

/// What an insertion did, in pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Insertion {
    /// Pixels where the object is in front and covers the whole pixel (α = 1).
    pub in_front: usize,
    /// Pixels where the object is in front and covers part of the pixel (0 < α < 1).
    pub partial: usize,
    /// Pixels where the object has coverage but is behind the photo's surface.
    pub hidden: usize,
}

impl VirtualObject {
    /// An object from its premultiplied RGBA and its range; the sizes must agree. A NaN
    /// or infinite colour or coverage is refused, naming the first pixel holding one (the
    /// fog's blur would spread it over the whole frame); a negative colour is set to 0,
    /// with a warning in the log, as for colour images ([`crate::io::image`]).
    pub fn from_range(mut rgba: RgbaImage, range: ScalarMap, name: &str) -> Result<VirtualObject> {
        let width = rgba.width();
        let channels = ["R", "G", "B", "A"];
        crate::io::image::finite_light(rgba.as_mut_slice(), width, name, "object", channels)?;
        let sizes = (
            (rgba.width(), rgba.height()),
            (range.width(), range.height()),
        );
        if sizes.0 != sizes.1 {
            return Err(Error::invalid(
                "insert_depth",
                format!("{}x{}", sizes.1 .0, sizes.1 .1),
                format!(
                    "the size of the object {name} ({}x{}): render its colour and depth in one pass",
                    sizes.0 .0, sizes.0 .1
                ),
            ));
        }
        let range = range.map(|&r| {
            if r.is_finite() && r > 0.0 {
                r
            } else {
                f32::NAN
            }
        });
        Ok(VirtualObject {
            rgba,
            range,
            name: name.to_string(),
        })
    }

    /// An object from its premultiplied RGBA and its depth along the optical axis
    /// (Blender's Z pass), stretched to range by `intrinsics` (those of the photo's
    /// camera, at this size).
    pub fn from_depth(
        rgba: RgbaImage,
        depth: ScalarMap,
        intrinsics: &Intrinsics,
        name: &str,
    ) -> Result<VirtualObject> {
        let (w, h) = (depth.width(), depth.height());
        let range = Grid::from_fn(w, h, |x, y| {
            (f64::from(*depth.get(x, y)) * intrinsics.range_per_depth(x, y)) as f32
        });
        VirtualObject::from_range(rgba, range, name)
    }

    /// Loads an object: its colour and coverage from the OpenEXR `path` (the `R`, `G`,
    /// `B` of a layer as [`crate::io::image::load_linear_rgb`] finds them, and the `A`
    /// beside them, 1 if there is none), and its distance from `depth_path` (a float
    /// `.exr`, `.npy` or `Pf` `.pfm`) or, without one, from the EXR's own `Z`
    /// (`ViewLayer.Depth.Z`) or `depth` channel. `kind` says what the distance is:
    /// [`DepthKind::Depth`] (along the optical axis, as Blender's Z pass; needs
    /// `intrinsics`) or [`DepthKind::Range`].
    pub fn load(
        path: &Path,
        depth_path: Option<&Path>,
        kind: DepthKind,
        intrinsics: Option<&Intrinsics>,
    ) -> Result<VirtualObject> {
        let name = path.display().to_string();
        let (rgba, own_depth) = read_object_exr(path, depth_path.is_none())?;
        let distance = match (depth_path, own_depth) {
            (Some(p), _) => read_distance(p)?,
            (None, Some(d)) => d,
            (None, None) => {
                return Err(Error::format(
                    path,
                    "the object has no depth channel (Z, <layer>.Depth.Z or depth): give \
                     its depth map as `insert_depth`",
                ))
            }
        };
        match kind {
            DepthKind::Range => VirtualObject::from_range(rgba, distance, &name),
            DepthKind::Depth => {
                let k = intrinsics.ok_or_else(|| {
                    Error::invalid(
                        "insert_depth_kind",
                        "depth",
                        "the camera's focal length to turn depth into range: give `focal` or \
                         `fov` (the object's camera is the photo's), or `insert_depth_kind` \
                         range",
                    )
                })?;
                VirtualObject::from_depth(rgba, distance, k, &name)
            }
            other => Err(Error::invalid(
                "insert_depth_kind",
                other,
                "depth (along the optical axis, Blender's Z) or range",
            )),
        }
    }

    /// Composites the object into `image` and `range` (the photo's, at the object's
    /// size), as the module documentation says.
    pub fn composite(&self, image: &mut RgbImage, range: &mut ScalarMap) -> Result<Insertion> {
        self.check_size(image.width(), image.height())?;
        if (range.width(), range.height()) != (image.width(), image.height()) {
            return Err(Error::invalid(
                "range",
                format!("{}x{}", range.width(), range.height()),
                format!(
                    "the image's size, {}x{}: refine the prepared photo first (it upsamples)",
                    image.width(),
                    image.height()
                ),
            ));
        }
        let mut done = Insertion::default();
        let pixels = image.as_mut_slice().iter_mut().zip(range.as_mut_slice());
        let object = self.rgba.as_slice().iter().zip(self.range.as_slice());
        for ((j, r), (c, &r_o)) in pixels.zip(object) {
            let alpha = c[3].clamp(0.0, 1.0);
            if alpha <= 0.0 || r_o.is_nan() {
                continue;
            }
            // A known range hides what lies at or behind it; the ego vehicle's 0 (the
            // nearest thing there is) hides every object.
            let behind = at_known_range(*r) && r_o >= *r;
            if behind {
                done.hidden += 1;
                continue;
            }
            for k in 0..3 {
                j[k] = c[k] + (1.0 - alpha) * j[k];
            }
            if alpha >= 0.5 {
                *r = r_o;
            }
            if alpha >= 1.0 {
                done.in_front += 1;
            } else {
                done.partial += 1;
            }
        }
        Ok(done)
    }

    /// Refuses an object not of the photo's size, naming both.
    fn check_size(&self, width: usize, height: usize) -> Result<()> {
        let (w, h) = (self.rgba.width(), self.rgba.height());
        if (w, h) != (width, height) {
            return Err(Error::invalid(
                "insert",
                format!("{} ({w}x{h})", self.name),
                format!(
                    "an object rendered at the photo's size, {width}x{height}, with its camera"
                ),
            ));
        }
        Ok(())
    }
}

/// Inserts `object` into `photo` and its `prepared` range (refined to the image's size)
/// before [`super::fog()`], which then fogs it with the photo. The photo's own range
/// decides what hides the object; pre-processing's holes filled and sky found count.
/// The object is scene: pre-processing's farthest scene point (`PrepStats::r_max`) grows
/// to the object's farthest visible pixel, so that physical fog, which moves what lies
/// beyond it out with the sky ([`PreparedPhoto::metres`]), reads the object's range as
/// given.
pub fn insert(
    photo: &mut Photo,
    prepared: &mut PreparedPhoto,
    object: &VirtualObject,
) -> Result<Insertion> {
    let before = prepared.range.clone();
    let done = object.composite(&mut photo.image, &mut prepared.range)?;
    if let Some(p) = &mut prepared.prepared {
        let written = before.as_slice().iter().zip(prepared.range.as_slice());
        let farthest = written
            .filter(|(b, a)| b.to_bits() != a.to_bits())
            .map(|(_, a)| *a)
            .fold(p.stats.r_max, f32::max);
        p.stats.r_max = farthest;
    }
    Ok(done)
}

/// Whether an EXR channel's full name is a depth: `Z`, a `Z` in a layer named `Depth`
/// (Blender's `ViewLayer.Depth.Z`), or `depth`.
#[cfg(any(feature = "codecs", test))]
fn is_depth_channel(full: &str) -> bool {
    let (layer, leaf) = full.rsplit_once('.').unwrap_or(("", full));
    let depth_layer = layer.split('.').any(|p| p.eq_ignore_ascii_case("depth"));
    (leaf == "Z" && (layer.is_empty() || depth_layer)) || full.eq_ignore_ascii_case("depth")
}

/// The premultiplied RGBA of an object's EXR and, when `want_depth`, its depth channel.
#[cfg(feature = "codecs")]
fn read_object_exr(path: &Path, want_depth: bool) -> Result<(RgbaImage, Option<ScalarMap>)> {
    use crate::io::codec::exr::{parse_exr_channel, parse_exr_rgb};
    let bytes = crate::io::limits::read_file(path)?;
    if !bytes.starts_with(&crate::io::image::EXR_MAGIC) {
        return Err(Error::format(
            path,
            "not an OpenEXR file; expected the object as an EXR with R, G, B, A (and Z)",
        ));
    }
    let colour = parse_exr_rgb(&bytes, path)?;
    // The alpha beside the colour channels read: `A`, or `<layer>.A`.
    let alpha_name = match colour.source.strip_suffix(".R, .G, .B") {
        Some(layer) => format!("{layer}.A"),
        None => "A".to_string(),
    };
    let alpha = parse_exr_channel(&bytes, path, |c| c == alpha_name)?;
    let (w, h) = (colour.image.width(), colour.image.height());
    let rgba = match alpha {
        Some((_, a)) if (a.width(), a.height()) == (w, h) => {
            let a = a.as_slice();
            Grid::from_fn(w, h, |x, y| {
                let [r, g, b] = *colour.image.get(x, y);
                [r, g, b, a[y * w + x]]
            })
        }
        Some((name, a)) => {
            return Err(Error::format(
                path,
                format!(
                    "EXR alpha {name} is {}x{} but the colour is {w}x{h}",
                    a.width(),
                    a.height()
                ),
            ))
        }
        None => colour.image.opaque(),
    };
    let depth = if want_depth {
        parse_exr_channel(&bytes, path, is_depth_channel)?.map(|(_, d)| d)
    } else {
        None
    };
    Ok((rgba, depth))
}

#[cfg(not(feature = "codecs"))]
fn read_object_exr(path: &Path, _want_depth: bool) -> Result<(RgbaImage, Option<ScalarMap>)> {
    Err(Error::format(
        path,
        "reading a virtual object needs OpenEXR support: build brume with the `codecs` feature",
    ))
}

/// An object's distance map from a float file: `.exr` (its depth channel), `.npy` or a
/// one-channel `.pfm`.
fn read_distance(path: &Path) -> Result<ScalarMap> {
    use crate::io::depth::{read_exr_scalar, read_npy_scalar, read_pfm, Pfm};
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    match ext.as_str() {
        "exr" => read_exr_scalar(path),
        "npy" => read_npy_scalar(path),
        "pfm" => match read_pfm(path)? {
            Pfm::Grey(map) => Ok(map),
            Pfm::Rgb(_) => Err(Error::format(
                path,
                "PFM is `PF` (colour); expected a one-channel `Pf` depth map",
            )),
        },
        _ => Err(Error::format(
            path,
            "expected the object's depth as a float .exr, .npy or .pfm",
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::is_depth_channel;

    #[test]
    fn depth_channels_are_told_from_others() {
        for name in ["Z", "ViewLayer.Depth.Z", "depth", "Depth", "depth.Z"] {
            assert!(is_depth_channel(name), "{name}");
        }
        for name in ["R", "ViewLayer.Combined.A", "Mist.Z", "Normal.Z", "A"] {
            assert!(!is_depth_channel(name), "{name}");
        }
    }
}
