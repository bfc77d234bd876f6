//! Depth, range and disparity maps in the formats users bring, turned into one thing: a
//! range map (distance from the camera centre to the surface seen at each pixel) with NaN
//! where the distance is unknown.
//!
//! Units: every conversion that knows the physical scale returns metres. Baselines are
//! taken in millimetres everywhere (the Middlebury convention), so disparity-based ranges
//! are computed in millimetres and divided by 1000. Float depth or range maps keep the
//! units of the file. For haze only relative range matters, so a wrong absolute scale
//! changes the look only through the haze density the user picks.
//!
//! The front end is here: the options, the result, and loading a file. Each file format
//! is decoded by its codec in `io::codec` (`raw` dispatches by extension), each dataset's
//! convention is in a module of its own (`middlebury`, `png16`, `android`), the geometry
//! is in `io::camera`, and `interpret` settles which convention a file follows. Two
//! formats come with a side file giving the camera: Middlebury 2014's `calib.txt` and
//! Cityscapes' `{name}_camera.json` (`cityscapes`). Every fact
//! that depends on the format (name, file layout, kinds, a fixed scale) is one row of the
//! table in `format.rs`: a new dataset format adds its [`DepthFormat`] variant and its row
//! (ARCore is only a row), and only a conversion no row can describe also adds a module
//! and its arm in `interpret` (Android DEPTH16's confidence bits).

use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use crate::io::camera::Mount;
use crate::raster::{Orientation, ScalarMap};
use crate::{Error, Result};

mod android;
mod apple;
mod cityscapes;
mod disparity;
mod format;
mod gdepth;
mod interpret;
mod middlebury;
mod orient;
mod png16;
mod raw;
mod stop;
mod xmp;

pub use disparity::{known_disparities, load_disparity_px, load_range_and_disparity};
use interpret::{interpret, SideFiles};
use raw::{decode_raw, Raw};

// The file readers live with their writers in `io::codec`; they stay reachable here, where
// callers loading depth have always found them.
pub use crate::io::codec::exr::read_exr_scalar;
pub use crate::io::codec::npy::read_npy_scalar;
pub use crate::io::codec::pfm::{parse_pfm, read_pfm, Pfm};
pub use crate::io::codec::tiff::read_tiff_scalar;

pub use crate::io::camera::Intrinsics;

pub use android::DEPTH16_DEFAULT_MIN_CONFIDENCE;
pub use cityscapes::{
    camera_candidates, disparity_px as cityscapes_disparity_px, parse_camera, parse_camera_str,
    CityscapesCamera, BASELINE_RANGE_M as CITYSCAPES_BASELINE_RANGE_M,
    FOCAL_RANGE_PX as CITYSCAPES_FOCAL_RANGE_PX, HEIGHT_RANGE_M as CITYSCAPES_HEIGHT_RANGE_M,
    PRINCIPAL_POINT_RANGE_PX as CITYSCAPES_PRINCIPAL_POINT_RANGE_PX,
    TILT_RANGE_RAD as CITYSCAPES_TILT_RANGE_RAD,
};
pub use gdepth::has_embedded_depth;
pub use middlebury::{
    parse_calib, parse_calib_str, Calib, MIDDLEBURY2006_BASELINE_MM,
    MIDDLEBURY2006_DISPARITY_OFFSET_PX, MIDDLEBURY2006_FOCAL_PX,
};
pub use orient::{DepthLayout, PhotoGeometry};

