//! The diffusion blur's settings: scheme, inner scale σ0, rate limit ρmax and texture
//! precision. The blur takes each pixel's target scale σ from a medium
//! ([`crate::medium`]) and knows nothing else of it; [`crate::schedule`] turns the
//! settings and the medium's largest σ into the N steps.

use crate::error::{check_positive, Error, Result};
use crate::gpu::texture::TexelFormat;
use crate::medium::Medium;
use crate::pipeline::Layout;
use crate::schedule::{Schedule, Scheme};
use std::fmt;
use std::str::FromStr;

/// Default inner scale σ0 (px): reproduces the paper's step counts (13 invariant, 1248 Euler at 25 px).
pub const DEFAULT_SIGMA0: f64 = 1.0;
/// Default maximum rate ρmax: the stability limit of the 4-neighbour update.
pub const DEFAULT_RHO_MAX: f64 = 0.25;
/// Default limit on the diffusion steps N of one render: Euler reaches σ = 100 px with
/// ρmax = 1/4 (the paper's experiments need 1248 at 25 px), and 20,000 passes over a
/// 1600x1120 image take about 13 minutes on llvmpipe. A value that would need more (a
/// tiny ρmax, a huge σ) is refused up front instead of running for hours.
pub const DEFAULT_MAX_STEPS: u32 = 20_000;

/// Float precision of the diffusion textures.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// RGBA32F (IEEE single).
    #[default]
    F32,
    /// RGBA16F (IEEE half).
    F16,
}

impl Precision {
    /// Both precisions, f32 first.
    pub const ALL: [Precision; 2] = [Precision::F32, Precision::F16];

    /// `f32` or `f16`.
    pub fn name(self) -> &'static str {
        match self {
            Precision::F32 => "f32",
            Precision::F16 => "f16",
        }
    }

    /// The format of the pre-multiplied colour targets.
    pub(crate) fn colour_format(self) -> TexelFormat {
        match self {
            Precision::F32 => TexelFormat::Rgba32F,
            Precision::F16 => TexelFormat::Rgba16F,
        }
    }

    /// The format of the second target of a chromatic τ (τ_g, τ_b).
    pub(crate) fn pair_format(self) -> TexelFormat {
        match self {
            Precision::F32 => TexelFormat::Rg32F,
            Precision::F16 => TexelFormat::Rg16F,
        }
    }

    /// The format of the per-pixel rate target.
    pub(crate) fn rate_format(self) -> TexelFormat {
        match self {
            Precision::F32 => TexelFormat::R32F,
            Precision::F16 => TexelFormat::R16F,
        }
    }
}

impl fmt::Display for Precision {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Precision {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Precision::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| Error::invalid("precision", s, "f32 or f16"))
    }
}

/// How the diffusion blur runs.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Blur {
    /// Diffusion scheme.
    pub scheme: Scheme,
    /// Inner scale σ0 of the input (px), > 0.
    pub sigma0: f64,
    /// Rate limit ρmax, in (0, 1/4].
    pub rho_max: f64,
    /// Texture precision of the diffusion passes.
    pub precision: Precision,
    /// The most diffusion steps a render may take ([`DEFAULT_MAX_STEPS`]).
    pub max_steps: u32,
    /// Coarse to fine: once the most blurred pixel has reached this scale (px, at least
    /// [`MIN_COARSE_FROM`]), run the remaining steps at half resolution and blend the
    /// result back ([`Schedule::coarse_start`], `src/pipeline/coarse.rs`); once its scale
    /// has doubled again, at a quarter of the resolution, and so on
    /// ([`Schedule::coarse_levels`]). A medium whose every pixel is blurred past the
    /// detail the half resolution drops ([`Medium::sigma_min`], a uniform blur of
    /// [`crate::schedule::STEP0_COARSE_SIGMA`] px or more) starts at step 0 whatever this
    /// scale ([`Schedule::coarse_start_above`]). Matched scheme, one τ target (a grey τ,
    /// or any τ of a medium whose in-scattered light is uniform,
    /// [`Medium::uniform_inscatter`]) and at least two remaining steps only; `None` (the
    /// library's default): every step at full resolution, the paper's pipeline. The
    /// CLI's and [`crate::photo`]'s default is [`DEFAULT_COARSE_FROM`] ([`Blur::photo`]).
    pub coarse_from: Option<f64>,
}

