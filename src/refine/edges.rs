//! A stereo matcher's depth edges moved to the image's, for [`super::RefineMode::Repair`].
//!
//! A matcher fattens near surfaces: its window straddles a depth edge and the nearer
//! surface, which has the stronger texture, wins, so a van's or a pole's range reaches 5 to
//! 14 px into the background beside it (Cityscapes' SGM at 2048 x 1024), and its
//! silhouette in the fog is wider than it and ragged. The guided filter cannot undo it
//! where [`super::repair`] keeps the measured range: there its guided range mixes both
//! surfaces, not far enough from the measured one to be taken.
//!
//! Here a pixel at a depth edge (a known range at least [`EDGE_STEP`] times its own within
//! [`EDGE_REACH_PX`]) may take the **weighted median** of the log ranges of its window
//! (every second pixel within [`EDGE_WINDOW_PX`]), each weighted by how alike its colour
//! is to the pixel's: exp(−|c − c₀|² / 2σ²), c the 8-bit sRGB codes / 255, σ
//! [`EDGE_SIGMA_COLOUR`]. A background pixel that took the van's range sits among pixels
//! of its colour that kept the background's, and takes theirs; a van pixel's like-coloured
//! neighbours are the van's. The median is one of the window's measured ranges, never a mix
//! of two surfaces. It is taken only where it lies on another surface than the pixel's
//! own (more than half an [`EDGE_STEP`] away) and its voters are [`EDGE_COLOUR_EVIDENCE`]
//! times as like the pixel in colour as those of the pixel's own surface: without a colour
//! edge a median would erode a pole thinner than the window. Pixels away from depth edges
//! are kept as they are. A colour-weighted median is the usual post-processing of such
//! matchers (Ma et al., "Constant time weighted median filtering for stereo matching",
//! ICCV 2013); a matcher's fattening wider than about half the window is moved only in
//! part.
//!
//! Measured on StereoSGBM with a known truth (`tools/stereo_refine_eval.py`) and on
//! Cityscapes frames: see the README's *Fattened edges*.

use crate::error::{Error, Result};
use crate::io::srgb::linear_to_srgb8_rgb;
use crate::raster::{Grid, RgbImage, ScalarMap};
use std::collections::VecDeque;

/// How many times farther than a pixel a known range within [`EDGE_REACH_PX`] must be for
/// the pixel to be at a depth edge: a step of 40 % (a matcher's noise on one surface, a few
/// per cent, is far below; a pole before a wall is 2x).
pub const EDGE_STEP: f32 = 1.4;

/// How far (px, a square's half side) a farther surface may be from a pixel at a depth
/// edge: as far as a matcher fattens (Cityscapes' SGM: up to 14 px).
pub const EDGE_REACH_PX: usize = 10;

/// The half side of the window whose ranges vote (px); every second pixel of it is read,
/// 11 x 11 of them.
pub const EDGE_WINDOW_PX: usize = 10;

/// The colour σ of the votes' weights, in sRGB-encoded values (0 to 1): colours 0.08 apart
/// per channel weigh e^−½ of alike ones.
pub const EDGE_SIGMA_COLOUR: f32 = 0.08;

/// How much more alike in colour the voters of the median's surface must be to a pixel
/// than those of its own surface (the mean of their weights), for the pixel to take the
/// median: without a colour edge every vote weighs the same, and the plain median of a
/// window would erode a pole of the wall's colour thinner than the window.
pub const EDGE_COLOUR_EVIDENCE: f32 = 1.5;

/// The window is read every `EDGE_WINDOW_STRIDE` pixels: as good as every pixel on
/// StereoSGBM (τ error within 2 %), a quarter of the reads.
const EDGE_WINDOW_STRIDE: usize = 2;

/// The most votes a window has: (2 · 10 / 2 + 1)².
const MAX_VOTES: usize = (2 * EDGE_WINDOW_PX / EDGE_WINDOW_STRIDE + 1).pow(2);

