//! The diffusion schedule: how many steps (N), the per-pixel rate ρ(x), and the per-step
//! neighbour offset h_k(x). This module is the single source of truth for that math: the
//! GPU pipeline uploads the rates and the offset law's uniforms from here, and the CPU
//! reference evaluates exactly the same functions in f64.
//!
//! All three schemes run the same update (paper 000, eq. 11-12):
//!
//! ```text
//! F(x, k+1) = F(x, k) + Σ_u ½(ρ(x+u) + ρ(x)) (F(x+u, k) − F(x, k)),  u ∈ {(±h_k, 0), (0, ±h_k)}
//! ```
//!
//! and differ only in N, ρ(x) and h_k(x):
//!
//! | scheme | N | ρ(x) | h_k(x) |
//! | --- | --- | --- | --- |
//! | `euler` (eq. 13) | ⌈(σmax² − σ0²) / 2ρmax⌉ | (σ² − σ0²) / 2N | 1 |
//! | `invariant` (eq. 18) | ⌈ln(σmax/σ0) / ρmax⌉ | ln(σ/σ0) / N | σ0·e^(kρ) |
//! | `matched` | as `invariant` | as `invariant` | m⁻¹(σ0²·e^(2kρ)·(e^(2ρ) − 1)/(2ρ)) |
//!
//! **Why `matched`.** With uniform ρ, one step adds variance 2ρ·m(h) per axis, where m(h) is
//! the second moment of a bilinear fetch at distance h: m(i + f) = (i + f)² + f(1 − f) =
//! i² + (2i + 1)f for integer i and f ∈ [0, 1) (bilinear interpolation spreads the sample
//! over two texels). The literal invariant scheme takes h_k = σk, so the variance grows by
//! (1 + 2ρ) per step instead of e^(2ρ) and the result under-blurs (see `bilinear_moment`). The
//! matched schedule keeps the paper's N and ρ(x) but picks h_k(x) so that step k adds
//! exactly σk+1² − σk² with σk = σ0·e^(kρ): after N steps the variance is σ(x)² − σ0² +
//! σ0² = σ(x)², bilinear spread included. m is piecewise linear and increasing, so m⁻¹
//! is exact and cheap: i = ⌊√m⌋, h = i + (m − i²)/(2i + 1).
//!
//! **Only ρ is per pixel.** Every scheme's offset is a function of the pixel's rate and the
//! step ([`OffsetLaw`]):
//!
//! ```text
//! t_k(ρ) = scale · e^(c_k·ρ),  c_k = (k + shift)·growth
//! h_k(ρ) = t_k(ρ)                         (euler, invariant)
//! h_k(ρ) = m⁻¹(t_k(ρ)² · sinh(ρ)/ρ)       (matched)
//! ```
//!
//! with (scale, growth, shift) = (1, 0, 0) for euler, (σ0, 1, 0) for invariant and
//! (σ0, 1, ½) for matched, since σ0²·e^((2k+1)ρ)·sinh(ρ)/ρ = σ0²·e^(2kρ)·(e^(2ρ) − 1)/(2ρ).
//! So the GPU needs one rate texture and two uniforms per pass (scale, c_k), not a
//! per-pixel law texture: a texture fewer to stream through every pass, 9 % of a pass on
//! llvmpipe. `glsl/diffuse.frag` evaluates [`OffsetLaw::offset`] in f32, with the Taylor
//! series of sinh(ρ)/ρ to ρ⁶ (exact to 5e-11 for ρ ≤ ¼, where the closed form
//! (e^(2ρ) − 1)/(2ρ) would cancel catastrophically in f32) and the matched branch chosen
//! when the shader is compiled; `tests/diffuse_shader.rs` runs the shader's offset law and
//! one of its passes on the GL driver against [`OffsetLaw`], and `tests/gpu_vs_cpu.rs`
//! compares the whole pipeline with the f64 reference.

use crate::error::{check_positive, Error, Result};
use std::fmt;
use std::str::FromStr;

/// A diffusion scheme: how the per-step offsets and per-pixel rates are chosen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Scheme {
    /// Forward Euler with unit offsets (paper 000, eq. 13). Slow at large scales.
    Euler,
    /// The scale-invariant scheme exactly as the paper writes it (eq. 18): offsets σk.
    /// Under-blurs: the variance grows by (1 + 2ρ) per step, not e^(2ρ).
    Invariant,
    /// The invariant scheme's N and rates with offsets chosen so that the variance,
    /// bilinear spread included, reaches σ(x)² exactly. The default.
    #[default]
    Matched,
}