/// What the values of a map measure.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum DepthKind {
    /// Distance along the optical axis (the z coordinate in camera space).
    Depth,
    /// Distance from the camera centre to the surface (what haze needs).
    Range,
    /// Stereo disparity in pixels; depth = focal * baseline / (disparity + offset).
    Disparity,
    /// A rendered frame's depth buffer: OpenGL window depth d ∈ [0, 1] of a perspective
    /// projection (a 16-bit PNG holds d·65535), turned into eye depth by the near and far
    /// planes and into range by the vertical field of view ([`crate::camera`]). d = 1
    /// (the far plane: nothing drawn, sky) is unknown.
    ZBuffer,
    /// A monocular depth estimator's relative inverse depth (MiDaS, DPT, Depth Anything's
    /// relative models): larger is nearer, known up to scale and shift, so depth ∝
    /// 1/(d + `disparity_offset`); 0 and below (the sky) is unknown. Not metric, unless
    /// `scale` gives the metres of 1/(d + offset).
    Inverse,
    /// A monocular depth estimator's affine-invariant depth (Marigold): d ∈ [0, 1], 0 at
    /// the nearest depth in the scene and 1 at the farthest, both chosen by the model for
    /// each image and not known to it, so the caller gives them: depth = `near` +
    /// d·(`far` − `near`) (a 16-bit PNG holds d·65535). In their units; metric with
    /// `scale`.
    Affine,
}

impl DepthKind {
    const NAMES: &'static str = "depth, range, disparity, zbuffer, inverse or affine";
}

impl FromStr for DepthKind {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "depth" => Ok(DepthKind::Depth),
            "range" => Ok(DepthKind::Range),
            "disparity" => Ok(DepthKind::Disparity),
            "zbuffer" => Ok(DepthKind::ZBuffer),
            "inverse" | "inverse-depth" | "inverse_depth" => Ok(DepthKind::Inverse),
            "affine" | "affine-invariant" | "affine_invariant" => Ok(DepthKind::Affine),
            _ => Err(Error::invalid("depth_kind", s, DepthKind::NAMES)),
        }
    }
}

impl fmt::Display for DepthKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            DepthKind::Depth => "depth",
            DepthKind::Range => "range",
            DepthKind::Disparity => "disparity",
            DepthKind::ZBuffer => "zbuffer",
            DepthKind::Inverse => "inverse",
            DepthKind::Affine => "affine",
        })
    }
}

/// Which camera of a rectified stereo pair a disparity map is aligned with. The
/// background next to a nearer surface that the other camera cannot see, which a matcher
/// leaves unknown, lies left of that surface in a left view's map and right of it in a
/// right view's ([`crate::prep::PrepOptions::stereo_view`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum StereoView {
    /// The left camera's: Cityscapes', Middlebury 2014's `disp0.pfm` and 2006's
    /// `disp1.png`, OpenCV's matchers'.
    #[default]
    Left,
    /// The right camera's: Middlebury 2014's `disp1.pfm` and 2006's `disp5.png`.
    Right,
}

impl FromStr for StereoView {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "left" => Ok(StereoView::Left),
            "right" => Ok(StereoView::Right),
            _ => Err(Error::invalid("stereo_view", s, "left or right")),
        }
    }
}

impl fmt::Display for StereoView {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            StereoView::Left => "left",
            StereoView::Right => "right",
        })
    }
}

