//! Atmospheric turbidity of a fisheye sky image, by matching its luminance distribution
//! with Preetham skies (paper 002, sec. 3.4, eq. 8).
//!
//! # Method
//!
//! 1. **Sun.** Given as angles, or found as the centroid of the largest 8-connected blob
//!    of near-maximal pixels (largest channel ≥ [`NEAR_MAX`] × the image's largest value:
//!    the saturated sun of a photograph, or a drawn sun disc). The centroid is the mean
//!    of the blob's unit direction vectors, converted back to (θs, φs): the mean of image
//!    positions would be pulled toward the centre by the fisheye's distortion.
//! 2. **Usable pixels.** Inside the horizon circle, at most 90° − `horizon_margin` from
//!    the zenith (default 10°: obstacles, haze layers and the model's worst fit lie at
//!    the horizon), at least `sun_exclusion` from the sun (default 10°: glare and the
//!    sun's own disc, which the model does not describe), not near-maximal (clipped) and
//!    not black.
//! 3. **Reference.** The zenith by default, or any direction; its luminance Y_ref is the
//!    mean over the usable pixels within [`REFERENCE_RADIUS_PX`] (4 px) of it, and the
//!    model side of the ratio is the mean of F over the same pixels: averaging both
//!    sides keeps the ratio exact while lowering the noise of a single reference pixel,
//!    and over a patch wide enough to span several 8-bit codes, its quantisation error.
//!    Patch pixels whose Y/F is more than 3 robust standard deviations (and 1 %) from
//!    the patch's median are left out: the edge of a cloud across the reference.
//! 4. **Samples.** N distinct usable pixels drawn uniformly by a seeded SplitMix64, one
//!    stream per repetition, so a seed fixes every result.
//! 5. **Ratios** (eq. 6, 8): observed q_i = Y_i/Y_ref, with Y the luminance of linear
//!    RGB in the image's own primaries (`luminance`: Rec. 709's weights for sRGB, the
//!    profile's for a Display P3 or Adobe RGB photo); model m_i(T) = F(θi, γi; T)/F(θref, γref; T): Y_z cancels, so only the
//!    Perez luminance function is needed.
//! 6. **RANSAC** against clouds (brighter and greyer than any clear sky) and other
//!    outliers. A hypothesis is a minimal subset: one sample, whose single equation
//!    m_i(T) = q_i is solved for T in [1, 20] (every root: the sign changes on a grid of
//!    step 0.5, interpolated linearly, which is close enough to sort inliers; step 7
//!    makes T exact). Its inliers are the samples whose relative residual
//!    |m_k(T)/q_k − 1| is below `threshold` (default 3 %). Half of the hypotheses use the
//!    configured reference; the other half use a random sample as the reference, so that
//!    a reference under a cloud is noticed: the configured reference is kept unless the
//!    best hypothesis with it has fewer than 90 % of the inliers of the best one without
//!    it, in which case that sample becomes the reference (`reference_fallback`).
//! 7. **Refinement.** T minimises Σ (m_i(T) − q_i)² over the inliers (eq. 8's terms,
//!    squared) by Levenberg-Marquardt in one parameter, within [1, 20], from the RANSAC
//!    hypothesis; if it does not converge, a grid scan and golden-section search bracket
//!    the minimum instead. The inliers are then re-selected with a threshold of 3 robust
//!    standard deviations (1.4826 × the median absolute relative residual), kept within
//!    [0.1 %, `threshold`], and T refitted, until the inlier set is stable.
//!
//! Why squares and not eq. 8's L1 sum: the L1 norm is there for robustness against
//! cloud pixels, which RANSAC and the re-selection already remove; on the remaining clear
//! pixels the squared cost is smooth, so Levenberg-Marquardt converges in a few steps,
//! and it is the maximum-likelihood fit for Gaussian pixel noise. Its curvature also
//! gives the fit's standard error σ_T = √(s²/Σ J²), s² = cost/(n − 1), J = dm/dT.
//!
//! With `fit_level`, the model ratios get a free level s, fitted with T: Σ (s·m_i(T) −
//! q_i)², s eliminated in closed form for each T (variable projection), so the search is
//! still over T alone. The reference then only sets the units: an error common to all
//! ratios (the reference pixels' noise or 8-bit quantisation, which is the same for
//! neighbouring pixels of one code, or thin cloud over it) moves s instead of T. Eq. 8
//! as written (s = 1) is the default.
//!
//! Repeated estimations (`repeats`, each with its own N samples) give the mean and the
//! sample standard deviation that paper 002's Table 1 reports.