impl Scheme {
    /// All schemes, in the order reports list them.
    pub const ALL: [Scheme; 3] = [Scheme::Euler, Scheme::Invariant, Scheme::Matched];

    /// The lowercase name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Scheme::Euler => "euler",
            Scheme::Invariant => "invariant",
            Scheme::Matched => "matched",
        }
    }
}

impl fmt::Display for Scheme {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Scheme {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Scheme::ALL
            .into_iter()
            .find(|scheme| scheme.name() == s)
            .ok_or_else(|| Error::invalid("scheme", s, "one of euler, invariant, matched"))
    }
}

/// How a scheme turns a pixel's rate ρ and the step k into the neighbour offset h_k (see
/// the module docs): t = scale·e^(c_k·ρ) with c_k = (k + shift)·growth, and h = t, or
/// h = m⁻¹(t²·sinh(ρ)/ρ) when `matched`. The shader takes (scale, c_k) as the uniform
/// `u_law` of each pass and `matched` as a compile-time switch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OffsetLaw {
    /// Offset at step 0, before the matched correction (px).
    pub scale: f64,
    /// 1 when the offset grows geometrically with the step, 0 when it is constant.
    pub growth: f64,
    /// Step shift: ½ for `matched`, whose step k spans σk to σk+1.
    pub shift: f64,
    /// Whether the offset is variance-matched: h = m⁻¹(t²·sinh(ρ)/ρ).
    pub matched: bool,
}

impl OffsetLaw {
    /// h_k for a pixel of rate `rate`.
    pub fn offset(&self, rate: f64, k: u32) -> f64 {
        let t = self.scale * (self.step_coefficient(k) * rate).exp();
        if self.matched {
            offset_for_moment(t * t * sinhc(rate))
        } else {
            t
        }
    }

    /// c_k = (k + shift)·growth, the exponent of step k per unit of rate.
    pub fn step_coefficient(&self, k: u32) -> f64 {
        (f64::from(k) + self.shift) * self.growth
    }

    /// (scale, c_k) in f32, as the shader's `u_law` takes them for step `k`.
    pub fn uniform(&self, k: u32) -> [f32; 2] {
        [self.scale as f32, self.step_coefficient(k) as f32]
    }
}

/// sinh(ρ)/ρ, with its limit 1 at ρ = 0.
fn sinhc(rate: f64) -> f64 {
    if rate.abs() < 1e-8 {
        1.0
    } else {
        rate.sinh() / rate
    }
}

/// A schedule for one render: the scheme, σ0, ρmax and the number of steps N that takes
/// the largest scale σmax from σ0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schedule {
    /// The scheme.
    pub scheme: Scheme,
    /// Inner scale σ0 of the input (px).
    pub sigma0: f64,
    /// Largest target scale (px) over the image.
    pub sigma_max: f64,
    /// Upper limit of the rate (1/4 for stability of the 4-neighbour update).
    pub rho_max: f64,
    /// Number of diffusion steps N.
    pub steps: u32,
}

/// Accepts a rate limit ρmax in (0, 1/4], or names `rho_max`.
pub(crate) fn check_rate_limit(rho_max: f64) -> Result<()> {
    if rho_max > 0.0 && rho_max <= 0.25 {
        return Ok(());
    }
    Err(Error::invalid(
        "rho_max",
        rho_max,
        "a rate in (0, 0.25] (larger rates make the 4-neighbour update unstable)",
    ))
}

impl Schedule {
    /// Plans the N steps that take σ0 to `sigma_max` under `scheme` with rates ≤ `rho_max`
    /// (paper 000, eq. 13 and eq. 18).
    pub fn new(scheme: Scheme, sigma0: f64, sigma_max: f64, rho_max: f64) -> Result<Self> {
        check_positive("sigma0", sigma0)?;
        check_positive("sigma_max", sigma_max)?;
        check_rate_limit(rho_max)?;
        if sigma_max < sigma0 {
            return Err(Error::invalid(
                "sigma_max",
                sigma_max,
                format!("at least the inner scale σ0 = {sigma0}"),
            ));
        }
        let steps = match scheme {
            Scheme::Euler => ((sigma_max * sigma_max - sigma0 * sigma0) / (2.0 * rho_max)).ceil(),
            Scheme::Invariant | Scheme::Matched => ((sigma_max / sigma0).ln() / rho_max).ceil(),
        };
        // Rounding guard: a ratio that is a hair above an integer must not add a step.
        let steps = steps.max(0.0) as u32;
        Ok(Schedule {
            scheme,
            sigma0,
            sigma_max,
            rho_max,
            steps,
        })
    }

