//! The Preetham, Shirley and Smits (1999) analytic daylight model ("A Practical Analytic
//! Model for Daylight", SIGGRAPH 99), as paper 002 uses it (sec. 3.2, eq. 6).
//!
//! Each of the luminance Y and the CIE chromaticities x and y of the sky in the direction
//! (θ, φ) is its zenith value times a ratio of Perez functions (Perez, Seals and Michalsky
//! 1993):
//!
//! ```text
//! Y(θ, γ) = Y_z · F_Y(θ, γ) / F_Y(0, θs)                                     (eq. 6)
//! F(θ, γ) = (1 + A·e^(B / cos θ)) · (1 + C·e^(D·γ) + E·cos²γ)
//! ```
//!
//! with γ the angle between the direction and the sun, and A..E linear in the turbidity T
//! ([`Perez::luminance`], [`Perez::x`], [`Perez::y`]). F(0, θs) is F at the zenith, whose
//! angle to the sun is θs: the ratio is 1 there, so Y(0, ·) = Y_z.
//!
//! # Coefficients and where they come from
//!
//! The distribution coefficients and the zenith formulas are the published ones, from the
//! appendix of Preetham et al. 1999 (A.2 for A..E, A.3 for Y_z, x_z, y_z), 4 decimals.
//! They were checked one by one against open implementations: Mitsuba 0.x
//! (`src/luminaires/sky.cpp`, a port of the authors' own code, which carries one more
//! decimal: 0.17872T − 1.46303 for A_Y …, and 0.00165 where the printed x_z matrix has
//! 0.00166) and several GLSL/HLSL ports of the paper's table that agree with it digit for
//! digit (e.g. the sky-model shaders derived from Dihara Wijetunga's `sky-models`). The
//! three.js `Sky` shader, often called "Preetham", does not use these tables (it is
//! Wallner's Rayleigh/Mie approximation) and was not used.
//!
//! Units: Y_z and Y are in kcd/m² (the paper's zenith formula), x and y are CIE 1931
//! chromaticities.
//!
//! # Colour
//!
//! [`PreethamSky::rgb`] converts xyY to XYZ (X = x·Y/y, Z = (1 − x − y)·Y/y) and XYZ to
//! linear sRGB with the inverse of the IEC 61966-2-1 matrix (D65 white, no chromatic adaptation: the
//! model's chromaticities are absolute). Negative components (out of the sRGB gamut,
//! which does not happen for T in 2..10 and a sun above the horizon) are clamped to 0.

use crate::error::{Error, Result};
use std::f64::consts::{FRAC_PI_2, PI};

/// The five Perez distribution coefficients A..E of one quantity (Y, x or y) at one
/// turbidity.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Perez {
    /// Darkening or brightening toward the horizon.
    pub a: f64,
    /// Its gradient.
    pub b: f64,
    /// Relative intensity of the circumsolar region.
    pub c: f64,
    /// Width of the circumsolar region.
    pub d: f64,
    /// Relative intensity of backscattered light.
    pub e: f64,
}

/// `[slope, intercept]` of A..E as linear functions of T: coefficient = slope·T + intercept.
type LinearInT = [[f64; 2]; 5];

/// Preetham et al. 1999, appendix A.2: the luminance Y.
const PEREZ_Y: LinearInT = [
    [0.1787, -1.4630],
    [-0.3554, 0.4275],
    [-0.0227, 5.3251],
    [0.1206, -2.5771],
    [-0.0670, 0.3703],
];
/// Preetham et al. 1999, appendix A.2: the chromaticity x.
const PEREZ_X: LinearInT = [
    [-0.0193, -0.2592],
    [-0.0665, 0.0008],
    [-0.0004, 0.2125],
    [-0.0641, -0.8989],
    [-0.0033, 0.0452],
];
/// Preetham et al. 1999, appendix A.2: the chromaticity y.
const PEREZ_CHROMA_Y: LinearInT = [
    [-0.0167, -0.2608],
    [-0.0950, 0.0092],
    [-0.0079, 0.2102],
    [-0.0441, -1.6537],
    [-0.0109, 0.0529],
];