/// Moves the depth edges of `range` (> 0 where it is a range) to the edges of `image`
/// (linear RGB, the same size): each pixel at a depth edge takes the colour-weighted median
/// of its window's ranges (see the module's doc). Pixels `kept_out` (the sky, the ego
/// vehicle), and any range not finite or ≤ 0, neither vote nor change. Returns the new
/// range and how many pixels changed.
///
/// Errors: [`Error::SizeMismatch`] when the image or the mask is not the range's size.
pub fn median_at_depth_edges(
    image: &RgbImage,
    range: &ScalarMap,
    kept_out: Option<&Grid<bool>>,
) -> Result<(ScalarMap, usize)> {
    let (w, h) = (range.width(), range.height());
    let sizes = [
        Some(("the image", image.width(), image.height())),
        kept_out.map(|m| ("the kept-out mask", m.width(), m.height())),
    ];
    for (name, gw, gh) in sizes.into_iter().flatten() {
        if (gw, gh) != (w, h) {
            return Err(Error::size_mismatch(name, (gw, gh), "the range", (w, h)));
        }
    }
    let is_kept_out = |i: usize| kept_out.is_some_and(|m| m.as_slice()[i]);
    let log_range: Vec<f32> = (range.as_slice().iter().enumerate())
        .map(|(i, &v)| {
            if v > 0.0 && v.is_finite() && !is_kept_out(i) {
                v.ln()
            } else {
                f32::NAN
            }
        })
        .collect();
    let farthest = square_max(&log_range, (w, h), EDGE_REACH_PX);
    // 8-bit codes: 3 bytes a pixel, by table, and the precision of most photos.
    let colour = linear_to_srgb8_rgb(image.as_slice());
    let step = EDGE_STEP.ln();
    let weights = weight_table();
    let votes = Votes {
        range: range.as_slice(),
        log_range: &log_range,
        colour: &colour,
        weights: &weights,
        size: (w, h),
    };
    let out = Grid::par_from_fn(w, h, |x, y| {
        let i = y * w + x;
        let l = log_range[i];
        if l.is_nan() || farthest[i] - l < step {
            *range.get(x, y)
        } else {
            votes.moved(x, y).unwrap_or(*range.get(x, y))
        }
    });
    let changed = (out.as_slice().iter())
        .zip(range.as_slice())
        .filter(|(a, b)| a != b)
        .count();
    Ok((out, changed))
}

/// What a pixel's window votes with.
struct Votes<'a> {
    range: &'a [f32],
    log_range: &'a [f32],
    colour: &'a [[u8; 3]],
    weights: &'a [f32],
    size: (usize, usize),
}

impl Votes<'_> {
    /// The range (x, y) takes, one of its window's measured ones: their weighted median
    /// where it lies on another surface than the pixel's own (more than half an
    /// [`EDGE_STEP`] from it) and its voters' colours are [`EDGE_COLOUR_EVIDENCE`] times
    /// as like the pixel's as those of the pixel's own surface; `None` (kept) otherwise.
    fn moved(&self, x: usize, y: usize) -> Option<f32> {
        let (w, h) = self.size;
        let own = self.log_range[y * w + x];
        let c0 = self.colour[y * w + x];
        let same = 0.5 * EDGE_STEP.ln();
        let mut votes = [Vote::default(); MAX_VOTES];
        let mut n = 0;
        // The weights of the votes below the pixel's own surface, on it, above it.
        let mut sums = [0.0f32; 3];
        for qy in window(y, h) {
            for qx in window(x, w) {
                let q = qy * w + qx;
                let l = self.log_range[q];
                if l.is_nan() {
                    continue;
                }
                let c = self.colour[q];
                let d2 = (0..3)
                    .map(|k| (i32::from(c[k]) - i32::from(c0[k])).unsigned_abs().pow(2))
                    .sum::<u32>() as usize;
                let weight = self.weights.get(d2).copied().unwrap_or(0.0);
                let side = if l <= own - same {
                    0
                } else if l < own + same {
                    1
                } else {
                    2
                };
                sums[side] += weight;
                votes[n] = Vote {
                    log_range: l,
                    weight,
                    at: q,
                };
                n += 1;
            }
        }
        // Most pixels at an edge are on the side the median takes: no sort needed.
        let half = 0.5 * sums.iter().sum::<f32>();
        if sums[0] < half && sums[0] + sums[1] >= half {
            return None;
        }
        let votes = &mut votes[..n];
        let chosen = weighted_median(votes)?;
        let median = chosen.log_range;
        if (median - own).abs() < same {
            return None;
        }
        let likeness = |centre: f32| {
            let (sum, count) = (votes.iter())
                .filter(|v| (v.log_range - centre).abs() < same)
                .fold((0.0, 0), |(s, c), v| (s + v.weight, c + 1));
            if count == 0 {
                0.0
            } else {
                sum / count as f32
            }
        };
        (likeness(median) > EDGE_COLOUR_EVIDENCE * likeness(own)).then(|| self.range[chosen.at])
    }
}