    /// The rate ρ of a pixel whose target scale is `sigma` (clamped to [σ0, σmax]): eq. 13
    /// for `euler`, eq. 18 for `invariant` and `matched`.
    pub fn rate(&self, sigma: f64) -> f64 {
        let sigma = sigma.clamp(self.sigma0, self.sigma_max);
        if self.steps == 0 {
            return 0.0;
        }
        let n = f64::from(self.steps);
        match self.scheme {
            Scheme::Euler => (sigma * sigma - self.sigma0 * self.sigma0) / (2.0 * n),
            Scheme::Invariant | Scheme::Matched => (sigma / self.sigma0).ln() / n,
        }
    }

    /// The offset law of this schedule's scheme.
    pub fn offset_law(&self) -> OffsetLaw {
        let (scale, growth, shift) = match self.scheme {
            Scheme::Euler => (1.0, 0.0, 0.0),
            Scheme::Invariant => (self.sigma0, 1.0, 0.0),
            Scheme::Matched => (self.sigma0, 1.0, 0.5),
        };
        OffsetLaw {
            scale,
            growth,
            shift,
            matched: self.scheme == Scheme::Matched,
        }
    }

    /// Offset h_k of step `k` for a pixel of rate `rate`.
    pub fn offset(&self, rate: f64, k: u32) -> f64 {
        self.offset_law().offset(rate, k)
    }

    /// The step k0 from which the coarse stage runs the steps at half resolution
    /// ([`crate::Blur::coarse_from`]): the first step at which the most blurred pixel
    /// (σ = σmax) has reached `from` px, σk = σ0·e^(k·ρ(σmax)). `None` when the stage would
    /// not pay (fewer than [`MIN_COARSE_STEPS`] steps left after k0) or cannot be exact in
    /// its variance (only the matched scheme's offsets keep the variance of a step when
    /// its offsets are halved: its law inverts the bilinear moment, the others' do not).
    pub fn coarse_start(&self, from: f64) -> Option<u32> {
        if !self.coarse_applies() {
            return None;
        }
        let top = self.rate(self.sigma_max);
        // A scale within COARSE_FROM_TOLERANCE of `from` has reached it; so `from` landing
        // exactly on a step starts there, whatever the rounding of the logarithms.
        let target = (from / self.sigma0).ln() - COARSE_FROM_TOLERANCE.ln_1p();
        let start = (target / top).ceil().max(0.0) as u32;
        (self.steps.saturating_sub(start) >= MIN_COARSE_STEPS).then_some(start)
    }

    /// [`Schedule::coarse_start`] for a frame whose every pixel asks for σ ≥ `sigma_min`
    /// ([`crate::medium::Medium::sigma_min`]): step 0 from [`STEP0_COARSE_SIGMA`] (a
    /// uniform blur of 10 px or more), because the full-resolution steps would only
    /// pre-blur what the 2x2 average then takes away; otherwise where σmax reaches `from`.
    pub fn coarse_start_above(&self, from: f64, sigma_min: f64) -> Option<u32> {
        if self.coarse_applies() && sigma_min >= STEP0_COARSE_SIGMA {
            return Some(0);
        }
        self.coarse_start(from)
    }

    /// Whether the coarse stage can run this schedule at all: the matched scheme, whose
    /// offsets keep a step's variance when halved (its law inverts the bilinear moment;
    /// the others' do not), with [`MIN_COARSE_STEPS`] steps at least.
    fn coarse_applies(&self) -> bool {
        self.scheme == Scheme::Matched && self.steps >= MIN_COARSE_STEPS
    }

    /// The weight a(ρ) = exp(−π²/8·(σN² − σk0²)) with which the coarse stage's blend puts
    /// back the detail the half resolution lost, for a pixel of rate `rate` (see
    /// `glsl/coarse_blend.frag`): the Gaussian transfer of the variance steps k0..N add,
    /// σk² = σ0²·e^(2kρ), at a quarter of a cycle per pixel, the centre of the band a 2x2
    /// average removes.
    pub fn detail_weight(&self, rate: f64, start: u32) -> f64 {
        self.level_detail_weight(1, rate, start)
    }

