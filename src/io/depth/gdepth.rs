//! The depth map a phone camera's portrait or lens-blur mode stores with its JPEG, in
//! either of Google's two formats, both described in the JPEG's XMP (`xmp`):
//!
//! - GDepth, Google's depth map metadata (<https://developers.google.com/depthmap-metadata>):
//!   the namespace `http://ns.google.com/photos/1.0/depthmap/` holds `Format`
//!   (`RangeInverse`, the default, or `RangeLinear`), `Near` and `Far` (the depth's least
//!   and greatest values, in `Units`: `m` by default, or `mm`), `Mime` (`image/png` or
//!   `image/jpeg`), `Data` (that image, base64: 8 or 16 grey bits, "stretched to fit the
//!   colour image") and `MeasureType` (`OpticalAxis`, the default: z-depth; or
//!   `OpticRay`: range). The packet is over 64 KB but for a tiny map: extended XMP.
//! - Dynamic Depth 1.0 (Android 10 on; the layout of AOSP's `dynamic_depth` library): a
//!   `Device` whose `Container:Directory` lists the items appended after the primary
//!   image, in order (`Item:Mime`, `Item:Length`, `Item:DataURI`; the primary image's
//!   length is 0), and a camera's `DepthMap` (namespace
//!   `http://ns.google.com/photos/dd/1.0/depthmap/`) with `Format`, `Near`, `Far`,
//!   `Units` (`Meters`; `Diopters`, 1/m, is refused; `None`: file units), `MeasureType`
//!   and `DepthURI`, the `DataURI` of the item that holds the depth image. The item
//!   starts after the primary image's end-of-image marker plus the lengths of the items
//!   before it.
//!
//! A sample v of b bits is d_n = v / (2^b − 1), and
//!
//! - `RangeLinear`: d = Near + d_n (Far − Near);
//! - `RangeInverse`: d = Far·Near / (Far − d_n (Far − Near)) (d_n = 0 at Near, 1 at Far;
//!   more codes for near depths, as a z-buffer has).
//!
//! Neither format has a value for "unknown", and a depth map stops somewhere: a portrait
//! mode clamps the sky and everything beyond its `Far` to `Far`. Read as a depth, that
//! wall of haze at `Far` leaves the distant scene and the sky nearly clear (the phone
//! evaluation of `tools/phone_depth_eval.py --format gdepth`). So a sample at the last
//! code (d_n = 1: `Far`) is unknown, as beyond a time-of-flight sensor's reach, and
//! pre-processing finds the sky in it and carries the scene on beyond the reach; so is a
//! depth of 0 or less (a writer's code for nothing measured, with `Near` 0). A writer
//! whose `Far` is its farthest measured depth loses those samples to the hole filling,
//! which continues the scene round them. A JPEG depth image is lossy: clamped at `Far`,
//! its codes that the coding moved off it are read as `Far` too (the `stop` module). The
//! optional confidence maps are read beside the depth, for `min_confidence` (in
//! `interpret`).
//!
//! A JPEG with neither is read as an iPhone's portrait, whose depth is an image of its
//! own after the photo (the `apple` module).
//!
//! A Dynamic Depth camera's `ImagingModel` (focal lengths in pixels of an image
//! `ImageWidth` x `ImageHeight`, the principal point as a fraction of it, 0.5 by default)
//! gives the intrinsics, scaled to the depth map's grid: depth along the optical axis
//! becomes range without a field of view (a `focal` or `fov` given wins).

use std::path::Path;

use base64::Engine;
use image::DynamicImage;

use super::xmp::XmpPackets;
use super::xmp::{finite_number, is_jpeg, prefix_of, primary_end, property, xmp_packets};
use super::{apple, stop};
use super::{DepthFormat, DepthKind, Intrinsics};
use crate::raster::{Grid, ScalarMap};
use crate::{Error, Result};

