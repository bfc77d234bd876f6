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
//!   the run takes the median of the first half, as it does where the samples do not show
//!   their slope (fewer than [`SLOPE_SAMPLES`], scattered about it by more than
//!   [`SLOPE_SCATTER`] of the disparity, or the halves no more than [`SLOPE_SIGNIFICANCE`]
//!   scatters apart: a matcher's noise, which extrapolated made each row of Cityscapes'
//!   left band a stripe of its own). The extrapolated disparity is kept within
//!   a factor 1.5 of it, so a slope cannot create a spike, and the range within the
//!   smallest and largest known range outside the sky; with non-positive range the run
//!   takes the anchor's value. Toward the bottom border the disparity does not fall (the
//!   slope is taken only where it rises): the ground comes nearer there, and a car's hood
//!   reflecting the street, whose disparity falls toward the border, was continued
//!   farther and farther, a light streak in each such column.
//! - Other anchors (an ego-vehicle pixel, the sky on the other sides) and lines longer than
//!   `max_depth`: the run is left to the hole filling.
//! - *Islands* first: a matcher leaves specks of wrong values inside the band it cannot
//!   match (on real Cityscapes frames runs of 1 to 22 px of disparity 0 to 4, 100 m to
//!   infinitely far, among the unknown columns by a road 6 m away; between the unknown rows
//!   of the hood at the bottom, its reflection of the street, 1.3 to 7 times the road's
//!   range). Ended by one, the run continued the speck's range: a white blotch in the fog.
//!   So, from the border inward and within `max_depth`, an *island* (known runs joined
//!   across unknown gaps under [`ISLAND_GAP`]; along the bottom one run) with fewer than
//!   [`SOLID_RUN`] known pixels, and fewer than the unknown stretch between it and the
//!   border, is dropped (unknown, then part of the run) when its median range is more than
//!   [`ISLAND_RATIO`] times what lies beyond it: the median of up to [`BEYOND`] known
//!   pixels beyond it within `max_depth` (at least half as many: a sparse lidar map is
//!   never judged), which must begin a wide surface ([`WIDE_RUN`]: a road, a facade, not
//!   a post). Along the bottom, where the ground comes nearer toward the border, the
//!   factor is [`BOTTOM_ISLAND_RATIO`] and what lies beyond is its continuation (as above)
//!   at the island. The first island that is not dropped, or a longer run, ends the
//!   search, and the run ends at it as before.
//! - *With the image* (not along the bottom, whose factor is small): an island longer than
//!   its stretch from the border (taken for a piece of a surface reaching the border) is
//!   judged all the same when the image shows the surface beyond it there (the median
//!   colours of its pixels and of those judged beyond it of one material,
//!   [`ColourGuide::alike`]); and an island is not joined to a run that begins a wide
//!   surface, is [`ISLAND_RATIO`] times nearer and of its material (specks on that
//!   surface). A glass facade of Cityscapes' Düsseldorf frame reached the border with
//!   specks of 200-450 m on it, 12-16 px from the border and 14 px from its measured part:
//!   a white patch in the fog.
//!
//! Filled pixels are known for the sides that follow (a corner is reached from both).

use super::colour_guide::ColourGuide;
use super::fill::{median_in_place, MAD_TO_SIGMA};

/// Largest ratio of the two halves' medians for a slope to be used, and the largest factor
/// between the extrapolated disparity and the first half's median.
const MAX_RATIO: f32 = 1.5;

/// A line's slope is followed only from this many samples on: fewer (a road striped with
/// the matcher's gaps leaves runs of 1 to 10 px by the band) say nothing of it.
const SLOPE_SAMPLES: usize = 8;

/// A line's slope is followed only where its samples lie on it: their scatter about it
/// (1.4826 x the median absolute residual, in disparity) at most this fraction of the
/// disparity (brume's synthetic street frame, measured with 0.5 % noise: its left band's
/// error 0.34 m, 0.23 m with every slope followed, 1.48 m with none; the lines by the
/// bands of Cityscapes' SGM disparity scatter 0.2 to 4 %, 10th to 90th percentile, and
/// 15 to 37 % of those with enough samples are followed)...
const SLOPE_SCATTER: f32 = 0.005;

