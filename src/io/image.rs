//! Colour images, as linear light: PNG, JPEG, WebP or TIFF (WebP and TIFF with the `codecs`
//! feature) in sRGB, decoded by the sRGB curve (or by their colour profile's); and the
//! float images renderers, engines and 3D tools write, OpenEXR, colour PFM and float
//! TIFF, whose values are linear already and are taken as they are (values above 1
//! included).
//!
//! The format is told by the file's first bytes (its magic number), not by its name, as
//! for PNG and JPEG before: the file name is only used in messages.
//!
//! A colour image's EXIF orientation is applied, as viewers apply it: a phone photo held
//! upright is stored sideways with a tag, and the fog's sky and horizon are found from the
//! top of the upright frame ([`load_upright_rgb`] says which orientation was applied, so
//! that its depth map is turned with it: [`crate::io::depth::PhotoGeometry`]). Maps (depth,
//! masks) are read as stored. A colour image's embedded ICC profile is read
//! ([`crate::io::colour_profile`]: Display P3 and the like are kept, and decoded by their
//! own curves where those are not sRGB's); a PNG's `cICP`, `gAMA` and `cHRM` chunks are
//! read too; with none of these, a PNG or JPEG is sRGB. An
//! EXR's `chromaticities` other than sRGB's (ACEScg's) become a profile of its primaries,
//! which its outputs say; without them its primaries are taken to be sRGB's.
//!
//! Float values: above 1 (HDR) they are kept; a NaN or infinite value is refused, naming
//! the first pixel holding one (the fog's blur would spread it over its whole footprint);
//! a negative value (the ringing of a sharp reconstruction filter, a denoiser's
//! undershoot: no light is negative) is clamped to 0, with a warning in the log. Alpha is
//! dropped without un-premultiplying: EXR colour is premultiplied by convention, so a
//! transparent background reads as black.

use std::path::Path;

use image::{DynamicImage, ImageDecoder, ImageFormat, ImageReader};

use crate::io::codec::exr::parse_exr_rgb;
use crate::io::codec::pfm::{parse_pfm, Pfm};
use crate::io::colour_profile::{ColourProfile, StatedColour};
pub(crate) use crate::io::heif::refuse_heif_bytes;
pub use crate::io::heif::{heif_brand, refuse_heif};
use crate::io::limits::check_size;
use crate::io::metadata::PhotoMetadata;
pub use crate::io::png_chunks::MAX_ICC_BYTES;
use crate::io::png_chunks::{
    check_png_chunks, describe_chromaticities, is_srgb_chrm, png_colour, png_ihdr_size, PngColour,
    PNG_IHDR_END,
};
use crate::raster::{Orientation, RgbImage};
use crate::{Error, Result};

pub use crate::io::srgb::{
    linear_rgba_to_srgb8_rgb, linear_to_srgb, linear_to_srgb8, linear_to_srgb8_rgb,
    srgb8_rgb_to_linear, srgb8_to_linear_table, srgb_to_linear,
};

/// What a photo's EXIF says that brume uses. Unreadable EXIF is none, as for a viewer.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhotoExif {
    /// The orientation that turned the stored pixels upright.
    pub orientation: Orientation,
    /// `FocalLengthIn35mmFilm` in mm, where given and not 0 (the tag's "unknown").
    pub focal_35mm: Option<f64>,
}

