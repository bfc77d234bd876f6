//! Paper 000's haze in physical units: an extinction coefficient β in m⁻¹ on a range map
//! in metres, the way datasets specify fog (Foggy Cityscapes: β = 0.005, 0.01 and
//! 0.02 m⁻¹, the same for every image), instead of κ per unit of each frame's largest
//! range (`haze::normalise_range`), which gives the same κ a different fog in every
//! frame.
//!
//! **Extinction.** β splits into scattering βs = a·β and absorption βa = (1 − a)·β by the
//! single-scattering albedo a ∈ [0, 1] ([`DEFAULT_ALBEDO`] = 1: pure scattering, as
//! Foggy Cityscapes uses). τ = exp(−β·R) with R in metres (Beer-Lambert, paper 000 eq. 1).
//! The meteorological visibility is the range at which τ falls to the 5 % contrast
//! threshold (Koschmieder): V = −ln 0.05/β = ln 20/β ≈ 2.996/β.
//!
//! **The blur law.** Paper 000's eq. 7 needs a length that counts as 1: in normalised
//! units it is the frame's largest range Rmax, and with κs = βs·Rmax it reads
//!
//! ```text
//! σ = σ0 + λ·√(βs·L)·min(R/L, 1)^(3/2)  =  σ0 + λ·r·√Ds,   r = min(R/L, 1),  Ds = βs·L·r
//! ```
//!
//! with L = Rmax: the second form is [`super::blur_from_optical_depth`], the law of the
//! engine fogs, with Ds the scattering optical depth over the first L of the ray. In
//! physical units brume takes **L = V**, the visibility, which no outlier pixel can move:
//! σ then depends on the optical depth β·R alone, σ = σ0 + λ·√(a·ln 20)·min(β·R/ln 20, 1)^(3/2),
//! so a fog twice as dense blurs a point as the first fog blurs one twice as far; the blur
//! grows until R = V (where τ = 5 %) and stays at σmax = σ0 + λ·√(a·ln 20) ≈ σ0 + 1.73·λ
//! (a = 1) beyond. On normalised data (L = 1 = Rmax, κ = β·Rmax) the
//! same formula is eq. 7 exactly.
//!
//! **Implementation.** [`PhysicalFog::haze`] is the [`Haze`] medium with its unit of range
//! set to V ([`Haze::range_unit`]) and κ = β·V per that unit: κa = (1 − a)·ln 20,
//! κs = a·ln 20. The shader is paper 000's, unchanged; the range texture holds metres
//! ([`metric_range`]), never divided by the frame's largest range.

use super::haze::{at_known_range, Haze};
use crate::error::{Error, Result};
use crate::raster::ScalarMap;

/// ln 20 ≈ 2.996: the optical depth β·V at the meteorological visibility V, where τ is the
/// 5 % contrast threshold (Koschmieder's law, V = −ln 0.05/β).
pub const VISIBILITY_OPTICAL_DEPTH: f64 = 2.995_732_273_553_991;

/// Default single-scattering albedo: 1, pure scattering (no absorption), as in fog and as
/// Foggy Cityscapes renders it.
pub const DEFAULT_ALBEDO: f64 = 1.0;

/// Fog in physical units: extinction β (m⁻¹) and single-scattering albedo (module docs).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct PhysicalFog {
    /// Extinction coefficient β = βa + βs in m⁻¹, > 0.
    pub beta: f64,
    /// Single-scattering albedo a = βs/β, in [0, 1].
    pub albedo: f64,
}

impl PhysicalFog {
    /// A fog of extinction `beta` (m⁻¹) and single-scattering `albedo`, checked.
    pub fn new(beta: f64, albedo: f64) -> Result<Self> {
        let fog = PhysicalFog { beta, albedo };
        fog.validate()?;
        Ok(fog)
    }

