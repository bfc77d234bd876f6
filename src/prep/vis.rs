//! The paper's figure 3: range before and after pre-processing.

use super::Prepared;
use crate::raster::ScalarMap;

const RED: [u8; 3] = [255, 0, 0];

/// Draws `before` (above) and `after` (below) as one 8-bit RGB picture of `width x
/// 2 height`, returned as `(width, height, pixels)` row-major, top row first. Range is
/// grey, near dark and far light, on one scale for both panels from the nearest known
/// value (black) to the largest output value (white, which is `Smax` when there is sky;
/// input values above it, far outliers, are white too).
/// Unknown pixels of `before` are red; in `after` the holes show their filled values and
/// the sky is white, tapering to grey through the horizon margin.
///
/// # Panics
/// If `before` and `after` differ in size.
pub fn visualize(before: &ScalarMap, after: &Prepared) -> (usize, usize, Vec<[u8; 3]>) {
    let (w, h) = (after.range.width(), after.range.height());
    assert!(
        before.width() == w && before.height() == h,
        "visualize: before is {}x{} but after is {w}x{h}",
        before.width(),
        before.height()
    );
    let finite = || {
        before
            .as_slice()
            .iter()
            .chain(after.range.as_slice())
            .filter(|v| v.is_finite())
    };
    let lo = finite().copied().fold(f32::INFINITY, f32::min);
    // The top of the scale is the output's: a far outlier of the input (removed by
    // `prepare`) would otherwise turn every other value black; it shows white.
    let hi = after
        .range
        .as_slice()
        .iter()
        .filter(|v| v.is_finite())
        .copied()
        .fold(f32::NEG_INFINITY, f32::max);
    let grey = |v: f32| {
        let t = if lo > 0.0 && hi > lo {
            (v / lo).ln() / (hi / lo).ln()
        } else if hi > lo {
            (v - lo) / (hi - lo)
        } else {
            1.0
        };
        let g = (t.clamp(0.0, 1.0) * 255.0).round() as u8;
        [g, g, g]
    };
    let top = before
        .as_slice()
        .iter()
        .map(|&v| if v.is_finite() { grey(v) } else { RED });
    let bottom = after.range.as_slice().iter().map(|&v| grey(v));
    (w, 2 * h, top.chain(bottom).collect())
}
