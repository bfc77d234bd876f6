//! Local outliers: small patches whose range disagrees with their neighbourhood, whatever
//! the frame's percentiles say (a stereo mismatch gives a blotch of 200-550 m on a van
//! 7 m away: far below the far-outlier cut, far above its surroundings).
//!
//! The test runs in disparity space, `d = 1 / R` (stereo noise is uniform there, and a
//! plane is affine in `d`, so a window's median is the plane's value at its centre):
//!
//! 1. The image is cut into square cells of `c = max(1, span / 2)` px. Each cell gets the
//!    median of the known disparities (outside the sky, `R > 0`) in the window of
//!    half-size `span` centred on it (read with a stride of `max(1, span / 12)`, at most
//!    25 x 25 samples); a window with fewer than a quarter of its samples known has no
//!    median.
//! 2. A known pixel *disagrees* when its disparity differs by more than `factor` (as a
//!    ratio, either way) from the median of *every* cell of the 3 x 3 cells round its own.
//!    A patch of span at most `span` covers at most a quarter of any of those windows, so it
//!    cannot move their medians; on either side of a depth edge at least one of the cells
//!    lies on the pixel's own surface, so edges are not flagged.
//! 3. The 8-connected components of disagreeing pixels (far ones and near ones apart) whose
//!    bounding box is at most `span` px on its longest side are outliers: they become
//!    unknown and are filled like holes from the surface round them. A pole, a post or a
//!    tree trunk against a distant background disagrees too, but it is long (and its
//!    component with it), so it stays.
//!
//! Cost: linear in the pixels (at most 625 samples per cell of `span² / 4` px).

use rayon::prelude::*;

/// Removes (sets to NaN) the local outliers among the finite, positive pixels of `work`
/// outside `sky`, as the module docs say. Returns how many pixels were removed.
pub(crate) fn remove_local(
    work: &mut [f32],
    sky: &[bool],
    width: usize,
    height: usize,
    factor: f64,
    span: usize,
) -> usize {
    if factor <= 1.0 || span == 0 || width * height == 0 {
        return 0;
    }
    let disp: Vec<f32> = work
        .par_iter()
        .zip(sky)
        .map(|(&r, &s)| {
            if !s && r.is_finite() && r > 0.0 {
                1.0 / r
            } else {
                f32::NAN
            }
        })
        .collect();
    let cell = (span / 2).max(1);
    let medians = cell_medians(&disp, width, height, cell, span);
    let (cw, ch) = (width.div_ceil(cell), height.div_ceil(cell));
    let around = medians_around(&medians, cw, ch);
    let factor = factor as f32;
    // 0: agrees (or unknown), 1: farther than every median, 2: nearer.
    let mut flag = vec![0u8; width * height];
    flag.par_chunks_mut(width)
        .enumerate()
        .for_each(|(y, flag)| {
            let around = &around[(y / cell) * cw..];
            for (x, flag) in flag.iter_mut().enumerate() {
                let d = disp[y * width + x];
                if d.is_finite() {
                    *flag = around[x / cell].disagreement(d, factor);
                }
            }
        });
    remove_small_patches(work, &mut flag, width, height, span)
}

/// The known medians of the 3 x 3 cells round a cell, in increasing order.
#[derive(Clone, Copy, Default)]
struct Around {
    medians: [f32; 9],
    len: usize,
}

impl Around {
    /// 0 when the disparity `d` is within `factor` (as a ratio, either way) of one of the
    /// medians, or there is none; else 1 when it is below them all (farther), 2 when not.
    fn disagreement(&self, d: f32, factor: f32) -> u8 {
        let m = &self.medians[..self.len];
        if m.is_empty() {
            return 0;
        }
        // The ratio to a median grows away from `d` on either side (and rounding keeps
        // that order), so the medians next to `d` decide whether any is near enough.
        let above = m.partition_point(|&v| v < d);
        let near_above = m.get(above).is_some_and(|&v| v / d <= factor);
        let near_below = above > 0 && d / m[above - 1] <= factor;
        if near_above || near_below {
            0
        } else if d < m[0] {
            1
        } else {
            2
        }
    }
}

