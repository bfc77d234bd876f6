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
//! 5. **Ratios** (eq. 6, 8): observed q_i = Y_i/Y_ref, with Y the Rec. 709 luminance of
//!    linear RGB; model m_i(T) = F(θi, γi; T)/F(θref, γref; T): Y_z cancels, so only the
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
                let lum = super::luminance(rgb);
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
            return Err(Error::format(
                name,
                format!(
                    "only {} usable sky pixels (inside the circle, ≥ {:.1}° above the \
                     horizon, ≥ {:.1}° from the sun, not clipped, not black); --samples {} \
                     needs at least as many",
                    usable.len(),
                    opts.horizon_margin.to_degrees(),
                    opts.sun_exclusion.to_degrees(),
                    opts.samples
                ),
            ));
        }
        let reference = opts.reference.unwrap_or([0.0, 0.0]);
        let (ref_patch, ref_y) =
            reference_patch(image, fisheye, reference, sun, clip).ok_or_else(|| {
                Error::format(
                    name,
                    format!(
                        "the reference point (zenith {:.1}°, azimuth {:.1}°) has no usable \
                         pixel within {REFERENCE_RADIUS_PX} px (clipped or black): choose \
                         another with --reference-zenith/--reference-azimuth",
                        reference[0].to_degrees(),
                        reference[1].to_degrees()
                    ),
                )
            })?;
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

/// The samples of one estimation and the reference patch: the ratios, residuals and fits.
struct Fit<'a> {
    pts: &'a [Usable],
    patch: &'a [Geom],
    patch_y: f64,
    /// The patch's mean F at the root-finding grid's T values ([`grid_t`]).
    patch_grid: &'a [f64],
    /// Fit the level s of the model ratios instead of fixing it to 1.
    free_level: bool,
}

/// A least-squares fit of T.
struct LeastSquares {
    t: f64,
    std: f64,
    /// The level s of the model ratios (1 unless fitted).
    level: f64,
}