/// How a depth file is laid out and scaled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum DepthFormat {
    /// Guess from the extension, bit depth and the presence of a calibration file.
    Auto,
    /// Middlebury 2014: `disp0.pfm` disparity (or the right view's `disp1.pfm`) plus
    /// `calib.txt`.
    Middlebury2014,
    /// Middlebury 2005/2006: 8-bit disparity PNG, `0` unknown, no calibration file.
    Middlebury2006,
    /// KITTI depth: 16-bit PNG, metres = value / 256, `0` unknown.
    Kitti,
    /// NYU Depth v2: 16-bit PNG in millimetres, `0` unknown.
    Nyu,
    /// TUM RGB-D: 16-bit PNG, metres = value / 5000, `0` unknown.
    Tum,
    /// Any 16-bit PNG, metres = value * `DepthOptions::scale`, `0` unknown.
    Png16,
    /// Float map (`.exr`, float `.tif`, `.npy`, `.pfm` without calibration); NaN, infinite
    /// or non-positive values are unknown.
    Float,
    /// Android Camera2 `ImageFormat.DEPTH16` saved as a 16-bit grey PNG: the low 13 bits
    /// are the range in millimetres, the high 3 bits a confidence code; range `0` and
    /// samples below [`DepthOptions::min_confidence`] are unknown. Read as range (see
    /// the `android` module for what the documentation says and does not say).
    AndroidDepth16,
    /// ARCore Depth API (`acquireDepthImage16Bits`) saved as a 16-bit grey PNG: all 16
    /// bits are millimetres along the camera's principal axis (z-depth), `0` unknown.
    Arcore,
    /// Cityscapes `{name}_disparity.png`: 16-bit grey, p > 0 is the disparity
    /// (p − 1)/256 px, `0` invalid, with the baseline and intrinsics of its
    /// `{name}_camera.json` ([`DepthOptions::camera`], or found beside the file or in the
    /// dataset's `camera/` folder): Z = baseline·fx/d metres, then range.
    Cityscapes,
    /// Google's depth map metadata (GDepth) in a JPEG's XMP, as a phone's portrait or
    /// lens-blur photo carries it: an 8- or 16-bit image scaled by its `Near`, `Far`,
    /// `Format` (RangeInverse or RangeLinear) and `Units`, depth or range as its
    /// `MeasureType` says (see the `gdepth` module). `auto` picks it for a `.jpg`.
    Gdepth,
    /// Android's Dynamic Depth (Android 10 on) in a JPEG: the depth image appended after
    /// the primary image as an item of its `Container:Directory`, described by a camera's
    /// `DepthMap` as GDepth describes its own (`Format`, `Near`, `Far`, `Units`,
    /// `MeasureType`). `auto` picks it for a `.jpg` that carries it.
    DynamicDepth,
    /// An iPhone's portrait photo saved as JPEG: its disparity (or depth) is an auxiliary
    /// JPEG after the photo, listed by the photo's Multi-Picture Format index and described
    /// by Apple's pixel data info XMP (`NativeFormat`, codes `IntMinValue`..`IntMaxValue`
    /// over `FloatMinValue`..`FloatMaxValue`, in 1/m or m), its camera's `IntrinsicMatrix`
    /// beside it (see the `apple` module). `auto` picks it for a `.jpg` that carries it.
    AppleDepth,
}

impl FromStr for DepthFormat {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        let wanted = s.trim().to_ascii_lowercase();
        DepthFormat::ALL
            .into_iter()
            .find(|f| f.rule().name == wanted)
            .ok_or_else(|| Error::invalid("depth_format", s, DepthFormat::names()))
    }
}

impl fmt::Display for DepthFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.rule().name)
    }
}