/// Preetham et al. 1999, appendix A.3: x_z = [T² T 1] · M · [θs³ θs² θs 1]ᵀ.
const ZENITH_X: [[f64; 4]; 3] = [
    [0.00166, -0.00375, 0.00209, 0.0],
    [-0.02903, 0.06377, -0.03202, 0.00394],
    [0.11693, -0.21196, 0.06052, 0.25886],
];
/// Preetham et al. 1999, appendix A.3: y_z, as [`ZENITH_X`].
const ZENITH_Y: [[f64; 4]; 3] = [
    [0.00275, -0.00610, 0.00317, 0.0],
    [-0.04214, 0.08970, -0.04153, 0.00516],
    [0.15346, -0.26756, 0.06670, 0.26688],
];

/// Linear sRGB from XYZ (D65): the exact inverse of IEC 61966-2-1's sRGB to XYZ matrix,
/// whose Y row is 0.2126, 0.7152, 0.0722 ([`super::luminance`]), so that the luminance of
/// the RGB is the model's Y. (The standard prints this inverse rounded to 4 decimals,
/// 3.2406, −1.5372, …, which would leave errors of a few 10⁻⁵ in Y.)
const XYZ_TO_SRGB: [[f64; 3]; 3] = [
    [3.2406254773, -1.5372079722, -0.4986285987],
    [-0.9689307147, 1.8757560609, 0.0415175238],
    [0.0557101204, -0.2040210506, 1.0569959423],
];

/// The smallest turbidity of the model's domain here: T = 1 is pure air (eq. 5).
pub const MIN_TURBIDITY: f64 = 1.0;
/// The largest turbidity accepted, the top of paper 002's search range (eq. 8). The fit
/// of Preetham et al. covers about 2..10; beyond, the formulas are extrapolated.
pub const MAX_TURBIDITY: f64 = 20.0;
/// Largest zenith angle at which the Perez function is evaluated: directions closer to
/// the horizon take its value (1/cos θ diverges there; Mitsuba's port clamps the same
/// way, at π/2 − 0.001).
pub const MAX_VIEW_ZENITH: f64 = FRAC_PI_2 - 1e-3;

impl Perez {
    fn from_table(table: &LinearInT, t: f64) -> Self {
        let c = |i: usize| table[i][0] * t + table[i][1];
        Perez {
            a: c(0),
            b: c(1),
            c: c(2),
            d: c(3),
            e: c(4),
        }
    }

    /// dA/dT .. dE/dT of a table (constant: the coefficients are linear in T).
    fn slopes(table: &LinearInT) -> Self {
        Perez {
            a: table[0][0],
            b: table[1][0],
            c: table[2][0],
            d: table[3][0],
            e: table[4][0],
        }
    }

    /// The coefficients of the luminance Y at turbidity `t`.
    pub fn luminance(t: f64) -> Self {
        Self::from_table(&PEREZ_Y, t)
    }

    /// Their derivatives with respect to T (for the estimator's Jacobian).
    pub fn luminance_slopes() -> Self {
        Self::slopes(&PEREZ_Y)
    }

    /// The coefficients of the chromaticity x at turbidity `t`.
    pub fn x(t: f64) -> Self {
        Self::from_table(&PEREZ_X, t)
    }

    /// The coefficients of the chromaticity y at turbidity `t`.
    pub fn y(t: f64) -> Self {
        Self::from_table(&PEREZ_CHROMA_Y, t)
    }

    /// The Perez function F(θ, γ) = (1 + A·e^(B/cos θ))·(1 + C·e^(D·γ) + E·cos²γ), with θ
    /// clamped to [`MAX_VIEW_ZENITH`].
    pub fn eval(&self, theta: f64, gamma: f64) -> f64 {
        self.eval_parts(secant(theta), gamma, gamma.cos().powi(2))
    }

