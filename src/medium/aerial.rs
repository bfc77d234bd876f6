//! Paper 002's aerial perspective as a medium: I_c = I⁰_c·Γ_c(T, s) + I∞_c(T, θ)(1 − Γ_c)
//! (eq. 10), with
//!
//! - Γ_c(T, s), the attenuation a camera channel sees through turbidity T over s metres
//!   (eq. 11), read from an [`AttenuationTable`] (a lookup texture over distance, rebuilt
//!   when T or the observer's altitude changes) — τ is chromatic: distant hills turn blue
//!   in clear air, grey in haze;
//! - I∞_c(T, θ) = I∞_c(θ')·ζ(T, θ, θ') (eq. 12-13): the horizon's light, given at zenith
//!   angle θ', carried to the pixel's zenith angle θ, which comes from the camera's ray
//!   (its pitch and vertical field of view for a photo; [`Camera::position`] and the clip
//!   planes are not used);
//! - σ from the scattering optical depth −ln Γ̄ (the mean of the three channels; all of
//!   the aerial extinction scatters) by [`blur_from_optical_depth`], capped at 10 (the
//!   sRGB curves' Γ_b reaches 0 where the reddened light leaves the gamut).
//!
//! The depth texture holds range (distance from the camera centre) in any unit:
//! [`AerialPerspective::metres_per_unit`] turns it into metres.

use super::{blur_from_optical_depth, Lookup, Medium, MediumSample, Pixel, UniformValue};
use crate::atmosphere::{
    gradation_coefficients, zeta, AttenuationTable, Channel, ZETA_MAX_ZENITH_RAD,
    ZETA_MIN_TURBIDITY,
};
use crate::camera::Camera;
use crate::error::{check_non_negative, check_positive, Error, Result};
use std::sync::Arc;

/// The largest scattering optical depth the blur law takes (τ̄ = e^(−10)).
pub const MAX_BLUR_OPTICAL_DEPTH: f64 = 10.0;

/// Paper 002's aerial perspective (module docs).
#[derive(Clone, Debug)]
pub struct AerialPerspective {
    /// Γ over distance for the turbidity, altitude and camera sensitivity.
    pub table: Arc<AttenuationTable>,
    /// The camera whose rays give each pixel's zenith angle (pitch, vertical field of view).
    pub camera: Camera,
    /// Metres per unit of the range texture (> 0).
    pub metres_per_unit: f64,
    /// I∞(θ'): the horizon's light, linear RGB.
    pub horizon_light: [f32; 3],
    /// θ', the zenith angle where `horizon_light` was measured (radians).
    pub reference_zenith: f64,
    /// Blur factor λ ≥ 0 (px).
    pub lambda: f64,
    /// The distance (m) that counts as 1 in the blur law (> 0).
    pub blur_range_m: f64,
}

impl AerialPerspective {
    /// Aerial perspective from `table` seen through `camera`, with the horizon's light
    /// `horizon_light` at 85° from the zenith, no blur, range in metres.
    pub fn new(table: Arc<AttenuationTable>, camera: Camera, horizon_light: [f32; 3]) -> Self {
        let blur_range_m = table.max_distance_m();
        AerialPerspective {
            table,
            camera,
            metres_per_unit: 1.0,
            horizon_light,
            reference_zenith: 85f64.to_radians(),
            lambda: 0.0,
            blur_range_m,
        }
    }

    /// ζ's coefficients for the shader: (A, B, 1/gradation(θ')).
    fn gradation_uniform(&self) -> [f32; 3] {
        // The same clamps as `zeta`: T ≥ 1.7, θ' ≤ 89.9°.
        let [a, b] = gradation_coefficients(self.table.turbidity().max(ZETA_MIN_TURBIDITY));
        let cos = self.reference_zenith.clamp(0.0, ZETA_MAX_ZENITH_RAD).cos();
        [
            a as f32,
            b as f32,
            (1.0 / (1.0 + a * (b / cos).exp())) as f32,
        ]
    }
}

impl Medium for AerialPerspective {
    fn name(&self) -> &'static str {
        "aerial"
    }

    fn glsl(&self) -> &'static str {
        include_str!("../../glsl/medium/aerial.glsl")
    }

    fn uniforms(&self) -> Vec<(&'static str, UniformValue)> {
        let t = &self.table;
        vec![
            (
                "u_gamma_coord",
                UniformValue::Vec4([
                    (1.0 / t.scale_m()) as f32,
                    (1.0 / t.log_span()) as f32,
                    t.max_distance_m() as f32,
                    t.samples() as f32,
                ]),
            ),
            ("u_metres", UniformValue::Float(self.metres_per_unit as f32)),
            ("u_horizon", UniformValue::Vec3(self.horizon_light)),
            ("u_gradation", UniformValue::Vec3(self.gradation_uniform())),
            (
                "u_aerial_blur",
                UniformValue::Vec2([self.lambda as f32, (1.0 / self.blur_range_m) as f32]),
            ),
        ]
    }

    fn chromatic(&self) -> bool {
        true
    }

    fn sigma_max(&self, sigma0: f64) -> f64 {
        blur_from_optical_depth(sigma0, self.lambda, 1.0, MAX_BLUR_OPTICAL_DEPTH)
    }

    fn sample(&self, p: Pixel) -> MediumSample {
        let s = p.depth.max(0.0) * self.metres_per_unit;
        let gamma = Channel::ALL.map(|c| self.table.sample(c, s));
        let ray = self
            .camera
            .pixel_ray(p.x, p.y, p.width, p.height)
            .normalize();
        let theta = ray.y.clamp(-1.0, 1.0).acos();
        let z = zeta(self.table.turbidity(), theta, self.reference_zenith);
        let mean = gamma.iter().sum::<f64>() / 3.0;
        let ds = (-mean.max(1e-30).ln()).min(MAX_BLUR_OPTICAL_DEPTH);
        MediumSample {
            transmission: gamma,
            inscatter: self.horizon_light.map(|v| f64::from(v) * z),
            sigma: blur_from_optical_depth(p.sigma0, self.lambda, s / self.blur_range_m, ds),
        }
    }

    fn validate(&self) -> Result<()> {
        check_positive("metres_per_unit", self.metres_per_unit)?;
        check_non_negative("lambda", self.lambda)?;
        check_positive("blur_range_m", self.blur_range_m)?;
        if !self
            .horizon_light
            .iter()
            .all(|v| v.is_finite() && *v >= 0.0)
        {
            let [r, g, b] = self.horizon_light;
            return Err(Error::invalid(
                "horizon_light",
                format!("{r},{g},{b}"),
                "three finite linear values ≥ 0",
            ));
        }
        if !(0.0..std::f64::consts::FRAC_PI_2).contains(&self.reference_zenith) {
            return Err(Error::invalid(
                "reference_zenith",
                self.reference_zenith.to_degrees(),
                "a zenith angle in [0°, 90°) where the horizon's light was measured",
            ));
        }
        self.camera.validate()
    }

    fn camera(&self) -> Option<Camera> {
        Some(self.camera)
    }

    fn lookups(&self) -> Vec<(&'static str, Lookup)> {
        vec![("u_gamma", self.table.lookup().clone())]
    }
}
