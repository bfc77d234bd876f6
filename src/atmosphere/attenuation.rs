//! Γ_c(T, s), paper 002's per-channel attenuation (eq. 11), and its table for the GPU.

use super::scattering::scattering_per_m;
use super::spectral::{
    grid_wavelength_nm, simpson_weights, Channel, Illuminant, Sensitivity, GRID_LEN,
};
use crate::error::{check_positive, Error, Result};
use crate::medium::{Lookup, Wrap};

/// Scan steps (log-spaced in distance) of the search for a channel's gamut limit.
const GAMUT_SCAN_STEPS: usize = 1024;

/// Paper 002's attenuation for one camera, turbidity and observer altitude: Γ_c(T, s) of
/// eq. 11 per channel, integrated over 380-780 nm on the 1 nm grid by Simpson's rule
/// (within 1e-8 of the exact integral, see [`simpson_weights`]).
///
/// ```text
/// Γ_c(s) = ∫ S(λ)·q_c(λ)·exp(−β_sc(λ, T, h0)·s) dλ / ∫ S(λ)·q_c(λ) dλ
/// ```
///
/// with S the [`Illuminant`] (D65 by default; the paper's eq. 11 is S = 1) and q_c
/// signed where the sensitivity is (see [`crate::atmosphere`] on negative lobes): Γ_c is
/// then exactly the factor by which channel c of a neutral surface's pixel falls over
/// distance s. Where the attenuated spectrum leaves the camera's gamut the signed integral
/// would cross zero; from that distance on ([`Aerial::gamut_limit_m`]) Γ_c is 0, as a
/// pixel value clipped at black.
///
/// As in the paper (eq. 9, 15, 18), β_sc is taken at the observer's altitude h0 along the
/// whole ray: a near-horizontal line of sight.
#[derive(Clone, Debug)]
pub struct Aerial {
    turbidity: f64,
    altitude_m: f64,
    illuminant: Illuminant,
    /// β_sc (m⁻¹) at each grid wavelength: decreasing in λ.
    beta_per_m: Vec<f64>,
    /// Simpson weight · S · q_c, normalised to sum 1, per channel.
    weights: [Vec<f64>; 3],
    gamut_limit_m: [f64; 3],
}

impl Aerial {
    /// Γ for `sensitivity` under daylight ([`Illuminant::D65`]) at turbidity `turbidity`
    /// (≥ 1) for an observer at `altitude_m` (m above sea level).
    pub fn new(sensitivity: &Sensitivity, turbidity: f64, altitude_m: f64) -> Result<Self> {
        Self::with_illuminant(sensitivity, Illuminant::D65, turbidity, altitude_m)
    }

    /// [`Aerial::new`] for the light `illuminant` ([`Illuminant::EqualEnergy`] is eq. 11 as
    /// printed).
    pub fn with_illuminant(
        sensitivity: &Sensitivity,
        illuminant: Illuminant,
        turbidity: f64,
        altitude_m: f64,
    ) -> Result<Self> {
        if !(turbidity.is_finite() && turbidity >= 1.0) {
            return Err(Error::invalid(
                "turbidity",
                turbidity,
                "a finite number ≥ 1 (1 is pure air)",
            ));
        }
        if !altitude_m.is_finite() {
            return Err(Error::invalid(
                "altitude",
                altitude_m,
                "a finite height above sea level in metres",
            ));
        }
        let beta_per_m: Vec<f64> = (0..GRID_LEN)
            .map(|i| scattering_per_m(grid_wavelength_nm(i), turbidity, altitude_m))
            .collect();
        let simpson = simpson_weights();
        let mut weights = [
            vec![0.0; GRID_LEN],
            vec![0.0; GRID_LEN],
            vec![0.0; GRID_LEN],
        ];
        for c in Channel::ALL {
            let w = &mut weights[c.index()];
            for (i, (wi, q)) in w.iter_mut().zip(sensitivity.curve(c)).enumerate() {
                *wi = simpson[i] * illuminant.power(grid_wavelength_nm(i)) * q;
            }
            let total: f64 = w.iter().sum();
            if total.is_nan() || total <= 0.0 {
                return Err(Error::invalid(
                    "sensitivity",
                    format!("channel {} responding {total} to {illuminant:?}", c.name()),
                    "a channel with a positive response to the illuminant",
                ));
            }
            w.iter_mut().for_each(|v| *v /= total);
        }
        let mut aerial = Aerial {
            turbidity,
            altitude_m,
            illuminant,
            beta_per_m,
            weights,
            gamut_limit_m: [f64::INFINITY; 3],
        };
        aerial.gamut_limit_m = aerial.first_zeros();
        Ok(aerial)
    }

