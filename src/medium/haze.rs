//! Paper 000's haze: Beer-Lambert transmission τ = exp(−(κa+κs)R) (eq. 1), a constant
//! airlight B (eq. 4), and the blur scale σ = σ0 + R^(3/2)(σmax − σ0) with
//! σmax = σ0 + λ·√κs (eq. 7), in normalised range.
//!
//! **Normalisation** (paper 000, sec. 2.2): the range map is divided by its largest value
//! so that R ∈ [0, 1], and κa, κs are given per unit of that largest range. After
//! pre-processing the largest value is the sky range Smax (> Rmax), so the sky sits at
//! R = 1 and gets σmax, and the farthest scene point gets slightly less. The depth texture
//! may hold the range in any unit: [`Haze::range_unit`] is the range that counts as 1.
//! Fog given physically (β in m⁻¹ on range in metres, no normalisation) is this medium
//! with the visibility as that unit: see [`super::physical`].
//!
//! **Chromatic haze.** [`Haze::tint`] scales the extinction per channel (e.g.
//! `[0.8, 1.0, 1.3]` for a bluish veil, blue light scattered most): τ_c = exp(−κ·tint_c·R).
//! With the default `[1, 1, 1]` the medium is grey and the images are paper 000's.

use super::{Medium, MediumSample, Pixel, UniformValue};
use crate::camera::FrameInputs;
use crate::error::{check_non_negative, check_positive, Error, Result};
use crate::raster::ScalarMap;

/// Default absorption coefficient κa (normalised units).
pub const DEFAULT_KA: f64 = 0.25;
/// Default scattering coefficient κs (normalised units).
pub const DEFAULT_KS: f64 = 0.75;
/// Default λ, the overall blur factor of eq. 7 (px).
pub const DEFAULT_LAMBDA: f64 = 8.0;
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
    /// Airlight colour B, linear RGB.
    pub airlight: [f32; 3],
    /// Relative extinction per channel, each > 0; `[1, 1, 1]` (grey) is paper 000.
    pub tint: [f64; 3],
    /// The depth texture's value that counts as normalised range 1 (> 0): 1 when the
    /// range is already normalised, Rmax (or Smax) when it is in metres.
    pub range_unit: f64,
}

impl Default for Haze {
    fn default() -> Self {
        Haze {
            ka: DEFAULT_KA,
            ks: DEFAULT_KS,
            lambda: DEFAULT_LAMBDA,
            airlight: DEFAULT_AIRLIGHT,
            tint: [1.0; 3],
            range_unit: 1.0,
        }
    }
}

impl Haze {
    /// κa + κs.
    pub fn extinction(&self) -> f64 {
        self.ka + self.ks
    }

    /// Extinction per channel: (κa + κs)·tint.
    pub fn extinction_rgb(&self) -> [f64; 3] {
        self.tint.map(|t| self.extinction() * t)
    }

    /// σmax − σ0 = λ·√κs (eq. 7): the blur the farthest point gets beyond σ0.
    pub fn sigma_span(&self) -> f64 {
        self.lambda * self.ks.sqrt()
    }

    /// τ per channel at normalised range `r` (eq. 1).
    pub fn transmission(&self, r: f64) -> [f64; 3] {
        self.extinction_rgb().map(|k| (-k * r).exp())
    }
}

impl Medium for Haze {
    fn name(&self) -> std::borrow::Cow<'static, str> {
        "haze".into()
    }

    fn glsl(&self) -> std::borrow::Cow<'static, str> {
        include_str!("../../glsl/medium/haze.glsl").into()
    }

    fn uniforms(
        &self,
        _frame: &FrameInputs,
    ) -> Vec<(std::borrow::Cow<'static, str>, UniformValue)> {
        let k = self.extinction_rgb().map(|v| v as f32);
        super::static_names(vec![
            ("u_extinction", UniformValue::Vec3(k)),
            (
                "u_range_scale",
                UniformValue::Float((1.0 / self.range_unit) as f32),
            ),
            (
                "u_sigma_span",
                UniformValue::Float(self.sigma_span() as f32),
            ),
            ("u_airlight", UniformValue::Vec3(self.airlight)),
        ])
    }

    // The airlight B is one colour.
    fn uniform_inscatter(&self) -> bool {
        true
    }

    fn chromatic(&self) -> bool {
        self.tint.iter().any(|&t| t != self.tint[0])
    }

    fn sigma_max(&self, sigma0: f64) -> f64 {
        sigma0 + self.sigma_span()
    }

    fn sample(&self, p: Pixel, _frame: &FrameInputs) -> MediumSample {
        let r = p.depth * (1.0 / self.range_unit);
        let sigma_max = self.sigma_max(p.sigma0);
        MediumSample {
            transmission: self.transmission(r),
            inscatter: self.airlight.map(f64::from),
            sigma: p.sigma0 + r.clamp(0.0, 1.0).powf(1.5) * (sigma_max - p.sigma0),
        }
    }

    fn validate(&self) -> Result<()> {
        check_non_negative("ka", self.ka)?;
        check_non_negative("ks", self.ks)?;
        check_non_negative("lambda", self.lambda)?;
        check_airlight(self.airlight)?;
        if !self.tint.iter().all(|t| t.is_finite() && *t > 0.0) {
            return Err(Error::invalid(
                "tint",
                format!("{},{},{}", self.tint[0], self.tint[1], self.tint[2]),
                "three finite factors > 0, e.g. 0.8,1,1.3",
            ));
        }
        check_positive("range_unit", self.range_unit)
    }
}

/// Normalises a range map to [0, 1] by its largest finite value (module docs). Unknown
/// values (NaN, ±inf, < 0) are treated as far (R = 1): pre-processing (`prep`) fills
/// them properly. 0 stays 0, at the camera: no fog. The loaders and
/// [`crate::photo::Photo::from_range`] make every unknown value NaN, so after them a 0 is
/// pre-processing's ego vehicle ([`crate::prep::Guides::ego_mask`]). Returns the map and
/// the divisor.
pub fn normalise_range(range: &ScalarMap) -> Result<(ScalarMap, f32)> {
    let r_max = largest_range(range)?;
    let normalised = range.map(|&v| if at_known_range(v) { v / r_max } else { 1.0 });
    Ok((normalised, r_max))
}

/// Whether a value of a range map is a range the fog can read as it is: finite and ≥ 0
/// (0 is the ego vehicle's, at the camera; see [`normalise_range`]).
pub fn at_known_range(v: f32) -> bool {
    v.is_finite() && v >= 0.0
}

/// The largest known (finite, > 0) value of a range map; an error when there is none.
pub fn largest_range(range: &ScalarMap) -> Result<f32> {
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
    Ok(r_max)
}

fn check_airlight(b: [f32; 3]) -> Result<()> {
    if b.iter().all(|c| c.is_finite() && *c >= 0.0) {
        Ok(())
    } else {
        Err(Error::invalid(
            "airlight",
            format!("{},{},{}", b[0], b[1], b[2]),
            "three finite linear values ≥ 0, e.g. 0.8,0.8,0.8",
        ))
    }
}