/// ... and where the halves' medians differ by more than this many times that scatter.
const SLOPE_SIGNIFICANCE: f32 = 3.0;

/// The factor by which an island is farther than the surface beyond it to be dropped: a
/// matcher's specks in Cityscapes' left band are 20 to 70 times as far as the road beyond
/// them; a far facade's strip between the band and a car in front (1.7 times the car's
/// range on brume's synthetic street) is a surface. As the local-outlier rule's factor.
const ISLAND_RATIO: f32 = 3.0;

/// [`ISLAND_RATIO`] on the bottom band, where the ground comes nearer toward the border.
const BOTTOM_ISLAND_RATIO: f32 = 1.15;

/// An island of a band line has fewer known pixels than this: one with more is the surface
/// the band continues. The specks a matcher leaves in its unmatched band are runs of 1 to
/// 22 px on Cityscapes frames, 36 px in all in one group.
const SOLID_RUN: usize = 48;

/// Known runs separated by unknown gaps shorter than this (px) are one island: a matcher's
/// specks come in groups, and a far strip hard against a nearer surface belongs with it
/// (on the synthetic SGBM view 2, 7 px of ground 50 m away, 7 px before a post 3.4 m away).
const ISLAND_GAP: usize = 16;

/// Known pixels beyond an island that say what the band meets: up to this many, at least
/// half as many.
const BEYOND: usize = 32;

/// Along a row, what an island's band meets must be a surface that wide (px, from where it
/// first shows past other specks; see `is_wide`): a road or a facade runs on
/// into the band; a post 34 px wide beside far ground (brume's synthetic SGBM view 2) does
/// not, and the far ground there is no speck (taken for one, the band continued the post
/// 144 px: that view's τ error in the band 0.057 → 0.11).
const WIDE_RUN: usize = 64;

/// The border a band line starts from.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Side {
    Left,
    Right,
    Top,
    Bottom,
}

impl Side {
    /// The number of lines from this border and their length.
    fn lines(self, (width, height): (usize, usize)) -> (usize, usize) {
        match self {
            Side::Left | Side::Right => (height, width),
            Side::Top | Side::Bottom => (width, height),
        }
    }

    /// The index of step `k` (from the border) on line `l`.
    fn index(self, l: usize, k: usize, (width, height): (usize, usize)) -> usize {
        match self {
            Side::Left => l * width + k,
            Side::Right => l * width + (width - 1 - k),
            Side::Top => k * width + l,
            Side::Bottom => (height - 1 - k) * width + l,
        }
    }
}

/// What [`fill_borders`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct BorderFill {
    /// Pixels given a range (the islands dropped included).
    pub filled: usize,
    /// Pixels made sky.
    pub sky: usize,
    /// Known pixels dropped as islands farther than the surface their band continues.
    pub islands: usize,
}

/// Fills the border bands of `work` (unknown = NaN, sky pixels flagged in `sky`), as the
/// module docs say, within `known` (the smallest and largest known range), with the
/// image's colours in `guide` when there is one; `filled` and `sky` are updated.
pub(crate) fn fill_borders(
    work: &mut [f32],
    sky: &mut [bool],
    filled: &mut [bool],
    (width, height): (usize, usize),
    max_depth: f64,
    known: (f32, f32),
    guide: Option<&ColourGuide>,
) -> BorderFill {
    let mut out = BorderFill::default();
    let mut samples: Vec<(usize, f32)> = Vec::new();
    for side in [Side::Left, Side::Right, Side::Top, Side::Bottom] {
        let (lines, len) = side.lines((width, height));
        let at = |l: usize, k: usize| side.index(l, k, (width, height));
        let (top, bottom) = (side == Side::Top, side == Side::Bottom);
        let limit = ((max_depth * len as f64) as usize).min(len.saturating_sub(1));
        for l in 0..lines {
            let line = |k: usize| at(l, k);
            let lim = (len, limit);
            out.islands += drop_far_islands(work, sky, &line, lim, (bottom, guide), &mut samples);
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
            let value = continuation(&samples, bottom);
            for k in 0..run {
                work[at(l, k)] = value(k).clamp(known.0, known.1);
                filled[at(l, k)] = true;
            }
            out.filled += run;
        }
    }
    out
}

