//! Pre-processing of real scanner range data (paper 000, sec. 4.1): hole filling, sky
//! detection, horizon margin and airlight estimation. Pure CPU, no GL.
//!
//! [`prepare`] turns a range map with unknown pixels (any non-finite value, normally NaN)
//! into a map that is finite everywhere, **without changing a single known value**:
//!
//! 1. **Components.** The 4-connected components of unknown pixels are labelled in linear
//!    time (one raster scan, breadth-first flood fill, no label image).
//! 2. **Sky.** A component is sky when it passes every rule of [`SkyRules`]; by default:
//!    it touches the top row; its area is at least 1 % of the image; it covers at least
//!    10 % of the top row (sky is wide at the top, an occlusion band or a border strip is
//!    not); it fills at least 30 % of its own bounding box (a thin frame of unknown pixels
//!    round the image, as stereo ground truth often has, fills about 1 %); and it does not
//!    reach the bottom row (an occlusion band running the whole height is not sky). Of the
//!    components that pass, the [`SkyRules::max_components`] (default 4) largest are sky.
//!    Sky pixels get the constant range `Smax = sky_range_factor x Rmax` (default 1.5),
//!    where `Rmax` is the maximum known range. The output stays in the input's units: a
//!    renderer that normalises range by `Rmax` ([`PrepStats::r_max`]) sees the sky at
//!    `sky_range_factor`. Indoor data (e.g. Middlebury Aloe, whose unknown pixels are
//!    occlusions, 3.5 % of the image in 1211 components, none touching the top row) gets
//!    no sky. [`PrepOptions::detect_sky`] = false treats every component as a hole.
//! 3. **Holes** (all other components) are filled by RANSAC (Fischler and Bolles 1981), as
//!    in the paper, "by sampling from the available values on each hole boundary" and
//!    keeping "the value that minimizes a robust function of the gradient across the
//!    boundary". The boundary is the set of *edges* (hole pixel `h`, known 4-neighbour
//!    `b`). A candidate surface `F` is scored by the truncated L1 jump it leaves across the
//!    boundary, `E(F) = sum_b min(|F(b) - R(b)|, delta)`: `F` continued onto the known side
//!    should meet the data. For a constant `F = c` this is exactly the truncated L1 norm of
//!    the finite-difference gradient `c - R(b)` across every boundary edge; for a plane it
//!    is the gradient left over after the plane's own slope. The truncation makes the
//!    score robust: a boundary that straddles a depth edge (foreground on one side,
//!    background on the other) is won by the majority surface instead of being averaged.
//!    `delta = 1.4826 x MAD` of the boundary values (one robust standard deviation),
//!    floored at a few ulps of their median. Each of the `ransac_samples` (default 32)
//!    trials draws one constant (a boundary value; all boundary values are tried when
//!    there are no more of them than trials) and one plane `R = a + b x + c y` through
//!    three boundary samples (only for boundaries of at least 4 edges; collinear triplets
//!    are skipped). Long boundaries are scored on an evenly strided subset of 1024 edges.
//!    A winning plane is refitted by least squares to its inliers (jump `< delta`) if that
//!    scores no worse; a plane must be strictly better than the best constant. This
//!    generalises the paper's sampled values to sampled planes, so a hole in a tilted
//!    surface is filled with the surface, not a step. The fill is finally clamped to the
//!    range of the boundary values, so extrapolation can never create a spike.
//! 4. **Horizon margin.** The exact Euclidean distance transform of the scene mask
//!    (separable lower-envelope method of Felzenszwalb and Huttenlocher, exact and linear
//!    like Maurer et al. 2003; see [`edt`]) is thresholded at `µ` ([`PrepOptions::margin_px`],
//!    default 8 px): the sky pixels within `µ` of the scene form the margin. There,
//!    `laplace(S) = 0` is solved with `S = R` on the scene side and `S = Smax` on the sky
//!    side, from `S0 = Smax`, by Jacobi iterations restricted to the list of margin pixels
//!    (default `ceil(2 µ)` sweeps, the paper's "about 2µ iterations"). Only margin pixels
//!    change. The range therefore tapers from the data into the sky with no hard step.
//! 5. **Airlight** ([`estimate_airlight`]): the per-channel median of the linear colour of
//!    the sky pixels (the median ignores the sun, birds, wires and saturated leakage);
//!    without sky, a neutral grey (R = G = B) at the 99th percentile of the Rec. 709
//!    luminance of the known pixels, since no pixel then shows the colour of the light.
//!
//! **Randomness.** A built-in SplitMix64 generator; each hole gets its own stream derived
//! from [`PrepOptions::seed`] (default 0) and the index of its first pixel, so the output is
//! bit-identical for the same seed and input on every platform, and the fill of one hole
//! does not depend on the others.
//!
//! **Cost.** Everything is linear in the number of pixels (the RANSAC part is linear in
//! the boundary length with a constant of `2 x ransac_samples x` at most 1024), single
//! threaded. Working memory beyond input and output: 4 bytes per unknown pixel (component
//! lists), 2 bytes per pixel (the `sky` and `filled` masks) and 4 bytes per pixel of the
//! sky's bounding box (distance transform, after the component lists are freed).

