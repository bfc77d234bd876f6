//! What brume reads from a PNG's chunks itself, before the png crate decodes it: checks
//! that keep the decoder from panicking or inflating without bound, the size in its first
//! chunk, and the colour space the file states without an ICC profile (`cICP`, `sRGB`,
//! `gAMA`, `cHRM`), which the image crate does not report.
//!
//! Colour, by the precedence of the PNG specification (third edition, 2025): `cICP`, then
//! an ICC profile (`iCCP`), then `sRGB`, then `gAMA` and `cHRM`.
//!
//! - `cICP` (coding-independent code points, ITU-T H.273): BT.709, Display P3, DCI-P3 or
//!   BT.2020 primaries with any curve moxcms evaluates (sRGB's, linear, BT.709's, a
//!   gamma). PQ and HLG (HDR) are refused: brume fogs standard-range light, and values
//!   decoded as standard range would be wrong everywhere. Others are ignored with a
//!   warning, and the next chunk in precedence decides.
//! - `gAMA` and `cHRM`: a gamma significantly different from sRGB's 1/2.2 decodes by its
//!   power curve (`gAMA` 1.0: linear light), chromaticities other than sRGB's are the
//!   primaries. A gamma within libpng's threshold of 1/2.2 (5 %) is read as sRGB's curve,
//!   as libpng's simplified reader does: tools write `gAMA` 0.45455 on sRGB images as a
//!   fallback, and decoding those by a pure power would move their dark codes (code 10 to
//!   3) although their authors meant sRGB. Browsers (Skia) decode it by the power.
//!
//! A stated colour space other than sRGB becomes a [`ColourProfile`] (an ICC profile
//! brume writes with moxcms), which the photo then follows as one read from `iCCP`.

use crate::io::colour_profile::{ColourProfile, StatedColour};
use crate::{Error, Result};
use moxcms::{ToneReprCurve, TransferCharacteristics};

/// The signature that starts every PNG file.
pub(crate) const PNG_SIGNATURE: &[u8; 8] = b"\x89PNG\r\n\x1a\n";

/// The largest ICC profile a PNG may inflate to: moxcms, which reads the profiles, reads
/// none larger (its own limit, set for the largest CMYK press profiles).
pub const MAX_ICC_BYTES: usize = 10 << 20;

/// Where a PNG's width and height end: the signature, `IHDR`'s length and type, then the
/// two 32-bit numbers.
pub(crate) const PNG_IHDR_END: usize = 24;

/// One chunk of a PNG: its type, the length it claims, and its data where the file holds
/// all of it.
struct Chunk<'a> {
    kind: &'a [u8],
    len: usize,
    data: Option<&'a [u8]>,
}

/// The chunks of PNG bytes `b`, walked by their lengths from the signature, up to `IEND`;
/// one that runs past the end is the last (the decoder reports the truncation).
fn chunks(b: &[u8]) -> impl Iterator<Item = Chunk<'_>> {
    let mut next = Some(PNG_SIGNATURE.len());
    std::iter::from_fn(move || {
        let i = next?;
        let head = b.get(i..).and_then(|rest| rest.get(..8))?;
        let len = be_u32(head) as usize;
        let kind = &head[4..8];
        // Length, type, data and CRC.
        next = i
            .checked_add(len)
            .and_then(|j| j.checked_add(12))
            .filter(|_| kind != b"IEND");
        let data = b.get(i + 8..).and_then(|rest| rest.get(..len));
        Some(Chunk { kind, len, data })
    })
}

