//! A photo's ICC colour profile, carried from the photo to the images brume writes of it.
//!
//! Phones write their photos in Display P3 (every iPhone since the 7, many Android
//! phones), cameras and editors in Adobe RGB or ProPhoto, each saying so in an embedded
//! ICC profile. Read as sRGB and written without a profile, such a photo's fogged output
//! shows duller colours than the photo beside it, fog or no fog. So the profile goes with
//! the photo:
//!
//! - **Matrix-shaper RGB with sRGB's tone curve** (Display P3, sRGB itself): the pixels
//!   are decoded by the sRGB curve as before, which is that profile's own, so the fog
//!   mixes linear light in the profile's primaries; PNG and JPEG outputs carry the
//!   profile as it was.
//! - **Matrix-shaper RGB with other curves** (Adobe RGB's gamma 2.2, ProPhoto's 1.8, a
//!   linear profile): each channel is decoded by its own curve, to linear light in the
//!   profile's primaries; outputs, encoded by sRGB's curve as always, carry those
//!   primaries with sRGB's curve (a profile brume writes with moxcms).
//! - **Other profiles** (lookup-table RGB profiles): their curves are not read, the fog
//!   mixes values decoded by the sRGB curve (approximate, with a warning), and outputs
//!   carry the profile, so that pixels the fog does not touch keep their colours.
//! - **Unreadable or not RGB** (a CMYK or grey profile): ignored with a warning, the
//!   photo taken as sRGB, as before.
//!
//! EXR and PFM outputs cannot hold an ICC profile, and their linear values are in the
//! profile's primaries: an EXR says them in its `chromaticities`
//! ([`ColourProfile::chromaticities`]); for a PFM, [`ColourProfile::primaries_are_srgb`]
//! lets the writer warn.

use std::sync::Arc;

use moxcms::{ColorProfile, DataColorSpace, ProfileText, ToneReprCurve};

use crate::io::srgb::linear_to_srgb;

/// An ICC colour profile read from a photo (see the module docs for what is done with
/// each kind).
#[derive(Clone, PartialEq)]
pub struct ColourProfile {
    /// The profile outputs carry.
    icc: Arc<Vec<u8>>,
    /// The profile's description ("Display P3"), or a placeholder.
    description: String,
    /// Per-channel decoding where the profile's curves are not sRGB's.
    curves: Option<Arc<ChannelCurves>>,
    /// Whether its primaries are sRGB's (within the rounding of ICC numbers).
    srgb_primaries: bool,
    /// CIE xy of its red, green and blue primaries and of its white.
    chromaticities: [[f64; 2]; 4],
}

/// How far, in 8-bit codes, a profile's curve may be from sRGB's at any code and still be
/// read as sRGB's: a quarter code, so that decoding by either gives every 8-bit code back.
const SRGB_CURVE_TOLERANCE_CODES: f32 = 0.25;

/// How far (in CIE XYZ) a profile's colorants may be from sRGB's for its primaries to be
/// sRGB's: profiles round them to s15Fixed16 and adapt them to D50 with their own matrix.
const SRGB_PRIMARIES_TOLERANCE: f64 = 2e-3;

/// Each channel's decoding to linear light at every 16-bit code (an 8-bit code `c` is
/// 16-bit code `257 c`, the same value).
#[derive(PartialEq)]
pub(crate) struct ChannelCurves([Vec<f32>; 3]);

impl ChannelCurves {
    /// Linear light of a pixel's 16-bit codes.
    pub(crate) fn decode(&self, rgb: [u16; 3]) -> [f32; 3] {
        std::array::from_fn(|i| self.0[i][usize::from(rgb[i])])
    }
}

impl std::fmt::Debug for ColourProfile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ColourProfile")
            .field("description", &self.description)
            .field("icc_bytes", &self.icc.len())
            .field("own_curves", &self.curves.is_some())
            .field("srgb_primaries", &self.srgb_primaries)
            .finish()
    }
}

