//! Image similarity, as paper 002 (sec. 7.2.3) compares a render with a photograph of the
//! same scene: the structural similarity index (SSIM) and the correlation of HSV
//! histograms (its eq. 27).
//!
//! - **SSIM** (Wang, Bovik, Sheikh and Simoncelli 2004, "Image quality assessment: from
//!   error visibility to structural similarity") on the sRGB-encoded values in [0, 1]
//!   (SSIM was designed for display values, not linear light), per channel with the
//!   paper's 11 x 11 Gaussian window of σ = 1.5 px, K1 = 0.01, K2 = 0.03, L = 1, borders
//!   left out (only windows wholly inside the image); the mean over the three channels.
//! - **HSV histogram correlation**: per channel of HSV (hue, saturation, value, each in
//!   [0, 1]), a histogram of `HSV_BINS` bins of each image and their correlation
//!   Σ(H1 − H̄1)(H2 − H̄2) / √(Σ(H1 − H̄1)² · Σ(H2 − H̄2)²) — eq. 27 as printed lacks the
//!   sums under the root; this is the usual form (OpenCV's `HISTCMP_CORREL`). The
//!   combined figure is the mean of the three.

use crate::error::{Error, Result};
use crate::io::image::linear_to_srgb;
use crate::raster::{Grid, RgbImage};

/// Bins of each HSV histogram.
pub const HSV_BINS: usize = 64;

/// SSIM's window: a Gaussian of σ = 1.5 px over 11 x 11 px (Wang et al. 2004).
const WINDOW_RADIUS: usize = 5;
const WINDOW_SIGMA: f64 = 1.5;
const K1: f64 = 0.01;
const K2: f64 = 0.03;

/// How alike two images are.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Similarity {
    /// Mean SSIM of the R, G and B channels, in [−1, 1] (1: identical).
    pub ssim: f64,
    /// SSIM per channel (R, G, B).
    pub ssim_rgb: [f64; 3],
    /// Mean of the H, S and V histogram correlations, in [−1, 1] (1: identical).
    pub hsv_correlation: f64,
    /// Histogram correlation per channel (H, S, V).
    pub hsv_correlation_hsv: [f64; 3],
}

/// Compares two linear-light images of one size (`a_name`, `b_name` name them in errors).
pub fn compare(a: &RgbImage, a_name: &str, b: &RgbImage, b_name: &str) -> Result<Similarity> {
    if (a.width(), a.height()) != (b.width(), b.height()) {
        return Err(Error::size_mismatch(
            a_name,
            (a.width(), a.height()),
            b_name,
            (b.width(), b.height()),
        ));
    }
    let side = 2 * WINDOW_RADIUS + 1;
    if a.width() < side || a.height() < side {
        return Err(Error::format(
            std::path::Path::new(a_name),
            format!(
                "is {}x{} px; SSIM compares {side}x{side} windows, so both images need at \
                 least that",
                a.width(),
                a.height()
            ),
        ));
    }
    let encoded =
        |img: &RgbImage, c: usize| img.map(|p| f64::from(linear_to_srgb(p[c].clamp(0.0, 1.0))));
    let ssim_rgb: [f64; 3] = std::array::from_fn(|c| ssim(&encoded(a, c), &encoded(b, c)));
    let (ha, hb) = (hsv_histograms(a), hsv_histograms(b));
    let hsv: [f64; 3] = std::array::from_fn(|c| correlation(&ha[c], &hb[c]));
    Ok(Similarity {
        ssim: ssim_rgb.iter().sum::<f64>() / 3.0,
        ssim_rgb,
        hsv_correlation: hsv.iter().sum::<f64>() / 3.0,
        hsv_correlation_hsv: hsv,
    })
}

/// Mean SSIM of two grey images in [0, 1] over every window wholly inside them.
pub fn ssim(x: &Grid<f64>, y: &Grid<f64>) -> f64 {
    let r = WINDOW_RADIUS as i64;
    let weights: Vec<f64> = (-r..=r)
        .map(|i| (-((i * i) as f64) / (2.0 * WINDOW_SIGMA * WINDOW_SIGMA)).exp())
        .collect();
    let norm: f64 = weights.iter().sum();
    let weights: Vec<f64> = weights.iter().map(|w| w / norm).collect();
    // The five local moments by a separable Gaussian: x, y, x², y², xy.
    let products = Grid::from_fn(x.width(), x.height(), |i, j| {
        let (a, b) = (*x.get(i, j), *y.get(i, j));
        [a, b, a * a, b * b, a * b]
    });
    let moments = separable_valid(&products, &weights);
    let (c1, c2) = ((K1 * 1.0).powi(2), (K2 * 1.0).powi(2));
    let values: Vec<f64> = moments
        .as_slice()
        .iter()
        .map(|m| {
            let (mx, my) = (m[0], m[1]);
            let (vx, vy, cxy) = (m[2] - mx * mx, m[3] - my * my, m[4] - mx * my);
            ((2.0 * mx * my + c1) * (2.0 * cxy + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2))
        })
        .collect();
    values.iter().sum::<f64>() / values.len() as f64
}