/// Refuses a PNG whose palette (`PLTE` chunk) is not whole RGB entries of 3 bytes, as the
/// PNG specification requires: the png crate (0.18.1) accepts any length from 3 to 768
/// bytes and then panics building its colour table from one that is not a multiple of 3
/// (image-rs/image-png#694; found by the `sky_mask` fuzzer). And one whose ICC profile
/// (`iCCP` chunk, compressed) inflates beyond [`MAX_ICC_BYTES`]: the png crate inflates
/// it whole when it opens the file, up to the decoder's memory limit (512 MiB), so a
/// 400 KB file took 828 MB.
pub(crate) fn check_png_chunks(b: &[u8], name: &str) -> Result<()> {
    for chunk in chunks(b) {
        if chunk.kind == b"PLTE" && !chunk.len.is_multiple_of(3) {
            return Err(Error::format(
                name,
                format!(
                    "PNG palette (PLTE chunk) of {} bytes, not whole RGB entries of 3 \
                     bytes; the file is corrupt",
                    chunk.len
                ),
            ));
        }
        if let (b"iCCP", Some(data)) = (chunk.kind, chunk.data) {
            check_iccp_size(data, name)?;
        }
    }
    Ok(())
}

/// Refuses an `iCCP` chunk's data (a name, a NUL, the compression method, a zlib stream)
/// whose profile inflates beyond [`MAX_ICC_BYTES`]. A chunk that is malformed otherwise is
/// left to the decoder.
fn check_iccp_size(data: &[u8], name: &str) -> Result<()> {
    let Some(nul) = data.iter().take(81).position(|&c| c == 0) else {
        return Ok(());
    };
    let Some(stream) = data.get(nul + 2..) else {
        return Ok(());
    };
    match fdeflate::decompress_to_vec_bounded(stream, MAX_ICC_BYTES) {
        Err(fdeflate::BoundedDecompressionError::OutputTooLarge { .. }) => Err(Error::format(
            name,
            format!(
                "its ICC colour profile (iCCP chunk, {} bytes compressed) inflates beyond \
                 {} MB, more than any profile holds: the file is corrupt or built to exhaust \
                 memory; save the image again without its profile",
                data.len(),
                MAX_ICC_BYTES >> 20
            ),
        )),
        _ => Ok(()),
    }
}

/// The width and height in the `IHDR` chunk that starts a PNG, if `head` is one and both
/// are non-zero (the specification's rule; anything else is left to the decoder's error).
pub(crate) fn png_ihdr_size(head: &[u8; PNG_IHDR_END]) -> Option<(u32, u32)> {
    if &head[..PNG_SIGNATURE.len()] != PNG_SIGNATURE || &head[12..16] != b"IHDR" {
        return None;
    }
    let (w, h) = (be_u32(&head[16..20]), be_u32(&head[20..24]));
    (w > 0 && h > 0).then_some((w, h))
}

fn be_u32(b: &[u8]) -> u32 {
    u32::from_be_bytes([b[0], b[1], b[2], b[3]])
}

/// The colour space a PNG states.
pub(crate) enum PngColour {
    /// sRGB: said by `sRGB`, by `gAMA`/`cHRM` that are sRGB's, or by nothing.
    Srgb,
    /// Its ICC profile (`iCCP`), which the decoder reads.
    IccProfile,
    /// Another colour space, stated by `cICP` or by `gAMA`/`cHRM`.
    Stated(ColourProfile),
}

/// The colour chunks of a PNG, as its file holds them.
#[derive(Default)]
struct ColourChunks<'a> {
    cicp: Option<&'a [u8]>,
    iccp: bool,
    srgb: bool,
    gama: Option<u32>,
    chrm: Option<Chromaticities>,
}