mod fit;
mod pixels;
#[cfg(test)]
mod tests;

pub use pixels::find_sun;

use fit::{grid_t, Fit, GRID_STEPS};
use pixels::{check_square, draw_distinct, image_max, is_usable, median, reference_patch};

use super::fisheye::Fisheye;
use super::preetham::{
    self, angle_between, check_sun, secant, Perez, MAX_TURBIDITY, MIN_TURBIDITY,
};
use crate::error::{Error, Result};
use crate::raster::RgbImage;
use crate::rng::SplitMix64;
use std::collections::{HashSet, VecDeque};
use std::f64::consts::FRAC_PI_2;
use std::time::Instant;

/// Default number N of sample points per estimation (paper 002, sec. 7.1).
pub const DEFAULT_SAMPLES: usize = 100;
/// Default number of repeated estimations.
pub const DEFAULT_REPEATS: usize = 10;
/// The most estimations a caller asks of one image (`brume turbidity --repeats`, Python's
/// `repeats`): 10,000 take about 4 s at 100 points each.
pub const MAX_REPEATS: usize = 10_000;
/// Default margin above the horizon where no sample is taken, degrees.
pub const DEFAULT_HORIZON_MARGIN_DEG: f64 = 10.0;
/// Default angular radius around the sun where no sample is taken, degrees.
pub const DEFAULT_SUN_EXCLUSION_DEG: f64 = 10.0;
/// Default RANSAC inlier threshold on the relative residual of a ratio.
pub const DEFAULT_THRESHOLD: f64 = 0.03;
/// Default number of RANSAC hypotheses per estimation.
pub const DEFAULT_HYPOTHESES: usize = 64;
/// A pixel is near-maximal (clipped, or the sun) when its largest channel is at least
/// this fraction of the image's largest channel value.
pub const NEAR_MAX: f64 = 0.98;
/// Radius of the reference patch, px.
pub const REFERENCE_RADIUS_PX: f64 = 4.0;
/// Floor of the re-selection threshold: residuals below it are never called outliers.
const MIN_THRESHOLD: f64 = 1e-3;
/// Floor of the threshold that leaves pixels out of the reference patch: above the
/// error of 8-bit quantisation (about 0.5 % in linear light at mid-grey), so that pixels
/// of neighbouring codes, whose mean is what the patch is for, stay in.
const PATCH_MIN_THRESHOLD: f64 = 0.01;
/// The configured reference is kept while its best hypothesis has this fraction of the
/// inliers of the best hypothesis overall.
const KEEP_REFERENCE: f64 = 0.9;

/// What [`TurbidityEstimator`] does (see the module docs for each step).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TurbidityOptions {
    /// How the image maps to directions.
    pub fisheye: Fisheye,
    /// Sun (zenith, azimuth) in radians, in the fisheye's azimuth convention; `None`:
    /// found from the saturated area.
    pub sun: Option<[f64; 2]>,
    /// Reference direction (zenith, azimuth) in radians; `None`: the zenith.
    pub reference: Option<[f64; 2]>,
    /// Sample points N per estimation, ≥ 5.
    pub samples: usize,
    /// Repeated estimations, ≥ 1.
    pub repeats: usize,
    /// Seed of the sampling.
    pub seed: u64,
    /// No sample closer than this to the horizon, radians, in [0, π/2).
    pub horizon_margin: f64,
    /// No sample closer than this to the sun, radians, in [0, π/2).
    pub sun_exclusion: f64,
    /// RANSAC inlier threshold on |m_i(T)/q_i − 1|, in (0, 1).
    pub threshold: f64,
    /// RANSAC hypotheses per estimation, ≥ 2.
    pub hypotheses: usize,
    /// Fit the level of the ratios: minimise Σ (s·m_i(T) − q_i)² with s eliminated in
    /// closed form (variable projection) instead of eq. 8's s = 1. Noise, 8-bit
    /// quantisation or haze in the reference pixels then scale s instead of biasing T.
    /// Off by default: eq. 8 as written.
    pub fit_level: bool,
    /// The luminance Y of a pixel as weights of its linear R, G, B: the Y row of the
    /// image's RGB-to-XYZ matrix ([`crate::io::colour_profile::ColourProfile::luminance_weights`]).
    /// Default Rec. 709's, for sRGB primaries; a Display P3 sky read with them would
    /// take its blue for darker than it is (T 10 estimated as 10.12).
    pub luminance: [f64; 3],
}

