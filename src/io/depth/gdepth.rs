//! Google's depth map metadata (`GDepth`): the depth map a phone camera's portrait or
//! lens-blur mode embeds in its JPEG (Google Camera, and the camera apps that write the
//! same XMP).
//!
//! What the specification says (<https://developers.google.com/depthmap-metadata>): the
//! XMP namespace `http://ns.google.com/photos/1.0/depthmap/` holds `Format`
//! (`RangeInverse`, the default, or `RangeLinear`), `Near` and `Far` (the depth's least
//! and greatest values, in `Units`: `m` by default, or `mm`), `Mime` (`image/png` or
//! `image/jpeg`), `Data` (that image, base64: 8 or 16 grey bits, "stretched to fit the
//! colour image") and `MeasureType` (`OpticalAxis`, the default: z-depth; or `OpticRay`:
//! range). A sample v of b bits is d_n = v / (2^b − 1), and
//!
//! - `RangeLinear`: d = Near + d_n (Far − Near);
//! - `RangeInverse`: d = Far·Near / (Far − d_n (Far − Near)) (d_n = 0 at Near, 1 at Far;
//!   more codes for near depths, as a z-buffer has).
//!
//! An XMP packet is at most 64 KB in a JPEG segment: a larger one (the depth image always
//! is, but for a tiny map) is split as Adobe's XMP specification (part 3, 1.1.3.1) says:
//! the standard packet names a GUID (`xmpNote:HasExtendedXMP`), and segments of the
//! extended packet carry that GUID, its full length and their offset in it.
//!
//! The format has no value for "unknown", and a depth map stops somewhere: a portrait
//! mode clamps the sky and everything beyond its `Far` to `Far`. Read as a depth, that
//! wall of haze at `Far` leaves the distant scene and the sky nearly clear (the phone
//! evaluation of `tools/phone_depth_eval.py --format gdepth`). So a sample at the last
//! code (d_n = 1: `Far`) is unknown, as beyond a time-of-flight sensor's reach, and
//! pre-processing finds the sky in it and carries the scene on beyond the reach; so is a
//! depth of 0 or less (a writer's code for nothing measured, with `Near` 0). A writer
//! whose `Far` is its farthest measured depth loses those samples to the hole filling,
//! which continues the scene round them. The optional confidence map is not read.
//! Android's newer Dynamic Depth container (depth as an item appended to the JPEG) is not
//! read either: such a file is refused with a message that says so.

use std::path::Path;

use base64::Engine;
use image::DynamicImage;

use super::DepthKind;
use crate::raster::{Grid, ScalarMap};
use crate::{Error, Result};

const GDEPTH_NAMESPACE: &str = "http://ns.google.com/photos/1.0/depthmap/";
const XMP_SIGNATURE: &[u8] = b"http://ns.adobe.com/xap/1.0/\0";
const EXTENDED_XMP_SIGNATURE: &[u8] = b"http://ns.adobe.com/xmp/extension/\0";
/// The GUID, full length and offset that lead each extended XMP segment's data.
const EXTENDED_HEADER: usize = 32 + 4 + 4;
/// JPEG markers: start of image, end of image, start of scan, APP1.
const SOI: u8 = 0xD8;
const EOI: u8 = 0xD9;
const SOS: u8 = 0xDA;
const APP1: u8 = 0xE1;

/// A depth map read from a JPEG's GDepth metadata.
pub(crate) struct EmbeddedDepth {
    /// The depth (or range) per sample in `units`, NaN where unknown; the embedded image's
    /// size, which may be smaller than the photo's.
    pub map: ScalarMap,
    /// What the values measure (`MeasureType`).
    pub kind: DepthKind,
    /// `m` (the file's `m` or `mm`, converted), or the file's own units.
    pub units: String,
    /// What the file said that the user should know.
    pub notes: Vec<String>,
}

/// Whether `bytes` start as a JPEG does.
fn is_jpeg(bytes: &[u8]) -> bool {
    bytes.starts_with(&[0xFF, SOI])
}

/// Whether a file is a JPEG whose XMP has a GDepth depth map (read from its header
/// segments only; any error is "no").
pub fn has_embedded_depth(path: &Path) -> bool {
    let Ok(bytes) = std::fs::read(path) else {
        return false;
    };
    is_jpeg(&bytes) && xmp_packets(&bytes, path).is_ok_and(|xmp| prefix_of(&xmp.standard).is_some())
}