impl ColourProfile {
    /// Reads the ICC profile `icc` embedded in the image `name`. None, with a warning,
    /// where it cannot be read or is not an RGB profile: the image is then taken as sRGB.
    pub fn from_icc(icc: Vec<u8>, name: &str) -> Option<ColourProfile> {
        let parsed = parse_rgb(&icc, name)?;
        let description = describe(&parsed);
        let profile = |icc: Vec<u8>, curves: Option<ChannelCurves>| ColourProfile {
            icc: Arc::new(icc),
            description: description.clone(),
            curves: curves.map(Arc::new),
            srgb_primaries: has_srgb_primaries(&parsed),
            chromaticities: chromaticities_of(&parsed),
        };
        if !parsed.is_matrix_shaper() {
            log::warn!(
                "{name}: its ICC colour profile \"{description}\" has no matrix and tone \
                 curves (a lookup-table profile), which is all brume reads: the fog mixes \
                 its values as if encoded by sRGB's curve (approximate); outputs carry the \
                 profile"
            );
            return Some(profile(icc, None));
        }
        match own_curves(&parsed) {
            Err(why) => {
                log::warn!(
                    "{name}: the tone curves of its ICC colour profile \"{description}\" \
                     cannot be evaluated ({why}); its colours are taken as sRGB"
                );
                None
            }
            Ok(None) => {
                log::info!(
                    "{name}: colour profile \"{description}\" (sRGB's tone curve): the fog \
                     mixes linear light in its primaries, and outputs carry it"
                );
                Some(profile(icc, None))
            }
            Ok(Some(curves)) => match with_srgb_curves(&parsed, creation_date(&icc)) {
                Ok(output_icc) => {
                    log::info!(
                        "{name}: colour profile \"{description}\": each channel decoded by \
                         its own tone curve; outputs carry its primaries with sRGB's curve"
                    );
                    Some(profile(output_icc, Some(curves)))
                }
                Err(e) => {
                    log::warn!(
                        "{name}: its colour profile \"{description}\" cannot be rewritten \
                         with sRGB's curve for the outputs ({e}); its colours are taken as \
                         sRGB"
                    );
                    None
                }
            },
        }
    }

    /// The ICC profile that PNG and JPEG outputs of the photo carry.
    pub fn icc(&self) -> &[u8] {
        &self.icc
    }

    /// The profile's description, for messages ("Display P3").
    pub fn description(&self) -> &str {
        &self.description
    }

    /// Whether the photo's primaries are sRGB's, so that an output without a profile (EXR,
    /// PFM) means the same colours.
    pub fn primaries_are_srgb(&self) -> bool {
        self.srgb_primaries
    }

    /// CIE xy of the photo's red, green and blue primaries and of its white, as an
    /// OpenEXR `chromaticities` attribute says them: the profile's colorants, which ICC
    /// adapts to D50, taken back to the photo's white by the inverse of the profile's own
    /// adaptation (`chad`), or, where it has none, of Bradford's from D65 (the white of
    /// display profiles).
    pub fn chromaticities(&self) -> [[f64; 2]; 4] {
        self.chromaticities
    }

    /// The matrix from CIE XYZ to the photo's linear RGB (rows r, g, b), from its
    /// [`ColourProfile::chromaticities`]: its white (XYZ with Y = 1) goes to r = g = b = 1.
    pub fn xyz_to_rgb(&self) -> [[f64; 3]; 3] {
        inverse(self.rgb_to_xyz())
    }

    /// The luminance of the photo's linear R, G, B: the Y row of its RGB to XYZ matrix
    /// (summing to 1), e.g. 0.2290, 0.6917, 0.0793 for Display P3.
    pub fn luminance_weights(&self) -> [f64; 3] {
        self.rgb_to_xyz()[1]
    }

    /// The matrix from the photo's linear RGB to CIE XYZ, from its chromaticities: r = g
    /// = b = 1 goes to its white with Y = 1.
    fn rgb_to_xyz(&self) -> [[f64; 3]; 3] {
        let [r, g, b, white] = self.chromaticities;
        rgb_to_xyz([r, g, b].map(xy_to_xyz), xy_to_xyz(white))
    }

    /// Whether the profile's curves are linear (gamma 1: a RAW developer's linear
    /// output), so that the photo's codes are proportional to light.
    pub fn has_linear_curves(&self) -> bool {
        self.curves.as_deref().is_some_and(|c| {
            let mid = c.decode([32768; 3]);
            mid.iter().all(|v| (v - 32768.0 / 65535.0).abs() < 1e-3)
        })
    }