    /// F from the precomputed parts of a direction: sec θ ([`secant`]), γ and cos²γ (the
    /// estimator evaluates F at the same points for many T).
    pub(crate) fn eval_parts(&self, sec: f64, gamma: f64, cos2: f64) -> f64 {
        (1.0 + self.a * (self.b * sec).exp())
            * (1.0 + self.c * (self.d * gamma).exp() + self.e * cos2)
    }

    /// F(θ, γ) and dF/dT, given the coefficients at T and their slopes `ds`.
    pub fn eval_with_derivative(&self, ds: &Perez, theta: f64, gamma: f64) -> (f64, f64) {
        self.eval_parts_with_derivative(ds, secant(theta), gamma, gamma.cos().powi(2))
    }

    /// [`Perez::eval_with_derivative`] from precomputed parts, as [`Perez::eval_parts`].
    pub(crate) fn eval_parts_with_derivative(
        &self,
        ds: &Perez,
        sec: f64,
        gamma: f64,
        cos2: f64,
    ) -> (f64, f64) {
        let eb = (self.b * sec).exp();
        let g = 1.0 + self.a * eb;
        let dg = ds.a * eb + self.a * eb * ds.b * sec;
        let ed = (self.d * gamma).exp();
        let h = 1.0 + self.c * ed + self.e * cos2;
        let dh = ds.c * ed + self.c * ed * ds.d * gamma + ds.e * cos2;
        (g * h, dg * h + g * dh)
    }
}

/// 1/cos θ with θ clamped to [`MAX_VIEW_ZENITH`]: the argument of the Perez gradation term.
pub fn secant(theta: f64) -> f64 {
    1.0 / theta.min(MAX_VIEW_ZENITH).cos()
}

/// Preetham's zenith luminance Y_z(T, θs) in kcd/m²:
/// (4.0453T − 4.9710)·tan χ − 0.2155T + 2.4192, χ = (4/9 − T/120)(π − 2θs).
pub fn zenith_luminance(t: f64, sun_zenith: f64) -> f64 {
    let chi = (4.0 / 9.0 - t / 120.0) * (PI - 2.0 * sun_zenith);
    (4.0453 * t - 4.9710) * chi.tan() - 0.2155 * t + 2.4192
}

/// Preetham's zenith chromaticity (x_z, y_z) at turbidity `t` and sun zenith angle
/// `sun_zenith` (radians).
pub fn zenith_chromaticity(t: f64, sun_zenith: f64) -> (f64, f64) {
    let s = sun_zenith;
    let thetas = [s * s * s, s * s, s, 1.0];
    let ts = [t * t, t, 1.0];
    let poly = |m: &[[f64; 4]; 3]| -> f64 {
        (0..3)
            .map(|i| ts[i] * (0..4).map(|j| m[i][j] * thetas[j]).sum::<f64>())
            .sum()
    };
    (poly(&ZENITH_X), poly(&ZENITH_Y))
}

/// The unit vector of direction (θ, φ): z up, x toward φ = 0.
pub fn unit_vector(theta: f64, phi: f64) -> [f64; 3] {
    let s = theta.sin();
    [s * phi.cos(), s * phi.sin(), theta.cos()]
}

/// The angle γ between directions (θ1, φ1) and (θ2, φ2).
pub fn angle_between(theta1: f64, phi1: f64, theta2: f64, phi2: f64) -> f64 {
    let c = theta1.cos() * theta2.cos() + theta1.sin() * theta2.sin() * (phi1 - phi2).cos();
    c.clamp(-1.0, 1.0).acos()
}

