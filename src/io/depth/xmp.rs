//! A JPEG's XMP, as phones store their depth maps' descriptions in it: the header's
//! segments, the standard packet and the extended one (Adobe's XMP specification, part 3,
//! 1.1.3.1: a packet over 64 KB is split, the standard packet naming a GUID in
//! `xmpNote:HasExtendedXMP`, each extended segment carrying that GUID, the full length
//! and its offset), a property's value, where the primary image ends (what a container
//! appends follows it), and the Multi-Picture Format index that lists the images after
//! it (CIPA DC-007: an APP2 segment `MPF\0`).

use std::path::Path;

use crate::{Error, Result};

const XMP_SIGNATURE: &[u8] = b"http://ns.adobe.com/xap/1.0/\0";
const EXTENDED_XMP_SIGNATURE: &[u8] = b"http://ns.adobe.com/xmp/extension/\0";
const MPF_SIGNATURE: &[u8] = b"MPF\0";
/// The GUID, full length and offset that lead each extended XMP segment's data.
const EXTENDED_HEADER: usize = 32 + 4 + 4;
/// JPEG markers: start of image, end of image, start of scan, APP1, APP2.
const SOI: u8 = 0xD8;
const EOI: u8 = 0xD9;
const SOS: u8 = 0xDA;
const APP1: u8 = 0xE1;
const APP2: u8 = 0xE2;

/// Whether `bytes` start as a JPEG does.
pub(super) fn is_jpeg(bytes: &[u8]) -> bool {
    bytes.starts_with(&[0xFF, SOI])
}

/// The XMP of a JPEG: the standard packet (empty if none) and the segments of the
/// extended one.
pub(super) struct XmpPackets<'a> {
    /// The standard packet, empty if there is none.
    pub standard: String,
    extended: Vec<&'a [u8]>,
    /// Where the first scan (or the end of the image) begins: the header's end.
    header_end: usize,
    /// The Multi-Picture Format index, if the header has one: the byte of the file its
    /// TIFF starts at (its entries' offsets count from there) and the TIFF.
    pub mpf: Option<(usize, &'a [u8])>,
}

impl XmpPackets<'_> {
    /// The extended packet the standard one names, put together from its segments;
    /// `None` when it names none.
    pub fn extended(&self, path: &Path) -> Result<Option<String>> {
        let Some(guid) = property(&self.standard, "xmpNote", "HasExtendedXMP") else {
            return Ok(None);
        };
        let guid = guid.trim().as_bytes();
        let broken = |what: String| Error::format(path, format!("extended XMP {what}"));
        let mut packet: Vec<u8> = Vec::new();
        let mut filled = 0usize;
        let held: usize = self.extended.iter().map(|s| s.len()).sum();
        for segment in self.extended.iter().filter(|s| s.starts_with(guid)) {
            let full = be_u32(&segment[32..36]) as usize;
            let offset = be_u32(&segment[36..40]) as usize;
            let chunk = &segment[EXTENDED_HEADER..];
            if full > held {
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
pub(super) fn xmp_packets<'a>(bytes: &'a [u8], path: &Path) -> Result<XmpPackets<'a>> {
    let truncated = || Error::format(path, "truncated JPEG: a header segment runs past the file");
    let mut packets = XmpPackets {
        standard: String::new(),
        extended: Vec::new(),
        header_end: 0,
        mpf: None,
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
            packets.header_end = i;
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
        } else if marker == APP2 && packets.mpf.is_none() {
            if let Some(tiff) = payload.strip_prefix(MPF_SIGNATURE) {
                packets.mpf = Some((i + 4 + MPF_SIGNATURE.len(), tiff));
            }
        }
        i += 2 + len;
    }
}

/// A property's `text` as a finite number, or an error that names the `property` (with its
/// format: `GDepth Near`, `Apple depth apdi:FloatMinValue`) and the text.
pub(super) fn finite_number(text: &str, property: &str, path: &Path) -> Result<f64> {
    text.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| {
            Error::format(
                path,
                format!("{property} is {text:?}: expected a finite number"),
            )
        })
}

/// The prefix the XMP binds to `namespace`, if it does.
pub(super) fn prefix_of(xmp: &str, namespace: &str) -> Option<String> {
    let at = xmp.find(namespace)?;
    let before = xmp[..at].trim_end_matches(['"', '\'']).trim_end();
    let before = before.strip_suffix('=')?.trim_end();
    let start = before.rfind("xmlns:")? + "xmlns:".len();
    let prefix = &before[start..];
    (!prefix.is_empty() && !prefix.contains(char::is_whitespace)).then(|| prefix.to_string())
}

/// The value of property `prefix:name` in an XMP packet: an attribute
/// (`prefix:name="value"`) or an element (`<prefix:name>value</prefix:name>`).
pub(super) fn property(xmp: &str, prefix: &str, name: &str) -> Option<String> {
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

/// Where the primary JPEG image of `bytes` ends (just past its end-of-image marker), from
/// its header's end: the entropy-coded data are scanned for markers (0xFF 0x00 is a
/// stuffed byte, 0xFF 0xD0-0xD7 a restart), and a progressive image's tables and further
/// scans between them are skipped by their lengths. `None` if the file ends first.
pub(super) fn primary_end(bytes: &[u8], xmp: &XmpPackets) -> Option<usize> {
    let mut i = xmp.header_end;
    loop {
        let marker = *bytes.get(i + 1)?;
        if bytes[i] != 0xFF {
            i += 1;
            continue;
        }
        match marker {
            EOI => return Some(i + 2),
            0x00 | 0xFF | 0xD0..=0xD7 => i += if marker == 0xFF { 1 } else { 2 },
            _ => {
                let len = bytes.get(i + 2..i + 4)?;
                i += 2 + usize::from(u16::from_be_bytes([len[0], len[1]]));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn properties_are_read_as_attributes_and_elements() {
        let xmp = r#"<rdf:Description xmlns:GDepth="http://ns.google.com/photos/1.0/depthmap/"
            GDepth:Format="RangeLinear" GDepth:Near = '1.5'>
            <GDepth:Far>12&amp;</GDepth:Far></rdf:Description>"#;
        let namespace = "http://ns.google.com/photos/1.0/depthmap/";
        assert_eq!(prefix_of(xmp, namespace).as_deref(), Some("GDepth"));
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
    fn the_primary_image_ends_at_its_end_of_image_marker() {
        // Header, a scan with a stuffed 0xFF and a restart, EOI, then appended bytes that
        // hold an EOI of their own.
        let jpeg = [
            &[0xFF, SOI, 0xFF, 0xE0, 0, 4, 1, 2][..],
            &[0xFF, SOS, 0, 3, 9, 7, 0xFF, 0x00, 5, 0xFF, 0xD3, 6],
            &[0xFF, EOI],
            &[1, 2, 0xFF, EOI],
        ]
        .concat();
        let xmp = xmp_packets(&jpeg, Path::new("a.jpg")).unwrap();
        assert_eq!(primary_end(&jpeg, &xmp), Some(22));
        assert_eq!(primary_end(&jpeg[..17], &xmp), None);
    }
}