    /// Whether the photo is decoded by its profile's own curves rather than sRGB's.
    pub fn has_own_curves(&self) -> bool {
        self.curves.is_some()
    }

    /// The profile's own curves, where the photo is decoded by them rather than sRGB's.
    pub(crate) fn own_curves(&self) -> Option<&ChannelCurves> {
        self.curves.as_deref()
    }
}

/// A colour space a file states without an ICC profile (a PNG's `cICP`, or its `cHRM` and
/// `gAMA`): chromaticities and one tone curve for the three channels.
pub(crate) struct StatedColour {
    /// CIE xy of the red, green and blue primaries.
    pub primaries: [[f64; 2]; 3],
    /// CIE xy of the white.
    pub white: [f64; 2],
    /// The decoding curve of every channel.
    pub curve: ToneReprCurve,
    /// What stated it, for messages and the profile's description.
    pub description: String,
}

impl ColourProfile {
    /// The colour space `stated` by the image `name`, as the ICC profile that says it
    /// (written by moxcms: colorants adapted to D50 by Bradford's, and that adaptation as
    /// its `chad`), read as [`ColourProfile::from_icc`] reads one. None where it is sRGB
    /// (primaries and curve), or, with a warning, where moxcms cannot write it.
    pub(crate) fn from_stated(stated: StatedColour, name: &str) -> Option<ColourProfile> {
        let white = xy_to_xyz(stated.white);
        let adapt = bradford(white, D50);
        let colorants = multiply(adapt, rgb_to_xyz(stated.primaries.map(xy_to_xyz), white));
        let column = |k: usize| moxcms::Xyzd {
            x: colorants[0][k],
            y: colorants[1][k],
            z: colorants[2][k],
        };
        let mut p = ColorProfile::new_srgb();
        p.cicp = None;
        (p.red_colorant, p.green_colorant, p.blue_colorant) = (column(0), column(1), column(2));
        p.chromatic_adaptation = Some(moxcms::Matrix3d { v: adapt });
        p.red_trc = Some(stated.curve.clone());
        p.green_trc = Some(stated.curve.clone());
        p.blue_trc = Some(stated.curve);
        p.description = Some(ProfileText::PlainString(stated.description));
        if has_srgb_primaries(&p) && matches!(own_curves(&p), Ok(None)) {
            return None;
        }
        match encode_dated(&p, STATED_PROFILE_DATE) {
            Ok(icc) => ColourProfile::from_icc(icc, name),
            Err(e) => {
                log::warn!(
                    "{name}: its colour space ({}) cannot be written as an ICC profile \
                     ({e}); its colours are taken as sRGB",
                    describe(&p)
                );
                None
            }
        }
    }
}

/// The profile `icc` parsed, where it is an RGB profile; None, with a warning naming the
/// image `name`, where it cannot be read or is for other data (CMYK, grey).
fn parse_rgb(icc: &[u8], name: &str) -> Option<ColorProfile> {
    let parsed = match ColorProfile::new_from_slice(icc) {
        Ok(p) => p,
        Err(e) => {
            log::warn!(
                "{name}: its ICC colour profile ({} bytes) cannot be read ({e}); its colours \
                 are taken as sRGB",
                icc.len()
            );
            return None;
        }
    };
    if parsed.color_space != DataColorSpace::Rgb {
        log::warn!(
            "{name}: its ICC colour profile \"{}\" is for {:?} data, not RGB; its colours \
             are taken as sRGB",
            describe(&parsed),
            parsed.color_space
        );
        return None;
    }
    Some(parsed)
}

/// The profile's description: its English text where it has several, else its first.
fn describe(p: &ColorProfile) -> String {
    let text = match &p.description {
        Some(ProfileText::PlainString(s)) => s.clone(),
        Some(ProfileText::Localizable(all)) => all
            .iter()
            .find(|s| s.language.eq_ignore_ascii_case("en"))
            .or(all.first())
            .map(|s| s.value.clone())
            .unwrap_or_default(),
        Some(ProfileText::Description(d)) => d.ascii_string.clone(),
        None => String::new(),
    };
    let text: String = text
        .trim_matches(char::from(0))
        .trim()
        .chars()
        .take(80)
        .collect();
    if text.is_empty() {
        "(unnamed)".into()
    } else {
        text
    }
}

