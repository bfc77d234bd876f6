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
//!   first unknown or sky pixel), extrapolated linearly *in disparity* `1/R`, where a plane
//!   is affine along any line (a facade along a row, the road along a column: both exact).
//!   The slope is the difference of the medians of the two halves of those pixels over that
//!   of their median positions (the mean of the middle two for an even count); when the
//!   halves differ by more than a factor 1.5 (a depth edge among them) the run takes the
//!   median of the first half, as it does where the samples do not show their slope (fewer
//!   than [`SLOPE_SAMPLES`], scattered about it by more than [`SLOPE_SCATTER`] of the
//!   disparity, or the halves no more than [`SLOPE_SIGNIFICANCE`] scatters apart: a
//!   matcher's noise, which extrapolated made each row of Cityscapes' left band a stripe of
//!   its own). A line then follows the median of the slopes so shown (0 where not) by the
//!   lines within [`POOLED_LINES`] of it that continue its surface ([`SURFACE_RATIO`]): the
//!   slope of a plane, the same on each line, and not one line's alone. Its level is pooled
//!   too: the line passes, at its innermost unknown step, through the median of what the
//!   fits of those lines give there, taken in pairs at equal distances either side, so that
//!   a plane changing from line to line keeps its value ([`pooled_range`]). The extrapolated
//!   disparity is kept within a factor 1.5 of it, so a slope cannot create a spike, and the
//!   range within the smallest and largest known range outside the sky; with non-positive
//!   range the run takes the anchor's value. Toward the bottom border the disparity does
//!   not fall (the slope is taken only where it rises): the ground comes nearer there, and
//!   a car's hood reflecting the street, whose disparity falls toward the border, was
//!   continued farther and farther, a light streak in each such column.
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
//!   never judged), which must begin a wide surface ([`WIDE_RUN`]: a road, a facade, not a
//!   post) where it first shows ([`SOLID_START`]). Along the bottom, where the ground comes
//!   nearer toward the border, the factor is [`BOTTOM_ISLAND_RATIO`] and what lies beyond
//!   is its continuation (as above) at the island. The first island that is not dropped, or
//!   a longer run, ends the search, and the run ends at it as before.
//! - *Lone specks* then, on the side bands: a row whose anchor is a far speck under
//!   [`ISLAND_RATIO`] times what lies beyond it, which the rows beside it do not show, is
//!   re-anchored where its pixels agree with theirs ([`drop_lone_specks`]).
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
/// disparity (brume's synthetic street frame, measured with 0.5 % noise, shows its
/// facades' slopes: its left band's error 0.19 m, 0.23 m with every line's own slope
/// followed, 1.48 m with none; the lines by the bands of Cityscapes' SGM disparity
/// scatter 0.2 to 4 %, 10th to 90th percentile, and 15 to 37 % of those with enough
/// samples show theirs)...
const SLOPE_SCATTER: f32 = 0.005;

/// ... and where the halves' medians differ by more than this many times that scatter.
const SLOPE_SIGNIFICANCE: f32 = 3.0;

/// A band line follows the median of the slopes of the lines this far either side of it
/// (itself among them) that continue its surface.
const POOLED_LINES: usize = 8;

/// Two band lines continue one surface when their first disparities are within this
/// factor of each other.
const SURFACE_RATIO: f32 = 1.25;

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

/// Where the surface beyond an island first shows: the first of its pixels (agreeing with
/// its median) that begins this many known pixels in a row, or, where none does (a road
/// striped with the matcher's gaps), the first. Two pixels of a van's range on its window,
/// 28 px before the van, were taken for where it began, and with the gap after them it
/// was no wide surface: a speck of 300 m before them was kept and three rows of the band
/// continued it (Cityscapes' Hamburg frame, rows 314-316: a white line over the van).
const SOLID_START: usize = 8;

/// A band line's anchor is judged against the anchors of at least this many lines near it
/// ([`drop_lone_specks`]).
const LONE_NEIGHBOURS: usize = 4;

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
        // Each line's run and fit first; filled once its neighbours' fits are known.
        let mut fits: Vec<Option<(usize, LineFit)>> = vec![None; lines];
        for (l, fit) in fits.iter_mut().enumerate() {
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
            *fit = Some((
                run,
                fit_from(work, sky, &line, (run, len), bottom, &mut samples),
            ));
        }
        if matches!(side, Side::Left | Side::Right) {
            let lim = (len, limit);
            out.islands += drop_lone_specks(work, sky, &mut fits, &at, lim, &mut samples);
        }
        let sloped: Vec<Option<(usize, LineFit)>> = (fits.iter().enumerate())
            .map(|(l, f)| f.map(|(run, fit)| (run, fit.with_slope(pooled_slope(&fits, l, fit)))))
            .collect();
        let mut values = Vec::new();
        for (l, (run, fit)) in (sloped.iter().enumerate()).filter_map(|(l, f)| f.map(|f| (l, f))) {
            let fit = fit.through(
                run - 1,
                pooled_range(&sloped, (l, fit), run - 1, &mut values),
            );
            for k in 0..run {
                work[at(l, k)] = fit.range_at(k).clamp(known.0, known.1);
                filled[at(l, k)] = true;
            }
            out.filled += run;
        }
    }
    out
}