/// The weighted sums of `g` over every window of `weights.len()` px on each axis that
/// lies wholly inside it (a "valid" convolution).
fn separable_valid(g: &Grid<[f64; 5]>, weights: &[f64]) -> Grid<[f64; 5]> {
    let n = weights.len();
    let (w, h) = (g.width() + 1 - n, g.height() + 1 - n);
    let sum = |taps: &mut dyn Iterator<Item = ([f64; 5], f64)>| {
        let mut acc = [0.0; 5];
        for (v, wt) in taps {
            for k in 0..5 {
                acc[k] += wt * v[k];
            }
        }
        acc
    };
    let rows = Grid::from_fn(w, g.height(), |x, y| {
        sum(&mut (0..n).map(|i| (*g.get(x + i, y), weights[i])))
    });
    Grid::from_fn(w, h, |x, y| {
        sum(&mut (0..n).map(|j| (*rows.get(x, y + j), weights[j])))
    })
}

/// The H, S and V histograms of an image (sRGB-encoded values, as a photo is seen).
fn hsv_histograms(img: &RgbImage) -> [Vec<f64>; 3] {
    let mut hist = [
        vec![0.0; HSV_BINS],
        vec![0.0; HSV_BINS],
        vec![0.0; HSV_BINS],
    ];
    for p in img.as_slice() {
        let rgb = p.map(|v| f64::from(linear_to_srgb(v.clamp(0.0, 1.0))));
        for (c, v) in hsv(rgb).into_iter().enumerate() {
            let bin = ((v * HSV_BINS as f64) as usize).min(HSV_BINS - 1);
            hist[c][bin] += 1.0;
        }
    }
    hist
}

/// Hue, saturation and value of an RGB colour, each in [0, 1] (hue in turns).
pub fn hsv([r, g, b]: [f64; 3]) -> [f64; 3] {
    let max = r.max(g).max(b);
    let min = r.min(g).min(b);
    let delta = max - min;
    let hue = if delta == 0.0 {
        0.0
    } else if max == r {
        ((g - b) / delta).rem_euclid(6.0) / 6.0
    } else if max == g {
        ((b - r) / delta + 2.0) / 6.0
    } else {
        ((r - g) / delta + 4.0) / 6.0
    };
    let saturation = if max == 0.0 { 0.0 } else { delta / max };
    [hue, saturation, max]
}

/// The correlation of two histograms; 1 for two flat (constant) ones, which are alike.
fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let mean = |h: &[f64]| h.iter().sum::<f64>() / h.len() as f64;
    let (ma, mb) = (mean(a), mean(b));
    let (mut num, mut da, mut db) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        num += (x - ma) * (y - mb);
        da += (x - ma) * (x - ma);
        db += (y - mb) * (y - mb);
    }
    if da == 0.0 && db == 0.0 {
        1.0
    } else if da == 0.0 || db == 0.0 {
        0.0
    } else {
        num / (da * db).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn card(w: usize, h: usize, shift: f32) -> RgbImage {
        Grid::from_fn(w, h, |x, y| {
            let v = ((x / 4 + y / 4) % 2) as f32 * 0.6 + 0.2;
            [v, (x as f32 / w as f32 + shift).min(1.0), 0.3]
        })
    }

    #[test]
    fn identical_images_are_alike() {
        let a = card(40, 30, 0.0);
        let s = compare(&a, "a", &a, "a").unwrap();
        assert!((s.ssim - 1.0).abs() < 1e-12, "{s:?}");
        assert!((s.hsv_correlation - 1.0).abs() < 1e-12, "{s:?}");
    }

    #[test]
    fn a_blurred_or_shifted_image_scores_lower() {
        let a = card(40, 30, 0.0);
        let blurred = Grid::from_fn(40, 30, |x, y| {
            let xs = [x.saturating_sub(1), x, (x + 1).min(39)];
            let mut acc = [0.0f32; 3];
            for &xx in &xs {
                let p = a.get(xx, y);
                for c in 0..3 {
                    acc[c] += p[c] / 3.0;
                }
            }
            acc
        });
        let s = compare(&a, "a", &blurred, "b").unwrap();
        assert!(s.ssim < 0.95 && s.ssim > 0.3, "{s:?}");
        let tinted = card(40, 30, 0.3);
        let t = compare(&a, "a", &tinted, "c").unwrap();
        assert!(t.hsv_correlation < 0.99, "{t:?}");
    }

    #[test]
    fn hsv_of_primaries() {
        assert_eq!(hsv([1.0, 0.0, 0.0]), [0.0, 1.0, 1.0]);
        let [h, s, v] = hsv([0.0, 1.0, 0.0]);
        assert!((h - 1.0 / 3.0).abs() < 1e-12 && s == 1.0 && v == 1.0);
        assert_eq!(hsv([0.5, 0.5, 0.5]), [0.0, 0.0, 0.5]);
    }

    #[test]
    fn sizes_must_agree() {
        let err = compare(&card(20, 20, 0.0), "a.png", &card(21, 20, 0.0), "b.png")
            .unwrap_err()
            .to_string();
        assert!(err.contains("a.png") && err.contains("b.png"), "{err}");
        assert!(compare(&card(8, 8, 0.0), "a", &card(8, 8, 0.0), "b").is_err());
    }
}