const GDEPTH_NAMESPACE: &str = "http://ns.google.com/photos/1.0/depthmap/";
const DYNAMIC_DEPTH_NAMESPACE: &str = "http://ns.google.com/photos/dd/1.0/depthmap/";
const CONTAINER_NAMESPACE: &str = "http://ns.google.com/photos/dd/1.0/container/";
const ITEM_NAMESPACE: &str = "http://ns.google.com/photos/dd/1.0/item/";
const DEVICE_NAMESPACE: &str = "http://ns.google.com/photos/dd/1.0/device/";
const IMAGING_MODEL_NAMESPACE: &str = "http://ns.google.com/photos/dd/1.0/imagingmodel/";

/// A depth map read from a phone's JPEG: its GDepth or Dynamic Depth metadata, or an
/// iPhone's depth image (the `apple` module).
pub(crate) struct EmbeddedDepth {
    /// The depth (or range) per sample in `units`, NaN where unknown; the embedded image's
    /// size, which may be smaller than the photo's.
    pub map: ScalarMap,
    /// What the values measure (`MeasureType`).
    pub kind: DepthKind,
    /// Which of the two formats described it.
    pub format: DepthFormat,
    /// The depth camera's intrinsics on the map's grid, where the file gives them
    /// (Dynamic Depth's `ImagingModel`).
    pub intrinsics: Option<Intrinsics>,
    /// Each sample's confidence in [0, 1] (the map's size), where the file has a
    /// confidence map (RangeLinear over [0, 1], both specifications say).
    pub confidence: Option<ScalarMap>,
    /// `m` (the file's units converted), or the file's own units.
    pub units: String,
    /// What the file said that the user should know.
    pub notes: Vec<String>,
}

/// Whether a file is a JPEG whose header names a depth map's namespace, GDepth's or
/// Dynamic Depth's, in its first MiB, or whose Multi-Picture index lists an image of
/// Apple's depth (any error is "no"; the depth loader reads the file whole and checks it).
pub fn has_embedded_depth(path: &Path) -> bool {
    use std::io::Read;
    // Only the head, and bounded: the image given may be a pipe or a device, which the
    // loaders read up to their limit only to refuse.
    let mut head = Vec::new();
    let read = std::fs::File::open(path).and_then(|f| f.take(HEAD_BYTES).read_to_end(&mut head));
    let names = |ns: &str| head.windows(ns.len()).any(|w| w == ns.as_bytes());
    read.is_ok()
        && is_jpeg(&head)
        && (names(GDEPTH_NAMESPACE)
            || names(DYNAMIC_DEPTH_NAMESPACE)
            || apple::has_apple_depth(path, &head))
}

/// How much of a file [`has_embedded_depth`] reads: the standard XMP packet comes in the
/// header's first segments, each at most 64 KB.
const HEAD_BYTES: u64 = 1 << 20;

/// The XMP's text, the standard packet first, then the extended one.
struct Packets<'a> {
    texts: Vec<&'a str>,
}

impl Packets<'_> {
    fn prefix(&self, namespace: &str) -> Option<String> {
        self.texts.iter().find_map(|t| prefix_of(t, namespace))
    }

    fn get(&self, prefix: &str, name: &str) -> Option<String> {
        self.texts.iter().find_map(|t| property(t, prefix, name))
    }
}

/// Where a file describes its depth map, and the depth image's bytes.
struct Described {
    format: DepthFormat,
    /// The prefix of the depth map's properties.
    prefix: String,
    image: Vec<u8>,
    mime: String,
    /// The confidence image's bytes and MIME type, if the file has one.
    confidence: Option<(Vec<u8>, String)>,
    /// Dynamic Depth's `ImagingModel` of the depth map's camera, if it has one.
    imaging_model: Option<ImagingModel>,
}

/// A Dynamic Depth camera's pinhole model: focal lengths in pixels of an image
/// `size` wide and high, the principal point as a fraction of it.
struct ImagingModel {
    focal: [f64; 2],
    size: [f64; 2],
    principal: [f64; 2],
}

