//! Fog for a photograph with depth, as a library: what `brume render`, `prep` and `batch`
//! do between the files and the pixels, for hosts that are not the command line (the
//! Python package, a dataset tool, an app).
//!
//! ```no_run
//! use brume::photo::{self, FogOptions, Photo, PrepareOptions};
//! # fn main() -> brume::Result<()> {
//! let mut headless = brume::Headless::new(None)?;
//! let photo = Photo::load("street.png".as_ref(), "street_depth.exr".as_ref(), &Default::default())?;
//! let prepared = photo::prepare(&photo, &PrepareOptions::for_photo(&photo), headless.renderer()?)?;
//! let fogged = photo::fog(headless.renderer()?, &photo, &prepared, &FogOptions::beta(0.02)?)?;
//! // The photo's colour profile and EXIF go with it.
//! brume::io::output::write_photo("street_fog.png".as_ref(), &fogged.rendered.image, &photo.metadata)?;
//! # Ok(()) }
//! ```
//!
//! The steps, each usable alone: [`Photo`] (an image and its range, loaded or given),
//! [`preprocess`] (holes, sky, the airlight, on the depth map's grid: CPU only, so a
//! dataset's loader thread can run it), [`PreparedPhoto::refine`] (upsampling and the
//! guided filter, on the GPU or by the CPU references), [`insert()`] (a rendered object,
//! depth-tested, before the fog), [`fog()`] (the haze in normalised or physical units, with
//! the diffusion blur), [`transmittance_map`], and [`capture()`] (exposure, sensor noise
//! and JPEG after the fog; [`BetaDistribution`] draws β per frame).

mod aerial;
pub mod capture;
mod distribution;
mod fog;
mod frames;
mod insert;
mod prepare;

pub use aerial::{
    aerial, dehaze, display_encoded_sky, estimate_sky_photo, load_sky_photo, metres_per_unit,
    pitch_for_horizon_row, turbidity_from_sky, AerialOptions, AerialPhoto, HorizonFrom, PhotoView,
    Retarget, SkyTurbidity, ALTITUDE_RANGE_M, DEFAULT_HORIZON_ZENITH_DEG, MAX_PITCH_DEG,
    TURBIDITY_RANGE,
};
pub use capture::{capture, CaptureOptions, SensorNoise};
pub use distribution::BetaDistribution;
pub use fog::{
    fog, fog_each, medium_range, transmittance_map, Extinction, FogOptions, FoggedPhoto,
    SKY_RANGE_M,
};
pub use frames::{transmittance_rgb8, Conventions, Frame, FrameFog, FrameOptions};
pub use insert::{insert, Insertion, VirtualObject};
pub use prepare::{prepare, preprocess, AirlightFrom, PrepareOptions, PreparedPhoto};

use crate::error::{Error, Result};
use crate::io::depth::{
    self, DepthFormat, DepthKind, DepthOptions, LoadedDepth, PhotoGeometry, StereoView,
};
use crate::io::image::PhotoExif;
use crate::io::metadata::PhotoMetadata;
use crate::io::{demo, image};
use crate::memory::Reservation;
use crate::raster::{Orientation, RgbImage, ScalarMap};
use std::path::Path;

/// A photograph (linear RGB) and its range, with where they came from.
#[derive(Clone, Debug)]
pub struct Photo {
    /// Linear-light RGB, row 0 at the top.
    pub image: RgbImage,
    /// The range map (the image's size or smaller by one factor, see
    /// [`crate::refine::check_depth_size`]) and how it was read.
    pub depth: LoadedDepth,
    /// The image's name in messages (its path).
    pub image_name: String,
    /// The depth's name in messages (its path).
    pub depth_name: String,
    /// What the image's EXIF said (its orientation, applied; its focal length); the
    /// default for an image without one, or given as an array.
    pub exif: PhotoExif,
    /// The image's colour profile and EXIF block, which its PNG and JPEG outputs carry;
    /// none for an image without them, or given as an array.
    pub metadata: PhotoMetadata,
}

/// What [`Photo::drop_left_right_mismatches`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LeftRightCheck {
    /// Pixels of known range whose disparity failed the check, now unknown.
    pub failed: usize,
    /// Pixels the check compared: of known range, with a disparity whose match lies inside
    /// the other image ([`crate::prep::stereo::has_match_inside`]).
    pub checked: usize,
}