/// Drops the islands of one band line (`at`: its step → index; `len` steps, the band at
/// most `limit` of them; `bottom`: the bottom band's rules; `guide`: the image's colours),
/// as the module docs say; returns the pixels dropped.
fn drop_far_islands(
    work: &mut [f32],
    sky: &[bool],
    at: &dyn Fn(usize) -> usize,
    (len, limit): (usize, usize),
    (bottom, guide): (bool, Option<&ColourGuide>),
    samples: &mut Vec<(usize, f32)>,
) -> usize {
    let known = |work: &[f32], k: usize| work[at(k)].is_finite() && !sky[at(k)];
    let unknown = |work: &[f32], k: usize| work[at(k)].is_nan() && !sky[at(k)];
    // Along the bottom an island is one run (a hood's reflections lie close to the road's
    // pieces above them), judged by its own factor.
    let (island_gap, ratio) = if bottom {
        (1, BOTTOM_ISLAND_RATIO)
    } else {
        (ISLAND_GAP, ISLAND_RATIO)
    };
    let mut dropped = 0;
    let mut k = 0;
    loop {
        k += (k..=limit).take_while(|&j| unknown(work, j)).count();
        if k > limit || !known(work, k) {
            return dropped; // the band meets no surface (the sky, the ego vehicle) or ends
        }
        // The island: known runs from k on, joined across unknown gaps under `island_gap`.
        // Not across to a run the image shows the island on, far nearer than it: there the
        // island is specks on that surface (a glass facade's, 13 times as far, 14 px from
        // it), not one object with it.
        let (mut end, mut count) = (k, 0);
        loop {
            let n = (end..len).take_while(|&j| known(work, j)).count();
            (end, count) = (end + n, count + n);
            let gap = (end..len).take_while(|&j| unknown(work, j)).count();
            let solid = count >= SOLID_RUN || end > limit; // judged so below, whatever follows
            if solid || gap >= island_gap || end + gap >= len || !known(work, end + gap) {
                break;
            }
            let next = end + gap;
            if guide.is_some() && is_wide(next, &|j| known(work, j), len) {
                let next_end = next + (next..len).take_while(|&j| known(work, j)).count();
                let steps = |r: std::ops::Range<usize>| r.filter(|&j| known(work, j)).collect();
                let (island, run): (Vec<_>, Vec<_>) = (steps(k..end), steps(next..next_end));
                if specks_on(work, at, guide, (&island, &run), ratio) {
                    break;
                }
            }
            end = next;
        }
        if count >= SOLID_RUN || end > limit {
            // The surface the band continues, or more than the band.
            return dropped;
        }
        samples.clear();
        samples.extend(
            (end..(end + limit).min(len))
                .take_while(|&j| !sky[at(j)] && work[at(j)] != f32::INFINITY)
                .filter(|&j| known(work, j))
                .map(|j| (j, work[at(j)]))
                .take(BEYOND),
        );
        if samples.len() < BEYOND / 2 {
            return dropped; // too little beyond it to judge it (a sparse map)
        }
        // At the bottom the ground comes nearer toward the border: the surface is judged
        // where the island is. Along a row the surface may slope either way (a facade),
        // and extrapolated over the gap to the island it made far strips look like specks:
        // its median, which must begin a wide surface where it first shows (past other
        // specks).
        let surface = if bottom {
            continuation(samples, true)((k + end) / 2)
        } else {
            let median = median_of(samples.iter().map(|&(_, r)| r));
            let agrees = |r: f32| r <= MAX_RATIO * median && median <= MAX_RATIO * r;
            let start = samples
                .iter()
                .find(|&&(_, r)| agrees(r))
                .map_or(end, |s| s.0);
            if !is_wide(start, &|j| known(work, j), len) {
                // Beyond it an object, not a surface the band can be (a post: far ground
                // seen beside it was taken for a speck and the band continued the post).
                return dropped;
            }
            median
        };
        let island: Vec<usize> = (k..end).filter(|&j| known(work, j)).collect();
        // A piece of a surface that reaches nearly to the border (a speck lies well inside
        // the band), unless it lies in a band and the image shows the surface beyond it
        // there. Not along the bottom, whose factor is small (on Aloe's true disparity a
        // piece of the table reaching the bottom border was farther than the ground's
        // continuation and of its colour).
        let speck_on_the_surface =
            k > 0 && !bottom && shows_the_surface(guide, at, &island, samples);
        if count > k && !speck_on_the_surface {
            return dropped;
        }
        if median_of(island.iter().map(|&j| work[at(j)])) <= ratio * surface {
            return dropped; // a surface of its own: the band ends at it
        }
        island.iter().for_each(|&j| work[at(j)] = f32::NAN);
        dropped += count;
        k = end;
    }
}

