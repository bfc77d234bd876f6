//! The options of pre-processing, with their defaults and checks.

use super::ground::Ground;
use crate::io::depth::{DepthKind, LoadedDepth, StereoView};
use crate::{Error, Result};

/// Which components of unknown pixels are sky under the depth rules. A component is sky
/// when it passes every rule; of those, the `max_components` largest are kept. See the
/// module docs.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SkyRules {
    /// Minimum area, as a fraction of the image (default 0.01). Also the minimum area of
    /// each region the image-guided detector grows.
    pub min_area_fraction: f64,
    /// The component must have a pixel in the top row (default true).
    pub must_touch_top: bool,
    /// At most this many components are sky, the largest (default 4; 0 disables sky).
    pub max_components: usize,
    /// Minimum number of top-row pixels, as a fraction of the width (default 0.1).
    pub min_top_fraction: f64,
    /// Minimum area as a fraction of the component's bounding box (default 0.3).
    pub min_bbox_fill: f64,
    /// Reject components that reach the bottom row (default true).
    pub reject_bottom: bool,
}

impl Default for SkyRules {
    fn default() -> Self {
        SkyRules {
            min_area_fraction: 0.01,
            must_touch_top: true,
            max_components: 4,
            min_top_fraction: 0.1,
            min_bbox_fill: 0.3,
            reject_bottom: true,
        }
    }
}

/// Rules of the image-guided sky detector, used when [`super::prepare_guided`] is given the
/// colour image (see the module docs, step 2, for what each one does).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ImageSkyRules {
    /// Seeds are looked for in this top fraction of the rows (default 0.05; at least one
    /// row).
    pub seed_rows: f64,
    /// Largest texture of a sky pixel: the 3 x 3 mean of its largest relative colour step
    /// to a 4-neighbour (default 0.05; a smooth sky with 1 % sensor noise scores about
    /// 0.02, a textured facade, foliage or tarmac 0.1 and more).
    pub max_texture: f64,
    /// Largest relative colour step between two sky pixels grown one from the other
    /// (default 0.08).
    pub max_step: f64,
    /// The sky is at least this bright, relative to the median luminance of the pixels of
    /// confident range (the scene; the whole image without any). Default 1: a daylight sky
    /// is rarely darker than the typical surface under it.
    pub min_brightness: f64,
    /// Blue or grey: `B >= min_blue_ratio x max(R, G)` in linear light (default 0.7; a
    /// grey or blue sky is about 0.9 and more, foliage and brick well below 0.5).
    pub min_blue_ratio: f64,
    /// The growth jumps occluders up to this many pixels thick, counted with the pixels
    /// next to them that the texture test refuses (default 6: a 2-px wire).
    pub bridge_px: usize,
    /// Gaps in the sky up to this fraction of the image become sky even when dark
    /// (default 0.002: birds, lamp heads, signs on wires).
    pub max_gap_fraction: f64,
}

impl Default for ImageSkyRules {
    fn default() -> Self {
        ImageSkyRules {
            seed_rows: 0.05,
            max_texture: 0.05,
            max_step: 0.08,
            min_brightness: 1.0,
            min_blue_ratio: 0.7,
            bridge_px: 6,
            max_gap_fraction: 0.002,
        }
    }
}

/// Largest accepted [`PrepOptions::margin_px`].
const MAX_MARGIN_PX: f64 = 65535.0;
/// Largest accepted [`PrepOptions::sky_range_factor`]: beyond it the whole scene is
/// squeezed into normalised range below 1/1000, where no haze shows.
const MAX_SKY_RANGE_FACTOR: f64 = 1000.0;
/// Largest accepted [`ImageSkyRules::bridge_px`].
const MAX_BRIDGE_PX: usize = 64;
/// Smallest far patch that is kept, whatever [`PrepOptions::far_patch_fraction`] says.
pub(super) const MIN_FAR_PATCH: usize = 16;
/// Smallest span of a local-outlier patch, whatever [`PrepOptions::local_outlier_span`]
/// says.
pub(super) const MIN_LOCAL_SPAN: usize = 4;