    /// The fog whose meteorological visibility is `visibility_m` metres:
    /// β = ln 20/V ([`VISIBILITY_OPTICAL_DEPTH`]).
    pub fn from_visibility(visibility_m: f64, albedo: f64) -> Result<Self> {
        if !(visibility_m.is_finite() && visibility_m > 0.0) {
            return Err(Error::invalid(
                "visibility",
                visibility_m,
                "a finite distance > 0 in metres (Foggy Cityscapes: 600, 300, 150)",
            ));
        }
        Self::new(VISIBILITY_OPTICAL_DEPTH / visibility_m, albedo)
    }

    /// Rejects a β that is not finite and > 0, or an albedo outside [0, 1].
    pub fn validate(&self) -> Result<()> {
        if !(self.beta.is_finite() && self.beta > 0.0) {
            return Err(Error::invalid(
                "beta",
                self.beta,
                "a finite extinction > 0 in m⁻¹ (Foggy Cityscapes: 0.005, 0.01, 0.02)",
            ));
        }
        if !(0.0..=1.0).contains(&self.albedo) {
            return Err(Error::invalid(
                "albedo",
                self.albedo,
                "a single-scattering albedo from 0 (absorption only) to 1 (scattering only)",
            ));
        }
        Ok(())
    }

    /// The meteorological visibility V = ln 20/β in metres: the reference length of the
    /// blur law (module docs).
    pub fn visibility_m(&self) -> f64 {
        VISIBILITY_OPTICAL_DEPTH / self.beta
    }

    /// Scattering coefficient βs = a·β (m⁻¹).
    pub fn scattering(&self) -> f64 {
        self.albedo * self.beta
    }

    /// Absorption coefficient βa = (1 − a)·β (m⁻¹).
    pub fn absorption(&self) -> f64 {
        (1.0 - self.albedo) * self.beta
    }

    /// τ = exp(−β·R) at range `range_m` metres (a grey medium).
    pub fn transmission(&self, range_m: f64) -> f64 {
        (-self.beta * range_m).exp()
    }

    /// Paper 000's haze medium for this fog on a range texture in metres: `base`'s λ,
    /// airlight and tint, its unit of range set to V and κ = β·V per that unit (module
    /// docs). Its τ is exp(−β·tint_c·R), its σ the law above.
    pub fn haze(&self, base: &Haze) -> Haze {
        let v = self.visibility_m();
        Haze {
            ka: self.absorption() * v,
            ks: self.scattering() * v,
            range_unit: v,
            ..*base
        }
    }
}