/// Whether a wide surface begins at step `start` of a line of `len` steps: its known runs,
/// joined across gaps under [`ISLAND_GAP`], reach [`WIDE_RUN`] steps from it, and half of
/// those steps are known (a road, a facade; not a post, nor specks beside each other: on a
/// Hamburg frame 20 px of specks at 120 m were taken for the surface that specks at 430 m
/// before them lay on). Three quarters known, as first asked, missed Düsseldorf's road by
/// the left band, striped with the matcher's gaps (44 of 64 known), and the band continued
/// a speck of 400 m before it.
fn is_wide(start: usize, known: &dyn Fn(usize) -> bool, len: usize) -> bool {
    let window = start..(start + WIDE_RUN).min(len);
    if window.clone().filter(|&j| known(j)).count() * 2 < WIDE_RUN {
        return false;
    }
    let mut gap = 0;
    for j in window {
        gap = if known(j) { 0 } else { gap + 1 };
        if gap >= ISLAND_GAP {
            return false;
        }
    }
    true
}

/// Whether the known pixels at steps `island` are specks on the surface of those at steps
/// `run` (which begins a wide surface): more than `ratio` times as far (medians) and, in
/// the image, alike. Without an image, never.
fn specks_on(
    work: &[f32],
    at: &dyn Fn(usize) -> usize,
    guide: Option<&ColourGuide>,
    (island, run): (&[usize], &[usize]),
    ratio: f32,
) -> bool {
    let median = |steps: &[usize]| median_of(steps.iter().map(|&j| work[at(j)]));
    guide.is_some_and(|g| median(island) > ratio * median(run) && alike(g, at, island, run))
}

/// The median of `ranges` (at least one; the upper one of an even count), by
/// [`median_in_place`] on them widened to f64 (exact).
fn median_of(ranges: impl Iterator<Item = f32>) -> f32 {
    let mut wide: Vec<f64> = ranges.map(f64::from).collect();
    median_in_place(&mut wide) as f32
}

/// Whether the image shows the surface beyond an island (the known pixels at steps
/// `samples`) at the island (its known pixels at steps `island`). Without an image, never.
fn shows_the_surface(
    guide: Option<&ColourGuide>,
    at: &dyn Fn(usize) -> usize,
    island: &[usize],
    samples: &[(usize, f32)],
) -> bool {
    let beyond: Vec<usize> = samples.iter().map(|&(j, _)| j).collect();
    guide.is_some_and(|g| alike(g, at, island, &beyond))
}

/// Whether the image shows the pixels at steps `a` and `b` of a line as one material
/// ([`ColourGuide::alike`]).
fn alike(guide: &ColourGuide, at: &dyn Fn(usize) -> usize, a: &[usize], b: &[usize]) -> bool {
    let pixels = |steps: &[usize]| -> Vec<usize> { steps.iter().map(|&j| at(j)).collect() };
    guide.alike(&pixels(a), &pixels(b))
}