impl PhotoExif {
    /// Reads the orientation (`Orientation`, IFD0) and the 35 mm equivalent focal length
    /// (`FocalLengthIn35mmFilm`, Exif IFD) from an EXIF block (TIFF data) of an image
    /// stored `size` (width, height). The focal length is dropped, with a warning, where
    /// the size the camera wrote (`PixelXDimension` x `PixelYDimension`) has another
    /// aspect ratio: the photo was cropped, and its field of view is not the tag's.
    fn parse(tiff: Vec<u8>, name: &str, size: (u32, u32)) -> PhotoExif {
        let exif = match exif::Reader::new().read_raw(tiff) {
            Ok(exif) => exif,
            Err(e) => {
                log::debug!("{name}: EXIF not read ({e})");
                return PhotoExif::default();
            }
        };
        let uint = |tag| {
            let field = exif.get_field(tag, exif::In::PRIMARY)?;
            field.value.get_uint(0)
        };
        let orientation = uint(exif::Tag::Orientation)
            .and_then(|v| u16::try_from(v).ok())
            .and_then(Orientation::from_exif)
            .unwrap_or_default();
        let mut focal_35mm = uint(exif::Tag::FocalLengthIn35mmFilm)
            .filter(|&mm| mm > 0)
            .map(f64::from);
        // 0 is the tags' "unknown". Long side over short: a tool that turned the pixels
        // without swapping the tags has not changed the field of view.
        let written = uint(exif::Tag::PixelXDimension)
            .zip(uint(exif::Tag::PixelYDimension))
            .filter(|&(w, h)| w > 0 && h > 0);
        if let (Some(f35), Some((w, h))) = (focal_35mm, written) {
            let aspect = |(w, h): (u32, u32)| f64::from(w.max(h)) / f64::from(w.min(h).max(1));
            if (aspect((w, h)) / aspect(size) - 1.0).abs() > CROP_TOLERANCE {
                log::warn!(
                    "{name}: its EXIF focal length ({f35} mm in 35 mm terms) is not used: \
                     the image is {}x{}, but the camera wrote {w}x{h} (a crop changes the \
                     field of view); give the field of view (`fov`)",
                    size.0,
                    size.1
                );
                focal_35mm = None;
            }
        }
        PhotoExif {
            orientation,
            focal_35mm,
        }
    }
}

/// How far a photo's aspect ratio may be from the one its EXIF says the camera wrote,
/// relatively, before it counts as cropped: sizes rounded to even pixels, or to a
/// codec's blocks, stay within it.
const CROP_TOLERANCE: f64 = 0.01;

/// The formats [`load_linear_rgb`] reads, for messages.
const COLOUR_FORMATS: &str = "a PNG, JPEG, WebP or TIFF (sRGB), an OpenEXR (.exr, linear) \
     or a colour PFM (`PF`, linear) file";

/// Loads a colour image as linear light: a PNG, JPEG, WebP or TIFF (8- or 16-bit, grey or
/// RGB, alpha dropped) converted from sRGB, or an OpenEXR, colour PFM or float TIFF taken
/// as linear (see the module docs for the EXR channels read and for NaN and negative
/// values). Errors name the file; sizes beyond `io::limits` are refused before the pixels
/// are allocated. The image is turned upright by its EXIF orientation
/// ([`load_upright_rgb`]).
pub fn load_linear_rgb(path: &Path) -> Result<RgbImage> {
    Ok(load_upright_rgb(path)?.image)
}

/// A colour image as [`load_upright_rgb`] reads it: its pixels turned upright, what its
/// EXIF says, and the colour profile and EXIF block its outputs carry.
#[derive(Clone, Debug)]
pub struct UprightPhoto {
    /// Linear light, row 0 at the top of the upright frame.
    pub image: RgbImage,
    /// What its EXIF says (none for EXR and PFM): the orientation applied, which the
    /// photo's depth map is turned by, and its focal length.
    pub exif: PhotoExif,
    /// Its embedded ICC profile, where it has a usable one, and its EXIF block, for its
    /// outputs to carry.
    pub metadata: PhotoMetadata,
    /// Whether the file holds linear light: an EXR, a PFM, or an image whose profile's
    /// curves are linear (a RAW developed to a linear TIFF or PNG). Otherwise its codes
    /// are display-encoded, and a camera's tone curve may have bent them beyond what the
    /// profile says.
    pub linear_light: bool,
}

/// [`load_linear_rgb`], with what its EXIF says and the metadata its outputs carry.
pub fn load_upright_rgb(path: &Path) -> Result<UprightPhoto> {
    let bytes = crate::io::limits::read_file(path)?;
    decode_upright_rgb(&bytes, &path.display().to_string())
}

/// Same as [`load_linear_rgb`] for bytes already in memory (an embedded asset); `name`
/// stands for the file in error messages. The format is told by the first bytes.
///
/// From an OpenEXR file, the `R`, `G`, `B` channels are read: the flat ones, else those
/// of the first layer with `Combined` in its name (Blender multilayer:
/// `ViewLayer.Combined.R`), else those of the first layer that has all three; failing
/// that, a lone `Y` channel as grey. Which channels were used is logged. A file holding
/// only depth is refused, with a hint to give it as the depth map.
pub fn decode_linear_rgb(bytes: &[u8], name: &str) -> Result<RgbImage> {
    Ok(decode_upright_rgb(bytes, name)?.image)
}

