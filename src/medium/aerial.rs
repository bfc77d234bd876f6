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
//!
//! I∞ may vary with azimuth (paper 002, sec. 4: brighter toward the sun):
//! [`AerialPerspective::horizon_sectors`] holds per-sector gains over `horizon_light`
//! ([`crate::sky::horizon_sectors`] finds them), interpolated linearly between the
//! sectors' centres by the ray's azimuth; a single sector of gain 1 by default. A single
//! sector's gain is folded into the horizon's light, and the shader is compiled without
//! the sectors' code (`AERIAL_HORIZON_SECTORS` undefined): no arc tangent per pixel.

use super::{blur_from_optical_depth, Lookup, Medium, MediumSample, Pixel, UniformValue, Wrap};
use crate::atmosphere::{
    gradation_coefficients, zeta, AttenuationTable, Channel, ZETA_MAX_ZENITH_RAD,
    ZETA_MIN_TURBIDITY,
};
use crate::camera::Camera;
use crate::camera::FrameInputs;
use crate::error::{check_non_negative, check_positive, Error, Result};
use std::sync::Arc;

/// The largest scattering optical depth the blur law takes (τ̄ = e^(−10)).
pub const MAX_BLUR_OPTICAL_DEPTH: f64 = 10.0;

/// Paper 002's aerial perspective (module docs).
#[derive(Clone, Debug)]
pub struct AerialPerspective {
    /// Γ over distance for the turbidity, altitude and camera sensitivity.
    pub table: Arc<AttenuationTable>,
    /// The camera whose rays give each pixel's zenith angle (pitch, vertical field of
    /// view). Unlike the depth-buffer media's camera it is part of the medium, not of the
    /// frame ([`crate::camera::FrameInputs`]): the horizon's light, its reference zenith
    /// and the sector gains were measured on the photo through this camera, so they only
    /// hold with it; a photo is one frame, and the range texture it reads needs no
    /// projection to be turned into distance.
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
    /// I∞'s gain by azimuth over `horizon_light` (one sector of 1: none).
    pub horizon_sectors: HorizonSectors,
}

/// Per-channel gains of the horizon's light by azimuth: `count` sectors of equal width
/// centred on an azimuth, linear between the sectors' centres, constant beyond the end
/// ones. Azimuths as [`crate::sky::horizon_sectors::ray_azimuth`]: 0 along −z, π/2
/// along +x. The GPU reads the gains from a `count` x 1 RGB lookup with the same bilinear
/// filter as [`HorizonSectors::gain`].
#[derive(Clone, Debug)]
pub struct HorizonSectors {
    gains: Vec<[f32; 3]>,
    centre: f64,
    sector_width: f64,
    lookup: Lookup,
}

impl HorizonSectors {
    /// One sector of gain 1: the horizon's light is the same in every direction.
    pub fn uniform() -> Self {
        Self::new(vec![[1.0; 3]], 0.0, std::f64::consts::TAU).expect("a valid table")
    }

    /// `gains` (linear, ≥ 0) of sectors `sector_width` radians wide, centred on azimuth
    /// `centre` (radians). Errors: no sector, a gain not finite or negative, a width
    /// not in (0, 2π].
    pub fn new(gains: Vec<[f32; 3]>, centre: f64, sector_width: f64) -> Result<Self> {
        if gains.is_empty()
            || gains
                .iter()
                .flatten()
                .any(|g| !(g.is_finite() && *g >= 0.0))
        {
            return Err(Error::invalid(
                "horizon_sectors",
                format!("{gains:?}"),
                "at least one sector of finite gains ≥ 0",
            ));
        }
        if !(sector_width > 0.0 && sector_width <= std::f64::consts::TAU && centre.is_finite()) {
            return Err(Error::invalid(
                "horizon sector width",
                sector_width,
                "a width in (0, 2π] radians about a finite centre",
            ));
        }
        let lookup = Lookup::rgb(gains.len(), 1, &gains, Wrap::ClampToEdge)?;
        Ok(HorizonSectors {
            gains,
            centre,
            sector_width,
            lookup,
        })
    }

    /// The sectors' gains, left to right.
    pub fn gains(&self) -> &[[f32; 3]] {
        &self.gains
    }

    /// The azimuth of the middle of the sectors, radians.
    pub fn centre(&self) -> f64 {
        self.centre
    }

    /// Each sector's width, radians.
    pub fn sector_width(&self) -> f64 {
        self.sector_width
    }

