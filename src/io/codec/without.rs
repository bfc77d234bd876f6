//! The float formats of the `codecs` feature (OpenEXR, float TIFF, NumPy `.npy`/`.npz`) in a
//! build without it: the same functions, each refusing its file with what to do, so that
//! a host that needs only PNG, JPEG and PFM builds none of their crates.

use crate::error::Error;
use std::path::Path;

/// The error for a file of `format` in a build without the `codecs` feature.
fn not_built(path: &Path, format: &str) -> Error {
    Error::format(
        path,
        format!(
            "{format} needs brume's `codecs` feature, off in this build (enable it, or \
             convert the file to PFM)"
        ),
    )
}

/// OpenEXR without the `codecs` feature.
pub mod exr {
    use super::not_built;
    use crate::error::Result;
    use crate::raster::{RgbImage, RgbaImage, ScalarMap};
    use std::fs::File;
    use std::io::BufWriter;
    use std::path::Path;

    /// Refuses `path`: OpenEXR needs the `codecs` feature.
    pub fn read_exr_scalar(path: &Path) -> Result<ScalarMap> {
        Err(not_built(path, "OpenEXR"))
    }

    pub(crate) fn parse_exr_scalar(_: &[u8], path: &Path) -> Result<ScalarMap> {
        Err(not_built(path, "OpenEXR"))
    }

    /// A colour image read from an EXR file (never, in this build).
    pub(crate) struct ExrColour {
        pub image: RgbImage,
        pub source: String,
        pub chromaticities: Option<[[f64; 2]; 4]>,
    }

    pub(crate) fn parse_exr_rgb(_: &[u8], path: &Path) -> Result<ExrColour> {
        Err(not_built(path, "OpenEXR"))
    }

    pub(crate) fn exr_colour_size(_: &[u8], path: &Path) -> Result<(usize, usize)> {
        Err(not_built(path, "OpenEXR"))
    }

    pub(crate) fn exr_depth_size(_: &[u8], _: &Path) -> Option<(usize, usize)> {
        None
    }

    fn unsupported() -> std::io::Error {
        std::io::Error::new(
            std::io::ErrorKind::Unsupported,
            "writing OpenEXR needs brume's `codecs` feature, off in this build",
        )
    }

    pub(crate) fn write_rgba(
        _: &mut BufWriter<&File>,
        _: &RgbaImage,
        _: Option<[[f64; 2]; 4]>,
    ) -> std::io::Result<()> {
        Err(unsupported())
    }

    pub(crate) fn write_scalar(_: &mut BufWriter<&File>, _: &ScalarMap) -> std::io::Result<()> {
        Err(unsupported())
    }
}

/// Float TIFF without the `codecs` feature.
pub mod tiff {
    use super::not_built;
    use crate::error::Result;
    use crate::io::codec::MapSamples;
    use crate::raster::ScalarMap;
    use std::path::Path;

    /// Refuses `path`: TIFF needs the `codecs` feature.
    pub fn read_tiff_scalar(path: &Path) -> Result<ScalarMap> {
        Err(not_built(path, "TIFF"))
    }

    pub(crate) fn parse_tiff(_: &[u8], path: &Path) -> Result<MapSamples> {
        Err(not_built(path, "TIFF"))
    }

    pub(crate) fn tiff_size(_: &[u8]) -> Option<(usize, usize)> {
        None
    }
}

/// NumPy `.npy` without the `codecs` feature.
pub mod npy {
    use super::not_built;
    use crate::error::Result;
    use crate::io::codec::{MapSamples, NpzDepth};
    use crate::raster::ScalarMap;
    use std::path::Path;

    /// Refuses `path`: `.npy` needs the `codecs` feature.
    pub fn read_npy_scalar(path: &Path) -> Result<ScalarMap> {
        Err(not_built(path, "NumPy .npy"))
    }

    pub(crate) fn parse_npy(_: &[u8], path: &Path) -> Result<MapSamples> {
        Err(not_built(path, "NumPy .npy"))
    }

    pub(crate) fn parse_npz(_: &[u8], path: &Path) -> Result<NpzDepth> {
        Err(not_built(path, "NumPy .npz"))
    }

    pub(crate) fn npy_size(_: &[u8], _: &Path) -> Option<(usize, usize)> {
        None
    }
}