/// Options of [`super::prepare`]. The defaults are those documented on each field.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PrepOptions {
    /// Sky detection rules on the range alone.
    pub sky: SkyRules,
    /// Sky detection rules on the colour image (when [`super::prepare_guided`] gets one).
    pub image_sky: ImageSkyRules,
    /// Width `µ` of the horizon margin in pixels, in [0, 65535] (default 8; 0: no margin).
    pub margin_px: f64,
    /// Jacobi sweeps in the margin; `None` (default) means `ceil(2 µ)`.
    pub jacobi_iterations: Option<usize>,
    /// `Smax = sky_range_factor x Rmax`; must be in (1, 1000] (default 1.5).
    pub sky_range_factor: f64,
    /// RANSAC trials per hole, each one constant and one plane candidate (default 32, >= 1).
    pub ransac_samples: usize,
    /// Seed of the RANSAC random streams (default 0).
    pub seed: u64,
    /// Look for sky at all (default true); when false, every unknown component is a hole
    /// (a sky mask given to [`super::prepare_guided`] is still used).
    pub detect_sky: bool,
    /// Known values above `far_outlier_factor x` the 99th percentile of the known values
    /// outside the sky are far outliers unless supported (see `far_patch_fraction`); they
    /// become unknown before `Rmax` is taken. Default 2; 0 turns the rule off; otherwise at
    /// least 1.
    pub far_outlier_factor: f64,
    /// A far value is supported when its 8-connected patch of values above the cut covers
    /// at least this fraction of the image (and at least 16 pixels); default 0.0005.
    pub far_patch_fraction: f64,
    /// Local outliers (step 3b): a known range whose disparity `1/R` differs by more than
    /// this factor (a ratio, either way) from the median of its neighbourhood, in a patch
    /// at most [`local_outlier_span`](Self::local_outlier_span) across, becomes unknown.
    /// Default 3; 0 turns the rule off; otherwise finite and > 1.
    pub local_outlier_factor: f64,
    /// Longest side of a local-outlier patch, as a fraction of the image's longer side
    /// (at least 4 px); also the half-size of the neighbourhood. In [0, 1], default 0.025
    /// (51 px on a 2048 x 1024 frame).
    pub local_outlier_span: f64,
    /// Border bands (step 4a): runs of unknown pixels from a border inward, at most this
    /// fraction of the line long, continue the surface they meet (or are sky, when they
    /// meet the sky) instead of being filled as holes. In [0, 1], default 0.15; 0 turns
    /// it off.
    pub border_band_fraction: f64,
    /// A monocular model's map gives the sky a depth, the farthest, where a sensor leaves
    /// it unknown: with `Some(k)`, known range above `k` times the lower quartile of the
    /// known range may be sky, and the image-guided detector grows the sky over such
    /// pixels that look like sky as over unknown ones (their range is kept where they do
    /// not). `None` (the default) for measured depth; [`crate::photo::preprocess`] sets
    /// [`MONOCULAR_SKY_FACTOR`] for inverse and affine-invariant depth. Finite and > 1.
    pub sky_in_far_tail: Option<f64>,
    /// `Some(f·B)`, the focal length in pixels times the baseline in metres, when the range
    /// comes from a stereo disparity (d ≈ f·B / R): a run of unknown pixels in a row beside
    /// a much nearer surface, left of it in a left view and right of it in a right view
    /// ([`Self::stereo_view`]), and about as wide as their disparities differ, is the
    /// background the other camera could not see, and is filled without the near surface
    /// beside it (see `src/prep/occlusion.rs`).
    /// [`crate::photo::preprocess`] sets it for a disparity (Cityscapes, Middlebury, one
    /// read with a focal length and baseline); `None` (the default) for any other map.
    /// Finite and > 0.
    pub stereo_focal_baseline: Option<f64>,
    /// Which view of its stereo pair the disparity is of, and so on which side of a nearer
    /// surface its occlusions lie: `None` (the default) takes [`LoadedDepth::stereo_view`]
    /// in [`Self::for_depth`], else the left view.
    pub stereo_view: Option<StereoView>,
    /// The level ground under a camera of known mount (a vehicle's: a Cityscapes camera
    /// file's height, pitch and roll, or `--camera-mount`'s, with the map's intrinsics, on
    /// the range's grid): below the horizon a ray meets the road at a range no measured
    /// value may exceed by much; small patches of values beyond 2x it (and beyond the road
    /// falling 5 % away) are a matcher's false matches and become holes (see
    /// `src/prep/ground.rs`).
    /// [`crate::photo::preprocess`] sets it from [`LoadedDepth::mount`]; `None` (the
    /// default) for any other map.
    pub ground: Option<Ground>,
}