/// How to read a depth file. `Default` guesses everything.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct DepthOptions {
    /// Layout and scale of the file; `Auto` guesses.
    pub format: DepthFormat,
    /// What the values measure; `None` takes the format's usual kind.
    pub kind: Option<DepthKind>,
    /// Middlebury 2014 `calib.txt`; `None` looks for `calib.txt` next to a `.pfm`.
    pub calib: Option<PathBuf>,
    /// Cityscapes `{name}_camera.json`; `None` looks for it beside a `*_disparity.png` and
    /// in the dataset's layout (see [`camera_candidates`]).
    pub camera: Option<PathBuf>,
    /// Multiplier from raw 16-bit PNG values to metres (or to pixels of disparity); for
    /// a float map, metres per unit; for a z-buffer, metres per unit of `near` and `far`
    /// (1 when they are in metres); for relative inverse depth, the metres of
    /// 1/(d + offset); for affine-invariant depth, metres per unit of `near` and `far`;
    /// for a phone's portrait JPEG, a factor on the metres it holds (an iPhone's relative
    /// map rescaled to a distance known in the scene). Given for a float map, a z-buffer,
    /// inverse or affine-invariant depth or a portrait JPEG, it makes the range metric
    /// ([`LoadedDepth::metric`]).
    pub scale: Option<f64>,
    /// Focal length in pixels.
    pub focal: Option<f64>,
    /// Stereo baseline in millimetres.
    pub baseline: Option<f64>,
    /// Added to disparity before dividing (Middlebury `doffs`/`dmin`), in pixels.
    pub disparity_offset: Option<f64>,
    /// Near clipping plane of a z-buffer's projection, or the nearest depth in the scene of
    /// an affine-invariant map (its 0), in the range's units (metres with `scale` 1).
    pub near: Option<f64>,
    /// Far clipping plane of a z-buffer's projection, `f64::INFINITY` for an infinite
    /// far plane (engines' reversed-Z projections have one); or the farthest depth in the
    /// scene of an affine-invariant map (its 1).
    pub far: Option<f64>,
    /// Whether a z-buffer is reversed-Z: window depth 1 at the near plane and 0 at the far
    /// one (Unreal, Bevy, Godot 4), nothing drawn at 0. False: OpenGL's standard, 0 at
    /// near, nothing drawn at 1.
    pub reversed_z: bool,
    /// Vertical field of view in degrees: the focal length of a z-buffer, or of a depth
    /// map when `focal` is not given; the upright photo's when `photo` is given.
    pub fov: Option<f64>,
    /// Lowest confidence, in [0, 1], of an `android-depth16` sample that is kept; less
    /// confident samples are unknown. `None` takes
    /// [`DEPTH16_DEFAULT_MIN_CONFIDENCE`]. For `gdepth` and `dynamic-depth`, the lowest
    /// value of the file's confidence map kept; `None` keeps every sample.
    pub min_confidence: Option<f64>,
    /// Range at or beyond which a value is unknown, the sky, in the range's units (metres
    /// when metric): for a model that gives the sky a depth of its own, near its largest
    /// (Depth Anything's metric models saturate toward 20 or 80 m), so that pre-processing
    /// finds the sky there with the image (inverse and affine maps' far tail is looked at
    /// for sky without it: [`crate::prep::PrepOptions::sky_in_far_tail`]).
    /// `None`: a float depth or range map's largest value is unknown when at least 1 % of
    /// its samples hold it exactly, 10 times beyond the mean of the others or more (Depth
    /// Pro's sky, clamped at 10 km; Blender's background, 1e10); `f64::INFINITY` keeps
    /// every value.
    pub sky_beyond: Option<f64>,
    /// The photo the map goes with, as stored, and what its EXIF says: the map is turned
    /// upright with it as `layout` says, `fov` is the upright photo's vertical field of
    /// view, and without `focal` or `fov` its 35 mm equivalent focal length turns depth
    /// into range. `None` (a map read on its own): the map as stored. Not serialised: it
    /// is the photo's, not a setting.
    #[serde(skip)]
    pub photo: Option<PhotoGeometry>,
    /// How the map lies against `photo`'s orientation.
    pub layout: DepthLayout,
    /// How the camera is mounted over a level road (a car's camera), for a map whose file
    /// gives no mount or the wrong one: replaces a Cityscapes camera file's, and becomes
    /// [`LoadedDepth::mount`] when the map has intrinsics and metres (else a note says it
    /// is ignored). Its pitch and roll are the upright photo's.
    pub camera_mount: Option<Mount>,
    /// Which view a disparity is of; `None`: the right one for a Middlebury 2014 map named
    /// `disp1.pfm` (its range then takes `cam1`'s intrinsics) or a 2005/2006 one named
    /// `disp5.png`, as the datasets name them, else the left one. Ignored, with a note, for
    /// any other kind of map.
    pub stereo_view: Option<StereoView>,
}

impl Default for DepthOptions {
    fn default() -> Self {
        DepthOptions {
            format: DepthFormat::Auto,
            kind: None,
            calib: None,
            camera: None,
            scale: None,
            focal: None,
            baseline: None,
            disparity_offset: None,
            near: None,
            far: None,
            reversed_z: false,
            fov: None,
            min_confidence: None,
            sky_beyond: None,
            photo: None,
            layout: DepthLayout::Auto,
            camera_mount: None,
            stereo_view: None,
        }
    }
}