/// The [`Around`] of every cell of the `cw x ch` grid of `medians`, in raster order.
fn medians_around(medians: &[f32], cw: usize, ch: usize) -> Vec<Around> {
    let mut around = vec![Around::default(); cw * ch];
    around.par_chunks_mut(cw).enumerate().for_each(|(cy, row)| {
        for (cx, a) in row.iter_mut().enumerate() {
            for ny in cy.saturating_sub(1)..(cy + 2).min(ch) {
                for nx in cx.saturating_sub(1)..(cx + 2).min(cw) {
                    let m = medians[ny * cw + nx];
                    if m.is_finite() {
                        a.medians[a.len] = m;
                        a.len += 1;
                    }
                }
            }
            a.medians[..a.len].sort_unstable_by(f32::total_cmp);
        }
    });
    around
}

/// The median disparity of the window of half-size `half` round the centre of every cell
/// of `cell x cell` px (NaN when under a quarter of its samples are known), cells in
/// raster order.
fn cell_medians(disp: &[f32], width: usize, height: usize, cell: usize, half: usize) -> Vec<f32> {
    let (cw, ch) = (width.div_ceil(cell), height.div_ceil(cell));
    let stride = (half / 12).max(1);
    let mut out = vec![0.0; cw * ch];
    out.par_chunks_mut(cw).enumerate().for_each(|(cy, out)| {
        let yc = (cy * cell + cell / 2).min(height - 1);
        let mut samples = Vec::new();
        for (cx, out) in out.iter_mut().enumerate() {
            let xc = (cx * cell + cell / 2).min(width - 1);
            samples.clear();
            let mut total = 0usize;
            let (y0, y1) = (yc.saturating_sub(half), (yc + half).min(height - 1));
            let (x0, x1) = (xc.saturating_sub(half), (xc + half).min(width - 1));
            for y in (y0..=y1).step_by(stride) {
                for x in (x0..=x1).step_by(stride) {
                    total += 1;
                    let d = disp[y * width + x];
                    if d.is_finite() {
                        samples.push(d);
                    }
                }
            }
            let m = if samples.len() * 4 >= total && !samples.is_empty() {
                let mid = samples.len() / 2;
                *samples.select_nth_unstable_by(mid, f32::total_cmp).1
            } else {
                f32::NAN
            };
            *out = m;
        }
    });
    out
}