/// The level ground of a depth map in metres whose camera's mount and intrinsics are
/// known (a Cityscapes disparity with its camera file, or a map given `camera_mount`).
fn ground_of(depth: &LoadedDepth) -> Option<Ground> {
    let metres = depth.metric && depth.units == "m";
    depth
        .mount
        .zip(depth.intrinsics)
        .filter(|_| metres)
        .map(|(mount, intrinsics)| Ground { mount, intrinsics })
}

/// [`PrepOptions::sky_in_far_tail`] for a monocular model's relative depth: beyond ten
/// times the lower quartile of the range (the sky's depth in such a map is that of the
/// farthest scene or more; a room is nowhere ten times deeper than its near quarter, so
/// its white ceiling keeps the protection of its range).
pub const MONOCULAR_SKY_FACTOR: f64 = 10.0;

impl Default for PrepOptions {
    fn default() -> Self {
        PrepOptions {
            sky: SkyRules::default(),
            image_sky: ImageSkyRules::default(),
            margin_px: 8.0,
            jacobi_iterations: None,
            sky_range_factor: 1.5,
            ransac_samples: 32,
            seed: 0,
            detect_sky: true,
            far_outlier_factor: 2.0,
            far_patch_fraction: 0.0005,
            local_outlier_factor: 3.0,
            local_outlier_span: 0.025,
            border_band_fraction: 0.15,
            sky_in_far_tail: None,
            stereo_focal_baseline: None,
            stereo_view: None,
            ground: None,
        }
    }
}

impl PrepOptions {
    /// These options for `depth`, what its reading tells filled in where they leave it
    /// open: [`MONOCULAR_SKY_FACTOR`] for a monocular model's inverse or affine-invariant
    /// depth ([`Self::sky_in_far_tail`]), the stereo geometry of a matched disparity
    /// ([`Self::stereo_focal_baseline`], [`Self::stereo_view`]).
    pub fn for_depth(&self, depth: &LoadedDepth) -> PrepOptions {
        let monocular = matches!(depth.kind, DepthKind::Inverse | DepthKind::Affine);
        PrepOptions {
            sky_in_far_tail: (self.sky_in_far_tail).or(monocular.then_some(MONOCULAR_SKY_FACTOR)),
            stereo_focal_baseline: self.stereo_focal_baseline.or(depth.stereo_focal_baseline),
            stereo_view: self.stereo_view.or(Some(depth.stereo_view)),
            ground: self.ground.or_else(|| ground_of(depth)),
            ..self.clone()
        }
    }

