//! Sky masks from semantic segmentation, for [`crate::prep::prepare_guided`].
//!
//! Three encodings, all lossless PNG (a JPEG's ringing would turn label values into
//! others):
//!
//! - **binary**: any PNG (grey or colour, 8 or 16 bits); a pixel is sky when one of its
//!   colour channels is not zero (alpha is ignored);
//! - **cityscapes-labelids**: a Cityscapes `*_gtFine_labelIds.png` (one 8-bit grey channel
//!   of label ids), sky is label id 23;
//! - **cityscapes-trainids**: a `*_labelTrainIds.png` (the train ids most segmentation
//!   networks output), sky is train id 10.
//!
//! [`SkyMaskFormat::from_file_name`] picks the format from the Cityscapes file names.
//!
//! Ego-vehicle masks ([`load_ego_mask`], `--ego-mask`) are read the same way: binary
//! (non-zero = the car's own hood) or Cityscapes label ids (label 1, "ego vehicle"; the
//! same `*_gtFine_labelIds.png` as the sky). Train ids do not name the ego vehicle (it is
//! 255, "ignore", with other labels), so they are refused.

use std::fmt;
use std::path::Path;
use std::str::FromStr;

use image::DynamicImage;

use crate::io::depth::LoadedDepth;
use crate::raster::Grid;
use crate::{Error, Result};

/// The Cityscapes label id of the sky (`labelIds` PNGs).
pub const CITYSCAPES_SKY_LABEL_ID: u16 = 23;
/// The Cityscapes train id of the sky (`labelTrainIds` PNGs).
pub const CITYSCAPES_SKY_TRAIN_ID: u16 = 10;
/// The Cityscapes label id of the ego vehicle (`labelIds` PNGs).
pub const CITYSCAPES_EGO_VEHICLE_LABEL_ID: u16 = 1;

/// The first 8 bytes of every PNG file.
const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];

/// How a sky mask file encodes the sky.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SkyMaskFormat {
    /// Non-zero = sky.
    Binary,
    /// Cityscapes label ids: 23 = sky.
    CityscapesLabelIds,
    /// Cityscapes train ids: 10 = sky.
    CityscapesTrainIds,
}

impl SkyMaskFormat {
    /// Every format, in the order of the help text.
    pub const ALL: [SkyMaskFormat; 3] = [
        SkyMaskFormat::Binary,
        SkyMaskFormat::CityscapesLabelIds,
        SkyMaskFormat::CityscapesTrainIds,
    ];

    /// The format a file name announces: `*_labelIds.png` (Cityscapes' `gtFine` and
    /// `gtCoarse` ground truth) is [`CityscapesLabelIds`](Self::CityscapesLabelIds),
    /// `*_labelTrainIds.png` is [`CityscapesTrainIds`](Self::CityscapesTrainIds), anything
    /// else [`Binary`](Self::Binary).
    pub fn from_file_name(path: &Path) -> Self {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        if name.ends_with("_labelids.png") {
            SkyMaskFormat::CityscapesLabelIds
        } else if name.ends_with("_labeltrainids.png") {
            SkyMaskFormat::CityscapesTrainIds
        } else {
            SkyMaskFormat::Binary
        }
    }

    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            SkyMaskFormat::Binary => "binary",
            SkyMaskFormat::CityscapesLabelIds => "cityscapes-labelids",
            SkyMaskFormat::CityscapesTrainIds => "cityscapes-trainids",
        }
    }

    /// The sky's value in a label format; `None` for binary.
    fn sky_label(self) -> Option<u16> {
        match self {
            SkyMaskFormat::Binary => None,
            SkyMaskFormat::CityscapesLabelIds => Some(CITYSCAPES_SKY_LABEL_ID),
            SkyMaskFormat::CityscapesTrainIds => Some(CITYSCAPES_SKY_TRAIN_ID),
        }
    }
}

impl fmt::Display for SkyMaskFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for SkyMaskFormat {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Self, String> {
        SkyMaskFormat::ALL
            .into_iter()
            .find(|f| f.name() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = SkyMaskFormat::ALL.iter().map(|f| f.name()).collect();
                format!(
                    "'{s}' is not a sky mask format; expected {}",
                    names.join(", ")
                )
            })
    }
}

