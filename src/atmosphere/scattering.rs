//! Paper 002's corrected scattering coefficients (§3.1, §5): Rayleigh β̂_R (eq. 15) and Mie
//! β̂_M (eq. 18), evaluated at the observer's altitude h0.
//!
//! Functions take the wavelength in **nanometres** and altitudes in metres; the formulas
//! run in SI (λ in metres) and return m⁻¹. The `_per_km` twins return km⁻¹, the unit of
//! the paper's Table 2.
//!
//! # K_R: 1.0396, not 0.0141/0.0135
//!
//! Eq. 3 at 550 nm and sea level gives β_R = 0.013563 km⁻¹, which the text quotes as
//! 0.0135 (truncated); its K_R = 1.0396 (eq. 14) is 0.0141/0.013563 = 1.03961, the ratio
//! with the unrounded value. The literal 0.0141/0.0135 = 1.0444 would give
//! β̂_R(550 nm) = 0.01417 km⁻¹ ≈ 0.0142, off Table 2's 0.0141. [`RAYLEIGH_CORRECTION`] is
//! therefore the printed 1.0396, and β̂_R(550 nm, 0) = 0.014100 km⁻¹.
//!
//! # The units of eq. 18
//!
//! The paper gives no unit for ĉ(T) or λ. Dimensionally β = ĉ·(2π/λ)^(ν−2)·(numbers), so
//! with ν = 4 and β in m⁻¹, ĉ is a length (m^(ν−3)), and λ must be in the same unit. Read
//! with λ in metres and ĉ(T) = (0.65T − 0.65)·10⁻¹⁶ m:
//!
//! ```text
//! β̂_M(550 nm, T, 0) = 0.434·π·0.65·10⁻¹⁶·(T − 1)·(2π/550·10⁻⁹ m)²·0.0092
//!                    = 1.0641·10⁻⁴·(T − 1) m⁻¹ = 0.10641·(T − 1) km⁻¹
//! ```
//!
//! This is the reading the paper was fitted in: the exceptionally clear turbidity it names
//! (T = 1.6, §7.2.1) gives 0.0638 km⁻¹, Table 2's top of "exceptionally clear" (0.0639),
//! and solving for K_M from T = 1.6 ↔ 0.0639 km⁻¹ gives 0.009208, the printed
//! K_M = 0.0092 (eq. 17). The same units make Preetham's concentration (0.6544T −
//! 0.6510)·10⁻¹⁶ with his K ≈ 0.67 about 70 times larger (73.7 at T = 2), as §7.2.1 says.
//! λ in nm or µm would make β̂_M 10¹⁸ or 10¹² times smaller, far below every band of
//! Table 2. Eq. 24 holds exactly since β̂_M ∝ ĉ(T) ∝ T − 1.
//!
//! With this reading the weather conditions of Table 2 are turbidity bands (the
//! [`WeatherCondition`] docs list the edges): T = 1 pure air, up to 1.60 exceptionally
//! clear, 2.71 very clear, 4.54 clear, 9.83 light haze, 19.3 haze, fog beyond. The paper's
//! own skies (Fig. 8: T = 1.9 … 4.36) are very clear to clear days.

/// Refractive index of air in the visible, n (eq. 3).
pub const AIR_REFRACTIVE_INDEX: f64 = 1.0003;
/// Molecular number density of the standard atmosphere, N (m⁻³, eq. 3).
pub const AIR_NUMBER_DENSITY_PER_M3: f64 = 2.545e25;
/// Depolarisation factor of air, p_n (eq. 3).
pub const AIR_DEPOLARIZATION: f64 = 0.035;
/// Rayleigh scale height H_R0 (m).
pub const RAYLEIGH_SCALE_HEIGHT_M: f64 = 7994.0;
/// K_R of eq. 14 as printed: 0.0141 km⁻¹ over eq. 3's unrounded 0.013563 km⁻¹ (see the
/// module docs for why not 0.0141/0.0135).
pub const RAYLEIGH_CORRECTION: f64 = 1.0396;
/// Junge's exponent ν (eq. 4).
pub const JUNGE_EXPONENT: f64 = 4.0;
/// The Mie fudge factor K_M of eq. 17, fitted to Table 2 at 550 nm.
pub const MIE_CORRECTION: f64 = 0.0092;
/// Mie scale height H_M0 (m).
pub const MIE_SCALE_HEIGHT_M: f64 = 1200.0;
/// The standard conditions of Table 2: the spectrally weighted mean wavelength of
/// daylight (nm), at sea level.
pub const STANDARD_WAVELENGTH_NM: f64 = 550.0;