/// [`decode_linear_rgb`], with what its EXIF says and the metadata its outputs carry.
pub fn decode_upright_rgb(bytes: &[u8], name: &str) -> Result<UprightPhoto> {
    let path = Path::new(name);
    let upright = |image| {
        Ok(UprightPhoto {
            image,
            exif: PhotoExif::default(),
            metadata: PhotoMetadata::default(),
            linear_light: true,
        })
    };
    if bytes.starts_with(&EXR_MAGIC) {
        let exr = parse_exr_rgb(bytes, path)?;
        log::info!("{name}: linear colour from EXR channels {}", exr.source);
        return Ok(UprightPhoto {
            image: linear_float(exr.image, name)?,
            exif: PhotoExif::default(),
            metadata: PhotoMetadata {
                profile: exr.chromaticities.and_then(|c| exr_profile(c, name)),
                exif: None,
            },
            linear_light: true,
        });
    }
    if is_pfm(bytes) {
        return match parse_pfm(bytes, path)? {
            Pfm::Rgb(image) => upright(linear_float(image, name)?),
            Pfm::Grey(_) => Err(grey_pfm(path)),
        };
    }
    let (mut decoded, exif, metadata) = decode_image(bytes, name, COLOUR_FORMATS, Role::Colour)?;
    let orientation = exif.orientation;
    if orientation != Orientation::Upright {
        log::info!(
            "{name}: {} upright, as its EXIF orientation says",
            orientation.describe()
        );
        let code = u8::try_from(orientation.exif()).expect("1 to 8");
        let theirs = image::metadata::Orientation::from_exif(code).expect("1 to 8");
        decoded.apply_orientation(theirs);
    }
    if matches!(
        decoded,
        DynamicImage::ImageRgb32F(_) | DynamicImage::ImageRgba32F(_)
    ) {
        // A float TIFF, as HDR merges and renderers write: linear already, as an EXR.
        let rgb = decoded.to_rgb32f();
        let (w, h) = (rgb.width() as usize, rgb.height() as usize);
        let image = RgbImage::from_vec(w, h, rgb.pixels().map(|p| p.0).collect());
        return Ok(UprightPhoto {
            image: linear_float(image, name)?,
            exif,
            metadata,
            linear_light: true,
        });
    }
    Ok(UprightPhoto {
        image: to_linear_rgb(&decoded, metadata.profile()),
        exif,
        linear_light: metadata
            .profile()
            .is_some_and(ColourProfile::has_linear_curves),
        metadata,
    })
}

/// The profile of an EXR whose `chromaticities` (red, green, blue, white) are not sRGB's
/// (ACEScg's, Display P3's): its linear values are in those primaries, which its outputs
/// then say (see [`ColourProfile::from_stated`]).
fn exr_profile([r, g, b, w]: [[f64; 2]; 4], name: &str) -> Option<ColourProfile> {
    let chromaticities = [w, r, g, b];
    if is_srgb_chrm(&chromaticities) {
        return None;
    }
    let stated = StatedColour {
        primaries: [r, g, b],
        white: w,
        curve: moxcms::ToneReprCurve::Parametric(vec![1.0]),
        description: format!(
            "EXR chromaticities {}",
            describe_chromaticities(&chromaticities)
        ),
    };
    ColourProfile::from_stated(stated, name)
}

/// The first four bytes of every OpenEXR file.
pub(crate) const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

/// Whether the bytes start like a PFM: `PF` or `Pf`, then whitespace (or nothing, so that
/// a file cut after its magic gets the PFM reader's message).
fn is_pfm(bytes: &[u8]) -> bool {
    (bytes.starts_with(b"PF") || bytes.starts_with(b"Pf"))
        && bytes.get(2).is_none_or(|b| b.is_ascii_whitespace())
}

/// The refusal of a grey PFM as a colour image. One unnamed channel is, in practice, a
/// disparity or depth map (Middlebury's disp0.pfm), unlike an EXR's `Y`, which names
/// luminance.
fn grey_pfm(path: &Path) -> Error {
    Error::format(
        path,
        "PFM is `Pf` (one channel, usually depth or disparity); a colour PFM is `PF` \
         (3 channels)",
    )
}

