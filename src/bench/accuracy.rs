//! The accuracy experiment of paper 000, sec. 5.2 (fig. 6), with a check of the scale
//! each scheme actually reaches.
//!
//! For each σref, scheme and precision:
//!
//! 1. **Error against a Gaussian.** The image is blurred uniformly to σref on the GPU (no
//!    attenuation, no airlight) and compared, in linear light, with the exact f64 Gaussian
//!    of std √(σref² − σ0²) with clamp-to-edge borders (the input is taken to be at scale
//!    σ0 already). RMS and max |error| over the RGB channels of the whole image, and RMS
//!    over the interior, which leaves ⌈3σref⌉ px out on every side so that border
//!    conventions neither hide nor fake scheme error.
//! 2. **Scale reached.** The same render of an impulse in the middle of a blank square of
//!    side 2·⌈6σref⌉ + 1 px. The response's variance per axis, var_x and var_y (second
//!    central moment, weights = response), is what the passes added; the input impulse
//!    stands for a pixel already at scale σ0, so the scale reached is
//!    σ_x = √(var_x + σ0²) (and σ_y alike), and the reported ratio is
//!    √((var_x + var_y)/2 + σ0²) / σref — 1 for a schedule whose variance reaches σref².
//!    The impulse has height 2π·σref² so that the response peaks near 1 and its tails
//!    stay in f16's normal range (a unit impulse would lose them to underflow in f16 and
//!    read as under-blurring); the moments do not depend on the height.
//!
//! A row is flagged **diverged** when the output holds a NaN or an infinity, or when its
//! largest error exceeds the input's value range: a blur is a convex average, so a
//! stable scheme can never be that far off.

use super::{Config, Configs, Progress};
use crate::error::{Error, Result};
use crate::medium::Medium;
use crate::raster::{Grid, RgbImage, RgbaImage};
use crate::reference;
use crate::{Blur, Precision, Renderer, Scheme};
use serde::Serialize;

/// What to measure.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AccuracyOptions {
    /// σref list, schemes, precisions and σ0.
    pub configs: Configs,
    /// [`crate::Blur::coarse_from`] of every render (coarse to fine), or none.
    pub coarse_from: Option<f64>,
}

/// The largest σref the accuracy experiment takes (px). Its cost grows with σ: the
/// impulse test renders a (2⌈6σ⌉ + 1)² image (1201² at 100 px, 48 MB of RGBA32F per
/// target) and the exact Gaussian reference takes 2(12σ + 1) taps per pixel of the whole
/// image; at σ = 1500 the impulse image alone would be 18001² px (5 GB), beyond any GL
/// texture limit. The paper's figures stop at 25 px.
pub const MAX_ACCURACY_SIGMA: f64 = 100.0;

impl AccuracyOptions {
    /// Rejects what [`Configs::validate`] rejects, and scales above
    /// [`MAX_ACCURACY_SIGMA`].
    pub fn validate(&self) -> Result<()> {
        self.configs.validate()?;
        super::speed::check_coarse_from(self.coarse_from)?;
        if let Some(&sigma) = self
            .configs
            .sigmas
            .iter()
            .find(|&&s| s > MAX_ACCURACY_SIGMA)
        {
            let side = 2 * (6.0 * sigma).ceil() as u64 + 1;
            return Err(Error::invalid(
                "sigmas",
                sigma,
                format!(
                    "scales ≤ {MAX_ACCURACY_SIGMA} px for the accuracy experiment (its impulse \
                     test at σ = {sigma} would render a {side}x{side} image)"
                ),
            ));
        }
        Ok(())
    }
}

/// One (σref, scheme, precision) measurement.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AccuracyRow {
    /// Target scale σref (px).
    pub sigma_ref: f64,
    /// Diffusion scheme.
    pub scheme: Scheme,
    /// Texture precision.
    pub precision: Precision,
    /// Diffusion steps N (the render runs N + 2 passes).
    pub steps: u32,
    /// Std of the reference Gaussian, √(σref² − σ0²) (px).
    pub reference_sigma: f64,
    /// RMS error over the whole image (RGB, linear light).
    pub rms: f64,
    /// RMS error over the interior; `None` when the margin leaves no pixel.
    pub rms_interior: Option<f64>,
    /// Margin left out for `rms_interior`: ⌈3σref⌉ px.
    pub interior_margin: usize,
    /// Largest absolute error over the whole image.
    pub max_abs: f64,
    /// Scale reached along x, √(var_x + σ0²) (px).
    pub scale_x: f64,
    /// Scale reached along y, √(var_y + σ0²) (px).
    pub scale_y: f64,
    /// √((var_x + var_y)/2 + σ0²) / σref: 1 when the variance reaches σref².
    pub scale_ratio: f64,
    /// NaN/inf in the output, or an error beyond the input's value range.
    pub diverged: bool,
    /// Anything a reader should know about this row (e.g. N = 0).
    pub note: Option<String>,
}