/// D50, the white of ICC's connection space.
const D50: [f64; 3] = [0.9642, 1.0, 0.8249];
/// D65 in XYZ (CIE 15: x 0.3127, y 0.3290).
const D65: [f64; 3] = [0.3127 / 0.3290, 1.0, (1.0 - 0.3127 - 0.3290) / 0.3290];
/// Bradford's cone response matrix.
const BRADFORD: [[f64; 3]; 3] = [
    [0.8951, 0.2664, -0.1614],
    [-0.7502, 1.7135, 0.0367],
    [0.0389, -0.0685, 1.0296],
];

/// How far a profile's `chad` may be from Bradford's adaptation of the white it implies
/// (any element) for it to be taken as the adaptation ICC asks for: moxcms's own profiles
/// store Bradford's cone matrix there instead.
const CHAD_TOLERANCE: f64 = 2e-3;

/// [`ColourProfile::chromaticities`] of a parsed profile.
fn chromaticities_of(p: &ColorProfile) -> [[f64; 2]; 4] {
    let chad = p.chromatic_adaptation.map(|m| m.v).filter(|&m| {
        let white = apply(inverse(m), D50);
        let expected = bradford(white, D50);
        let off = (0..9).map(|k| (m[k / 3][k % 3] - expected[k / 3][k % 3]).abs());
        off.fold(0.0, f64::max) <= CHAD_TOLERANCE
    });
    let to_d50 = chad.unwrap_or_else(|| bradford(D65, D50));
    let back = inverse(to_d50);
    let xy = |c: [f64; 3]| {
        let xyz = apply(back, c);
        let sum = xyz[0] + xyz[1] + xyz[2];
        if sum.abs() < 1e-12 {
            [0.0, 0.0]
        } else {
            [xyz[0] / sum, xyz[1] / sum]
        }
    };
    let colorant = |c: moxcms::Xyzd| [c.x, c.y, c.z];
    [
        xy(colorant(p.red_colorant)),
        xy(colorant(p.green_colorant)),
        xy(colorant(p.blue_colorant)),
        xy(D50),
    ]
}

/// XYZ of CIE xy `c`, at Y = 1.
fn xy_to_xyz([x, y]: [f64; 2]) -> [f64; 3] {
    [x / y, 1.0, (1.0 - x - y) / y]
}

/// The matrix from linear RGB to XYZ of primaries `rgb` (XYZ, any scale) whose sum is
/// `white`: each primary's column scaled so that RGB (1, 1, 1) is the white.
fn rgb_to_xyz(rgb: [[f64; 3]; 3], white: [f64; 3]) -> [[f64; 3]; 3] {
    let columns: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|k| rgb[k][i]));
    let scale = apply(inverse(columns), white);
    std::array::from_fn(|i| std::array::from_fn(|k| columns[i][k] * scale[k]))
}

/// Bradford's adaptation from white `from` to white `to` (XYZ).
fn bradford(from: [f64; 3], to: [f64; 3]) -> [[f64; 3]; 3] {
    let (cone_from, cone_to) = (apply(BRADFORD, from), apply(BRADFORD, to));
    let scale: [[f64; 3]; 3] = std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            if i == j {
                cone_to[i] / cone_from[i]
            } else {
                0.0
            }
        })
    });
    multiply(inverse(BRADFORD), multiply(scale, BRADFORD))
}