/// A range map and how it was obtained.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedDepth {
    /// Range per pixel, row 0 at the top; NaN where unknown.
    pub range: ScalarMap,
    /// The format actually used (never `Auto`).
    pub format: DepthFormat,
    /// What the file's values measured.
    pub kind: DepthKind,
    /// Units of `range`: `m`, or `file units` for float maps of depth or range and
    /// z-buffers read without `scale`.
    pub units: String,
    /// Whether `range` is in metres that can be trusted: the scale comes from a
    /// calibration (Middlebury 2014 `calib.txt`, a Cityscapes camera file), from a
    /// dataset's fixed scale (KITTI, NYU, TUM, Android DEPTH16, ARCore), or from geometry
    /// the caller gave in full (`scale` for a 16-bit PNG, a float map or a z-buffer's
    /// planes; `focal` and `baseline` for a disparity). False for maps in file units
    /// (float maps and z-buffers without `scale`) and for Middlebury 2006 read with any
    /// of its approximate default focal, baseline or offset (the built-in demo among
    /// them). Physical fog (β in m⁻¹) needs it.
    pub metric: bool,
    /// Intrinsics used to turn depth into range, if any.
    pub intrinsics: Option<Intrinsics>,
    /// Remarks for the user: assumptions made, options ignored.
    pub notes: Vec<String>,
    /// Number of NaN pixels in `range`.
    pub unknown_pixels: usize,
    /// How `range` was turned from the file's layout to lie on its upright photo
    /// ([`DepthOptions::photo`]); [`Orientation::Upright`] when it was not.
    pub turned: Orientation,
    /// f·B (px·m) of a stereo pair's disparity (Cityscapes, Middlebury, or any disparity
    /// read with `focal` and `baseline`; a left or a right view's), whose holes beside a
    /// nearer surface are occlusions of the background
    /// ([`crate::prep::PrepOptions::stereo_focal_baseline`]): `range`'s grid's disparity
    /// steps are f·B·(1/Z₁ − 1/Z₂) px. `None` for other maps.
    pub stereo_focal_baseline: Option<f64>,
    /// Which view of its stereo pair a disparity is of ([`DepthOptions::stereo_view`]):
    /// where its occlusions lie. [`StereoView::Left`] for other maps.
    pub stereo_view: StereoView,
    /// How the camera is mounted over the road ([`DepthOptions::camera_mount`], or a
    /// Cityscapes camera file's height, pitch and roll), with [`Self::intrinsics`] the
    /// level ground's range along each ray ([`crate::prep::PrepOptions::ground`]); `None`
    /// for other maps, and for a turned map without `camera_mount`.
    pub mount: Option<Mount>,
}

impl LoadedDepth {
    /// Replaces the range by the same view at another size (a refinement's upsampling to
    /// the image's), its intrinsics scaled to the new grid with it.
    pub fn replace_range(&mut self, range: ScalarMap) {
        let scale = range.width() as f64 / self.range.width() as f64;
        self.intrinsics = self.intrinsics.map(|k| k.scaled(scale));
        self.stereo_focal_baseline = self.stereo_focal_baseline.map(|fb| fb * scale);
        self.range = range;
    }

    /// A warning when depth along the optical axis (given, or from a z-buffer or a
    /// monocular model's inverse or affine-invariant depth) was used as range for want of
    /// `focal` or `fov`: range exceeds depth by 1/cos of the angle off the axis, so the fog
    /// is too thin away from the centre. It says by how much in this frame's corners at a
    /// 45° vertical field of view. `None` for range, or depth turned into range.
    pub fn depth_as_range_warning(&self) -> Option<String> {
        if self.kind == DepthKind::Range || self.intrinsics.is_some() {
            return None;
        }
        let (w, h) = (self.range.width(), self.range.height());
        let corner_tan = (w as f64 / h as f64).hypot(1.0) * 22.5f64.to_radians().tan();
        let short = 1.0 - 1.0 / corner_tan.hypot(1.0);
        Some(format!(
            "depth along the optical axis used as range for want of `focal` or `fov`: {:.0} % \
             short in this {w}x{h} frame's corners at a 45° vertical field of view (less fog \
             there than there should be); give `focal` or `fov` (or a photo whose EXIF has its \
             35 mm equivalent focal length)",
            short * 100.0
        ))
    }