/// The whole experiment.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AccuracyReport {
    /// `GL_RENDERER` of the context that ran it.
    pub renderer: String,
    /// Image width (px).
    pub width: usize,
    /// Image height (px).
    pub height: usize,
    /// Inner scale σ0 (px).
    pub sigma0: f64,
    /// Rate limit ρmax.
    pub rho_max: f64,
    /// One row per (σref, scheme, precision), σ outermost.
    pub rows: Vec<AccuracyRow>,
}

/// Runs the experiment on `image` (linear light). `progress` is called before and after
/// each render with work counted in diffusion passes (see [`Progress`]).
pub fn run_accuracy(
    renderer: &mut Renderer,
    image: &RgbImage,
    opts: &AccuracyOptions,
    progress: &dyn Fn(Progress),
) -> Result<AccuracyReport> {
    opts.validate()?;
    let configs = &opts.configs;
    let total = planned_passes(configs)?;
    let input = reference::rgba64_from_rgb(image);
    let value_range = rgb_value_range(image);
    let mut done = 0;
    let mut rows = Vec::new();
    for &sigma_ref in &configs.sigmas {
        // One reference per σ, shared by every scheme and precision.
        let reference_sigma = reference_std(sigma_ref, configs.sigma0);
        let expected = reference::to_f32(&reference::gaussian_blur(&input, reference_sigma));
        let impulse = Impulse::new(sigma_ref);
        for config in configs.each().filter(|c| c.sigma_ref == sigma_ref) {
            let label = config.label();
            progress(Progress {
                done,
                total,
                what: &label,
            });
            let steps = config.schedule()?.steps;
            let config = Config {
                blur: Blur {
                    coarse_from: opts.coarse_from,
                    ..config.blur
                },
                ..config
            };
            let row = measure(renderer, image, &expected, &impulse, &config, value_range)?;
            rows.push(AccuracyRow {
                steps,
                reference_sigma,
                ..row
            });
            // The blur and the impulse: two renders of N + 2 passes.
            done += 2 * u64::from(steps + 2);
            progress(Progress {
                done,
                total,
                what: &label,
            });
        }
    }
    Ok(AccuracyReport {
        renderer: renderer.caps().renderer.clone(),
        width: image.width(),
        height: image.height(),
        sigma0: configs.sigma0,
        rho_max: crate::blur::DEFAULT_RHO_MAX,
        rows,
    })
}

/// √(σref² − σ0²): the blur that takes an input at σ0 to σref.
pub fn reference_std(sigma_ref: f64, sigma0: f64) -> f64 {
    (sigma_ref * sigma_ref - sigma0 * sigma0).max(0.0).sqrt()
}

/// Total passes of the whole run (two renders per configuration), for progress.
fn planned_passes(configs: &Configs) -> Result<u64> {
    let mut total = 0;
    for config in configs.each() {
        total += 2 * u64::from(config.schedule()?.steps + 2);
    }
    Ok(total)
}

/// Error and scale figures of one configuration (steps and reference σ filled by the
/// caller).
fn measure(
    renderer: &mut Renderer,
    image: &RgbImage,
    expected: &RgbaImage,
    impulse: &Impulse,
    config: &Config,
    value_range: f64,
) -> Result<AccuracyRow> {
    let sigma_ref = config.sigma_ref;
    let range = Grid::filled(image.width(), image.height(), 0.0f32);
    let blurred = renderer
        .render(image, &range, &config.medium(), &config.blur)?
        .image;
    let whole = reference::rgb_error(&blurred, expected, 0);
    let margin = (3.0 * sigma_ref).ceil() as usize;
    let interior = reference::rgb_error(&blurred, expected, margin);
    let (var_x, var_y) = impulse.variances(renderer, config)?;
    let s0 = config.blur.sigma0 * config.blur.sigma0;
    let finite = whole.rms.is_finite() && all_finite(&blurred);
    let diverged = !finite || whole.max_abs > value_range.max(f64::EPSILON);
    Ok(AccuracyRow {
        sigma_ref,
        scheme: config.blur.scheme,
        precision: config.blur.precision,
        steps: 0,
        reference_sigma: 0.0,
        rms: whole.rms,
        rms_interior: (interior.samples > 0).then_some(interior.rms),
        interior_margin: margin,
        max_abs: whole.max_abs,
        scale_x: (var_x + s0).sqrt(),
        scale_y: (var_y + s0).sqrt(),
        scale_ratio: ((var_x + var_y) / 2.0 + s0).sqrt() / sigma_ref,
        diverged,
        note: row_note(config, diverged)?,
    })
}

