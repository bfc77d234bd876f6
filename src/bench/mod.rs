//! Benchmarks that reproduce paper 000's experiments (sec. 5.2-5.3):
//!
//! - [`accuracy`] (fig. 6): every scheme and precision blurs an image uniformly to σref on
//!   the GPU and is compared with the exact Gaussian of std √(σref² − σ0²); the scale
//!   actually reached is measured from an impulse response.
//! - [`speed`] (fig. 7): the same configurations timed at one image size, median and
//!   standard deviation of several runs after a warm-up.
//! - [`fog`]: the engine fogs of papers 001 and 003 on brume's procedural scene, each
//!   blur mode, median of several runs after a warm-up.
//! - [`turbidity`]: paper 002's Table 1, the turbidity estimator on Preetham sky images
//!   (CPU only), clear and with synthetic clouds.
//!
//! [`report`] prints tables and writes CSV/JSON and `plot` (the `plots` feature) draws the
//! two figures; the command-line arguments and progress bars belong to the `brume` program
//! (`src/cli`).
//!
//! ```text
//! brume bench accuracy --plot fig6.png --csv fig6.csv       # about 1.5 min at 641x555
//! brume bench speed --max-passes 200 --plot fig7.svg        # Euler at σ ≥ 12 left out
//! brume bench speed --sigmas 5,25 --schemes matched --precisions f32 --json
//! ```
//!
//! What the figures mean (defined once, here and in the submodules):
//! - *RMS* / *max|err|*: over the RGB channels in linear light, against the exact
//!   clamp-to-edge Gaussian of std √(σref² − σ0²); *interior* leaves ⌈3σref⌉ px out.
//!   Euler's unit steps with clamp-to-edge sampling behave like a mirrored border, not a
//!   replicated one, so its whole-image RMS is dominated by the border: read the interior.
//! - *scale reached*: √(var + σ0²) of the GPU's impulse response, per axis; *ratio* is
//!   that over σref (see [`accuracy`]).
//! - *time*: `PassTimes::total_ms` of the N + 2 passes, median and sample std of
//!   `--runs` renders after a warm-up, with the clock that produced it (see [`speed`]).

pub mod accuracy;
pub mod fog;
#[cfg(feature = "plots")]
pub mod plot;
pub mod refine;
pub mod report;
pub mod speed;
pub mod turbidity;

pub use accuracy::{run_accuracy, AccuracyOptions, AccuracyReport, AccuracyRow};
pub use speed::{run_speed, SpeedOptions, SpeedReport, SpeedRow};

use crate::blur::{Blur, DEFAULT_RHO_MAX};
use crate::error::{Error, Result};
use crate::medium::UniformBlur;
use crate::raster::{Grid, RgbImage};
use crate::schedule::Schedule;
use crate::{Precision, Scheme};

/// The σref list of paper 000's figures 6 and 7 (px).
pub const DEFAULT_SIGMAS: [f64; 9] = [1.0, 2.0, 3.0, 5.0, 8.0, 12.0, 16.0, 20.0, 25.0];

/// One progress event: `done` of `total` work units are finished, and `what` is being
/// worked on now. Work is counted in diffusion passes (N + 2 per render) so that a
/// progress bar moves in proportion to time: one Euler render at σ = 25 is 1250 units,
/// an invariant one 15.
#[derive(Clone, Copy, Debug)]
pub struct Progress<'a> {
    /// Units finished so far.
    pub done: u64,
    /// Units planned in all.
    pub total: u64,
    /// The configuration being rendered, e.g. `euler f32 σ=25`.
    pub what: &'a str,
}

/// The configurations common to both benchmarks, checked once.
#[derive(Clone, Debug, PartialEq)]
pub struct Configs {
    /// Target scales σref (px), each ≥ σ0.
    pub sigmas: Vec<f64>,
    /// Schemes, in report order.
    pub schemes: Vec<Scheme>,
    /// Precisions, in report order.
    pub precisions: Vec<Precision>,
    /// Inner scale σ0 of the input (px).
    pub sigma0: f64,
}

impl Default for Configs {
    fn default() -> Self {
        Configs {
            sigmas: DEFAULT_SIGMAS.to_vec(),
            schemes: Scheme::ALL.to_vec(),
            precisions: Precision::ALL.to_vec(),
            sigma0: crate::blur::DEFAULT_SIGMA0,
        }
    }
}

impl Configs {
    /// Rejects empty lists and scales below σ0, naming the command-line option.
    pub fn validate(&self) -> Result<()> {
        if !(self.sigma0.is_finite() && self.sigma0 > 0.0) {
            return Err(Error::invalid("sigma0", self.sigma0, "a finite scale > 0"));
        }
        if self.sigmas.is_empty() {
            return Err(Error::invalid("sigmas", "(empty)", "at least one scale"));
        }
        if let Some(bad) = self
            .sigmas
            .iter()
            .find(|s| !(s.is_finite() && **s >= self.sigma0))
        {
            return Err(Error::invalid(
                "sigmas",
                bad,
                format!("finite scales ≥ σ0 = {} px", self.sigma0),
            ));
        }
        if self.schemes.is_empty() {
            return Err(Error::invalid("schemes", "(empty)", "at least one scheme"));
        }
        if self.precisions.is_empty() {
            return Err(Error::invalid(
                "precisions",
                "(empty)",
                "at least one precision",
            ));
        }
        Ok(())
    }

    /// Every (σref, scheme, precision) in report order: σ outermost, as the figures read.
    pub fn each(&self) -> impl Iterator<Item = Config> + '_ {
        self.sigmas.iter().flat_map(move |&sigma_ref| {
            self.schemes.iter().flat_map(move |&scheme| {
                self.precisions.iter().map(move |&precision| Config {
                    sigma_ref,
                    blur: Blur {
                        scheme,
                        sigma0: self.sigma0,
                        rho_max: DEFAULT_RHO_MAX,
                        precision,
                        ..Blur::default()
                    },
                })
            })
        })
    }
}

/// One configuration of either experiment: a uniform blur to σref with one scheme and
/// precision.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// Target scale σref (px).
    pub sigma_ref: f64,
    /// Scheme, σ0, ρmax and precision.
    pub blur: Blur,
}

impl Config {
    /// The medium: a pure blur to σref.
    pub fn medium(&self) -> UniformBlur {
        UniformBlur::new(self.sigma_ref)
    }

    /// The N steps that reach σref.
    pub fn schedule(&self) -> Result<Schedule> {
        self.blur.schedule(self.sigma_ref, "sigmas")
    }

    /// `scheme precision σ=…`, for progress and tables.
    pub fn label(&self) -> String {
        config_label(self.sigma_ref, self.blur.scheme, self.blur.precision)
    }
}

/// A deterministic high-contrast test image (random colours in [0, 1]): the speed
/// benchmark's input, whose content does not change the time of a pass, and a fallback
/// for tests.
pub fn synthetic_image(width: usize, height: usize, seed: u64) -> RgbImage {
    // xorshift64: the same image on every machine, no dependency.
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    Grid::from_fn(width, height, |_, _| [next(), next(), next()])
}

/// `label σ=…` for progress messages and tables.
fn config_label(sigma: f64, scheme: Scheme, precision: Precision) -> String {
    format!("{scheme} {precision} σ={sigma}")
}
