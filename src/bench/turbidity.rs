//! Paper 002's Table 1 (sec. 7.1.1): the turbidity estimator on Preetham sky images.
//!
//! For each T in 2..9, a 500 x 500 equidistant fisheye image of the Preetham sky with the
//! sun at θs = 58.4°, φs = −179.4° is rendered ([`crate::sky::render_sky_image`], linear,
//! f32, no sun disc) and the turbidity is estimated 100 times from N = 100 random points
//! each (one sampling stream per estimation); the mean and sample standard deviation of
//! the 100 estimates are compared with the paper's. The same is done again with seeded
//! synthetic clouds over 20 % of the sky ([`crate::sky::clouds`]: grey blobs 1.5 to 2.5
//! times as bright as the sky behind them, soft 3 px edges), which paper 002 does not
//! test but which its RANSAC step is there for.
//!
//! A row passes when |mean − T| ≤ [`MAX_BIAS`] and its std is at most the paper's.
//! Times are wall-clock per estimation on one thread (the estimator is sequential),
//! not counting the one-off preparation of each image.

use crate::error::{Error, Result};
use crate::sky::clouds::{add_clouds, CloudOptions};
use crate::sky::turbidity::{TurbidityEstimator, TurbidityOptions};
use crate::sky::{render_sky_image, Fisheye, PreethamSky};
use std::fmt::Write;
use std::time::Instant;

/// Paper 002, Table 1: (T of the sky model, mean T̄ of 100 estimates, σ_T).
pub const PAPER_TABLE_1: [(f64, f64, f64); 8] = [
    (2.0, 2.011791, 0.004660),
    (3.0, 2.851666, 0.027230),
    (4.0, 4.241544, 0.043840),
    (5.0, 4.992700, 0.055292),
    (6.0, 5.836839, 0.061853),
    (7.0, 7.138090, 0.062630),
    (8.0, 8.010996, 0.135764),
    (9.0, 9.099154, 0.089461),
];

/// The largest |mean − T| a row may have to pass.
pub const MAX_BIAS: f64 = 0.05;

/// The experiment's settings; the defaults are the paper's.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TurbidityBenchOptions {
    /// Side of the sky images, px (paper: 500).
    pub size: usize,
    /// Turbidities of the sky models (paper: 2..9).
    pub turbidities: Vec<f64>,
    /// Sun zenith angle, degrees (paper: 58.4).
    pub sun_zenith_deg: f64,
    /// Sun azimuth, degrees (paper: −179.4).
    pub sun_azimuth_deg: f64,
    /// Estimations per image (paper: 100).
    pub estimations: usize,
    /// Sample points per estimation (paper: 100).
    pub samples: usize,
    /// Cloud cover of the second pass, in (0, 0.9]; 0 leaves the cloudy pass out.
    pub cloud_cover: f64,
    /// Seed of the sampling and of the clouds.
    pub seed: u64,
    /// Quantise the images to 8-bit sRGB first, as a PNG written by `brume sky` and
    /// read back would be (exposure of [`crate::sky::display_exposure`]).
    pub eight_bit: bool,
    /// Fit the level of the ratios ([`TurbidityOptions::fit_level`]).
    pub fit_level: bool,
}

impl Default for TurbidityBenchOptions {
    fn default() -> Self {
        TurbidityBenchOptions {
            size: 500,
            turbidities: (2..=9).map(f64::from).collect(),
            sun_zenith_deg: 58.4,
            sun_azimuth_deg: -179.4,
            estimations: 100,
            samples: 100,
            cloud_cover: 0.2,
            seed: 0,
            eight_bit: false,
            fit_level: false,
        }
    }
}

/// One row of the table: one sky image.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TurbidityBenchRow {
    /// T of the sky model.
    pub turbidity: f64,
    /// Cloud cover of the image (0: clear).
    pub clouds: f64,
    /// Mean of the estimates.
    pub mean: f64,
    /// Sample standard deviation of the estimates.
    pub std: f64,
    /// Smallest and largest estimate.
    pub range: [f64; 2],
    /// Mean number of inliers (of N samples).
    pub inliers: f64,
    /// Estimations whose reference was voted out (a cloud over the zenith).
    pub reference_fallbacks: usize,
    /// Mean wall-clock time per estimation, ms.
    pub ms_per_estimation: f64,
    /// The paper's T̄ and σ_T at this T, if it has them.
    pub paper: Option<[f64; 2]>,
    /// |mean − T| ≤ [`MAX_BIAS`] and std ≤ the paper's (or no paper value).
    pub pass: bool,
}

