//! The camera after the fog: what a sensor makes of the foggy scene, for datasets whose
//! images should look captured rather than rendered. Applied to the fogged image (linear
//! RGB, 1 = full scale), in this order, each step optional:
//!
//! 1. **Exposure**: every value times 2^`exposure_stops`.
//! 2. **Shot and read noise**, the Poisson-Gaussian model of raw sensor data (Foi et al.
//!    2008): a value v collects n = v / K photo-electrons on average, K = [`SensorNoise::gain`]
//!    the value of one electron (1 / the full-well capacity at this ISO: K = 1/4000 is a
//!    well of 4000 e⁻ at full scale); the count is Poisson, and the readout adds a Gaussian
//!    of standard deviation σ = [`SensorNoise::read_noise`] (in value units). So
//!    v' = K·Poisson(v/K) + N(0, σ²): mean v, variance K·v + σ², independent per pixel
//!    and channel.
//! 3. **Clipping** to [0, 1], the sensor's range (black level to full well), whenever a
//!    step above or below ran.
//! 4. **JPEG**: the image, as 8-bit sRGB, encoded at [`CaptureOptions::jpeg_quality`] and
//!    decoded again, so that its block artefacts are in whatever file is written.
//!
//! The noise is drawn from [`CaptureOptions::seed`] by brume's own fixed generator: the
//! same seed gives the same image on every platform and build. Alpha is kept as it was.

use crate::error::{Error, Result};
use crate::io::image::{decode_linear_rgb, linear_rgba_to_srgb8_rgb};
use crate::raster::RgbaImage;
use crate::rng::SplitMix64;

/// The Poisson-Gaussian noise of a sensor (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct SensorNoise {
    /// K: the linear value of one photo-electron (1 / full-well electrons), in [0, 1];
    /// 0 for no shot noise. Shot noise has variance K·v at value v. 0.0005 is a small sensor at high ISO; 0.0001 a
    /// large one at base ISO.
    pub gain: f64,
    /// σ: the read noise's standard deviation in linear value units, ≥ 0 (e.g. 0.002).
    pub read_noise: f64,
}

/// What the camera does after the fog. `Default` does nothing: [`CaptureOptions::is_off`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct CaptureOptions {
    /// Exposure change in stops (the image times 2^stops); 0 keeps it.
    pub exposure_stops: f64,
    /// Shot and read noise; `None` for none.
    pub noise: Option<SensorNoise>,
    /// JPEG quality in 1..=100 of an encode-decode round trip; `None` for none.
    pub jpeg_quality: Option<u8>,
    /// The seed of the noise.
    pub seed: u64,
}

impl Default for CaptureOptions {
    fn default() -> Self {
        CaptureOptions {
            exposure_stops: 0.0,
            noise: None,
            jpeg_quality: None,
            seed: 0,
        }
    }
}

/// The noise's sub-stream of the seed, so that other draws from the same seed (β per
/// frame) do not share numbers with it.
const NOISE_STREAM: u64 = 0x006e_6f69_7365;

/// What a JPEG quality may be.
const JPEG_QUALITIES: &str = "a JPEG quality from 1 to 100";

impl CaptureOptions {
    /// The options as brume's JSON reports give them: `null` when off.
    pub fn to_json(&self) -> serde_json::Value {
        if self.is_off() {
            return serde_json::Value::Null;
        }
        serde_json::json!({
            "exposure_stops": self.exposure_stops,
            "shot_noise_gain": self.noise.map(|n| n.gain),
            "read_noise": self.noise.map(|n| n.read_noise),
            "jpeg_quality": self.jpeg_quality,
            "seed": self.seed,
        })
    }

    /// Whether these options leave the image as it is.
    pub fn is_off(&self) -> bool {
        self.exposure_stops == 0.0 && self.noise.is_none() && self.jpeg_quality.is_none()
    }

    /// The options as a host's flags or keywords give them, checked ([`Self::validate`]):
    /// no noise unless a gain or a read noise is given (the other one then 0), the JPEG
    /// quality as any integer (refused outside 1..=100, named `jpeg_quality`).
    pub fn from_parts(
        exposure_stops: f64,
        shot_noise_gain: Option<f64>,
        read_noise: Option<f64>,
        jpeg_quality: Option<i64>,
        seed: u64,
    ) -> Result<Self> {
        let jpeg_quality = match jpeg_quality {
            None => None,
            Some(q) => Some(
                u8::try_from(q)
                    .ok()
                    .filter(|q| (1..=100).contains(q))
                    .ok_or_else(|| Error::invalid("jpeg_quality", q, JPEG_QUALITIES))?,
            ),
        };
        let noise = match (shot_noise_gain, read_noise) {
            (None, None) => None,
            (gain, read) => Some(SensorNoise {
                gain: gain.unwrap_or(0.0),
                read_noise: read.unwrap_or(0.0),
            }),
        };
        let opts = CaptureOptions {
            exposure_stops,
            noise,
            jpeg_quality,
            seed,
        };
        opts.validate()?;
        Ok(opts)
    }

