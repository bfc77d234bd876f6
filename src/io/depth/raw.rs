//! A depth file decoded by its codec but not yet interpreted: the sample type is known
//! (8-bit, 16-bit or float), what the values measure is not.

use std::path::Path;

use super::gdepth::{self, EmbeddedDepth};
use super::{DepthFormat, DepthKind};
use crate::io::codec::exr::{exr_depth_size, parse_exr_scalar};
use crate::io::codec::npy::{npy_size, parse_npy, parse_npz};
use crate::io::codec::pfm::{parse_header, parse_pfm, Pfm};
use crate::io::codec::png::{self, GreyPng};
use crate::io::codec::tiff::{parse_tiff, tiff_size};
use crate::io::codec::MapSamples;
use crate::io::limits::check_map_decoding_fits;
use crate::io::png_chunks::{png_ihdr_size, PNG_IHDR_END};
use crate::memory::Reservation;
use crate::raster::{Grid, ScalarMap};
use crate::{Error, Result};

/// A depth file decoded but not yet interpreted.
pub(super) enum Raw {
    /// 8-bit grey PNG samples.
    Grey8(Grid<u8>),
    /// 16-bit grey PNG samples, or a uint16 NumPy array's.
    Grey16(Grid<u16>),
    /// Float samples; a PFM may be a Middlebury 2014 disparity, other float files may not.
    /// `focal_px`: the focal length an `.npz` archive holds beside the map (Depth Pro's
    /// `focallength_px`), on the map's grid.
    Float {
        map: ScalarMap,
        from_pfm: bool,
        focal_px: Option<f64>,
    },
    /// A depth map a phone's JPEG embeds (GDepth, Dynamic Depth, Apple's), decoded by its
    /// own rules.
    Embedded(EmbeddedDepth),
}

impl Raw {
    /// A copy of the samples as decoded; `None` for an embedded map (decoded by its own
    /// rules, never a stereo pair's disparity).
    pub(super) fn samples(&self) -> Option<Raw> {
        match self {
            Raw::Grey8(g) => Some(Raw::Grey8(g.clone())),
            Raw::Grey16(g) => Some(Raw::Grey16(g.clone())),
            Raw::Float {
                map,
                from_pfm,
                focal_px,
            } => Some(Raw::Float {
                map: map.clone(),
                from_pfm: *from_pfm,
                focal_px: *focal_px,
            }),
            Raw::Embedded(_) => None,
        }
    }

    /// The kind of file, for messages.
    pub(super) fn describe(&self) -> &'static str {
        match self {
            Raw::Grey8(_) => "an 8-bit PNG",
            Raw::Grey16(_) => "16-bit integers (a PNG, a 16-bit TIFF or a uint16 array)",
            Raw::Float { from_pfm: true, .. } => "a float PFM",
            Raw::Float { .. } => "a float map",
            Raw::Embedded(e) => match e.format {
                DepthFormat::Gdepth => "a JPEG's GDepth depth map",
                DepthFormat::AppleDepth => "an iPhone portrait JPEG's depth image",
                _ => "a JPEG's Dynamic Depth depth map",
            },
        }
    }

    /// Width and height in pixels.
    pub(super) fn size(&self) -> (usize, usize) {
        match self {
            Raw::Grey8(g) => (g.width(), g.height()),
            Raw::Grey16(g) => (g.width(), g.height()),
            Raw::Float { map, .. } => (map.width(), map.height()),
            Raw::Embedded(e) => (e.map.width(), e.map.height()),
        }
    }

    /// What the file itself says its values measure, where it says it.
    pub(super) fn measured_kind(&self) -> Option<DepthKind> {
        match self {
            Raw::Embedded(e) => Some(e.kind),
            _ => None,
        }
    }
}