/// The range at step `k` of a line whose first known pixels are `samples` (step, range;
/// at least one), as the module docs say; `never_farther`: nowhere farther than the
/// samples' first half (the bottom band).
fn continuation(samples: &[(usize, f32)], never_farther: bool) -> Box<dyn Fn(usize) -> f32> {
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
    let mut slope = if d1.max(d2) <= MAX_RATIO * d1.min(d2) && k2 > k1 {
        (d2 - d1) / (k2 - k1)
    } else {
        0.0
    };
    if !shows_its_slope(samples, (k1, d1), slope, d2 - d1) {
        slope = 0.0;
    }
    if never_farther {
        slope = slope.min(0.0); // toward the border (k falling) the disparity does not fall
    }
    Box::new(move |k| {
        let d = (d1 + slope * (k as f32 - k1)).clamp(d1 / MAX_RATIO, d1 * MAX_RATIO);
        1.0 / d
    })
}

/// Whether a line's `samples` (step, range) show the `slope` (per step, in disparity)
/// fitted through `(k1, d1)`, whose halves' medians differ by `rise`: at least
/// [`SLOPE_SAMPLES`] of them, lying on it within [`SLOPE_SCATTER`], and the rise beyond
/// [`SLOPE_SIGNIFICANCE`] times their scatter. A matcher's noise on the few pixels by a
/// band, extrapolated over the band, gave each row a slope of its own: stripes across
/// Cityscapes' left band (rows of 9.4 to 13.2 m over a road 10 to 11 m away).
fn shows_its_slope(samples: &[(usize, f32)], (k1, d1): (f32, f32), slope: f32, rise: f32) -> bool {
    if samples.len() < SLOPE_SAMPLES {
        return false;
    }
    let mut residuals: Vec<f64> = samples
        .iter()
        .map(|&(k, r)| f64::from((1.0 / r - d1 - slope * (k as f32 - k1)).abs()))
        .collect();
    let scatter = (MAD_TO_SIGMA * median_in_place(&mut residuals)) as f32;
    scatter <= SLOPE_SCATTER * d1 && rise.abs() > SLOPE_SIGNIFICANCE * scatter
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
        let done = fill_borders(
            &mut work,
            &mut sky,
            &mut filled,
            (w, h),
            0.2,
            (0.0, 1e9),
            None,
        );
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

    /// A road by a stereo pair's left band, measured with a matcher's noise (3 % in
    /// disparity): each row's few first pixels (6, then a gap: the road striped with the
    /// matcher's gaps) or its noisy run of 32 show no slope, and the band takes their
    /// median, within the noise of the row's true range; followed, their slopes made
    /// each row a stripe of its own, up to 1.5 times off.
    #[test]
    fn a_band_by_noisy_pixels_takes_their_median_not_their_slope() {
        let (w, h, band) = (200, 40, 90);
        let truth = |y: usize| 1.0 / (0.1 + 0.002 * y as f32);
        for striped in [true, false] {
            let mut rng = crate::rng::SplitMix64::new(7);
            let mut range = vec![f32::NAN; w * h];
            for y in 0..h {
                for x in band..w {
                    if striped && (band + 6..band + 9).contains(&x) {
                        continue;
                    }
                    let noise = 1.0 + 0.03 * (2.0 * rng.unit() as f32 - 1.0);
                    range[y * w + x] = truth(y) / noise;
                }
            }
            let (work, done) = fill_line(&range, (w, h));
            assert_eq!(done.filled, band * h, "{done:?}");
            for y in 0..h {
                for x in 0..band {
                    let e = work[y * w + x] / truth(y) - 1.0;
                    assert!(e.abs() < 0.035, "striped {striped}, ({x}, {y}): {e}");
                }
            }
        }
    }

    /// One row: `cells` from the left border ('.' unknown, a digit d: range 10·d m, 'F' a
    /// speck 500 m away, 'p' a pole 3 m away), then a facade 10 m away to the end of the row.
    fn row(cells: &str, width: usize) -> Vec<f32> {
        let mut line: Vec<f32> = cells
            .chars()
            .map(|c| match c {
                '.' => f32::NAN,
                'F' => 500.0,
                'p' => 3.0,
                d => 10.0 * d.to_digit(10).expect("a digit") as f32,
            })
            .collect();
        line.resize(width, 10.0);
        line
    }

    /// `line` filled as one image line (a row: its left band; a column: top then bottom)
    /// or as an image of that size, no sky, bands up to half the line.
    fn fill_line(line: &[f32], size: (usize, usize)) -> (Vec<f32>, BorderFill) {
        fill_line_seen(line, size, None)
    }

    /// [`fill_line`] with the line's `image`, when given.
    fn fill_line_seen(
        line: &[f32],
        (w, h): (usize, usize),
        image: Option<&crate::raster::RgbImage>,
    ) -> (Vec<f32>, BorderFill) {
        let guide = image.map(|i| ColourGuide::new(i, 0.08));
        let mut work = line.to_vec();
        let mut sky = vec![false; line.len()];
        let mut filled = vec![false; line.len()];
        let done = fill_borders(
            &mut work,
            &mut sky,
            &mut filled,
            (w, h),
            0.5,
            (1.0, 1e4),
            guide.as_ref(),
        );
        (work, done)
    }

    /// A speck longer than its distance to the border is taken for a piece of a surface
    /// reaching the border, unless the image shows the surface beyond it there: of the
    /// facade's chromaticity, a quarter brighter (its shading), it is a speck on the facade
    /// (Cityscapes' Düsseldorf glass facade) and dropped, also where it is near enough to
    /// the facade to be joined to it; of another colour (far ground), three times as
    /// bright, or without the image it is kept; touching the border (no band before it),
    /// kept.
    #[test]
    fn a_speck_the_image_shows_on_the_surface_beyond_is_dropped() {
        let facade = [0.10f32, 0.15, 0.10];
        let seen =
            |cells: &str, speck: [f32; 3]| {
                let line = row(cells, 160);
                let image = crate::raster::Grid::from_fn(160, 1, |x, _| {
                    if line[x] == 500.0 {
                        speck
                    } else {
                        facade
                    }
                });
                fill_line_seen(&line, (160, 1), Some(&image))
            };
        let near_border = format!("....{}{}", "F".repeat(10), ".".repeat(20));
        let shaded = facade.map(|c| 1.25 * c);
        let (work, done) = seen(&near_border, shaded);
        assert_eq!(done.islands, 10, "{done:?}");
        assert!(work.iter().all(|&r| (r - 10.0).abs() < 1e-4), "{work:?}");
        let ground = [0.12, 0.10, 0.05];
        assert_eq!(seen(&near_border, ground).1.islands, 0);
        let lit = facade.map(|c| 3.0 * c); // its chromaticity, but no shading of it
        assert_eq!(seen(&near_border, lit).1.islands, 0);
        assert_eq!(fill_line(&row(&near_border, 160), (160, 1)).1.islands, 0);
        let at_border = format!("{}{}", "F".repeat(10), ".".repeat(20));
        assert_eq!(seen(&at_border, shaded).1.islands, 0);
        // 8 px from the facade, a gap the island would be joined across (and the facade
        // then taken for its surface): specks on the facade are not joined to it.
        let by_facade = format!("......{}........", "F".repeat(10));
        let (work, done) = seen(&by_facade, shaded);
        assert_eq!(done.islands, 10, "{done:?}");
        assert!(work.iter().all(|&r| (r - 10.0).abs() < 1e-4), "{work:?}");
        assert_eq!(seen(&by_facade, ground).1.islands, 0);
        // Nearer specks after them are no surface for them to lie on (not wide): joined,
        // all are dropped (a Hamburg frame's road; taken for one, they ended the band).
        let specks = format!("{}{}", "4".repeat(20), ".".repeat(30));
        let by_specks = format!("......{}........{specks}", "F".repeat(10));
        let (work, done) = seen(&by_specks, shaded);
        assert_eq!(done.islands, 30, "{done:?}");
        assert!(work.iter().all(|&r| (r - 10.0).abs() < 1e-4), "{work:?}");
    }

    /// Cityscapes' left band: specks of far disparity among the unknown columns, which the
    /// band used to continue (a white blotch by a road 6 m away), are dropped; the band
    /// continues the facade beyond them.
    #[test]
    fn far_specks_in_a_band_are_dropped_and_the_band_continues_its_surface() {
        let line = row("........FF.....F....FFF....................", 100);
        let (work, done) = fill_line(&line, (100, 1));
        assert_eq!(done.islands, 6, "{done:?}");
        assert!(work.iter().all(|&r| (r - 10.0).abs() < 1e-4), "{work:?}");
        // Groups of specks far apart: what lies beyond the first is judged where the
        // facade shows, past the second.
        let apart = format!("........FF{}FF{}", ".".repeat(20), ".".repeat(20));
        let (work, done) = fill_line(&row(&apart, 120), (120, 1));
        assert_eq!(done.islands, 4, "{done:?}");
        assert!(work.iter().all(|&r| (r - 10.0).abs() < 1e-4), "{work:?}");
        // A road striped with the matcher's gaps (half of it known, gaps of 4 px) is a
        // surface all the same (Düsseldorf's road by the left band).
        let striped = format!(
            "............FFFFFF{}{}",
            ".".repeat(20),
            "1111....".repeat(12)
        );
        let (work, done) = fill_line(&row(&striped, 140), (140, 1));
        assert_eq!(done.islands, 6, "{done:?}");
        assert!(
            work[..12].iter().all(|&r| (r - 10.0).abs() < 1e-4),
            "{work:?}"
        );
    }

    /// What is not a speck stays as it was, and ends the band: a strip less than
    /// [`ISLAND_RATIO`] times as far as what is beyond it (a far facade before a car), a
    /// piece at or near the border, a pole nearer than the facade, far ground beside a
    /// post (brume's synthetic SGBM view 2), a speck hard against a post.
    #[test]
    fn surfaces_in_a_band_are_kept() {
        let dots = |n: usize| ".".repeat(n);
        // Far ground beside a post: what the band meets is no wide surface.
        let beside_post = format!("{}FF{}{}{}", dots(12), dots(20), "p".repeat(20), dots(30));
        // A speck hard against a post is one island with it, the post's.
        let with_post = format!("........FF......pppppppp{}", dots(10));
        // Each 20 px from the facade (a gap under 16 px would join it to the facade).
        let strip = format!("......22222{}", dots(20));
        let at_border = format!("FF{}", dots(20));
        let near_border = format!(".FFFF{}", dots(20));
        let pole = format!("......pp{}", dots(20));
        for cells in [
            &strip,
            &at_border,
            &near_border,
            &pole,
            &beside_post,
            &with_post,
        ] {
            let line = row(cells, 100);
            let (work, done) = fill_line(&line, (100, 1));
            assert_eq!(done.islands, 0, "{cells}: {done:?}");
            for (k, (a, b)) in line.iter().zip(&work).enumerate() {
                assert!(
                    a.is_nan() || a.to_bits() == b.to_bits(),
                    "{cells}: step {k}"
                );
            }
        }
        // A sparse map (a lidar's: one known pixel in 8) has too little beyond a speck to
        // judge it.
        let mut sparse: Vec<f32> = (0..80)
            .map(|k| if k % 8 == 0 { 10.0 } else { f32::NAN })
            .collect();
        sparse[0] = f32::NAN;
        sparse[4] = 500.0;
        let (_, done) = fill_line(&sparse, (80, 1));
        assert_eq!(done.islands, 0, "{done:?}");
    }

    /// A hood at the bottom reflecting the street: rows of 1.3 times the road's range among
    /// its unknown rows are dropped (along the bottom the ground comes nearer), and the
    /// band below the road continues it, never farther.
    #[test]
    fn a_hoods_reflection_in_the_bottom_band_is_dropped() {
        let h = 80;
        // Top to bottom: 50 rows of road receding upward, then the hood: unknown rows with
        // 3 rows of reflection 1.3 times as far as the road's last row, 18 rows below it.
        let road = |y: usize| 1.0 / (0.05 + 0.0005 * y as f32);
        let mut column: Vec<f32> = (0..h)
            .map(|y| if y < 50 { road(y) } else { f32::NAN })
            .collect();
        column[68..71].fill(1.3 * road(49));
        let (work, done) = fill_line(&column, (1, h));
        assert_eq!(done.islands, 3, "{done:?}");
        for (y, &r) in work.iter().enumerate().skip(50) {
            assert!(r <= road(49) * 1.0001, "row {y}: {r} vs {}", road(49));
            assert!(
                (r - road(y)).abs() / road(y) < 1e-3,
                "row {y}: the road's plane"
            );
        }
        // The same reflection in a side band is a surface of its own (under 3 times).
        let line: Vec<f32> = column.iter().rev().copied().collect();
        let (_, done) = fill_line(&line, (h, 1));
        assert_eq!(done.islands, 0, "{done:?}");
    }

    /// Toward the bottom border a slope that recedes (a hood reflecting the street, whose
    /// disparity falls toward the border) is not followed: the first half's median holds.
    #[test]
    fn the_bottom_band_never_continues_farther() {
        // Steps 8..24 from the border, disparity rising away from it.
        let s: Vec<(usize, f32)> = (8..24)
            .map(|k| (k, 1.0 / (0.05 + 0.001 * k as f32)))
            .collect();
        let free = continuation(&s, false);
        let held = continuation(&s, true);
        assert!(free(0) > s[0].1, "{} {}", free(0), s[0].1);
        let first_half = 1.0 / (0.05 + 0.001 * 11.5);
        assert!(
            (held(0) - first_half).abs() < 1e-3,
            "{} {first_half}",
            held(0)
        );
        // A slope toward nearer is followed alike.
        let rising: Vec<(usize, f32)> = s.iter().map(|&(k, r)| (32 - k, r)).rev().collect();
        assert_eq!(
            continuation(&rising, true)(0),
            continuation(&rising, false)(0)
        );
    }

    /// Each of the three conditions on following a slope, alone: a clean slope of 16
    /// samples is followed; of 6, not (too few); with a 2 % scatter about it, not; a slope
    /// of 0.24 % between the halves within a 0.3 % scatter, not (no more than its noise),
    /// of 2 %, followed.
    #[test]
    fn a_slope_is_followed_only_where_the_samples_show_it() {
        // Steps 10.., disparity 0.1 (1 + slope (k - 10)), times 1 ± noise alternately.
        let line = |n: usize, slope: f32, noise: f32| -> Vec<(usize, f32)> {
            (10..10 + n)
                .map(|k| {
                    let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                    let d = 0.1 * (1.0 + slope * (k - 10) as f32) * (1.0 + sign * noise);
                    (k, 1.0 / d)
                })
                .collect()
        };
        let followed = |s: &[(usize, f32)]| {
            let f = continuation(s, false);
            f(0) != f(100)
        };
        assert!(followed(&line(16, 0.02, 0.0)));
        assert!(!followed(&line(6, 0.02, 0.0)));
        assert!(!followed(&line(16, 0.02, 0.02)));
        assert!(!followed(&line(16, 0.0003, 0.003)));
        assert!(followed(&line(16, 0.0025, 0.003)));
    }

    #[test]
    fn a_depth_edge_in_the_samples_gives_a_constant() {
        let mut s: Vec<(usize, f32)> = (5..13).map(|k| (k, 10.0)).collect();
        s.extend((13..21).map(|k| (k, 40.0)));
        let f = continuation(&s, false);
        assert_eq!(f(0), 10.0);
        assert_eq!(continuation(&[(3, 7.0)], false)(0), 7.0);
        assert_eq!(continuation(&[(3, 0.0), (4, 1.0)], false)(0), 0.0);
    }
}