impl ImagingModel {
    /// The model on a grid `width` x `height` (the depth map's, over the same view).
    fn on_grid(&self, width: usize, height: usize) -> Intrinsics {
        let (sx, sy) = (width as f64 / self.size[0], height as f64 / self.size[1]);
        // A fraction of the image's extent to the pixel index whose centre is there.
        Intrinsics {
            fx: self.focal[0] * sx,
            fy: self.focal[1] * sy,
            cx: self.principal[0] * width as f64 - 0.5,
            cy: self.principal[1] * height as f64 - 0.5,
        }
    }
}

/// Reads the depth map that the JPEG `bytes` describe in their XMP, GDepth or Dynamic
/// Depth (`path` names the file in messages).
pub(crate) fn decode(bytes: &[u8], path: &Path) -> Result<EmbeddedDepth> {
    if !is_jpeg(bytes) {
        return Err(Error::format(
            path,
            "not a JPEG (no start-of-image marker 0xFFD8): a .jpg depth file is a phone's \
             portrait photo with its depth map (GDepth, Dynamic Depth or an iPhone's)",
        ));
    }
    let xmp = xmp_packets(bytes, path)?;
    let extended = xmp.extended(path)?;
    let texts = [Some(xmp.standard.as_str()), extended.as_deref()];
    let packets = Packets {
        texts: texts.into_iter().flatten().collect(),
    };
    let described = if let Some(prefix) = packets.prefix(GDEPTH_NAMESPACE) {
        gdepth(&packets, prefix, path)?
    } else if let Some(prefix) = packets.prefix(DYNAMIC_DEPTH_NAMESPACE) {
        dynamic_depth(&packets, prefix, bytes, &xmp, path)?
    } else if let Some(depth) = apple::decode(bytes, &xmp, path)? {
        return Ok(depth);
    } else {
        let listed = match xmp.mpf {
            Some(_) => " (its Multi-Picture index lists no image of Apple's depth)",
            None => "",
        };
        return Err(Error::format(
            path,
            format!(
                "a JPEG holds depth as a phone's portrait photo does, in XMP that describes \
                 it (GDepth: http://ns.google.com/photos/1.0/depthmap/, or Dynamic Depth: \
                 http://ns.google.com/photos/dd/1.0/depthmap/) or as an iPhone's auxiliary \
                 image (Apple's http://ns.apple.com/pixeldatainfo/1.0/ in a Multi-Picture \
                 Format image), and this one has none{listed}: expected such a JPEG, or a \
                 depth map as .png, .pfm, .exr, .tif, .tiff or .npy"
            ),
        ));
    };
    to_depth(described, &packets, path)
}

/// GDepth: the properties, and the depth image from `Data`.
fn gdepth(packets: &Packets, prefix: String, path: &Path) -> Result<Described> {
    let get = |name: &str| packets.get(&prefix, name);
    let required =
        |name: &str| get(name).ok_or_else(|| missing(DepthFormat::Gdepth, &prefix, name, path));
    let mime = required("Mime")?;
    let image = base64_property("Data", &required("Data")?, path)?;
    let confidence = match get("Confidence") {
        Some(data) => {
            let mime = get("ConfidenceMime").unwrap_or_else(|| "image/png".into());
            Some((
                base64_property("Confidence", &data, path)?,
                mime.trim().to_string(),
            ))
        }
        None => None,
    };
    Ok(Described {
        format: DepthFormat::Gdepth,
        prefix,
        image,
        mime: mime.trim().to_string(),
        confidence,
        imaging_model: None,
    })
}

/// A base64 property's bytes (whitespace allowed: Android's encoder breaks lines).
fn base64_property(name: &str, data: &str, path: &Path) -> Result<Vec<u8>> {
    let compact: Vec<u8> = data.bytes().filter(|b| !b.is_ascii_whitespace()).collect();
    base64::engine::general_purpose::STANDARD
        .decode(&compact)
        .map_err(|e| Error::format(path, format!("GDepth {name} is not base64 ({e})")))
}