    /// Checks the values, naming the one that is wrong and what it should be.
    pub fn validate(&self) -> Result<()> {
        if !(self.exposure_stops.is_finite() && self.exposure_stops.abs() <= 20.0) {
            return Err(Error::invalid(
                "exposure_stops",
                self.exposure_stops,
                "a number of stops in [-20, 20]",
            ));
        }
        if let Some(n) = &self.noise {
            if !(n.gain.is_finite() && (0.0..=1.0).contains(&n.gain)) {
                return Err(Error::invalid(
                    "shot_noise_gain",
                    n.gain,
                    "the value of one electron, in [0, 1] (1 / full-well electrons, e.g. \
                     0.00025; 0 for no shot noise)",
                ));
            }
            if !(n.read_noise.is_finite() && (0.0..=1.0).contains(&n.read_noise)) {
                return Err(Error::invalid(
                    "read_noise",
                    n.read_noise,
                    "a standard deviation in linear value units, in [0, 1] (e.g. 0.002)",
                ));
            }
        }
        if let Some(q) = self.jpeg_quality {
            if !(1..=100).contains(&q) {
                return Err(Error::invalid("jpeg_quality", q, JPEG_QUALITIES));
            }
        }
        Ok(())
    }
}

/// Applies `opts` to `image` (linear RGBA, 1 = full scale) in place; nothing when they are
/// off. Errors: [`Error::InvalidParameter`] for bad options; the JPEG codec's.
pub fn capture(image: &mut RgbaImage, opts: &CaptureOptions) -> Result<()> {
    opts.validate()?;
    if opts.is_off() {
        return Ok(());
    }
    expose(image, opts.exposure_stops);
    if let Some(noise) = &opts.noise {
        add_sensor_noise(image, noise, opts.seed);
    }
    clip_to_sensor_range(image);
    if let Some(q) = opts.jpeg_quality {
        jpeg_round_trip(image, q)?;
    }
    Ok(())
}

/// Multiplies the colour by 2^stops.
fn expose(image: &mut RgbaImage, stops: f64) {
    if stops == 0.0 {
        return;
    }
    let gain = 2f64.powf(stops) as f32;
    for p in image.as_mut_slice() {
        for c in &mut p[..3] {
            *c *= gain;
        }
    }
}

/// v' = K·Poisson(v/K) + N(0, σ²) per pixel and channel (negative and NaN values collect
/// no electrons).
fn add_sensor_noise(image: &mut RgbaImage, noise: &SensorNoise, seed: u64) {
    let mut rng = SplitMix64::for_stream(seed, NOISE_STREAM);
    for p in image.as_mut_slice() {
        for c in &mut p[..3] {
            let v = f64::from(*c);
            let v = if v.is_finite() { v.max(0.0) } else { 0.0 };
            let signal = if noise.gain > 0.0 {
                noise.gain * poisson(&mut rng, v / noise.gain)
            } else {
                v
            };
            *c = (signal + noise.read_noise * standard_normal(&mut rng)) as f32;
        }
    }
}

/// Clamps the colour to [0, 1] (NaN to 0).
fn clip_to_sensor_range(image: &mut RgbaImage) {
    for p in image.as_mut_slice() {
        for c in &mut p[..3] {
            *c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
        }
    }
}

/// Encodes the image's colour as an 8-bit sRGB JPEG of `quality` (1..=100).
pub fn encode_jpeg(image: &RgbaImage, quality: u8) -> Result<Vec<u8>> {
    if !(1..=100).contains(&quality) {
        return Err(Error::invalid("jpeg_quality", quality, JPEG_QUALITIES));
    }
    let rgb = linear_rgba_to_srgb8_rgb(image.as_slice()).into_flattened();
    let mut bytes = Vec::new();
    let mut encoder = ::image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, quality);
    let (w, h) = (image.width() as u32, image.height() as u32);
    encoder
        .encode(&rgb, w, h, ::image::ExtendedColorType::Rgb8)
        .map_err(|e| {
            Error::invalid(
                "jpeg_quality",
                quality,
                format!("an image the JPEG encoder takes ({w}x{h}, at most 65535 a side): {e}"),
            )
        })?;
    Ok(bytes)
}

/// Replaces the colour by its JPEG round trip at `quality`; alpha is kept.
fn jpeg_round_trip(image: &mut RgbaImage, quality: u8) -> Result<()> {
    let bytes = encode_jpeg(image, quality)?;
    let decoded = decode_linear_rgb(&bytes, "the captured JPEG")?;
    for (p, q) in image.as_mut_slice().iter_mut().zip(decoded.as_slice()) {
        p[..3].copy_from_slice(q);
    }
    Ok(())
}

