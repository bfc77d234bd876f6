//! Border bands: the band along the left border where a stereo pair has no match, and the
//! rows or columns that rectification leaves without data. Filled as one hole they take
//! the range of whatever surface wins the vote on their boundary (a facade, the sky's
//! neighbour, the road), so a whole band gets one wrong value. Filled here instead, line
//! by line, each from the surface it continues:
//!
//! - Sides in the order left, right, top, bottom. A *band line* is the run of unknown
//!   pixels (outside the sky) from the border inward, if it is at most `max_depth` of the
//!   line long; the pixel that ends it is its *anchor*.
//! - On the top side, an anchor in the sky makes the run sky (rectification rows above the
//!   sky are sky). On the other sides it does not: the sky reaches lower at the image
//!   border than one band's width inward (a roof line in perspective), and the sky
//!   detector, which sees the image, has already made sky what is; the run is left to the
//!   hole filling, which never fills from the sky.
//! - An anchor with known range: the run continues the surface of the first known pixels
//!   after it (up to `2 x max(4, min(run, 16))` pixels along the line, stopping at the
//!   first unknown or sky pixel), extrapolated linearly *in disparity* `1/R`, where a
//!   plane is affine along any line (a facade along a row, the road along a column: both
//!   exact). The slope is the difference of the medians of the two halves of those
//!   pixels over that of their median positions (the mean of the middle two for an even
//!   count); when the halves differ by more than a factor 1.5 (a depth edge among them)
//!   the run takes the median of the first half. The extrapolated disparity is kept within
//!   a factor 1.5 of it, so a slope cannot create a spike, and the range within the
//!   smallest and largest known range outside the sky; with non-positive range the run
//!   takes the anchor's value.
//! - Other anchors (an ego-vehicle pixel, the sky on the other sides) and lines longer than
//!   `max_depth`: the run is left to the hole filling.
//!
//! Filled pixels are known for the sides that follow (a corner is reached from both).

/// Largest ratio of the two halves' medians for a slope to be used, and the largest
/// factor between the extrapolated disparity and the first half's median.
const MAX_RATIO: f32 = 1.5;

/// What [`fill_borders`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct BorderFill {
    /// Pixels given a range.
    pub filled: usize,
    /// Pixels made sky.
    pub sky: usize,
}

/// Fills the border bands of `work` (unknown = NaN, sky pixels flagged in `sky`), as the
/// module docs say, within `known` (the smallest and largest known range); `filled` and
/// `sky` are updated.
pub(crate) fn fill_borders(
    work: &mut [f32],
    sky: &mut [bool],
    filled: &mut [bool],
    (width, height): (usize, usize),
    max_depth: f64,
    known: (f32, f32),
) -> BorderFill {
    let mut out = BorderFill::default();
    let mut samples: Vec<(usize, f32)> = Vec::new();
    // (number of lines, line length, index of step k on line l, whether the run below the
    // top border takes the sky).
    type At<'f> = &'f dyn Fn(usize, usize) -> usize;
    let sides: [(usize, usize, At, bool); 4] = [
        (height, width, &|l, k| l * width + k, false),
        (height, width, &|l, k| l * width + (width - 1 - k), false),
        (width, height, &|l, k| k * width + l, true),
        (width, height, &|l, k| (height - 1 - k) * width + l, false),
    ];
    for (lines, len, at, top) in sides {
        let limit = ((max_depth * len as f64) as usize).min(len.saturating_sub(1));
        for l in 0..lines {
            let unknown = |k: usize| work[at(l, k)].is_nan() && !sky[at(l, k)];
            let run = (0..=limit).take_while(|&k| unknown(k)).count();
            if run == 0 || run > limit {
                continue;
            }
            let anchor = at(l, run);
            if sky[anchor] && top {
                (0..run).for_each(|k| sky[at(l, k)] = true);
                out.sky += run;
                continue;
            }
            if sky[anchor] || !work[anchor].is_finite() {
                continue;
            }
            let want = run.clamp(4, 16) * 2;
            samples.clear();
            for k in run..(run + want).min(len) {
                let v = work[at(l, k)];
                if !v.is_finite() || sky[at(l, k)] {
                    break;
                }
                samples.push((k, v));
            }
            let value = continuation(&samples);
            for k in 0..run {
                work[at(l, k)] = value(k).clamp(known.0, known.1);
                filled[at(l, k)] = true;
            }
            out.filled += run;
        }
    }
    out
}