/// Checks a turbidity for the model: finite, in [[`MIN_TURBIDITY`], [`MAX_TURBIDITY`]].
pub fn check_turbidity(t: f64) -> Result<()> {
    if t.is_finite() && (MIN_TURBIDITY..=MAX_TURBIDITY).contains(&t) {
        Ok(())
    } else {
        Err(Error::invalid(
            "turbidity",
            t,
            format!("a turbidity T in [{MIN_TURBIDITY}, {MAX_TURBIDITY}] (1: pure air)"),
        ))
    }
}

/// Checks a sun position (radians): zenith angle in [0, 90°) (the model has no night,
/// and a sun on the horizon makes tan χ of Y_z meaningless), finite azimuth.
pub fn check_sun(sun_zenith: f64, sun_azimuth: f64) -> Result<()> {
    if !(sun_zenith.is_finite() && (0.0..FRAC_PI_2).contains(&sun_zenith)) {
        return Err(Error::invalid(
            "sun_zenith",
            format!("{}°", sun_zenith.to_degrees()),
            "a zenith angle in [0°, 90°) (the sun above the horizon)",
        ));
    }
    if !sun_azimuth.is_finite() {
        return Err(Error::invalid(
            "sun_azimuth",
            sun_azimuth,
            "a finite azimuth",
        ));
    }
    Ok(())
}

/// A Preetham sky: turbidity and sun position, with the model's coefficients and zenith
/// values computed once.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PreethamSky {
    turbidity: f64,
    sun_zenith: f64,
    sun_azimuth: f64,
    perez: [Perez; 3],
    /// Y_z (kcd/m²), x_z, y_z.
    zenith: [f64; 3],
    /// F(0, θs) of Y, x, y: the denominators of eq. 6.
    norm: [f64; 3],
}

impl PreethamSky {
    /// The sky of turbidity `turbidity` (in [1, 20]) with the sun at zenith angle
    /// `sun_zenith` (radians, in [0, π/2)) and azimuth `sun_azimuth` (radians, any finite
    /// value: it is only compared with the view azimuth). Refuses, naming the parameter,
    /// values outside these domains and the rare low sun at high turbidity for which
    /// Preetham's Y_z formula is not positive.
    pub fn new(turbidity: f64, sun_zenith: f64, sun_azimuth: f64) -> Result<Self> {
        check_turbidity(turbidity)?;
        check_sun(sun_zenith, sun_azimuth)?;
        let t = turbidity;
        let perez = [Perez::luminance(t), Perez::x(t), Perez::y(t)];
        let (xz, yz) = zenith_chromaticity(t, sun_zenith);
        let zenith = [zenith_luminance(t, sun_zenith), xz, yz];
        if zenith[0] <= 0.0 {
            return Err(Error::invalid(
                "sun_zenith",
                format!("{}°", sun_zenith.to_degrees()),
                format!(
                    "a higher sun: at T = {t} Preetham's zenith luminance formula gives {:.3} \
                     kcd/m² (not positive) for this sun",
                    zenith[0]
                ),
            ));
        }
        let norm = perez.map(|p| p.eval(0.0, sun_zenith));
        Ok(PreethamSky {
            turbidity,
            sun_zenith,
            sun_azimuth,
            perez,
            zenith,
            norm,
        })
    }

    /// The turbidity T.
    pub fn turbidity(&self) -> f64 {
        self.turbidity
    }

    /// The sun's zenith angle θs, radians.
    pub fn sun_zenith(&self) -> f64 {
        self.sun_zenith
    }

    /// The sun's azimuth φs, radians, as given.
    pub fn sun_azimuth(&self) -> f64 {
        self.sun_azimuth
    }

    /// Y_z, the zenith luminance, kcd/m².
    pub fn zenith_luminance(&self) -> f64 {
        self.zenith[0]
    }

    /// (x_z, y_z), the zenith chromaticity.
    pub fn zenith_chromaticity(&self) -> (f64, f64) {
        (self.zenith[1], self.zenith[2])
    }

    /// The Perez coefficients of Y, x and y, in that order.
    pub fn coefficients(&self) -> [Perez; 3] {
        self.perez
    }