const NM: f64 = 1e-9;

/// Eq. 3 without the correction of eq. 14: the textbook Rayleigh coefficient (m⁻¹) at
/// wavelength `lambda_nm` and altitude `altitude_m`.
pub fn rayleigh_uncorrected_per_m(lambda_nm: f64, altitude_m: f64) -> f64 {
    let n2m1 = AIR_REFRACTIVE_INDEX * AIR_REFRACTIVE_INDEX - 1.0;
    let lambda = lambda_nm * NM;
    let king = (6.0 + 3.0 * AIR_DEPOLARIZATION) / (6.0 - 7.0 * AIR_DEPOLARIZATION);
    8.0 * std::f64::consts::PI.powi(3) * n2m1 * n2m1
        / (3.0 * AIR_NUMBER_DENSITY_PER_M3 * lambda.powi(4))
        * king
        * (-altitude_m / RAYLEIGH_SCALE_HEIGHT_M).exp()
}

/// β̂_R (eq. 15): the corrected Rayleigh coefficient (m⁻¹) at wavelength `lambda_nm` for an
/// observer at `altitude_m`. 0.0141 km⁻¹ at 550 nm and sea level.
pub fn rayleigh_per_m(lambda_nm: f64, altitude_m: f64) -> f64 {
    rayleigh_uncorrected_per_m(lambda_nm, altitude_m) * RAYLEIGH_CORRECTION
}

/// [`rayleigh_per_m`] in km⁻¹.
pub fn rayleigh_per_km(lambda_nm: f64, altitude_m: f64) -> f64 {
    rayleigh_per_m(lambda_nm, altitude_m) * 1e3
}

/// ĉ(T) = (0.65T − 0.65)·10⁻¹⁶ (eq. 16), in metres (see the module docs): zero at T = 1,
/// where eq. 5 leaves no particles.
pub fn mie_concentration(turbidity: f64) -> f64 {
    (0.65 * turbidity - 0.65) * 1e-16
}

/// β̂_M (eq. 18): the corrected Mie coefficient (m⁻¹) at wavelength `lambda_nm`, turbidity
/// `turbidity` (≥ 1) and observer altitude `altitude_m`. 0.10641·(T − 1) km⁻¹ at 550 nm
/// and sea level.
pub fn mie_per_m(lambda_nm: f64, turbidity: f64, altitude_m: f64) -> f64 {
    let lambda = lambda_nm * NM;
    0.434
        * mie_concentration(turbidity)
        * std::f64::consts::PI
        * (2.0 * std::f64::consts::PI / lambda).powf(JUNGE_EXPONENT - 2.0)
        * (-altitude_m / MIE_SCALE_HEIGHT_M).exp()
        * MIE_CORRECTION
}

/// [`mie_per_m`] in km⁻¹.
pub fn mie_per_km(lambda_nm: f64, turbidity: f64, altitude_m: f64) -> f64 {
    mie_per_m(lambda_nm, turbidity, altitude_m) * 1e3
}

/// β_sc = β̂_R + β̂_M (eq. 2 with eq. 15 and 18), m⁻¹: all of the aerial extinction, since
/// the model has no absorption.
pub fn scattering_per_m(lambda_nm: f64, turbidity: f64, altitude_m: f64) -> f64 {
    rayleigh_per_m(lambda_nm, altitude_m) + mie_per_m(lambda_nm, turbidity, altitude_m)
}

/// [`scattering_per_m`] in km⁻¹.
pub fn scattering_per_km(lambda_nm: f64, turbidity: f64, altitude_m: f64) -> f64 {
    scattering_per_m(lambda_nm, turbidity, altitude_m) * 1e3
}

/// The turbidity whose β̂_M at 550 nm and sea level is `mie_per_km` (the inverse of eq. 18
/// under Table 2's standard conditions).
pub fn turbidity_of_standard_mie(mie_per_km: f64) -> f64 {
    1.0 + mie_per_km / self::mie_per_km(STANDARD_WAVELENGTH_NM, 2.0, 0.0)
}