/// A range map in metres for a [`PhysicalFog`]: known values kept as they are (never
/// divided by the largest; 0, the ego vehicle's, at the camera), unknown ones (NaN, ±inf,
/// < 0, only left by `--no-prep`) taken as the largest known range, as
/// [`super::haze::normalise_range`] takes them as 1. Returns the map and that largest
/// range.
pub fn metric_range(range: &ScalarMap) -> Result<(ScalarMap, f32)> {
    let r_max = super::haze::largest_range(range)?;
    let filled = range.map(|&v| if at_known_range(v) { v } else { r_max });
    Ok((filled, r_max))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::FrameInputs;
    use crate::medium::{blur_from_optical_depth, Medium, Pixel};

    fn pixel(depth: f64) -> Pixel {
        Pixel {
            x: 0,
            y: 0,
            width: 1,
            height: 1,
            depth,
            sigma0: 1.0,
        }
    }

    #[test]
    fn visibility_is_ln_20_over_beta() {
        assert_eq!(VISIBILITY_OPTICAL_DEPTH, 20f64.ln());
        for (beta, v) in [(0.005, 599.146), (0.01, 299.573), (0.02, 149.787)] {
            let fog = PhysicalFog::new(beta, 1.0).unwrap();
            assert!((fog.visibility_m() - v).abs() < 1e-3, "{beta}");
            let back = PhysicalFog::from_visibility(fog.visibility_m(), 1.0).unwrap();
            assert!((back.beta - beta).abs() < 1e-15);
            // τ at the visibility is the 5 % threshold.
            assert!((fog.transmission(fog.visibility_m()) - 0.05).abs() < 1e-12);
        }
    }

    #[test]
    fn the_haze_medium_gives_exp_minus_beta_r_in_metres() {
        let fog = PhysicalFog::new(0.02, 0.7).unwrap();
        let haze = fog.haze(&Haze::default());
        haze.validate().unwrap();
        for r in [0.0, 1.0, 37.5, 149.0, 400.0, 5000.0] {
            let tau = haze.sample(pixel(r), &FrameInputs::default()).transmission;
            let want = (-0.02 * r).exp();
            assert!(tau.iter().all(|t| (t - want).abs() < 1e-12), "{r}: {tau:?}");
        }
        assert!((haze.ks / haze.extinction() - 0.7).abs() < 1e-12);
    }

    #[test]
    fn the_blur_is_the_optical_depth_law_with_the_visibility_as_unit() {
        let fog = PhysicalFog::new(0.01, 0.6).unwrap();
        let haze = Haze {
            lambda: 9.0,
            ..fog.haze(&Haze::default())
        };
        let v = fog.visibility_m();
        for r in [0.0, 10.0, 120.0, 299.0, 300.0, 1e4] {
            let r_unit = (r / v).min(1.0);
            let ds = fog.scattering() * v * r_unit;
            let want = blur_from_optical_depth(1.0, 9.0, r_unit, ds);
            let got = haze.sample(pixel(r), &FrameInputs::default()).sigma;
            assert!((got - want).abs() < 1e-9, "{r}: {got} vs {want}");
        }
        // σmax = σ0 + λ·√(a·ln 20), whatever β.
        let want = 1.0 + 9.0 * (0.6 * VISIBILITY_OPTICAL_DEPTH).sqrt();
        assert!((haze.sigma_max(1.0) - want).abs() < 1e-12);
        let dense = PhysicalFog::new(0.05, 0.6).unwrap().haze(&haze);
        assert!((dense.sigma_max(1.0) - want).abs() < 1e-12);
    }

    #[test]
    fn on_normalised_data_the_law_is_eq_7() {
        // Rmax = 1 plays the visibility: κ = β·1. Eq. 7: σ0 + R^(3/2)·λ·√κs.
        let (ka, ks, lambda) = (0.25, 0.75, 8.0);
        let normalised = Haze {
            ka,
            ks,
            lambda,
            ..Haze::default()
        };
        for r in [0.0f64, 0.1, 0.5, 0.9, 1.0] {
            let eq7 = 1.0 + r.powf(1.5) * lambda * ks.sqrt();
            let law = blur_from_optical_depth(1.0, lambda, r, ks * r);
            let got = normalised.sample(pixel(r), &FrameInputs::default()).sigma;
            assert!(
                (got - eq7).abs() < 1e-12 && (law - eq7).abs() < 1e-12,
                "{r}"
            );
        }
    }

    #[test]
    fn bad_values_are_named() {
        for beta in [0.0, -0.01, f64::NAN, f64::INFINITY] {
            let e = PhysicalFog::new(beta, 1.0).unwrap_err().to_string();
            assert!(e.contains("invalid beta"), "{e}");
        }
        for a in [-0.1, 1.5, f64::NAN] {
            let e = PhysicalFog::new(0.01, a).unwrap_err().to_string();
            assert!(e.contains("invalid albedo"), "{e}");
        }
        for v in [0.0, -300.0, f64::INFINITY] {
            let e = PhysicalFog::from_visibility(v, 1.0)
                .unwrap_err()
                .to_string();
            assert!(e.contains("invalid visibility"), "{e}");
        }
    }

    #[test]
    fn metric_range_keeps_metres_and_fills_unknown_with_the_largest() {
        let range =
            ScalarMap::from_vec(6, 1, vec![12.5, f32::NAN, 480.0, -1.0, 0.0, f32::INFINITY]);
        let (m, r_max) = metric_range(&range).unwrap();
        assert_eq!(r_max, 480.0);
        // 0, the ego vehicle's range after pre-processing, stays at the camera.
        assert_eq!(m.as_slice(), &[12.5, 480.0, 480.0, 480.0, 0.0, 480.0]);
        assert!(metric_range(&ScalarMap::from_vec(1, 1, vec![f32::NAN])).is_err());
    }
}
