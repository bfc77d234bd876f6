//! Tiling noise textures for a fog's density (paper 001, sec. 3.3): generated from a seed,
//! or loaded from a PNG.
//!
//! The paper samples a "previously generated" black-and-white noise texture at the world
//! position, shifted over time; the texture repeats across the world, so it must tile
//! without a seam. [`TilingNoise`] makes one:
//!
//! - **Periodic gradient (Perlin) noise.** Octave `o` has a square lattice of
//!   `period·2^o` cells across the tile; a lattice corner `(i, j)` gets one of eight unit
//!   gradients (the axes and the diagonals) through a permutation table `perm` of 0..256
//!   shuffled by SplitMix64 from the seed (one table per octave, drawn in order):
//!   `g(i, j) = G[perm[(perm[i mod P] + j mod P) mod 256] mod 8]`. Indices taken modulo the
//!   octave's period `P` make the noise periodic over the tile, so the last texel of a row
//!   continues into the first. Inside a cell the four corner ramps are blended with
//!   Perlin's quintic fade 6t⁵ − 15t⁴ + 10t³ (continuous slope across cells).
//! - **fBm.** The octaves are summed with amplitudes `persistence^o`.
//! - **Normalised** to mean exactly ½ and range [0, 1]: `n' = ½ + ½·(n − mean)/max|n − mean|`.
//!   A mean of ½ makes the average density factor of paper 001's eq. 9 the midpoint of
//!   its low and high values, whatever the seed.
//!
//! Texel `(x, y)` is the noise at its centre, lattice coordinates `((x + ½)·P/size,
//! (y + ½)·P/size)`. Everything is f64 additions, multiplications, divisions and floors,
//! no transcendental function and no float from the hash beyond the fixed gradient table:
//! the same seed gives the same bits on every platform.

use std::path::Path;

use image::DynamicImage;

use super::lookup::{Lookup, Wrap};
use crate::error::{Error, Result};
use crate::rng::SplitMix64;

/// Default texture size (px per side).
pub const DEFAULT_SIZE_PX: usize = 256;
/// Default lattice cells across the tile for the first octave.
pub const DEFAULT_PERIOD: u32 = 4;
/// Default number of octaves: the last has 4·2⁴ = 64 cells of 4 px on a 256 px tile.
pub const DEFAULT_OCTAVES: u32 = 5;
/// Default amplitude ratio between successive octaves.
pub const DEFAULT_PERSISTENCE: f64 = 0.5;

/// The permutation table's length: the largest lattice period an octave may have.
const TABLE: usize = 256;

/// The eight gradients: axes and diagonals, unit length.
const GRADIENTS: [[f64; 2]; 8] = {
    const S: f64 = std::f64::consts::FRAC_1_SQRT_2;
    [
        [1.0, 0.0],
        [-1.0, 0.0],
        [0.0, 1.0],
        [0.0, -1.0],
        [S, S],
        [-S, S],
        [S, -S],
        [-S, -S],
    ]
};

/// A recipe for a square, seamlessly tiling fBm texture (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TilingNoise {
    /// Texels per side (≥ 2).
    pub size_px: usize,
    /// The seed of the permutation tables.
    pub seed: u64,
    /// Lattice cells across the tile in the first octave (≥ 1).
    pub period: u32,
    /// Number of octaves (≥ 1); the last has `period·2^(octaves−1)` cells, at most 256
    /// and at most `size_px` (a cell narrower than a texel would only alias).
    pub octaves: u32,
    /// Amplitude ratio between successive octaves, in (0, 1].
    pub persistence: f64,
}

impl Default for TilingNoise {
    fn default() -> Self {
        TilingNoise {
            size_px: DEFAULT_SIZE_PX,
            seed: 0,
            period: DEFAULT_PERIOD,
            octaves: DEFAULT_OCTAVES,
            persistence: DEFAULT_PERSISTENCE,
        }
    }
}

impl TilingNoise {
    /// The default recipe at `size_px` texels per side with `seed`.
    pub fn new(size_px: usize, seed: u64) -> Self {
        TilingNoise {
            size_px,
            seed,
            ..TilingNoise::default()
        }
    }

    /// The finest octave's lattice period (cells across the tile).
    fn finest_period(&self) -> Option<u64> {
        let doublings = 1u64.checked_shl(self.octaves.checked_sub(1)?)?;
        u64::from(self.period).checked_mul(doublings)
    }