impl Default for TurbidityOptions {
    fn default() -> Self {
        TurbidityOptions {
            fisheye: Fisheye::default(),
            sun: None,
            reference: None,
            samples: DEFAULT_SAMPLES,
            repeats: DEFAULT_REPEATS,
            seed: 0,
            horizon_margin: DEFAULT_HORIZON_MARGIN_DEG.to_radians(),
            sun_exclusion: DEFAULT_SUN_EXCLUSION_DEG.to_radians(),
            threshold: DEFAULT_THRESHOLD,
            hypotheses: DEFAULT_HYPOTHESES,
            fit_level: false,
            luminance: super::REC709_LUMINANCE,
        }
    }
}

impl TurbidityOptions {
    /// Refuses, naming the field, any option outside its domain.
    pub fn validate(&self) -> Result<()> {
        if let Some([z, a]) = self.sun {
            check_sun(z, a)?;
        }
        if let Some([z, a]) = self.reference {
            if !(z.is_finite() && (0.0..FRAC_PI_2).contains(&z)) {
                return Err(Error::invalid(
                    "reference_zenith",
                    format!("{}°", z.to_degrees()),
                    "a zenith angle in [0°, 90°)",
                ));
            }
            if !a.is_finite() {
                return Err(Error::invalid("reference_azimuth", a, "a finite azimuth"));
            }
        }
        if self.samples < 5 {
            return Err(Error::invalid(
                "samples",
                self.samples,
                "at least 5 sample points",
            ));
        }
        if self.repeats == 0 {
            return Err(Error::invalid("repeats", 0, "at least 1 estimation"));
        }
        for (name, v) in [
            ("horizon_margin", self.horizon_margin),
            ("sun_exclusion", self.sun_exclusion),
        ] {
            if !(v.is_finite() && (0.0..FRAC_PI_2).contains(&v)) {
                return Err(Error::invalid(
                    name,
                    format!("{}°", v.to_degrees()),
                    "an angle in [0°, 90°)",
                ));
            }
        }
        if !(self.threshold.is_finite() && self.threshold > 0.0 && self.threshold < 1.0) {
            return Err(Error::invalid(
                "threshold",
                self.threshold,
                "a relative residual in (0, 1), e.g. 0.03",
            ));
        }
        if self.hypotheses < 2 {
            return Err(Error::invalid("hypotheses", self.hypotheses, "at least 2"));
        }
        let w = self.luminance;
        if !(w.iter().all(|v| v.is_finite() && *v >= 0.0) && w.iter().sum::<f64>() > 0.0) {
            return Err(Error::invalid(
                "luminance",
                format!("{w:?}"),
                "weights of R, G, B ≥ 0, not all 0 (the Y row of the image's RGB to XYZ)",
            ));
        }
        Ok(())
    }
}

/// Where the sun position came from.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[serde(rename_all = "lowercase", tag = "kind")]
pub enum SunSource {
    /// Given by the caller.
    Given,
    /// Found as the centroid of the largest near-maximal blob of this many pixels.
    Detected {
        /// Pixels of the blob.
        pixels: usize,
    },
}

impl SunSource {
    /// `given` or `detected`, as reports say it.
    pub fn name(&self) -> &'static str {
        match self {
            SunSource::Given => "given",
            SunSource::Detected { .. } => "detected",
        }
    }
}

/// The sun found in an image by [`find_sun`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct SunDetection {
    /// Zenith angle, radians.
    pub zenith: f64,
    /// Azimuth, radians, in the fisheye's convention.
    pub azimuth: f64,
    /// Pixels of the blob.
    pub pixels: usize,
}

/// One estimation from N samples.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SingleEstimate {
    /// The turbidity T.
    pub turbidity: f64,
    /// Its standard error from the fit's curvature.
    pub fit_std: f64,
    /// Samples kept as clear sky.
    pub inliers: usize,
    /// Samples drawn (N).
    pub samples: usize,
    /// RMS of the inliers' relative residuals m_i(T)/q_i − 1.
    pub rms: f64,
    /// The reference used, (zenith, azimuth) in radians.
    pub reference: [f64; 2],
    /// True when the configured reference was voted out (a cloud over it) and a sample
    /// served instead.
    pub reference_fallback: bool,
    /// The level s of the model ratios: 1, or fitted with `fit_level` (how far the
    /// reference's luminance is from what the clear-sky fit expects).
    pub level: f64,
    /// Wall-clock time of this estimation, ms.
    pub ms: f64,
}