/// Loads a sky mask (true = sky) from a PNG in `format`, or, for `None`, in the format its
/// name announces ([`SkyMaskFormat::from_file_name`]). Returns the mask and the format
/// used. Errors name the file: not a PNG, undecodable, or (label formats) not one grey
/// channel.
pub fn load_sky_mask(
    path: &Path,
    format: Option<SkyMaskFormat>,
) -> Result<(Grid<bool>, SkyMaskFormat)> {
    let bytes = crate::io::limits::read_file(path)?;
    let format = format.unwrap_or_else(|| SkyMaskFormat::from_file_name(path));
    let mask = decode_sky_mask(&bytes, &path.display().to_string(), format)?;
    Ok((mask, format))
}

/// Checks a mask read from `path` (for the option `name`, a `what`) against the range it
/// goes with (`range_name` in messages): the range's size, and not every pixel set
/// (`all_set` says what that means). Logs how many pixels it sets.
pub fn check_mask(
    (name, path, what): (&str, &Path, &str),
    mask: &Grid<bool>,
    range: &crate::raster::ScalarMap,
    range_name: &str,
    all_set: &str,
) -> Result<()> {
    if (mask.width(), mask.height()) != (range.width(), range.height()) {
        return Err(Error::size_mismatch(
            path.display(),
            (mask.width(), mask.height()),
            range_name,
            (range.width(), range.height()),
        ));
    }
    let set = mask.as_slice().iter().filter(|&&s| s).count();
    log::info!(
        "{}: {what}, {set} pixels ({:.1} %)",
        path.display(),
        100.0 * set as f64 / mask.len().max(1) as f64
    );
    if set == mask.len() {
        return Err(Error::invalid(name, path.display(), all_set));
    }
    Ok(())
}

/// A range's sky and ego-vehicle masks, checked against it ([`load_range_masks`]).
#[derive(Clone, Debug, Default)]
pub struct RangeMasks {
    /// The sky (true = sky).
    pub sky: Option<Grid<bool>>,
    /// How the sky mask was read.
    pub sky_format: Option<SkyMaskFormat>,
    /// The ego vehicle (true = the car's hood).
    pub ego: Option<Grid<bool>>,
}

/// Loads the sky mask `sky` (its path, and its format or `None` for the one its name
/// announces) and the ego-vehicle mask `ego`, each checked against the range of `depth`
/// (named `range_name` in messages) by [`check_mask`] as `sky_mask` and `ego_mask`. A
/// mask is turned as the depth map was to lie on its upright photo
/// ([`LoadedDepth::turned`]), unless its shape is the turned map's already.
pub fn load_range_masks(
    sky: Option<(&Path, Option<SkyMaskFormat>)>,
    ego: Option<&Path>,
    depth: &LoadedDepth,
    range_name: &str,
) -> Result<RangeMasks> {
    let range = &depth.range;
    let turn_like_depth = |m: Grid<bool>| {
        let upright = (m.width(), m.height()) == (range.width(), range.height());
        match depth.turned {
            t if t.swaps_axes() && upright => m,
            t => m.into_oriented(t),
        }
    };
    let mut masks = RangeMasks::default();
    if let Some((path, format)) = sky {
        let (m, format) = load_sky_mask(path, format)?;
        let m = turn_like_depth(m);
        let what = ("sky_mask", path, "sky mask");
        check_mask(what, &m, range, range_name, &all_sky_hint(format))?;
        (masks.sky, masks.sky_format) = (Some(m), Some(format));
    }
    if let Some(path) = ego {
        let (m, format) = load_ego_mask(path, None)?;
        let m = turn_like_depth(m);
        let what = ("ego_mask", path, "ego-vehicle mask");
        check_mask(what, &m, range, range_name, &all_ego_hint(format))?;
        masks.ego = Some(m);
    }
    Ok(masks)
}

/// What an all-sky mask of `format` probably is, for [`check_mask`].
pub fn all_sky_hint(format: SkyMaskFormat) -> String {
    format!(
        "a mask with ground in it: every pixel is sky as read ({format}); is it inverted, \
         or of another `sky_mask_format`?"
    )
}

