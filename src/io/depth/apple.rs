//! The depth map an iPhone's portrait photo keeps when saved as JPEG: a second JPEG after
//! the photo, listed by the photo's Multi-Picture Format index (CIPA DC-007: an APP2
//! segment `MPF\0` holding a TIFF whose MP Index IFD has one 16-byte entry per image —
//! attribute, size, and offset from that TIFF header, 0 for the photo itself — in tag
//! 0xB002). Each auxiliary image carries XMP in Apple's namespaces:
//!
//! - pixel data info (`apdi`, `http://ns.apple.com/pixeldatainfo/1.0/`): `NativeFormat`,
//!   the Core Video pixel format the camera recorded, written as the number its four
//!   characters make (`hdis`/`fdis`: disparity in 1/m, half or full float; `hdep`/`fdep`:
//!   depth in m), and how it was squeezed into the codes stored: `IntMinValue` to
//!   `IntMaxValue` spread evenly over `FloatMinValue` to `FloatMaxValue`;
//! - depth data (`depthData`, `http://ns.apple.com/depthData/1.0/`): `Accuracy`
//!   (`absolute`, or `relative`: two cameras' estimate, right in order, not in scale) and
//!   the camera's `IntrinsicMatrix` (column-major `fx 0 0 0 fy 0 cx cy 1`, in pixels of an
//!   image `IntrinsicMatrixReferenceWidth` x `IntrinsicMatrixReferenceHeight`).
//!
//! The portrait mattes (person, skin, hair, …) are auxiliary images too, with a grey
//! `NativeFormat`: not depth, skipped; so is anything else an MPF index lists (an HDR gain
//! map). The depth is taken along the optical axis, as Apple's point clouds use it with
//! the intrinsic matrix. The codes are spread over the map's own least and greatest
//! values, so some sample is always at the farthest code (the least disparity, the
//! greatest depth); where the map is clamped there — a spike of samples at it, the
//! background as far as the two cameras could tell — it is where the map stops, read as
//! unknown with the codes the JPEG moved off it (the `stop` module), so that
//! pre-processing carries the scene on beyond it. A disparity of 0 or less (infinitely
//! far) is unknown too.

use std::ops::Range;
use std::path::Path;

use super::gdepth::{decode_image, EmbeddedDepth};
use super::stop;
use super::xmp::{finite_number, prefix_of, property, xmp_packets, XmpPackets};
use super::{DepthFormat, DepthKind, Intrinsics};
use crate::{Error, Result};

/// Apple's pixel data info: what an auxiliary image's codes hold.
const PIXEL_DATA_INFO: &str = "http://ns.apple.com/pixeldatainfo/1.0/";
/// Apple's depth data: the map's accuracy and its camera's calibration.
const DEPTH_DATA: &str = "http://ns.apple.com/depthData/1.0/";
/// The MP Index IFD's tag of the image entries.
const MP_ENTRY: u16 = 0xB002;
/// The bytes of one MP entry.
const MP_ENTRY_LEN: usize = 16;

/// What an auxiliary image's codes record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Recorded {
    /// Disparity, 1/m.
    Disparity,
    /// Depth, m.
    Depth,
}

impl Recorded {
    /// The quantity of a `NativeFormat`: the number its four characters make, as Apple
    /// writes it, or the characters themselves; `None` for a format that is no depth (a
    /// matte's grey `L008`).
    fn of_native_format(format: &str) -> Option<Recorded> {
        let format = format.trim();
        let code = match format.parse::<u32>() {
            Ok(number) => number.to_be_bytes(),
            Err(_) => format.as_bytes().try_into().ok()?,
        };
        match &code {
            b"hdis" | b"fdis" => Some(Recorded::Disparity),
            b"hdep" | b"fdep" => Some(Recorded::Depth),
            _ => None,
        }
    }
}