/// The range at step `k` of a line whose first known pixels are `samples` (step, range;
/// at least one), as the module docs say.
fn continuation(samples: &[(usize, f32)]) -> Box<dyn Fn(usize) -> f32> {
    let first = samples[0].1;
    if samples.iter().any(|&(_, r)| r <= 0.0) || samples.len() < 2 {
        return Box::new(move |_| first);
    }
    let half = samples.len() / 2;
    // The median of the disparities and of the steps (in order along the line; for an
    // even count the mean of the middle two): exact for a plane either way it slopes.
    let stats = |part: &[(usize, f32)]| {
        let mut d: Vec<f32> = part.iter().map(|&(_, r)| 1.0 / r).collect();
        d.sort_unstable_by(f32::total_cmp);
        let n = part.len();
        let (lo, hi) = ((n - 1) / 2, n / 2);
        let med = 0.5 * (d[lo] + d[hi]);
        let pos = 0.5 * (part[lo].0 + part[hi].0) as f32;
        (pos, med)
    };
    let (k1, d1) = stats(&samples[..half]);
    let (k2, d2) = stats(&samples[half..]);
    let slope = if d1.max(d2) <= MAX_RATIO * d1.min(d2) && k2 > k1 {
        (d2 - d1) / (k2 - k1)
    } else {
        0.0
    };
    Box::new(move |k| {
        let d = (d1 + slope * (k as f32 - k1)).clamp(d1 / MAX_RATIO, d1 * MAX_RATIO);
        1.0 / d
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_left_band_continues_a_plane_and_top_rows_above_sky_are_sky() {
        let (w, h) = (40, 20);
        // A facade whose disparity is affine in x and y, the top 4 rows sky in columns
        // 20.., a band of 6 unknown columns on the left, 2 unknown rows at the top.
        let truth = |x: usize, y: usize| 1.0 / (0.02 + 0.001 * x as f32 + 0.0005 * y as f32);
        let mut work = vec![0.0f32; w * h];
        let mut sky = vec![false; w * h];
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                if x < 6 || y < 2 {
                    work[i] = f32::NAN;
                } else if y < 6 && x >= 20 {
                    sky[i] = true;
                    work[i] = f32::INFINITY;
                } else {
                    work[i] = truth(x, y);
                }
            }
        }
        let known = work.clone();
        let mut filled = vec![false; w * h];
        let done = fill_borders(&mut work, &mut sky, &mut filled, (w, h), 0.2, (0.0, 1e9));
        assert_eq!(done.sky, 2 * 20, "{done:?}");
        assert_eq!(done.filled, 6 * (h - 2) + 2 * 20, "{done:?}");
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                if known[i].is_finite() {
                    assert_eq!(work[i].to_bits(), known[i].to_bits());
                } else if !sky[i] {
                    let e = (work[i] - truth(x, y)).abs() / truth(x, y);
                    assert!(e < 1e-4, "({x}, {y}): {} vs {}", work[i], truth(x, y));
                }
            }
        }
        assert!((20..w).all(|x| sky[x] && sky[w + x]));
    }

    #[test]
    fn a_depth_edge_in_the_samples_gives_a_constant() {
        let mut s: Vec<(usize, f32)> = (5..13).map(|k| (k, 10.0)).collect();
        s.extend((13..21).map(|k| (k, 40.0)));
        let f = continuation(&s);
        assert_eq!(f(0), 10.0);
        assert_eq!(continuation(&[(3, 7.0)])(0), 7.0);
        assert_eq!(continuation(&[(3, 0.0), (4, 1.0)])(0), 0.0);
    }
}