/// The size of the colour image in the EXR or PFM file `bytes` from its header, as
/// [`decode_upright_rgb`] would decode it (its errors, where the header is enough to
/// tell); `None` for other files.
fn float_image_size(bytes: &[u8], path: &Path) -> Option<Result<(usize, usize)>> {
    if bytes.starts_with(&EXR_MAGIC) {
        return Some(crate::io::codec::exr::exr_colour_size(bytes, path));
    }
    if is_pfm(bytes) {
        let header = crate::io::codec::pfm::parse_header(bytes, path);
        return Some(header.and_then(|h| match h.channels {
            3 => Ok((h.width, h.height)),
            _ => Err(grey_pfm(path)),
        }));
    }
    None
}

/// Checks a float image's values as the module docs say: refuses the first NaN or
/// infinite value, with its pixel, and clamps negative values to 0, with a warning.
fn linear_float(mut image: RgbImage, name: &str) -> Result<RgbImage> {
    let width = image.width();
    finite_light(image.as_mut_slice(), width, name, "colour", ["R", "G", "B"])?;
    Ok(image)
}

/// Refuses the first NaN or infinite value of `pixels` (rows of `width`), naming the pixel
/// and its channel of `channels`, and sets negative values of the R, G and B channels (the
/// first three) to 0, with a warning in the log: the checks of float colour images and of
/// inserted objects, whose light and coverage the fog's blur would spread over the frame.
/// `what` names the values in the message.
pub(crate) fn finite_light<const N: usize>(
    pixels: &mut [[f32; N]],
    width: usize,
    name: &str,
    what: &str,
    channels: [&str; N],
) -> Result<()> {
    let values = pixels.iter().flatten();
    if let Some(i) = values.clone().position(|v| !v.is_finite()) {
        let (pixel, channel) = (i / N, i % N);
        let count = values.filter(|v| !v.is_finite()).count();
        return Err(Error::format(
            name,
            format!(
                "{what} value {} at pixel ({}, {}) (x, y from the top left), channel {}; \
                 {count} value(s) are NaN or infinite in all, and brume needs finite values: \
                 fix them in the renderer or compositor",
                pixels[pixel][channel],
                pixel % width,
                pixel / width,
                channels[channel]
            ),
        ));
    }
    let mut negative = 0usize;
    let mut lowest = 0.0f32;
    for v in pixels.iter_mut().flat_map(|p| &mut p[..N.min(3)]) {
        if *v < 0.0 {
            negative += 1;
            lowest = lowest.min(*v);
            *v = 0.0;
        }
    }
    if negative > 0 {
        log::warn!("{name}: {negative} negative colour value(s), down to {lowest}, set to 0");
    }
    Ok(())
}

/// Decodes PNG or JPEG bytes without any colour conversion; shared with the depth loaders
/// so that 8- and 16-bit PNG depth maps keep their raw values.
pub(crate) fn decode_any(bytes: &[u8], name: &str) -> Result<DynamicImage> {
    let (image, ..) = decode_image(bytes, name, "a PNG or JPEG file", Role::Map)?;
    Ok(image)
}

/// What a decoded file is to brume, for the one thing that differs: a colour image's EXIF
/// orientation is read, to be applied; a map's (depth, transmittance, mask, noise) is
/// not, as the map is read as stored and turned with its photo.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Role {
    Colour,
    Map,
}

/// PNG, JPEG or (for a colour image, with the `codecs` feature) WebP or TIFF bytes checked
/// (their kind, a JPEG's end, a PNG's palette) and opened, no pixel decoded yet;
/// `expected` is what the caller accepts, for the message on data that is none of them.
fn open_decoder<'a>(
    bytes: &'a [u8],
    name: &str,
    expected: &str,
    role: Role,
) -> Result<(impl ImageDecoder + 'a, ImageFormat)> {
    refuse_heif_bytes(bytes, name)?;
    let mut reader = ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| Error::io(name, e))?;
    let Some(format) = reader.format() else {
        return Err(Error::format(
            name,
            format!(
                "unrecognised image data (starts with {}); expected {expected}",
                hex_prefix(bytes)
            ),
        ));
    };
    let readable = match format {
        ImageFormat::Png | ImageFormat::Jpeg => true,
        // A photo: maps are lossless data, which lossy WebP is not; a TIFF map is read
        // by `io::codec::tiff`.
        ImageFormat::WebP | ImageFormat::Tiff => role == Role::Colour,
        _ => false,
    };
    if !readable {
        // Recognised by its magic number, but no decoder is built in for it.
        return Err(Error::format(
            name,
            format!("this is a {format:?} image, which is not read; expected {expected}"),
        ));
    }
    if matches!(format, ImageFormat::WebP | ImageFormat::Tiff) && !cfg!(feature = "codecs") {
        return Err(Error::format(
            name,
            format!(
                "this is a {format:?} image, which this build of brume does not read (its \
                 `codecs` feature is off): convert it to PNG or JPEG, or build brume with \
                 that feature"
            ),
        ));
    }
    if format == ImageFormat::Jpeg && !jpeg_reaches_end_marker(bytes) {
        // The JPEG decoder pads a truncated scan with grey instead of failing.
        return Err(Error::format(
            name,
            "JPEG data ends before its end-of-image marker; the file is truncated",
        ));
    }
    if format == ImageFormat::Png {
        check_png_chunks(bytes, name)?;
    }
    reader.limits(decoder_limits(format));
    let decoder = reader.into_decoder().map_err(cannot_decode(format, name))?;
    Ok((decoder, format))
}