/// The images after the first that an MPF index lists: their bytes' spans in the file.
/// `tiff` is the index (the APP2 segment's payload after `MPF\0`), which starts at byte
/// `tiff_start` of the file, the origin of the entries' offsets.
fn mpf_images(tiff: &[u8], tiff_start: usize) -> std::result::Result<Vec<Range<usize>>, String> {
    let index = exif::Reader::new()
        .read_raw(tiff.to_vec())
        .map_err(|e| format!("its Multi-Picture index is unreadable ({e})"))?;
    let tag = exif::Tag(exif::Context::Tiff, MP_ENTRY);
    let Some(field) = index.get_field(tag, exif::In::PRIMARY) else {
        return Err("its Multi-Picture index has no MP entries (tag 0xB002)".into());
    };
    let exif::Value::Undefined(entries, _) = &field.value else {
        return Err("its Multi-Picture index's MP entries (tag 0xB002) are not bytes".into());
    };
    let word = |b: &[u8]| {
        let b = [b[0], b[1], b[2], b[3]];
        if index.little_endian() {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        }
    };
    let images = entries.chunks_exact(MP_ENTRY_LEN).skip(1).map(|entry| {
        let (size, offset) = (word(&entry[4..8]) as usize, word(&entry[8..12]) as usize);
        let start = tiff_start.saturating_add(offset);
        start..start.saturating_add(size)
    });
    Ok(images.collect())
}

/// An auxiliary image of Apple's that holds depth, with its XMP's text and prefixes.
struct AppleImage<'a> {
    bytes: &'a [u8],
    xmp: String,
    apdi: String,
    recorded: Recorded,
    /// The image's place in the MPF index (2 for the first after the photo).
    number: usize,
}

/// The depth map of an iPhone portrait JPEG `bytes` (whose header `header` describes):
/// `None` if its MPF index lists no image of Apple's depth (or it has no index).
pub(super) fn decode(
    bytes: &[u8],
    header: &XmpPackets,
    path: &Path,
) -> Result<Option<EmbeddedDepth>> {
    let Some((tiff_start, tiff)) = header.mpf else {
        return Ok(None);
    };
    let broken = |what: String| Error::format(path, format!("Apple portrait JPEG: {what}"));
    let images = mpf_images(tiff, tiff_start).map_err(broken)?;
    let count = images.len() + 1;
    for (k, span) in images.into_iter().enumerate() {
        let number = k + 2;
        let Some(image) = bytes.get(span.clone()) else {
            return Err(broken(format!(
                "image {number} of {count} in its Multi-Picture index ({} bytes at byte {}) \
                 runs past the file's {} bytes (a truncated file?)",
                span.len(),
                span.start,
                bytes.len()
            )));
        };
        let header = xmp_packets(image, path).map_err(|e| {
            broken(format!(
                "image {number} of {count} in its Multi-Picture index is not a JPEG ({e})"
            ))
        })?;
        let Some(apdi) = prefix_of(&header.standard, PIXEL_DATA_INFO) else {
            continue;
        };
        let format = property(&header.standard, &apdi, "NativeFormat").unwrap_or_default();
        if let Some(recorded) = Recorded::of_native_format(&format) {
            let found = AppleImage {
                bytes: image,
                xmp: header.standard,
                apdi,
                recorded,
                number,
            };
            return to_depth(found, path).map(Some);
        }
    }
    Ok(None)
}

