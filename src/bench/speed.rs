//! The speed experiment of paper 000, sec. 5.3 (fig. 7): for each σref, scheme and
//! precision, one warm-up render and then `runs` timed renders of a uniform blur at one
//! image size. The figure is `PassTimes::total_ms` of each run — the N + 2 passes, timed
//! by `GL_TIME_ELAPSED` where the driver has it (else `glFinish` + wall clock; the report
//! says which) — summarised by its median and sample standard deviation. Uploads and the
//! read-back are outside the figure, as in the paper. The renderer's timing is
//! [`crate::Timing::Blocking`]; a run whose GPU-timer figures are rejected (disjoint, or
//! implausible) is not repeated but left out (the row's `runs` counts those kept).
//!
//! The input is [`super::synthetic_image`]: a pass costs the same whatever the pixels
//! hold, and the figure must not depend on which demo image is built in.

use super::{Config, Configs, Progress};
use crate::error::{Error, Result};
use crate::medium::uniform::CHROMATIC_TRANSMISSION;
use crate::medium::UniformBlur;
use crate::raster::Grid;
use crate::schedule::Schedule;
use crate::{Precision, Renderer, Scheme};
use serde::Serialize;

/// Default image size of the speed benchmark (px): the paper's 1600 x 1120.
pub const DEFAULT_SIZE: (usize, usize) = (1600, 1120);
/// Default number of timed runs per configuration.
pub const DEFAULT_RUNS: usize = 5;

/// Whether the transmission is the same in every channel (paper 000) or differs per
/// channel. A uniform blur has no in-scattered light, so both run the offset layout, one
/// RGBA target (`crate::pipeline`, *Two layouts*).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Tau {
    /// τ = 1 in every channel: the paper's pipeline.
    #[default]
    Grey,
    /// τ = [`CHROMATIC_TRANSMISSION`]: the chromatic blur.
    Rgb,
}

impl Tau {
    /// The medium of a configuration: a uniform blur to σref through this τ.
    fn medium(self, config: &Config) -> UniformBlur {
        match self {
            Tau::Grey => config.medium(),
            Tau::Rgb => UniformBlur {
                transmission: CHROMATIC_TRANSMISSION,
                ..config.medium()
            },
        }
    }
}

/// What to time.
#[derive(Clone, Debug, PartialEq)]
pub struct SpeedOptions {
    /// σref list, schemes, precisions and σ0.
    pub configs: Configs,
    /// Image width (px).
    pub width: usize,
    /// Image height (px).
    pub height: usize,
    /// Timed runs per configuration (after one warm-up), ≥ 1.
    pub runs: usize,
    /// Skip configurations with more than this many passes (N + 2).
    pub max_passes: Option<u32>,
    /// Grey or chromatic transmission.
    pub tau: Tau,
    /// [`crate::Blur::coarse_from`] of every render (coarse to fine), or none.
    pub coarse_from: Option<f64>,
}

/// Rejects a [`crate::Blur::coarse_from`] the pipeline would refuse, before any work
/// ([`crate::Blur::check_coarse_from`]: the error names `coarse_from`).
pub fn check_coarse_from(coarse_from: Option<f64>) -> Result<()> {
    let blur = crate::Blur {
        coarse_from,
        ..crate::Blur::default()
    };
    blur.check_coarse_from()
}

impl Default for SpeedOptions {
    fn default() -> Self {
        SpeedOptions {
            configs: Configs::default(),
            width: DEFAULT_SIZE.0,
            height: DEFAULT_SIZE.1,
            runs: DEFAULT_RUNS,
            max_passes: None,
            tau: Tau::Grey,
            coarse_from: None,
        }
    }
}