    /// The turbidity T.
    pub fn turbidity(&self) -> f64 {
        self.turbidity
    }

    /// The observer's altitude h0 (m).
    pub fn altitude_m(&self) -> f64 {
        self.altitude_m
    }

    /// The light whose attenuation Γ measures.
    pub fn illuminant(&self) -> Illuminant {
        self.illuminant
    }

    /// The largest scattering coefficient over the grid (m⁻¹): β_sc at 380 nm, since both
    /// Rayleigh (λ⁻⁴) and Mie (λ⁻²) fall with wavelength.
    pub fn max_coefficient_per_m(&self) -> f64 {
        self.beta_per_m[0]
    }

    /// The smallest scattering coefficient over the grid (m⁻¹): β_sc at 780 nm.
    pub fn min_coefficient_per_m(&self) -> f64 {
        self.beta_per_m[GRID_LEN - 1]
    }

    /// The distance (m) from which Γ_c is 0: where the signed integral first reaches zero
    /// (the attenuated spectrum leaves the camera's gamut in channel c, or every
    /// wavelength has underflowed). Infinite only if the search found neither.
    pub fn gamut_limit_m(&self, channel: Channel) -> f64 {
        self.gamut_limit_m[channel.index()]
    }

    /// The signed integral of eq. 11 (normalised), before the gamut clip.
    fn signed(&self, channel: Channel, distance_m: f64) -> f64 {
        self.weights[channel.index()]
            .iter()
            .zip(&self.beta_per_m)
            .map(|(w, b)| w * (-b * distance_m).exp())
            .sum()
    }

    /// Per channel, the first distance where the signed integral is ≤ 0: a log-spaced
    /// scan (shared by the channels) from optical depth 10⁻⁶ at 380 nm to 800 at 780 nm,
    /// where every exponential has underflowed to 0, then bisection to the last bit.
    fn first_zeros(&self) -> [f64; 3] {
        let lo = 1e-6 / self.max_coefficient_per_m();
        let hi = 800.0 / self.min_coefficient_per_m();
        let ratio = (hi / lo).powf(1.0 / GAMUT_SCAN_STEPS as f64);
        let mut zeros = [f64::INFINITY; 3];
        let mut prev = lo;
        let mut e = vec![0.0; GRID_LEN];
        for k in 1..=GAMUT_SCAN_STEPS {
            let s = if k == GAMUT_SCAN_STEPS {
                hi
            } else {
                lo * ratio.powi(k as i32)
            };
            for (ei, b) in e.iter_mut().zip(&self.beta_per_m) {
                *ei = (-b * s).exp();
            }
            for c in Channel::ALL {
                let signed: f64 = self.weights[c.index()]
                    .iter()
                    .zip(&e)
                    .map(|(w, e)| w * e)
                    .sum();
                if zeros[c.index()].is_infinite() && signed <= 0.0 {
                    zeros[c.index()] = self.bisect_zero(c, prev, s);
                }
            }
            if zeros.iter().all(|z| z.is_finite()) {
                break;
            }
            prev = s;
        }
        zeros
    }

    /// The zero of channel c's signed integral in (a, b], positive at a and not at b.
    fn bisect_zero(&self, channel: Channel, mut a: f64, mut b: f64) -> f64 {
        loop {
            let mid = 0.5 * (a + b);
            if mid <= a || mid >= b {
                return b;
            }
            if self.signed(channel, mid) <= 0.0 {
                b = mid;
            } else {
                a = mid;
            }
        }
    }

    /// Γ_c at distance `distance_m` (m; negative counts as 0): 1 at 0, falling to 0 at
    /// [`Aerial::gamut_limit_m`] and beyond.
    pub fn attenuation(&self, channel: Channel, distance_m: f64) -> f64 {
        let s = distance_m.max(0.0);
        if s == 0.0 {
            return 1.0;
        }
        if s >= self.gamut_limit_m(channel) {
            return 0.0;
        }
        self.signed(channel, s).clamp(0.0, 1.0)
    }