impl Fit<'_> {
    /// F of the reference and its T-derivative.
    fn ref_f_d(&self, p: &Perez, slopes: &Perez, reference: Ref) -> (f64, f64) {
        match reference {
            Ref::Patch => {
                let (mut f, mut d) = (0.0, 0.0);
                for g in self.patch {
                    let (a, b) = g.f_d(p, slopes);
                    f += a;
                    d += b;
                }
                let n = self.patch.len() as f64;
                (f / n, d / n)
            }
            Ref::Sample(j) => self.pts[j].geom.f_d(p, slopes),
        }
    }

    fn ref_f(&self, p: &Perez, reference: Ref) -> f64 {
        match reference {
            Ref::Patch => self.patch.iter().map(|g| g.f(p)).sum::<f64>() / self.patch.len() as f64,
            Ref::Sample(j) => self.pts[j].geom.f(p),
        }
    }

    fn ref_y(&self, reference: Ref) -> f64 {
        match reference {
            Ref::Patch => self.patch_y,
            Ref::Sample(j) => self.pts[j].y,
        }
    }

    /// The observed ratio q_i.
    fn q(&self, i: usize, reference: Ref) -> f64 {
        self.pts[i].y / self.ref_y(reference)
    }

    /// Every T in [1, 20] where m_i(T) = q_i, approximately: the sign changes of
    /// m_i(T) − q_i on the grid of [`grid_t`], each root interpolated linearly in its
    /// interval. A hypothesis only has to be close enough to sort inliers from clouds
    /// (a relative error in T of 10⁻³ moves the ratios far less than the 3 % threshold);
    /// the refinement then fits T exactly, and the grid needs no evaluation of the
    /// reference patch off its precomputed values.
    fn solve_one(&self, i: usize, reference: Ref) -> Vec<f64> {
        let q = self.q(i, reference);
        let g = |k: usize| {
            let p = Perez::luminance(grid_t(k));
            let fr = match reference {
                Ref::Patch => self.patch_grid[k],
                Ref::Sample(j) => self.pts[j].geom.f(&p),
            };
            self.pts[i].geom.f(&p) / fr - q
        };
        let mut roots = Vec::new();
        let mut ga = g(0);
        if ga == 0.0 {
            roots.push(grid_t(0));
        }
        for k in 1..=GRID_STEPS {
            let gb = g(k);
            if gb == 0.0 {
                roots.push(grid_t(k));
            } else if ga * gb < 0.0 {
                let (a, b) = (grid_t(k - 1), grid_t(k));
                roots.push(a + (b - a) * ga / (ga - gb));
            }
            ga = gb;
        }
        roots
    }

    /// Relative residuals s·m_k(T)/q_k − 1 of every sample (0 for the reference sample).
    fn relative_residuals(&self, t: f64, reference: Ref, level: f64) -> Vec<f64> {
        let p = Perez::luminance(t);
        let fr = self.ref_f(&p, reference);
        let yr = self.ref_y(reference);
        self.pts
            .iter()
            .enumerate()
            .map(|(k, s)| {
                if Ref::Sample(k) == reference {
                    0.0
                } else {
                    level * (s.geom.f(&p) / fr) / (s.y / yr) - 1.0
                }
            })
            .collect()
    }

    /// The inliers of hypothesis T and the sum of their |relative residuals|.
    fn inliers(&self, t: f64, reference: Ref, threshold: f64) -> (Vec<usize>, f64) {
        let residuals = self.relative_residuals(t, reference, 1.0);
        let mut spread = 0.0;
        let inliers = (0..self.pts.len())
            .filter(|&k| Ref::Sample(k) != reference && residuals[k].abs() < threshold)
            .inspect(|&k| spread += residuals[k].abs())
            .collect();
        (inliers, spread)
    }

    /// Σ (s·m_i(T) − q_i)² over `set`, its gradient part Σ J r, curvature Σ J², and the
    /// level s: 1, or with `free_level` the least-squares s(T) = Σ m q / Σ m² (variable
    /// projection: s is eliminated, T stays the only parameter, and J includes ds/dT).
    fn cost(&self, set: &[usize], reference: Ref, t: f64) -> (f64, f64, f64, f64) {
        let p = Perez::luminance(t);
        let slopes = Perez::luminance_slopes();
        let (fr, dfr) = self.ref_f_d(&p, &slopes, reference);
        let yr = self.ref_y(reference);
        let mq: Vec<(f64, f64, f64)> = set
            .iter()
            .map(|&i| {
                let (f, df) = self.pts[i].geom.f_d(&p, &slopes);
                (f / fr, (df * fr - f * dfr) / (fr * fr), self.pts[i].y / yr)
            })
            .collect();
        let (level, dlevel) = if self.free_level {
            let (mut mq_sum, mut mm, mut dmq, mut mdm) = (0.0, 0.0, 0.0, 0.0);
            for &(m, dm, q) in &mq {
                mq_sum += m * q;
                mm += m * m;
                dmq += dm * q;
                mdm += m * dm;
            }
            let level = mq_sum / mm;
            (level, (dmq * mm - mq_sum * 2.0 * mdm) / (mm * mm))
        } else {
            (1.0, 0.0)
        };
        let (mut cost, mut jr, mut jj) = (0.0, 0.0, 0.0);
        for &(m, dm, q) in &mq {
            let r = level * m - q;
            let j = level * dm + dlevel * m;
            cost += r * r;
            jr += j * r;
            jj += j * j;
        }
        (cost, jr, jj, level)
    }

    /// Levenberg-Marquardt on T from `t0`, within [1, 20]; a bracketing search instead
    /// when it does not converge.
    fn least_squares(&self, set: &[usize], reference: Ref, t0: f64) -> LeastSquares {
        let clamp = |t: f64| t.clamp(MIN_TURBIDITY, MAX_TURBIDITY);
        let mut t = clamp(t0);
        let (mut cost, mut jr, mut jj, mut level) = self.cost(set, reference, t);
        let mut lambda = 1e-3;
        let mut converged = false;
        for _ in 0..100 {
            if jj <= 0.0 {
                break;
            }
            let tn = clamp(t - jr / (jj * (1.0 + lambda)));
            let (cn, jrn, jjn, ln) = self.cost(set, reference, tn);
            if cn <= cost {
                let step = (tn - t).abs();
                (t, cost, jr, jj, level) = (tn, cn, jrn, jjn, ln);
                lambda = (lambda * 0.1).max(1e-12);
                if step <= 1e-10 * t {
                    converged = true;
                    break;
                }
            } else {
                lambda *= 10.0;
                if lambda > 1e8 {
                    // No decrease along the gradient: a minimum (or a bound) is reached.
                    converged = true;
                    break;
                }
            }
        }
        if !converged {
            t = self.bracket(set, reference);
            (cost, _, jj, level) = self.cost(set, reference, t);
        }
        let free = if self.free_level { 2.0 } else { 1.0 };
        let dof = (set.len() as f64 - free).max(1.0);
        let std = if jj > 0.0 {
            (cost / dof / jj).sqrt()
        } else {
            f64::INFINITY
        };
        LeastSquares { t, std, level }
    }

    /// The global minimum of the cost on [1, 20]: a grid scan, then golden-section
    /// search between the neighbours of the best grid point.
    fn bracket(&self, set: &[usize], reference: Ref) -> f64 {
        let cost = |t: f64| self.cost(set, reference, t).0;
        let step = 0.25;
        let n = ((MAX_TURBIDITY - MIN_TURBIDITY) / step).round() as usize;
        let at = |k: usize| MIN_TURBIDITY + step * k as f64;
        let best = (0..=n)
            .min_by(|&a, &b| cost(at(a)).total_cmp(&cost(at(b))))
            .unwrap_or(0);
        let (mut lo, mut hi) = (at(best.saturating_sub(1)), at((best + 1).min(n)));
        let phi = (5f64.sqrt() - 1.0) / 2.0;
        let (mut c, mut d) = (hi - phi * (hi - lo), lo + phi * (hi - lo));
        let (mut fc, mut fd) = (cost(c), cost(d));
        while hi - lo > 1e-9 {
            if fc < fd {
                (hi, d, fd) = (d, c, fc);
                c = hi - phi * (hi - lo);
                fc = cost(c);
            } else {
                (lo, c, fc) = (c, d, fd);
                d = lo + phi * (hi - lo);
                fd = cost(d);
            }
        }
        0.5 * (lo + hi)
    }
}

