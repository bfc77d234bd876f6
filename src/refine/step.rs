//! The refinement step of a photo's range, as `brume render`, `prep`, `batch` and `view`
//! run it between pre-processing and the fog: a depth map smaller than the image is
//! upsampled guided by the image, then the guided filter runs if asked for. The GPU's
//! passes ([`crate::Renderer`]) and their f64 CPU references ([`CpuFilter`]) are
//! interchangeable behind [`RangeFilter`].

use super::beyond::RecedingCells;
use super::{
    at_image_size, check_positive, nearest_to_image_size, Refine, DEFAULT_UPSAMPLE_SIGMA_COLOUR,
};
use crate::error::{Error, Result};
use crate::io::depth::DepthFormat;
use crate::memory::Reservation;
use crate::prep::Prepared;
use crate::raster::{Grid, RgbImage, ScalarMap};
use std::borrow::Cow;

/// Which refinement a range gets (`--refine`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum RefineMode {
    /// No refinement (a smaller depth map is still upsampled, guided).
    #[default]
    None,
    /// The guided filter, everywhere.
    Guided,
    /// The guided filter where the range is unreliable only: where pre-processing filled
    /// it (holes, outliers, left-right mismatches, border bands); elsewhere the range is
    /// kept as measured.
    Unreliable,
    /// The measured range with its depth edges moved to the image's (a colour-weighted
    /// median where a pixel is at a depth edge, which trims a matcher's fattened near
    /// surfaces), then the guided range where that is much nearer than it, half of each
    /// where pre-processing filled the range, that range elsewhere (see [`repair`]): a
    /// stereo matcher's false matches in the sky and on textureless far surfaces are
    /// repaired, the depth it got right is kept. The default for Cityscapes disparity.
    Repair,
}

impl RefineMode {
    /// The mode's name as the command line and the Python package take it.
    pub fn name(self) -> &'static str {
        match self {
            RefineMode::None => "none",
            RefineMode::Guided => "guided",
            RefineMode::Unreliable => "unreliable",
            RefineMode::Repair => "repair",
        }
    }

    /// The refinement a depth map of `format` gets unless told otherwise: [`Self::Repair`]
    /// for stereo-matched disparity (Cityscapes' SGM), measured to make it better in every
    /// region (README, "Real depth"); none for the rest, whose depth is a sensor's or a
    /// renderer's, on which it was not measured.
    pub fn default_for(format: DepthFormat) -> RefineMode {
        match format {
            DepthFormat::Cityscapes => RefineMode::Repair,
            _ => RefineMode::None,
        }
    }
}

/// Where [`RefineMode::Repair`] starts and ends taking the guided range: the guided log
/// range exceeds the measured one by 1.0 (the measured range 2.7 times nearer) to 1.5
/// (4.5 times), with a smoothstep between.
pub const REPAIR_NEARER: [f64; 2] = [1.0, 1.5];

/// The weight of the guided range where pre-processing filled the range, in
/// [`RefineMode::Repair`]: there the guided and the filled range were measured equally
/// good, and their mean better than either.
pub const REPAIR_FILLED_WEIGHT: f64 = 0.5;