/// Sets to NaN the 8-connected patches of equal non-zero `flag` whose bounding box is at
/// most `span` px on its longest side; returns how many pixels that was.
fn remove_small_patches(
    work: &mut [f32],
    flag: &mut [u8],
    width: usize,
    height: usize,
    span: usize,
) -> usize {
    let mut patch = Vec::new();
    let mut removed = 0;
    for seed in 0..flag.len() {
        let kind = flag[seed];
        if kind == 0 || kind > 2 {
            continue;
        }
        // Visited pixels are marked kind + 2 (3 or 4), so they are not taken again.
        flag[seed] = kind + 2;
        patch.clear();
        patch.push(seed);
        let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
        let mut head = 0;
        while head < patch.len() {
            let p = patch[head];
            head += 1;
            let (x, y) = (p % width, p / width);
            (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
            for q in super::outliers::neighbours8(p, width, height)
                .into_iter()
                .flatten()
            {
                if flag[q] == kind {
                    flag[q] = kind + 2;
                    patch.push(q);
                }
            }
        }
        if (x1 - x0 + 1).max(y1 - y0 + 1) <= span {
            patch.iter().for_each(|&p| work[p] = f32::NAN);
            removed += patch.len();
        }
    }
    removed
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// The test as the module docs state it, median by median: `Around` must agree with
    /// it to the bit, near the factor's edge too.
    #[test]
    fn the_nearest_medians_decide_as_every_median_would() {
        let mut rng = SplitMix64::new(11);
        let factor = 1.5f32;
        for case in 0..4000 {
            let n = rng.below(10);
            let mut around = Around::default();
            for _ in 0..n {
                around.medians[around.len] = 0.01 + rng.unit() as f32;
                around.len += 1;
            }
            let medians = around.medians;
            around.medians[..n].sort_unstable_by(f32::total_cmp);
            // Now and then a disparity exactly a factor away from a median, or equal to one.
            let d = match (case % 4, n) {
                (0, 1..) => medians[0] * factor,
                (1, 1..) => medians[n - 1] / factor,
                (2, 1..) => medians[n / 2],
                _ => 0.01 + 1.2 * rng.unit() as f32,
            };
            let (mut supported, mut farther) = (false, true);
            for &m in &medians[..n] {
                let ratio = if d > m { d / m } else { m / d };
                supported |= ratio <= factor;
                farther &= d < m;
            }
            let want = match (n, supported, farther) {
                (0, ..) | (_, true, _) => 0,
                (_, false, true) => 1,
                (_, false, false) => 2,
            };
            assert_eq!(around.disagreement(d, factor), want, "d {d}, {medians:?}");
        }
    }

    /// A road (range rising toward a horizon), a building 50 m away on the upper half, a
    /// pole 3 px wide and 50 px tall 6 m away in front of it, a far blotch on the road and
    /// a near speck on the building.
    fn scene() -> (usize, usize, Vec<f32>) {
        let (w, h) = (120, 100);
        let mut m = vec![0.0f32; w * h];
        for y in 0..h {
            for x in 0..w {
                m[y * w + x] = if y < 40 {
                    50.0 + 0.01 * x as f32
                } else {
                    // The road: disparity affine in y.
                    200.0 / (y as f32 - 35.0)
                };
            }
        }
        for y in 5..55 {
            for x in 60..63 {
                m[y * w + x] = 6.0;
            }
        }
        (w, h, m)
    }

    #[test]
    fn blotches_go_poles_and_surfaces_stay() {
        let (w, h, clean) = scene();
        let mut m = clean.clone();
        let mut planted = Vec::new();
        for y in 75..82 {
            for x in 20..26 {
                m[y * w + x] = 400.0; // a stereo mismatch on the road, ~3-5 m away
                planted.push(y * w + x);
            }
        }
        for y in 10..12 {
            for x in 90..92 {
                m[y * w + x] = 2.0; // a near speck on the building
                planted.push(y * w + x);
            }
        }
        let sky = vec![false; w * h];
        let removed = remove_local(&mut m, &sky, w, h, 3.0, 12);
        assert_eq!(removed, planted.len());
        assert!(planted.iter().all(|&p| m[p].is_nan()));
        for (i, (a, b)) in m.iter().zip(&clean).enumerate() {
            if !planted.contains(&i) {
                assert_eq!(a.to_bits(), b.to_bits(), "pixel {i} changed");
            }
        }
    }

    #[test]
    fn a_short_pole_is_a_patch_and_the_rule_can_be_off() {
        // A wall 50 m away and a post 3 px wide, 20 px tall, 6 m away.
        let (w, h) = (80, 60);
        let mut clean = vec![50.0f32; w * h];
        for y in 20..40 {
            for x in 30..33 {
                clean[y * w + x] = 6.0;
            }
        }
        let sky = vec![false; w * h];
        let mut m = clean.clone();
        assert_eq!(remove_local(&mut m, &sky, w, h, 0.0, 12), 0, "off");
        assert_eq!(
            remove_local(&mut m, &sky, w, h, 3.0, 12),
            0,
            "longer than the span"
        );
        assert_eq!(m, clean);
        assert_eq!(remove_local(&mut m, &sky, w, h, 3.0, 24), 60, "a patch");
        assert!(m.iter().all(|v| v.is_nan() || *v == 50.0));
        // Sky pixels are never looked at.
        let mut m = clean.clone();
        let sky: Vec<bool> = clean.iter().map(|&v| v == 6.0).collect();
        assert_eq!(remove_local(&mut m, &sky, w, h, 3.0, 24), 0);
        assert_eq!(m, clean);
    }
}