/// Intervals of the grid on which the minimal equations are bracketed: steps of 0.5.
const GRID_STEPS: usize = 38;

/// T at point `k` of that grid, from 1 to 20.
fn grid_t(k: usize) -> f64 {
    MIN_TURBIDITY + (MAX_TURBIDITY - MIN_TURBIDITY) * k as f64 / GRID_STEPS as f64
}

/// `n` distinct indices in `0..len`, uniformly (`n ≤ len`).
fn draw_distinct(rng: &mut SplitMix64, len: usize, n: usize) -> Vec<usize> {
    if 2 * n > len {
        // Dense: a partial Fisher-Yates shuffle of all indices.
        let mut all: Vec<usize> = (0..len).collect();
        for i in 0..n {
            let j = i + rng.below(len - i);
            all.swap(i, j);
        }
        all.truncate(n);
        return all;
    }
    let mut seen = HashSet::with_capacity(2 * n);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let i = rng.below(len);
        if seen.insert(i) {
            out.push(i);
        }
    }
    out
}

fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let m = values.len() / 2;
    if values.len() % 2 == 1 {
        values[m]
    } else {
        0.5 * (values[m - 1] + values[m])
    }
}

/// Usable as a sample or reference: finite, not black, not clipped.
fn is_usable(rgb: [f32; 3], lum: f64, clip: f64) -> bool {
    let top = rgb[0].max(rgb[1]).max(rgb[2]) as f64;
    lum > 0.0 && lum.is_finite() && top < clip
}

