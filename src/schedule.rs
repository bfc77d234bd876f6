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

impl Schedule {
    /// Plans the N steps that take σ0 to `sigma_max` under `scheme` with rates ≤ `rho_max`
    /// (paper 000, eq. 13 and eq. 18).
    pub fn new(scheme: Scheme, sigma0: f64, sigma_max: f64, rho_max: f64) -> Result<Self> {
        check_positive("sigma0", sigma0)?;
        check_positive("sigma_max", sigma_max)?;
        if !(rho_max > 0.0 && rho_max <= 0.25) {
            return Err(Error::invalid(
                "rho_max",
                rho_max,
                "a rate in (0, 0.25] (larger rates make the 4-neighbour update unstable)",
            ));
        }
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
    fn bad_parameters_are_errors() {
        assert!(Schedule::new(Scheme::Euler, 0.0, 5.0, 0.25).is_err());
        assert!(Schedule::new(Scheme::Euler, 1.0, f64::NAN, 0.25).is_err());
        assert!(Schedule::new(Scheme::Euler, 1.0, 5.0, 0.3).is_err());
        assert!(Schedule::new(Scheme::Euler, 2.0, 1.0, 0.25).is_err());
        assert!("fast".parse::<Scheme>().is_err());
    }
}