    /// A warning when a depth or range map looks like a disparity or a monocular model's
    /// inverse depth read as depth (the fog would then be thickest on what is nearest):
    /// the median known value of the frame's bottom tenth of rows, where a photo's
    /// nearest ground or table is, is over [`INVERTED_RATIO`] times that of the rows
    /// from 30 to 50 % of its height, where its farthest surfaces and horizon are.
    /// `None` for other kinds, which say what they are, and where either band has fewer
    /// than [`INVERTED_MIN_SAMPLES`] known values.
    pub fn inverted_warning(&self) -> Option<String> {
        if !matches!(self.kind, DepthKind::Depth | DepthKind::Range) {
            return None;
        }
        let h = self.range.height();
        let bottom = median_known_in_rows(&self.range, h - h / 10..h)?;
        let middle = median_known_in_rows(&self.range, h * 3 / 10..h / 2)?;
        (f64::from(bottom) > INVERTED_RATIO * f64::from(middle)).then(|| {
            format!(
                "its values grow toward the bottom of the frame (median {bottom:.4} in the \
                 bottom tenth of rows, {:.1} times the {middle:.4} at mid-height), as a \
                 disparity's or an inverse depth's do, where depth and range shrink toward \
                 the ground: read as {}, the fog is thickest on what is nearest. A disparity \
                 needs `depth_kind` disparity with `focal` and `baseline`; a monocular \
                 model's relative inverse depth (MiDaS, Depth Anything) `depth_kind` inverse",
                bottom / middle,
                self.kind
            )
        })
    }

    /// What a host should show even to a user who reads no notes: the
    /// [`depth_as_range_warning`](Self::depth_as_range_warning), the
    /// [`inverted_warning`](Self::inverted_warning), and the notes of options given but
    /// ignored (an option the user set to no effect is most often a mistake). The other
    /// notes (assumptions such as a default principal point) stay in `notes`.
    pub fn warnings(&self) -> Vec<String> {
        let ignored = self.notes.iter().filter(|n| is_ignored_option_note(n));
        self.inverted_warning()
            .into_iter()
            .chain(self.depth_as_range_warning())
            .chain(ignored.cloned())
            .collect()
    }
}

/// The view of a disparity read as `format` from `path` ([`DepthOptions::stereo_view`]):
/// as given, else the right one for a Middlebury 2014 `disp1.pfm` or 2006 `disp5.png`,
/// else the left one.
fn stereo_view_for(format: DepthFormat, path: &Path, opts: &DepthOptions) -> StereoView {
    opts.stereo_view
        .unwrap_or(if middlebury::names_right_view(format, path) {
            StereoView::Right
        } else {
            StereoView::Left
        })
}

/// The view a loaded map keeps: `view` for a disparity whose occlusions pre-processing
/// looks for (`stereo`), noted when it is the right one; else the left one, noting a
/// `stereo_view` given to no effect.
fn kept_stereo_view(
    view: StereoView,
    stereo: bool,
    opts: &DepthOptions,
    notes: &mut Vec<String>,
) -> StereoView {
    if !stereo {
        if let Some(given) = opts.stereo_view {
            notes.push(format!(
                "`stereo_view` {given} ignored: only an upright stereo disparity has its \
                 occlusions looked for"
            ));
        }
        return StereoView::Left;
    }
    if view == StereoView::Right {
        notes.push(
            "read as the right view's disparity: its occlusions are looked for right of \
             nearer surfaces"
                .to_string(),
        );
    }
    view
}

/// How many times the bottom rows' median value must exceed the middle rows' for
/// [`LoadedDepth::inverted_warning`]: a street's disparity or inverse depth is 10 to 20
/// times larger on the road before the camera than at the horizon, its depth as many times
/// smaller; a portrait's or a wall's are about even either way.
pub const INVERTED_RATIO: f64 = 2.0;

