//! The engine fogs' blurs ([`FogBlur`]): paper 001's Gaussian ([`GaussBlur`]) and
//! brume's diffusion ([`Blur`]), and choosing one by name as a host's options do.

use crate::blur::{Blur, Precision};
use crate::error::{check_positive, Error, Result};
use crate::medium::UniformValue;

/// The Gaussian blur's parameters (paper 001, sec. 3.4; [`GaussBlur::weight`] is its
/// weight b).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussBlur {
    /// Distance (world units) at which the weight reaches the fog's density (> 0).
    pub distance: f64,
    /// Exponent of the distance (≥ 0).
    pub falloff: f64,
    /// Largest weight, in [0, 1].
    pub maximum: f64,
    /// Precision of the intermediate target of the separate mode, and of the read-back.
    pub precision: Precision,
}

impl Default for GaussBlur {
    /// Weight = the fog's density at 100 units, growing linearly with distance, at most 1.
    fn default() -> Self {
        GaussBlur {
            distance: 100.0,
            falloff: 1.0,
            maximum: 1.0,
            precision: Precision::F32,
        }
    }
}

impl GaussBlur {
    /// Rejects out-of-domain parameters by name.
    pub fn validate(&self) -> Result<()> {
        check_positive("blur_distance", self.distance)?;
        if !(self.falloff.is_finite() && self.falloff >= 0.0) {
            return Err(Error::invalid("blur_falloff", self.falloff, "a number ≥ 0"));
        }
        if !(0.0..=1.0).contains(&self.maximum) {
            return Err(Error::invalid(
                "blur_max",
                self.maximum,
                "a weight in [0, 1]",
            ));
        }
        Ok(())
    }

    /// The weight b of the blurred image at distance `l` for a fog of `density` (the
    /// GLSL's `blur_weight`).
    pub fn weight(&self, density: f64, l: f64) -> f64 {
        (density * (l.max(0.0) / self.distance).powf(self.falloff)).min(self.maximum)
    }

    pub(super) fn uniform(&self) -> UniformValue {
        UniformValue::Vec3([
            self.distance as f32,
            self.falloff as f32,
            self.maximum as f32,
        ])
    }
}

/// How engine fog is blurred: not at all (one pass), by paper 001's Gaussian in the
/// fog's pass or in a second one, or by brume's diffusion to the medium's σ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FogBlur {
    /// Fog only, one pass.
    None,
    /// Paper 001: the fog-free image blurred in the fog's pass.
    GaussSingle(GaussBlur),
    /// Paper 001: the fogged image blurred in a second pass.
    GaussSeparate(GaussBlur),
    /// brume's diffusion blur to the medium's σ.
    Diffusion(Blur),
}

impl FogBlur {
    /// `none`, `gauss-single`, `gauss-separate` or `diffusion`.
    pub fn name(&self) -> &'static str {
        match self {
            FogBlur::None => "none",
            FogBlur::GaussSingle(_) => "gauss-single",
            FogBlur::GaussSeparate(_) => "gauss-separate",
            FogBlur::Diffusion(_) => "diffusion",
        }
    }

    /// The blur named `name` (`none`, `gauss-single`, `gauss-separate` or `diffusion`,
    /// as [`FogBlur::name`] gives them) with `gauss`'s or `diffusion`'s settings: how
    /// `brume scene --blur` and the Python engine fogs choose one. The Gaussian's values
    /// are checked whichever is chosen, the diffusion's when it is. A setting of a blur
    /// not chosen that differs from its default (`sigma0` without the diffusion blur,
    /// `blur_max` without a Gaussian one, a `precision` without any blur) is refused,
    /// naming its field: it cannot take effect.
    pub fn chosen(name: &str, gauss: GaussBlur, diffusion: Blur) -> Result<FogBlur> {
        gauss.validate()?;
        let blur = match name {
            "none" => FogBlur::None,
            "gauss-single" => FogBlur::GaussSingle(gauss),
            "gauss-separate" => FogBlur::GaussSeparate(gauss),
            "diffusion" => FogBlur::Diffusion(diffusion),
            other => {
                return Err(Error::invalid(
                    "blur",
                    format!("{other:?}"),
                    "'none', 'gauss-single', 'gauss-separate' or 'diffusion'",
                ))
            }
        };
        if let FogBlur::Diffusion(d) = &blur {
            d.validate()?;
        }
        refuse_unread(&blur, &gauss, &diffusion)
    }

    /// Refuses a medium's blur strength λ given (`lambda`) with a blur other than the
    /// diffusion, the only one that reads it.
    pub fn check_lambda(&self, lambda: Option<f64>) -> Result<()> {
        match (lambda, self) {
            (Some(lambda), FogBlur::None | FogBlur::GaussSingle(_) | FogBlur::GaussSeparate(_)) => {
                Err(Error::invalid(
                    "lambda",
                    lambda,
                    format!("`blur` diffusion with it, not `blur` {}", self.name()),
                ))
            }
            _ => Ok(()),
        }
    }
}