    /// γ, the angle between the direction (θ, φ) and the sun.
    pub fn sun_angle(&self, theta: f64, phi: f64) -> f64 {
        angle_between(theta, phi, self.sun_zenith, self.sun_azimuth)
    }

    /// Eq. 6's ratio F(θ, γ)/F(0, θs) of the luminance: Y(θ, φ)/Y_z.
    pub fn relative_luminance(&self, theta: f64, phi: f64) -> f64 {
        self.perez[0].eval(theta, self.sun_angle(theta, phi)) / self.norm[0]
    }

    /// The luminance Y (kcd/m²) in direction (θ, φ) (radians, θ from the zenith). Below
    /// the horizon (θ > π/2) the model is undefined: 0.
    pub fn luminance(&self, theta: f64, phi: f64) -> f64 {
        if theta > FRAC_PI_2 {
            return 0.0;
        }
        self.zenith[0] * self.relative_luminance(theta, phi)
    }

    /// The luminance ratio Y(θ, φ)/Y(θref, φref) of eq. 8's model side: Y_z cancels and
    /// only the Perez functions remain.
    pub fn luminance_ratio(&self, theta: f64, phi: f64, theta_ref: f64, phi_ref: f64) -> f64 {
        let f = |t: f64, p: f64| self.perez[0].eval(t, self.sun_angle(t, p));
        f(theta, phi) / f(theta_ref, phi_ref)
    }

    /// CIE (x, y, Y) in direction (θ, φ), Y in kcd/m²; (0, 0, 0) below the horizon.
    pub fn xyy(&self, theta: f64, phi: f64) -> [f64; 3] {
        if theta > FRAC_PI_2 {
            return [0.0; 3];
        }
        let gamma = self.sun_angle(theta, phi);
        let v = |i: usize| self.zenith[i] * self.perez[i].eval(theta, gamma) / self.norm[i];
        [v(1), v(2), v(0)]
    }

    /// CIE XYZ in direction (θ, φ), kcd/m² (see the module docs).
    pub fn xyz(&self, theta: f64, phi: f64) -> [f64; 3] {
        let [x, y, big_y] = self.xyy(theta, phi);
        if big_y <= 0.0 || y <= 0.0 {
            return [0.0; 3];
        }
        [x * big_y / y, big_y, (1.0 - x - y) * big_y / y]
    }