impl SpeedOptions {
    /// Rejects empty lists, scales below σ0, a zero size and zero runs.
    pub fn validate(&self) -> Result<()> {
        self.configs.validate()?;
        check_coarse_from(self.coarse_from)?;
        if self.width == 0 || self.height == 0 {
            return Err(Error::invalid(
                "size",
                format!("{}x{}", self.width, self.height),
                "WIDTHxHEIGHT, both ≥ 1, e.g. 1600x1120",
            ));
        }
        if self.runs == 0 {
            return Err(Error::invalid("runs", 0, "at least 1 timed run"));
        }
        Ok(())
    }
}

/// One configuration's timing, or why it was skipped.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SpeedRow {
    /// Target scale σref (px).
    pub sigma_ref: f64,
    /// Diffusion scheme.
    pub scheme: Scheme,
    /// Texture precision.
    pub precision: Precision,
    /// Diffusion steps N.
    pub steps: u32,
    /// Passes per render: N + 2 at full resolution, N + 1 + 2L with L coarse levels
    /// ([`crate::Blur::coarse_from`]; the passes of a level are smaller).
    pub passes: u32,
    /// True when `max_passes` left this configuration out; the figures are then `None`.
    pub skipped: bool,
    /// Why it was skipped.
    pub reason: Option<String>,
    /// Clock of the timed runs: `gpu-timer`, `wall`, or `mixed` if the driver's timer
    /// was rejected for some runs.
    pub clock: Option<String>,
    /// Timed runs.
    pub runs: usize,
    /// Median total time of the N + 2 passes (ms).
    pub median_ms: Option<f64>,
    /// Sample standard deviation of the total time (ms); `None` with one run.
    pub std_ms: Option<f64>,
    /// Median time per pass, median_ms / passes (ms).
    pub ms_per_pass: Option<f64>,
    /// Every timed total (ms), in run order.
    pub samples_ms: Vec<f64>,
    /// The passes of one render as they ran (`medium`, `diffuse 1`, `down 1/2`, …): N + 2
    /// at full resolution, more with the coarse stage. Empty when skipped.
    pub pass_names: Vec<String>,
    /// The median time of each pass of `pass_names` over the timed runs (ms); empty when
    /// skipped or when no run had figures.
    pub pass_median_ms: Vec<f64>,
}

/// A speed ratio between two schemes at one σ and precision.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SpeedRatio {
    /// σref (px): the largest one at which both schemes ran.
    pub sigma_ref: f64,
    /// Precision of both.
    pub precision: Precision,
    /// The slower scheme (numerator).
    pub slow: Scheme,
    /// The faster scheme (denominator).
    pub fast: Scheme,
    /// median(slow) / median(fast).
    pub ratio: f64,
}

/// The whole experiment.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SpeedReport {
    /// `GL_RENDERER` of the context that ran it.
    pub renderer: String,
    /// The clock the renderer prefers (`gpu-timer` or `wall`); each row says what it got.
    pub clock: String,
    /// Image width (px).
    pub width: usize,
    /// Image height (px).
    pub height: usize,
    /// Timed runs per configuration.
    pub runs: usize,
    /// The most passes (N + 2) a configuration may take, if any; one that takes more is
    /// skipped, and its row says so.
    pub max_passes: Option<u32>,
    /// Grey or chromatic transmission.
    pub tau: Tau,
    /// One row per (σref, scheme, precision), σ outermost.
    pub rows: Vec<SpeedRow>,
    /// Euler / matched and Euler / invariant at the largest σ where both ran.
    pub ratios: Vec<SpeedRatio>,
}