/// One pixel of [`RefineMode::Repair`]: the log-range mix of the `measured` (after
/// pre-processing) and the `guided` range (both > 0). The weight of the guided range is
/// w = smoothstep over [`REPAIR_NEARER`] of ln guided − ln measured; where the range was
/// `filled` the measured range's weight 1 − w is multiplied by 1 − [`REPAIR_FILLED_WEIGHT`].
///
/// Why one sign: a stereo matcher's disparity of the sky or of a textureless far surface
/// can err only upward (a disparity below 0 is invalid, and there the true one is near
/// 0), so its false matches are always too near, often by a factor of 5 to 50 (measured
/// on StereoSGBM with a known truth, `tools/stereo_refine_eval.py`); where the guided
/// filter is wrong on correct depth, it mostly pulls a far surface nearer (where a window
/// holds a near and a far surface the guide cannot tell apart) or blurs an edge by less
/// than a factor of 2.7, which the rule leaves alone.
pub fn repair(measured: f32, guided: f32, filled: bool) -> f32 {
    // Computed as measured · (guided / measured)^weight, which is the log-range mix: most
    // pixels of a frame take one side alone (weight 0 or 1) or halve the logs (a filled
    // pixel where the guide is not much farther), which need no logarithm and no
    // exponential (a 12 MP frame's mix took 120 ms in three f64 transcendentals a pixel).
    let (m, g) = (f64::from(measured), f64::from(guided));
    let ratio = g / m;
    let [t0, t1] = REPAIR_NEARER;
    let mut weight = if ratio <= t0.exp() {
        0.0
    } else if ratio >= t1.exp() {
        1.0
    } else {
        let x = (ratio.ln() - t0) / (t1 - t0);
        x * x * (3.0 - 2.0 * x)
    };
    if filled {
        weight = 1.0 - (1.0 - weight) * (1.0 - REPAIR_FILLED_WEIGHT);
    }
    if weight == 0.0 {
        measured
    } else if weight == 1.0 {
        guided
    } else if weight == 0.5 {
        (m * ratio.sqrt()) as f32
    } else {
        (m * (weight * ratio.ln()).exp()) as f32
    }
}

/// How a photo's range is refined with its image.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct RefineOptions {
    /// Whether and where the guided filter runs.
    pub mode: RefineMode,
    /// The guided filter's window and regularisation.
    pub filter: Refine,
    /// The colour σ of the joint bilateral upsampling of a smaller depth map, in
    /// sRGB-encoded values.
    pub upsample_sigma_colour: f64,
}

impl Default for RefineOptions {
    /// No guided filter (measured on stereo-matched depth, it blurs what the matcher got
    /// right: README, "Real depth"); Foggy Cityscapes' window; σ 0.15 for upsampling.
    fn default() -> Self {
        RefineOptions {
            mode: RefineMode::None,
            filter: Refine::default(),
            upsample_sigma_colour: DEFAULT_UPSAMPLE_SIGMA_COLOUR,
        }
    }
}

impl RefineOptions {
    /// Checks the values, naming the field.
    pub fn validate(&self) -> Result<()> {
        self.filter.validate()?;
        if !(self.upsample_sigma_colour.is_finite() && self.upsample_sigma_colour > 0.0) {
            return Err(Error::invalid(
                "upsample_sigma_colour",
                self.upsample_sigma_colour,
                "a colour σ > 0 (sRGB-encoded values)",
            ));
        }
        Ok(())
    }

    /// What runs for a range of `range` size under an image of `image` size.
    pub fn plan(&self, image: (usize, usize), range: (usize, usize)) -> RefinePlan {
        RefinePlan {
            upsample: image != range,
            edges: self.mode == RefineMode::Repair,
            guided: (self.mode != RefineMode::None).then_some(self.filter),
            combine: match self.mode {
                RefineMode::Unreliable => Combine::WhereFilled,
                RefineMode::Repair => Combine::Repair,
                RefineMode::None | RefineMode::Guided => Combine::Guided,
            },
        }
    }
}

/// What a refinement runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefinePlan {
    /// The depth map is smaller than the image: joint bilateral upsampling first.
    pub upsample: bool,
    /// The depth edges are moved to the image's before the guided filter
    /// ([`super::median_at_depth_edges`], [`RefineMode::Repair`]).
    pub edges: bool,
    /// The guided filter at the image's size, if on.
    pub guided: Option<Refine>,
    /// How the guided range and the measured one are combined.
    pub combine: Combine,
}

/// How [`refine_range`] combines the guided range with the measured one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Combine {
    /// The guided range everywhere.
    Guided,
    /// The guided range where pre-processing filled the range, else the measured one
    /// ([`RefineMode::Unreliable`]).
    WhereFilled,
    /// [`repair`] per pixel ([`RefineMode::Repair`]).
    Repair,
}