/// The result of [`estimate_turbidity`]: `repeats` estimations and their statistics.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TurbidityEstimate {
    /// Mean T over the repeated estimations.
    pub turbidity: f64,
    /// Sample standard deviation of T over the repetitions; with one estimation, its
    /// fit's standard error.
    pub std: f64,
    /// Mean of the fits' standard errors.
    pub fit_std: f64,
    /// Estimations made.
    pub repeats: usize,
    /// Sample points per estimation.
    pub samples: usize,
    /// Mean number of inliers per estimation.
    pub inliers: f64,
    /// Mean level s of the model ratios (1 unless `fit_level`).
    pub level: f64,
    /// Sun zenith angle used, radians.
    pub sun_zenith: f64,
    /// Sun azimuth used, radians.
    pub sun_azimuth: f64,
    /// Where the sun came from.
    pub sun_source: SunSource,
    /// Configured reference (zenith, azimuth), radians.
    pub reference: [f64; 2],
    /// Estimations in which the configured reference was replaced.
    pub reference_fallbacks: usize,
    /// Pixels that could be drawn as samples.
    pub usable_pixels: usize,
    /// Mean time per estimation, ms (not counting the image's one-off preparation).
    pub ms_per_estimation: f64,
    /// Time of the preparation (sun detection, usable pixels), ms.
    pub prepare_ms: f64,
    /// Every estimation.
    pub estimates: Vec<SingleEstimate>,
}

/// Estimates the turbidity of `image` (a square linear-RGB fisheye sky image) as the
/// module docs describe. `name` stands for the image in error messages (its file name).
pub fn estimate_turbidity(
    image: &RgbImage,
    name: &str,
    opts: &TurbidityOptions,
) -> Result<TurbidityEstimate> {
    TurbidityEstimator::new(image, name, opts)?.run()
}

/// The parts of a direction that the Perez function needs, computed once per pixel.
#[derive(Clone, Copy, Debug)]
struct Geom {
    sec: f64,
    gamma: f64,
    cos2: f64,
}

impl Geom {
    fn new(theta: f64, phi: f64, sun: [f64; 2]) -> Self {
        let gamma = angle_between(theta, phi, sun[0], sun[1]);
        Geom {
            sec: secant(theta),
            gamma,
            cos2: gamma.cos().powi(2),
        }
    }

    fn f(&self, p: &Perez) -> f64 {
        p.eval_parts(self.sec, self.gamma, self.cos2)
    }

    fn f_d(&self, p: &Perez, slopes: &Perez) -> (f64, f64) {
        p.eval_parts_with_derivative(slopes, self.sec, self.gamma, self.cos2)
    }
}

/// A usable pixel: its geometry, luminance and direction.
#[derive(Clone, Copy, Debug)]
struct Usable {
    geom: Geom,
    y: f64,
    dir: [f64; 2],
}

/// An image prepared for repeated estimations: the sun, the usable pixels and the
/// reference patch, found once.
#[derive(Clone, Debug)]
pub struct TurbidityEstimator {
    opts: TurbidityOptions,
    name: String,
    sun: [f64; 2],
    sun_source: SunSource,
    usable: Vec<Usable>,
    reference: [f64; 2],
    ref_patch: Vec<Geom>,
    ref_y: f64,
    /// Mean F of the patch at each T of the root-finding grid, computed once.
    patch_grid: Vec<f64>,
    prepare_ms: f64,
}

/// The reference of one hypothesis: the configured patch or one of the samples.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Ref {
    Patch,
    Sample(usize),
}

/// A RANSAC hypothesis and its score.
#[derive(Clone, Debug)]
struct Hypothesis {
    reference: Ref,
    t: f64,
    inliers: Vec<usize>,
    spread: f64,
}

impl Hypothesis {
    fn better_than(&self, other: &Option<Hypothesis>) -> bool {
        match other {
            None => true,
            Some(o) => {
                self.inliers.len() > o.inliers.len()
                    || (self.inliers.len() == o.inliers.len() && self.spread < o.spread)
            }
        }
    }
}