/// The weather conditions of the paper's Table 2 (after McCartney), by β_M at 550 nm and
/// sea level. With eq. 18 they are turbidity bands (β̂_M = 0.10641·(T − 1) km⁻¹):
///
/// | condition           | β_M (km⁻¹)        | T              | representative T (β̂_M km⁻¹) |
/// |---------------------|-------------------|----------------|-----------------------------|
/// | pure air            | 0                 | 1              | 1 (0)                       |
/// | exceptionally clear | 0 – 0.0639        | 1 – 1.60       | 1.3 (0.0319)                |
/// | very clear          | 0.0639 – 0.1819   | 1.60 – 2.71    | 2.0 (0.1064)                |
/// | clear               | 0.1819 – 0.3769   | 2.71 – 4.54    | 3.5 (0.2660)                |
/// | light haze          | 0.3769 – 0.9399   | 4.54 – 9.83    | 6.6 (0.5959)                |
/// | haze                | 0.9399 – 1.9459   | 9.83 – 19.3    | 14 (1.383)                  |
/// | fog                 | 1.9459 – > 78     | 19.3 – > 734   | 120 (12.66)                 |
///
/// The representative turbidity is the band's centre in β_M: the geometric mean of its
/// edges (the arithmetic one for exceptionally clear, whose lower edge is 0), rounded to
/// two digits. It keeps T = 1.6, the paper's "exceptionally clear" (§7.2.1), on the top
/// edge of its band, where the paper's fit of K_M put it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum WeatherCondition {
    /// No particles: β_M = 0, T = 1.
    PureAir,
    /// β_M up to 0.0639 km⁻¹.
    ExceptionallyClear,
    /// β_M 0.0639 – 0.1819 km⁻¹.
    VeryClear,
    /// β_M 0.1819 – 0.3769 km⁻¹.
    Clear,
    /// β_M 0.3769 – 0.9399 km⁻¹.
    LightHaze,
    /// β_M 0.9399 – 1.9459 km⁻¹.
    Haze,
    /// β_M from 1.9459 km⁻¹ ("more than 78" at the dense end).
    Fog,
}

impl WeatherCondition {
    /// All conditions, clearest first.
    pub const ALL: [WeatherCondition; 7] = [
        WeatherCondition::PureAir,
        WeatherCondition::ExceptionallyClear,
        WeatherCondition::VeryClear,
        WeatherCondition::Clear,
        WeatherCondition::LightHaze,
        WeatherCondition::Haze,
        WeatherCondition::Fog,
    ];

    /// Table 2's band of β_M (km⁻¹) at 550 nm and sea level, [min, max]; fog's max is
    /// open (∞: the table says "more than 78").
    pub fn mie_band_per_km(self) -> (f64, f64) {
        match self {
            WeatherCondition::PureAir => (0.0, 0.0),
            WeatherCondition::ExceptionallyClear => (0.0, 0.0639),
            WeatherCondition::VeryClear => (0.0639, 0.1819),
            WeatherCondition::Clear => (0.1819, 0.3769),
            WeatherCondition::LightHaze => (0.3769, 0.9399),
            WeatherCondition::Haze => (0.9399, 1.9459),
            WeatherCondition::Fog => (1.9459, f64::INFINITY),
        }
    }

    /// A turbidity well inside the band (see the type's docs for how it was chosen).
    pub fn representative_turbidity(self) -> f64 {
        match self {
            WeatherCondition::PureAir => 1.0,
            WeatherCondition::ExceptionallyClear => 1.3,
            WeatherCondition::VeryClear => 2.0,
            WeatherCondition::Clear => 3.5,
            WeatherCondition::LightHaze => 6.6,
            WeatherCondition::Haze => 14.0,
            WeatherCondition::Fog => 120.0,
        }
    }