impl RefinePlan {
    /// Whether anything runs at all.
    pub fn is_empty(&self) -> bool {
        !self.upsample && self.guided.is_none()
    }
}

/// How a refinement's passes run: on the GPU ([`crate::Renderer`]) or by their CPU
/// references ([`CpuFilter`]).
pub trait RangeFilter {
    /// Upsamples `range` (> 0, smaller than `image` by one factor) to the image's size
    /// guided by it ([`super::joint_bilateral_upsample_reference`]).
    fn upsample(
        &mut self,
        image: &RgbImage,
        range: &ScalarMap,
        sigma_colour: f64,
    ) -> Result<ScalarMap>;
    /// The guided filter of `range` (> 0, of the image's size) with `image` as guide
    /// ([`super::guided_range_reference`]).
    fn guided(&mut self, image: &RgbImage, range: &ScalarMap, opts: &Refine) -> Result<ScalarMap>;
    /// Bytes of system memory per pixel of the image that a refinement by this filter takes
    /// at its peak, checked before it runs: [`CpuFilter`]'s figure unless a filter says.
    fn bytes_per_pixel(&self) -> u64 {
        CPU_FILTER_BYTES_PER_PIXEL
    }
    /// Bytes of system memory counted in [`RangeFilter::bytes_per_pixel`] that the filter
    /// already holds from an earlier call and reuses, or frees before it allocates: none
    /// unless a filter says.
    fn kept_bytes(&self) -> u64 {
        0
    }
}

/// [`RangeFilter::bytes_per_pixel`] of [`CpuFilter`]: `brume prep --refine repair` or
/// `guided` of a 4000x3000 frame grew its resident memory by 20.0 bytes per pixel from the
/// start of the refinement to its end (13.9 of address space, which `ulimit -v` counts).
const CPU_FILTER_BYTES_PER_PIXEL: u64 = 22;

/// The bytes per pixel of the image that moving the depth edges
/// ([`super::median_at_depth_edges`]) holds besides the filter's: the colour's 8-bit codes
/// (3), the log range and its neighbourhood's farthest (4 each), the kept-out mask (1),
/// the result (4).
const EDGES_BYTES_PER_PIXEL: u64 = 16;

/// [`RangeFilter::bytes_per_pixel`] of the renderer on a software renderer, which keeps its
/// textures in system memory: a 4000x3000 `brume render --refine repair` on llvmpipe grew
/// its resident memory by 31.2 bytes per pixel over the refinement (it aborted under
/// `ulimit -v` with 23 bytes per pixel of address space left when it began).
const SOFTWARE_GPU_FILTER_BYTES_PER_PIXEL: u64 = 34;

/// [`RangeFilter::bytes_per_pixel`] of the renderer on a GPU: the refined range read back.
const GPU_FILTER_BYTES_PER_PIXEL: u64 = 8;

impl RangeFilter for crate::Renderer {
    fn upsample(
        &mut self,
        image: &RgbImage,
        range: &ScalarMap,
        sigma_colour: f64,
    ) -> Result<ScalarMap> {
        Ok(crate::Renderer::upsample(self, image, range, sigma_colour)?.0)
    }
    fn guided(&mut self, image: &RgbImage, range: &ScalarMap, opts: &Refine) -> Result<ScalarMap> {
        Ok(crate::Renderer::refine(self, image, range, opts)?.0)
    }
    fn bytes_per_pixel(&self) -> u64 {
        if self.caps().software() {
            SOFTWARE_GPU_FILTER_BYTES_PER_PIXEL
        } else {
            GPU_FILTER_BYTES_PER_PIXEL
        }
    }
    /// The uploads' textures kept from the last frame, on a software renderer.
    fn kept_bytes(&self) -> u64 {
        self.kept_upload_bytes()
    }
}