impl LeftRightCheck {
    /// Whether most pixels failed: true matches fail for a minority even on compressed,
    /// differently exposed real pairs (a fifth of Middlebury's Aloe JPEG pair's ground
    /// truth), wrong ones for most. A pair given the wrong way round (a right view's
    /// disparity read as a left view's, or the other image not the pair's) fails so.
    pub fn mostly_failed(&self) -> bool {
        2 * self.failed > self.checked
    }
}

/// Bytes per pixel that a render holds in system memory besides the GL textures: the
/// decoded colour (8-bit, then linear f32), the depth (raw, then range), pre-processing's
/// maps, the normalised range, the read-back and the encoded output. Measured: a
/// 4000x3000 render peaks at 1.44 GB on llvmpipe (2026-12-05), 120 bytes per pixel, of
/// which the textures (counted by the renderer's own check, with the coarse stage's
/// levels) are 80.
pub const CPU_BYTES_PER_PIXEL: u64 = 64;

impl Photo {
    /// Loads an image and its depth map (any format [`depth::load_range`] reads), after
    /// checking from the image's header that the work fits in the memory left.
    ///
    /// Errors: the loaders', [`Error::OutOfMemory`], and [`Error::InvalidParameter`] for a
    /// depth map neither the image's size nor smaller by one factor.
    ///
    /// The image is turned upright by its EXIF orientation and the depth map with it
    /// ([`DepthOptions::layout`] says how the map lies; `opts.photo` is set here).
    pub fn load(image_path: &Path, depth_path: &Path, opts: &DepthOptions) -> Result<Photo> {
        Photo::load_keeping(image_path, depth_path, opts, false).map(|(photo, _)| photo)
    }

    /// [`Photo::load`], and where the depth is a stereo pair's disparity, that disparity in
    /// pixels as the file stores it ([`depth::load_range_and_disparity`], the file decoded
    /// once), for [`Photo::drop_left_right_mismatches`]; `None` for other depth maps.
    pub fn load_stereo(
        image_path: &Path,
        depth_path: &Path,
        opts: &DepthOptions,
    ) -> Result<(Photo, Option<ScalarMap>)> {
        Photo::load_keeping(image_path, depth_path, opts, true)
    }

    /// [`Photo::load`], with the disparity in pixels too when `keep_disparity` asks for it.
    fn load_keeping(
        image_path: &Path,
        depth_path: &Path,
        opts: &DepthOptions,
        keep_disparity: bool,
    ) -> Result<(Photo, Option<ScalarMap>)> {
        let image::UprightPhoto {
            image,
            exif,
            metadata,
            ..
        } = load_image_within_memory(image_path)?;
        let opts = DepthOptions {
            photo: Some(PhotoGeometry::of_upright(
                image.width(),
                image.height(),
                exif,
            )),
            ..opts.clone()
        };
        let (depth, disparity_px) = if keep_disparity {
            depth::load_range_and_disparity(depth_path, &opts)?
        } else {
            (depth::load_range(depth_path, &opts)?, None)
        };
        let photo = Photo {
            image,
            depth,
            image_name: image_path.display().to_string(),
            depth_name: depth_path.display().to_string(),
            exif,
            metadata,
        };
        photo.check_depth_fits()?;
        Ok((photo, disparity_px))
    }

    /// A photo from arrays: `image` linear RGB and `range_m` the distance from the camera
    /// centre in metres (NaN, ≤ 0 or infinite where unknown), the image's size or smaller
    /// by one factor. Errors: [`Error::NoValidDepth`] (named `range_m`) where no pixel's
    /// range is known, as the loaders refuse such a file.
    pub fn from_range(image: RgbImage, range_m: ScalarMap) -> Result<Photo> {
        let unknown_pixels = range_m
            .as_slice()
            .iter()
            .filter(|v| !(v.is_finite() && **v > 0.0))
            .count();
        if unknown_pixels == range_m.len() {
            return Err(Error::NoValidDepth {
                path: "range_m".into(),
            });
        }
        let range = range_m.map(|&v| {
            if v.is_finite() && v > 0.0 {
                v
            } else {
                f32::NAN
            }
        });
        let photo = Photo {
            image,
            depth: LoadedDepth {
                range,
                format: DepthFormat::Float,
                kind: DepthKind::Range,
                units: "m".into(),
                metric: true,
                intrinsics: None,
                notes: Vec::new(),
                unknown_pixels,
                turned: Orientation::Upright,
                stereo_focal_baseline: None,
                stereo_view: StereoView::Left,
                mount: None,
            },
            // The arguments' names, as the messages say them.
            image_name: "image".into(),
            depth_name: "range_m".into(),
            exif: PhotoExif::default(),
            metadata: PhotoMetadata::default(),
        };
        photo.check_depth_fits()?;
        Ok(photo)
    }

