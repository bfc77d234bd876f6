//! The extinction β of each frame of a dataset, drawn from a distribution: fixed, uniform
//! between two values, or log-normal (β's logarithm normal, so that thin and thick fog
//! are drawn in proportion, as visibilities spread over decades are).

use std::fmt;
use std::str::FromStr;

use crate::error::{Error, Result};
use crate::rng::SplitMix64;

/// A distribution of the extinction β (1/m). Parsed from `0.02`, `uniform:LOW,HIGH` or
/// `lognormal:MU,SIGMA` ([`FromStr`]); drawn per frame by [`BetaDistribution::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BetaDistribution {
    /// Always this β.
    Fixed(f64),
    /// Uniform in [low, high], 0 < low ≤ high.
    Uniform {
        /// The least β.
        low: f64,
        /// The largest β.
        high: f64,
    },
    /// ln β normal of mean `mu` and standard deviation `sigma` ≥ 0: the median β is
    /// e^mu (e.g. mu −4.6 for 0.01 per metre), and β is within a factor e^sigma of it
    /// two draws in three.
    LogNormal {
        /// The mean of ln β.
        mu: f64,
        /// The standard deviation of ln β.
        sigma: f64,
    },
}

/// What [`BetaDistribution::from_str`] takes, for messages.
const FORMS: &str = "a β in 1/m (0.02), uniform:LOW,HIGH (1/m, 0 < LOW <= HIGH, e.g. \
     uniform:0.005,0.03) or lognormal:MU,SIGMA (the mean and standard deviation of ln β, \
     SIGMA >= 0, e.g. lognormal:-4.6,0.5 for a median of 0.01)";

/// The sub-stream of a seed that β draws use (the capture noise uses another).
const BETA_STREAM: u64 = 0x6265_7461;

impl BetaDistribution {
    /// Checks the parameters: β positive and finite, low ≤ high, σ ≥ 0, and draws that
    /// stay within f64 (|mu| + 8σ < 700).
    pub fn validate(&self) -> Result<()> {
        let bad = |why: &str| Err(Error::invalid("beta_dist", self, why.to_string()));
        match *self {
            BetaDistribution::Fixed(b) if !(b.is_finite() && b > 0.0) => {
                bad("a β in 1/m, finite and > 0")
            }
            BetaDistribution::Uniform { low, high }
                if !(low.is_finite() && high.is_finite() && 0.0 < low && low <= high) =>
            {
                bad("uniform:LOW,HIGH with 0 < LOW <= HIGH, finite, in 1/m")
            }
            BetaDistribution::LogNormal { mu, sigma }
                if !(mu.is_finite() && sigma.is_finite() && sigma >= 0.0)
                    || mu.abs() + 8.0 * sigma >= 700.0 =>
            {
                bad("lognormal:MU,SIGMA with SIGMA >= 0 and |MU| + 8·SIGMA < 700 (ln β)")
            }
            _ => Ok(()),
        }
    }

    /// The β below which a fraction `p` ∈ (0, 1) of the draws fall (the inverse of the
    /// cumulative distribution).
    pub fn quantile(&self, p: f64) -> f64 {
        match *self {
            BetaDistribution::Fixed(b) => b,
            BetaDistribution::Uniform { low, high } => low + (high - low) * p,
            BetaDistribution::LogNormal { mu, sigma } => (mu + sigma * normal_quantile(p)).exp(),
        }
    }

    /// The β of frame `index` under `seed`: a function of both alone (not of which frames
    /// were drawn before), so that frames rendered in any order or in parallel get the
    /// same β.
    pub fn sample(&self, seed: u64, index: u64) -> f64 {
        let mut rng = SplitMix64::for_stream(seed ^ BETA_STREAM, index);
        // (0, 1): the quantile of 0 is −∞ for the log-normal.
        let p = (rng.unit() + 0.5 / (1u64 << 53) as f64).min(1.0 - f64::EPSILON / 2.0);
        self.quantile(p)
    }
}

impl FromStr for BetaDistribution {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        let text = s.trim();
        let bad = || Error::invalid("beta_dist", s, FORMS);
        let number = |t: &str| t.trim().parse::<f64>().map_err(|_| bad());
        let pair = |t: &str| -> Result<(f64, f64)> {
            let (a, b) = t.split_once(',').ok_or_else(bad)?;
            Ok((number(a)?, number(b)?))
        };
        let dist = match text.split_once(':') {
            None => BetaDistribution::Fixed(number(text)?),
            Some((name, params)) => match name.trim().to_ascii_lowercase().as_str() {
                "fixed" => BetaDistribution::Fixed(number(params)?),
                "uniform" => {
                    let (low, high) = pair(params)?;
                    BetaDistribution::Uniform { low, high }
                }
                "lognormal" | "log-normal" => {
                    let (mu, sigma) = pair(params)?;
                    BetaDistribution::LogNormal { mu, sigma }
                }
                _ => return Err(bad()),
            },
        };
        dist.validate()?;
        Ok(dist)
    }
}

impl fmt::Display for BetaDistribution {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BetaDistribution::Fixed(b) => write!(f, "{b}"),
            BetaDistribution::Uniform { low, high } => write!(f, "uniform:{low},{high}"),
            BetaDistribution::LogNormal { mu, sigma } => write!(f, "lognormal:{mu},{sigma}"),
        }
    }
}

/// The standard normal quantile Φ⁻¹(p), p ∈ (0, 1): Acklam's rational approximation
/// (relative error below 1.2e-9).
// Acklam's coefficients as published.
#[allow(clippy::excessive_precision)]
pub(crate) fn normal_quantile(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969683028665376e+01,
        2.209460984245205e+02,
        -2.759285104469687e+02,
        1.383577518672690e+02,
        -3.066479806614716e+01,
        2.506628277459239e+00,
    ];
    const B: [f64; 5] = [
        -5.447609879822406e+01,
        1.615858368580409e+02,
        -1.556989798598866e+02,
        6.680131188771972e+01,
        -1.328068155288572e+01,
    ];
    const C: [f64; 6] = [
        -7.784894002430293e-03,
        -3.223964580411365e-01,
        -2.400758277161838e+00,
        -2.549732539343734e+00,
        4.374664141464968e+00,
        2.938163982698783e+00,
    ];
    const D: [f64; 4] = [
        7.784695709041462e-03,
        3.224671290700398e-01,
        2.445134137142996e+00,
        3.754408661907416e+00,
    ];
    const LOW: f64 = 0.02425;
    let tail = |q: f64| {
        let num = ((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5];
        let den = (((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0;
        num / den
    };
    if p < LOW {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - LOW {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        let num = ((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5];
        let den = ((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0;
        q * num / den
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_quantile_matches_tabulated_values() {
        // Φ⁻¹ from standard tables.
        for (p, z) in [
            (0.5, 0.0),
            (0.975, 1.959963984540054),
            (0.841344746068543, 1.0),
            (0.001, -3.090232306167814),
            (0.99, 2.326347874040841),
        ] {
            assert!((normal_quantile(p) - z).abs() < 1e-8, "p {p}");
        }
    }
}