/// The image crate's memory limit for decoding an image of `format`. Its default, 512 MiB,
/// holds any 8- or 16-bit image within `io::limits`, but refused an 8000x6000 float TIFF
/// (576 MB in RGB f32) with "Memory limit exceeded"; a TIFF may take what the largest image
/// `io::limits` allows takes in RGBA f32, 1 GiB. The memory left is checked before, from
/// the header ([`crate::photo::check_memory_before_decoding`]).
fn decoder_limits(format: ImageFormat) -> image::Limits {
    let mut limits = image::Limits::default();
    if format == ImageFormat::Tiff {
        limits.max_alloc = Some(crate::io::limits::MAX_PIXELS as u64 * 16);
    }
    limits
}

/// The error of an image the decoder gave up on: one it does not read, or a damaged one.
fn cannot_decode(format: ImageFormat, name: &str) -> impl Fn(image::ImageError) -> Error + '_ {
    move |e| {
        let why = match e {
            // A variant the decoder does not read (a TIFF of 64-bit floats): not damage.
            image::ImageError::Unsupported(_) => {
                "brume reads 8- and 16-bit integer and 32-bit float samples: convert it (to \
                 PNG, or to a float EXR or 32-bit float TIFF)"
            }
            _ => "the file may be truncated or corrupt",
        };
        Error::format(name, format!("cannot decode as {format:?}: {e}; {why}"))
    }
}

/// The EXIF of an opened image (`bytes`, of `format`), and its block as stored; none that
/// cannot be read. A TIFF's tags are in the file's own directories, which are read but
/// not copied to the outputs (they point into the file's pixel data).
fn exif_of(
    decoder: &mut impl ImageDecoder,
    (bytes, format): (&[u8], ImageFormat),
    name: &str,
) -> (PhotoExif, Option<Vec<u8>>) {
    let size = decoder.dimensions();
    if format == ImageFormat::Tiff {
        return (PhotoExif::parse(bytes.to_vec(), name, size), None);
    }
    match decoder.exif_metadata() {
        Ok(Some(tiff)) => (PhotoExif::parse(tiff.clone(), name, size), Some(tiff)),
        _ => (PhotoExif::default(), None),
    }
}

/// The stored size of image `bytes` (the file `name`) from its header, after the checks
/// every read of it makes (a JPEG's end, a PNG's palette and ICC profile, an EXR's
/// headers), without decoding its pixels: for checks before a decode. An EXR's or a PFM's
/// is its colour image's, as [`decode_upright_rgb`] reads it. Errors: the loaders'.
pub fn image_dimensions(bytes: &[u8], name: &str) -> Result<(u32, u32)> {
    if let Some(size) = float_image_size(bytes, Path::new(name)) {
        // Within io::limits' sides, which u32 holds.
        return size.map(|(w, h)| (w as u32, h as u32));
    }
    let (decoder, _) = open_decoder(bytes, name, "a PNG, JPEG or WebP file", Role::Colour)?;
    Ok(decoder.dimensions())
}

/// The stored size of the PNG or JPEG file at `path`, from its header: for checks of many
/// files before any is decoded. A PNG's is its first chunk (`IHDR`), so nothing after it
/// is read (its ICC profile is not inflated); a JPEG is read whole, as the decoder does,
/// and checked as [`image_dimensions`] checks it. Errors: the loaders'.
pub fn read_image_dimensions(path: &Path) -> Result<(u32, u32)> {
    use std::io::Read;
    let mut head = [0; PNG_IHDR_END];
    // A file that cannot be opened, or is shorter, gets its error from the whole read.
    let read = std::fs::File::open(path).and_then(|mut f| f.read_exact(&mut head));
    if let Some(size) = read.ok().and_then(|()| png_ihdr_size(&head)) {
        return Ok(size);
    }
    let bytes = crate::io::limits::read_file(path)?;
    image_dimensions(&bytes, &path.display().to_string())
}