    /// Checks every field; an out-of-domain one gives [`Error::InvalidParameter`].
    pub fn validate(&self) -> Result<()> {
        check_fraction("min_area_fraction", self.sky.min_area_fraction)?;
        check_fraction("sky.min_top_fraction", self.sky.min_top_fraction)?;
        check_fraction("sky.min_bbox_fill", self.sky.min_bbox_fill)?;
        self.validate_image_sky()?;
        if !(0.0..=MAX_MARGIN_PX).contains(&self.margin_px) {
            return Err(Error::invalid(
                "margin_px",
                self.margin_px,
                "a number of pixels in [0, 65535]",
            ));
        }
        if !(self.sky_range_factor > 1.0 && self.sky_range_factor <= MAX_SKY_RANGE_FACTOR) {
            return Err(Error::invalid(
                "sky_range_factor",
                self.sky_range_factor,
                format!(
                    "a number in (1, {MAX_SKY_RANGE_FACTOR}]: the sky's range as a multiple of \
                     the farthest measured range"
                ),
            ));
        }
        if self.ransac_samples == 0 {
            return Err(Error::invalid("ransac_samples", 0, "at least 1"));
        }
        let f = self.far_outlier_factor;
        if !(f == 0.0 || (f >= 1.0 && f.is_finite())) {
            return Err(Error::invalid(
                "far_outlier_factor",
                f,
                "0 (off) or a finite number >= 1: the multiple of the 99th percentile of \
                 the known range above which isolated values are outliers",
            ));
        }
        check_fraction("far_patch_fraction", self.far_patch_fraction)?;
        if let Some(k) = self
            .sky_in_far_tail
            .filter(|k| !(k.is_finite() && *k > 1.0))
        {
            return Err(Error::invalid(
                "sky_in_far_tail",
                k,
                "a finite multiple of the range's lower quartile, greater than 1",
            ));
        }
        let f = self.local_outlier_factor;
        if !(f == 0.0 || (f > 1.0 && f.is_finite())) {
            return Err(Error::invalid(
                "local_outlier_factor",
                f,
                "0 (off) or a finite number > 1: the ratio between a patch's range and its \
                 neighbourhood's above which the patch is an outlier",
            ));
        }
        check_fraction("local_outlier_span", self.local_outlier_span)?;
        if let Some(fb) = self
            .stereo_focal_baseline
            .filter(|fb| !(fb.is_finite() && *fb > 0.0))
        {
            return Err(Error::invalid(
                "stereo_focal_baseline",
                fb,
                "a finite focal length in pixels times a baseline in metres, greater than 0",
            ));
        }
        if let Some(ground) = &self.ground {
            ground.validate()?;
        }
        check_fraction("border_band_fraction", self.border_band_fraction)
    }

    fn validate_image_sky(&self) -> Result<()> {
        let r = &self.image_sky;
        check_fraction("image_sky.seed_rows", r.seed_rows)?;
        check_fraction("image_sky.max_gap_fraction", r.max_gap_fraction)?;
        for (name, v) in [
            ("image_sky.max_texture", r.max_texture),
            ("image_sky.max_step", r.max_step),
            ("image_sky.min_brightness", r.min_brightness),
            ("image_sky.min_blue_ratio", r.min_blue_ratio),
        ] {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(Error::invalid(name, v, "a finite number >= 0"));
            }
        }
        if r.bridge_px > MAX_BRIDGE_PX {
            return Err(Error::invalid(
                "image_sky.bridge_px",
                r.bridge_px,
                format!("at most {MAX_BRIDGE_PX} pixels"),
            ));
        }
        Ok(())
    }

    /// The number of Jacobi sweeps actually used: the option, or `ceil(2 µ)`.
    pub fn jacobi_sweeps(&self) -> usize {
        self.jacobi_iterations
            .unwrap_or((2.0 * self.margin_px).ceil() as usize)
    }
}

fn check_fraction(name: &str, v: f64) -> Result<()> {
    if (0.0..=1.0).contains(&v) {
        Ok(())
    } else {
        Err(Error::invalid(name, v, "a fraction in [0, 1]"))
    }
}

/// Bytes per pixel of the range map that pre-processing allocates besides the range
/// itself and its guides: without an image guide, and with one (whose sky finder keeps
/// its luminance, texture and colour steps). From `brume prep`'s peak RSS: about 18 bytes
/// per pixel in all without an image (4000 x 3000 and 8000 x 6000, the decoded range
/// included), 60 with one (4000 x 3000, the decoded image included); rounded up.
const PREP_BYTES_PER_PIXEL: [u64; 2] = [16, 40];

/// Refuses, before its maps are allocated, a pre-processing of a `w x h` range that would
/// not fit in the memory left ([`crate::memory`]), rather than let the allocator abort.
pub(super) fn check_memory(w: usize, h: usize, guided: bool) -> Result<crate::memory::Reservation> {
    let per_pixel = PREP_BYTES_PER_PIXEL[usize::from(guided)];
    crate::memory::reserve(
        &format!("pre-processing a {w}x{h} range map"),
        per_pixel * w as u64 * h as u64,
        &format!(
            "pre-processing holds about {per_pixel} bytes per pixel of the depth map besides \
             it: use a smaller depth map"
        ),
    )
}