/// What an all-ego mask of `format` probably is, for [`check_mask`].
pub fn all_ego_hint(format: SkyMaskFormat) -> String {
    format!(
        "a mask with the scene in it: every pixel is the ego vehicle as read ({format}); is \
         it inverted, or a label image not named *_labelIds.png?"
    )
}

/// [`load_sky_mask`] on bytes in memory; `name` stands for the file in messages.
pub fn decode_sky_mask(bytes: &[u8], name: &str, format: SkyMaskFormat) -> Result<Grid<bool>> {
    decode_label(bytes, name, format, format.sky_label(), Masked::Sky)
}

/// Loads an ego-vehicle mask (true = the ego vehicle) from a PNG in `format`, or, for
/// `None`, in the format its name announces ([`SkyMaskFormat::from_file_name`]): binary
/// (non-zero) or Cityscapes label ids (label 1). Returns the mask and the format used.
/// Errors as [`load_sky_mask`], and for train ids, which do not name the ego vehicle.
pub fn load_ego_mask(
    path: &Path,
    format: Option<SkyMaskFormat>,
) -> Result<(Grid<bool>, SkyMaskFormat)> {
    let bytes = crate::io::limits::read_file(path)?;
    let format = format.unwrap_or_else(|| SkyMaskFormat::from_file_name(path));
    let mask = decode_ego_mask(&bytes, &path.display().to_string(), format)?;
    Ok((mask, format))
}

/// [`load_ego_mask`] on bytes in memory; `name` stands for the file in messages.
pub fn decode_ego_mask(bytes: &[u8], name: &str, format: SkyMaskFormat) -> Result<Grid<bool>> {
    let label = match format {
        SkyMaskFormat::Binary => None,
        SkyMaskFormat::CityscapesLabelIds => Some(CITYSCAPES_EGO_VEHICLE_LABEL_ID),
        SkyMaskFormat::CityscapesTrainIds => {
            return Err(Error::format(
                name,
                "Cityscapes train ids do not name the ego vehicle (it is 255, 'ignore', like \
                 other labels): give the *_gtFine_labelIds.png (label 1) or a binary mask",
            ))
        }
    };
    decode_label(bytes, name, format, label, Masked::EgoVehicle)
}

/// What a mask marks, for the warning about a binary mask that looks like a label image.
#[derive(Clone, Copy)]
enum Masked {
    Sky,
    EgoVehicle,
}

/// The pixels of a PNG mask equal to `label` (label formats) or not zero (`None`).
fn decode_label(
    bytes: &[u8],
    name: &str,
    format: SkyMaskFormat,
    label: Option<u16>,
    masked: Masked,
) -> Result<Grid<bool>> {
    if !bytes.starts_with(&PNG_SIGNATURE) {
        return Err(Error::format(
            name,
            "a mask is read from a PNG file (lossless: a JPEG's compression would change \
             label values)",
        ));
    }
    let img = super::image::decode_any(bytes, name)?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    let mask = match label {
        None => binary_mask(&img, name, masked),
        Some(label) => label_values(&img, name, format)?
            .iter()
            .map(|&v| v == label)
            .collect(),
    };
    Ok(Grid::from_vec(w, h, mask))
}

/// Non-zero colour = set (sky, or the ego vehicle). Warns when the file holds more than
/// two values, as a label image given as binary would set nearly every pixel.
fn binary_mask(img: &DynamicImage, name: &str, masked: Masked) -> Vec<bool> {
    let rgb = img.to_rgb16();
    let mut values = std::collections::BTreeSet::new();
    let mask = rgb
        .pixels()
        .map(|p| {
            if values.len() <= 2 {
                values.insert(p.0);
            }
            p.0.iter().any(|&c| c != 0)
        })
        .collect();
    if values.len() > 2 {
        let (what, labels) = match masked {
            Masked::Sky => (
                "sky",
                "for a Cityscapes label PNG give `sky_mask_format` cityscapes-labelids or \
                 cityscapes-trainids",
            ),
            Masked::EgoVehicle => (
                "the ego vehicle",
                "a Cityscapes label PNG is read as labels when named *_labelIds.png",
            ),
        };
        log::warn!(
            "{name}: a binary mask with more than two values (every non-zero pixel is \
             {what}); {labels}"
        );
    }
    mask
}