/// A photo's stored size and EXIF, read from its header without decoding its pixels
/// (an EXR or a PFM has no EXIF).
pub fn read_photo_header(path: &Path) -> Result<(usize, usize, PhotoExif)> {
    let bytes = crate::io::limits::read_file(path)?;
    let name = path.display().to_string();
    if let Some(size) = float_image_size(&bytes, path) {
        let (w, h) = size?;
        return Ok((w, h, PhotoExif::default()));
    }
    let (mut decoder, format) = open_decoder(&bytes, &name, COLOUR_FORMATS, Role::Colour)?;
    let (w, h) = decoder.dimensions();
    let exif = exif_of(&mut decoder, (&bytes, format), &name).0;
    Ok((w as usize, h as usize, exif))
}

/// [`decode_any`], with what the caller accepts (`expected`) for the message on data that
/// is none of them, and the file's `role`; with a colour image's EXIF (its orientation not
/// applied), colour profile and EXIF block.
fn decode_image(
    bytes: &[u8],
    name: &str,
    expected: &str,
    role: Role,
) -> Result<(DynamicImage, PhotoExif, PhotoMetadata)> {
    let (mut decoder, format) = open_decoder(bytes, name, expected, role)?;
    let cannot = cannot_decode(format, name);
    let (exif, metadata) = match role {
        Role::Colour => {
            let (exif, block) = exif_of(&mut decoder, (bytes, format), name);
            let profile = match format {
                ImageFormat::Png => match png_colour(bytes, name)? {
                    PngColour::IccProfile => profile_of(&mut decoder, name),
                    PngColour::Srgb => None,
                    PngColour::Stated(profile) => Some(profile),
                },
                // The image crate's TIFF decoder drops a profile larger than its pixels
                // allow for (a small image's); the tiff crate's own limits do not.
                #[cfg(feature = "codecs")]
                ImageFormat::Tiff => crate::io::codec::tiff::icc_profile(bytes, name)
                    .and_then(|icc| ColourProfile::from_icc(icc, name)),
                _ => profile_of(&mut decoder, name),
            };
            let metadata = PhotoMetadata {
                profile,
                exif: block.map(std::sync::Arc::new),
            };
            (exif, metadata)
        }
        Role::Map => (PhotoExif::default(), PhotoMetadata::default()),
    };
    // The size is checked from the header, before the pixel buffer is allocated.
    let (w, h) = decoder.dimensions();
    check_size(
        Path::new(name),
        &format!("{format:?}"),
        u64::from(w),
        u64::from(h),
    )?;
    if format == ImageFormat::Jpeg {
        check_jpeg_holds(bytes.len(), w, h, name)?;
    }
    // The budget `ImageReader::decode` applies, which `into_decoder` leaves to its caller.
    decoder_limits(format)
        .reserve(decoder.total_bytes())
        .map_err(&cannot)?;
    let image = DynamicImage::from_decoder(decoder).map_err(cannot)?;
    Ok((image, exif, metadata))
}

/// The colour profile of an opened PNG or JPEG ([`ColourProfile::from_icc`]); none where
/// it has none or it cannot be used.
fn profile_of(decoder: &mut impl ImageDecoder, name: &str) -> Option<ColourProfile> {
    match decoder.icc_profile() {
        Ok(Some(icc)) => ColourProfile::from_icc(icc, name),
        Ok(None) => None,
        Err(e) => {
            log::warn!("{name}: its ICC colour profile cannot be read ({e}); taken as sRGB");
            None
        }
    }
}

/// Fewest pixels per byte a JPEG can hold, with a margin: every 8x8 block of every scan
/// costs at least one bit (a DC difference; progressive AC scans can skip blocks in runs),
/// so 512 pixels a byte at most, halved for safety.
const JPEG_MAX_PIXELS_PER_BYTE: u64 = 1024;