/// Runs the experiment. `progress` is called when a configuration starts and after each
/// of its renders, with work counted in passes (see [`Progress`]).
pub fn run_speed(
    renderer: &mut Renderer,
    opts: &SpeedOptions,
    progress: &dyn Fn(Progress),
) -> Result<SpeedReport> {
    opts.validate()?;
    let image = super::synthetic_image(opts.width, opts.height, 1);
    let range = Grid::filled(opts.width, opts.height, 0.0f32);
    let plans = plan(opts)?;
    let total: u64 = plans
        .iter()
        .filter(|(_, _, skip)| skip.is_none())
        .map(|(_, s, _)| (opts.runs as u64 + 1) * u64::from(s.steps + 2))
        .sum();
    let mut done = 0;
    let mut rows = Vec::new();
    for (config, schedule, skip) in &plans {
        let label = config.label();
        let row = match skip {
            Some(reason) => skipped_row(config, schedule, reason.clone()),
            None => {
                // Say what is starting: one Euler render can take a minute.
                progress(Progress {
                    done,
                    total,
                    what: &label,
                });
                let medium = opts.tau.medium(config);
                let blur = crate::Blur {
                    coarse_from: opts.coarse_from,
                    ..config.blur
                };
                let mut samples = Vec::with_capacity(opts.runs);
                let mut clocks = Vec::with_capacity(opts.runs);
                let mut passes = PassSamples::default();
                // Run 0 is the warm-up: shader caches, target allocation, first query.
                for run in 0..=opts.runs {
                    let out = renderer.render(&image, &range, &medium, &blur)?;
                    if let (true, Some(ms)) = (run > 0, out.times.total()) {
                        samples.push(ms);
                        clocks.push(out.times.clock.name());
                        passes.add(&out);
                    }
                    done += u64::from(schedule.steps + 2);
                    progress(Progress {
                        done,
                        total,
                        what: &label,
                    });
                }
                timed_row(config, schedule, samples, &clocks, passes)
            }
        };
        rows.push(row);
    }
    let ratios = ratios(&rows);
    Ok(SpeedReport {
        renderer: renderer.caps().renderer.clone(),
        clock: renderer.preferred_clock().name().into(),
        width: opts.width,
        height: opts.height,
        runs: opts.runs,
        max_passes: opts.max_passes,
        tau: opts.tau,
        rows,
        ratios,
    })
}

/// Every configuration with its schedule and, if `max_passes` rules it out, why.
fn plan(opts: &SpeedOptions) -> Result<Vec<(Config, Schedule, Option<String>)>> {
    opts.configs
        .each()
        .map(|config| {
            let schedule = config.schedule()?;
            let passes = schedule.steps + 2;
            let skip = opts
                .max_passes
                .filter(|&max| passes > max)
                .map(|max| format!("{passes} passes > the limit of {max}"));
            Ok((config, schedule, skip))
        })
        .collect()
}

fn skipped_row(config: &Config, schedule: &Schedule, reason: String) -> SpeedRow {
    SpeedRow {
        sigma_ref: config.sigma_ref,
        scheme: config.blur.scheme,
        precision: config.blur.precision,
        steps: schedule.steps,
        passes: schedule.steps + 2,
        skipped: true,
        reason: Some(reason),
        clock: None,
        runs: 0,
        median_ms: None,
        std_ms: None,
        ms_per_pass: None,
        samples_ms: Vec::new(),
        pass_names: Vec::new(),
        pass_median_ms: Vec::new(),
    }
}

/// Each pass's times over the timed runs of one configuration.
#[derive(Default)]
struct PassSamples {
    names: Vec<String>,
    times: Vec<Vec<f64>>,
}

impl PassSamples {
    /// Adds a timed render's pass times; its passes are named once, from the first.
    fn add(&mut self, out: &crate::Rendered) {
        let pass_ms = &out.times.pass_ms;
        if self.names.is_empty() {
            self.names = out.pass_names();
            self.times = vec![Vec::new(); self.names.len()];
        }
        if self.names.len() != pass_ms.len() {
            return;
        }
        for (times, &ms) in self.times.iter_mut().zip(pass_ms) {
            times.push(ms);
        }
    }

    fn medians(&self) -> Vec<f64> {
        self.times.iter().filter_map(|t| median(t)).collect()
    }
}