/// The whole experiment.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TurbidityBenchReport {
    /// The settings.
    pub options: TurbidityBenchOptions,
    /// Clear rows, then cloudy rows.
    pub rows: Vec<TurbidityBenchRow>,
    /// Every row passes.
    pub pass: bool,
    /// Mean time per estimation over all rows, ms.
    pub ms_per_estimation: f64,
    /// Sample points per second (paper: 200).
    pub points_per_second: f64,
}

impl TurbidityBenchOptions {
    /// Refuses, naming the field, any setting outside its domain.
    pub fn validate(&self) -> Result<()> {
        if self.size < 16 {
            return Err(Error::invalid("size", self.size, "an image side ≥ 16 px"));
        }
        if self.turbidities.is_empty() {
            return Err(Error::invalid("turbidities", "(empty)", "at least one T"));
        }
        for &t in &self.turbidities {
            crate::sky::preetham::check_turbidity(t)?;
        }
        crate::sky::preetham::check_sun(
            self.sun_zenith_deg.to_radians(),
            self.sun_azimuth_deg.to_radians(),
        )?;
        if self.estimations == 0 {
            return Err(Error::invalid("estimations", 0, "at least 1 estimation"));
        }
        if !(self.cloud_cover.is_finite() && (0.0..=0.9).contains(&self.cloud_cover)) {
            return Err(Error::invalid(
                "cloud_cover",
                self.cloud_cover,
                "a fraction of the sky in [0, 0.9] (0: no cloudy pass)",
            ));
        }
        Ok(())
    }
}

/// Runs the experiment; `progress(done, total, what)` is called before each image.
pub fn run_turbidity_bench(
    opts: &TurbidityBenchOptions,
    progress: &dyn Fn(usize, usize, &str),
) -> Result<TurbidityBenchReport> {
    opts.validate()?;
    let sun = [
        opts.sun_zenith_deg.to_radians(),
        opts.sun_azimuth_deg.to_radians(),
    ];
    let fisheye = Fisheye::default();
    let covers: Vec<f64> = if opts.cloud_cover > 0.0 {
        vec![0.0, opts.cloud_cover]
    } else {
        vec![0.0]
    };
    let total = covers.len() * opts.turbidities.len();
    let mut rows = Vec::with_capacity(total);
    for &cover in &covers {
        for (i, &t) in opts.turbidities.iter().enumerate() {
            progress(
                rows.len(),
                total,
                &format!("T = {t}, clouds {:.0} %", cover * 100.0),
            );
            let sky = PreethamSky::new(t, sun[0], sun[1])?;
            let mut image = render_sky_image(&sky, opts.size, &fisheye)?;
            if cover > 0.0 {
                let clouds = CloudOptions {
                    coverage: cover,
                    seed: opts.seed ^ (i as u64 + 1).wrapping_mul(0x9E37_79B9),
                    ..CloudOptions::default()
                };
                add_clouds(&mut image, &fisheye, &clouds)?;
            }
            if opts.eight_bit {
                quantise(&mut image, &fisheye, sun);
            }
            let estimator = TurbidityEstimator::new(
                &image,
                "sky model",
                &TurbidityOptions {
                    fisheye,
                    sun: Some(sun),
                    samples: opts.samples,
                    repeats: opts.estimations,
                    seed: opts.seed,
                    fit_level: opts.fit_level,
                    ..TurbidityOptions::default()
                },
            )?;
            let start = Instant::now();
            let e = estimator.run()?;
            let ms = start.elapsed().as_secs_f64() * 1e3 / e.repeats as f64;
            let paper = PAPER_TABLE_1.iter().find(|p| p.0 == t).map(|p| [p.1, p.2]);
            let pass = (e.turbidity - t).abs() <= MAX_BIAS && paper.is_none_or(|p| e.std <= p[1]);
            let values = e.estimates.iter().map(|s| s.turbidity);
            rows.push(TurbidityBenchRow {
                turbidity: t,
                clouds: cover,
                mean: e.turbidity,
                std: e.std,
                range: [
                    values.clone().fold(f64::INFINITY, f64::min),
                    values.fold(f64::NEG_INFINITY, f64::max),
                ],
                inliers: e.inliers,
                reference_fallbacks: e.reference_fallbacks,
                ms_per_estimation: ms,
                paper,
                pass,
            });
        }
    }
    progress(total, total, "done");
    let ms = rows.iter().map(|r| r.ms_per_estimation).sum::<f64>() / rows.len() as f64;
    Ok(TurbidityBenchReport {
        options: opts.clone(),
        pass: rows.iter().all(|r| r.pass),
        ms_per_estimation: ms,
        points_per_second: opts.samples as f64 / (ms * 1e-3),
        rows,
    })
}