mod airlight;
mod components;
pub mod edt;
mod fill;
mod margin;
mod sky;
pub mod synthetic;
mod vis;

use std::time::Instant;

use crate::raster::{Grid, ScalarMap};
use crate::{Error, Result};

pub use airlight::{estimate_airlight, AirlightEstimate, AirlightSource};
pub use vis::visualize;

/// Which components of unknown pixels are sky. A component is sky when it passes every
/// rule; of those, the `max_components` largest are kept. See the module docs.
#[derive(Clone, Debug, PartialEq)]
pub struct SkyRules {
    /// Minimum area, as a fraction of the image (default 0.01).
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

/// Largest accepted [`PrepOptions::margin_px`].
const MAX_MARGIN_PX: f64 = 65535.0;
/// Largest accepted [`PrepOptions::sky_range_factor`]: beyond it the whole scene is
/// squeezed into normalised range below 1/1000, where no haze shows.
const MAX_SKY_RANGE_FACTOR: f64 = 1000.0;

/// Options of [`prepare`]. The defaults are those documented on each field.
#[derive(Clone, Debug, PartialEq)]
pub struct PrepOptions {
    /// Sky detection rules.
    pub sky: SkyRules,
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
    /// Look for sky at all (default true); when false, every unknown component is a hole.
    pub detect_sky: bool,
}

impl Default for PrepOptions {
    fn default() -> Self {
        PrepOptions {
            sky: SkyRules::default(),
            margin_px: 8.0,
            jacobi_iterations: None,
            sky_range_factor: 1.5,
            ransac_samples: 32,
            seed: 0,
            detect_sky: true,
        }
    }
}

impl PrepOptions {
    /// Checks every field; an out-of-domain one gives [`Error::InvalidParameter`].
    pub fn validate(&self) -> Result<()> {
        check_fraction("min_area_fraction", self.sky.min_area_fraction)?;
        check_fraction("sky.min_top_fraction", self.sky.min_top_fraction)?;
        check_fraction("sky.min_bbox_fill", self.sky.min_bbox_fill)?;
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

/// What [`prepare`] found and did, and how long it took (serialised as is in the CLI's
/// JSON reports).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct PrepStats {
    /// Number of holes (non-sky components of unknown pixels) filled.
    pub holes: usize,
    /// Number of pixels in those holes.
    pub hole_pixels: usize,
    /// Number of sky components.
    pub sky_components: usize,
    /// Number of sky pixels (margin included).
    pub sky_pixels: usize,
    /// Number of sky pixels in the horizon margin (the ones the Jacobi iterations change).
    pub margin_pixels: usize,
    /// Maximum known range `Rmax`.
    pub r_max: f32,
    /// Sky range `Smax`, if there is sky.
    pub s_max: Option<f32>,
    /// Milliseconds spent labelling components and filling holes.
    pub fill_ms: f64,
    /// Milliseconds spent selecting and assigning the sky.
    pub sky_ms: f64,
    /// Milliseconds spent on the distance transform and the Jacobi iterations.
    pub margin_ms: f64,
    /// Milliseconds for the whole of [`prepare`].
    pub total_ms: f64,
}

/// The result of [`prepare`].
#[derive(Clone, Debug, PartialEq)]
pub struct Prepared {
    /// The range map, finite everywhere; known input values bit-identical.
    pub range: ScalarMap,
    /// Pixels that are sky (set to `Smax`, or relaxed in the margin).
    pub sky: Grid<bool>,
    /// Pixels that were holes and have been filled.
    pub filled: Grid<bool>,
    /// What was found and timings.
    pub stats: PrepStats,
}

/// Fills holes, detects sky and builds the horizon margin (see the module docs).
///
/// Unknown pixels are the non-finite ones. Errors: [`Error::InvalidParameter`] for bad
/// options, [`Error::Prep`] when the map has no known value at all (or, with sky, a
/// maximum known range that is not positive).
pub fn prepare(range: &ScalarMap, opts: &PrepOptions) -> Result<Prepared> {
    opts.validate()?;
    let t0 = Instant::now();
    let (w, h) = (range.width(), range.height());
    let mut work: Vec<f32> = range
        .as_slice()
        .iter()
        .map(|&v| if v.is_finite() { v } else { f32::NAN })
        .collect();
    let r_max = work
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(f32::NEG_INFINITY, f32::max);
    if r_max == f32::NEG_INFINITY {
        return Err(Error::Prep(format!(
            "no valid range value: all {} pixels ({w}x{h}) are unknown (NaN or infinite)",
            range.len()
        )));
    }
    let mut stats = PrepStats {
        r_max,
        ..PrepStats::default()
    };

    let comps = components::label_unknown(&mut work, w, h);
    let sky_ids = if opts.detect_sky {
        sky::select_sky(&comps, &opts.sky, w, h)
    } else {
        Vec::new()
    };
    let mut is_sky = vec![false; comps.list.len()];
    sky_ids.iter().for_each(|&i| is_sky[i] = true);

    let mut filled = vec![false; w * h];
    fill_holes(
        &mut work,
        &mut filled,
        w,
        h,
        &comps,
        &is_sky,
        opts,
        &mut stats,
    )?;
    let t1 = Instant::now();

    let mut sky = vec![false; w * h];
    let sky_bbox = assign_sky(&mut work, &mut sky, &comps, &sky_ids, opts, &mut stats)?;
    drop(comps);
    let t2 = Instant::now();

    if let Some(bbox) = sky_bbox {
        let margin = margin::margin_pixels(&sky, w, h, bbox, opts.margin_px as f32);
        margin::jacobi(&mut work, w, h, &margin, opts.jacobi_sweeps());
        stats.margin_pixels = margin.len();
    }
    let t3 = Instant::now();

    stats.fill_ms = ms(t1 - t0);
    stats.sky_ms = ms(t2 - t1);
    stats.margin_ms = ms(t3 - t2);
    stats.total_ms = ms(t3 - t0);
    Ok(Prepared {
        range: Grid::from_vec(w, h, work),
        sky: Grid::from_vec(w, h, sky),
        filled: Grid::from_vec(w, h, filled),
        stats,
    })
}

fn ms(d: std::time::Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// Fills every non-sky component of `comps` in `work` and marks it in `filled`.
#[allow(clippy::too_many_arguments)]
fn fill_holes(
    work: &mut [f32],
    filled: &mut [bool],
    w: usize,
    h: usize,
    comps: &components::Components,
    is_sky: &[bool],
    opts: &PrepOptions,
    stats: &mut PrepStats,
) -> Result<()> {
    let mut filler = fill::HoleFiller::default();
    for (c, _) in comps.list.iter().zip(is_sky).filter(|(_, &s)| !s) {
        let pixels = comps.pixels_of(c);
        let mut rng = crate::rng::SplitMix64::for_stream(opts.seed, pixels[0] as u64);
        filler.fill(work, w, h, pixels, opts.ransac_samples, &mut rng)?;
        pixels.iter().for_each(|&p| filled[p as usize] = true);
        stats.holes += 1;
        stats.hole_pixels += pixels.len();
    }
    Ok(())
}

/// Sets the sky components to `Smax` and marks them; returns the union of their bounding
/// boxes, or `None` without sky.
fn assign_sky(
    work: &mut [f32],
    sky: &mut [bool],
    comps: &components::Components,
    sky_ids: &[usize],
    opts: &PrepOptions,
    stats: &mut PrepStats,
) -> Result<Option<[usize; 4]>> {
    if sky_ids.is_empty() {
        return Ok(None);
    }
    if stats.r_max <= 0.0 {
        return Err(Error::Prep(format!(
            "the maximum known range is {} but the sky range Smax = factor x Rmax needs Rmax > 0",
            stats.r_max
        )));
    }
    let s_max = (opts.sky_range_factor * f64::from(stats.r_max)) as f32;
    let mut bbox = [usize::MAX, usize::MAX, 0, 0];
    for &i in sky_ids {
        let c = &comps.list[i];
        for &p in comps.pixels_of(c) {
            work[p as usize] = s_max;
            sky[p as usize] = true;
        }
        bbox = [
            bbox[0].min(c.bbox[0]),
            bbox[1].min(c.bbox[1]),
            bbox[2].max(c.bbox[2]),
            bbox[3].max(c.bbox[3]),
        ];
        stats.sky_pixels += c.len;
    }
    stats.sky_components = sky_ids.len();
    stats.s_max = Some(s_max);
    Ok(Some(bbox))
}