    /// An image and a transmittance map τ (Foggy Cityscapes' and others' τ maps: an 8- or
    /// 16-bit grey PNG, as [`crate::compat::load_optical_depth`] reads it), the map read
    /// as its optical depth −ln τ: a range in "metres" for a fog of β = 1 m⁻¹, so that
    /// physical fog at β = 1 gives back the map's τ and the blur follows βR = −ln τ as it
    /// would from the range. Errors: the loaders', the memory check, a map of another
    /// size than the image.
    pub fn load_transmittance(image_path: &Path, map_path: &Path) -> Result<Photo> {
        // The map is taken as the photo is stored, as a depth map is.
        let image::UprightPhoto {
            image,
            exif,
            metadata,
            ..
        } = load_image_within_memory(image_path)?;
        let orientation = exif.orientation;
        let range = crate::compat::load_optical_depth(map_path)?.into_oriented(orientation);
        let (image_name, depth_name) = (image_path.display(), map_path.display());
        if (image.width(), image.height()) != (range.width(), range.height()) {
            return Err(Error::size_mismatch(
                image_name,
                (image.width(), image.height()),
                depth_name,
                (range.width(), range.height()),
            ));
        }
        Ok(Photo {
            image,
            depth: LoadedDepth {
                range,
                format: DepthFormat::Float,
                kind: DepthKind::Range,
                units: "optical depth".into(),
                metric: true,
                intrinsics: None,
                notes: vec!["transmittance map: its optical depth −ln τ, fogged at β = 1".into()],
                unknown_pixels: 0,
                turned: orientation,
                stereo_focal_baseline: None,
                stereo_view: StereoView::Left,
                mount: None,
            },
            image_name: image_name.to_string(),
            depth_name: depth_name.to_string(),
            exif,
            metadata,
        })
    }

    /// The built-in demo: Middlebury's Aloe at half size, its disparity read with offset 0
    /// (normalised range, not metres).
    pub fn demo() -> Result<Photo> {
        Ok(Photo {
            image: demo::demo_image()?,
            depth: demo::demo_range()?,
            image_name: "built-in demo image".into(),
            depth_name: "built-in demo disparity".into(),
            exif: PhotoExif::default(),
            metadata: PhotoMetadata::default(),
        })
    }

    /// Refuses fog in physical units (the option `name` = `value`) on a range not known
    /// to be in metres ([`LoadedDepth::metric`]), saying how it was read and what would do,
    /// normalised range (`ka`/`ks`) among it.
    pub fn require_metres(&self, name: &str, value: impl std::fmt::Display) -> Result<()> {
        self.refuse_unless_metric(name, value, "; or use `ka`/`ks` (normalised range)")
    }

    /// [`Photo::require_metres`] for a caller that has no normalised range to offer
    /// (a dataset's frames, whose fog is always in metres).
    pub(crate) fn require_metric_depth(
        &self,
        name: &str,
        value: impl std::fmt::Display,
    ) -> Result<()> {
        self.refuse_unless_metric(name, value, "")
    }

    fn refuse_unless_metric(
        &self,
        name: &str,
        value: impl std::fmt::Display,
        alternative: &str,
    ) -> Result<()> {
        if self.depth.metric {
            return Ok(());
        }
        let depth = &self.depth;
        let why = if depth.units != "m" {
            format!("in {}", depth.units)
        } else {
            "with approximate default geometry (give `focal`, `baseline` and \
             `disparity_offset`)"
                .to_string()
        };
        Err(Error::invalid(
            name,
            value,
            format!(
                "range in metres, but {} was read as {} {} {why}: give its calibration \
                 (`calib` calib.txt, `camera` NAME_camera.json), a metric `depth_format` \
                 (cityscapes, kitti, nyu, tum, android-depth16, arcore) or `depth_scale` in \
                 metres per unit{alternative}",
                self.depth_name, depth.format, depth.kind
            ),
        ))
    }