/// The CPU references of the GPU passes, in f64 (the same results within 1e-4): for a
/// host without a GL context, and `brume prep`, which opens none.
#[derive(Clone, Copy, Debug, Default)]
pub struct CpuFilter;

impl RangeFilter for CpuFilter {
    fn upsample(
        &mut self,
        image: &RgbImage,
        range: &ScalarMap,
        sigma_colour: f64,
    ) -> Result<ScalarMap> {
        super::joint_bilateral_upsample_reference(image, range, sigma_colour)
    }
    fn guided(&mut self, image: &RgbImage, range: &ScalarMap, opts: &Refine) -> Result<ScalarMap> {
        super::guided_range_reference(image, range, opts)
    }
}

/// Refines `range` (finite everywhere; 0 marks the ego vehicle, never fogged) with
/// `image` (linear RGB) as guide, as `opts` asks: the result has the image's size.
/// `filled` (on the range's grid) marks where pre-processing filled the range, which
/// [`RefineMode::Unreliable`] refines alone; without it that mode refines everywhere.
///
/// Errors: [`Error::InvalidParameter`] for bad options, a depth size
/// [`super::check_depth_size`] refuses or a range ≤ 0 or not finite elsewhere; the
/// filter's own errors.
pub fn refine_range(
    image: &RgbImage,
    range: &ScalarMap,
    filled: Option<&Grid<bool>>,
    opts: &RefineOptions,
    filter: &mut dyn RangeFilter,
) -> Result<ScalarMap> {
    refine_with_masks(image, range, (filled, None), opts, filter)
}

/// Refuses a refinement of a `w`x`h` image that cannot fit in the memory left, before it
/// allocates: `prep` and `render` aborted the process on a failed allocation there. The
/// `kept` bytes the filter holds already are not counted twice.
fn check_memory(w: usize, h: usize, per_pixel: u64, kept: u64) -> Result<Reservation> {
    crate::memory::reserve(
        &format!("refining the range of a {w}x{h} image"),
        (per_pixel * w as u64 * h as u64).saturating_sub(kept),
        &format!(
            "the refinement holds about {per_pixel} bytes per pixel of the image: use a \
             smaller image, or no refinement"
        ),
    )
}