impl TurbidityEstimator {
    /// Checks the options and the image (square, with enough usable sky pixels), finds
    /// the sun if it is not given, and lists the usable pixels. Errors name the option,
    /// or the image by `name`.
    pub fn new(image: &RgbImage, name: &str, opts: &TurbidityOptions) -> Result<Self> {
        let start = Instant::now();
        opts.validate()?;
        let size = check_square(image, name)?;
        let fisheye = &opts.fisheye;
        let max = image_max(image, fisheye)?;
        if max <= 0.0 {
            return Err(Error::format(
                name,
                "no sky pixels: every pixel inside the fisheye circle is black",
            ));
        }
        let (sun, sun_source) = match opts.sun {
            Some(s) => (s, SunSource::Given),
            None => {
                let d = find_sun(image, name, fisheye)?;
                (
                    [d.zenith, d.azimuth],
                    SunSource::Detected { pixels: d.pixels },
                )
            }
        };
        let clip = NEAR_MAX * max;
        let max_zenith = FRAC_PI_2 - opts.horizon_margin;
        let mut usable = Vec::new();
        for y in 0..size {
            for x in 0..size {
                let Some((theta, phi)) = fisheye.pixel_direction(size, x, y) else {
                    continue;
                };
                let rgb = *image.get(x, y);
                let lum = super::weighted_luminance(opts.luminance, rgb);
                if theta > max_zenith || !is_usable(rgb, lum, clip) {
                    continue;
                }
                let geom = Geom::new(theta, phi, sun);
                if geom.gamma < opts.sun_exclusion {
                    continue;
                }
                usable.push(Usable {
                    geom,
                    y: lum,
                    dir: [theta, phi],
                });
            }
        }
        if usable.len() < opts.samples {
            return Err(Error::invalid(
                "samples",
                opts.samples,
                format!(
                    "at most the {} usable sky pixels of {name} (inside the circle, ≥ {:.1}° \
                     above the horizon, ≥ {:.1}° from the sun, not clipped, not black)",
                    usable.len(),
                    opts.horizon_margin.to_degrees(),
                    opts.sun_exclusion.to_degrees(),
                ),
            ));
        }
        let reference = opts.reference.unwrap_or([0.0, 0.0]);
        let (ref_patch, ref_y) =
            reference_patch(image, fisheye, reference, sun, clip, opts.luminance).ok_or_else(
                || {
                    Error::format(
                        name,
                        format!(
                            "the reference point (zenith {:.1}°, azimuth {:.1}°) has no usable \
                         pixel within {REFERENCE_RADIUS_PX} px (clipped or black): choose \
                         another with `reference_zenith`/`reference_azimuth`",
                            reference[0].to_degrees(),
                            reference[1].to_degrees()
                        ),
                    )
                },
            )?;
        let patch_grid = (0..=GRID_STEPS)
            .map(|k| {
                let p = Perez::luminance(grid_t(k));
                ref_patch.iter().map(|g| g.f(&p)).sum::<f64>() / ref_patch.len() as f64
            })
            .collect();
        Ok(TurbidityEstimator {
            opts: opts.clone(),
            name: name.to_string(),
            sun,
            sun_source,
            usable,
            reference,
            ref_patch,
            ref_y,
            patch_grid,
            prepare_ms: start.elapsed().as_secs_f64() * 1e3,
        })
    }

    /// The sun position used (zenith, azimuth), radians.
    pub fn sun(&self) -> [f64; 2] {
        self.sun
    }

    /// Number of pixels samples are drawn from.
    pub fn usable_pixels(&self) -> usize {
        self.usable.len()
    }

    /// All `repeats` estimations and their statistics.
    pub fn run(&self) -> Result<TurbidityEstimate> {
        let estimates = (0..self.opts.repeats)
            .map(|k| self.estimate_once(k as u64))
            .collect::<Result<Vec<_>>>()?;
        let n = estimates.len() as f64;
        let mean = |f: &dyn Fn(&SingleEstimate) -> f64| estimates.iter().map(f).sum::<f64>() / n;
        let turbidity = mean(&|e| e.turbidity);
        let fit_std = mean(&|e| e.fit_std);
        let std = if estimates.len() > 1 {
            (estimates
                .iter()
                .map(|e| (e.turbidity - turbidity).powi(2))
                .sum::<f64>()
                / (n - 1.0))
                .sqrt()
        } else {
            fit_std
        };
        Ok(TurbidityEstimate {
            turbidity,
            std,
            fit_std,
            repeats: estimates.len(),
            samples: self.opts.samples,
            inliers: mean(&|e| e.inliers as f64),
            level: mean(&|e| e.level),
            sun_zenith: self.sun[0],
            sun_azimuth: self.sun[1],
            sun_source: self.sun_source,
            reference: self.reference,
            reference_fallbacks: estimates.iter().filter(|e| e.reference_fallback).count(),
            usable_pixels: self.usable.len(),
            ms_per_estimation: mean(&|e| e.ms),
            prepare_ms: self.prepare_ms,
            estimates,
        })
    }

