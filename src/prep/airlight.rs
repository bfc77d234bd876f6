//! Airlight estimation from the sky, or from the most distant known pixels.

use super::Prepared;
use crate::raster::RgbImage;

/// Fraction of the known pixels, the most distant, used when there is no sky.
const FARTHEST_FRACTION: f64 = 0.01;

/// Which pixels an [`AirlightEstimate`] comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AirlightSource {
    /// The sky pixels (paper sec. 4.1: "estimated from sky regions").
    Sky,
    /// No sky: the 1 % most distant known (not filled) pixels.
    Farthest,
}

/// The airlight colour and where it came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AirlightEstimate {
    /// Linear-light RGB: the per-channel median of the source pixels.
    pub rgb: [f32; 3],
    /// Which pixels were used.
    pub source: AirlightSource,
    /// How many pixels were used.
    pub pixels: usize,
}

/// Estimates the airlight: the per-channel median of the linear colour of the sky pixels
/// of `prepared`; with no sky, of the 1 % most distant known pixels (ties at the threshold
/// included). The median (not the mean, not the maximum) ignores the sun, birds, wires and
/// bright leakage round foliage. Non-finite colours are skipped.
///
/// # Panics
/// If `image` and `prepared` differ in size.
pub fn estimate_airlight(image: &RgbImage, prepared: &Prepared) -> AirlightEstimate {
    let (w, h) = (prepared.range.width(), prepared.range.height());
    assert!(
        image.width() == w && image.height() == h,
        "estimate_airlight: image is {}x{} but the range is {w}x{h}",
        image.width(),
        image.height()
    );
    let (source, idx) = if prepared.stats.sky_pixels > 0 {
        (AirlightSource::Sky, sky_pixels(prepared))
    } else {
        (AirlightSource::Farthest, farthest_pixels(prepared))
    };
    let colours: Vec<[f32; 3]> = idx
        .iter()
        .map(|&i| image.as_slice()[i])
        .filter(|c| c.iter().all(|v| v.is_finite()))
        .collect();
    AirlightEstimate {
        rgb: median_rgb(&colours),
        source,
        pixels: colours.len(),
    }
}

fn sky_pixels(p: &Prepared) -> Vec<usize> {
    (0..p.sky.len()).filter(|&i| p.sky.as_slice()[i]).collect()
}

/// Indices of the most distant known pixels (at least one).
fn farthest_pixels(p: &Prepared) -> Vec<usize> {
    let (r, sky, filled) = (p.range.as_slice(), p.sky.as_slice(), p.filled.as_slice());
    let known = |i: usize| !sky[i] && !filled[i];
    let mut ranges: Vec<f32> = (0..r.len()).filter(|&i| known(i)).map(|i| r[i]).collect();
    if ranges.is_empty() {
        return (0..r.len()).collect();
    }
    let k = ((ranges.len() as f64 * FARTHEST_FRACTION).ceil() as usize).max(1);
    let n = ranges.len();
    let threshold = *ranges.select_nth_unstable_by(n - k, f32::total_cmp).1;
    (0..r.len())
        .filter(|&i| known(i) && r[i] >= threshold)
        .collect()
}

/// Per-channel median (upper median); black for no colour.
fn median_rgb(colours: &[[f32; 3]]) -> [f32; 3] {
    if colours.is_empty() {
        return [0.0; 3];
    }
    let mut ch = vec![0.0f32; colours.len()];
    let mut out = [0.0; 3];
    for (c, o) in out.iter_mut().enumerate() {
        ch.iter_mut().zip(colours).for_each(|(v, col)| *v = col[c]);
        let mid = ch.len() / 2;
        *o = *ch.select_nth_unstable_by(mid, f32::total_cmp).1;
    }
    out
}