/// Dynamic Depth: the depth map's properties, and its item from the container appended
/// after the primary image.
fn dynamic_depth(
    packets: &Packets,
    prefix: String,
    bytes: &[u8],
    xmp: &XmpPackets,
    path: &Path,
) -> Result<Described> {
    let uri = packets
        .get(&prefix, "DepthURI")
        .ok_or_else(|| missing(DepthFormat::DynamicDepth, &prefix, "DepthURI", path))?;
    let broken = |what: String| Error::format(path, format!("Dynamic Depth {what}"));
    let items = container_items(packets);
    let Some(index) = items
        .iter()
        .position(|i| i.uri.as_deref() == Some(uri.trim()))
    else {
        return Err(broken(format!(
            "DepthURI {uri:?} names no item of its Container:Directory ({} items)",
            items.len()
        )));
    };
    let start = primary_end(bytes, xmp)
        .ok_or_else(|| broken("file ends inside its primary image".into()))?;
    // An item's bytes: after the primary image, past the items before it.
    let payload = |index: usize, what: &str| -> Result<Vec<u8>> {
        let offset = items[..index]
            .iter()
            .fold(0usize, |o, item| o.saturating_add(item.length));
        let length = items[index].length;
        start
            .checked_add(offset)
            .and_then(|from| bytes.get(from..from.checked_add(length)?))
            .map(<[u8]>::to_vec)
            .ok_or_else(|| {
                broken(format!(
                    "{what} item of {length} bytes at {offset} after the primary image runs \
                     past the file ({} bytes after it): a truncated file?",
                    bytes.len() - start
                ))
            })
    };
    let confidence_uri = packets.get(&prefix, "ConfidenceURI");
    let confidence = match confidence_uri.as_deref().map(str::trim) {
        Some(uri) if !uri.is_empty() => {
            let Some(at) = items.iter().position(|i| i.uri.as_deref() == Some(uri)) else {
                return Err(broken(format!(
                    "ConfidenceURI {uri:?} names no item of its Container:Directory"
                )));
            };
            Some((payload(at, "confidence")?, items[at].mime.clone()))
        }
        _ => None,
    };
    Ok(Described {
        format: DepthFormat::DynamicDepth,
        imaging_model: imaging_model(packets, &prefix, path)?,
        prefix,
        image: payload(index, "depth")?,
        mime: items[index].mime.clone(),
        confidence,
    })
}

/// The `ImagingModel` of the camera whose `DepthMap` this is (the `Device:Camera` element
/// round its `DepthURI`; the whole packet without a `Device` namespace), if it has one:
/// focal lengths and image size required, positive and finite; principal point 0.5, 0.5
/// unless given.
fn imaging_model(packets: &Packets, prefix: &str, path: &Path) -> Result<Option<ImagingModel>> {
    let Some(model) = packets.prefix(IMAGING_MODEL_NAMESPACE) else {
        return Ok(None);
    };
    let device = packets.prefix(DEVICE_NAMESPACE);
    let Some(camera) = packets.texts.iter().find_map(|text| {
        let at = text.find(&format!("{prefix}:DepthURI"))?;
        let Some(device) = &device else {
            return Some(*text);
        };
        let open = format!("<{device}:Camera");
        let start = text[..at].rfind(&open)?;
        let end = text[at..]
            .find(&format!("</{device}:Camera>"))
            .map_or(text.len(), |e| at + e);
        Some(&text[start..end])
    }) else {
        return Ok(None);
    };
    let value = |name: &str, default: Option<f64>| -> Result<Option<f64>> {
        let Some(text) = property(camera, &model, name) else {
            return Ok(default);
        };
        let v = text
            .trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && *v > 0.0);
        v.map(Some).ok_or_else(|| {
            Error::format(
                path,
                format!(
                    "Dynamic Depth ImagingModel {name} is {text:?}: expected a positive number"
                ),
            )
        })
    };
    let required = [
        value("FocalLengthX", None)?,
        value("FocalLengthY", None)?,
        value("ImageWidth", None)?,
        value("ImageHeight", None)?,
    ];
    let [Some(fx), Some(fy), Some(w), Some(h)] = required else {
        return Ok(None);
    };
    let principal = [
        value("PrincipalPointX", Some(0.5))?.unwrap_or(0.5),
        value("PrincipalPointY", Some(0.5))?.unwrap_or(0.5),
    ];
    Ok(Some(ImagingModel {
        focal: [fx, fy],
        size: [w, h],
        principal,
    }))
}

