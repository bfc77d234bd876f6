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
use crate::io::image::{self, linear_to_srgb};
use crate::raster::{Grid, RgbImage};
use std::path::Path;

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
    let encoded = |img: &RgbImage, x: usize, y: usize, c: usize| {
        f64::from(linear_to_srgb(img.get(x, y)[c].clamp(0.0, 1.0)))
    };
    let ssim_rgb: [f64; 3] = std::array::from_fn(|c| {
        mean_ssim((a.width(), a.height()), |x, y| {
            (encoded(a, x, y, c), encoded(b, x, y, c))
        })
    });
    let (ha, hb) = (hsv_histograms(a), hsv_histograms(b));
    let hsv: [f64; 3] = std::array::from_fn(|c| correlation(&ha[c], &hb[c]));
    Ok(Similarity {
        ssim: ssim_rgb.iter().sum::<f64>() / 3.0,
        ssim_rgb,
        hsv_correlation: hsv.iter().sum::<f64>() / 3.0,
        hsv_correlation_hsv: hsv,
    })
}

/// Bytes per pixel of each image that [`compare_files`] holds: the decoded linear image
/// and what its decoder holds beside it. From `brume compare`'s peak RSS on two 8000 x
/// 6000 PNGs: 15.1 bytes per pixel of each; rounded up.
const COMPARE_BYTES_PER_PIXEL: u64 = 16;

/// Compares the image files `a` and `b` as [`compare`] compares images, after refusing,
/// from their headers, a pair that cannot fit in the memory left ([`crate::memory`]).
/// Returns the similarity and the images' size (upright, as compared). Errors: the
/// loaders', [`Error::OutOfMemory`], and [`compare`]'s.
pub fn compare_files(a: &Path, b: &Path) -> Result<(Similarity, (usize, usize))> {
    let read = |path: &Path| -> Result<(Vec<u8>, String)> {
        Ok((
            crate::io::limits::read_file(path)?,
            path.display().to_string(),
        ))
    };
    let ((a_bytes, a_name), (b_bytes, b_name)) = (read(a)?, read(b)?);
    let _reserved = crate::photo::check_decoding_fits(
        &[(&a_bytes, &a_name), (&b_bytes, &b_name)],
        "comparing",
        COMPARE_BYTES_PER_PIXEL,
        "a comparison holds about {} bytes per pixel of each image: compare smaller images",
    )?;
    let a_image = image::decode_linear_rgb(&a_bytes, &a_name)?;
    drop(a_bytes);
    let b_image = image::decode_linear_rgb(&b_bytes, &b_name)?;
    let similarity = compare(&a_image, &a_name, &b_image, &b_name)?;
    Ok((similarity, (a_image.width(), a_image.height())))
}

/// Mean SSIM of two grey images in [0, 1] over every window wholly inside them.
pub fn ssim(x: &Grid<f64>, y: &Grid<f64>) -> f64 {
    mean_ssim((x.width(), x.height()), |i, j| (*x.get(i, j), *y.get(i, j)))
}