    /// The weight with which the blend of coarse level `level` (1: half resolution) back
    /// into the level above puts back the detail that level's 2x2 average removed, for a
    /// pixel of rate `rate` and a level that started at step `start`: as
    /// [`Schedule::detail_weight`] at the centre of that band, a quarter of a cycle per
    /// texel of the finer level, 2^(1−ℓ)/4 cycle per px ([`level_detail_decay`]).
    pub fn level_detail_weight(&self, level: u32, rate: f64, start: u32) -> f64 {
        let variance = |k: u32| self.sigma0 * self.sigma0 * (2.0 * f64::from(k) * rate).exp();
        (-level_detail_decay(level) * (variance(self.steps) - variance(start))).exp()
    }
}

impl Schedule {
    /// The factor on the offset law's scale of the coarse stage's first level's steps
    /// from `start` to N: [`Schedule::level_scale`] of a single half-resolution level.
    pub fn coarse_scale(&self, start: u32) -> f64 {
        self.level_scale(1, start, self.steps)
    }

    /// The factor on the offset law's scale of the steps `start..end` that run at coarse
    /// level `level` (1: half resolution, 2: quarter, …): the level's 2x2 average and its
    /// bilinear up-sampling add [`level_resampling_variance`] px² to whatever it blurs, so
    /// its steps add that much less (the matched law's variance per step is proportional
    /// to scale²). Exact for the most blurred pixels, whose detail the blends drop; a
    /// pixel whose detail comes back (a ≈ 1) is blurred by the stage about as much as it
    /// asked for (σN² − σk0² small), and one in between by up to (1 − a) times the
    /// resampling variance more.
    pub fn level_scale(&self, level: u32, start: u32, end: u32) -> f64 {
        let top = self.rate(self.sigma_max);
        let variance = |k: u32| self.sigma0 * self.sigma0 * (2.0 * f64::from(k) * top).exp();
        let added = variance(end) - variance(start);
        if added <= 0.0 {
            return 0.0;
        }
        (1.0 - level_resampling_variance(level) / added)
            .max(0.0)
            .sqrt()
    }

    /// The steps at which the coarse stage's levels start, given the first level's start
    /// (from [`Schedule::coarse_start`]): level 1 (half resolution) at `first`, and a
    /// level ℓ + 1 at half of level ℓ's resolution once the most blurred pixel's scale has
    /// doubled since level ℓ began, k ≥ kℓ + ln 2 / ρ(σmax): the blur, counted in the new
    /// level's pixels, is then at least what it was in level ℓ's pixels when that level
    /// began (≥ `coarse_from`), so every level holds as little detail at its Nyquist
    /// frequency as the first. A level is added only when it leaves
    /// [`MIN_COARSE_STEPS`] steps after its start, and at most [`MAX_COARSE_LEVELS`].
    pub fn coarse_levels(&self, first: u32) -> Vec<u32> {
        let top = self.rate(self.sigma_max);
        let mut starts = vec![first];
        if top <= 0.0 {
            return starts;
        }
        let doubling = (std::f64::consts::LN_2 - COARSE_FROM_TOLERANCE.ln_1p()) / top;
        while starts.len() < MAX_COARSE_LEVELS {
            let last = f64::from(*starts.last().expect("one level at least"));
            // The tolerance in `doubling`: a doubling that lands on a step starts there.
            let next = (last + doubling).ceil() as u32;
            if self.steps.saturating_sub(next) < MIN_COARSE_STEPS {
                break;
            }
            starts.push(next);
        }
        starts
    }
}

/// Variance (full-resolution px² per axis) of coarse level `level`'s resampling (level 1:
/// half resolution): a level-ℓ texel is 2^ℓ px, its 2x2 average adds ¼ of the finer
/// level's texel² and the bilinear up-sampling at a quarter and three quarters of a texel
/// f(1 − f) = 3/16 of its own texel²: 4^(ℓ−1)·(¼ + ¾) = 4^(ℓ−1) px².
pub fn level_resampling_variance(level: u32) -> f64 {
    COARSE_RESAMPLING_VARIANCE * 4f64.powi(level.saturating_sub(1) as i32)
}

/// The most levels the coarse stage recurses to: half and quarter resolution. A third
/// level (an eighth) takes the last 2-4 steps of σ 25 from a sixteenth of the pixels to a
/// sixty-fourth: predicted no gain (its own down and blend passes cost about what it
/// saves), measured 0.50 of full resolution against 0.55 with two levels from 3 px and
/// 0.40 against 0.41 from 2 px (`bench speed`, 1600x1120, 5 rounds on a loaded machine,
/// README's speed section). But each level spreads the coarse increment twice as far
/// across a depth edge: on the space-variant haze of `tests/coarse.rs` the error against
/// the f64 reference grew from RMS 7.4e-3 to 8.2e-3 (from 2 px) with it. Two levels keep
/// most of the gain for a smaller error.
pub const MAX_COARSE_LEVELS: usize = 2;

