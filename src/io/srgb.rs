//! The sRGB transfer curve (IEC 61966-2-1), both ways: exact per value, and by tables
//! for whole 8-bit images, on every core. PNG and JPEG photos are decoded by it and
//! brume's 8-bit outputs encoded by it (`io::image` re-exports these functions).

use rayon::prelude::*;

/// sRGB-encoded value in `[0, 1]` to linear light, with the exact piecewise curve of
/// IEC 61966-2-1 (linear segment below 0.04045).
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Interleaved 8-bit sRGB RGB (3 bytes a pixel) as linear-light pixels, by
/// [`srgb8_to_linear_table`], on every core.
pub fn srgb8_rgb_to_linear(rgb: &[u8]) -> Vec<[f32; 3]> {
    let lut = srgb8_to_linear_table();
    crate::parallel::run(|| {
        rgb.par_chunks_exact(3)
            .map(|p| {
                [
                    lut[usize::from(p[0])],
                    lut[usize::from(p[1])],
                    lut[usize::from(p[2])],
                ]
            })
            .collect()
    })
}

/// The RGB of linear RGBA pixels as 8-bit sRGB (alpha dropped), by [`linear_to_srgb8`],
/// on every core. `into_flattened` makes it interleaved bytes without a copy.
pub fn linear_rgba_to_srgb8_rgb(rgba: &[[f32; 4]]) -> Vec<[u8; 3]> {
    linear_to_srgb8_rgb(rgba)
}

/// [`linear_rgba_to_srgb8_rgb`] of pixels of `N` ≥ 3 channels (RGB or RGBA), the first
/// three taken.
pub fn linear_to_srgb8_rgb<const N: usize>(pixels: &[[f32; N]]) -> Vec<[u8; 3]> {
    const { assert!(N >= 3, "an RGB or RGBA pixel") };
    crate::parallel::run(|| {
        pixels
            .par_iter()
            .map(|p| [p[0], p[1], p[2]].map(linear_to_srgb8))
            .collect()
    })
}

/// The linear value of each 8-bit sRGB code value, by the exact curve: 256 lookups
/// instead of one `powf` per channel when decoding 8-bit pixels.
pub fn srgb8_to_linear_table() -> [f32; 256] {
    std::array::from_fn(|v| srgb_to_linear(v as f32 / 255.0))
}

/// The 8-bit sRGB code value of a linear value, as brume's PNG writer makes it: clamped
/// to [0, 1] (NaN as 0, black), encoded, rounded. By table: the same code as encoding
/// with [`linear_to_srgb`] and rounding, for every `f32`, in two lookups instead of a
/// `powf`: the 6.3 M values of a 2048x1024 frame in 52 ms instead of 139 on this machine.
pub fn linear_to_srgb8(v: f32) -> u8 {
    // NaN would otherwise survive the clamp.
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    let table = srgb8_table();
    // v·BINS is exact (a power of two), so v lies in bin `floor` or at its end (v = 1).
    let code = table.bin_start[(v * SRGB8_BINS as f32) as usize];
    code + u8::from(v >= table.thresholds[usize::from(code)])
}

/// [`linear_to_srgb8`] by the formula, for a clamped `v`: what the table reproduces.
fn linear_to_srgb8_by_formula(v: f32) -> u8 {
    (linear_to_srgb(v) * 255.0).round() as u8
}

/// Bins of [0, 1] narrower than the closest two code thresholds (1/(255·12.92) =
/// 3.0e-4 apart on the curve's linear segment, wider above): a bin holds at most one.
const SRGB8_BINS: usize = 4096;

/// [`linear_to_srgb8`]'s tables.
struct Srgb8Table {
    /// `thresholds[k]`: the smallest `f32` the formula encodes to k + 1 or above (k <
    /// 255), and +∞ for 255.
    thresholds: [f32; 256],
    /// The code of each bin's first value, `i / SRGB8_BINS` (and of 1.0 last).
    bin_start: [u8; SRGB8_BINS + 1],
}