fn apply(m: [[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| (0..3).map(|k| m[i][k] * v[k]).sum())
}

fn multiply(a: [[f64; 3]; 3], b: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

/// The inverse of `m` by its adjugate; the identity for a singular matrix (a profile's
/// adaptation is never singular: its columns are three whites' responses).
fn inverse(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let cof = |r: usize, c: usize| {
        let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
        let (c1, c2) = ((c + 1) % 3, (c + 2) % 3);
        m[r1][c1] * m[r2][c2] - m[r1][c2] * m[r2][c1]
    };
    let det: f64 = (0..3).map(|c| m[0][c] * cof(0, c)).sum();
    if det.abs() < 1e-12 {
        return std::array::from_fn(|i| std::array::from_fn(|j| f64::from(u8::from(i == j))));
    }
    std::array::from_fn(|i| std::array::from_fn(|j| cof(j, i) / det))
}

/// Whether the colorants are sRGB's.
fn has_srgb_primaries(p: &ColorProfile) -> bool {
    let srgb = ColorProfile::new_srgb();
    let close = |a: moxcms::Xyzd, b: moxcms::Xyzd| {
        [a.x - b.x, a.y - b.y, a.z - b.z]
            .iter()
            .all(|d| d.abs() <= SRGB_PRIMARIES_TOLERANCE)
    };
    close(p.red_colorant, srgb.red_colorant)
        && close(p.green_colorant, srgb.green_colorant)
        && close(p.blue_colorant, srgb.blue_colorant)
}

/// Each channel's decoding at every 16-bit code, or None where all three curves are
/// sRGB's (within [`SRGB_CURVE_TOLERANCE_CODES`]), so that the photo keeps sRGB's
/// decoding, exactly as without a profile. Errors: a curve moxcms cannot evaluate, or
/// one giving a value that is not finite.
fn own_curves(p: &ColorProfile) -> std::result::Result<Option<ChannelCurves>, String> {
    let trcs = [&p.red_trc, &p.green_trc, &p.blue_trc];
    let mut tables: [Vec<f32>; 3] = Default::default();
    let mut all_srgb = true;
    for (table, trc) in tables.iter_mut().zip(trcs) {
        let trc = trc.as_ref().ok_or("a channel has no curve")?;
        *table = curve_table(trc)?;
        all_srgb &= is_srgb_curve(table);
    }
    Ok((!all_srgb).then_some(ChannelCurves(tables)))
}

/// A curve's linear value at every 16-bit code, clamped to [0, 1].
fn curve_table(trc: &ToneReprCurve) -> std::result::Result<Vec<f32>, String> {
    if let ToneReprCurve::Parametric(params) = trc {
        // moxcms indexes the first parameter without checking that there is one.
        if params.is_empty() {
            return Err("a parametric curve without parameters".into());
        }
    }
    let curve = trc.make_linear_evaluator().map_err(|e| e.to_string())?;
    (0..=u16::MAX)
        .map(|code| {
            let v = curve.evaluate_value(f32::from(code) / 65535.0);
            if v.is_finite() {
                Ok(v.clamp(0.0, 1.0))
            } else {
                Err(format!("{v} at code {code} of 65535"))
            }
        })
        .collect()
}

/// Whether a curve (its 16-bit table) is sRGB's, compared at every 8-bit code in the
/// encoded domain.
fn is_srgb_curve(table: &[f32]) -> bool {
    (0..=255u16).all(|c| {
        let encoded = linear_to_srgb(table[usize::from(c) * 257]) * 255.0;
        (encoded - f32::from(c)).abs() <= SRGB_CURVE_TOLERANCE_CODES
    })
}

/// The profile with sRGB's curve on each channel and no lookup tables: what outputs,
/// encoded by that curve, carry.
fn with_srgb_curves(
    p: &ColorProfile,
    date: [u8; 12],
) -> std::result::Result<Vec<u8>, moxcms::CmsError> {
    let srgb = ColorProfile::new_srgb();
    let mut out = p.clone();
    out.red_trc = srgb.red_trc.clone();
    out.green_trc = srgb.green_trc.clone();
    out.blue_trc = srgb.blue_trc;
    // A CICP tag would say the original transfer; the curves now say sRGB's.
    out.cicp = None;
    out.lut_a_to_b_perceptual = None;
    out.lut_a_to_b_colorimetric = None;
    out.lut_a_to_b_saturation = None;
    out.lut_b_to_a_perceptual = None;
    out.lut_b_to_a_colorimetric = None;
    out.lut_b_to_a_saturation = None;
    out.description = Some(ProfileText::PlainString(format!(
        "{} primaries, sRGB curve (brume)",
        describe(p)
    )));
    encode_dated(&out, date)
}

/// Where an ICC profile's header holds its creation date and time (six big-endian 16-bit
/// numbers).
const ICC_DATE: std::ops::Range<usize> = 24..36;

/// The creation date a profile `icc` holds (zeros where it is too short to hold one).
fn creation_date(icc: &[u8]) -> [u8; 12] {
    icc.get(ICC_DATE)
        .and_then(|d| d.try_into().ok())
        .unwrap_or_default()
}

/// The creation date of the profiles brume writes for a colour space a file states (a
/// PNG's cICP, gAMA or cHRM; an EXR's chromaticities): fixed, 2025-06-24 00:00:00 (the PNG
/// specification's third edition), so that one photo gives the same bytes every run.
const STATED_PROFILE_DATE: [u8; 12] = [0x07, 0xe9, 0, 6, 0, 24, 0, 0, 0, 0, 0, 0];

/// `p` encoded by moxcms with `date` as its creation date: moxcms writes the moment of
/// encoding, which made every run's output of one photo differ. The profile's ID (an MD5
/// of the profile, which the date is part of) is left 0, as moxcms leaves it: none.
fn encode_dated(
    p: &ColorProfile,
    date: [u8; 12],
) -> std::result::Result<Vec<u8>, moxcms::CmsError> {
    let mut icc = p.encode()?;
    if let Some(header) = icc.get_mut(ICC_DATE) {
        header.copy_from_slice(&date);
    }
    Ok(icc)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::srgb::srgb_to_linear;

    fn read(p: &ColorProfile) -> Option<ColourProfile> {
        ColourProfile::from_icc(p.encode().unwrap(), "test")
    }

    /// Display P3 has sRGB's curve: kept byte for byte, decoded as sRGB (exactly as
    /// without a profile), its primaries not sRGB's.
    #[test]
    fn display_p3_is_kept_as_it_is() {
        let icc = ColorProfile::new_display_p3().encode().unwrap();
        let p = ColourProfile::from_icc(icc.clone(), "p3").expect("an RGB profile");
        assert_eq!(p.icc(), icc.as_slice());
        assert!(!p.has_own_curves());
        assert!(!p.primaries_are_srgb());
        assert!(p.own_curves().is_none());
    }

    /// Display P3's primaries (SMPTE EG 432-1) and D65, from moxcms's profile (whose
    /// `chad` is Bradford's cone matrix, not an adaptation: ignored), from the same with
    /// the adaptation Apple's Display P3 profile holds (Bradford's from D65), and from
    /// Adobe RGB's (without one).
    #[test]
    fn chromaticities_are_the_standards() {
        let close = |got: [[f64; 2]; 4], want: [[f64; 2]; 4]| {
            let near = got.iter().flatten().zip(want.iter().flatten());
            assert!(
                near.clone().all(|(g, w)| (g - w).abs() < 1e-3),
                "{got:?} for {want:?}"
            );
        };
        let d65 = [0.3127, 0.3290];
        let p3 = [[0.680, 0.320], [0.265, 0.690], [0.150, 0.060], d65];
        let mut moxcms_p3 = ColorProfile::new_display_p3();
        close(read(&moxcms_p3).unwrap().chromaticities(), p3);
        let apple_chad = [
            [1.047882080078125, 0.022918701171875, -0.050201416015625],
            [0.0295867919921875, 0.990478515625, -0.017059326171875],
            [-0.0092315673828125, 0.01507568359375, 0.751678466796875],
        ];
        moxcms_p3.chromatic_adaptation = Some(moxcms::Matrix3d { v: apple_chad });
        close(read(&moxcms_p3).unwrap().chromaticities(), p3);
        // A real adaptation from another white is used: D50's own (identity) keeps the
        // colorants' D50 chromaticities.
        moxcms_p3.chromatic_adaptation = Some(moxcms::Matrix3d {
            v: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        });
        let white = read(&moxcms_p3).unwrap().chromaticities()[3];
        assert!((white[0] - 0.3457).abs() < 1e-3 && (white[1] - 0.3585).abs() < 1e-3);
        let mut adobe = ColorProfile::new_adobe_rgb();
        adobe.chromatic_adaptation = None;
        close(
            read(&adobe).unwrap().chromaticities(),
            [[0.64, 0.33], [0.21, 0.71], [0.15, 0.06], d65],
        );
    }

    /// The Y rows the standards publish: IEC 61966-2-1's for sRGB, SMPTE EG 432-1's for
    /// Display P3, Adobe RGB (1998)'s specification's.
    #[test]
    fn luminance_weights_are_the_standards() {
        let cases = [
            (ColorProfile::new_srgb(), [0.2126, 0.7152, 0.0722]),
            (ColorProfile::new_display_p3(), [0.2290, 0.6917, 0.0793]),
            (ColorProfile::new_adobe_rgb(), [0.2973, 0.6274, 0.0753]),
        ];
        for (profile, want) in cases {
            let got = read(&profile).unwrap().luminance_weights();
            let near = got.iter().zip(want).all(|(g, w)| (g - w).abs() < 1e-3);
            assert!(near, "{got:?} for {want:?}");
            assert!((got.iter().sum::<f64>() - 1.0).abs() < 1e-9, "{got:?}");
        }
    }

    #[test]
    fn srgb_is_srgb() {
        let p = read(&ColorProfile::new_srgb()).expect("an RGB profile");
        assert!(p.primaries_are_srgb() && !p.has_own_curves(), "{p:?}");
    }

    /// Adobe RGB's gamma 563/256 (ICC's u8Fixed8) decodes each code by its own curve, and
    /// outputs carry Adobe's colorants with sRGB's curve.
    #[test]
    fn a_gamma_curve_decodes_by_itself_and_outputs_carry_srgb_curves() {
        let adobe = ColorProfile::new_adobe_rgb();
        let p = read(&adobe).expect("an RGB profile");
        assert!(p.has_own_curves() && !p.primaries_are_srgb(), "{p:?}");
        let gamma = 563.0 / 256.0;
        for c in [0u8, 1, 10, 128, 200, 255] {
            let want = (f64::from(c) / 255.0).powf(gamma) as f32;
            let got = p.own_curves().unwrap().decode([u16::from(c) * 257; 3]);
            for v in got {
                assert!((v - want).abs() < 2e-5, "code {c}: {v} against {want}");
            }
        }
        let out = ColorProfile::new_from_slice(p.icc()).unwrap();
        for (a, b) in [
            (out.red_colorant, adobe.red_colorant),
            (out.green_colorant, adobe.green_colorant),
            (out.blue_colorant, adobe.blue_colorant),
        ] {
            assert!((a.x - b.x).abs() + (a.y - b.y).abs() + (a.z - b.z).abs() < 1e-4);
        }
        let curve = curve_table(out.red_trc.as_ref().unwrap()).unwrap();
        assert!(is_srgb_curve(&curve));
        for c in [0u16, 3, 10, 128, 255] {
            let srgb = srgb_to_linear(f32::from(c) / 255.0);
            assert!(
                (curve[usize::from(c) * 257] - srgb).abs() < 1e-4,
                "code {c}"
            );
        }
    }

    /// An RGB profile without a matrix and curves (lookup tables only): kept as it is,
    /// the photo decoded by sRGB's curve.
    #[test]
    fn a_profile_without_curves_is_kept_as_it_is() {
        let mut tables_only = ColorProfile::new_display_p3();
        tables_only.red_trc = None;
        tables_only.green_trc = None;
        tables_only.blue_trc = None;
        let icc = tables_only.encode().unwrap();
        let p = ColourProfile::from_icc(icc.clone(), "luts").expect("an RGB profile");
        assert_eq!(p.icc(), icc.as_slice());
        assert!(!p.has_own_curves());
    }

    #[test]
    fn unreadable_and_non_rgb_profiles_are_ignored() {
        assert!(ColourProfile::from_icc(vec![0; 200], "zeros").is_none());
        assert!(ColourProfile::from_icc(Vec::new(), "empty").is_none());
        let mut cmyk = ColorProfile::new_srgb();
        cmyk.color_space = DataColorSpace::Cmyk;
        assert!(read(&cmyk).is_none());
    }

    /// One step off sRGB's curve at a single code is not sRGB's; a table within a tenth
    /// of a code everywhere is.
    #[test]
    fn the_srgb_curve_test_has_a_quarter_code_tolerance() {
        let srgb: Vec<f32> = (0..=u16::MAX)
            .map(|c| srgb_to_linear(f32::from(c) / 65535.0))
            .collect();
        assert!(is_srgb_curve(&srgb));
        let mut near = srgb.clone();
        let step = linear_to_srgb_code_step(&srgb, 100);
        near[100 * 257] += 0.1 * step;
        assert!(is_srgb_curve(&near));
        let mut off = srgb;
        off[100 * 257] += 0.5 * step;
        assert!(!is_srgb_curve(&off));
    }

    /// The linear size of one 8-bit code's step at `code`.
    fn linear_to_srgb_code_step(table: &[f32], code: usize) -> f32 {
        table[(code + 1) * 257] - table[code * 257]
    }
}