    /// Linear sRGB in direction (θ, φ), in kcd/m² (its Rec. 709 luminance is Y), negative
    /// components clamped to 0 (see the module docs).
    pub fn rgb(&self, theta: f64, phi: f64) -> [f64; 3] {
        let xyz = self.xyz(theta, phi);
        XYZ_TO_SRGB.map(|row| (row[0] * xyz[0] + row[1] * xyz[1] + row[2] * xyz[2]).max(0.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sky::luminance;

    const SUN: (f64, f64) = (58.4, -179.4);

    fn sky(t: f64) -> PreethamSky {
        PreethamSky::new(t, SUN.0.to_radians(), SUN.1.to_radians()).unwrap()
    }

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn coefficients_match_the_published_table() {
        // Spot values worked by hand from Preetham et al. 1999, appendix A.2.
        let y = Perez::luminance(2.0);
        assert!(close(y.a, -1.1056, 1e-12) && close(y.b, -0.2833, 1e-12));
        assert!(close(y.c, 5.2797, 1e-12) && close(y.d, -2.3359, 1e-12));
        assert!(close(y.e, 0.2363, 1e-12));
        let x = Perez::x(5.0);
        assert!(close(x.a, -0.3557, 1e-12) && close(x.d, -1.2194, 1e-12));
        let cy = Perez::y(9.0);
        assert!(close(cy.b, -0.8458, 1e-12) && close(cy.e, -0.0452, 1e-12));
        // Zenith values, appendix A.3: sun at the zenith leaves the constant column.
        let (xz, yz) = zenith_chromaticity(2.0, 0.0);
        assert!(close(xz, 2.0 * 0.00394 + 0.25886, 1e-12), "{xz}");
        assert!(close(yz, 2.0 * 0.00516 + 0.26688, 1e-12), "{yz}");
        // θs = 1 rad sums each row.
        let (xz, _) = zenith_chromaticity(3.0, 1.0);
        let want = 9.0 * (0.00166 - 0.00375 + 0.00209)
            + 3.0 * (-0.02903 + 0.06377 - 0.03202 + 0.00394)
            + (0.11693 - 0.21196 + 0.06052 + 0.25886);
        assert!(close(xz, want, 1e-12));
        // Y_z at T = 2, θs = 30°: χ = (4/9 − 1/60)·(2π/3).
        let chi: f64 = (4.0 / 9.0 - 2.0 / 120.0) * (2.0 * PI / 3.0);
        let want = (4.0453 * 2.0 - 4.9710) * chi.tan() - 0.2155 * 2.0 + 2.4192;
        assert!(close(
            zenith_luminance(2.0, 30f64.to_radians()),
            want,
            1e-12
        ));
        // Clear sky, sun at 30°: a few kcd/m², as in the paper's Fig. 4.
        assert!((3.0..6.0).contains(&want), "{want}");
    }

    #[test]
    fn the_zenith_is_y_z_and_the_sky_is_bluish() {
        for t in 2..=9 {
            let s = sky(t as f64);
            for phi in [-3.0, 0.0, 1.0, 2.5] {
                assert!(close(s.luminance(0.0, phi), s.zenith_luminance(), 1e-12));
                assert!(close(s.relative_luminance(0.0, phi), 1.0, 1e-12));
                let [x, y, _] = s.xyy(0.0, phi);
                let (xz, yz) = s.zenith_chromaticity();
                assert!(close(x, xz, 1e-12) && close(y, yz, 1e-12));
            }
            // Clear skies are blue (B > R) away from the sun; turbid ones greyer.
            let rgb = s.rgb(0.3, 0.0);
            assert!(rgb[2] > rgb[0], "T = {t}: {rgb:?}");
            // The RGB's Rec. 709 luminance is the model's Y.
            for (th, ph) in [(0.2, 0.1), (1.2, -2.0), (1.5, 3.0)] {
                let rgb = s.rgb(th, ph).map(|c| c as f32);
                let y = s.luminance(th, ph);
                assert!(
                    close(luminance(rgb), y, 1e-4 * y),
                    "{} vs {y}",
                    luminance(rgb)
                );
            }
        }
        let blue = |t: f64| {
            let c = sky(t).rgb(0.3, 0.0);
            c[2] / c[0]
        };
        assert!(blue(2.0) > blue(9.0));
    }

    #[test]
    fn brightest_toward_the_sun_along_its_almucantar() {
        for t in 2..=9 {
            let s = sky(t as f64);
            let (ts, ps) = (s.sun_zenith(), s.sun_azimuth());
            // At the sun's zenith angle, luminance falls as the azimuth moves away, up to
            // 90° (beyond, the backscatter term E·cos²γ may lift it again).
            let mut last = f64::INFINITY;
            for k in 0..=18 {
                let y = s.luminance(ts, ps + (k as f64 * 5.0).to_radians());
                assert!(y < last, "T = {t}, {}°: {y} ≥ {last}", k * 5);
                last = y;
            }
            // Over the whole sky, the brightest point is in the sun's half.
            let mut best = (0.0, 0.0, 0.0);
            for i in 0..=89 {
                for j in -180..180 {
                    let (th, ph) = ((i as f64).to_radians(), (j as f64).to_radians());
                    let y = s.luminance(th, ph);
                    if y > best.0 {
                        best = (y, th, ph);
                    }
                }
            }
            assert!(
                s.sun_angle(best.1, best.2) < 40f64.to_radians(),
                "T = {t}: {best:?}"
            );
            // The circumsolar sky is several times the antisolar sky at the same height.
            let ratio = s.luminance(ts - 0.05, ps) / s.luminance(ts - 0.05, ps + PI);
            assert!(ratio > 2.0, "T = {t}: {ratio}");
        }
    }

    #[test]
    fn horizon_to_zenith_ratio_falls_with_turbidity() {
        // Away from the sun, a clear sky is much brighter at the horizon than at its deep
        // blue zenith (A < 0); haze evens the sky out, so the ratio falls as T grows.
        let ratio = |t: f64| {
            let s = sky(t);
            s.luminance(80f64.to_radians(), s.sun_azimuth() + PI / 2.0) / s.zenith_luminance()
        };
        let mut last = f64::INFINITY;
        for t in 2..=9 {
            let r = ratio(t as f64);
            assert!(r < last, "T = {t}: {r}");
            last = r;
        }
        assert!(ratio(2.0) > 2.0, "{}", ratio(2.0));
        // Overall, the zenith luminance grows with T (more scattering).
        assert!(sky(9.0).zenith_luminance() > sky(2.0).zenith_luminance());
    }

    #[test]
    fn luminance_is_continuous() {
        for t in [2.0, 5.5, 9.0] {
            let s = sky(t);
            let step = 1e-6;
            for i in 0..90 {
                for j in -180..180 {
                    let (th, ph) = ((i as f64).to_radians(), (j as f64).to_radians());
                    let y = s.luminance(th, ph);
                    let dy = (s.luminance(th + step, ph) - y).abs()
                        + (s.luminance(th, ph + step) - y).abs();
                    assert!(dy < 1e-3 * y.max(1e-3), "T = {t} at ({i}°, {j}°)");
                }
            }
            // Across the azimuth seam.
            let a = s.luminance(0.7, PI - 1e-9);
            let b = s.luminance(0.7, -PI + 1e-9);
            assert!(close(a, b, 1e-6 * a));
            // In T.
            let a = PreethamSky::new(t, 1.0, 0.3).unwrap().luminance(0.5, 2.0);
            let b = PreethamSky::new(t + 1e-7, 1.0, 0.3)
                .unwrap()
                .luminance(0.5, 2.0);
            assert!(close(a, b, 1e-5 * a));
        }
    }

    #[test]
    fn derivative_in_t_matches_differences() {
        let slopes = Perez::luminance_slopes();
        for t in [1.5, 4.0, 12.0] {
            let h = 1e-6;
            for (th, g) in [(0.0, 1.0), (1.2, 0.3), (1.5, 2.5)] {
                let (_, d) = Perez::luminance(t).eval_with_derivative(&slopes, th, g);
                let fd = (Perez::luminance(t + h).eval(th, g)
                    - Perez::luminance(t - h).eval(th, g))
                    / (2.0 * h);
                assert!(close(d, fd, 1e-6 * fd.abs().max(1.0)), "{d} vs {fd}");
            }
        }
    }

    #[test]
    fn bad_parameters_are_named() {
        let e = PreethamSky::new(0.5, 0.5, 0.0).unwrap_err().to_string();
        assert!(e.contains("turbidity"), "{e}");
        let e = PreethamSky::new(f64::NAN, 0.5, 0.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("turbidity"), "{e}");
        let e = PreethamSky::new(3.0, FRAC_PI_2, 0.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("sun_zenith") && e.contains("90°"), "{e}");
        let e = PreethamSky::new(3.0, -0.1, 0.0).unwrap_err().to_string();
        assert!(e.contains("sun_zenith"), "{e}");
        let e = PreethamSky::new(3.0, 0.1, f64::INFINITY)
            .unwrap_err()
            .to_string();
        assert!(e.contains("sun_azimuth"), "{e}");
        // T = 20 with a sun just above the horizon: Y_z < 0.
        let e = PreethamSky::new(20.0, 89.5f64.to_radians(), 0.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("zenith luminance"), "{e}");
    }
}