/// Decodes `bytes` with the codec for extension `ext`; a JPEG only as GDepth, which
/// `format` must allow (the others' layouts are checked once the file is decoded).
pub(super) fn decode_raw(bytes: &[u8], path: &Path, ext: &str, format: DepthFormat) -> Result<Raw> {
    let _reserved = check_decoding_fits(bytes, path, ext)?;
    match ext {
        "png" => Ok(match png::decode_grey(bytes, path)? {
            GreyPng::Grey8(g) => Raw::Grey8(g),
            GreyPng::Grey16(g) => Raw::Grey16(g),
        }),
        // A colour PFM is refused from its header, before its three channels are decoded.
        "pfm" if parse_header(bytes, path)?.channels != 1 => Err(colour_pfm(path)),
        "pfm" => match parse_pfm(bytes, path)? {
            Pfm::Grey(map) => Ok(Raw::Float {
                map,
                from_pfm: true,
                focal_px: None,
            }),
            Pfm::Rgb(_) => Err(colour_pfm(path)),
        },
        "exr" => Ok(from_samples(
            MapSamples::Float(parse_exr_scalar(bytes, path)?),
            None,
        )),
        "tif" | "tiff" => Ok(from_samples(parse_tiff(bytes, path)?, None)),
        "npy" => Ok(from_samples(parse_npy(bytes, path)?, None)),
        "npz" => {
            let archive = parse_npz(bytes, path)?;
            Ok(from_samples(archive.samples, archive.focal_px))
        }
        "jpg" | "jpeg"
            if !matches!(
                format,
                DepthFormat::Auto
                    | DepthFormat::Gdepth
                    | DepthFormat::DynamicDepth
                    | DepthFormat::AppleDepth
            ) =>
        {
            Err(Error::format(
                path,
                format!(
                    "`depth_format` {format} expects {}, found a JPEG",
                    format.rule().layout.expected()
                ),
            ))
        }
        "jpg" | "jpeg" => Ok(Raw::Embedded(gdepth::decode(bytes, path)?)),
        _ => {
            crate::io::image::refuse_heif_bytes(bytes, &path.display().to_string())?;
            Err(Error::format(
                path,
                format!(
                    "unknown depth file extension `{ext}`; expected .png, .pfm, .exr, .tif, \
                     .tiff, .npy, .npz, or a .jpg with its depth (a phone's portrait photo)"
                ),
            ))
        }
    }
}

fn colour_pfm(path: &Path) -> Error {
    Error::format(
        path,
        "PFM is `PF` (3 colour channels); a depth or disparity PFM must be `Pf` (1 channel)",
    )
}

/// Refuses a depth file whose decoding cannot fit in the memory left, from the size its
/// header gives, before the decoder allocates for it. Files whose header cannot be read
/// are left to the decoder's error; an `.npz` member and a phone JPEG's depth image are
/// checked as they are reached ([`parse_npz`], [`gdepth::decode_image`]).
fn check_decoding_fits(bytes: &[u8], path: &Path, ext: &str) -> Result<Option<Reservation>> {
    let size = match ext {
        "png" => bytes
            .first_chunk::<PNG_IHDR_END>()
            .and_then(png_ihdr_size)
            .map(|(w, h)| (w as usize, h as usize)),
        "pfm" => parse_header(bytes, path).ok().map(|h| (h.width, h.height)),
        "exr" => exr_depth_size(bytes, path),
        "tif" | "tiff" => tiff_size(bytes),
        "npy" => npy_size(bytes, path),
        _ => None,
    };
    let Some((w, h)) = size else {
        return Ok(None);
    };
    check_map_decoding_fits(&path.display().to_string(), w, h, 0).map(Some)
}

/// A float or integer file's samples (EXR, TIFF, NumPy): uint16 ones as a 16-bit PNG's,
/// which hold the same; floats with the focal length in pixels an archive held beside them.
fn from_samples(array: MapSamples, focal_px: Option<f64>) -> Raw {
    match array {
        MapSamples::Float(map) => Raw::Float {
            map,
            from_pfm: false,
            focal_px,
        },
        MapSamples::Uint16(grid) => Raw::Grey16(grid),
    }
}