    /// (Γ_r, Γ_g, Γ_b) at `distance_m`.
    pub fn attenuation_rgb(&self, distance_m: f64) -> [f64; 3] {
        Channel::ALL.map(|c| self.attenuation(c, distance_m))
    }

    /// −ln Γ_c: channel c's scattering optical depth over `distance_m`, the grey equivalent
    /// that [`crate::medium::blur_from_optical_depth`] takes (all of the aerial extinction
    /// is scattering). +∞ from the gamut limit on; callers cap the blur there.
    pub fn scattering_optical_depth(&self, channel: Channel, distance_m: f64) -> f64 {
        -self.attenuation(channel, distance_m).ln()
    }
}

/// Γ_r, Γ_g, Γ_b tabulated over distance for the GPU: a three-channel [`Lookup`] of
/// [`AttenuationTable::SAMPLES`] x 1 texels (`RGB32F`, one fetch for the three), bilinear,
/// clamped to its edges.
///
/// # The coordinate
///
/// Sample i holds Γ at x = i/(n − 1) of the log-ish coordinate
///
/// ```text
/// x(s) = ln(1 + s/s0) / Λ,   Λ = ln(1 + s_max/s0),   s0 = 1/β_sc(380 nm)
/// ```
///
/// linear below the scale s0 (the shortest mean free path over the spectrum) and
/// logarithmic beyond. In it each exponential e^(−βs) has a bounded curvature whatever β
/// and s_max: d²/dx² e^(−βs) = Λ²·(t² − t)·e^(βs0 − t) with t = β(s + s0) ≥ βs0, and
/// βs0 ≤ 1, so |…| ≤ 0.84·Λ². Linear interpolation on n samples is then within
///
/// ```text
/// |Γ_table − Γ| ≤ 0.84·Λ²·ρ / (8(n − 1)²)  (+ 6e-8 for the f32 texels)
/// ```
///
/// with ρ = ∫|S·q_c| / ∫S·q_c (1 for a non-negative camera; 1.98, 1.25, 1.23 for the
/// r, g, b of the sRGB default), plus, for a signed camera whose gamut limit lies within
/// s_max, what linear interpolation misses across the clip there (at most the smaller of
/// the signed values at the two samples around it): [`AttenuationTable::error_bound`].
/// For 1024 samples and T = 20 out to 200 km (Λ = 6.8) the first term is under 1e-5,
/// where a coordinate uniform in s could miss by (β·s_max)²/(8(n − 1)²) ≈ 9 %. Measured
/// against the direct integral over T = 1 … 120, s_max = 5 km … 1000 km, the largest
/// error is 6.8e-6 away from the clip and 4.2e-5 across it (blue, pure air, near 156 km,
/// where Γ_b is already below 1e-3).
///
/// # In GLSL
///
/// ```glsl
/// uniform sampler2D table;        // lookup(): width n, height 1, RGB, bilinear, clamped
/// uniform float inv_scale;        // 1.0 / scale_m()
/// uniform float inv_log_span;     // 1.0 / log_span()
/// uniform float max_distance;     // max_distance_m()
/// const float n = 1024.0;         // samples()
///
/// vec3 attenuation(float s) {     // s: distance to the camera in metres
///     float x = log(1.0 + clamp(s, 0.0, max_distance) * inv_scale) * inv_log_span;
///     float u = (0.5 + x * (n - 1.0)) / n;
///     return texture(table, vec2(u, 0.5)).rgb;
/// }
/// ```
///
/// `u` maps x = 0 and x = 1 to the centres of the first and last texels, so no sample
/// is ever blended with the clamped edge; v = (c + ½)/3 is row c's centre. In f32 the
/// rounding of `1.0 + s·inv_scale` moves x by at most ~6e-8/Λ, and Γ by less than 1e-7.
/// Beyond s_max the table holds Γ(s_max).
#[derive(Clone, Debug)]
pub struct AttenuationTable {
    turbidity: f64,
    altitude_m: f64,
    max_distance_m: f64,
    scale_m: f64,
    log_span: f64,
    spread: [f64; 3],
    kink: [f64; 3],
    lookup: Lookup,
}

impl AttenuationTable {
    /// The default number of samples over distance (the texture's width).
    pub const SAMPLES: usize = 1024;