/// [`refine_range`], with the receding ground beyond the sensor's reach and the sky (on
/// the range's grid) interpolated when the range is upsampled
/// ([`super::beyond::interpolate_receding`]).
fn refine_with_masks(
    image: &RgbImage,
    range: &ScalarMap,
    (filled, receding): (Option<&Grid<bool>>, Option<RecedingCells>),
    opts: &RefineOptions,
    filter: &mut dyn RangeFilter,
) -> Result<ScalarMap> {
    opts.validate()?;
    let (w, h) = (image.width(), image.height());
    super::check_depth_size((w, h), (range.width(), range.height()))?;
    let plan = opts.plan((w, h), (range.width(), range.height()));
    if plan.is_empty() {
        return Ok(range.clone());
    }
    let per_pixel = filter.bytes_per_pixel() + if plan.edges { EDGES_BYTES_PER_PIXEL } else { 0 };
    let _reserved = check_memory(w, h, per_pixel, filter.kept_bytes())?;
    // The ego vehicle's range 0 is not a range to filter (the filter reads log range): it
    // is kept out at the nearest range and put back after. A range without any is read as
    // it is, not copied (a copy is 48 MB at 12 MP).
    let has_ego = range.as_slice().contains(&0.0);
    let ego_on_range_grid = has_ego.then(|| range.map(|&v| v == 0.0));
    let ego = (ego_on_range_grid.as_ref()).map(|e| at_image_size(e, w, h));
    let positive = if has_ego {
        let nearest = range
            .as_slice()
            .iter()
            .copied()
            .filter(|&v| v > 0.0)
            .fold(f32::INFINITY, f32::min);
        Cow::Owned(range.map(|&v| if v == 0.0 { nearest } else { v }))
    } else {
        Cow::Borrowed(range)
    };
    check_positive(&positive)?;
    let measured = if plan.upsample {
        let mut up = filter.upsample(image, &positive, opts.upsample_sigma_colour)?;
        if let Some(masks) = receding {
            super::beyond::interpolate_receding(&positive, masks, &mut up);
        }
        Cow::Owned(up)
    } else {
        positive
    };
    let measured = if plan.edges {
        let sky = receding.map(|(_, sky)| at_image_size(sky, w, h));
        let is = |mask: &Option<Cow<Grid<bool>>>, x, y| mask.as_ref().is_some_and(|m| *m.get(x, y));
        let kept_out = (ego.is_some() || sky.is_some())
            .then(|| Grid::par_from_fn(w, h, |x, y| is(&ego, x, y) || is(&sky, x, y)));
        Cow::Owned(super::median_at_depth_edges(image, &measured, kept_out.as_ref())?.0)
    } else {
        measured
    };
    let mut out = match &plan.guided {
        None => measured.into_owned(),
        Some(filter_opts) => {
            let refined = filter.guided(image, &measured, filter_opts)?;
            let filled = filled.map(|f| at_image_size(f, w, h));
            let is_filled = |x, y| filled.as_ref().is_some_and(|f| *f.get(x, y));
            match plan.combine {
                Combine::Guided => refined,
                Combine::WhereFilled if filled.is_none() => refined,
                Combine::WhereFilled => Grid::par_from_fn(w, h, |x, y| {
                    *if is_filled(x, y) { &refined } else { &measured }.get(x, y)
                }),
                Combine::Repair => Grid::par_from_fn(w, h, |x, y| {
                    repair(*measured.get(x, y), *refined.get(x, y), is_filled(x, y))
                }),
            }
        }
    };
    if let Some(ego) = &ego {
        for (v, _) in out
            .as_mut_slice()
            .iter_mut()
            .zip(ego.as_slice())
            .filter(|(_, &e)| e)
        {
            *v = 0.0;
        }
    }
    Ok(out)
}

/// [`refine_range`] on a pre-processed range, in place: its range is refined with what
/// pre-processing filled as the unreliable pixels, the ground it found receding beyond the
/// sensor's reach interpolated as it recedes ([`Prepared::receding`]), and its masks are
/// brought to the image's size with it. Returns the plan that ran.
pub fn refine_prepared(
    image: &RgbImage,
    prepared: &mut Prepared,
    opts: &RefineOptions,
    filter: &mut dyn RangeFilter,
) -> Result<RefinePlan> {
    let (w, h) = (image.width(), image.height());
    let range_size = (prepared.range.width(), prepared.range.height());
    let plan = opts.plan((w, h), range_size);
    if plan.is_empty() {
        return Ok(plan);
    }
    let masks = (
        Some(&prepared.filled),
        Some((&prepared.receding, &prepared.sky)),
    );
    prepared.range = refine_with_masks(image, &prepared.range, masks, opts, filter)?;
    for mask in [
        &mut prepared.sky,
        &mut prepared.filled,
        &mut prepared.beyond_reach,
        &mut prepared.receding,
    ] {
        bring_to_image_size(mask, w, h);
    }
    Ok(plan)
}

