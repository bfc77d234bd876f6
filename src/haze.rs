//! The paper-000 haze model in normalised units: transmission from range (eq. 1), blur
//! scale from range (eq. 7), and the render specification that the GPU pipeline and the
//! CPU reference both consume.
//!
//! **Normalisation** (paper 000, sec. 2.2): the range map is divided by its largest value
//! so that R ∈ [0, 1], and κa, κs are given per unit of that largest range. After
//! pre-processing the largest value is the sky range Smax (> Rmax), so the sky sits at
//! R = 1 and gets σmax, and the farthest scene point gets slightly less.

use crate::error::{Error, Result};
use crate::raster::{Grid, ScalarMap};
use crate::schedule::{Schedule, Scheme};
use crate::Precision;

/// Default absorption coefficient κa (normalised units).
pub const DEFAULT_KA: f64 = 0.25;
/// Default scattering coefficient κs (normalised units).
pub const DEFAULT_KS: f64 = 0.75;
/// Default λ, the overall blur factor of eq. 7 (px).
pub const DEFAULT_LAMBDA: f64 = 8.0;
/// Default inner scale σ0 (px): reproduces the paper's step counts (GUIDE.md).
pub const DEFAULT_SIGMA0: f64 = 1.0;
/// Default maximum rate ρmax: the stability limit of the 4-neighbour update.
pub const DEFAULT_RHO_MAX: f64 = 0.25;
/// Default airlight B (linear RGB), used when none is given or estimated.
pub const DEFAULT_AIRLIGHT: [f32; 3] = [0.8, 0.8, 0.8];

/// Participating-medium parameters of paper 000 (normalised units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Haze {
    /// Absorption coefficient κa ≥ 0.
    pub ka: f64,
    /// Scattering coefficient κs ≥ 0.
    pub ks: f64,
    /// Blur factor λ ≥ 0 (px): σmax = σ0 + λ·√κs.
    pub lambda: f64,
    /// Inner scale σ0 > 0 (px).
    pub sigma0: f64,
    /// Airlight colour B, linear RGB.
    pub airlight: [f32; 3],
}

impl Default for Haze {
    fn default() -> Self {
        Haze {
            ka: DEFAULT_KA,
            ks: DEFAULT_KS,
            lambda: DEFAULT_LAMBDA,
            sigma0: DEFAULT_SIGMA0,
            airlight: DEFAULT_AIRLIGHT,
        }
    }
}

impl Haze {
    /// σmax = σ0 + λ·√κs (eq. 7).
    pub fn sigma_max(&self) -> f64 {
        self.sigma0 + self.lambda * self.ks.sqrt()
    }

    /// κa + κs.
    pub fn extinction(&self) -> f64 {
        self.ka + self.ks
    }

    /// Rejects negative or non-finite parameters, naming the option.
    pub fn validate(&self) -> Result<()> {
        non_negative("--ka", self.ka)?;
        non_negative("--ks", self.ks)?;
        non_negative("--lambda", self.lambda)?;
        positive("--sigma0", self.sigma0)?;
        check_airlight(self.airlight)
    }
}

/// How the target scale σ(x) is set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SigmaField {
    /// From range by eq. 7: σ = σ0 + R^(3/2)·(σmax − σ0).
    FromRange {
        /// σmax (px).
        sigma_max: f64,
    },
    /// The same σ everywhere (accuracy checks against a Gaussian).
    Uniform(f64),
}

/// Everything a render needs besides the image and the range map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSpec {
    /// κa + κs per unit normalised range (0 turns attenuation off).
    pub extinction: f64,
    /// Airlight B, linear RGB.
    pub airlight: [f32; 3],
    /// Target scale field.
    pub sigma: SigmaField,
    /// Inner scale σ0 (px).
    pub sigma0: f64,
    /// Rate limit ρmax.
    pub rho_max: f64,
    /// Diffusion scheme.
    pub scheme: Scheme,
    /// Texture precision of the diffusion passes.
    pub precision: Precision,
}

impl RenderSpec {
    /// The haze render of `haze`.
    pub fn haze(haze: &Haze, scheme: Scheme, precision: Precision) -> Self {
        RenderSpec {
            extinction: haze.extinction(),
            airlight: haze.airlight,
            sigma: SigmaField::FromRange {
                sigma_max: haze.sigma_max(),
            },
            sigma0: haze.sigma0,
            rho_max: DEFAULT_RHO_MAX,
            scheme,
            precision,
        }
    }