/// Scales `image` by its display exposure and rounds it through 8-bit sRGB and back.
fn quantise(image: &mut crate::raster::RgbImage, fisheye: &Fisheye, sun: [f64; 2]) {
    use crate::io::image::{linear_to_srgb, srgb_to_linear};
    let scale = crate::sky::display_exposure(image, fisheye, sun[0], sun[1], 0.0).unwrap_or(1.0);
    for p in image.as_mut_slice() {
        *p = p.map(|c| {
            let code = (linear_to_srgb((c as f64 * scale).clamp(0.0, 1.0) as f32) * 255.0).round();
            srgb_to_linear(code / 255.0)
        });
    }
}

/// The report as a text table, the paper's values side by side.
pub fn turbidity_table(report: &TurbidityBenchReport) -> String {
    let o = &report.options;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Paper 002, Table 1: turbidity of {0}x{0} Preetham skies{5}, sun at θs = {1}°, \
         φs = {2}°; {3} estimations of N = {4} points each{6}",
        o.size,
        o.sun_zenith_deg,
        o.sun_azimuth_deg,
        o.estimations,
        o.samples,
        if o.eight_bit {
            " (8-bit sRGB)"
        } else {
            " (f32 linear)"
        },
        if o.fit_level {
            ", level fitted"
        } else {
            ", eq. 8 (level 1)"
        },
    );
    let _ = writeln!(
        s,
        "{:>5} {:>7} | {:>10} {:>10} | {:>10} {:>10} | {:>10} {:>7} {:>9} | pass",
        "T", "clouds", "mean", "std", "paper T̄", "paper σ", "mean−T", "inliers", "ms/est"
    );
    for r in &report.rows {
        let (pm, ps) = match r.paper {
            Some([m, sd]) => (format!("{m:.6}"), format!("{sd:.6}")),
            None => ("-".into(), "-".into()),
        };
        let _ = writeln!(
            s,
            "{:>5.1} {:>6.0}% | {:>10.6} {:>10.2e} | {:>10} {:>10} | {:>+10.2e} {:>7.1} {:>9.3} | {}",
            r.turbidity,
            r.clouds * 100.0,
            r.mean,
            r.std,
            pm,
            ps,
            r.mean - r.turbidity,
            r.inliers,
            r.ms_per_estimation,
            if r.pass { "yes" } else { "NO" },
        );
    }
    let _ = writeln!(
        s,
        "{:.3} ms per estimation on one thread ({:.0} sample points/s; paper: 200 points/s); \
         pass = |mean − T| ≤ {MAX_BIAS} and std ≤ the paper's: {}",
        report.ms_per_estimation,
        report.points_per_second,
        if report.pass {
            "all rows"
        } else {
            "NOT all rows"
        }
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_small_run_reproduces_the_table_shape() {
        let opts = TurbidityBenchOptions {
            size: 120,
            turbidities: vec![2.0, 9.0],
            estimations: 4,
            ..TurbidityBenchOptions::default()
        };
        let report = run_turbidity_bench(&opts, &|_, _, _| {}).unwrap();
        assert_eq!(report.rows.len(), 4);
        assert!(report.pass, "{}", turbidity_table(&report));
        let table = turbidity_table(&report);
        assert!(
            table.contains("2.011791") && table.contains("0.089461"),
            "{table}"
        );
        let bad = TurbidityBenchOptions {
            cloud_cover: 2.0,
            ..opts
        };
        let e = run_turbidity_bench(&bad, &|_, _, _| {}).unwrap_err();
        assert!(e.to_string().contains("cloud_cover"), "{e}");
    }
}
