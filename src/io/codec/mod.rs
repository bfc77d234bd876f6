//! File formats, one module each, holding a format's reader and writer side by side so
//! that a change to one is made, and seen, next to the other. Codecs turn bytes into
//! grids and back: what the values mean (depth, disparity, colour) is decided by their
//! callers in `io::depth` and `io::image`, and getting the bytes safely onto disk is
//! `io::output`'s job.

#[cfg(feature = "codecs")]
pub mod exr;
pub mod jpeg;
#[cfg(feature = "codecs")]
pub mod npy;
pub mod pfm;
pub mod png;
#[cfg(feature = "codecs")]
pub mod tiff;
#[cfg(not(feature = "codecs"))]
mod without;
#[cfg(not(feature = "codecs"))]
pub use without::{exr, npy, tiff};

/// A one-channel map's samples as a float file decodes them (`npy::parse_npy`,
/// `npy::parse_npz`, `tiff::parse_tiff`): floats, or 16-bit integers that hold what a
/// 16-bit PNG does.
#[cfg_attr(not(feature = "codecs"), allow(dead_code))]
pub(crate) enum MapSamples {
    /// float16, float32 or float64 values, as float32.
    Float(crate::raster::ScalarMap),
    /// uint16 values: no unit of their own, like a 16-bit PNG's.
    Uint16(crate::raster::Grid<u16>),
}

/// An `.npz` archive's depth map, and the focal length in pixels it holds beside it.
#[cfg_attr(not(feature = "codecs"), allow(dead_code))]
pub(crate) struct NpzDepth {
    /// The depth array's samples.
    pub samples: MapSamples,
    /// The scalar array [`NPZ_FOCAL_ARRAY`], where the archive holds one.
    pub focal_px: Option<f64>,
}

/// The name of the focal length in pixels Depth Pro's `infer` returns beside its depth:
/// an archive saved as `np.savez(path, **prediction)` holds both.
pub(crate) const NPZ_FOCAL_ARRAY: &str = "focallength_px";

#[cfg(feature = "codecs")]
impl MapSamples {
    /// The float map, where the file `path` holds one; `integers` says what else it holds
    /// and what was expected.
    pub(crate) fn floats(
        self,
        path: &std::path::Path,
        integers: &str,
    ) -> crate::Result<crate::raster::ScalarMap> {
        match self {
            MapSamples::Float(map) => Ok(map),
            MapSamples::Uint16(_) => Err(crate::Error::format(
                path,
                format!("{integers} here (a float map)"),
            )),
        }
    }
}

/// Encodes the 8-bit RGB image `bytes` (`w * h` pixels, row 0 at the top) by `encoder`,
/// with the ICC profile `icc` and the EXIF block `exif` where given.
pub(crate) fn encode_rgb8<E: image::ImageEncoder>(
    mut encoder: E,
    bytes: &[u8],
    (w, h): (u32, u32),
    icc: Option<&[u8]>,
    exif: Option<Vec<u8>>,
) -> std::io::Result<()> {
    let other = |e: image::error::UnsupportedError| std::io::Error::other(e.to_string());
    if let Some(icc) = icc {
        encoder.set_icc_profile(icc.to_vec()).map_err(other)?;
    }
    if let Some(exif) = exif {
        encoder.set_exif_metadata(exif).map_err(other)?;
    }
    encoder
        .write_image(bytes, w, h, image::ExtendedColorType::Rgb8)
        .map_err(|e| std::io::Error::other(e.to_string()))
}