/// Reads the GDepth depth map of the JPEG `bytes` (`path` names it in messages).
pub(crate) fn decode(bytes: &[u8], path: &Path) -> Result<EmbeddedDepth> {
    if !is_jpeg(bytes) {
        return Err(Error::format(
            path,
            "not a JPEG (no start-of-image marker 0xFFD8): a .jpg depth file is a phone's \
             portrait photo with its GDepth depth map",
        ));
    }
    let xmp = xmp_packets(bytes, path)?;
    let Some(prefix) = prefix_of(&xmp.standard) else {
        return Err(Error::format(
            path,
            "a JPEG holds depth only as Google's depth map metadata (GDepth, the XMP \
             namespace http://ns.google.com/photos/1.0/depthmap/ that a phone's portrait or \
             lens-blur photo carries), and this one has none (Android's Dynamic Depth \
             container is not read): expected a JPEG with GDepth, or a depth map as .png, \
             .pfm, .exr, .tif, .tiff or .npy",
        ));
    };
    let extended = xmp.extended(path)?;
    let get = |name: &str| {
        property(&xmp.standard, &prefix, name)
            .or_else(|| extended.as_deref().and_then(|e| property(e, &prefix, name)))
    };
    let required = |name: &str| {
        get(name).ok_or_else(|| {
            Error::format(
                path,
                format!("GDepth metadata without {prefix}:{name}: expected the depth map's {name}"),
            )
        })
    };
    let number = |name: &str| -> Result<f64> {
        let text = required(name)?;
        text.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| {
                Error::format(
                    path,
                    format!("GDepth {name} is {text:?}: expected a finite number"),
                )
            })
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
                format!("GDepth MeasureType is {other:?}: expected OpticalAxis or OpticRay"),
            ))
        }
    };
    let (metres_per_unit, units) = match get("Units").as_deref().map(str::trim) {
        None => {
            notes.push("GDepth without Units: metres (the format's default)".into());
            (1.0, "m".to_string())
        }
        Some("m") => (1.0, "m".to_string()),
        Some("mm") => (1e-3, "m".to_string()),
        Some(other) => {
            notes.push(format!(
                "GDepth Units {other:?} is neither m nor mm: the depth is in file units"
            ));
            (1.0, super::interpret::FILE_UNITS.to_string())
        }
    };
    let mime = required("Mime")?;
    let data = required("Data")?;
    let image = decode_data(&data, mime.trim(), path)?;
    notes.push(format!(
        "GDepth {} map, {} {format}, Near {near} Far {far}",
        image.describe(),
        mime.trim()
    ));
    let map = image.map(|d_n| {
        let depth = encoding.depth(d_n) * metres_per_unit;
        if depth > 0.0 && depth.is_finite() && d_n < 1.0 {
            depth as f32
        } else {
            f32::NAN
        }
    });
    let at_far = map.as_slice().iter().filter(|v| v.is_nan()).count();
    if at_far > 0 {
        notes.push(format!(
            "{at_far} samples at Far or below 0 m unknown: Far is where the map stops (the \
             sky and all beyond it), not a depth"
        ));
    }
    Ok(EmbeddedDepth {
        map,
        kind,
        units,
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
                format!("GDepth Near {near} and Far {far}: expected {what}"),
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
                format!("GDepth Format is {other:?}: expected RangeInverse or RangeLinear"),
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

/// The embedded depth image's samples, normalised to [0, 1].
enum Samples {
    Eight(Grid<u8>),
    Sixteen(Grid<u16>),
}

impl Samples {
    fn describe(&self) -> String {
        let (bits, w, h) = match self {
            Samples::Eight(g) => (8, g.width(), g.height()),
            Samples::Sixteen(g) => (16, g.width(), g.height()),
        };
        format!("{w}x{h} {bits}-bit")
    }

    fn map(&self, f: impl Fn(f64) -> f32) -> ScalarMap {
        match self {
            Samples::Eight(g) => g.map(|&v| f(f64::from(v) / f64::from(u8::MAX))),
            Samples::Sixteen(g) => g.map(|&v| f(f64::from(v) / f64::from(u16::MAX))),
        }
    }
}

/// Decodes the base64 `Data` (whitespace allowed: Android's encoder breaks lines) as the
/// grey image `mime` names.
fn decode_data(data: &str, mime: &str, path: &Path) -> Result<Samples> {
    let compact: Vec<u8> = data.bytes().filter(|b| !b.is_ascii_whitespace()).collect();
    let bytes = base64::engine::general_purpose::STANDARD
        .decode(&compact)
        .map_err(|e| Error::format(path, format!("GDepth Data is not base64 ({e})")))?;
    if !matches!(mime, "image/png" | "image/jpeg") {
        return Err(Error::format(
            path,
            format!("GDepth Mime is {mime:?}: expected image/png or image/jpeg"),
        ));
    }
    let name = format!("{} (its GDepth depth image)", path.display());
    Ok(match crate::io::image::decode_any(&bytes, &name)? {
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

/// The XMP of a JPEG: the standard packet (empty if none) and the segments of the
/// extended one.
struct XmpPackets<'a> {
    standard: String,
    extended: Vec<&'a [u8]>,
}

impl XmpPackets<'_> {
    /// The extended packet the standard one names, put together from its segments;
    /// `None` when it names none.
    fn extended(&self, path: &Path) -> Result<Option<String>> {
        let Some(guid) = property(&self.standard, "xmpNote", "HasExtendedXMP") else {
            return Ok(None);
        };
        let guid = guid.trim().as_bytes();
        let broken = |what: String| Error::format(path, format!("extended XMP {what}"));
        let mut packet: Vec<u8> = Vec::new();
        let mut filled = 0usize;
        for segment in self.extended.iter().filter(|s| s.starts_with(guid)) {
            let full = be_u32(&segment[32..36]) as usize;
            let offset = be_u32(&segment[36..40]) as usize;
            let chunk = &segment[EXTENDED_HEADER..];
            if full > self.extended.iter().map(|s| s.len()).sum::<usize>() {
                return Err(broken(format!(
                    "says it is {full} bytes long, more than its segments hold"
                )));
            }
            packet.resize(full, 0);
            let end = offset.checked_add(chunk.len()).filter(|&e| e <= full);
            let Some(end) = end else {
                return Err(broken(format!(
                    "segment at offset {offset} ({} bytes) ends past its length {full}",
                    chunk.len()
                )));
            };
            packet[offset..end].copy_from_slice(chunk);
            filled += chunk.len();
        }
        if packet.is_empty() || filled < packet.len() {
            return Err(broken(format!(
                "{} is incomplete: {filled} of {} bytes (a truncated file?)",
                String::from_utf8_lossy(guid),
                packet.len()
            )));
        }
        String::from_utf8(packet)
            .map(Some)
            .map_err(|_| broken("is not UTF-8 text".into()))
    }
}

fn be_u32(b: &[u8]) -> u32 {
    u32::from_be_bytes([b[0], b[1], b[2], b[3]])
}

/// The XMP segments of a JPEG's header (APP1 segments before the first scan).
fn xmp_packets<'a>(bytes: &'a [u8], path: &Path) -> Result<XmpPackets<'a>> {
    let truncated = || Error::format(path, "truncated JPEG: a header segment runs past the file");
    let mut packets = XmpPackets {
        standard: String::new(),
        extended: Vec::new(),
    };
    let mut i = 2;
    loop {
        // Markers may be preceded by fill bytes 0xFF.
        while bytes.get(i) == Some(&0xFF) && bytes.get(i + 1) == Some(&0xFF) {
            i += 1;
        }
        let (Some(&0xFF), Some(&marker)) = (bytes.get(i), bytes.get(i + 1)) else {
            return Err(Error::format(
                path,
                format!("not a JPEG header at byte {i}: expected a marker (0xFF ..)"),
            ));
        };
        if marker == SOS || marker == EOI {
            return Ok(packets);
        }
        // Markers without a length: TEM and the restart markers.
        if marker == 0x01 || (0xD0..=0xD7).contains(&marker) {
            i += 2;
            continue;
        }
        let len = bytes.get(i + 2..i + 4).ok_or_else(truncated)?;
        let len = usize::from(u16::from_be_bytes([len[0], len[1]]));
        let payload = bytes.get(i + 4..i + 2 + len.max(2)).ok_or_else(truncated)?;
        if marker == APP1 {
            if let Some(xmp) = payload.strip_prefix(XMP_SIGNATURE) {
                packets.standard = String::from_utf8_lossy(xmp).into_owned();
            } else if let Some(ext) = payload.strip_prefix(EXTENDED_XMP_SIGNATURE) {
                if ext.len() >= EXTENDED_HEADER {
                    packets.extended.push(ext);
                }
            }
        }
        i += 2 + len;
    }
}

/// The prefix the XMP binds to the GDepth namespace, if it does.
fn prefix_of(xmp: &str) -> Option<String> {
    let at = xmp.find(GDEPTH_NAMESPACE)?;
    let before = xmp[..at].trim_end_matches(['"', '\'']).trim_end();
    let before = before.strip_suffix('=')?.trim_end();
    let start = before.rfind("xmlns:")? + "xmlns:".len();
    let prefix = &before[start..];
    (!prefix.is_empty() && !prefix.contains(char::is_whitespace)).then(|| prefix.to_string())
}

/// The value of property `prefix:name` in an XMP packet: an attribute
/// (`prefix:name="value"`) or an element (`<prefix:name>value</prefix:name>`).
fn property(xmp: &str, prefix: &str, name: &str) -> Option<String> {
    let qualified = format!("{prefix}:{name}");
    if let Some(text) = element_text(xmp, &qualified) {
        return Some(text);
    }
    let mut from = 0;
    while let Some(found) = xmp[from..].find(&qualified) {
        let at = from + found;
        from = at + qualified.len();
        let preceded = xmp[..at].ends_with(|c: char| c.is_whitespace());
        let rest = xmp[from..].trim_start();
        let Some(rest) = rest.strip_prefix('=').map(str::trim_start) else {
            continue;
        };
        let Some(quote) = rest.chars().next().filter(|c| *c == '"' || *c == '\'') else {
            continue;
        };
        let value = &rest[1..];
        if preceded {
            return value.find(quote).map(|end| unescape(&value[..end]));
        }
    }
    None
}

/// The text of the first element `<qualified …>text</qualified>` (its start tag may have
/// attributes, such as a namespace declaration).
fn element_text(xmp: &str, qualified: &str) -> Option<String> {
    let open = format!("<{qualified}");
    let mut from = 0;
    while let Some(found) = xmp[from..].find(&open) {
        let after = from + found + open.len();
        from = after;
        if !xmp[after..].starts_with(|c: char| c == '>' || c == '/' || c.is_whitespace()) {
            continue;
        }
        let tag_end = after + xmp[after..].find('>')?;
        if xmp[..tag_end].ends_with('/') {
            return Some(String::new());
        }
        let text = &xmp[tag_end + 1..];
        let end = text.find(&format!("</{qualified}>"))?;
        return Some(unescape(&text[..end]));
    }
    None
}

/// The five predefined XML entities, as a property's text holds them.
fn unescape(text: &str) -> String {
    text.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&amp;", "&")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn properties_are_read_as_attributes_and_elements() {
        let xmp = r#"<rdf:Description xmlns:GDepth="http://ns.google.com/photos/1.0/depthmap/"
            GDepth:Format="RangeLinear" GDepth:Near = '1.5'>
            <GDepth:Far>12&amp;</GDepth:Far></rdf:Description>"#;
        assert_eq!(prefix_of(xmp).as_deref(), Some("GDepth"));
        assert_eq!(
            property(xmp, "GDepth", "Format").as_deref(),
            Some("RangeLinear")
        );
        assert_eq!(property(xmp, "GDepth", "Near").as_deref(), Some("1.5"));
        assert_eq!(property(xmp, "GDepth", "Far").as_deref(), Some("12&"));
        assert_eq!(property(xmp, "GDepth", "Mime"), None);
        // A longer name that starts with the one asked for is another property.
        let xmp = r#"<x GDepth:ConfidenceMime="image/png" GDepth:Mime="image/jpeg"/>"#;
        assert_eq!(
            property(xmp, "GDepth", "Mime").as_deref(),
            Some("image/jpeg")
        );
        // An element whose start tag declares its namespace, and an empty one.
        let xmp = r#"<xmpNote:HasExtendedXMP xmlns:xmpNote="http://ns.adobe.com/xmp/note/"
            >A1B2</xmpNote:HasExtendedXMP><GDepth:Near/>"#;
        let guid = property(xmp, "xmpNote", "HasExtendedXMP");
        assert_eq!(guid.as_deref(), Some("A1B2"));
        assert_eq!(property(xmp, "GDepth", "Near").as_deref(), Some(""));
    }

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