/// Variance (full-resolution px² per axis) of the coarse stage's resampling: ¼ for the
/// 2x2 box average, ¾ for bilinear up-sampling at a quarter and three quarters of a
/// half-resolution texel (f(1 − f) = 3/16 half texel² = ¾ px²).
pub const COARSE_RESAMPLING_VARIANCE: f64 = 1.0;

/// How far (relative) short of [`crate::Blur::coarse_from`] the most blurred pixel's
/// scale may be and still count as having reached it ([`Schedule::coarse_start`]): σmax
/// comes from a range, λ and κs and is shown to two decimals, and a σmax of 7.996 px (the
/// viewer's `--lambda 8.08`, "σmax 8.00 px") gave σ3 = 1.9997 px, which made a 2 px stage
/// start one full-resolution step later than σmax 8.000 (about a tenth of that frame's GPU
/// time) for an aliasing residue at the half resolution's band 0.15 % larger. A scale
/// 0.1 % short leaves 1 % more of that residue at 2 px (exp(π²/8·2·10⁻³·σ²)). The levels'
/// doublings ([`Schedule::coarse_levels`]) take the same tolerance.
pub const COARSE_FROM_TOLERANCE: f64 = 1e-3;

/// The least σ (px) that every pixel of a frame must ask for for the coarse stage to
/// start at step 0 ([`Schedule::coarse_start_above`]). No pixel then keeps any of its
/// full-resolution detail (its blend weight is below 1e-50), but the 2x2 average of an
/// unblurred image aliases its finest detail into the half resolution, and only the blur
/// that follows takes the aliased band down, as 1/σ. Measured on white noise, the worst
/// case (`tests/coarse.rs`, interior RMS against the exact Gaussian, f32), starting at step
/// 0 against full resolution: +112 % at 3 px, +138 % at 4, +39 % at 5, +20 % at 8, −10 %
/// at 12 (160x128 px); +2 % at 9, −2 % at 10 (256x224 px, another noise), where issue
/// 21's accuracy budget is +10 %. (`bench accuracy`'s photo, with little energy near the
/// Nyquist frequency, stays within it from 3 px.)
pub const STEP0_COARSE_SIGMA: f64 = 10.0;

/// The fewest steps the coarse stage must take over to pay for its two passes (a 2x2
/// average and the blend): each half-resolution step costs a quarter of a full one.
pub const MIN_COARSE_STEPS: u32 = 2;

/// 2π²·(1/4)²: the exponent per px² of variance of a Gaussian's transfer at a quarter of
/// a cycle per pixel ([`Schedule::detail_weight`]).
pub const DETAIL_DECAY: f64 = std::f64::consts::PI * std::f64::consts::PI / 8.0;

/// [`DETAIL_DECAY`] for coarse level `level`'s blend: the band its average removes is
/// centred 2^(ℓ−1) times lower in frequency than the first level's, so the exponent per px²
/// is 4^(ℓ−1) times smaller.
pub fn level_detail_decay(level: u32) -> f64 {
    DETAIL_DECAY / 4f64.powi(level.saturating_sub(1) as i32)
}

/// m(h): the second moment of a bilinear fetch at distance `h` ≥ 0 from the pixel centre.
pub fn bilinear_moment(h: f64) -> f64 {
    let i = h.floor();
    let f = h - i;
    i * i + (2.0 * i + 1.0) * f
}

