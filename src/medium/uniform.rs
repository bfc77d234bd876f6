//! A blur to one scale σ everywhere, through a uniform filter τ and with no in-scattered
//! light: the medium of paper 000's accuracy experiment (τ = 1, the result compared with
//! an exact Gaussian), of `brume render --uniform-sigma`, and of the speed benchmark
//! (`--tau rgb` times the chromatic blur with a τ that differs per channel).

use super::{Medium, MediumSample, Pixel, UniformValue};
use crate::camera::FrameInputs;
use crate::error::{Error, Result};

/// Blur everything to `sigma` px and multiply by `transmission`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UniformBlur {
    /// Target scale σ (px), ≥ the blur's σ0.
    pub sigma: f64,
    /// τ per channel, in (0, 1]; `[1, 1, 1]` leaves the colour as it is.
    pub transmission: [f64; 3],
}

/// The τ of `--tau rgb` in the speed benchmark: a bluish filter, each channel different.
pub const CHROMATIC_TRANSMISSION: [f64; 3] = [0.9, 0.8, 0.6];

impl UniformBlur {
    /// A pure blur to `sigma` px (τ = 1).
    pub fn new(sigma: f64) -> Self {
        UniformBlur {
            sigma,
            transmission: [1.0; 3],
        }
    }
}

impl Medium for UniformBlur {
    fn name(&self) -> std::borrow::Cow<'static, str> {
        "uniform_blur".into()
    }

    fn glsl(&self) -> std::borrow::Cow<'static, str> {
        include_str!("../../glsl/medium/uniform_blur.glsl").into()
    }

    fn uniforms(
        &self,
        _frame: &FrameInputs,
    ) -> Vec<(std::borrow::Cow<'static, str>, UniformValue)> {
        super::static_names(vec![
            ("u_sigma", UniformValue::Float(self.sigma as f32)),
            (
                "u_transmission",
                UniformValue::Vec3(self.transmission.map(|t| t as f32)),
            ),
        ])
    }

    // No in-scattered light at all.
    fn uniform_inscatter(&self) -> bool {
        true
    }

    fn chromatic(&self) -> bool {
        self.transmission.iter().any(|&t| t != self.transmission[0])
    }

    fn sigma_max(&self, _sigma0: f64) -> f64 {
        self.sigma
    }

    fn sigma_min(&self, _sigma0: f64) -> f64 {
        self.sigma
    }

    fn sample(&self, _pixel: Pixel, _frame: &FrameInputs) -> MediumSample {
        MediumSample {
            transmission: self.transmission,
            inscatter: [0.0; 3],
            sigma: self.sigma,
        }
    }

    fn validate(&self) -> Result<()> {
        if !(self.sigma.is_finite() && self.sigma > 0.0) {
            return Err(Error::invalid(
                "uniform_sigma",
                self.sigma,
                "a finite scale > 0 px",
            ));
        }
        if !self.transmission.iter().all(|t| *t > 0.0 && *t <= 1.0) {
            let [r, g, b] = self.transmission;
            return Err(Error::invalid(
                "transmission",
                format!("{r},{g},{b}"),
                "three values in (0, 1]",
            ));
        }
        Ok(())
    }
}