    /// Rejects a recipe that cannot tile or would alias, naming the parameter.
    pub fn validate(&self) -> Result<()> {
        if !(2..=crate::io::limits::MAX_SIDE).contains(&self.size_px) {
            return Err(Error::invalid(
                "noise size",
                self.size_px,
                format!("2 to {} texels per side", crate::io::limits::MAX_SIDE),
            ));
        }
        if self.period == 0 {
            return Err(Error::invalid("noise period", 0, "at least 1 lattice cell"));
        }
        let limit = (TABLE as u64).min(self.size_px as u64);
        if self.octaves == 0 || self.finest_period().is_none_or(|p| p > limit) {
            return Err(Error::invalid(
                "noise octaves",
                self.octaves,
                format!(
                    "at least 1, with period·2^(octaves−1) ≤ {limit} cells (period {}, \
                     {} texels)",
                    self.period, self.size_px
                ),
            ));
        }
        if !(self.persistence.is_finite() && self.persistence > 0.0 && self.persistence <= 1.0) {
            return Err(Error::invalid(
                "noise persistence",
                self.persistence,
                "an amplitude ratio in (0, 1]",
            ));
        }
        Ok(())
    }

    /// The texture's values, row 0 first, in [0, 1] with mean ½.
    pub fn values(&self) -> Result<Vec<f32>> {
        self.validate()?;
        let n = self.size_px;
        let mut rng = SplitMix64::new(self.seed);
        let mut sum = vec![0.0f64; n * n];
        let mut amplitude = 1.0;
        for octave in 0..self.octaves {
            let period = self.period as usize * (1 << octave);
            let perm = permutation(&mut rng);
            let scale = period as f64 / n as f64;
            for (y, row) in sum.chunks_exact_mut(n).enumerate() {
                let v = (y as f64 + 0.5) * scale;
                for (x, value) in row.iter_mut().enumerate() {
                    let u = (x as f64 + 0.5) * scale;
                    *value += amplitude * perlin(&perm, period, u, v);
                }
            }
            amplitude *= self.persistence;
        }
        let mean = sum.iter().sum::<f64>() / sum.len() as f64;
        let spread = sum.iter().fold(0.0f64, |m, v| m.max((v - mean).abs()));
        // A constant field (cannot happen with unit gradients, but keep it finite).
        let gain = if spread > 0.0 { 0.5 / spread } else { 0.0 };
        Ok(sum
            .iter()
            .map(|v| (0.5 + (v - mean) * gain).clamp(0.0, 1.0) as f32)
            .collect())
    }

    /// The texture as a tiling ([`Wrap::Repeat`]) lookup.
    pub fn lookup(&self) -> Result<Lookup> {
        Lookup::new(self.size_px, self.size_px, self.values()?, Wrap::Repeat)
    }
}

/// 0..256 shuffled by Fisher-Yates with `rng`.
fn permutation(rng: &mut SplitMix64) -> [u8; TABLE] {
    let mut perm: [u8; TABLE] = std::array::from_fn(|i| i as u8);
    for i in (1..TABLE).rev() {
        perm.swap(i, rng.below(i + 1));
    }
    perm
}

/// Perlin's quintic fade: 0 and 1 with zero first and second derivatives at the ends.
fn fade(t: f64) -> f64 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

/// Periodic 2D gradient noise at lattice coordinates (u, v) ≥ 0, period `period` cells.
fn perlin(perm: &[u8; TABLE], period: usize, u: f64, v: f64) -> f64 {
    let (u0, v0) = (u.floor(), v.floor());
    let (fu, fv) = (u - u0, v - v0);
    let (i, j) = (u0 as usize, v0 as usize);
    let corner = |di: usize, dj: usize| {
        let (ci, cj) = ((i + di) % period, (j + dj) % period);
        let hash = perm[(usize::from(perm[ci]) + cj) % TABLE];
        let g = GRADIENTS[usize::from(hash) % GRADIENTS.len()];
        g[0] * (fu - di as f64) + g[1] * (fv - dj as f64)
    };
    let (a, b) = (fade(fu), fade(fv));
    let lerp = |p: f64, q: f64, t: f64| p + t * (q - p);
    lerp(
        lerp(corner(0, 0), corner(1, 0), a),
        lerp(corner(0, 1), corner(1, 1), a),
        b,
    )
}

/// The largest side of a noise texture [`load_png`] reads, px: a texture that tiles needs
/// no more, and an 8000 x 6000 one took the process past a memory limit into an abort.
pub const MAX_NOISE_SIDE: u32 = 4096;