impl<'a> ColourChunks<'a> {
    /// The colour chunks before the image data of PNG bytes `b` (any after it are not
    /// the image's); a `gAMA` or `cHRM` of the wrong length is none.
    fn read(b: &'a [u8]) -> ColourChunks<'a> {
        let mut found = ColourChunks::default();
        for chunk in chunks(b).take_while(|c| c.kind != b"IDAT") {
            match (chunk.kind, chunk.data) {
                (b"cICP", Some(d)) => found.cicp = Some(d),
                (b"iCCP", _) => found.iccp = true,
                (b"sRGB", _) => found.srgb = true,
                (b"gAMA", Some(d)) if d.len() == 4 => found.gama = Some(be_u32(d)),
                (b"cHRM", Some(d)) if d.len() == 32 => {
                    let v = |k: usize| f64::from(be_u32(&d[4 * k..])) / 1e5;
                    found.chrm = Some(std::array::from_fn(|k| [v(2 * k), v(2 * k + 1)]));
                }
                _ => {}
            }
        }
        found
    }
}

/// The colour space PNG bytes `b` (the file `name`) state, by the module's rules. Errors:
/// an HDR PNG (`cICP` with PQ or HLG).
pub(crate) fn png_colour(b: &[u8], name: &str) -> Result<PngColour> {
    let found = ColourChunks::read(b);
    if let Some(stated) = found
        .cicp
        .map(|d| cicp_colour(d, name))
        .transpose()?
        .flatten()
    {
        return Ok(stated_or_srgb(stated, name));
    }
    if found.iccp {
        return Ok(PngColour::IccProfile);
    }
    if found.srgb {
        return Ok(PngColour::Srgb);
    }
    Ok(gama_chrm_colour(found.gama, found.chrm, name))
}

/// The colour space a PNG's `gAMA` and `cHRM` state: sRGB where each is missing or
/// sRGB's.
fn gama_chrm_colour(gama: Option<u32>, chrm: Option<Chromaticities>, name: &str) -> PngColour {
    let curve = gama.and_then(|g| gamma_curve(g, name));
    let primaries = chrm.filter(|c| !is_srgb_chrm(c));
    if curve.is_none() && primaries.is_none() {
        return PngColour::Srgb;
    }
    let [white, red, green, blue] = primaries.unwrap_or(SRGB_CHRM);
    let mut said = vec![];
    if let Some(c) = &primaries {
        said.push(format!("cHRM {}", describe_chromaticities(c)));
    }
    if let Some(g) = gama {
        said.push(format!("gAMA {:.5}", f64::from(g) / 1e5));
    }
    let stated = StatedColour {
        primaries: [red, green, blue],
        white,
        curve: curve.unwrap_or_else(srgb_curve),
        description: format!("PNG {}", said.join(", ")),
    };
    stated_or_srgb(stated, name)
}

/// A stated colour space as a profile; sRGB (with the warning moxcms's failure gave) where
/// it cannot be made one.
fn stated_or_srgb(stated: StatedColour, name: &str) -> PngColour {
    ColourProfile::from_stated(stated, name).map_or(PngColour::Srgb, PngColour::Stated)
}

/// libpng's threshold for a gamma to differ from another (`PNG_GAMMA_THRESHOLD`): 5 % of
/// their product from 1.
const GAMMA_THRESHOLD: f64 = 0.05;

/// The decoding curve of a `gAMA` chunk's value `g` (the encoding exponent, times 100 000):
/// none where it is within [`GAMMA_THRESHOLD`] of sRGB's 1/2.2 (or is 0, which the
/// specification forbids, with a warning).
fn gamma_curve(g: u32, name: &str) -> Option<ToneReprCurve> {
    if g == 0 {
        log::warn!("{name}: its PNG gAMA chunk says gamma 0, which is none; taken as sRGB");
        return None;
    }
    let exponent = f64::from(g) / 1e5;
    if (exponent * 2.2 - 1.0).abs() <= GAMMA_THRESHOLD {
        return None;
    }
    Some(ToneReprCurve::Parametric(vec![(1.0 / exponent) as f32]))
}

/// sRGB's chromaticities as a `cHRM` chunk lists them: white (D65), red, green, blue.
const SRGB_CHRM: Chromaticities = [[0.3127, 0.329], [0.64, 0.33], [0.3, 0.6], [0.15, 0.06]];

/// How far (in CIE x or y) a `cHRM` chunk may be from sRGB's for it to say sRGB: libpng
/// writes them rounded to 1e-5, others to 1e-3 or 1e-4.
const SRGB_CHRM_TOLERANCE: f64 = 1e-3;

/// Chromaticities (white, red, green, blue) as profile descriptions and messages say
/// them: `R 0.680,0.320 G … B … W …`.
pub(crate) fn describe_chromaticities([w, r, g, b]: &Chromaticities) -> String {
    let xy = |c: &[f64; 2]| format!("{:.3},{:.3}", c[0], c[1]);
    format!("R {} G {} B {} W {}", xy(r), xy(g), xy(b), xy(w))
}

/// Whether chromaticities (white, red, green, blue) are sRGB's, within
/// [`SRGB_CHRM_TOLERANCE`].
pub(crate) fn is_srgb_chrm(c: &Chromaticities) -> bool {
    let pairs = c.iter().flatten().zip(SRGB_CHRM.iter().flatten());
    pairs
        .into_iter()
        .all(|(a, b)| (a - b).abs() <= SRGB_CHRM_TOLERANCE)
}

fn srgb_curve() -> ToneReprCurve {
    ToneReprCurve::Parametric(vec![2.4, 1. / 1.055, 0.055 / 1.055, 1. / 12.92, 0.04045])
}

/// The colour space a `cICP` chunk's data `d` states; none (with a warning) where brume
/// does not read it, so that the next chunk in precedence decides. Errors: PQ or HLG.
fn cicp_colour(d: &[u8], name: &str) -> Result<Option<StatedColour>> {
    let ignored = |why: String| {
        log::warn!("{name}: its PNG cICP chunk {d:?} is ignored: {why}");
        Ok(None)
    };
    let &[primaries, transfer, matrix, _full_range] = d else {
        return ignored(format!("{} bytes, not 4", d.len()));
    };
    if matches!(transfer, 16 | 18) {
        let curve = if transfer == 16 { "PQ" } else { "HLG" };
        return Err(Error::format(
            name,
            format!(
                "an HDR PNG (cICP transfer {transfer}, {curve}); brume fogs standard-range \
                 photos: save it as an SDR image (sRGB or Display P3) first"
            ),
        ));
    }
    if matrix != 0 {
        return ignored(format!("matrix coefficients {matrix}; a PNG holds RGB (0)"));
    }
    let Some(([white, red, green, blue], space)) = cicp_primaries(primaries) else {
        return ignored(format!("colour primaries {primaries} are not read"));
    };
    let curve = TransferCharacteristics::try_from(transfer)
        .and_then(ToneReprCurve::try_from)
        .ok()
        .filter(|_| transfer != 2);
    let Some(curve) = curve else {
        return ignored(format!("transfer characteristics {transfer} are not read"));
    };
    Ok(Some(StatedColour {
        primaries: [red, green, blue],
        white,
        curve,
        description: format!("PNG cICP {primaries}/{transfer} ({space})"),
    }))
}

/// CIE xy of a white and of red, green and blue primaries, in a `cHRM` chunk's order.
pub(crate) type Chromaticities = [[f64; 2]; 4];

/// The chromaticities of the `cICP` colour primaries brume reads (ITU-T H.273 table 2),
/// with their name.
fn cicp_primaries(code: u8) -> Option<(Chromaticities, &'static str)> {
    const D65: [f64; 2] = [0.3127, 0.329];
    const P3: [[f64; 2]; 3] = [[0.68, 0.32], [0.265, 0.69], [0.15, 0.06]];
    let [r, g, b] = P3;
    match code {
        1 => Some((SRGB_CHRM, "BT.709")),
        9 => Some((
            [D65, [0.708, 0.292], [0.17, 0.797], [0.131, 0.046]],
            "BT.2020",
        )),
        11 => Some(([[0.314, 0.351], r, g, b], "DCI-P3")),
        12 => Some(([D65, r, g, b], "Display P3")),
        _ => None,
    }
}

/// PNG bytes of the signature and `chunks` (type, data), CRCs left at 0: brume's own
/// walks read only lengths and types, and its checks refuse before the decoder reads more.
#[cfg(test)]
pub(crate) fn png_of_chunks(chunks: &[(&[u8; 4], &[u8])]) -> Vec<u8> {
    let mut png = PNG_SIGNATURE.to_vec();
    for (kind, data) in chunks {
        png.extend((data.len() as u32).to_be_bytes());
        png.extend(*kind);
        png.extend(*data);
        png.extend([0; 4]);
    }
    png
}

#[cfg(test)]
mod tests {
    use super::*;