    /// The table of [`Aerial::new`]`(sensitivity, turbidity, altitude_m)` (D65 light) over
    /// [0, `max_distance_m`] with [`AttenuationTable::SAMPLES`] samples.
    pub fn new(
        sensitivity: &Sensitivity,
        turbidity: f64,
        altitude_m: f64,
        max_distance_m: f64,
    ) -> Result<Self> {
        let aerial = Aerial::new(sensitivity, turbidity, altitude_m)?;
        Self::from_aerial(&aerial, max_distance_m, Self::SAMPLES)
    }

    /// The table of `aerial` over [0, `max_distance_m`] with `samples` (≥ 2) samples.
    pub fn from_aerial(aerial: &Aerial, max_distance_m: f64, samples: usize) -> Result<Self> {
        check_positive("max distance", max_distance_m)?;
        if samples < 2 {
            return Err(Error::invalid("samples", samples, "at least 2"));
        }
        let scale_m = 1.0 / aerial.max_coefficient_per_m();
        let log_span = (max_distance_m / scale_m).ln_1p();
        let values: Vec<[f32; 3]> = (0..samples)
            .map(|i| {
                let s = if i == samples - 1 {
                    max_distance_m
                } else {
                    scale_m * (i as f64 / (samples - 1) as f64 * log_span).exp_m1()
                };
                Channel::ALL.map(|c| aerial.attenuation(c, s) as f32)
            })
            .collect();
        let spread = Channel::ALL.map(|c| {
            let w = &aerial.weights[c.index()];
            w.iter().map(|v| v.abs()).sum::<f64>() / w.iter().sum::<f64>()
        });
        // Across the gamut limit Γ has a kink (the signed integral clipped at 0), which
        // linear interpolation between the samples around it, p > 0 and q ≤ 0 signed,
        // misses by at most p·|q|/(p + |q|).
        let kink = Channel::ALL.map(|c| {
            let limit = aerial.gamut_limit_m(c);
            if limit >= max_distance_m {
                return 0.0;
            }
            let x = (limit / scale_m).ln_1p() / log_span;
            let i = ((x * (samples - 1) as f64).floor() as usize).min(samples - 2);
            let at = |i: usize| scale_m * (i as f64 / (samples - 1) as f64 * log_span).exp_m1();
            let p = aerial.signed(c, at(i)).max(0.0);
            let q = aerial.signed(c, at(i + 1));
            if q < 0.0 {
                p * -q / (p - q)
            } else {
                p
            }
        });
        Ok(AttenuationTable {
            turbidity: aerial.turbidity(),
            altitude_m: aerial.altitude_m(),
            max_distance_m,
            scale_m,
            log_span,
            spread,
            kink,
            lookup: Lookup::rgb(samples, 1, &values, Wrap::ClampToEdge)?,
        })
    }

    /// The lookup to bind (its values and id; clones share them).
    pub fn lookup(&self) -> &Lookup {
        &self.lookup
    }

    /// Samples over distance n (the texture's width).
    pub fn samples(&self) -> usize {
        self.lookup.width()
    }

    /// The turbidity the table was built for.
    pub fn turbidity(&self) -> f64 {
        self.turbidity
    }

    /// The observer altitude (m) the table was built for.
    pub fn altitude_m(&self) -> f64 {
        self.altitude_m
    }

    /// s_max (m): the last sample's distance.
    pub fn max_distance_m(&self) -> f64 {
        self.max_distance_m
    }

    /// s0 (m): where the coordinate turns from linear to logarithmic, 1/β_sc(380 nm).
    pub fn scale_m(&self) -> f64 {
        self.scale_m
    }

    /// Λ = ln(1 + s_max/s0).
    pub fn log_span(&self) -> f64 {
        self.log_span
    }

    /// x(s) ∈ [0, 1], the table coordinate of distance `distance_m` (clamped to
    /// [0, s_max]).
    pub fn coordinate(&self, distance_m: f64) -> f64 {
        (distance_m.clamp(0.0, self.max_distance_m) / self.scale_m).ln_1p() / self.log_span
    }

    /// The texture coordinate u of distance `distance_m`: (½ + x·(n − 1))/n.
    pub fn u_of_distance(&self, distance_m: f64) -> f64 {
        let n = self.samples() as f64;
        (0.5 + self.coordinate(distance_m) * (n - 1.0)) / n
    }