/// Brings `map` to the image's size ([`nearest_to_image_size`]) in place: nothing is done
/// where it has that size already.
fn bring_to_image_size<T: Copy + Send + Sync>(map: &mut Grid<T>, width: usize, height: usize) {
    if (map.width(), map.height()) != (width, height) {
        *map = nearest_to_image_size(map, width, height);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Counts the calls, and upsamples by nearest / filters to a constant, so that the
    /// step's own logic (ego pixels, the unreliable mask, the masks' sizes) is tested
    /// apart from the filters (tested against their references in `tests/refine.rs`).
    #[derive(Default)]
    struct Fake {
        upsampled: usize,
        filtered: usize,
    }

    impl RangeFilter for Fake {
        fn upsample(&mut self, image: &RgbImage, range: &ScalarMap, _: f64) -> Result<ScalarMap> {
            self.upsampled += 1;
            Ok(nearest_to_image_size(range, image.width(), image.height()))
        }
        fn guided(&mut self, _: &RgbImage, range: &ScalarMap, _: &Refine) -> Result<ScalarMap> {
            self.filtered += 1;
            assert!(
                range.as_slice().iter().all(|&v| v > 0.0),
                "log range of ≤ 0"
            );
            Ok(range.map(|_| 7.0))
        }
    }

    fn image(w: usize, h: usize) -> RgbImage {
        Grid::from_fn(w, h, |x, _| [x as f32 / w as f32; 3])
    }

    #[test]
    fn nothing_runs_by_default_at_the_image_size() {
        let range = Grid::from_fn(4, 2, |x, _| 1.0 + x as f32);
        let mut fake = Fake::default();
        let out = refine_range(
            &image(4, 2),
            &range,
            None,
            &RefineOptions::default(),
            &mut fake,
        )
        .unwrap();
        assert_eq!(out, range);
        assert_eq!((fake.upsampled, fake.filtered), (0, 0));
    }

    #[test]
    fn a_smaller_range_is_upsampled_and_the_ego_vehicle_stays_at_zero() {
        let range = Grid::from_fn(2, 2, |x, y| if (x, y) == (1, 1) { 0.0 } else { 3.0 });
        let mut fake = Fake::default();
        let opts = RefineOptions {
            mode: RefineMode::Guided,
            ..RefineOptions::default()
        };
        let out = refine_range(&image(8, 8), &range, None, &opts, &mut fake).unwrap();
        assert_eq!((fake.upsampled, fake.filtered), (1, 1));
        assert_eq!((out.width(), out.height()), (8, 8));
        assert_eq!(*out.get(6, 6), 0.0, "ego cell");
        assert_eq!(*out.get(1, 6), 7.0, "filtered elsewhere");
    }

    /// At the image's size (the range read in place, not copied, where it has no ego
    /// pixel): the ego pixel stays 0, the rest is repaired; without one nothing is 0.
    #[test]
    fn at_the_image_size_the_ego_vehicle_stays_at_zero() {
        let opts = RefineOptions {
            mode: RefineMode::Repair,
            ..RefineOptions::default()
        };
        for ego in [true, false] {
            let range = Grid::from_fn(4, 3, |x, y| if ego && (x, y) == (2, 2) { 0.0 } else { 3.0 });
            let mut fake = Fake::default();
            let out = refine_range(&image(4, 3), &range, None, &opts, &mut fake).unwrap();
            assert_eq!((fake.upsampled, fake.filtered), (0, 1));
            assert_eq!(*out.get(2, 2), if ego { 0.0 } else { 3.0 }, "ego {ego}");
            // The guide's 7 is 2.3 times the measured 3: repair keeps the measured range.
            assert_eq!(*out.get(0, 0), 3.0, "ego {ego}");
        }
    }

    #[test]
    fn unreliable_takes_the_filter_where_filled_alone() {
        let range = Grid::from_fn(4, 4, |_, _| 2.0);
        let filled = Grid::from_fn(4, 4, |x, _| x == 0);
        let opts = RefineOptions {
            mode: RefineMode::Unreliable,
            ..RefineOptions::default()
        };
        let out = refine_range(
            &image(4, 4),
            &range,
            Some(&filled),
            &opts,
            &mut Fake::default(),
        )
        .unwrap();
        assert_eq!(*out.get(0, 2), 7.0);
        assert_eq!(*out.get(1, 2), 2.0);
    }

    /// Worked values of the rule, by hand: ln 10 = 2.302585.
    #[test]
    fn repair_takes_the_guided_range_where_the_measured_one_is_far_nearer() {
        let close = |a: f32, b: f64| (f64::from(a) - b).abs() < 1e-4 * b;
        let e = std::f64::consts::E as f32;
        // 2 nats nearer: beyond 1.5, all guided.
        assert!(close(repair(10.0, 10.0 * e * e, false), 10.0 * 7.389056));
        // 0.5 nats nearer, or farther: all measured.
        assert!(close(repair(10.0, 10.0 * e.sqrt(), false), 10.0));
        assert!(close(repair(10.0, 1.0, false), 10.0));
        // 1.25 nats: half way, smoothstep 0.5: exp(ln 10 + 0.625).
        assert!(close(repair(10.0, 10.0 * 1.25f32.exp(), false), 18.682460));
        // Filled: the measured weight halves; 1 nat farther in the guide → exp(ln 10 − 0.5).
        assert!(close(repair(10.0, 10.0 / e, true), 6.065307));
        // Filled and half way: w = 1 − 0.5 · 0.5 = 0.75 → exp(ln 10 + 0.9375).
        assert!(close(repair(10.0, 10.0 * 1.25f32.exp(), true), 25.535894));
    }

    /// The rule as its doc states it, in logs: the mix is within an f32 rounding of it
    /// over ranges from 1 cm to 10 km, on both sides of and inside the smoothstep.
    #[test]
    fn repair_is_the_log_range_mix() {
        let textbook = |m: f32, g: f32, filled: bool| {
            let (lm, lg) = (f64::from(m).ln(), f64::from(g).ln());
            let [t0, t1] = REPAIR_NEARER;
            let x = ((lg - lm - t0) / (t1 - t0)).clamp(0.0, 1.0);
            let mut w = x * x * (3.0 - 2.0 * x);
            if filled {
                w = 1.0 - (1.0 - w) * (1.0 - REPAIR_FILLED_WEIGHT);
            }
            ((1.0 - w) * lm + w * lg).exp()
        };
        let mut rng = crate::rng::SplitMix64::new(7);
        let mut inside = 0;
        for k in 0..200_000 {
            let m = (10f64.powf(rng.unit() * 6.0 - 2.0)) as f32;
            // The guide from 10 times nearer to 10 times farther, a fifth of the draws in
            // the smoothstep's band.
            let nats = if k % 5 == 0 {
                1.0 + rng.unit() * 0.5
            } else {
                rng.unit() * 4.6 - 2.3
            };
            let g = (f64::from(m) * nats.exp()) as f32;
            let filled = k % 2 == 1;
            let (got, want) = (repair(m, g, filled), textbook(m, g, filled));
            let err = (f64::from(got) - want).abs() / want;
            assert!(err <= 1.2e-7, "{m} {g} {filled}: {got} against {want}");
            let ln_ratio = (f64::from(g) / f64::from(m)).ln();
            inside += usize::from(ln_ratio > 1.0 && ln_ratio < 1.5);
        }
        assert!(inside > 30_000, "{inside} draws in the band");
        // One side alone is that side's value to the bit.
        assert_eq!(repair(3.3, 2.0, false), 3.3);
        assert_eq!(repair(3.3, 300.0, false), 300.0);
        assert_eq!(repair(3.3, 300.0, true), 300.0);
    }

    #[test]
    fn cityscapes_disparity_is_repaired_by_default_and_nothing_else() {
        assert_eq!(
            RefineMode::default_for(DepthFormat::Cityscapes),
            RefineMode::Repair
        );
        for f in [
            DepthFormat::Middlebury2006,
            DepthFormat::AndroidDepth16,
            DepthFormat::Float,
        ] {
            assert_eq!(RefineMode::default_for(f), RefineMode::None, "{f:?}");
        }
    }

    #[test]
    fn another_aspect_ratio_is_refused_naming_both_sizes() {
        let range = Grid::from_fn(4, 3, |_, _| 2.0);
        let err = refine_range(
            &image(16, 9),
            &range,
            None,
            &RefineOptions::default(),
            &mut Fake::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("4x3") && err.contains("16x9"), "{err}");
    }
}