/// Loads a noise texture from a PNG: grey or RGB (alpha ignored), 8 or 16 bits per
/// sample, read as values in [0, 1] (`sample / 255` or `/ 65535`). Of an RGB file the red
/// channel is used, as paper 001's listing reads `.x`. The image's top row becomes texture
/// row 0 (v = 0). Errors name the file and say what was expected.
pub fn load_png(path: &Path) -> Result<(usize, usize, Vec<f32>)> {
    let bytes = crate::io::limits::read_file(path)?;
    const SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0D, 0x0A, 0x1A, 0x0A];
    if !bytes.starts_with(&SIGNATURE) {
        return Err(Error::format(
            path,
            "not a PNG file; expected a grey or RGB PNG (8 or 16 bits) noise texture",
        ));
    }
    let name = path.display().to_string();
    let (w, h) = crate::io::image::image_dimensions(&bytes, &name)?;
    if w.max(h) > MAX_NOISE_SIDE {
        return Err(Error::format(
            path,
            format!(
                "noise texture is {w}x{h} px; expected at most {MAX_NOISE_SIDE} px a side (it \
                 tiles over the fog: 256 to 1024 px is usual)"
            ),
        ));
    }
    let image = crate::io::image::decode_any(&bytes, &name)?;
    let (w, h) = (image.width() as usize, image.height() as usize);
    let values: Vec<f32> = match &image {
        DynamicImage::ImageLuma8(_)
        | DynamicImage::ImageLumaA8(_)
        | DynamicImage::ImageRgb8(_)
        | DynamicImage::ImageRgba8(_) => image
            .to_rgb8()
            .pixels()
            .map(|p| f32::from(p.0[0]) / 255.0)
            .collect(),
        DynamicImage::ImageLuma16(_)
        | DynamicImage::ImageLumaA16(_)
        | DynamicImage::ImageRgb16(_)
        | DynamicImage::ImageRgba16(_) => image
            .to_rgb16()
            .pixels()
            .map(|p| f32::from(p.0[0]) / 65535.0)
            .collect(),
        other => {
            return Err(Error::format(
                path,
                format!(
                    "noise PNG has colour type {:?}; expected grey or RGB with 8 or 16 bits \
                     per sample",
                    other.color()
                ),
            ))
        }
    };
    Ok((w, h, values))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stats(v: &[f32]) -> (f64, f64) {
        let n = v.len() as f64;
        let mean = v.iter().map(|&x| f64::from(x)).sum::<f64>() / n;
        let var = v
            .iter()
            .map(|&x| (f64::from(x) - mean).powi(2))
            .sum::<f64>()
            / n;
        (mean, var.sqrt())
    }

    #[test]
    fn noise_tiles_seamlessly() {
        let recipe = TilingNoise::new(128, 7);
        let n = recipe.size_px;
        let lookup = recipe.lookup().unwrap();
        let v = lookup.values();
        // The bilinear sample at u = 0 is the one at u = 1 (and v likewise): the same two
        // texels, the last and the first, blended half and half.
        for t in [0.1, 0.37, 0.5, 0.93] {
            let (a, b) = (lookup.sample(0.0, t), lookup.sample(1.0, t));
            assert!((a - b).abs() < 1e-12, "u seam at v = {t}: {a} vs {b}");
            let (a, b) = (lookup.sample(t, 0.0), lookup.sample(t, 1.0));
            assert!((a - b).abs() < 1e-12, "v seam at u = {t}: {a} vs {b}");
        }
        // Neighbouring texels across the wrap differ no more than neighbours inside.
        let at = |x: usize, y: usize| f64::from(v[y * n + x]);
        let mut inner: f64 = 0.0;
        let mut seam: f64 = 0.0;
        for y in 0..n {
            for x in 0..n - 1 {
                inner = inner.max((at(x + 1, y) - at(x, y)).abs());
                inner = inner.max((at(y, x + 1) - at(y, x)).abs());
            }
            seam = seam.max((at(0, y) - at(n - 1, y)).abs());
            seam = seam.max((at(y, 0) - at(y, n - 1)).abs());
        }
        assert!(
            seam <= inner,
            "seam step {seam} > largest inner step {inner}"
        );
        // And the field is smooth: a texel step is a small part of the range.
        assert!(inner < 0.2, "largest step {inner}");
        // A non-periodic lattice would fail this: compare with the step between the first
        // column and the middle one, which is not a neighbour.
        let far: f64 = (0..n)
            .map(|y| (at(0, y) - at(n / 2, y)).abs())
            .fold(0.0, f64::max);
        assert!(far > inner, "the field barely varies: {far} vs {inner}");
    }

    #[test]
    fn noise_is_deterministic_per_seed() {
        let a = TilingNoise::new(64, 42).values().unwrap();
        let b = TilingNoise::new(64, 42).values().unwrap();
        let c = TilingNoise::new(64, 43).values().unwrap();
        assert_eq!(a, b);
        let differ = a.iter().zip(&c).filter(|(p, q)| p != q).count();
        assert!(
            differ > a.len() / 2,
            "seeds 42 and 43 share {differ} texels"
        );
        // Pinned bits: a change of algorithm (or a platform's arithmetic) shows here.
        let digest = a.iter().fold(0u64, |h, v| {
            (h ^ u64::from(v.to_bits())).wrapping_mul(0x100_0000_01B3)
        });
        assert_eq!(digest, NOISE_64_SEED_42_DIGEST, "digest {digest:#x}");
    }

    /// FNV-style digest of `TilingNoise::new(64, 42)`.
    const NOISE_64_SEED_42_DIGEST: u64 = 0xe5ee_c594_bd18_de2e;

    #[test]
    fn noise_spans_the_unit_range_around_one_half() {
        for seed in [0, 1, 2, 99] {
            let v = TilingNoise::new(256, seed).values().unwrap();
            let (mean, std) = stats(&v);
            let lo = v.iter().copied().fold(f32::MAX, f32::min);
            let hi = v.iter().copied().fold(f32::MIN, f32::max);
            assert!(lo >= 0.0 && hi <= 1.0, "range [{lo}, {hi}]");
            // One extreme touches the range's end (the larger deviation from the mean).
            assert!(lo == 0.0 || hi == 1.0, "range [{lo}, {hi}]");
            assert!((mean - 0.5).abs() < 1e-6, "seed {seed}: mean {mean}");
            assert!(std > 0.1, "seed {seed}: std {std}");
        }
    }

    #[test]
    fn bad_recipes_are_refused_by_name() {
        let bad = |r: TilingNoise| r.validate().unwrap_err().to_string();
        assert!(bad(TilingNoise::new(1, 0)).contains("noise size"));
        let too_fine = TilingNoise {
            octaves: 8,
            ..TilingNoise::default()
        };
        assert!(bad(too_fine).contains("noise octaves"));
        let none = TilingNoise {
            octaves: 0,
            ..TilingNoise::default()
        };
        assert!(bad(none).contains("noise octaves"));
        let huge = TilingNoise {
            octaves: 40,
            ..TilingNoise::default()
        };
        assert!(bad(huge).contains("noise octaves"));
        let flat = TilingNoise {
            period: 0,
            ..TilingNoise::default()
        };
        assert!(bad(flat).contains("noise period"));
        let loud = TilingNoise {
            persistence: 1.5,
            ..TilingNoise::default()
        };
        assert!(bad(loud).contains("noise persistence"));
        assert!(TilingNoise::default().validate().is_ok());
    }

    #[test]
    fn png_noise_is_read_as_unit_values() {
        let dir = tempfile::tempdir().unwrap();
        let grey = dir.path().join("grey16.png");
        let img =
            image::ImageBuffer::<image::Luma<u16>, _>::from_raw(2, 1, vec![0, 65535]).unwrap();
        img.save(&grey).unwrap();
        assert_eq!(load_png(&grey).unwrap(), (2, 1, vec![0.0, 1.0]));
        let rgb = dir.path().join("rgb8.png");
        let img = image::RgbImage::from_raw(1, 2, vec![51, 0, 0, 255, 255, 255]).unwrap();
        img.save(&rgb).unwrap();
        assert_eq!(load_png(&rgb).unwrap(), (1, 2, vec![0.2, 1.0]));

        let missing = dir.path().join("missing.png");
        assert!(load_png(&missing)
            .unwrap_err()
            .to_string()
            .contains("missing.png"));
        let text = dir.path().join("noise.png");
        std::fs::write(&text, b"not an image").unwrap();
        let e = load_png(&text).unwrap_err().to_string();
        assert!(e.contains("noise.png") && e.contains("expected"), "{e}");

        // Refused from its header, before it is decoded; the largest side is read.
        let wide = dir.path().join("wide.png");
        image::GrayImage::new(MAX_NOISE_SIDE + 1, 1)
            .save(&wide)
            .unwrap();
        let e = load_png(&wide).unwrap_err().to_string();
        assert!(e.contains("wide.png") && e.contains("4097x1 px"), "{e}");
        let widest = dir.path().join("widest.png");
        image::GrayImage::new(MAX_NOISE_SIDE, 1)
            .save(&widest)
            .unwrap();
        assert_eq!(load_png(&widest).unwrap().0, 4096);
    }
}