fn timed_row(
    config: &Config,
    schedule: &Schedule,
    samples: Vec<f64>,
    clocks: &[&str],
    pass_samples: PassSamples,
) -> SpeedRow {
    // The passes that ran: N + 2, or N + 1 + 2L with L coarse levels.
    let passes = match pass_samples.names.len() {
        0 => schedule.steps + 2,
        n => n as u32,
    };
    let median_ms = median(&samples);
    let clock = match clocks.first() {
        Some(first) if clocks.iter().all(|c| c == first) => first.to_string(),
        _ => "mixed".into(),
    };
    SpeedRow {
        sigma_ref: config.sigma_ref,
        scheme: config.blur.scheme,
        precision: config.blur.precision,
        steps: schedule.steps,
        passes,
        skipped: false,
        reason: None,
        clock: Some(clock),
        runs: samples.len(),
        median_ms,
        std_ms: sample_std(&samples),
        ms_per_pass: median_ms.map(|m| m / f64::from(passes)),
        samples_ms: samples,
        pass_median_ms: pass_samples.medians(),
        pass_names: pass_samples.names,
    }
}

/// Median (mean of the middle two for an even count); `None` for no sample.
pub fn median(samples: &[f64]) -> Option<f64> {
    let mut v = samples.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(v[n / 2]),
        _ => Some(0.5 * (v[n / 2 - 1] + v[n / 2])),
    }
}

/// Sample standard deviation (n − 1); `None` below two samples.
pub fn sample_std(samples: &[f64]) -> Option<f64> {
    let n = samples.len();
    if n < 2 {
        return None;
    }
    let mean = samples.iter().sum::<f64>() / n as f64;
    let ss: f64 = samples.iter().map(|v| (v - mean).powi(2)).sum();
    Some((ss / (n - 1) as f64).sqrt())
}

/// Euler / matched and Euler / invariant, per precision, at the largest σ where both
/// schemes were timed.
fn ratios(rows: &[SpeedRow]) -> Vec<SpeedRatio> {
    let median_of = |sigma: f64, scheme: Scheme, precision: Precision| {
        rows.iter()
            .find(|r| r.sigma_ref == sigma && r.scheme == scheme && r.precision == precision)
            .and_then(|r| r.median_ms)
    };
    let mut out = Vec::new();
    for precision in Precision::ALL {
        for fast in [Scheme::Matched, Scheme::Invariant] {
            let best = rows
                .iter()
                .filter(|r| r.scheme == Scheme::Euler && r.precision == precision)
                .filter_map(|r| {
                    let slow = r.median_ms?;
                    let quick = median_of(r.sigma_ref, fast, precision)?;
                    Some((r.sigma_ref, slow / quick))
                })
                .max_by(|a, b| a.0.total_cmp(&b.0));
            if let Some((sigma_ref, ratio)) = best {
                out.push(SpeedRatio {
                    sigma_ref,
                    precision,
                    slow: Scheme::Euler,
                    fast,
                    ratio,
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_and_std() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), Some(2.5));
        assert_eq!(median(&[]), None);
        let s = sample_std(&[1.0, 2.0, 3.0, 4.0]).unwrap();
        assert!((s - 1.290_994_448_7).abs() < 1e-9);
        assert_eq!(sample_std(&[1.0]), None);
    }

    #[test]
    fn max_passes_skips_with_a_reason() {
        let opts = SpeedOptions {
            configs: Configs {
                sigmas: vec![25.0],
                ..Configs::default()
            },
            max_passes: Some(100),
            ..SpeedOptions::default()
        };
        let plans = plan(&opts).unwrap();
        let euler = plans
            .iter()
            .find(|p| p.0.blur.scheme == Scheme::Euler)
            .unwrap();
        assert_eq!(euler.2.as_deref(), Some("1250 passes > the limit of 100"));
        assert!(plans
            .iter()
            .filter(|p| p.0.blur.scheme != Scheme::Euler)
            .all(|p| p.2.is_none()));
    }
}