    /// Takes the disparities that fail the left-right photoconsistency check against
    /// `right`, the stereo pair's other image ([`crate::prep::stereo`]): the right one for a
    /// left view's disparity, the left one for a right view's
    /// ([`LoadedDepth::stereo_view`], checked mirrored), as unknown, for pre-processing to
    /// fill from reliable neighbours; the depth's notes say how many. `disparity` is the
    /// depth's disparity in pixels as [`Photo::load_stereo`] returned it with this photo
    /// (any stereo disparity, of the image's size; `None` for a depth that holds none).
    /// Returns how many pixels failed. Errors name `right`: a depth that holds no stereo
    /// disparity ([`LoadedDepth::not_a_stereo_disparity`]), a disparity or a right image
    /// of another size than the image. Only when asked for: on brume's scene and on
    /// Middlebury's Aloe pair, matched by StereoSGBM, it flagged correct pixels too and made
    /// τ worse (README, "Real depth").
    pub fn drop_left_right_mismatches(
        &mut self,
        disparity: Option<&ScalarMap>,
        right: &Path,
    ) -> Result<LeftRightCheck> {
        let not_a_disparity = |why: String| {
            Error::invalid(
                "right",
                right.display(),
                format!(
                    "a stereo pair's disparity as the depth with it ({}: {why})",
                    self.depth_name
                ),
            )
        };
        if let Some(why) = self.depth.not_a_stereo_disparity() {
            return Err(not_a_disparity(why));
        }
        let disparity = disparity.ok_or_else(|| {
            not_a_disparity("its disparity in pixels was not given with it".into())
        })?;
        let (w, h) = (self.image.width(), self.image.height());
        if (disparity.width(), disparity.height()) != (w, h) {
            return Err(Error::invalid(
                "right",
                right.display(),
                format!(
                    "a disparity of the image's size, {w}x{h}, as the depth with it ({} is \
                     {}x{})",
                    self.depth_name,
                    disparity.width(),
                    disparity.height()
                ),
            ));
        }
        let right_image = image::load_linear_rgb(right)?;
        let bad = crate::prep::stereo::mismatches_of_view(
            &self.image,
            &right_image,
            disparity,
            self.depth.stereo_view,
            crate::prep::stereo::DEFAULT_THRESHOLD,
        )
        .map_err(|e| match e {
            Error::SizeMismatch { .. } => Error::invalid(
                "right",
                right.display(),
                format!("a right image of the left image's size, {w}x{h}"),
            ),
            e => e,
        })?;
        let view = self.depth.stereo_view;
        let checked = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                self.depth.range.get(x, y).is_finite()
                    && crate::prep::stereo::has_match_inside(x, *disparity.get(x, y), w, view)
            })
            .count();
        let mut dropped = 0;
        let range = self.depth.range.as_mut_slice().iter_mut();
        for (v, _) in range
            .zip(bad.as_slice())
            .filter(|(v, &b)| b && v.is_finite())
        {
            *v = f32::NAN;
            dropped += 1;
        }
        self.depth.unknown_pixels += dropped;
        self.depth.notes.push(format!(
            "{dropped} px failed the left-right check against {} (> 12/255) and are unknown: \
             {:.1} % of the {checked} px checked (of known range, their match inside it)",
            right.display(),
            100.0 * dropped as f64 / checked.max(1) as f64
        ));
        Ok(LeftRightCheck {
            failed: dropped,
            checked,
        })
    }

    /// The photo's pinhole intrinsics at the image's size: those its depth was read with
    /// (scaled from the depth map's grid), else square pixels of `focal_px`, or of the
    /// vertical field of view `fov_y_deg`, or of its EXIF 35 mm equivalent focal length,
    /// with the principal point at the centre; `None` with none of them. What a virtual
    /// object's depth is stretched to range by ([`VirtualObject::load`]), and the aerial
    /// perspective's camera.
    pub fn image_intrinsics(
        &self,
        focal_px: Option<f64>,
        fov_y_deg: Option<f64>,
    ) -> Option<depth::Intrinsics> {
        let (w, h) = (self.image.width(), self.image.height());
        if let Some(k) = self.depth.intrinsics {
            return Some(k.scaled(w as f64 / self.depth.range.width() as f64));
        }
        let from_fov = |fov: f64| h as f64 / 2.0 / (fov.to_radians() / 2.0).tan();
        match focal_px.or_else(|| fov_y_deg.map(from_fov)) {
            Some(focal) => Some(depth::Intrinsics::centred(focal, w, h)),
            None => (self.exif.focal_35mm).map(|f| depth::Intrinsics::of_35mm_equivalent(f, w, h)),
        }
    }

    /// The depth map has the image's size, or is smaller by one factor on both sides (it
    /// is then upsampled, guided by the image); the error names both.
    pub fn check_depth_fits(&self) -> Result<()> {
        let (image, range) = (&self.image, &self.depth.range);
        let sizes = (
            (image.width(), image.height()),
            (range.width(), range.height()),
        );
        crate::refine::check_depth_size(sizes.0, sizes.1).map_err(|e| match e {
            Error::InvalidParameter { expected, .. } => Error::invalid(
                "depth",
                format!("{} ({}x{})", self.depth_name, sizes.1 .0, sizes.1 .1),
                format!(
                    "a depth map for {} ({}x{}): {expected}",
                    self.image_name, sizes.0 .0, sizes.0 .1
                ),
            ),
            e => e,
        })
    }
}

