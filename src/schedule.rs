//! The diffusion schedule: how many steps (N), the per-pixel rate ρ(x), and the per-step
//! neighbour offset h_k(x). This module is the single source of truth for that math: the
//! GPU pipeline uploads [`PixelLaw`]s and per-step uniforms from here, and the CPU
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
//! (1 + 2ρ) per step instead of e^(2ρ) and the result under-blurs (see GUIDE.md). The
//! matched schedule keeps the paper's N and ρ(x) but picks h_k(x) so that step k adds
//! exactly σk+1² − σk² with σk = σ0·e^(kρ): after N steps the variance is σ(x)² − σ0² +
//! σ0² = σ(x)², bilinear spread included. m is piecewise linear and increasing, so m⁻¹
//! is exact and cheap: i = ⌊√m⌋, h = i + (m − i²)/(2i + 1).
//!
//! To keep the shader scheme-agnostic, each pixel carries a [`PixelLaw`] (ρ, a, b) and
//! every scheme's offset is h_k = g(a·e^(k·b)) with g the identity or m⁻¹(t²) (the
//! [`Scheme::corrects_bilinear`] flag). The shader `glsl/diffuse.frag` evaluates
//! [`offset_from_law`] in GLSL; `tests/` compare the two through the whole pipeline.

use crate::error::{Error, Result};
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

    /// Whether the offset law is passed through m⁻¹(t²) (see the module docs).
    pub fn corrects_bilinear(self) -> bool {
        matches!(self, Scheme::Matched)
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
            .ok_or_else(|| Error::invalid("--scheme", s, "one of euler, invariant, matched"))
    }
}

/// What each pixel carries into the diffusion passes: its rate ρ and the two numbers of
/// its offset law h_k = g(a·e^(k·b)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelLaw {
    /// Diffusion rate ρ(x) ∈ [0, ρmax].
    pub rate: f64,
    /// Offset law scale a.
    pub a: f64,
    /// Offset law exponent b (per step).
    pub b: f64,
}

/// Per-pixel laws packed as the GPU textures hold them: ρ for the rate texture and (a, b)
/// for the law texture, in f32. Built straight from the range map so that a 1600x1120
/// render does not also hold a 24-byte-per-pixel f64 copy.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PackedLaws {
    /// ρ per pixel, row-major.
    pub rate: Vec<f32>,
    /// (a, b) per pixel, row-major.
    pub law: Vec<[f32; 2]>,
}

impl PackedLaws {
    /// Packs `law(i)` for the pixels `0..len`.
    pub fn from_fn(len: usize, mut law: impl FnMut(usize) -> PixelLaw) -> Self {
        let mut packed = PackedLaws {
            rate: Vec::with_capacity(len),
            law: Vec::with_capacity(len),
        };
        for i in 0..len {
            let l = law(i);
            packed.rate.push(l.rate as f32);
            packed.law.push([l.a as f32, l.b as f32]);
        }
        packed
    }

    /// The same law for all `len` pixels (uniform blurs, benchmarks).
    pub fn uniform(len: usize, law: PixelLaw) -> Self {
        PackedLaws::from_fn(len, |_| law)
    }

    /// Number of pixels.
    pub fn len(&self) -> usize {
        self.rate.len()
    }

    /// True when there are no pixels.
    pub fn is_empty(&self) -> bool {
        self.rate.is_empty()
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
        check_positive_finite("--sigma0", sigma0)?;
        check_positive_finite("sigma_max", sigma_max)?;
        if !(rho_max > 0.0 && rho_max <= 0.25) {
            return Err(Error::invalid(
                "--rho-max",
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

    /// The per-pixel law for a pixel whose target scale is `sigma` (clamped to
    /// [σ0, σmax]).
    pub fn law(&self, sigma: f64) -> PixelLaw {
        let sigma = sigma.clamp(self.sigma0, self.sigma_max);
        if self.steps == 0 {
            return PixelLaw {
                rate: 0.0,
                a: 1.0,
                b: 0.0,
            };
        }
        let n = f64::from(self.steps);
        match self.scheme {
            Scheme::Euler => PixelLaw {
                rate: (sigma * sigma - self.sigma0 * self.sigma0) / (2.0 * n),
                a: 1.0,
                b: 0.0,
            },
            Scheme::Invariant => {
                let rate = (sigma / self.sigma0).ln() / n;
                PixelLaw {
                    rate,
                    a: self.sigma0,
                    b: rate,
                }
            }
            Scheme::Matched => {
                let rate = (sigma / self.sigma0).ln() / n;
                PixelLaw {
                    rate,
                    a: self.sigma0 * growth_gain(rate).sqrt(),
                    b: rate,
                }
            }
        }
    }

    /// Offset h_k of step `k` for a pixel with law `law`.
    pub fn offset(&self, law: &PixelLaw, k: u32) -> f64 {
        offset_from_law(law.a, law.b, k, self.scheme.corrects_bilinear())
    }
}

/// (e^(2ρ) − 1) / (2ρ): the factor by which the matched scheme's squared offset exceeds
/// σk², with its limit 1 at ρ = 0.
fn growth_gain(rate: f64) -> f64 {
    let x = 2.0 * rate;
    if x.abs() < 1e-8 {
        1.0 + x / 2.0
    } else {
        x.exp_m1() / x
    }
}

/// h_k = g(a·e^(k·b)), with g = m⁻¹(t²) when `corrects_bilinear`, else the identity.
/// Mirrored in `glsl/diffuse.frag`.
pub fn offset_from_law(a: f64, b: f64, k: u32, corrects_bilinear: bool) -> f64 {
    let t = a * (f64::from(k) * b).exp();
    if corrects_bilinear {
        offset_for_moment(t * t)
    } else {
        t
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

fn check_positive_finite(name: &str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(name, value, "a finite number > 0"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_step_counts() {
        // GUIDE.md: σ0 = 1, ρmax = 1/4, σmax = 25 → 13 invariant steps, 1248 Euler steps.
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
                let law = s.law(sigma);
                assert!(
                    law.rate >= 0.0 && law.rate <= 0.25 + 1e-12,
                    "{scheme} {sigma}"
                );
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
            let law = s.law(sigma);
            let added: f64 = (0..s.steps)
                .map(|k| 2.0 * law.rate * bilinear_moment(s.offset(&law, k)))
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
        let law = s.law(25.0);
        let added: f64 = (0..s.steps)
            .map(|k| 2.0 * law.rate * s.offset(&law, k).powi(2))
            .sum();
        assert!(added < 0.9 * (625.0 - 1.0), "added {added}");
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