/// One `Container:Item` of a Dynamic Depth directory.
struct Item {
    mime: String,
    length: usize,
    uri: Option<String>,
}

/// The items of the `Container:Directory`, in order (unreadable lengths as 0).
fn container_items(packets: &Packets) -> Vec<Item> {
    let (Some(container), Some(item)) = (
        packets.prefix(CONTAINER_NAMESPACE),
        packets.prefix(ITEM_NAMESPACE),
    ) else {
        return Vec::new();
    };
    let open = format!("<{container}:Item");
    let mut items = Vec::new();
    for text in &packets.texts {
        let starts: Vec<usize> = text.match_indices(&open).map(|(at, _)| at).collect();
        for (k, &at) in starts.iter().enumerate() {
            let end = starts.get(k + 1).copied().unwrap_or(text.len());
            let chunk = &text[at..end];
            let get = |name: &str| property(chunk, &item, name).map(|v| v.trim().to_string());
            items.push(Item {
                mime: get("Mime").unwrap_or_default(),
                length: get("Length").and_then(|l| l.parse().ok()).unwrap_or(0),
                uri: get("DataURI"),
            });
        }
    }
    items
}

fn missing(format: DepthFormat, prefix: &str, name: &str, path: &Path) -> Error {
    Error::format(
        path,
        format!(
            "{} metadata without {prefix}:{name}: expected the depth map's {name}",
            name_of(format)
        ),
    )
}

/// The format's name in messages.
fn name_of(format: DepthFormat) -> &'static str {
    match format {
        DepthFormat::DynamicDepth => "Dynamic Depth",
        _ => "GDepth",
    }
}