    /// PNG bytes of `IHDR` (a 1x1 RGB image) and `chunks`.
    fn png_of(chunks: &[(&[u8; 4], Vec<u8>)]) -> Vec<u8> {
        let ihdr: (&[u8; 4], &[u8]) = (b"IHDR", &[0, 0, 0, 1, 0, 0, 0, 1, 8, 2, 0, 0, 0]);
        let rest = chunks.iter().map(|(kind, data)| (*kind, data.as_slice()));
        png_of_chunks(&std::iter::once(ihdr).chain(rest).collect::<Vec<_>>())
    }

    fn gama(g: u32) -> (&'static [u8; 4], Vec<u8>) {
        (b"gAMA", g.to_be_bytes().to_vec())
    }

    fn stated(chunks: &[(&[u8; 4], Vec<u8>)]) -> Option<ColourProfile> {
        match png_colour(&png_of(chunks), "t.png").unwrap() {
            PngColour::Stated(p) => Some(p),
            PngColour::Srgb => None,
            PngColour::IccProfile => panic!("no iCCP was given"),
        }
    }

    /// libpng's threshold: `gAMA` within 5 % of 1/2.2 is sRGB, beyond it (1/1.8, as old
    /// Macs wrote) its own power; 0 is none.
    #[test]
    fn a_gamma_near_srgbs_is_srgb() {
        assert!(stated(&[gama(45455)]).is_none());
        assert!(stated(&[gama(43500)]).is_none());
        assert!(stated(&[gama(0)]).is_none());
        let mac = stated(&[gama(55556)]).expect("gamma 1.8");
        assert!(mac.has_own_curves() && mac.primaries_are_srgb());
        let curve = mac.own_curves().unwrap().decode([32768; 3])[0];
        assert!((f64::from(curve) - (32768f64 / 65535.0).powf(1.8)).abs() < 1e-4);
    }