/// The label of every pixel of a one-channel (grey, 8- or 16-bit) PNG.
fn label_values(img: &DynamicImage, name: &str, format: SkyMaskFormat) -> Result<Vec<u16>> {
    match img {
        DynamicImage::ImageLuma8(g) => Ok(g.as_raw().iter().map(|&v| u16::from(v)).collect()),
        DynamicImage::ImageLuma16(g) => Ok(g.as_raw().clone()),
        other => Err(Error::format(
            name,
            format!(
                "a {format} mask is one grey channel of label ids, but this PNG is {:?} \
                 (a Cityscapes *_color.png? give the *_labelIds.png, or a binary mask with \
                 `sky_mask_format` binary)",
                other.color()
            ),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png(img: DynamicImage) -> Vec<u8> {
        let mut out = std::io::Cursor::new(Vec::new());
        img.write_to(&mut out, image::ImageFormat::Png).unwrap();
        out.into_inner()
    }

    #[test]
    fn formats_from_names_and_text() {
        let f = |n: &str| SkyMaskFormat::from_file_name(Path::new(n));
        assert_eq!(
            f("aachen_000000_000019_gtFine_labelIds.png"),
            SkyMaskFormat::CityscapesLabelIds
        );
        assert_eq!(
            f("x_gtFine_labelTrainIds.png"),
            SkyMaskFormat::CityscapesTrainIds
        );
        assert_eq!(f("x_gtFine_color.png"), SkyMaskFormat::Binary);
        assert_eq!(f("sky.png"), SkyMaskFormat::Binary);
        for format in SkyMaskFormat::ALL {
            assert_eq!(format.name().parse::<SkyMaskFormat>(), Ok(format));
        }
        assert!("labelids".parse::<SkyMaskFormat>().is_err());
    }

    #[test]
    fn labels_and_binary_values() {
        let labels = image::GrayImage::from_raw(3, 1, vec![23, 10, 0]).unwrap();
        let bytes = png(DynamicImage::ImageLuma8(labels));
        let get = |f| decode_sky_mask(&bytes, "m.png", f).unwrap().into_vec();
        assert_eq!(get(SkyMaskFormat::CityscapesLabelIds), [true, false, false]);
        assert_eq!(get(SkyMaskFormat::CityscapesTrainIds), [false, true, false]);
        assert_eq!(get(SkyMaskFormat::Binary), [true, true, false]);
        let labels = image::GrayImage::from_raw(3, 1, vec![1, 23, 0]).unwrap();
        let bytes = png(DynamicImage::ImageLuma8(labels));
        let ego = |f| decode_ego_mask(&bytes, "m.png", f).map(|m| m.into_vec());
        assert_eq!(
            ego(SkyMaskFormat::CityscapesLabelIds).unwrap(),
            [true, false, false]
        );
        assert_eq!(ego(SkyMaskFormat::Binary).unwrap(), [true, true, false]);
        let err = ego(SkyMaskFormat::CityscapesTrainIds)
            .unwrap_err()
            .to_string();
        assert!(err.contains("labelIds"), "{err}");
    }

    #[test]
    fn colour_labels_and_jpeg_are_refused() {
        let rgb = image::RgbImage::from_raw(1, 1, vec![70, 130, 180]).unwrap();
        let bytes = png(DynamicImage::ImageRgb8(rgb));
        let err = decode_sky_mask(&bytes, "c.png", SkyMaskFormat::CityscapesLabelIds);
        assert!(matches!(err, Err(Error::Format { .. })), "{err:?}");
        assert_eq!(
            decode_sky_mask(&bytes, "c.png", SkyMaskFormat::Binary)
                .unwrap()
                .into_vec(),
            [true]
        );
        let err = decode_sky_mask(b"\xff\xd8\xff\xe0", "m.jpg", SkyMaskFormat::Binary);
        assert!(matches!(err, Err(Error::Format { .. })), "{err:?}");
    }
}
