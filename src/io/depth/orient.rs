//! A depth map and its photo's EXIF: a phone stores its sensor's frame and an orientation
//! tag that viewers apply, and writes its depth (DEPTH16, GDepth, Dynamic Depth) in the
//! stored frame; brume turns the photo upright ([`crate::io::image`]) and the map with
//! it, unless the map is upright already. The tag's 35 mm equivalent focal length gives
//! the intrinsics that turn depth into range.

use std::fmt;
use std::path::Path;
use std::str::FromStr;

use super::DepthOptions;
use crate::io::image::PhotoExif;
use crate::raster::Orientation;
use crate::{Error, Result};

/// The photo a depth map goes with, as its file stores it and as its EXIF tells: its
/// stored size, and the orientation that turns it upright and its 35 mm equivalent focal
/// length. The loaders turn the map as the photo ([`DepthLayout`] says when) and take the
/// focal length where no `focal` or `fov` is given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotoGeometry {
    /// Stored width in pixels.
    pub width: usize,
    /// Stored height in pixels.
    pub height: usize,
    /// What its EXIF says: how the stored pixels turn upright, and
    /// `FocalLengthIn35mmFilm` (the focal length that gives a 35 mm film frame, 36 x 24
    /// mm, the photo's diagonal angle of view).
    pub exif: PhotoExif,
}

impl PhotoGeometry {
    /// The geometry of a photo loaded upright (`width x height`) with its EXIF.
    pub fn of_upright(width: usize, height: usize, exif: PhotoExif) -> PhotoGeometry {
        let (width, height) = if exif.orientation.swaps_axes() {
            (height, width)
        } else {
            (width, height)
        };
        PhotoGeometry {
            width,
            height,
            exif,
        }
    }

    /// The geometry of the photo at `path`, read from its header: for a host that reads
    /// the photo itself and gives brume only the depth file (it must then turn the photo
    /// upright by the same orientation, as viewers and OpenCV's `imread` do).
    pub fn read(path: &Path) -> Result<PhotoGeometry> {
        let (width, height, exif) = crate::io::image::read_photo_header(path)?;
        Ok(PhotoGeometry {
            width,
            height,
            exif,
        })
    }
}

/// How a depth map is laid out against its photo's EXIF orientation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum DepthLayout {
    /// As the photo is stored (as phones write depth), unless its shape fits only the
    /// upright photo (a map made from the photo as a viewer shows it, turned by 90°).
    #[default]
    Auto,
    /// As the photo is stored: turned with it.
    Stored,
    /// Upright already (made from the photo as viewers show it, e.g. read by OpenCV's
    /// `imread`, which applies the tag): not turned.
    Upright,
}

impl FromStr for DepthLayout {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "auto" => Ok(DepthLayout::Auto),
            "stored" => Ok(DepthLayout::Stored),
            "upright" => Ok(DepthLayout::Upright),
            _ => Err(Error::invalid("depth_layout", s, "auto, stored or upright")),
        }
    }
}

impl fmt::Display for DepthLayout {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DepthLayout::Auto => "auto",
            DepthLayout::Stored => "stored",
            DepthLayout::Upright => "upright",
        })
    }
}

/// How a `width x height` map is turned to lie on its upright photo, with a note saying
/// so: [`Orientation::Upright`] without a photo, for an upright photo, or for a map
/// upright already.
pub(super) fn turn_for_photo(
    opts: &DepthOptions,
    width: usize,
    height: usize,
    notes: &mut Vec<String>,
) -> Orientation {
    let photo = match opts.photo {
        Some(photo) if photo.exif.orientation != Orientation::Upright => photo,
        photo => {
            if opts.layout != DepthLayout::Auto {
                let why = match photo {
                    Some(_) => "the photo has no EXIF orientation to turn by",
                    None => "the map is read without its photo, as stored",
                };
                notes.push(format!("`depth_layout` {} ignored: {why}", opts.layout));
            }
            return Orientation::Upright;
        }
    };
    let orientation = photo.exif.orientation;
    let shown = orientation.describe();
    let stored = (photo.width, photo.height);
    let fits = |image| crate::refine::check_depth_size(image, (width, height)).is_ok();
    let upright_by_shape = orientation.swaps_axes() && !fits(stored) && fits((stored.1, stored.0));
    match opts.layout {
        DepthLayout::Upright => {
            notes.push(format!(
                "taken as upright (`depth_layout` upright): not {shown} with the photo"
            ));
            Orientation::Upright
        }
        DepthLayout::Auto if upright_by_shape => {
            notes.push(format!(
                "upright already (its shape is the upright photo's): not {shown} with the \
                 photo, as its EXIF orientation says"
            ));
            Orientation::Upright
        }
        DepthLayout::Auto | DepthLayout::Stored => {
            notes.push(format!(
                "{shown} with the photo, as its EXIF orientation says (the map taken as the \
                 photo is stored; `depth_layout` upright if it was made upright)"
            ));
            orientation
        }
    }
}