fn srgb8_table() -> &'static Srgb8Table {
    static TABLE: std::sync::OnceLock<Srgb8Table> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let thresholds: [f32; 256] = std::array::from_fn(|k| match k {
            255 => f32::INFINITY,
            _ => first_float_encoded_to(k as u8 + 1),
        });
        let bin_start = std::array::from_fn(|i| {
            let start = i as f32 / SRGB8_BINS as f32;
            thresholds.partition_point(|&t| t <= start) as u8
        });
        Srgb8Table {
            thresholds,
            bin_start,
        }
    })
}

/// The smallest `f32` in [0, 1] whose code value by the formula is at least `code` (≥ 1),
/// by bisection over the floats' bit patterns, which order non-negative floats (the
/// formula is monotone: the tests check it around every threshold).
fn first_float_encoded_to(code: u8) -> f32 {
    let (mut below, mut at) = (0u32, 1.0f32.to_bits());
    while at - below > 1 {
        let mid = below + (at - below) / 2;
        if linear_to_srgb8_by_formula(f32::from_bits(mid)) >= code {
            at = mid;
        } else {
            below = mid;
        }
    }
    f32::from_bits(at)
}

/// Linear-light value in `[0, 1]` to sRGB encoding, the exact inverse of
/// [`srgb_to_linear`] (linear segment below 0.0031308).
pub fn linear_to_srgb(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        v * 12.92
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table gives the formula's code for every float near each threshold (±256
    /// ulps, where a non-monotone step or an off-by-one threshold would show), for a
    /// sweep of every 61st float in [0, 1], and for the clamped and NaN inputs.
    #[test]
    fn srgb8_table_equals_the_formula() {
        let check = |v: f32| {
            let clamped = v.clamp(0.0, 1.0);
            assert_eq!(
                linear_to_srgb8(v),
                linear_to_srgb8_by_formula(clamped),
                "{v:e} (bits {:#x})",
                v.to_bits()
            );
        };
        for &t in &srgb8_table().thresholds[..255] {
            let bits = t.to_bits();
            (bits.saturating_sub(256)..=bits + 256)
                .map(f32::from_bits)
                .for_each(check);
        }
        (0..=1.0f32.to_bits())
            .step_by(61)
            .map(f32::from_bits)
            .for_each(check);
        [-1.0, -0.0, 1.0, 1.5, f32::INFINITY, f32::NEG_INFINITY]
            .into_iter()
            .for_each(check);
        assert_eq!(linear_to_srgb8(f32::NAN), 0);
        // An independent check of the curve: IEC 61966-2-1 in f64 at mid-codes.
        for code in 0..=255u8 {
            let s = f64::from(code) / 255.0;
            let linear = if s <= 0.040_45 {
                s / 12.92
            } else {
                ((s + 0.055) / 1.055).powf(2.4)
            };
            assert_eq!(linear_to_srgb8(linear as f32), code, "code {code}");
        }
    }

    /// The whole-image conversions keep each pixel's channels in order and in place (they
    /// run in parallel chunks): every pixel differs, so a swap or a shift would show.
    #[test]
    fn whole_image_conversions_equal_the_per_value_ones() {
        let bytes: Vec<u8> = (0..3 * 1000).map(|i| (i * 7 % 256) as u8).collect();
        let linear = srgb8_rgb_to_linear(&bytes);
        assert_eq!(linear.len(), 1000);
        for (p, rgb) in linear.iter().enumerate() {
            for c in 0..3 {
                assert_eq!(rgb[c], srgb_to_linear(f32::from(bytes[3 * p + c]) / 255.0));
            }
        }
        let rgba: Vec<[f32; 4]> = (0..1000)
            .map(|i| {
                [
                    i as f32 / 999.0,
                    1.0 - i as f32 / 999.0,
                    (i % 13) as f32 / 12.0,
                    0.5,
                ]
            })
            .collect();
        let encoded = linear_rgba_to_srgb8_rgb(&rgba);
        for (p, q) in rgba.iter().zip(&encoded) {
            assert_eq!(*q, [p[0], p[1], p[2]].map(linear_to_srgb8));
        }
        let rgb: Vec<[f32; 3]> = rgba.iter().map(|p| [p[0], p[1], p[2]]).collect();
        assert_eq!(linear_to_srgb8_rgb(&rgb), encoded);
    }
}