    /// A `cICP` that is not read (3 bytes, YCbCr matrix, unknown primaries or curve) leaves
    /// the decision to the chunks after it in precedence; `cICP` 1/13 is sRGB itself; a
    /// chunk after the image data is not the image's.
    #[test]
    fn an_unread_cicp_defers_to_the_next_chunk() {
        let linear = gama(100_000);
        for cicp in [
            vec![1, 8, 0],
            vec![1, 8, 1, 1],
            vec![3, 8, 0, 1],
            vec![1, 2, 0, 1],
        ] {
            let p = stated(&[(b"cICP", cicp.clone()), linear.clone()]);
            assert!(p.expect("gAMA 1 decides").has_own_curves(), "{cicp:?}");
        }
        assert!(stated(&[(b"cICP", vec![1, 13, 0, 1]), linear.clone()]).is_none());
        assert!(stated(&[(b"IDAT", vec![]), linear]).is_none());
        let iccp = png_of(&[(b"iCCP", b"x\0\0".to_vec()), gama(100_000)]);
        assert!(matches!(
            png_colour(&iccp, "t.png"),
            Ok(PngColour::IccProfile)
        ));
    }

    /// HLG is refused as PQ is.
    #[test]
    fn hdr_curves_are_refused() {
        for (transfer, name) in [(16, "PQ"), (18, "HLG")] {
            let png = png_of(&[(b"cICP", vec![9, transfer, 0, 1])]);
            let e = png_colour(&png, "hdr.png").err().unwrap().to_string();
            assert!(e.contains("hdr.png") && e.contains(name), "{e}");
        }
    }
}