/// The fit of a band line (`at`: its step → index) whose unknown run from the border is
/// `run` steps: to the known pixels from its anchor on, up to `2 x max(4, min(run, 16))`
/// of them, to the first unknown or sky pixel.
fn fit_from(
    work: &[f32],
    sky: &[bool],
    at: &dyn Fn(usize) -> usize,
    (run, len): (usize, usize),
    bottom: bool,
    samples: &mut Vec<(usize, f32)>,
) -> LineFit {
    let want = run.clamp(4, 16) * 2;
    samples.clear();
    for k in run..(run + want).min(len) {
        let v = work[at(k)];
        if !v.is_finite() || sky[at(k)] {
            break;
        }
        samples.push((k, v));
    }
    LineFit::of(samples, bottom)
}

/// Re-anchors the band lines whose anchor is a lone far speck, dropping it; returns the
/// pixels dropped. A line's anchor is one when it is more than [`MAX_RATIO`] times as far
/// as the median anchor of the lines within [`POOLED_LINES`] of it (at least
/// [`LONE_NEIGHBOURS`] of them): a speck has no counterpart on the lines beside it, a
/// surface has. The line then begins where its own known pixels first agree with that
/// median within [`SURFACE_RATIO`], if fewer than [`SOLID_START`] known pixels lie before
/// that within the band (specks, not a surface). A nearer anchor is left alone: a pole or
/// a car's edge may cross the band on a few lines. The islands rule misses such specks
/// when they are under [`ISLAND_RATIO`] times the surface beyond them: on Cityscapes'
/// Aachen frame a speck of 36 m, one or two pixels, before the road at 19 m, continued
/// across the left band on one row (a light line); on Hamburg's, 25-33 m on two rows
/// before a van at 16 m.
fn drop_lone_specks(
    work: &mut [f32],
    sky: &[bool],
    fits: &mut [Option<(usize, LineFit)>],
    at: &dyn Fn(usize, usize) -> usize,
    (len, limit): (usize, usize),
    samples: &mut Vec<(usize, f32)>,
) -> usize {
    let known = |work: &[f32], l: usize, k: usize| work[at(l, k)].is_finite() && !sky[at(l, k)];
    let anchors: Vec<Option<f32>> = (fits.iter().enumerate())
        .map(|(l, f)| f.map(|(run, _)| work[at(l, run)]))
        .collect();
    let mut dropped = 0;
    for l in 0..fits.len() {
        let (Some((run, _)), Some(anchor)) = (fits[l], anchors[l]) else {
            continue;
        };
        let mut others: Vec<f64> = (pooled_lines(l, fits.len()).filter(|&n| n != l))
            .filter_map(|n| anchors[n].map(f64::from))
            .collect();
        if others.len() < LONE_NEIGHBOURS {
            continue;
        }
        let median = median_in_place(&mut others) as f32;
        if anchor <= MAX_RATIO * median {
            continue;
        }
        let agrees = |r: f32| within_factor(r, median, SURFACE_RATIO);
        let Some(start) = (run..=limit).find(|&k| known(work, l, k) && agrees(work[at(l, k)]))
        else {
            continue;
        };
        let specks: Vec<usize> = (run..start).filter(|&k| known(work, l, k)).collect();
        if specks.len() >= SOLID_START {
            continue;
        }
        specks.iter().for_each(|&k| work[at(l, k)] = f32::NAN);
        dropped += specks.len();
        let line = |k: usize| at(l, k);
        fits[l] = Some((
            start,
            fit_from(work, sky, &line, (start, len), false, samples),
        ));
    }
    dropped
}

/// The band lines within [`POOLED_LINES`] of line `l` (itself among them), of `lines`.
fn pooled_lines(l: usize, lines: usize) -> std::ops::Range<usize> {
    l.saturating_sub(POOLED_LINES)..(l + POOLED_LINES + 1).min(lines)
}

/// Whether the positive values `a` and `b` are within `factor` of each other, either way.
fn within_factor(a: f32, b: f32, factor: f32) -> bool {
    a <= factor * b && b <= factor * a
}