/// Says plainly when a row has nothing to measure or blew up.
fn row_note(config: &Config, diverged: bool) -> Result<Option<String>> {
    if config.schedule()?.steps == 0 {
        return Ok(Some(
            "N = 0: σref = σ0 so there is nothing to diffuse (output = input)".into(),
        ));
    }
    Ok(diverged.then(|| "diverged: output not finite or error beyond the input's range".into()))
}

/// Largest − smallest RGB value of the input: the bound on a blur's error.
fn rgb_value_range(image: &RgbImage) -> f64 {
    let (lo, hi) = image
        .as_slice()
        .iter()
        .flat_map(|p| p.iter())
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    f64::from(hi - lo)
}

fn all_finite(image: &RgbaImage) -> bool {
    image
        .as_slice()
        .iter()
        .all(|p| p[..3].iter().all(|v| v.is_finite()))
}

/// An impulse in the middle of a blank square big enough that the response stays clear
/// of the borders (6σ on every side).
struct Impulse {
    image: RgbImage,
}

impl Impulse {
    fn new(sigma_ref: f64) -> Self {
        let half = (6.0 * sigma_ref).ceil() as usize;
        let side = 2 * half + 1;
        // Height 2π·σ² keeps the response near 1 (module docs).
        let height = (2.0 * std::f64::consts::PI * sigma_ref * sigma_ref) as f32;
        let image = Grid::from_fn(side, side, |x, y| {
            if (x, y) == (half, half) {
                [height; 3]
            } else {
                [0.0; 3]
            }
        });
        Impulse { image }
    }

    /// Renders the impulse with `config` and returns the response's variance along x and
    /// y (red channel).
    fn variances(&self, renderer: &mut Renderer, config: &Config) -> Result<(f64, f64)> {
        let side = self.image.width();
        let range = Grid::filled(side, side, 0.0f32);
        let medium: &dyn Medium = &config.medium();
        let response = renderer
            .render(&self.image, &range, medium, &config.blur)?
            .image;
        Ok(central_variances(&response.map(|p| f64::from(p[0]))))
    }
}

/// Second central moments along x and y of a (non-negative, ideally) weight grid. NaN
/// when the mass is zero or not finite, which marks the row as suspect.
pub fn central_variances(weights: &Grid<f64>) -> (f64, f64) {
    let cells = || {
        (0..weights.height())
            .flat_map(move |y| (0..weights.width()).map(move |x| (x as f64, y as f64)))
            .zip(weights.as_slice().iter().copied())
    };
    let mass: f64 = cells().map(|(_, w)| w).sum();
    if !(mass.is_finite() && mass != 0.0) {
        return (f64::NAN, f64::NAN);
    }
    let mx = cells().map(|((x, _), w)| x * w).sum::<f64>() / mass;
    let my = cells().map(|((_, y), w)| y * w).sum::<f64>() / mass;
    let vx = cells().map(|((x, _), w)| (x - mx).powi(2) * w).sum::<f64>() / mass;
    let vy = cells().map(|((_, y), w)| (y - my).powi(2) * w).sum::<f64>() / mass;
    (vx, vy)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn variances_of_a_known_spread() {
        // Mass 1 at x = 1 and 3 (y = 2): mean 2, var_x 1, var_y 0.
        let g = Grid::from_fn(5, 5, |x, y| {
            if y == 2 && (x == 1 || x == 3) {
                0.5
            } else {
                0.0
            }
        });
        let (vx, vy) = central_variances(&g);
        assert!((vx - 1.0).abs() < 1e-12 && vy.abs() < 1e-12, "{vx} {vy}");
        assert!(central_variances(&Grid::filled(3, 3, 0.0)).0.is_nan());
    }

    #[test]
    fn reference_std_removes_the_inner_scale() {
        assert!((reference_std(5.0, 3.0) - 4.0).abs() < 1e-12);
        assert_eq!(reference_std(1.0, 1.0), 0.0);
    }

    #[test]
    fn impulse_has_room_and_height() {
        let imp = Impulse::new(2.0);
        assert_eq!(imp.image.width(), 25);
        let peak = imp.image.get(12, 12)[0];
        assert!((f64::from(peak) - 8.0 * std::f64::consts::PI).abs() < 1e-4);
    }
}