/// `blur`, or the first setting of `gauss` or `diffusion` that it does not read and
/// that differs from its default, refused saying which blur reads it.
fn refuse_unread(blur: &FogBlur, gauss: &GaussBlur, diffusion: &Blur) -> Result<FogBlur> {
    let (g, d) = (GaussBlur::default(), Blur::default());
    let gaussian = [
        differs("blur_distance", gauss.distance, g.distance),
        differs("blur_falloff", gauss.falloff, g.falloff),
        differs("blur_max", gauss.maximum, g.maximum),
    ];
    let diffusing = [
        differs("scheme", diffusion.scheme, d.scheme),
        differs("sigma0", diffusion.sigma0, d.sigma0),
        differs("rho_max", diffusion.rho_max, d.rho_max),
    ];
    let precision = [
        differs("precision", gauss.precision, g.precision).or(differs(
            "precision",
            diffusion.precision,
            d.precision,
        )),
    ];
    let groups = [
        (
            matches!(blur, FogBlur::GaussSingle(_) | FogBlur::GaussSeparate(_)),
            &gaussian[..],
            "`blur` gauss-single or gauss-separate",
        ),
        (
            matches!(blur, FogBlur::Diffusion(_)),
            &diffusing[..],
            "`blur` diffusion",
        ),
        (*blur != FogBlur::None, &precision[..], "a blur"),
    ];
    for (read, settings, needs) in groups {
        if let (false, Some((field, value))) = (read, settings.iter().flatten().next()) {
            return Err(Error::invalid(
                *field,
                value,
                format!("{needs} with it, not `blur` {}", blur.name()),
            ));
        }
    }
    Ok(*blur)
}

/// `field` = `value` where it is not `default`.
fn differs<T: PartialEq + std::fmt::Display>(
    field: &'static str,
    value: T,
    default: T,
) -> Option<(&'static str, String)> {
    (value != default).then(|| (field, value.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_blur_is_chosen_by_name_and_another_blurs_settings_are_refused() {
        let (g, d) = (GaussBlur::default(), Blur::default());
        let chosen = |name: &str, g: GaussBlur, d: Blur| FogBlur::chosen(name, g, d);
        assert_eq!(chosen("none", g, d).unwrap(), FogBlur::None);
        assert_eq!(
            chosen("gauss-single", g, d).unwrap(),
            FogBlur::GaussSingle(g)
        );
        let err = |r: Result<FogBlur>| r.unwrap_err().to_string();
        let sigma = Blur { sigma0: 2.0, ..d };
        assert_eq!(
            err(chosen("none", g, sigma)),
            "invalid sigma0 = 2: expected `blur` diffusion with it, not `blur` none"
        );
        assert_eq!(
            chosen("diffusion", g, sigma).unwrap(),
            FogBlur::Diffusion(sigma)
        );
        let wide = GaussBlur { maximum: 0.5, ..g };
        assert!(err(chosen("diffusion", wide, d)).starts_with("invalid blur_max = 0.5"));
        assert_eq!(
            chosen("gauss-separate", wide, d).unwrap(),
            FogBlur::GaussSeparate(wide)
        );
        let half = (
            GaussBlur {
                precision: Precision::F16,
                ..g
            },
            Blur {
                precision: Precision::F16,
                ..d
            },
        );
        assert!(err(chosen("none", half.0, half.1)).contains("a blur with it"));
        assert!(chosen("gauss-single", half.0, half.1).is_ok());
        // Values are checked: the Gaussian's whichever blur is chosen, the diffusion's
        // when it is.
        let bad = GaussBlur { maximum: 2.0, ..g };
        assert!(err(chosen("none", bad, d)).starts_with("invalid blur_max = 2"));
        // λ is the medium's, and only the diffusion blur reads it.
        assert!(FogBlur::Diffusion(d).check_lambda(Some(4.0)).is_ok());
        assert!(FogBlur::None.check_lambda(None).is_ok());
        assert_eq!(
            FogBlur::GaussSingle(g)
                .check_lambda(Some(4.0))
                .unwrap_err()
                .to_string(),
            "invalid lambda = 4: expected `blur` diffusion with it, not `blur` gauss-single"
        );
        let bad = Blur { sigma0: 0.0, ..d };
        assert!(err(chosen("diffusion", g, bad)).starts_with("invalid sigma0 = 0"));
        assert!(err(chosen("box", g, d)).starts_with("invalid blur = \"box\""));
    }
}