/// The [`Blur::coarse_from`] that `brume render`, `batch`, `view` and [`crate::photo`] (so
/// the Python package) use unless told `--coarse-from off` (px). The library's [`Blur::default`] keeps the stage off: it is
/// the paper's pipeline, which the f64 reference ([`crate::reference`]) computes exactly.
///
/// 2 px, the aliasing floor (a 2 px blur leaves under 1 % of the band the half-resolution
/// grid cannot hold): against 3 px, 10–25 % less GPU time on photos, for 15–20 % more RMS
/// error at depth edges (README, *Speed*).
pub const DEFAULT_COARSE_FROM: f64 = 2.0;

/// The precision of the coarse stage's levels, whatever the render's: each level's blend
/// subtracts two of its images, and in f16 their rounding took the f16 render past the
/// accuracy budget at σ ≥ 16 px (`bench accuracy`: +12 % interior RMS at 25 px, against
/// −36 % in f32 levels); the levels hold a third of the pixels at most.
pub const COARSE_PRECISION: Precision = Precision::F32;

/// The smallest [`Blur::coarse_from`] (px): below about 2 px the image still has detail
/// at the half resolution's Nyquist frequency, which the 2x2 average would alias.
pub const MIN_COARSE_FROM: f64 = 2.0;

impl Default for Blur {
    fn default() -> Self {
        Blur {
            scheme: Scheme::default(),
            sigma0: DEFAULT_SIGMA0,
            rho_max: DEFAULT_RHO_MAX,
            precision: Precision::default(),
            max_steps: DEFAULT_MAX_STEPS,
            coarse_from: None,
        }
    }
}

impl Blur {
    /// The blur of a photo: the default with the coarse-to-fine stage from
    /// [`DEFAULT_COARSE_FROM`], as `brume render` and [`crate::photo::FogOptions`] use it.
    pub fn photo() -> Self {
        Blur {
            coarse_from: Some(DEFAULT_COARSE_FROM),
            ..Blur::default()
        }
    }

    /// The default blur with another scheme and precision.
    pub fn new(scheme: Scheme, precision: Precision) -> Self {
        Blur {
            scheme,
            precision,
            ..Blur::default()
        }
    }

    /// Checks `medium` and plans the schedule that reaches the largest σ it asks for: what
    /// the GPU pipeline and the CPU reference both run.
    pub fn schedule_for(&self, medium: &dyn Medium) -> Result<Schedule> {
        medium.validate()?;
        self.schedule(
            medium.sigma_max(self.sigma0),
            &format!("blur scale of {}", medium.name()),
        )
    }

    /// Checks σ0 (finite, > 0), ρmax (in (0, 1/4]) and [`Blur::coarse_from`] before any
    /// work, naming the field; planning a schedule checks them too.
    pub fn validate(&self) -> Result<()> {
        check_positive("sigma0", self.sigma0)?;
        crate::schedule::check_rate_limit(self.rho_max)?;
        self.check_coarse_from()
    }

    /// Rejects a [`Blur::coarse_from`] that is not a finite scale ≥ [`MIN_COARSE_FROM`]
    /// (`None` passes), naming `coarse_from`.
    pub fn check_coarse_from(&self) -> Result<()> {
        match self.coarse_from {
            Some(from) if !(from.is_finite() && from >= MIN_COARSE_FROM) => Err(Error::invalid(
                "coarse_from",
                from,
                format!(
                    "a finite scale ≥ {MIN_COARSE_FROM} px (below it the half resolution \
                     aliases detail), or none"
                ),
            )),
            _ => Ok(()),
        }
    }

    /// The step from which `schedule` runs at half resolution, if
    /// [`Blur::coarse_from`] asks for it and the stage applies to `medium` (see the field;
    /// step 0 when its [`Medium::sigma_min`] is at least
    /// [`crate::schedule::STEP0_COARSE_SIGMA`]); an error names `coarse_from` when it is
    /// not a finite scale ≥ [`MIN_COARSE_FROM`].
    pub fn coarse_start(&self, schedule: &Schedule, medium: &dyn Medium) -> Result<Option<u32>> {
        self.check_coarse_from()?;
        let Some(from) = self.coarse_from else {
            return Ok(None);
        };
        Ok(if Layout::of(medium).tau_pair() {
            None
        } else {
            schedule.coarse_start_above(from, medium.sigma_min(self.sigma0))
        })
    }

    /// Bytes per full-resolution pixel that the coarse stage's levels may take for
    /// `medium` (0 when [`Blur::coarse_from`] is off or the stage does not apply to it):
    /// every level ([`crate::schedule::MAX_COARSE_LEVELS`]) holds three colour targets
    /// and, unless ρ travels in their alpha ([`Medium::uniform_inscatter`]), a rate in
    /// [`COARSE_PRECISION`] on a quarter of the pixels of the level above, Σ 4^−ℓ < ⅓
    /// of one such texel per pixel, rounded up. The memory check adds it to the frame's
    /// own textures (`Renderer`, [`crate::memory`]).
    pub fn coarse_bytes_per_pixel(&self, medium: &dyn Medium) -> u64 {
        self.coarse_bytes_in(Layout::of(medium))
    }