/// The median slope of the band lines within [`POOLED_LINES`] of line `l` that continue
/// its surface (their first disparity within [`SURFACE_RATIO`] of its own `fit`'s), each
/// as its own samples showed it (0 where they did not): a plane's disparity changes along
/// a line by the same amount on every line, and a line whose few pixels show a slope that
/// its neighbours' do not is the matcher's (two rows of Cityscapes' Düsseldorf road, 9.7
/// to 8.7 m across the band, between rows at 7.8 to 8.0 m).
fn pooled_slope(fits: &[Option<(usize, LineFit)>], l: usize, fit: LineFit) -> f32 {
    let LineFit::Disparity { d1, .. } = fit else {
        return 0.0;
    };
    let mut slopes: Vec<f64> = fits[pooled_lines(l, fits.len())]
        .iter()
        .filter_map(|f| match *f {
            Some((_, LineFit::Disparity { d1: d, slope, .. }))
                if within_factor(d, d1, SURFACE_RATIO) =>
            {
                Some(f64::from(slope))
            }
            _ => None,
        })
        .collect();
    median_in_place(&mut slopes) as f32
}

/// The range at step `k` of band line `l` (of `fit`): the median of what the fits of the
/// lines within [`POOLED_LINES`] of it that continue its surface (as for [`pooled_slope`])
/// give there, taken in pairs at equal distances either side (both or neither), so that
/// a plane whose range changes from line to line (the road by a left band) keeps its
/// value.
///
/// Each line's fit starts from its own first pixels, and a matcher's noise on them made
/// every column of Cityscapes' bottom band a streak of its own (Düsseldorf's road: 5.3 to
/// 7.4 m side by side on one row); a plane gives the same value from any of its lines.
fn pooled_range(
    fits: &[Option<(usize, LineFit)>],
    (l, fit): (usize, LineFit),
    k: usize,
    values: &mut Vec<f64>,
) -> f32 {
    let first = fit.first_disparity();
    let on_surface = |n: usize| {
        fits[n]
            .map(|(_, f)| f)
            .filter(|f| within_factor(f.first_disparity(), first, SURFACE_RATIO))
    };
    values.clear();
    values.push(f64::from(fit.range_at(k)));
    for j in 1..=POOLED_LINES.min(l).min(fits.len() - 1 - l) {
        if let (Some(a), Some(b)) = (on_surface(l - j), on_surface(l + j)) {
            values.extend([f64::from(a.range_at(k)), f64::from(b.range_at(k))]);
        }
    }
    median_in_place(values) as f32
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
        // specks, and past pieces of its range too small to begin it: see SOLID_START).
        let surface = if bottom {
            LineFit::of(samples, true).range_at((k + end) / 2)
        } else {
            let median = median_of(samples.iter().map(|&(_, r)| r));
            let agrees = |r: f32| within_factor(r, median, MAX_RATIO);
            let agreeing = || samples.iter().filter(|&&(_, r)| agrees(r)).map(|s| s.0);
            let solid = |j: usize| (j..j + SOLID_START).all(|i| i < len && known(work, i));
            let start = agreeing()
                .find(|&j| solid(j))
                .or_else(|| agreeing().next())
                .unwrap_or(end);
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

/// How a band line continues the surface of its first known pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
enum LineFit {
    /// One range all along the band.
    Constant(f32),
    /// The disparity `d1` at step `k1`, changing by `slope` per step, kept within a factor
    /// [`MAX_RATIO`] of `d1`.
    Disparity { k1: f32, d1: f32, slope: f32 },
}

impl LineFit {
    /// The fit of a line whose first known pixels are `samples` (step, range; at least
    /// one), as the module docs say; `never_farther`: nowhere farther than the samples'
    /// first half (the bottom band).
    fn of(samples: &[(usize, f32)], never_farther: bool) -> LineFit {
        if samples.iter().any(|&(_, r)| r <= 0.0) || samples.len() < 2 {
            return LineFit::Constant(samples[0].1);
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
        let mut slope = if within_factor(d1, d2, MAX_RATIO) && k2 > k1 {
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
        LineFit::Disparity { k1, d1, slope }
    }

    /// The same fit with another slope (a constant stays one).
    fn with_slope(self, slope: f32) -> LineFit {
        match self {
            LineFit::Disparity { k1, d1, .. } => LineFit::Disparity { k1, d1, slope },
            constant => constant,
        }
    }

    /// The same fit (its slope) through range `r` at step `k`.
    fn through(self, k: usize, r: f32) -> LineFit {
        match self {
            LineFit::Constant(_) => LineFit::Constant(r),
            LineFit::Disparity { slope, .. } => LineFit::Disparity {
                k1: k as f32,
                d1: 1.0 / r,
                slope,
            },
        }
    }

    /// The disparity where the fit starts, by which lines are judged to continue one
    /// surface.
    fn first_disparity(&self) -> f32 {
        match *self {
            LineFit::Constant(r) => 1.0 / r,
            LineFit::Disparity { d1, .. } => d1,
        }
    }

    /// The range at step `k`.
    fn range_at(&self, k: usize) -> f32 {
        match *self {
            LineFit::Constant(r) => r,
            LineFit::Disparity { k1, d1, slope } => {
                1.0 / (d1 + slope * (k as f32 - k1)).clamp(d1 / MAX_RATIO, d1 * MAX_RATIO)
            }
        }
    }
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
#[path = "border_tests.rs"]
mod tests;