fn to_depth(image: AppleImage, path: &Path) -> Result<EmbeddedDepth> {
    let get = |name: &str| property(&image.xmp, &image.apdi, name);
    let number = |name: &str, default: Option<f64>| -> Result<f64> {
        let Some(text) = get(name) else {
            return default.ok_or_else(|| {
                Error::format(
                    path,
                    format!(
                        "Apple depth image (image {} of its Multi-Picture index) without \
                         apdi:{name}: expected its codes' range and the values they stand for",
                        image.number
                    ),
                )
            });
        };
        finite_number(&text, &format!("Apple depth apdi:{name}"), path)
    };
    let codes = [
        number("IntMinValue", Some(0.0))?,
        number("IntMaxValue", None)?,
    ];
    let values = [
        number("FloatMinValue", None)?,
        number("FloatMaxValue", None)?,
    ];
    if codes[0] == codes[1] || values[0] == values[1] {
        return Err(Error::format(
            path,
            format!(
                "Apple depth apdi:IntMinValue..IntMaxValue {}..{} over FloatMinValue.. \
                 FloatMaxValue {}..{}: expected two different codes and two different values",
                codes[0], codes[1], values[0], values[1]
            ),
        ));
    }
    let samples = decode_image(image.bytes, "image/jpeg", "Apple", path)?;
    let mut scale = CodeScale::new(codes, values, image.recorded);
    scale.stop = stop::lossy_stop(samples.codes().map(|code| scale.off_stop(code)));
    let map = samples.map_codes(|code| scale.depth(code).map_or(f32::NAN, |d| d as f32));
    let recorded = image.recorded;
    let what = match recorded {
        Recorded::Disparity => "disparity (1/m)",
        Recorded::Depth => "depth (m)",
    };
    let mut notes = vec![format!(
        "Apple depth image {} of the Multi-Picture index: {} {what}, codes {}..{} over {}..{}",
        image.number,
        samples.describe(),
        codes[0],
        codes[1],
        values[0],
        values[1]
    )];
    let unknown = map.as_slice().iter().filter(|v| v.is_nan()).count();
    if scale.stop.is_some() {
        notes.push(format!(
            "{unknown} samples at the farthest code (or within {} of 255 of it, where the \
             JPEG's coding moved them) or of no positive {what} unknown: the map is clamped \
             there (the background as far as the cameras could tell), not a depth",
            stop::LOSSY_STOP_CODES
        ));
    } else if unknown > 0 {
        notes.push(format!("{unknown} samples of no positive {what} unknown"));
    }
    let prefix = prefix_of(&image.xmp, DEPTH_DATA);
    let depth_data = |name: &str| prefix.as_ref().and_then(|p| property(&image.xmp, p, name));
    if depth_data("Accuracy").as_deref().map(str::trim) != Some("absolute") {
        notes.push(
            "Apple depth Accuracy is relative (or unsaid): the dual camera's estimate, right \
             in order but not in scale, so fog in physical units (beta, visibility) on it is \
             approximate; `depth_scale` rescales it to a distance known in the scene"
                .into(),
        );
    }
    let intrinsics = intrinsic_matrix(&depth_data, map.width(), map.height());
    Ok(EmbeddedDepth {
        map,
        kind: DepthKind::Depth,
        format: DepthFormat::AppleDepth,
        intrinsics,
        confidence: None,
        units: "m".into(),
        notes,
    })
}

/// How an auxiliary image's codes stand for depth: `codes[0]..codes[1]` spread evenly over
/// `values[0]..values[1]` of what it `recorded`.
struct CodeScale {
    codes: [f64; 2],
    values: [f64; 2],
    recorded: Recorded,
    /// The code of the least disparity or the greatest depth.
    farthest: f64,
    /// How near the farthest code (a fraction of the code range) a code is where the map
    /// stops, if it is clamped there ([`stop::lossy_stop`]); `None`: every code a depth.
    stop: Option<f64>,
}

impl CodeScale {
    fn new(codes: [f64; 2], values: [f64; 2], recorded: Recorded) -> CodeScale {
        let farthest = match recorded {
            Recorded::Disparity if values[0] < values[1] => codes[0],
            Recorded::Depth if values[0] > values[1] => codes[0],
            _ => codes[1],
        };
        CodeScale {
            codes,
            values,
            recorded,
            farthest,
            stop: None,
        }
    }

    /// How far `code` is from the farthest code, as a fraction of the code range.
    fn off_stop(&self, code: f64) -> f64 {
        (code - self.farthest).abs() / (self.codes[1] - self.codes[0]).abs()
    }

    /// The depth in metres of `code`; `None` where the map stops, or for no positive
    /// disparity or depth.
    fn depth(&self, code: f64) -> Option<f64> {
        let ([c0, c1], [v0, v1]) = (self.codes, self.values);
        let v = v0 + (code - c0) / (c1 - c0) * (v1 - v0);
        let depth = match self.recorded {
            Recorded::Disparity => 1.0 / v,
            Recorded::Depth => v,
        };
        let stopped = self
            .stop
            .is_some_and(|t| stop::stopped(self.off_stop(code), t));
        (!stopped && v > 0.0 && depth.is_finite()).then_some(depth)
    }
}