/// The side of a square, non-empty image, or an error naming it.
fn check_square(image: &RgbImage, name: &str) -> Result<usize> {
    if image.is_empty() || image.width() != image.height() {
        return Err(Error::format(
            name,
            format!(
                "is {}x{}: a fisheye sky image must be square, with the horizon circle \
                 inscribed (crop it to the circle's bounding square)",
                image.width(),
                image.height()
            ),
        ));
    }
    Ok(image.width())
}

/// The largest channel value inside the horizon circle.
fn image_max(image: &RgbImage, fisheye: &Fisheye) -> Result<f64> {
    let size = image.width();
    let mut max = 0.0f64;
    for y in 0..size {
        for x in 0..size {
            if fisheye.pixel_direction(size, x, y).is_some() {
                let p = image.get(x, y);
                max = max.max(p[0].max(p[1]).max(p[2]) as f64);
            }
        }
    }
    Ok(max)
}

/// The usable pixels within [`REFERENCE_RADIUS_PX`] of the reference direction and
/// their mean luminance, or `None` if there is none.
fn reference_patch(
    image: &RgbImage,
    fisheye: &Fisheye,
    reference: [f64; 2],
    sun: [f64; 2],
    clip: f64,
) -> Option<(Vec<Geom>, f64)> {
    let size = image.width();
    let (px, py) = fisheye.pixel(size, reference[0], reference[1])?;
    let r = REFERENCE_RADIUS_PX;
    let (x0, x1) = (
        (px - r).floor().max(0.0) as usize,
        ((px + r).ceil() as usize).min(size),
    );
    let (y0, y1) = (
        (py - r).floor().max(0.0) as usize,
        ((py + r).ceil() as usize).min(size),
    );
    let mut patch = Vec::new();
    for y in y0..y1 {
        for x in x0..x1 {
            let (cx, cy) = (x as f64 + 0.5 - px, y as f64 + 0.5 - py);
            if cx * cx + cy * cy > r * r {
                continue;
            }
            let Some((theta, phi)) = fisheye.pixel_direction(size, x, y) else {
                continue;
            };
            let rgb = *image.get(x, y);
            let lum = super::luminance(rgb);
            if !is_usable(rgb, lum, clip) {
                continue;
            }
            patch.push((Geom::new(theta, phi, sun), lum));
        }
    }
    if patch.is_empty() {
        return None;
    }
    // Leave out the pixels that disagree with the rest of the patch (the edge of a cloud
    // across it): over a few pixels the model's F hardly changes shape with T, so Y/F at
    // a middling T is the same for every clear pixel; keep those within 3 robust
    // standard deviations (at least 1 %, PATCH_MIN_THRESHOLD) of the median.
    let mid = Perez::luminance(5.0);
    let u: Vec<f64> = patch.iter().map(|(g, lum)| lum / g.f(&mid)).collect();
    let m = median(&mut u.clone());
    let mut dev: Vec<f64> = u.iter().map(|v| (v / m - 1.0).abs()).collect();
    let limit = (3.0 * 1.4826 * median(&mut dev.clone())).max(PATCH_MIN_THRESHOLD);
    dev.iter_mut()
        .for_each(|d| *d = if *d <= limit { 1.0 } else { 0.0 });
    let kept: Vec<(Geom, f64)> = patch
        .into_iter()
        .zip(dev)
        .filter(|(_, keep)| *keep > 0.0)
        .map(|(p, _)| p)
        .collect();
    let n = kept.len() as f64;
    let mean = kept.iter().map(|(_, lum)| lum).sum::<f64>() / n;
    Some((kept.into_iter().map(|(g, _)| g).collect(), mean))
}