/// Mean SSIM over every window wholly inside a `width x height` pair of grey images whose
/// values at a pixel `sample` gives. The five local moments (x, y, x², y², xy) by a
/// separable Gaussian, one row at a time: each row's products are weighted along it into
/// a ring of the window's last rows, which are weighted down the columns. The images are
/// read once and nothing of their size is allocated (a full-size grid of the five moments
/// per step took 160 bytes per pixel: 7.5 GB to compare two 8000x6000 photos).
fn mean_ssim((width, height): (usize, usize), sample: impl Fn(usize, usize) -> (f64, f64)) -> f64 {
    let weights = window_weights();
    let n = weights.len();
    let (w, h) = (width + 1 - n, height + 1 - n);
    let weighted = |taps: &mut dyn Iterator<Item = ([f64; 5], f64)>| {
        let mut acc = [0.0; 5];
        for (v, wt) in taps {
            for k in 0..5 {
                acc[k] += wt * v[k];
            }
        }
        acc
    };
    let (c1, c2) = ((K1 * 1.0).powi(2), (K2 * 1.0).powi(2));
    let mut products = vec![[0.0; 5]; width];
    let mut rows = vec![vec![[0.0; 5]; w]; n];
    // Summed in row-major order from −0.0, as `Iterator::sum` over every window's value.
    let mut total = -0.0;
    for y in 0..height {
        for (x, p) in products.iter_mut().enumerate() {
            let (a, b) = sample(x, y);
            *p = [a, b, a * a, b * b, a * b];
        }
        for (x, r) in rows[y % n].iter_mut().enumerate() {
            *r = weighted(&mut (0..n).map(|i| (products[x + i], weights[i])));
        }
        let Some(top) = (y + 1).checked_sub(n) else {
            continue;
        };
        let ring = &rows;
        let column = |x: usize| weighted(&mut (0..n).map(|j| (ring[(top + j) % n][x], weights[j])));
        for m in (0..w).map(column) {
            let (mx, my) = (m[0], m[1]);
            let (vx, vy, cxy) = (m[2] - mx * mx, m[3] - my * my, m[4] - mx * my);
            total += ((2.0 * mx * my + c1) * (2.0 * cxy + c2))
                / ((mx * mx + my * my + c1) * (vx + vy + c2));
        }
    }
    total / (w * h) as f64
}

/// SSIM's window along one axis: the Gaussian of σ = 1.5 px over 11 px, normalised.
fn window_weights() -> Vec<f64> {
    let r = WINDOW_RADIUS as i64;
    let weights: Vec<f64> = (-r..=r)
        .map(|i| (-((i * i) as f64) / (2.0 * WINDOW_SIGMA * WINDOW_SIGMA)).exp())
        .collect();
    let norm: f64 = weights.iter().sum();
    weights.iter().map(|w| w / norm).collect()
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

    /// The row-by-row SSIM against its definition computed window by window, with the 2D
    /// Gaussian's weights (the product of the two axes'), on an uneven pair of sizes and
    /// on an image of exactly one window.
    #[test]
    fn ssim_matches_its_definition_window_by_window() {
        let value = |seed: u64, x: usize, y: usize| {
            let h = (x as u64 * 73_856_093) ^ (y as u64 * 19_349_663) ^ (seed * 83_492_791);
            (h.wrapping_mul(2_654_435_761) % 1000) as f64 / 1000.0
        };
        let weights = window_weights();
        let n = weights.len();
        let (c1, c2) = (K1 * K1, K2 * K2);
        for (w, h) in [(23, 17), (11, 11), (11, 30)] {
            let x = Grid::from_fn(w, h, |i, j| value(1, i, j));
            // y: x darkened and noisier, so every term of the formula matters.
            let y = Grid::from_fn(w, h, |i, j| 0.7 * x.get(i, j) + 0.3 * value(2, i, j));
            let mut sum = 0.0;
            for y0 in 0..=h - n {
                for x0 in 0..=w - n {
                    let mut m = [0.0; 5];
                    for j in 0..n {
                        for i in 0..n {
                            let wt = weights[i] * weights[j];
                            let (a, b) = (*x.get(x0 + i, y0 + j), *y.get(x0 + i, y0 + j));
                            for (k, v) in [a, b, a * a, b * b, a * b].into_iter().enumerate() {
                                m[k] += wt * v;
                            }
                        }
                    }
                    let (vx, vy) = (m[2] - m[0] * m[0], m[3] - m[1] * m[1]);
                    let cxy = m[4] - m[0] * m[1];
                    sum += ((2.0 * m[0] * m[1] + c1) * (2.0 * cxy + c2))
                        / ((m[0] * m[0] + m[1] * m[1] + c1) * (vx + vy + c2));
                }
            }
            let direct = sum / ((w + 1 - n) * (h + 1 - n)) as f64;
            let streamed = ssim(&x, &y);
            assert!(
                (streamed - direct).abs() < 1e-12,
                "{w}x{h}: {streamed} vs {direct}"
            );
            assert!(streamed < 0.99, "{w}x{h}: {streamed}");
            assert!((ssim(&x, &x) - 1.0).abs() < 1e-12);
        }
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