    /// The lookup's horizontal coordinate for azimuth `azimuth`: sector k's centre at
    /// texel k (the shader computes the same).
    fn coordinate(&self, azimuth: f64) -> f64 {
        let n = self.gains.len() as f64;
        let d = (azimuth - self.centre + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        (d / self.sector_width + n / 2.0) / n
    }

    /// The gain at azimuth `azimuth` (radians), per channel.
    pub fn gain(&self, azimuth: f64) -> [f64; 3] {
        let u = self.coordinate(azimuth);
        std::array::from_fn(|c| self.lookup.sample_channel(u, 0.5, c))
    }

    /// The gain of a single sector, the same in every direction; `None` for several.
    fn single_gain(&self) -> Option<[f32; 3]> {
        match self.gains.as_slice() {
            [gain] => Some(*gain),
            _ => None,
        }
    }

    /// (centre, 1/width, count) for the shader.
    fn uniform_value(&self) -> [f32; 3] {
        [
            self.centre as f32,
            (1.0 / self.sector_width) as f32,
            self.gains.len() as f32,
        ]
    }
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
            horizon_sectors: HorizonSectors::uniform(),
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
    fn name(&self) -> std::borrow::Cow<'static, str> {
        "aerial".into()
    }

    /// The sectors' code only where there are several (`AERIAL_HORIZON_SECTORS`): one
    /// sector's gain goes into `u_horizon` instead.
    fn glsl(&self) -> std::borrow::Cow<'static, str> {
        const AERIAL_GLSL: &str = include_str!("../../glsl/medium/aerial.glsl");
        match self.horizon_sectors.single_gain() {
            Some(_) => AERIAL_GLSL.into(),
            None => format!("#define AERIAL_HORIZON_SECTORS\n{AERIAL_GLSL}").into(),
        }
    }

    fn uniforms(
        &self,
        _frame: &FrameInputs,
    ) -> Vec<(std::borrow::Cow<'static, str>, UniformValue)> {
        let t = &self.table;
        let single = self.horizon_sectors.single_gain();
        let horizon = match single {
            Some(gain) => std::array::from_fn(|c| self.horizon_light[c] * gain[c]),
            None => self.horizon_light,
        };
        let mut uniforms = vec![
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
            ("u_horizon", UniformValue::Vec3(horizon)),
            ("u_gradation", UniformValue::Vec3(self.gradation_uniform())),
            (
                "u_aerial_blur",
                UniformValue::Vec2([self.lambda as f32, (1.0 / self.blur_range_m) as f32]),
            ),
        ];
        if single.is_none() {
            let sectors = UniformValue::Vec3(self.horizon_sectors.uniform_value());
            uniforms.push(("u_horizon_sectors", sectors));
        }
        super::static_names(uniforms)
    }

    fn chromatic(&self) -> bool {
        true
    }

    fn sigma_max(&self, sigma0: f64) -> f64 {
        blur_from_optical_depth(sigma0, self.lambda, 1.0, MAX_BLUR_OPTICAL_DEPTH)
    }

    fn sample(&self, p: Pixel, _frame: &FrameInputs) -> MediumSample {
        let s = p.depth.max(0.0) * self.metres_per_unit;
        let gamma = Channel::ALL.map(|c| self.table.sample(c, s));
        let ray = self
            .camera
            .pixel_ray(p.x, p.y, p.width, p.height)
            .normalize();
        let theta = ray.y.clamp(-1.0, 1.0).acos();
        let z = zeta(self.table.turbidity(), theta, self.reference_zenith);
        let gain = self
            .horizon_sectors
            .gain(crate::sky::horizon_sectors::ray_azimuth(ray));
        let mean = gamma.iter().sum::<f64>() / 3.0;
        let ds = (-mean.max(1e-30).ln()).min(MAX_BLUR_OPTICAL_DEPTH);
        MediumSample {
            transmission: gamma,
            inscatter: std::array::from_fn(|c| f64::from(self.horizon_light[c]) * z * gain[c]),
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

    /// The photo's own camera, whatever the frame gives: see [`AerialPerspective::camera`].
    fn frame_camera(&self, _frame: &FrameInputs) -> Option<crate::camera::FrameCamera> {
        Some(self.camera.into())
    }

    fn lookups(&self) -> Vec<(std::borrow::Cow<'static, str>, super::Lookup)> {
        let mut lookups = vec![("u_gamma", self.table.lookup().clone())];
        if self.horizon_sectors.single_gain().is_none() {
            lookups.push(("u_horizon_gain", self.horizon_sectors.lookup.clone()));
        }
        super::static_names(lookups)
    }
}
