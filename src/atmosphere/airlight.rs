//! ζ(T, θ, θ′) of paper 002 (eq. 13): the ratio of the sky's intensity at zenith angle θ to
//! that at θ′ on the same azimuth, from the gradation term of Preetham's luminance model,
//! by which eq. 12 carries the horizon's measured airlight to other view directions.

/// The largest zenith angle ζ evaluates (rad): 89.9°. Views at or below the horizon
/// (θ ≥ 90°, cos θ ≤ 0) take the ratio of this angle.
pub const ZETA_MAX_ZENITH_RAD: f64 = 89.9 * std::f64::consts::PI / 180.0;

/// The smallest turbidity ζ evaluates: lower turbidities are taken as this one.
pub const ZETA_MIN_TURBIDITY: f64 = 1.7;

/// (A, B) of Preetham's gradation 1 + A·e^(B/cos θ) at turbidity T: A = 0.178T − 1.463,
/// B = −0.355T + 0.427 ([`zeta`] clamps T first). These are paper 002's eq. 13 as printed:
/// Preetham et al.'s own A_Y, B_Y (0.1787T − 1.4630, −0.3554T + 0.4275, `sky::preetham`)
/// rounded to three decimals, which moves ζ by 0.8 % at T = 2 and 0.04 % at T = 9.
pub fn gradation_coefficients(turbidity: f64) -> [f64; 2] {
    [0.178 * turbidity - 1.463, -0.355 * turbidity + 0.427]
}

/// Preetham's gradation 1 + A·e^(B/cos θ), θ clamped to [0, [`ZETA_MAX_ZENITH_RAD`]].
fn gradation(turbidity: f64, zenith_rad: f64) -> f64 {
    let cos = zenith_rad.clamp(0.0, ZETA_MAX_ZENITH_RAD).cos();
    let [a, b] = gradation_coefficients(turbidity);
    1.0 + a * (b / cos).exp()
}

/// ζ(T, θ, θ′) (eq. 13): the sky's intensity at zenith angle `zenith_rad` over that at
/// `reference_zenith_rad` (radians), same azimuth, at turbidity `turbidity`.
///
/// Where it is defined and why it is clamped:
///
/// - **θ toward 90°.** For T > 1.203, B < 0 and e^(B/cos θ) → 0 as cos θ → 0⁺: the
///   gradation tends to 1 at the horizon and stays finite. For T < 1.203, B > 0 and it
///   diverges (e^(B/cos θ) → ∞), and below the horizon (cos θ < 0) the sign of the exponent
///   flips for every T and it diverges too. Both angles are therefore clamped to
///   [0, [`ZETA_MAX_ZENITH_RAD`]] = [0°, 89.9°] (cos θ ≥ 0.0017): views below the horizon
///   (distant terrain seen downward) get the horizon's ratio.
/// - **Low T.** The gradation at the zenith, 1 + A·e^B, crosses zero at T ≈ 1.645 (it is
///   negative below, and the ratio changes sign or divides by zero); Preetham's fit is not
///   meant for such clear air. T is therefore clamped to at least [`ZETA_MIN_TURBIDITY`]
///   = 1.7, where the gradation is positive at every θ (0.027 at the zenith, rising to 1 at
///   the horizon), which keeps the lowest turbidity the paper measured (1.9) unchanged.
///
/// ζ(T, θ, θ) = 1 and ζ(T, θ, θ′)·ζ(T, θ′, θ) = 1. For 1.7 ≤ T < 8.2 (A < 0) the sky
/// brightens toward the horizon, so ζ(T, θ, 90°) ≤ 1 rises with θ; above T ≈ 8.2 (A > 0)
/// Preetham's gradation inverts.
pub fn zeta(turbidity: f64, zenith_rad: f64, reference_zenith_rad: f64) -> f64 {
    let t = turbidity.max(ZETA_MIN_TURBIDITY);
    gradation(t, zenith_rad) / gradation(t, reference_zenith_rad)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn deg(d: f64) -> f64 {
        d.to_radians()
    }

    #[test]
    fn zeta_is_one_on_the_same_angle_and_reciprocal() {
        for t in [1.0, 1.7, 1.9, 2.94, 4.36, 9.0, 20.0] {
            for a in [0.0, 10.0, 45.0, 80.0, 89.0, 90.0, 120.0] {
                assert!((zeta(t, deg(a), deg(a)) - 1.0).abs() < 1e-15, "T {t} θ {a}");
                for b in [0.0, 30.0, 60.0, 85.0, 90.0, 170.0] {
                    let product = zeta(t, deg(a), deg(b)) * zeta(t, deg(b), deg(a));
                    assert!((product - 1.0).abs() < 1e-12, "T {t} θ {a} θ' {b}");
                    assert!(zeta(t, deg(a), deg(b)).is_finite());
                    assert!(zeta(t, deg(a), deg(b)) > 0.0);
                }
            }
        }
    }

    #[test]
    fn zeta_brightens_toward_the_horizon_and_clamps_below_it() {
        for t in [1.9, 2.0, 2.94, 4.36, 8.0] {
            let mut prev = 0.0;
            for k in 0..=90 {
                let z = zeta(t, deg(k as f64), deg(90.0));
                assert!(z > 0.0 && z <= 1.0 + 1e-12, "T {t} θ {k}: {z}");
                assert!(z >= prev, "T {t} θ {k}: {z} < {prev}");
                prev = z;
            }
            // The horizon is the reference's own value, and below it stays there.
            assert_eq!(zeta(t, deg(100.0), deg(89.9)), 1.0);
            assert_eq!(zeta(t, deg(180.0), deg(90.0)), 1.0);
        }
        // Hazier skies are flatter: the zenith is closer to the horizon's brightness.
        assert!(zeta(4.36, 0.0, deg(90.0)) > zeta(1.9, 0.0, deg(90.0)));
        // Below the clamp T behaves as 1.7, where the zenith gradation is still positive.
        assert_eq!(zeta(1.0, 0.3, 1.2), zeta(1.7, 0.3, 1.2));
        assert!(gradation(1.7, 0.0) > 0.02 && gradation(1.6, 0.0) < 0.0);
    }
}