/// Refuses a JPEG too short for the size it claims. The decoder fills what the scan data
/// does not cover instead of failing, so a 1 kB file claiming 10280x10280 took 10 s and
/// 1.9 GB to decode into a grey picture.
fn check_jpeg_holds(len: usize, w: u32, h: u32, name: &str) -> Result<()> {
    let pixels = u64::from(w) * u64::from(h);
    let needed = pixels / JPEG_MAX_PIXELS_PER_BYTE;
    if (len as u64) < needed {
        return Err(Error::format(
            name,
            format!(
                "JPEG header claims {w}x{h} pixels, which need at least {needed} bytes, but the \
                 file has {len}; it is truncated or corrupt"
            ),
        ));
    }
    Ok(())
}

/// Walks the JPEG marker segments from SOI and the entropy-coded data after each SOS, and
/// says whether an EOI marker is reached before the bytes run out. Segments are skipped by
/// their length, so an EXIF thumbnail's own EOI does not count.
fn jpeg_reaches_end_marker(b: &[u8]) -> bool {
    if !b.starts_with(&[0xFF, 0xD8]) {
        return false;
    }
    let mut i = 2;
    while i < b.len() {
        if b[i] != 0xFF {
            i += 1;
            continue;
        }
        while i < b.len() && b[i] == 0xFF {
            i += 1; // fill bytes
        }
        let Some(&marker) = b.get(i) else {
            return false;
        };
        i += 1;
        match marker {
            0xD9 => return true,
            // Stuffed zero, restart markers and TEM carry no length.
            0x00 | 0x01 | 0xD0..=0xD7 => {}
            _ => {
                let Some(len) = b.get(i..i + 2) else {
                    return false;
                };
                i += usize::from(u16::from_be_bytes([len[0], len[1]]));
                if marker == 0xDA {
                    i = skip_entropy_coded_data(b, i);
                }
            }
        }
    }
    false
}

/// Index of the first marker after a scan's entropy-coded data (or `b.len()`).
fn skip_entropy_coded_data(b: &[u8], mut i: usize) -> usize {
    while i + 1 < b.len() {
        if b[i] == 0xFF && !matches!(b[i + 1], 0x00 | 0xD0..=0xD7) {
            return i;
        }
        i += 1;
    }
    b.len()
}