/// Reads the image file `image_path` once, refuses it from its header if a render of it
/// cannot fit in the memory left ([`check_memory_before_decoding`]), and decodes it
/// upright.
fn load_image_within_memory(image_path: &Path) -> Result<image::UprightPhoto> {
    load_checked(image_path, reserve_before_decoding)
}

/// Reads the image file at `path` once, runs `check` on its bytes and name (a check of
/// the memory its work needs, from its header, reserved while it is decoded), and decodes
/// it upright.
pub(crate) fn load_checked(
    path: &Path,
    check: impl FnOnce(&[u8], &str) -> Result<Reservation>,
) -> Result<image::UprightPhoto> {
    let bytes = crate::io::limits::read_file(path)?;
    let name = path.display().to_string();
    let _reserved = check(&bytes, &name)?;
    image::decode_upright_rgb(&bytes, &name)
}

/// Refuses, from the header of the image file `name` (its `bytes`) alone, an image whose
/// pre-processing and render cannot fit in the memory left, before decoding it (a header
/// that cannot be read is left to the decoder to report).
pub fn check_memory_before_decoding(bytes: &[u8], name: &str) -> Result<()> {
    reserve_before_decoding(bytes, name).map(drop)
}

/// [`check_memory_before_decoding`], the memory reserved until the reservation is dropped.
fn reserve_before_decoding(bytes: &[u8], name: &str) -> Result<Reservation> {
    check_decoding_fits(
        &[(bytes, name)],
        "loading the photo",
        CPU_BYTES_PER_PIXEL,
        "a photo holds about {} bytes per pixel in memory while it is pre-processed and \
         rendered (textures aside): use a smaller image",
    )
}

/// [`check_memory_before_decoding`] for the work `doing` ("loading the photo") on the
/// image `files` (each its bytes and name), of `per_pixel` bytes per pixel of each (the
/// files' bytes aside, which are in memory already); `hint` says what holds them and what
/// to do, with `{}` for the number.
pub(crate) fn check_decoding_fits(
    files: &[(&[u8], &str)],
    doing: &str,
    per_pixel: u64,
    hint: &str,
) -> Result<Reservation> {
    let mut pixels = 0;
    let named: Vec<String> = files
        .iter()
        // Through brume's reader, whose checks run before the decoder allocates anything
        // (a PNG's ICC profile that inflates to hundreds of megabytes).
        .map(
            |&(bytes, name)| match image::image_dimensions(bytes, name) {
                Ok((w, h)) => {
                    pixels += u64::from(w) * u64::from(h);
                    format!("{name} ({w}x{h})")
                }
                // Left to the decoder to report.
                Err(_) => name.to_string(),
            },
        )
        .collect();
    crate::memory::reserve(
        &format!("{doing} {}", named.join(" with ")),
        per_pixel * pixels,
        &hint.replace("{}", &per_pixel.to_string()),
    )
}