/// A standard normal deviate (Box-Muller, one of the pair).
pub(crate) fn standard_normal(rng: &mut SplitMix64) -> f64 {
    // 1 - unit() is in (0, 1]: its logarithm is finite.
    let u1 = 1.0 - rng.unit();
    let u2 = rng.unit();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// A Poisson deviate of mean `lambda` ≥ 0: multiplication of uniforms below 10, else
/// Hörmann's transformed rejection with squeeze (PTRS, 1993), as NumPy draws them.
fn poisson(rng: &mut SplitMix64, lambda: f64) -> f64 {
    if lambda <= 0.0 {
        return 0.0;
    }
    if lambda < 10.0 {
        let limit = (-lambda).exp();
        let mut k = 0.0;
        let mut product = rng.unit();
        while product > limit {
            k += 1.0;
            product *= rng.unit();
        }
        return k;
    }
    let slam = lambda.sqrt();
    let loglam = lambda.ln();
    let b = 0.931 + 2.53 * slam;
    let a = -0.059 + 0.02483 * b;
    let inv_alpha = 1.1239 + 1.1328 / (b - 3.4);
    let vr = 0.9277 - 3.6224 / (b - 2.0);
    loop {
        let u = rng.unit() - 0.5;
        let v = rng.unit();
        let us = 0.5 - u.abs();
        let k = ((2.0 * a / us + b) * u + lambda + 0.43).floor();
        if us >= 0.07 && v <= vr {
            return k;
        }
        if k < 0.0 || (us < 0.013 && v > us) {
            continue;
        }
        if v.ln() + inv_alpha.ln() - (a / (us * us) + b).ln()
            <= -lambda + k * loglam - ln_gamma(k + 1.0)
        {
            return k;
        }
    }
}

/// ln Γ(x) for x ≥ 1 (Stirling's series after shifting x to ≥ 7; NumPy's `loggam`).
fn ln_gamma(x: f64) -> f64 {
    // The coefficients as NumPy prints them.
    #[allow(clippy::excessive_precision)]
    const A: [f64; 10] = [
        8.333333333333333e-02,
        -2.777777777777778e-03,
        7.936507936507937e-04,
        -5.952380952380952e-04,
        8.417508417508418e-04,
        -1.917526917526918e-03,
        6.410256410256410e-03,
        -2.955065359477124e-02,
        1.796443723688307e-01,
        -1.39243221690590e+00,
    ];
    if x == 1.0 || x == 2.0 {
        return 0.0;
    }
    let shift = if x < 7.0 { (7.0 - x).floor() } else { 0.0 };
    let x0 = x + shift;
    let x2 = 1.0 / (x0 * x0);
    let series = A.iter().rev().skip(1).fold(A[9], |acc, &a| acc * x2 + a);
    let mut gl = series / x0 + 0.5 * std::f64::consts::TAU.ln() + (x0 - 0.5) * x0.ln() - x0;
    let mut y = x0;
    for _ in 0..shift as usize {
        y -= 1.0;
        gl -= y.ln();
    }
    gl
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn from_parts_makes_noise_only_when_asked_and_names_a_bad_quality() {
        let off = CaptureOptions::from_parts(0.0, None, None, None, 0).unwrap();
        assert!(off.is_off());
        let read = CaptureOptions::from_parts(0.0, None, Some(0.01), Some(90), 3).unwrap();
        let noise = read.noise.unwrap();
        assert_eq!((noise.gain, noise.read_noise), (0.0, 0.01));
        assert_eq!((read.jpeg_quality, read.seed), (Some(90), 3));
        for q in [0, 101, -1, 1 << 40] {
            let e = CaptureOptions::from_parts(0.0, None, None, Some(q), 0).unwrap_err();
            assert!(
                matches!(&e, Error::InvalidParameter { name, .. } if name == "jpeg_quality"),
                "{e}"
            );
        }
        let e = CaptureOptions::from_parts(0.0, Some(2.0), None, None, 0).unwrap_err();
        assert!(e.to_string().contains("shot_noise_gain"), "{e}");
    }

    #[test]
    fn ln_gamma_matches_log_factorials() {
        let mut log_factorial = 0.0f64;
        for n in 1..40u32 {
            // ln Γ(n + 1) = ln n!
            log_factorial += f64::from(n).ln();
            let got = ln_gamma(f64::from(n) + 1.0);
            assert!(
                (got - log_factorial).abs() < 1e-9,
                "n = {n}: {got} vs {log_factorial}"
            );
        }
        // Γ(1/2) = √π, Γ(3/2) = √π/2
        let half = ln_gamma(1.5);
        assert!((half - (std::f64::consts::PI.sqrt() / 2.0).ln()).abs() < 1e-9);
    }
}