    /// Γ_c at `distance_m` as the GPU reads it: channel c of the lookup's bilinear sample
    /// at (u_of_distance, ½).
    pub fn sample(&self, channel: Channel, distance_m: f64) -> f64 {
        let u = self.u_of_distance(distance_m);
        self.lookup.sample_channel(u, 0.5, channel.index())
    }

    /// The bound on |sample − Aerial::attenuation| for channel c over [0, s_max] (see the
    /// type's docs): 0.84·Λ²·ρ_c / (8(n − 1)²) + 1e-7, plus, where the channel's gamut
    /// limit lies within s_max, what interpolation across that kink can miss.
    pub fn error_bound(&self, channel: Channel) -> f64 {
        let h = 1.0 / (self.samples() - 1) as f64;
        let c = channel.index();
        0.84 * self.log_span.powi(2) * self.spread[c] * h * h / 8.0 + 1e-7 + self.kink[c]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atmosphere::WeatherCondition;

    /// Turbidities from pure air to thick fog.
    const TURBIDITIES: [f64; 8] = [1.0, 1.3, 1.9, 2.94, 4.36, 9.0, 20.0, 120.0];

    /// Distances from 1 mm to 1000 km, log-spaced, plus 0.
    fn distances() -> impl Iterator<Item = f64> {
        std::iter::once(0.0).chain((0..=360).map(|k| 1e-3 * 10f64.powf(k as f64 / 40.0)))
    }

    #[test]
    fn gamma_is_one_at_zero_and_falls_in_zero_one() {
        let cameras = [
            Sensitivity::cie_srgb(),
            Sensitivity::from_samples(&[(400.0, [0.1, 0.5, 1.0]), (700.0, [1.0, 0.5, 0.0])])
                .unwrap(),
        ];
        for sensitivity in &cameras {
            for illuminant in [Illuminant::D65, Illuminant::EqualEnergy] {
                for &t in &TURBIDITIES {
                    for h0 in [0.0, 40.0, 2000.0] {
                        let aerial =
                            Aerial::with_illuminant(sensitivity, illuminant, t, h0).unwrap();
                        for c in Channel::ALL {
                            assert_eq!(aerial.attenuation(c, 0.0), 1.0);
                            assert_eq!(aerial.attenuation(c, -5.0), 1.0);
                            assert_eq!(aerial.scattering_optical_depth(c, 0.0), 0.0);
                            let limit = aerial.gamut_limit_m(c);
                            let mut prev = 1.0;
                            for s in distances() {
                                let g = aerial.attenuation(c, s);
                                let what = format!("{illuminant:?} T {t} h0 {h0} {c:?} s {s}");
                                assert!((0.0..=1.0).contains(&g), "{what}: {g}");
                                // Positive up to the gamut limit, then 0.
                                assert_eq!(g > 0.0, s < limit, "{what}: {g}, limit {limit}");
                                assert!(g <= prev, "{what}: {g} after {prev}");
                                if s > 0.0 && s < limit {
                                    assert!(g < prev, "{what}: not decreasing from {prev}");
                                }
                                let depth = aerial.scattering_optical_depth(c, s);
                                assert!(depth >= 0.0 && (depth == -g.ln()), "{what}");
                                prev = g;
                            }
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn simpson_on_the_1_nm_grid_is_within_1e_8_of_a_fine_integral() {
        // The reference: Simpson at 0.05 nm on the same continuous integrand (the analytic
        // CIE fit in sRGB, D65 interpolated linearly).
        use crate::atmosphere::spectral::{cie_1931_xyz, XYZ_TO_LINEAR_SRGB};
        let fine = |c: Channel, t: f64, s: f64| {
            let n = 8000;
            let h = 400.0 / n as f64;
            let (mut num, mut den) = (0.0, 0.0);
            for i in 0..=n {
                let lambda = 380.0 + i as f64 * h;
                let w = if i == 0 || i == n {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                let xyz = cie_1931_xyz(lambda);
                let row = XYZ_TO_LINEAR_SRGB[c.index()];
                let q = row[0] * xyz[0] + row[1] * xyz[1] + row[2] * xyz[2];
                let f = w * q * Illuminant::D65.power(lambda);
                num += f * (-scattering_per_m(lambda, t, 0.0) * s).exp();
                den += f;
            }
            num / den
        };
        let sensitivity = Sensitivity::cie_srgb();
        for (t, s) in [(1.0, 20e3), (2.0, 5e3), (3.0, 10e3), (20.0, 1e3)] {
            let aerial = Aerial::new(&sensitivity, t, 0.0).unwrap();
            for c in Channel::ALL {
                let err = (aerial.attenuation(c, s) - fine(c, t, s)).abs();
                assert!(err < 1e-8, "T {t} s {s} {c:?}: {err:e}");
            }
        }
    }

    #[test]
    fn gamut_limit_only_clips_what_is_already_black() {
        // The signed integral of the sRGB curves crosses zero once the channel's own
        // light is nearly gone (blue first: 138 km in pure air, 2.2 km at T = 20):
        // clipping it at 0 changes Γ by less than 0.01 (0.006 in pure air).
        let sensitivity = Sensitivity::cie_srgb();
        for &t in &TURBIDITIES {
            let aerial = Aerial::new(&sensitivity, t, 0.0).unwrap();
            for c in Channel::ALL {
                let limit = aerial.gamut_limit_m(c);
                assert!(limit.is_finite(), "T {t} {c:?}");
                assert!(aerial.signed(c, limit * 0.999_999) > 0.0);
                assert!(aerial.signed(c, limit) <= 0.0);
                // The most negative value beyond the limit.
                let worst = (0..400)
                    .map(|k| aerial.signed(c, limit * 1.02f64.powi(k)))
                    .fold(0.0, f64::min);
                assert!(worst > -0.01, "T {t} {c:?}: {worst}");
            }
            // A camera with non-negative curves never reaches its limit before every
            // wavelength has underflowed.
            let positive =
                Sensitivity::from_samples(&[(380.0, [1.0; 3]), (780.0, [1.0; 3])]).unwrap();
            let a = Aerial::new(&positive, t, 0.0).unwrap();
            // (Each term w·e^(−βs) is 0 once below the smallest subnormal, 5e-324.)
            let underflow = 700.0 / a.min_coefficient_per_m();
            assert!(a.gamut_limit_m(Channel::R) > underflow);
        }
    }

    #[test]
    fn gamma_matches_single_wavelength_and_paper_ordering() {
        // A narrow-band camera sees exp(−β(λ)s) of its own wavelength (eq. 10's premise).
        let narrow =
            Sensitivity::from_samples(&[(548.0, [0.0; 3]), (550.0, [1.0; 3]), (552.0, [0.0; 3])])
                .unwrap();
        let aerial = Aerial::with_illuminant(&narrow, Illuminant::EqualEnergy, 3.0, 0.0).unwrap();
        let beta = scattering_per_m(550.0, 3.0, 0.0);
        for s in [100.0, 1e3, 1e4] {
            let g = aerial.attenuation(Channel::G, s);
            // Equal weights at 549, 550 and 551 nm, where β differs by ±0.4 %: the mean of
            // the three exponentials is off the central one at second order.
            assert!(
                (g / (-beta * s).exp() - 1.0).abs() < 1e-4 * beta * s,
                "{s}: {g}"
            );
        }
        // Blue fades first, red last: haze is bluish-white and distant things redden.
        let srgb = Aerial::new(&Sensitivity::cie_srgb(), 2.0, 40.0).unwrap();
        for s in [500.0, 3500.0, 20e3] {
            let [r, g, b] = srgb.attenuation_rgb(s);
            assert!(r > g && g > b, "{s}: {r} {g} {b}");
        }
        // More turbid air attenuates more; a higher observer sees less.
        for c in Channel::ALL {
            let a2 = Aerial::new(&Sensitivity::cie_srgb(), 2.0, 0.0).unwrap();
            let a4 = Aerial::new(&Sensitivity::cie_srgb(), 4.0, 0.0).unwrap();
            let high = Aerial::new(&Sensitivity::cie_srgb(), 4.0, 1500.0).unwrap();
            assert!(a4.attenuation(c, 3500.0) < a2.attenuation(c, 3500.0));
            assert!(high.attenuation(c, 3500.0) > a4.attenuation(c, 3500.0));
        }
    }

    #[test]
    fn table_matches_the_direct_integral() {
        let sensitivity = Sensitivity::cie_srgb();
        let mut worst_overall: f64 = 0.0;
        for &t in &TURBIDITIES {
            for (h0, s_max) in [(0.0, 5e3), (40.0, 50e3), (0.0, 200e3), (1000.0, 1e6)] {
                let aerial = Aerial::new(&sensitivity, t, h0).unwrap();
                let table =
                    AttenuationTable::from_aerial(&aerial, s_max, AttenuationTable::SAMPLES)
                        .unwrap();
                for c in Channel::ALL {
                    assert_eq!(table.sample(c, 0.0), 1.0);
                    let end = aerial.attenuation(c, s_max);
                    assert!((table.sample(c, s_max) - end).abs() < 1e-7);
                    assert_eq!(table.sample(c, 2.0 * s_max), table.sample(c, s_max));
                    let bound = table.error_bound(c);
                    assert!(bound < 1e-4, "T {t} s_max {s_max}: bound {bound}");
                    // Midway between samples in x, where interpolation errs most, and
                    // 1001 distances uniform in s.
                    let n = table.samples();
                    let midway = (0..n - 1).map(|i| {
                        let x = (i as f64 + 0.5) / (n - 1) as f64;
                        table.scale_m() * (x * table.log_span()).exp_m1()
                    });
                    let uniform = (0..=1000).map(|k| s_max * k as f64 / 1000.0);
                    let mut worst: f64 = 0.0;
                    for s in midway.chain(uniform) {
                        let err = (table.sample(c, s) - aerial.attenuation(c, s)).abs();
                        worst = worst.max(err);
                    }
                    assert!(
                        worst <= bound,
                        "T {t} h0 {h0} s_max {s_max} {c:?}: {worst} > {bound}"
                    );
                    worst_overall = worst_overall.max(worst);
                }
            }
        }
        eprintln!("table vs direct integral: max |error| {worst_overall:e}");
        let t = AttenuationTable::new(&sensitivity, 2.0, 0.0, 50e3).unwrap();
        eprintln!("spread ρ of the sRGB default: {:?}", t.spread);
    }

    #[test]
    fn table_coordinate_hits_texel_centres() {
        let table = AttenuationTable::new(&Sensitivity::cie_srgb(), 3.0, 0.0, 30e3).unwrap();
        let n = table.samples() as f64;
        assert_eq!(table.samples(), 1024);
        assert_eq!(table.u_of_distance(0.0), 0.5 / n);
        assert!((table.u_of_distance(30e3) - (n - 0.5) / n).abs() < 1e-15);
        assert_eq!(table.u_of_distance(-1.0), 0.5 / n);
        assert!((table.coordinate(table.scale_m()) - 2f64.ln() / table.log_span()).abs() < 1e-15);
        assert_eq!(table.lookup().height(), 1);
        assert_eq!(table.lookup().channels(), 3);
        assert_eq!(table.lookup().wrap(), Wrap::ClampToEdge);
        // Texel i is exactly the direct value at its distance.
        let aerial = Aerial::new(&Sensitivity::cie_srgb(), 3.0, 0.0).unwrap();
        for i in [0, 1, 17, 500, 1023] {
            let s = table.scale_m() * (i as f64 / (n - 1.0) * table.log_span()).exp_m1();
            let texel = table
                .lookup()
                .texel_channel(i as i64, 0, Channel::G.index());
            assert!(
                (texel - aerial.attenuation(Channel::G, s)).abs() < 1e-7,
                "{i}"
            );
        }
    }

    #[test]
    fn rebuilding_is_deterministic_and_bad_parameters_are_refused() {
        let s = Sensitivity::cie_srgb();
        let t = WeatherCondition::Haze.representative_turbidity();
        let a = AttenuationTable::new(&s, t, 40.0, 20e3).unwrap();
        let b = AttenuationTable::new(&s, t, 40.0, 20e3).unwrap();
        assert_eq!(a.lookup().values(), b.lookup().values());
        assert_ne!(a.lookup().id(), b.lookup().id());
        assert!(AttenuationTable::new(&s, 0.9, 0.0, 1e3).is_err());
        assert!(AttenuationTable::new(&s, f64::NAN, 0.0, 1e3).is_err());
        assert!(AttenuationTable::new(&s, 2.0, f64::INFINITY, 1e3).is_err());
        assert!(AttenuationTable::new(&s, 2.0, 0.0, 0.0).is_err());
        let aerial = Aerial::new(&s, 2.0, 0.0).unwrap();
        assert!(AttenuationTable::from_aerial(&aerial, 1e3, 1).is_err());
    }
}