/// The camera's `IntrinsicMatrix` on the map's grid `width` x `height`, scaled from its
/// reference image's: `None` where it or its reference size is missing or malformed (the
/// depth then needs a field of view, as any depth along the optical axis).
fn intrinsic_matrix(
    depth_data: &dyn Fn(&str) -> Option<String>,
    width: usize,
    height: usize,
) -> Option<Intrinsics> {
    let number = |text: &str| text.trim().parse::<f64>().ok().filter(|v| v.is_finite());
    let matrix: Vec<f64> = rdf_items(&depth_data("IntrinsicMatrix")?)
        .iter()
        .map(|t| number(t))
        .collect::<Option<_>>()?;
    let reference = [
        number(&depth_data("IntrinsicMatrixReferenceWidth")?)?,
        number(&depth_data("IntrinsicMatrixReferenceHeight")?)?,
    ];
    let [fx, a, b, c, fy, d, e, f, one] = matrix[..] else {
        return None;
    };
    // Column-major, as Apple's simd matrix is kept (the principal point in the third
    // column's first two entries); a row-major writer's has it at the end of the rows.
    let (cx, cy) = match (a, b, c, d) {
        (0.0, 0.0, 0.0, 0.0) => (e, f),
        _ if (a, c, e, f) == (0.0, 0.0, 0.0, 0.0) => (b, d),
        _ => return None,
    };
    let valid = fx > 0.0 && fy > 0.0 && one == 1.0 && reference.iter().all(|&r| r > 0.0);
    let (sx, sy) = (width as f64 / reference[0], height as f64 / reference[1]);
    // A pixel's centre keeps its place in the image as the grid is scaled.
    valid.then_some(Intrinsics {
        fx: fx * sx,
        fy: fy * sy,
        cx: (cx + 0.5) * sx - 0.5,
        cy: (cy + 0.5) * sy - 0.5,
    })
}

/// The items of an `rdf:Seq` (or any `rdf:li` list) in a property's text.
fn rdf_items(text: &str) -> Vec<&str> {
    text.split("<rdf:li>")
        .skip(1)
        .filter_map(|item| item.split("</rdf:li>").next())
        .collect()
}

/// Whether the JPEG at `path`, whose first bytes are `head`, lists an image of Apple's
/// depth in its MPF index: the first [`IMAGE_HEAD_BYTES`] of each of the first
/// [`MAX_IMAGES_LOOKED_AT`] listed images are read for the pixel data info namespace and a
/// depth's `NativeFormat` (any error is "no"; [`decode`] reads the file whole and checks
/// it).
pub(super) fn has_apple_depth(path: &Path, head: &[u8]) -> bool {
    use std::io::{Read, Seek, SeekFrom};
    let Ok(header) = xmp_packets(head, path) else {
        return false;
    };
    let Some(Ok(images)) = header.mpf.map(|(start, tiff)| mpf_images(tiff, start)) else {
        return false;
    };
    let Ok(mut file) = std::fs::File::open(path) else {
        return false;
    };
    images.iter().take(MAX_IMAGES_LOOKED_AT).any(|span| {
        let mut bytes = Vec::new();
        let read = file.seek(SeekFrom::Start(span.start as u64)).and_then(|_| {
            let len = (span.len() as u64).min(IMAGE_HEAD_BYTES);
            (&mut file).take(len).read_to_end(&mut bytes)
        });
        read.is_ok() && names_apple_depth(&bytes)
    })
}

/// How much of each MPF image [`has_apple_depth`] reads: its XMP comes in its header.
const IMAGE_HEAD_BYTES: u64 = 64 << 10;

/// How many MPF images [`has_apple_depth`] looks into: an iPhone lists a handful (the
/// disparity, the mattes, a gain map), and an index of thousands of entries, each read
/// again from the file, would make the quick check slow.
const MAX_IMAGES_LOOKED_AT: usize = 32;