    /// [`Blur::coarse_bytes_per_pixel`] for a frame in `layout`.
    fn coarse_bytes_in(&self, layout: Layout) -> u64 {
        if self.coarse_from.is_none() || layout.tau_pair() {
            return 0;
        }
        let texel = |format: TexelFormat| format.bytes_per_texel() as u64;
        let rate = if layout.rate_in_alpha() {
            0
        } else {
            texel(COARSE_PRECISION.rate_format())
        };
        (3 * texel(COARSE_PRECISION.colour_format()) + rate).div_ceil(3)
    }

    /// The N-step schedule that takes σ0 to `sigma_max`, the largest scale a medium asks
    /// for; a medium asking for less than σ0, or for more than [`Blur::max_steps`] steps,
    /// is an error naming `what` (or `rho_max`, when a small ρmax is the cause).
    pub fn schedule(&self, sigma_max: f64, what: &str) -> Result<Schedule> {
        check_positive("sigma0", self.sigma0)?;
        if !(sigma_max.is_finite() && sigma_max >= self.sigma0) {
            return Err(Error::invalid(
                what,
                sigma_max,
                format!("a finite scale ≥ sigma0 = {} px", self.sigma0),
            ));
        }
        let schedule = Schedule::new(self.scheme, self.sigma0, sigma_max, self.rho_max)?;
        if schedule.steps > self.max_steps {
            let (name, value) = if self.rho_max < DEFAULT_RHO_MAX {
                ("rho_max", self.rho_max)
            } else {
                (what, sigma_max)
            };
            let needs = if schedule.steps == u32::MAX {
                "more than 4 billion".to_string()
            } else {
                schedule.steps.to_string()
            };
            let remedy = if self.scheme == Scheme::Euler {
                "use the matched scheme (steps grow as log σ, not σ²), raise rho_max (≤ 0.25) \
                 or ask for less blur"
            } else {
                "raise rho_max (≤ 0.25) or ask for less blur"
            };
            return Err(Error::invalid(
                name,
                value,
                format!(
                    "a blur of at most {} diffusion steps (max_steps); the {} scheme needs \
                     {needs} here: {remedy}",
                    self.max_steps, self.scheme
                ),
            ));
        }
        Ok(schedule)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coarse_levels_counted_only_when_they_can_run() {
        let on = Blur {
            coarse_from: Some(DEFAULT_COARSE_FROM),
            ..Blur::default()
        };
        let grey = Layout::Premultiplied { chromatic: false };
        // f32 levels: three RGBA32F targets and an R32F rate, 52 bytes, on ⅓ of the pixels.
        assert_eq!(on.coarse_bytes_in(grey), 18);
        // The same in f16: the levels stay f32.
        let half = Blur {
            precision: Precision::F16,
            ..on
        };
        assert_eq!(half.coarse_bytes_in(grey), 18);
        // ρ in the colour's alpha: three RGBA32F targets, 48 bytes.
        assert_eq!(on.coarse_bytes_in(Layout::Offset), 16);
        let chromatic = Layout::Premultiplied { chromatic: true };
        assert_eq!(on.coarse_bytes_in(chromatic), 0);
        assert_eq!(Blur::default().coarse_bytes_in(grey), 0);
    }

    #[test]
    fn validate_names_the_field_that_is_out_of_range() {
        assert!(Blur::default().validate().is_ok());
        assert!(Blur::photo().validate().is_ok());
        let refused = |change: fn(&mut Blur), field: &str| {
            let mut blur = Blur::default();
            change(&mut blur);
            match blur.validate() {
                Err(Error::InvalidParameter { name, .. }) => assert_eq!(name, field, "{blur:?}"),
                other => panic!("{blur:?}: {other:?}"),
            }
        };
        refused(|b| b.sigma0 = 0.0, "sigma0");
        refused(|b| b.sigma0 = f64::NAN, "sigma0");
        refused(|b| b.rho_max = 0.3, "rho_max");
        refused(|b| b.rho_max = 0.0, "rho_max");
        refused(|b| b.coarse_from = Some(1.0), "coarse_from");
        refused(|b| b.coarse_from = Some(f64::INFINITY), "coarse_from");
    }
}