    /// The condition of turbidity `turbidity` by its β̂_M at 550 nm and sea level (a value
    /// on a shared edge goes to the clearer condition).
    pub fn of_turbidity(turbidity: f64) -> WeatherCondition {
        let mie = mie_per_km(STANDARD_WAVELENGTH_NM, turbidity, 0.0);
        if mie <= 0.0 {
            return WeatherCondition::PureAir;
        }
        Self::ALL[1..]
            .iter()
            .copied()
            .find(|c| mie <= c.mie_band_per_km().1)
            .unwrap_or(WeatherCondition::Fog)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `x` to 3 significant digits.
    fn sig3(x: f64) -> f64 {
        let scale = 10f64.powi(2 - x.abs().log10().floor() as i32);
        (x * scale).round() / scale
    }

    #[test]
    fn rayleigh_at_standard_conditions_is_table_2s() {
        assert_eq!(sig3(rayleigh_per_km(550.0, 0.0)), 0.0141);
        assert!((rayleigh_per_km(550.0, 0.0) - 0.0141).abs() < 1e-6);
        // Eq. 3 alone is the paper's 0.0135 (truncated) and K_R is its exact complement.
        let eq3 = rayleigh_uncorrected_per_m(550.0, 0.0) * 1e3;
        assert_eq!(sig3(eq3), 0.0136);
        assert!((eq3 - 0.013563).abs() < 1e-6, "{eq3}");
        assert!((0.0141 / eq3 - RAYLEIGH_CORRECTION).abs() < 5e-5);
        // The literal 0.0141/0.0135 would not reproduce Table 2.
        assert_eq!(sig3(eq3 * 0.0141 / 0.0135), 0.0142);
        // λ⁻⁴.
        let ratio = rayleigh_per_m(400.0, 0.0) / rayleigh_per_m(800.0, 0.0);
        assert!((ratio - 16.0).abs() < 1e-12);
    }

    #[test]
    fn mie_units_put_each_weather_condition_in_its_band() {
        let per_t = mie_per_km(550.0, 2.0, 0.0);
        assert!((per_t - 0.106408).abs() < 1e-6, "{per_t}");
        for condition in WeatherCondition::ALL {
            let t = condition.representative_turbidity();
            let mie = mie_per_km(550.0, t, 0.0);
            let (lo, hi) = condition.mie_band_per_km();
            assert!(
                (lo..=hi).contains(&mie),
                "{condition:?}: T = {t} gives {mie} km⁻¹, outside [{lo}, {hi}]"
            );
            if condition != WeatherCondition::PureAir {
                // Well inside: not on an edge.
                assert!(mie > lo && mie < hi, "{condition:?}");
            }
            assert_eq!(WeatherCondition::of_turbidity(t), condition);
        }
        // The paper's exceptionally clear turbidity sits on the top of its band.
        let t16 = mie_per_km(550.0, 1.6, 0.0);
        assert!((t16 - 0.0639).abs() < 2e-4 && t16 <= 0.0639, "{t16}");
        assert_eq!(
            WeatherCondition::of_turbidity(1.6),
            WeatherCondition::ExceptionallyClear
        );
        // K_M is what T = 1.6 ↔ 0.0639 km⁻¹ gives, rounded to 2 digits.
        let k_fit = 0.0639 / (t16 / MIE_CORRECTION);
        assert!((k_fit - 0.0092).abs() < 5e-5, "{k_fit}");
        // λ in nm would be 10¹⁸ times smaller: out of every band but pure air.
        assert!(mie_per_km(550.0, 2.0, 0.0) * 1e-18 < 1e-12);
        // The band edges as turbidities.
        assert!((turbidity_of_standard_mie(0.0639) - 1.6005).abs() < 1e-4);
        assert!((turbidity_of_standard_mie(1.9459) - 19.287).abs() < 1e-3);
    }

    #[test]
    fn eq_24_mie_ratio_is_the_turbidity_excess_ratio() {
        let turbidities = [1.1, 1.6, 1.9, 2.0, 2.94, 4.36, 7.5, 20.0, 120.0];
        for &t1 in &turbidities {
            for &t2 in &turbidities {
                for lambda in [380.0, 550.0, 780.0] {
                    for h0 in [0.0, 40.0, 3000.0] {
                        let ratio = mie_per_m(lambda, t1, h0) / mie_per_m(lambda, t2, h0);
                        let expected = (t1 - 1.0) / (t2 - 1.0);
                        assert!(
                            (ratio / expected - 1.0).abs() < 1e-12,
                            "T {t1}/{t2}: {ratio} vs {expected}"
                        );
                    }
                }
            }
        }
        assert_eq!(mie_per_m(550.0, 1.0, 0.0), 0.0);
    }

    #[test]
    fn coefficients_fall_off_with_their_scale_heights() {
        for h0 in [-400.0, 40.0, 1200.0, 5000.0] {
            let r = rayleigh_per_m(500.0, h0) / rayleigh_per_m(500.0, 0.0);
            assert!((r / (-h0 / 7994.0f64).exp() - 1.0).abs() < 1e-12);
            let m = mie_per_m(500.0, 3.0, h0) / mie_per_m(500.0, 3.0, 0.0);
            assert!((m / (-h0 / 1200.0f64).exp() - 1.0).abs() < 1e-12);
            let sc = scattering_per_km(500.0, 3.0, h0);
            let sum = rayleigh_per_km(500.0, h0) + mie_per_km(500.0, 3.0, h0);
            assert!((sc - sum).abs() < 1e-15);
        }
        // ν = 4: Mie goes as λ⁻².
        let ratio = mie_per_m(400.0, 3.0, 0.0) / mie_per_m(800.0, 3.0, 0.0);
        assert!((ratio - 4.0).abs() < 1e-12);
    }
}
