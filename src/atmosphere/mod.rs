//! Paper 002's aerial perspective model, per camera channel, on the CPU: the corrected
//! scattering coefficients ([`scattering`]), the camera's spectral sensitivities
//! ([`spectral`]), the attenuation Γ_c(T, s) of eq. 11 ([`Aerial`]) and its table for the
//! GPU ([`AttenuationTable`]), and the sky ratio ζ of eq. 13 ([`zeta`]).
//!
//! Pixel values follow eq. 10, `I_c = I_c⁰·Γ_c(T, s) + I_c^∞·(1 − Γ_c(T, s))`.
//!
//! # Units
//!
//! Distances and altitudes in metres, coefficients in m⁻¹ (with km⁻¹ twins, the unit of
//! the paper's Table 2), wavelengths in nm. The module docs of [`scattering`] derive the
//! units of eq. 18, which the paper leaves implicit.
//!
//! # Negative sensitivity lobes
//!
//! The default camera is the CIE observer mapped to linear sRGB, whose curves are signed
//! (an ideal sRGB camera must "subtract" some wavelengths). Γ_c integrates them signed,
//! weighted by a daylight (D65) spectrum:
//!
//! ```text
//! Γ_c(s) = ∫ D65·q_c·e^(−β_sc·s) dλ / ∫ D65·q_c dλ
//! ```
//!
//! Why signed: a pixel value is linear in the spectrum, I_c = ∫ L·q_c, so for a grey
//! surface in daylight the attenuated value is exactly I_c·Γ_c with the signed q_c, in
//! every channel. Clamping the lobes to zero would describe another camera (one whose
//! white is no longer r = g = b) and changes Γ by up to 0.08 (red, pure air, 76 km).
//! Why D65 and not eq. 11's flat spectrum: D65 is sRGB's white (it maps to r = g = b),
//! so it is what a neutral surface reflects by day; equal energy is offered as
//! [`Illuminant::EqualEnergy`]. The denominators are positive (each channel's response to
//! white). What the sign costs: far enough, the reddened spectrum leaves the sRGB gamut
//! and the signed integral crosses zero, blue first (at 138 km in pure air, 19 km at
//! T = 2.94, 2.2 km at T = 20, where green is down to 13 %, 1.4 % and 1 %). Γ_c is 0 from
//! that distance on ([`Aerial::gamut_limit_m`]), as a pixel clipped at black; the signed
//! integral beyond never goes below −0.006, so the clip moves Γ by less than that. With
//! it, Γ_c is 1 at s = 0, lies in [0, 1] and falls strictly until it reaches 0, for
//! T = 1 … 120, h0 = 0 … 2 km, 1 mm … 1000 km, either illuminant (tested). A camera with
//! non-negative curves (a measured one) never reaches the clip.

pub mod airlight;
pub mod attenuation;
pub mod scattering;
pub mod spectral;

pub mod horizon;

pub use airlight::{gradation_coefficients, zeta, ZETA_MAX_ZENITH_RAD, ZETA_MIN_TURBIDITY};
pub use attenuation::{Aerial, AttenuationTable};
pub use horizon::{horizon_light, HorizonLight};
pub use scattering::WeatherCondition;
pub use spectral::{Channel, Illuminant, Sensitivity};