    /// A uniform blur to scale `sigma` with no attenuation and no airlight.
    pub fn uniform(sigma: f64, sigma0: f64, scheme: Scheme, precision: Precision) -> Self {
        RenderSpec {
            extinction: 0.0,
            airlight: [0.0; 3],
            sigma: SigmaField::Uniform(sigma),
            sigma0,
            rho_max: DEFAULT_RHO_MAX,
            scheme,
            precision,
        }
    }

    /// Rejects out-of-domain values, naming the option.
    pub fn validate(&self) -> Result<()> {
        non_negative("extinction (--ka + --ks)", self.extinction)?;
        positive("--sigma0", self.sigma0)?;
        check_airlight(self.airlight)?;
        match self.sigma {
            SigmaField::Uniform(s) if !(s.is_finite() && s >= self.sigma0) => Err(Error::invalid(
                "--uniform-sigma",
                s,
                format!("a finite scale ≥ σ0 = {} px", self.sigma0),
            )),
            SigmaField::FromRange { sigma_max }
                if !(sigma_max.is_finite() && sigma_max >= self.sigma0) =>
            {
                Err(Error::invalid(
                    "sigma_max",
                    sigma_max,
                    "a finite scale ≥ σ0",
                ))
            }
            _ => Ok(()),
        }
    }

    /// The largest scale any pixel can ask for.
    pub fn sigma_max(&self) -> f64 {
        match self.sigma {
            SigmaField::FromRange { sigma_max } => sigma_max,
            SigmaField::Uniform(s) => s,
        }
    }

    /// The N-step schedule that reaches [`Self::sigma_max`].
    pub fn schedule(&self) -> Result<Schedule> {
        self.validate()?;
        Schedule::new(self.scheme, self.sigma0, self.sigma_max(), self.rho_max)
    }

    /// σ(x) for normalised range `r` (eq. 7, or the uniform scale).
    pub fn sigma_at(&self, r: f64) -> f64 {
        match self.sigma {
            SigmaField::FromRange { sigma_max } => {
                self.sigma0 + r.clamp(0.0, 1.0).powf(1.5) * (sigma_max - self.sigma0)
            }
            SigmaField::Uniform(s) => s,
        }
    }

    /// τ = exp(−κ·R) (eq. 1) for normalised range `r`.
    pub fn transmission(&self, r: f64) -> f64 {
        (-self.extinction * r).exp()
    }

    /// The per-pixel rates ρ of `schedule` over a normalised range map, in f64 (the CPU
    /// reference).
    pub fn rates(&self, range: &ScalarMap, schedule: &Schedule) -> Grid<f64> {
        range.map(|&r| self.rate_at(r, schedule))
    }

    /// The same rates in f32, row-major, as the GPU's rate texture takes them. Built
    /// straight from the range map so that a 1600x1120 render does not also hold an f64
    /// copy.
    pub fn packed_rates(&self, range: &ScalarMap, schedule: &Schedule) -> Vec<f32> {
        range
            .as_slice()
            .iter()
            .map(|&r| self.rate_at(r, schedule) as f32)
            .collect()
    }

    fn rate_at(&self, r: f32, schedule: &Schedule) -> f64 {
        schedule.rate(self.sigma_at(f64::from(r)))
    }
}

/// Normalises a range map to [0, 1] by its largest finite value (module docs). Unknown
/// values (NaN, ±inf, ≤ 0) are treated as far (R = 1): pre-processing (`prep`) fills
/// them properly. Returns the map and the divisor.
pub fn normalise_range(range: &ScalarMap) -> Result<(ScalarMap, f32)> {
    let r_max = range
        .as_slice()
        .iter()
        .copied()
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold(0f32, f32::max);
    if r_max <= 0.0 {
        return Err(Error::invalid(
            "range map",
            "no positive finite value",
            "at least one known range value",
        ));
    }
    let normalised = range.map(|&v| {
        if v.is_finite() && v > 0.0 {
            v / r_max
        } else {
            1.0
        }
    });
    Ok((normalised, r_max))
}

fn non_negative(name: &str, v: f64) -> Result<()> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(name, v, "a finite number ≥ 0"))
    }
}

fn positive(name: &str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(name, v, "a finite number > 0"))
    }
}

fn check_airlight(b: [f32; 3]) -> Result<()> {
    if b.iter().all(|c| c.is_finite() && *c >= 0.0) {
        Ok(())
    } else {
        Err(Error::invalid(
            "--airlight",
            format!("{},{},{}", b[0], b[1], b[2]),
            "three finite linear values ≥ 0, e.g. 0.8,0.8,0.8",
        ))
    }
}