/// The fewest known values a band of rows must have for [`LoadedDepth::inverted_warning`]
/// to judge it.
pub const INVERTED_MIN_SAMPLES: usize = 64;

/// The median of the known (finite, > 0) values of `map`'s `rows`; `None` below
/// [`INVERTED_MIN_SAMPLES`] of them.
fn median_known_in_rows(map: &ScalarMap, rows: std::ops::Range<usize>) -> Option<f32> {
    let w = map.width();
    let slice = &map.as_slice()[rows.start * w..rows.end * w];
    let mut known: Vec<f32> = (slice.iter().copied())
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    if known.len() < INVERTED_MIN_SAMPLES {
        return None;
    }
    let mid = known.len() / 2;
    Some(*known.select_nth_unstable_by(mid, f32::total_cmp).1)
}

/// Whether a loader's note tells of an option (or a file) given and not used: they all
/// say "ignored", and no other note does.
pub fn is_ignored_option_note(note: &str) -> bool {
    note.contains("ignored")
}

// Checks of option values, shared by the dataset modules so that a bad value reads the
// same whichever format it came with.
fn positive_option(value: f64, name: &str, what: &str) -> Result<f64> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(Error::invalid(name, value, what))
    }
}

fn finite_option(value: f64, name: &str) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::invalid(name, value, "a finite number of pixels"))
    }
}

/// Loads a depth, range or disparity file and returns a range map with NaN for unknown
/// pixels. See [`DepthFormat`] for the layouts and [`DepthOptions`] for the knobs.
pub fn load_range(path: &Path, opts: &DepthOptions) -> Result<LoadedDepth> {
    load_file(path, opts, Keep::RangeOnly).map(|(loaded, _)| loaded)
}

/// What [`load_file`] keeps of the decoded samples besides the range.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Keep {
    RangeOnly,
    /// A copy of the samples as the file stores them (a stereo disparity's pixels).
    Samples,
}

/// [`load_range`], and with [`Keep::Samples`] the decoded samples before they were
/// interpreted (`None` for a phone's embedded map, which is never a stereo disparity).
fn load_file(path: &Path, opts: &DepthOptions, keep: Keep) -> Result<(LoadedDepth, Option<Raw>)> {
    let bytes = crate::io::limits::read_file(path)?;
    let ext = extension_of(path);
    let calib = read_side_file(middlebury::calib_file(path, &ext, opts))?;
    let camera = read_side_file(cityscapes::camera_file(path, &ext, opts)?)?;
    load_with_side_files(&bytes, path, opts, side(&calib), side(&camera), keep)
}

/// A side file read by [`read_side_file`], borrowed as the loaders take it.
fn side(file: &Option<(PathBuf, String)>) -> Option<(&Path, &str)> {
    file.as_ref().map(|(p, t)| (p.as_path(), t.as_str()))
}

/// The path and text of a side file (a calib.txt, a camera file) when there is one.
fn read_side_file(path: Option<PathBuf>) -> Result<Option<(PathBuf, String)>> {
    match path {
        Some(p) => {
            let text = crate::io::limits::read_text(&p)?;
            Ok(Some((p, text)))
        }
        None => Ok(None),
    }
}

/// [`load_range`] on bytes already in memory, which `load_range` itself calls once it has
/// read the files. `name` stands for the file: its extension picks the codec and errors
/// name it. Nothing is read from disk: a Middlebury 2014 `calib.txt` is passed as `calib`
/// (its path, for messages, and its text), where `load_range` would have found it through
/// [`DepthOptions::calib`] or beside the file. (A Cityscapes disparity's camera file goes
/// to [`load_cityscapes_from_bytes`].)
pub fn load_range_from_bytes(
    bytes: &[u8],
    name: &Path,
    opts: &DepthOptions,
    calib: Option<(&Path, &str)>,
) -> Result<LoadedDepth> {
    load_with_side_files(bytes, name, opts, calib, None, Keep::RangeOnly).map(|(loaded, _)| loaded)
}