/// The depth map a file describes, read as its properties say.
fn to_depth(described: Described, packets: &Packets, path: &Path) -> Result<EmbeddedDepth> {
    let Described {
        format: depth_format,
        prefix,
        image,
        mime,
        confidence,
        imaging_model,
    } = described;
    let format_name = name_of(depth_format);
    let get = |name: &str| packets.get(&prefix, name);
    let number = |name: &str| -> Result<f64> {
        let text = get(name).ok_or_else(|| missing(depth_format, &prefix, name, path))?;
        finite_number(&text, &format!("{format_name} {name}"), path)
    };
    let mut notes = Vec::new();
    let format = get("Format").unwrap_or_else(|| "RangeInverse".into());
    let (near, far) = (number("Near")?, number("Far")?);
    let encoding = Encoding::new(format.trim(), near, far, path)?;
    let kind = match get("MeasureType").as_deref().map(str::trim) {
        None | Some("OpticalAxis") => DepthKind::Depth,
        Some("OpticRay") => DepthKind::Range,
        Some(other) => {
            return Err(Error::format(
                path,
                format!("{format_name} MeasureType is {other:?}: expected OpticalAxis or OpticRay"),
            ))
        }
    };
    let units = get("Units").map(|u| u.trim().to_string());
    let (to_metres, unit_name): (fn(f64) -> f64, &str) = match units.as_deref() {
        None => {
            notes.push(format!("{format_name} without Units: metres (the default)"));
            (|d| d, "m")
        }
        Some("m" | "Meters") => (|d| d, "m"),
        Some("mm") => (|d| d * 1e-3, "m"),
        Some("Diopters") => {
            return Err(Error::format(
                path,
                format!(
                    "{format_name} Units Diopters (inverse metres) are not read: expected \
                     Meters (GDepth: m or mm)"
                ),
            ))
        }
        Some(other) => {
            notes.push(format!(
                "{format_name} Units {other:?} is not a length: the depth is in file units"
            ));
            (|d| d, super::interpret::FILE_UNITS)
        }
    };
    let samples = decode_image(&image, &mime, format_name, path)?;
    notes.push(format!(
        "{format_name} {} map, {mime} {format}, Near {near} Far {far}",
        samples.describe(),
    ));
    // Far is where the map stops, whether many samples are at it or few; in a JPEG, so
    // are the codes its coding moved off it, if the map is clamped there.
    let top = samples.top_code();
    let tolerance = match mime == "image/jpeg" {
        true => stop::lossy_stop(samples.codes().map(|v| (top - v) / top)).unwrap_or(0.0),
        false => 0.0,
    };
    let map = samples.map(|d_n| {
        let depth = to_metres(encoding.depth(d_n));
        if depth > 0.0 && depth.is_finite() && !stop::stopped(1.0 - d_n, tolerance) {
            depth as f32
        } else {
            f32::NAN
        }
    });
    let at_far = map.as_slice().iter().filter(|v| v.is_nan()).count();
    if at_far > 0 {
        let near_far = match tolerance > 0.0 {
            true => format!(
                " (or within {} codes of it: a JPEG depth image clamped at Far)",
                stop::LOSSY_STOP_CODES
            ),
            false => String::new(),
        };
        notes.push(format!(
            "{at_far} samples at Far{near_far} or below 0 m unknown: Far is where the map \
             stops (the sky and all beyond it), not a depth"
        ));
    }
    let intrinsics = imaging_model.map(|m| m.on_grid(map.width(), map.height()));
    let confidence = match confidence {
        Some((bytes, mime)) => {
            let what = format!("{format_name} confidence");
            let samples = decode_image(&bytes, &mime, &what, path)?;
            let c = samples.map(|c| c as f32);
            if (c.width(), c.height()) != (map.width(), map.height()) {
                return Err(Error::format(
                    path,
                    format!(
                        "{what} map is {}x{}: expected the depth map's size, {}x{}",
                        c.width(),
                        c.height(),
                        map.width(),
                        map.height()
                    ),
                ));
            }
            Some(c)
        }
        None => None,
    };
    Ok(EmbeddedDepth {
        confidence,
        intrinsics,
        map,
        kind,
        format: depth_format,
        units: unit_name.to_string(),
        notes,
    })
}

/// The depth of a normalised sample d_n ∈ [0, 1], by the file's `Format`.
enum Encoding {
    Linear { near: f64, far: f64 },
    Inverse { near: f64, far: f64 },
}

impl Encoding {
    fn new(format: &str, near: f64, far: f64, path: &Path) -> Result<Encoding> {
        let bad = |what: &str| {
            Error::format(
                path,
                format!("depth map's Near {near} and Far {far}: expected {what}"),
            )
        };
        match format {
            "RangeLinear" if near == far => Err(bad("two different depths")),
            "RangeLinear" => Ok(Encoding::Linear { near, far }),
            "RangeInverse" if !(near > 0.0 && far > near) => {
                Err(bad("0 < Near < Far for RangeInverse"))
            }
            "RangeInverse" => Ok(Encoding::Inverse { near, far }),
            other => Err(Error::format(
                path,
                format!("depth map's Format is {other:?}: expected RangeInverse or RangeLinear"),
            )),
        }
    }

    fn depth(&self, d_n: f64) -> f64 {
        match *self {
            Encoding::Linear { near, far } => near + d_n * (far - near),
            Encoding::Inverse { near, far } => far * near / (far - d_n * (far - near)),
        }
    }
}

/// The embedded depth image's samples, of 8 or 16 bits.
pub(super) enum Samples {
    Eight(Grid<u8>),
    Sixteen(Grid<u16>),
}

impl Samples {
    pub(super) fn describe(&self) -> String {
        let (bits, w, h) = match self {
            Samples::Eight(g) => (8, g.width(), g.height()),
            Samples::Sixteen(g) => (16, g.width(), g.height()),
        };
        format!("{w}x{h} {bits}-bit")
    }