/// Finds the sun in a fisheye sky image: the centroid of the largest 8-connected blob of
/// near-maximal pixels (largest channel ≥ [`NEAR_MAX`] × the image's largest value) inside
/// the horizon circle, as the mean of the blob's unit direction vectors. `name` stands
/// for the image in errors.
pub fn find_sun(image: &RgbImage, name: &str, fisheye: &Fisheye) -> Result<SunDetection> {
    let size = check_square(image, name)?;
    let max = image_max(image, fisheye)?;
    if max <= 0.0 {
        return Err(Error::format(
            name,
            "no sky pixels: every pixel inside the fisheye circle is black",
        ));
    }
    let clip = NEAR_MAX * max;
    let bright = |x: usize, y: usize| {
        let p = image.get(x, y);
        p[0].max(p[1]).max(p[2]) as f64 >= clip && fisheye.pixel_direction(size, x, y).is_some()
    };
    let mut label = vec![false; size * size];
    let mut best: Vec<(usize, usize)> = Vec::new();
    let mut queue = VecDeque::new();
    for y in 0..size {
        for x in 0..size {
            if label[y * size + x] || !bright(x, y) {
                continue;
            }
            label[y * size + x] = true;
            queue.push_back((x, y));
            let mut blob = Vec::new();
            while let Some((cx, cy)) = queue.pop_front() {
                blob.push((cx, cy));
                for dy in -1i64..=1 {
                    for dx in -1i64..=1 {
                        let (nx, ny) = (cx as i64 + dx, cy as i64 + dy);
                        if nx < 0 || ny < 0 || nx >= size as i64 || ny >= size as i64 {
                            continue;
                        }
                        let (nx, ny) = (nx as usize, ny as usize);
                        if !label[ny * size + nx] && bright(nx, ny) {
                            label[ny * size + nx] = true;
                            queue.push_back((nx, ny));
                        }
                    }
                }
            }
            if blob.len() > best.len() {
                best = blob;
            }
        }
    }
    let mut v = [0.0; 3];
    for &(x, y) in &best {
        if let Some((theta, phi)) = fisheye.pixel_direction(size, x, y) {
            let u = preetham::unit_vector(theta, phi);
            v = [v[0] + u[0], v[1] + u[1], v[2] + u[2]];
        }
    }
    let norm = super::dot(v, v).sqrt();
    let zenith = if norm > 0.0 {
        (v[2] / norm).clamp(-1.0, 1.0).acos()
    } else {
        FRAC_PI_2
    };
    if zenith >= FRAC_PI_2 - 1e-6 {
        return Err(Error::format(
            name,
            "cannot find the sun: the brightest pixels are at the horizon; give --sun-zenith \
             and --sun-azimuth",
        ));
    }
    Ok(SunDetection {
        zenith,
        azimuth: v[1].atan2(v[0]),
        pixels: best.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sky::clouds::{add_clouds, CloudOptions};
    use crate::sky::{draw_sun_disc, render_sky_image, PreethamSky};

    const SUN: [f64; 2] = [0.9, 2.0];

    fn image(t: f64, size: usize) -> RgbImage {
        let sky = PreethamSky::new(t, SUN[0], SUN[1]).unwrap();
        render_sky_image(&sky, size, &Fisheye::default()).unwrap()
    }

    fn opts() -> TurbidityOptions {
        TurbidityOptions {
            sun: Some(SUN),
            repeats: 3,
            ..TurbidityOptions::default()
        }
    }

    #[test]
    fn clear_skies_give_their_turbidity_back() {
        for t in [1.5, 3.0, 7.5, 15.0] {
            let e = estimate_turbidity(&image(t, 96), "sky", &opts()).unwrap();
            assert!((e.turbidity - t).abs() < 1e-3, "T = {t}: {e:?}");
            assert!(e.std < 1e-3, "{e:?}");
            assert!(e.inliers > 90.0, "{e:?}");
            assert_eq!(e.reference_fallbacks, 0);
        }
    }

    #[test]
    fn a_cloud_over_the_reference_is_voted_out() {
        let mut img = image(4.0, 96);
        // A grey cloud twice as bright over the zenith only.
        for y in 40..56 {
            for x in 40..56 {
                let p = img.get_mut(x, y);
                let g = 2.0 * crate::sky::luminance(*p) as f32;
                *p = [g; 3];
            }
        }
        let e = estimate_turbidity(&img, "sky", &opts()).unwrap();
        assert!((e.turbidity - 4.0).abs() < 0.01, "{e:?}");
        assert_eq!(e.reference_fallbacks, 3, "{e:?}");
    }

    #[test]
    fn clouds_are_rejected() {
        let mut img = image(6.0, 128);
        let clouds = CloudOptions {
            coverage: 0.3,
            seed: 3,
            ..CloudOptions::default()
        };
        add_clouds(&mut img, &Fisheye::default(), &clouds).unwrap();
        let e = estimate_turbidity(&img, "sky", &opts()).unwrap();
        assert!((e.turbidity - 6.0).abs() < 0.01, "{e:?}");
        assert!(e.inliers < 90.0, "{e:?}");
    }

    #[test]
    fn the_sun_is_found_from_a_saturated_disc() {
        let f = Fisheye::default();
        for (z, a) in [(30f64, 100f64), (58.4, -179.4), (70.0, -20.0)] {
            let (z, a) = (z.to_radians(), a.to_radians());
            let sky = PreethamSky::new(3.0, z, a).unwrap();
            let mut img = render_sky_image(&sky, 200, &f).unwrap();
            draw_sun_disc(&mut img, &f, z, a, 2f64.to_radians()).unwrap();
            let d = find_sun(&img, "sky", &f).unwrap();
            assert!(
                angle_between(d.zenith, d.azimuth, z, a) < 0.3f64.to_radians(),
                "{d:?}"
            );
            let o = TurbidityOptions {
                sun: None,
                repeats: 2,
                ..TurbidityOptions::default()
            };
            let e = estimate_turbidity(&img, "sky", &o).unwrap();
            assert!(matches!(e.sun_source, SunSource::Detected { .. }));
            assert!((e.turbidity - 3.0).abs() < 0.05, "{e:?}");
        }
    }

    #[test]
    fn bad_images_and_options_are_named() {
        let e = estimate_turbidity(&RgbImage::filled(20, 30, [1.0; 3]), "a.png", &opts())
            .unwrap_err()
            .to_string();
        assert!(e.contains("a.png") && e.contains("square"), "{e}");
        let e = estimate_turbidity(&RgbImage::filled(40, 40, [0.0; 3]), "b.exr", &opts())
            .unwrap_err()
            .to_string();
        assert!(e.contains("b.exr") && e.contains("no sky pixels"), "{e}");
        let o = TurbidityOptions {
            samples: 100_000,
            ..opts()
        };
        let e = estimate_turbidity(&image(3.0, 64), "c.exr", &o)
            .unwrap_err()
            .to_string();
        assert!(e.contains("c.exr") && e.contains("--samples"), "{e}");
        for (o, name) in [
            (
                TurbidityOptions {
                    sun: Some([1.6, 0.0]),
                    ..opts()
                },
                "sun_zenith",
            ),
            (
                TurbidityOptions {
                    samples: 2,
                    ..opts()
                },
                "samples",
            ),
            (
                TurbidityOptions {
                    repeats: 0,
                    ..opts()
                },
                "repeats",
            ),
            (
                TurbidityOptions {
                    threshold: 0.0,
                    ..opts()
                },
                "threshold",
            ),
            (
                TurbidityOptions {
                    reference: Some([2.0, 0.0]),
                    ..opts()
                },
                "reference_zenith",
            ),
        ] {
            let e = o.validate().unwrap_err().to_string();
            assert!(e.contains(name), "{e}");
        }
    }

    #[test]
    fn helpers_behave() {
        let mut rng = SplitMix64::new(1);
        for (len, n) in [(10, 10), (1000, 5), (7, 4)] {
            let d = draw_distinct(&mut rng, len, n);
            let set: HashSet<usize> = d.iter().copied().collect();
            assert_eq!((d.len(), set.len()), (n, n));
            assert!(d.iter().all(|&i| i < len));
        }
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 2.0, 3.0]), 2.5);
    }
}