/// m⁻¹: the bilinear offset whose second moment is `m` ≥ 0.
pub fn offset_for_moment(m: f64) -> f64 {
    let i = m.sqrt().floor();
    i + (m - i * i) / (2.0 * i + 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_step_counts() {
        // The paper: σ0 = 1, ρmax = 1/4, σmax = 25 → 13 invariant steps, "more than 900" Euler.
        let inv = Schedule::new(Scheme::Invariant, 1.0, 25.0, 0.25).unwrap();
        let eul = Schedule::new(Scheme::Euler, 1.0, 25.0, 0.25).unwrap();
        assert_eq!(inv.steps, 13);
        assert_eq!(eul.steps, 1248);
    }

    #[test]
    fn rates_stay_below_rho_max() {
        for scheme in Scheme::ALL {
            let s = Schedule::new(scheme, 1.0, 17.3, 0.25).unwrap();
            for sigma in [1.0, 2.0, 9.5, 17.3] {
                let rate = s.rate(sigma);
                assert!((0.0..=0.25 + 1e-12).contains(&rate), "{scheme} {sigma}");
            }
        }
    }

    #[test]
    fn moment_inverse_round_trips() {
        for i in 0..2000 {
            let h = i as f64 * 0.0137;
            let back = offset_for_moment(bilinear_moment(h));
            assert!((back - h).abs() < 1e-9, "h = {h} came back as {back}");
        }
    }

    #[test]
    fn matched_variance_reaches_target() {
        // Sum of per-step variances 2ρ·m(h_k) must equal σ² − σ0² for every σ.
        let s = Schedule::new(Scheme::Matched, 1.0, 25.0, 0.25).unwrap();
        for sigma in [1.5, 3.0, 8.0, 25.0] {
            let rate = s.rate(sigma);
            let added: f64 = (0..s.steps)
                .map(|k| 2.0 * rate * bilinear_moment(s.offset(rate, k)))
                .sum();
            let want = sigma * sigma - 1.0;
            assert!(
                (added - want).abs() < 1e-9 * want,
                "{sigma}: {added} vs {want}"
            );
        }
    }

    #[test]
    fn literal_invariant_under_blurs() {
        let s = Schedule::new(Scheme::Invariant, 1.0, 25.0, 0.25).unwrap();
        let rate = s.rate(25.0);
        let added: f64 = (0..s.steps)
            .map(|k| 2.0 * rate * s.offset(rate, k).powi(2))
            .sum();
        assert!(added < 0.9 * (625.0 - 1.0), "added {added}");
    }

    #[test]
    fn offset_laws_match_the_paper() {
        let s = |scheme| Schedule::new(scheme, 1.5, 25.0, 0.25).unwrap();
        let rate = 0.2;
        for k in [0, 1, 7] {
            let kf = f64::from(k);
            assert_eq!(s(Scheme::Euler).offset(rate, k), 1.0);
            let inv = s(Scheme::Invariant).offset(rate, k);
            assert!(
                (inv - 1.5 * (kf * rate).exp()).abs() < 1e-12,
                "eq. 18 at k = {k}"
            );
            // matched: m(h_k) = σk² (e^(2ρ) − 1) / (2ρ), σk = σ0 e^(kρ).
            let want = 2.25 * (2.0 * kf * rate).exp() * (2.0 * rate).exp_m1() / (2.0 * rate);
            let got = bilinear_moment(s(Scheme::Matched).offset(rate, k));
            assert!(
                (got - want).abs() < 1e-12 * want,
                "k = {k}: {got} vs {want}"
            );
        }
    }

    /// The truncation error of the Taylor series to ρ⁶ that `glsl/diffuse.frag` uses for
    /// sinh(ρ)/ρ, over the whole rate range: below 5e-11 (the claim of the module docs and
    /// of the shader's comment; the next term, ρ⁸/9!, is 4.2e-11 at ρ = ¼), 2000 times
    /// below an f32 ULP at 1. This checks the mathematics in f64 only; the shader's own f32
    /// evaluation runs on the GL driver in `tests/diffuse_shader.rs`.
    #[test]
    fn sinhc_series_truncation_is_far_below_f32_resolution() {
        let series = |r: f64| {
            let r2 = r * r;
            1.0 + r2 * (1.0 / 6.0 + r2 * (1.0 / 120.0 + r2 / 5040.0))
        };
        let mut worst: f64 = 0.0;
        for i in 0..=1000 {
            let r = 0.25 * f64::from(i) / 1000.0;
            let err = (series(r) - sinhc(r)).abs();
            worst = worst.max(err);
            assert!(err < 5e-11, "ρ = {r}: error {err}");
        }
        // The bound is the truncation's, not slack: at ρ = ¼ the error is the next term's.
        let next_term = 0.25f64.powi(8) / 362_880.0;
        assert!(
            (worst - next_term).abs() < 0.1 * next_term,
            "{worst} vs {next_term}"
        );
    }

    #[test]
    fn coarse_start_is_where_sigma_max_reaches_the_scale() {
        let s = Schedule::new(Scheme::Matched, 1.0, 25.0, 0.25).unwrap();
        // σk = 25^(k/13): 3.44 px at k = 5, 2.10 at 3, 4.42 at 6.
        assert_eq!(s.coarse_start(3.0), Some(5));
        assert_eq!(s.coarse_start(2.0), Some(3));
        assert_eq!(s.coarse_start(4.0), Some(6));
        // Landing exactly on a step starts there, not one later; so does landing within
        // the tolerance below it, and not beyond.
        assert_eq!(s.coarse_start(25f64.powf(5.0 / 13.0)), Some(5));
        let sigma5 = 25f64.powf(5.0 / 13.0);
        assert_eq!(
            s.coarse_start(sigma5 * (1.0 + 0.9 * COARSE_FROM_TOLERANCE)),
            Some(5)
        );
        assert_eq!(
            s.coarse_start(sigma5 * (1.0 + 1.1 * COARSE_FROM_TOLERANCE)),
            Some(6)
        );
        // The viewer's frame: σmax 7.996 reaches 1.9997 px at k = 3 of 9.
        let viewer = Schedule::new(Scheme::Matched, 1.0, 7.996, 0.25).unwrap();
        assert_eq!(viewer.steps, 9);
        assert_eq!(viewer.coarse_start(2.0), Some(3));
        assert_eq!(viewer.coarse_levels(3), vec![3, 6]);
        // Too few steps left, or a scheme whose offsets do not scale exactly: no stage.
        assert_eq!(s.coarse_start(20.0), None);
        for scheme in [Scheme::Euler, Scheme::Invariant] {
            let other = Schedule::new(scheme, 1.0, 25.0, 0.25).unwrap();
            assert_eq!(other.coarse_start(3.0), None, "{scheme}");
        }
    }

    #[test]
    fn coarse_starts_at_step_zero_only_where_every_pixel_is_blurred_enough() {
        let s = Schedule::new(Scheme::Matched, 1.0, 25.0, 0.25).unwrap();
        // A uniform 25 px (σmin = σmax), from any scale: no full-resolution step.
        assert_eq!(s.coarse_start_above(2.0, 25.0), Some(0));
        assert_eq!(s.coarse_start_above(4.0, STEP0_COARSE_SIGMA), Some(0));
        // Pixels asking for less (a haze's σ0 at range 0): where σmax reaches `from`.
        assert_eq!(s.coarse_start_above(2.0, 1.0), Some(3));
        assert_eq!(
            s.coarse_start_above(2.0, 0.99 * STEP0_COARSE_SIGMA),
            Some(3)
        );
        // Step 0 leaves every step to the stage even where `from` would leave too few.
        let u = Schedule::new(Scheme::Matched, 1.0, 12.0, 0.25).unwrap();
        assert_eq!(u.coarse_start(11.0), None);
        assert_eq!(u.coarse_start_above(11.0, 12.0), Some(0));
        // Never for a scheme the stage cannot run.
        let e = Schedule::new(Scheme::Invariant, 1.0, 25.0, 0.25).unwrap();
        assert_eq!(e.coarse_start_above(2.0, 25.0), None);
    }

    #[test]
    fn coarse_scale_takes_the_resampling_variance_off() {
        let s = Schedule::new(Scheme::Matched, 1.0, 25.0, 0.25).unwrap();
        let start = s.coarse_start(3.0).unwrap();
        let top = s.rate(25.0);
        let shrink = s.coarse_scale(start);
        // The half-resolution steps add shrink² of each step's variance (scale² law):
        let added: f64 = (start..s.steps)
            .map(|k| 2.0 * top * bilinear_moment(s.offset(top, k)))
            .sum();
        let want = added - COARSE_RESAMPLING_VARIANCE;
        assert!((shrink * shrink * added - want).abs() < 1e-9 * want);
    }

    #[test]
    fn coarse_levels_start_where_the_top_scale_doubles() {
        // σ 25, N = 13, σk = 25^(k/13): a level starts once σk has doubled since the
        // previous level began (ln 2 / ρ = 2.8 steps), and only with 2 steps left after it.
        let s = Schedule::new(Scheme::Matched, 1.0, 25.0, 0.25).unwrap();
        assert_eq!(s.coarse_levels(5), vec![5, 8]); // σ 3.44, 7.18 (then 15.0 at 11)
        assert_eq!(s.coarse_levels(3), vec![3, 6]); // (9; 12 would leave 1 step)
        let sigma = |k: u32| 25f64.powf(f64::from(k) / 13.0);
        for pair in s.coarse_levels(3).windows(2) {
            assert!(sigma(pair[1]) >= 2.0 * sigma(pair[0]) - 1e-9, "{pair:?}");
            assert!(
                sigma(pair[1] - 1) < 2.0 * sigma(pair[0]),
                "{pair:?} starts late"
            );
        }
        // The viewer's σmax 8 (N = 9): from 3 px one level, from 2 px two.
        let v = Schedule::new(Scheme::Matched, 1.0, 8.0, 0.25).unwrap();
        assert_eq!(v.coarse_levels(v.coarse_start(3.0).unwrap()), vec![5]);
        assert_eq!(v.coarse_levels(v.coarse_start(2.0).unwrap()), vec![3, 6]);
        // A huge blur stops at MAX_COARSE_LEVELS.
        let big = Schedule::new(Scheme::Matched, 1.0, 1e4, 0.25).unwrap();
        assert_eq!(big.coarse_levels(3).len(), MAX_COARSE_LEVELS);
        assert_eq!(big.coarse_levels(3), vec![3, 6]);
    }

    #[test]
    fn each_level_takes_its_own_resampling_variance_off() {
        // Level ℓ's 2x2 average and bilinear up-sampling add 4^(ℓ−1) px²; its steps at the
        // top rate add (scale factor)² of the full-resolution steps' variance, so the sum
        // over the levels plus the resampling is what full resolution adds.
        let s = Schedule::new(Scheme::Matched, 1.0, 25.0, 0.25).unwrap();
        let top = s.rate(25.0);
        let step_variance = |k: u32| 2.0 * top * bilinear_moment(s.offset(top, k));
        let starts = s.coarse_levels(3);
        let mut total: f64 = (0..starts[0]).map(step_variance).sum();
        for (l, &start) in starts.iter().enumerate() {
            let level = l as u32 + 1;
            let end = starts.get(l + 1).copied().unwrap_or(s.steps);
            let factor = s.level_scale(level, start, end);
            assert!(factor > 0.9 && factor < 1.0, "level {level}: {factor}");
            let steps: f64 = (start..end).map(step_variance).sum();
            total += factor * factor * steps + level_resampling_variance(level);
        }
        assert_eq!(level_resampling_variance(3), 16.0);
        assert!((total - (625.0 - 1.0)).abs() < 1e-9, "{total}");
        // The one-level form is level 1's.
        assert_eq!(s.coarse_scale(5), s.level_scale(1, 5, s.steps));
    }

    #[test]
    fn deeper_levels_keep_more_of_their_lower_band() {
        // Level ℓ's band is centred at 2^(1−ℓ)/4 cycle per px: its transfer decays 4^(ℓ−1)
        // times slower in the variance.
        let s = Schedule::new(Scheme::Matched, 1.0, 25.0, 0.25).unwrap();
        assert_eq!(level_detail_decay(1), DETAIL_DECAY);
        assert_eq!(level_detail_decay(3), DETAIL_DECAY / 16.0);
        let (a1, a2) = (
            s.level_detail_weight(1, 0.02, 5),
            s.level_detail_weight(2, 0.02, 5),
        );
        assert!(a2 > a1, "{a1} {a2}");
        assert!((a2.ln() * 4.0 - a1.ln()).abs() < 1e-12);
        assert_eq!(s.detail_weight(0.02, 5), a1);
    }

    #[test]
    fn detail_weight_keeps_unblurred_detail_and_drops_blurred() {
        let s = Schedule::new(Scheme::Matched, 1.0, 25.0, 0.25).unwrap();
        assert_eq!(s.detail_weight(0.0, 5), 1.0);
        assert!(s.detail_weight(s.rate(25.0), 5) < 1e-100);
        // Monotone in the rate.
        let a = s.detail_weight(0.02, 5);
        let b = s.detail_weight(0.05, 5);
        assert!(1.0 > a && a > b && b > 0.0, "{a} {b}");
        // The Gaussian transfer at ¼ cycle per px of the added variance.
        let added = (26.0f64 * 0.02).exp() - (10.0f64 * 0.02).exp();
        assert!((a - (-DETAIL_DECAY * added).exp()).abs() < 1e-15);
    }

    #[test]
    fn bad_parameters_are_errors() {
        assert!(Schedule::new(Scheme::Euler, 0.0, 5.0, 0.25).is_err());
        assert!(Schedule::new(Scheme::Euler, 1.0, f64::NAN, 0.25).is_err());
        assert!(Schedule::new(Scheme::Euler, 1.0, 5.0, 0.3).is_err());
        assert!(Schedule::new(Scheme::Euler, 2.0, 1.0, 0.25).is_err());
        assert!("fast".parse::<Scheme>().is_err());
    }
}