fn hex_prefix(bytes: &[u8]) -> String {
    if bytes.is_empty() {
        return "nothing: the file is empty".to_string();
    }
    bytes
        .iter()
        .take(8)
        .map(|b| format!("{b:02x}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// Linear light of a decoded PNG or JPEG: by its profile's own curves where it has them,
/// else by sRGB's.
fn to_linear_rgb(img: &DynamicImage, profile: Option<&ColourProfile>) -> RgbImage {
    let (w, h) = (img.width() as usize, img.height() as usize);
    let is_8bit = matches!(
        img,
        DynamicImage::ImageLuma8(_)
            | DynamicImage::ImageLumaA8(_)
            | DynamicImage::ImageRgb8(_)
            | DynamicImage::ImageRgba8(_)
    );
    let data = match (profile.and_then(ColourProfile::own_curves), is_8bit) {
        (Some(curves), true) => img
            .to_rgb8()
            .pixels()
            .map(|px| curves.decode(px.0.map(|c| u16::from(c) * 257)))
            .collect(),
        (Some(curves), false) => img
            .to_rgb16()
            .pixels()
            .map(|px| curves.decode(px.0))
            .collect(),
        (None, true) => srgb8_rgb_to_linear(img.to_rgb8().as_raw()),
        (None, false) => img
            .to_rgb32f()
            .pixels()
            .map(|p| p.0.map(srgb_to_linear))
            .collect(),
    };
    RgbImage::from_vec(w, h, data)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::png_chunks::png_of_chunks;

    /// An 8-bit palette PNG of 2x1 pixels (indices 0, 1) whose PLTE chunk holds `palette`,
    /// CRCs left at 0 (the palette check reads only lengths and types).
    fn palette_png(palette: &[u8]) -> Vec<u8> {
        png_of_chunks(&[
            (b"IHDR", &[0, 0, 0, 2, 0, 0, 0, 1, 8, 3, 0, 0, 0]),
            (b"PLTE", palette),
            (
                b"IDAT",
                &[0x78, 0x01, 1, 3, 0, 0xfc, 0xff, 0, 0, 1, 0, 4, 0, 2],
            ),
            (b"IEND", &[]),
        ])
    }

    #[test]
    fn a_palette_of_partial_entries_is_refused_before_decoding() {
        for len in [4, 5, 521, 767] {
            let png = palette_png(&vec![7; len]);
            let e = check_png_chunks(&png, "m.png").unwrap_err().to_string();
            assert!(
                e.starts_with("m.png: ") && e.contains(&format!("PLTE chunk) of {len} bytes")),
                "{e}"
            );
            // The whole decoder refuses it too, where png 0.18.1 alone panics.
            let e = decode_any(&png, "m.png").unwrap_err().to_string();
            assert!(e.contains("PLTE"), "{e}");
        }
        for len in [3, 6, 768] {
            assert!(check_png_chunks(&palette_png(&vec![7; len]), "m.png").is_ok());
        }
        // Truncated files, and lengths that would overflow the walk, are left to the
        // decoder.
        let png = palette_png(&[1, 2, 3, 4]);
        for end in 0..png.len() {
            let _ = check_png_chunks(&png[..end], "m.png");
        }
        let mut huge = palette_png(&[1, 2, 3]);
        huge[8..12].copy_from_slice(&u32::MAX.to_be_bytes());
        assert!(check_png_chunks(&huge, "m.png").is_ok());
    }

    /// A PNG of one 1x1 grey pixel with an `iCCP` chunk whose profile inflates to `size`
    /// zero bytes (CRCs left at 0: the check reads lengths and types, and it refuses before
    /// the decoder reads the chunks).
    fn iccp_png(size: usize) -> Vec<u8> {
        let mut iccp = b"bomb\0\0".to_vec();
        iccp.extend(fdeflate::compress_to_vec(&vec![0; size]));
        png_of_chunks(&[
            (b"IHDR", &[0, 0, 0, 1, 0, 0, 0, 1, 8, 0, 0, 0, 0]),
            (b"iCCP", &iccp),
            (b"IEND", &[]),
        ])
    }

    /// A PNG's size is read from its first chunk alone: the header of a file cut short
    /// after `IHDR` (which the decoder cannot open) is enough, and a profile that inflates
    /// beyond any is not inflated; a JPEG is checked as a decode checks it.
    #[test]
    fn a_pngs_size_is_read_from_its_first_chunk() {
        let dir = tempfile::tempdir().unwrap();
        let mut bomb = iccp_png(MAX_ICC_BYTES + 1);
        bomb[16..24].copy_from_slice(&[0, 0, 0x1f, 0x40, 0, 0, 0x17, 0x70]);
        let cut = dir.path().join("cut.png");
        std::fs::write(&cut, &bomb[..PNG_IHDR_END]).unwrap();
        assert_eq!(read_image_dimensions(&cut).unwrap(), (8000, 6000));
        assert!(image_dimensions(&bomb[..PNG_IHDR_END], "cut.png").is_err());
        let whole = dir.path().join("bomb.png");
        std::fs::write(&whole, &bomb).unwrap();
        assert_eq!(read_image_dimensions(&whole).unwrap(), (8000, 6000));
        let short = dir.path().join("short.jpg");
        std::fs::write(&short, b"\xff\xd8\xff\xe0").unwrap();
        let e = read_image_dimensions(&short).unwrap_err().to_string();
        assert!(e.contains("short.jpg") && e.contains("truncated"), "{e}");
    }

    /// A profile that inflates beyond 10 MB is refused before the png crate inflates it
    /// (up to 512 MiB); one within is left to the decoder.
    #[test]
    fn an_iccp_chunk_that_inflates_beyond_any_profile_is_refused() {
        let bomb = iccp_png(MAX_ICC_BYTES + 1);
        assert!(bomb.len() < MAX_ICC_BYTES / 50, "{} bytes", bomb.len());
        let e = decode_linear_rgb(&bomb, "bomb.png")
            .unwrap_err()
            .to_string();
        assert!(e.contains("bomb.png") && e.contains("iCCP"), "{e}");
        assert!(check_png_chunks(&iccp_png(MAX_ICC_BYTES), "ok.png").is_ok());
    }

    /// The largest TIFF `io::limits` lets through fits the decoder's limit in RGBA f32 (an
    /// 8000x6000 float TIFF failed with "Memory limit exceeded" under the default 512 MiB,
    /// which the other formats keep).
    #[test]
    fn the_largest_float_tiff_fits_the_decoders_limit() {
        let rgba_f32 = crate::io::limits::MAX_PIXELS as u64 * 16;
        assert!(decoder_limits(ImageFormat::Tiff).reserve(rgba_f32).is_ok());
        assert!(decoder_limits(ImageFormat::Png)
            .reserve(8000 * 6000 * 12)
            .is_err());
    }
}