/// The weight of a vote by the squared distance of its colour's 8-bit codes from the
/// pixel's, exp(−d² / 2σ²), up to where it is below e^−30 (then 0: beside the pixel's own
/// vote of weight 1 a sum of 121 such is lost in an `f32`'s rounding).
fn weight_table() -> Vec<f32> {
    let sigma = f64::from(EDGE_SIGMA_COLOUR) * 255.0;
    let two_sigma2 = 2.0 * sigma * sigma;
    let len = (30.0 * two_sigma2).ceil() as usize;
    (0..len)
        .map(|d2| (-(d2 as f64) / two_sigma2).exp() as f32)
        .collect()
}

/// One pixel's vote in a window: its log range, its weight, where it is.
#[derive(Clone, Copy, Default)]
struct Vote {
    log_range: f32,
    weight: f32,
    at: usize,
}

/// The weighted median of `votes`, sorted in place: the vote of the smallest log range
/// whose weight and that of all smaller ones is at least half the votes'. `None` for no
/// votes.
fn weighted_median(votes: &mut [Vote]) -> Option<Vote> {
    votes.sort_unstable_by(|a, b| a.log_range.total_cmp(&b.log_range));
    let half = 0.5 * votes.iter().map(|v| v.weight).sum::<f32>();
    let mut sum = 0.0;
    for vote in votes.iter() {
        sum += vote.weight;
        if sum >= half {
            return Some(*vote);
        }
    }
    votes.last().copied()
}

/// The coordinates of a window's pixels along one axis round `centre`: every
/// [`EDGE_WINDOW_STRIDE`]-th within [`EDGE_WINDOW_PX`], the centre among them, inside
/// `0..n`.
fn window(centre: usize, n: usize) -> impl Iterator<Item = usize> {
    let reach = EDGE_WINDOW_PX / EDGE_WINDOW_STRIDE * EDGE_WINDOW_STRIDE;
    let first = centre.saturating_sub(reach);
    // The first read must be `centre` minus a whole number of strides.
    let first = first + (centre - first) % EDGE_WINDOW_STRIDE;
    (first..=(centre + reach).min(n - 1)).step_by(EDGE_WINDOW_STRIDE)
}

/// The largest value of `values` (row-major, `w` x `h`, NaN for none) in the square of half
/// side `r` round each pixel, −∞ where the square holds none: a running maximum along each
/// row, then the element-wise maximum of the 2r + 1 rows round each row (rows in parallel,
/// read in order).
fn square_max(values: &[f32], (w, h): (usize, usize), r: usize) -> Vec<f32> {
    use rayon::prelude::*;
    let mut rows = vec![f32::NEG_INFINITY; w * h];
    let mut out = vec![f32::NEG_INFINITY; w * h];
    crate::parallel::run(|| {
        (values.par_chunks_exact(w).zip(rows.par_chunks_exact_mut(w)))
            .for_each(|(src, dst)| running_max(src, r, dst));
        out.par_chunks_exact_mut(w)
            .enumerate()
            .for_each(|(y, dst)| {
                for row in rows
                    .chunks_exact(w)
                    .take(y + r + 1)
                    .skip(y.saturating_sub(r))
                {
                    dst.iter_mut().zip(row).for_each(|(d, &v)| *d = d.max(v));
                }
            });
    });
    out
}

/// Writes to `dst` the largest of `values` within `r` of each position (NaN counts as
/// none, −∞ where there is none), with a deque of the candidates: each value enters and
/// leaves once.
fn running_max(values: &[f32], r: usize, dst: &mut [f32]) {
    let n = values.len();
    let mut candidates: VecDeque<usize> = VecDeque::new();
    let mut next = 0;
    for (i, out) in dst.iter_mut().enumerate().take(n) {
        while next < n && next <= i + r {
            let v = values[next];
            if !v.is_nan() {
                while candidates.back().is_some_and(|&j| values[j] <= v) {
                    candidates.pop_back();
                }
                candidates.push_back(next);
            }
            next += 1;
        }
        while candidates.front().is_some_and(|&j| j + r < i) {
            candidates.pop_front();
        }
        *out = candidates.front().map_or(f32::NEG_INFINITY, |&j| values[j]);
    }
}

#[cfg(test)]
#[path = "edges_tests.rs"]
mod tests;