/// Whether an image's first bytes name the pixel data info namespace and one of the
/// `NativeFormat`s of depth, as a number or as its characters.
fn names_apple_depth(head: &[u8]) -> bool {
    let names = |text: &[u8]| head.windows(text.len()).any(|w| w == text);
    let formats: [&[u8]; 8] = [
        b"1751411059",
        b"1717856627",
        b"1751410032",
        b"1717855600",
        b"hdis",
        b"fdis",
        b"hdep",
        b"fdep",
    ];
    names(PIXEL_DATA_INFO.as_bytes()) && formats.iter().any(|code| names(code))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Codes spread evenly over the values, every one a depth; clamped at the farthest
    /// code, that code and those within 3 of 255 of it are where the map stops.
    #[test]
    fn codes_are_depths_but_where_clamped() {
        let clamped = |mut scale: CodeScale| {
            scale.stop = Some(stop::LOSSY_STOP_CODES / 255.0);
            scale
        };
        let reaching = CodeScale::new([0.0, 255.0], [0.2, 1.0], Recorded::Disparity);
        assert_eq!(reaching.depth(255.0), Some(1.0));
        let at = |code: f64| 1.0 / (0.2 + code / 255.0 * 0.8);
        for code in [0.0, 3.0, 100.0] {
            assert!(
                (reaching.depth(code).unwrap() - at(code)).abs() < 1e-12,
                "{code}"
            );
        }
        let disparity = clamped(reaching);
        for code in [0.0, 1.0, 3.0] {
            assert_eq!(disparity.depth(code), None, "{code}");
        }
        assert!((disparity.depth(4.0).unwrap() - at(4.0)).abs() < 1e-12);
        // A depth's farthest code is its greatest depth, at either end.
        let depth = clamped(CodeScale::new([0.0, 255.0], [0.5, 8.5], Recorded::Depth));
        assert_eq!(depth.depth(0.0), Some(0.5));
        assert_eq!(
            (depth.depth(253.0), depth.depth(251.0).is_some()),
            (None, true)
        );
        let reversed = clamped(CodeScale::new([0.0, 255.0], [8.5, 0.5], Recorded::Depth));
        assert_eq!(
            (reversed.depth(0.0), reversed.depth(255.0)),
            (None, Some(0.5))
        );
        // A disparity of 0 or less is infinitely far, or behind the camera: unknown.
        let through_zero = CodeScale::new([0.0, 255.0], [-0.5, 1.0], Recorded::Disparity);
        assert_eq!(through_zero.depth(50.0), None);
        assert_eq!(through_zero.depth(255.0), Some(1.0));
    }

    #[test]
    fn native_formats_are_read_as_numbers_and_characters() {
        let number = |name: &[u8; 4]| u32::from_be_bytes(*name).to_string();
        assert_eq!(
            number(b"hdis"),
            "1751411059",
            "an iPhone's portrait, as written"
        );
        for (name, recorded) in [
            (b"hdis", Recorded::Disparity),
            (b"fdis", Recorded::Disparity),
            (b"hdep", Recorded::Depth),
            (b"fdep", Recorded::Depth),
        ] {
            assert_eq!(Recorded::of_native_format(&number(name)), Some(recorded));
            let text = std::str::from_utf8(name).unwrap();
            assert_eq!(Recorded::of_native_format(text), Some(recorded));
            assert!(names_apple_depth(
                format!("{PIXEL_DATA_INFO} {}", number(name)).as_bytes()
            ));
        }
        assert_eq!(
            Recorded::of_native_format("1278226488"),
            None,
            "L008, a matte"
        );
        assert_eq!(Recorded::of_native_format("disparity"), None);
        assert!(!names_apple_depth(
            format!("{PIXEL_DATA_INFO} 1278226488").as_bytes()
        ));
    }

    /// A depth data packet's properties: `items` the matrix's, of a 4032 x 3024 reference.
    fn depth_data(items: String) -> impl Fn(&str) -> Option<String> {
        move |name: &str| match name {
            "IntrinsicMatrix" => Some(items.clone()),
            "IntrinsicMatrixReferenceWidth" => Some("4032".into()),
            "IntrinsicMatrixReferenceHeight" => Some("3024".into()),
            _ => None,
        }
    }

    #[test]
    fn the_intrinsic_matrix_is_read_in_either_order_and_scaled() {
        let seq =
            |v: [f64; 9]| -> String { v.iter().map(|x| format!("<rdf:li>{x}</rdf:li>")).collect() };
        let columns = seq([2800.0, 0.0, 0.0, 0.0, 2800.0, 0.0, 2015.5, 1511.5, 1.0]);
        let rows = seq([2800.0, 0.0, 2015.5, 0.0, 2800.0, 1511.5, 0.0, 0.0, 1.0]);
        for items in [columns, rows] {
            let k = intrinsic_matrix(&depth_data(items), 768, 576).unwrap();
            let s = 768.0 / 4032.0;
            assert!((k.fx - 2800.0 * s).abs() < 1e-9 && (k.fy - 2800.0 * s).abs() < 1e-9);
            // The reference image's centre is the map's.
            assert!((k.cx - 383.5).abs() < 1e-9, "{}", k.cx);
            assert!((k.cy - 287.5).abs() < 1e-9, "{}", k.cy);
        }
        let skewed = seq([2800.0, 3.0, 0.0, 0.0, 2800.0, 0.0, 2015.5, 1511.5, 1.0]);
        assert!(intrinsic_matrix(&depth_data(skewed), 768, 576).is_none());
        assert!(intrinsic_matrix(&depth_data("<rdf:li>1</rdf:li>".into()), 768, 576).is_none());
    }
}