/// A depth, range, disparity, inverse or affine-invariant depth or z-buffer map already in
/// memory (a depth camera's frame, a monocular model's output, an engine's depth buffer
/// read back), read as [`load_range`] reads a float file of it with `opts`: NaN or
/// infinite unknown, the kind, scale and geometry from `opts`. `opts.format` is `Auto` or
/// `Float` (other formats name a file layout); no side file is read, so `calib` and
/// `camera` are refused (give `focal` and `baseline`). `name` stands for the map in messages.
pub fn range_from_map(map: ScalarMap, name: &str, opts: &DepthOptions) -> Result<LoadedDepth> {
    let side_file = |option: &str, path: &Option<PathBuf>| match path {
        Some(p) => Err(Error::invalid(
            option,
            p.display(),
            "no side file for a map in memory: give its geometry (`focal`, `baseline`, \
             `disparity_offset`, `fov`)",
        )),
        None => Ok(()),
    };
    side_file("calib", &opts.calib)?;
    side_file("camera", &opts.camera)?;
    let raw = Raw::Float {
        map,
        from_pfm: false,
        focal_px: None,
    };
    let name = Path::new(name);
    interpret(raw, name, opts, SideFiles::default(), Vec::new(), 1.0)
}

/// Loads a Cityscapes `{name}_disparity.png` as range in metres ([`LoadedDepth::metric`]),
/// with its camera file: `camera`, or else the first of [`camera_candidates`] that exists
/// (an error names them all when none does).
pub fn load_cityscapes(disparity: &Path, camera: Option<&Path>) -> Result<LoadedDepth> {
    let opts = DepthOptions {
        format: DepthFormat::Cityscapes,
        camera: camera.map(Path::to_path_buf),
        ..DepthOptions::default()
    };
    load_range(disparity, &opts)
}

/// [`load_cityscapes`] on bytes already in memory: the disparity PNG's bytes (`name`
/// stands for the file in messages) and the camera file's path and text.
pub fn load_cityscapes_from_bytes(
    disparity: &[u8],
    name: &Path,
    camera: (&Path, &str),
) -> Result<LoadedDepth> {
    let opts = DepthOptions {
        format: DepthFormat::Cityscapes,
        camera: Some(camera.0.to_path_buf()),
        ..DepthOptions::default()
    };
    load_with_side_files(disparity, name, &opts, None, Some(camera), Keep::RangeOnly)
        .map(|(loaded, _)| loaded)
}

/// The loaders' common path: the side files are parsed if the format uses them (or noted
/// as ignored), then the file is decoded and interpreted.
fn load_with_side_files(
    bytes: &[u8],
    name: &Path,
    opts: &DepthOptions,
    calib: Option<(&Path, &str)>,
    camera: Option<(&Path, &str)>,
    keep: Keep,
) -> Result<(LoadedDepth, Option<Raw>)> {
    let mut notes = Vec::new();
    let ext = extension_of(name);
    let calib = middlebury::take_calib(&ext, opts, calib, &mut notes)?;
    let camera = cityscapes::take_camera(name, &ext, opts, camera, &mut notes)?;
    let raw = decode_raw(bytes, name, &ext, opts.format)?;
    let samples = match keep {
        Keep::Samples => raw.samples(),
        Keep::RangeOnly => None,
    };
    let loaded = interpret(raw, name, opts, SideFiles { calib, camera }, notes, 1.0)?;
    Ok((loaded, samples))
}

/// Decodes embedded depth bytes as if read from a file with extension `ext`. `pixel_scale`
/// is how many full-size pixels one pixel of this map spans: a Middlebury 2006 map
/// downsampled by 2 keeps full-size disparities but its pixels see twice the angle.
pub(crate) fn range_from_bytes(
    bytes: &[u8],
    name: &Path,
    ext: &str,
    opts: &DepthOptions,
    pixel_scale: f64,
) -> Result<LoadedDepth> {
    let raw = decode_raw(bytes, name, ext, opts.format)?;
    interpret(
        raw,
        name,
        opts,
        SideFiles::default(),
        Vec::new(),
        pixel_scale,
    )
}

fn extension_of(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}