    /// Estimation number `k`: N samples from stream `k` of the seed, RANSAC, refinement.
    pub fn estimate_once(&self, k: u64) -> Result<SingleEstimate> {
        let start = Instant::now();
        let mut rng = SplitMix64::for_stream(self.opts.seed, k);
        let samples = draw_distinct(&mut rng, self.usable.len(), self.opts.samples);
        let pts: Vec<Usable> = samples.iter().map(|&i| self.usable[i]).collect();
        let fit = Fit {
            pts: &pts,
            patch: &self.ref_patch,
            patch_y: self.ref_y,
            patch_grid: &self.patch_grid,
            free_level: self.opts.fit_level,
        };
        let n = pts.len();

        // RANSAC: even hypotheses use the configured reference, odd ones a random sample.
        let (mut best_patch, mut best_sample): (Option<Hypothesis>, Option<Hypothesis>) =
            (None, None);
        for h in 0..self.opts.hypotheses {
            let reference = if h % 2 == 0 {
                Ref::Patch
            } else {
                Ref::Sample(rng.below(n))
            };
            let i = loop {
                let i = rng.below(n);
                if Ref::Sample(i) != reference {
                    break i;
                }
            };
            for t in fit.solve_one(i, reference) {
                let (inliers, spread) = fit.inliers(t, reference, self.opts.threshold);
                let hyp = Hypothesis {
                    reference,
                    t,
                    inliers,
                    spread,
                };
                let slot = if reference == Ref::Patch {
                    &mut best_patch
                } else {
                    &mut best_sample
                };
                if hyp.better_than(slot) {
                    *slot = Some(hyp);
                }
            }
        }
        let count = |h: &Option<Hypothesis>| h.as_ref().map_or(0, |h| h.inliers.len());
        let most = count(&best_patch).max(count(&best_sample));
        let best = if count(&best_patch) as f64 >= KEEP_REFERENCE * count(&best_sample) as f64 {
            best_patch
        } else {
            best_sample
        };
        let min_inliers = (n / 5).max(3);
        let Some(best) = best.filter(|b| b.inliers.len() >= min_inliers) else {
            return Err(self.no_fit(most, n));
        };

        // Refinement: fit on the inliers, re-select them by their robust spread, refit.
        let reference = best.reference;
        let mut inliers = best.inliers;
        let mut t = best.t;
        let mut result = fit.least_squares(&inliers, reference, t);
        for _ in 0..8 {
            t = result.t;
            let residuals = fit.relative_residuals(t, reference, result.level);
            let mut abs: Vec<f64> = inliers.iter().map(|&i| residuals[i].abs()).collect();
            let sigma = 1.4826 * median(&mut abs);
            let threshold = (3.0 * sigma).clamp(MIN_THRESHOLD, self.opts.threshold);
            let next: Vec<usize> = (0..n)
                .filter(|&i| Ref::Sample(i) != reference && residuals[i].abs() < threshold)
                .collect();
            if next.len() < min_inliers {
                break;
            }
            if next == inliers {
                break;
            }
            inliers = next;
            result = fit.least_squares(&inliers, reference, t);
        }
        let residuals = fit.relative_residuals(result.t, reference, result.level);
        let rms = (inliers.iter().map(|&i| residuals[i].powi(2)).sum::<f64>()
            / inliers.len() as f64)
            .sqrt();
        Ok(SingleEstimate {
            turbidity: result.t,
            fit_std: result.std,
            inliers: inliers.len(),
            samples: n,
            rms,
            reference: match reference {
                Ref::Patch => self.reference,
                Ref::Sample(j) => pts[j].dir,
            },
            reference_fallback: reference != Ref::Patch,
            level: result.level,
            ms: start.elapsed().as_secs_f64() * 1e3,
        })
    }

    fn no_fit(&self, inliers: usize, n: usize) -> Error {
        Error::format(
            &self.name,
            format!(
                "no clear-sky fit: at most {inliers} of {n} samples agree with any Preetham sky \
                 of T in [1, 20] (overcast, not a sky image, or the fisheye convention or the \
                 sun position is wrong)"
            ),
        )
    }
}