    /// `f` of each sample's d_n = v / (2^bits − 1).
    fn map(&self, f: impl Fn(f64) -> f32) -> ScalarMap {
        match self {
            Samples::Eight(g) => g.map(|&v| f(f64::from(v) / f64::from(u8::MAX))),
            Samples::Sixteen(g) => g.map(|&v| f(f64::from(v) / f64::from(u16::MAX))),
        }
    }

    /// `f` of each sample's code v.
    pub(super) fn map_codes(&self, f: impl Fn(f64) -> f32) -> ScalarMap {
        match self {
            Samples::Eight(g) => g.map(|&v| f(f64::from(v))),
            Samples::Sixteen(g) => g.map(|&v| f(f64::from(v))),
        }
    }

    /// Each sample's code v.
    pub(super) fn codes(&self) -> Box<dyn Iterator<Item = f64> + '_> {
        match self {
            Samples::Eight(g) => Box::new(g.as_slice().iter().map(|&v| f64::from(v))),
            Samples::Sixteen(g) => Box::new(g.as_slice().iter().map(|&v| f64::from(v))),
        }
    }

    /// The greatest code: 2^bits − 1.
    pub(super) fn top_code(&self) -> f64 {
        match self {
            Samples::Eight(_) => f64::from(u8::MAX),
            Samples::Sixteen(_) => f64::from(u16::MAX),
        }
    }
}

/// Decodes the depth image (the grey image `mime` names).
pub(super) fn decode_image(
    bytes: &[u8],
    mime: &str,
    format_name: &str,
    path: &Path,
) -> Result<Samples> {
    if !matches!(mime, "image/png" | "image/jpeg") {
        return Err(Error::format(
            path,
            format!(
                "{format_name} depth image's Mime is {mime:?}: expected image/png or image/jpeg"
            ),
        ));
    }
    let name = format!("{} (its {format_name} depth image)", path.display());
    // Left to the decoder to report when its header cannot be read.
    let _reserved = match crate::io::image::image_dimensions(bytes, &name) {
        Ok((w, h)) => {
            let (w, h) = (w as usize, h as usize);
            Some(crate::io::limits::check_map_decoding_fits(&name, w, h, 0)?)
        }
        Err(_) => None,
    };
    Ok(match crate::io::image::decode_any(bytes, &name)? {
        DynamicImage::ImageLuma8(g) => Samples::Eight(grid(g)),
        DynamicImage::ImageLuma16(g) => Samples::Sixteen(grid(g)),
        // A grey picture saved in colour (Android's Bitmap.compress writes JPEG as YCbCr).
        image if image.color().bits_per_pixel() / u16::from(image.color().channel_count()) > 8 => {
            Samples::Sixteen(grid(image.to_luma16()))
        }
        image => Samples::Eight(grid(image.to_luma8())),
    })
}

fn grid<T: image::Primitive>(img: image::ImageBuffer<image::Luma<T>, Vec<T>>) -> Grid<T> {
    let (w, h) = (img.width() as usize, img.height() as usize);
    Grid::from_vec(w, h, img.into_raw())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_encodings_are_the_specifications() {
        let path = Path::new("x.jpg");
        let linear = Encoding::new("RangeLinear", 2.0, 10.0, path).unwrap();
        assert_eq!(linear.depth(0.0), 2.0);
        assert_eq!(linear.depth(0.5), 6.0);
        assert_eq!(linear.depth(1.0), 10.0);
        let inverse = Encoding::new("RangeInverse", 2.0, 10.0, path).unwrap();
        assert_eq!(inverse.depth(0.0), 2.0);
        assert_eq!(inverse.depth(1.0), 10.0);
        // Encoding d = 4 as the specification does: d_n = Far (d − Near) / (d (Far − Near)).
        let d_n = 10.0 * (4.0 - 2.0) / (4.0 * (10.0 - 2.0));
        assert!((inverse.depth(d_n) - 4.0).abs() < 1e-12);
        assert!(Encoding::new("RangeInverse", 0.0, 10.0, path).is_err());
        assert!(Encoding::new("RangeLinear", 3.0, 3.0, path).is_err());
        assert!(Encoding::new("Disparity", 1.0, 3.0, path).is_err());
    }
}
