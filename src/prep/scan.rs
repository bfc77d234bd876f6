//! Scan lines: a LiDAR's points projected into the camera (KITTI's depth maps) know a
//! pixel on each line the scanner swept and none between, a few rows apart; none above
//! its top beam; and, the scanner above and behind the camera and the projection without
//! an occlusion test, the background it saw past a nearer object's edge on the object.
//!
//! Left as they are, the unknown rows between the lines join into one component over the
//! whole frame: the depth rules find no sky in it (it reaches the bottom), the scene above
//! the top beam is never the scene beyond the sensor's reach, and the holes between lines
//! are long strips that one surface fills along the row (a streak of a box's range over
//! the ground beside it). So the lines are found first ([`find_lines`]): gaps, unknown
//! runs down a column between two pixels on lines no more than [`max_gap`] rows apart, and
//! the top line. A real scanner's line is a row of dots 2 to 4 px apart, most columns
//! missing it, so a pixel within [`dot_reach`] of a known one along its row lies on the
//! line ([`on_lines`]), and a line's dots are joined along the row ([`join_dots`]) before
//! the gaps down the columns are filled. The depth rules read every unknown pixel below
//! the top line as known ([`ScanLines::closed`]); the scene beyond the reach is only what
//! lies over it, and over the columns whose line reaches the scanner's top beam not even
//! that ([`ScanLines::keep_beyond_reach_over_line`]). Once the outliers are gone, the
//! points unlike the points of their colour round them go
//! ([`drop_points_unlike_their_colour`]), and each gap is filled from its two ends
//! ([`fill_gaps`]): linearly in 1/R (a plane of the scene is affine in inverse depth)
//! where they are of one surface or the image shows no edge between them, else each end
//! up to the image's colour edge; without the image, a gap between two surfaces is left
//! to the hole fill.

use super::colour_guide::ColourGuide;

/// Gaps are at most this fraction of the height ([`MIN_MAX_GAP`] rows at least): KITTI's
/// lines are about 5 to 7 rows apart at 375 rows (0.4° to 0.5° between beams, a focal
/// length of 721 px), 12 at the most here.
const MAX_GAP_FRACTION: f64 = 1.0 / 32.0;
/// See [`MAX_GAP_FRACTION`].
const MIN_MAX_GAP: usize = 4;
/// A map is scanned when at least this share of the unknown pixels below each column's
/// first known pixel lie in gaps (a stereo matcher's holes are blobs and bands: a few
/// percent of theirs do) ...
const SCANNED_SHARE: f64 = 0.5;
/// ... and they are most of the pixels there (a left-right check leaves a stereo map
/// known in four pixels of five, its failures scattered in short runs).
const SCANNED_UNKNOWN_SHARE: f64 = 0.5;
/// A gap whose ends are within this ratio of each other is on one surface.
const SAME_SURFACE_RATIO: f32 = 1.5;

/// The longest gap in a map of `height` rows.
fn max_gap(height: usize) -> usize {
    ((height as f64 * MAX_GAP_FRACTION).round() as usize).max(MIN_MAX_GAP)
}

/// A scanned map's gaps and top line.
pub(crate) struct ScanLines {
    /// The unknown pixels between two lines down a column.
    pub(crate) gaps: Vec<bool>,
    /// Each column's topmost known row, `h` in a column no line crosses.
    own_top: Vec<usize>,
    /// Each column's top line: the topmost known row of the columns within [`max_gap`] of
    /// it (a column between two returns of a line, or left of the scanner's view, takes
    /// the line of the nearest column a line crosses).
    top_line: Vec<usize>,
}

impl ScanLines {
    /// `work` as the depth rules read it: every unknown pixel below its column's topmost
    /// known one known (the gaps, a run without returns, the rows below the last line),
    /// and in a column no line crosses every one below the top line, so that the scene
    /// over the lines is one region, not joined to the bottom through the lines.
    pub(crate) fn closed(&self, work: &[f32]) -> Vec<f32> {
        let w = self.top_line.len();
        let h = work.len() / w;
        let line = |x: usize| match self.own_top[x] {
            y if y < h => y,
            _ => self.top_line[x],
        };
        let below = |p: usize| p / w >= line(p % w);
        (0..work.len())
            .map(|p| {
                if below(p) && work[p].is_nan() {
                    1.0
                } else {
                    work[p]
                }
            })
            .collect()
    }

    /// Keeps of the scene beyond the sensor's reach (`beyond`, see `reach.rs`) the pixels
    /// over the top line: what no beam reached there is the far skyline; below the line it
    /// is a face between returns, a hole.
    ///
    /// When the image or a mask has found the sky (`sky_seen`), so that what is left over
    /// the line is the scene, and the top beam's row is known ([`top_beam`]), a column
    /// whose line reaches the beam met a surface there, which goes on up (a street's trees
    /// and houses): over it lies no scene beyond the reach but a hole, filled from below.
    /// The scene beyond the reach is kept over columns whose line lies under the beam,
    /// where the upper beams met nothing, by the majority of the columns round each
    /// ([`BEAM_COLUMNS_FRACTION`]), so that a gap in a tree's crown leaves no strip.
    pub(crate) fn keep_beyond_reach_over_line(&self, beyond: &mut Vec<usize>, sky_seen: bool) {
        let w = self.top_line.len();
        let h = self.gaps.len() / w;
        let beam = sky_seen.then(|| top_beam(&self.own_top, h)).flatten();
        let under_beam = match beam {
            Some(beam) => {
                let margin = max_gap(h) as f64;
                let met_nothing: Vec<bool> = (0..w)
                    .map(|x| self.top_line[x] as f64 >= beam[x] + margin)
                    .collect();
                majority_round(&met_nothing, ((w as f64) * BEAM_COLUMNS_FRACTION) as usize)
            }
            None => vec![true; w],
        };
        beyond.retain(|&p| p / w < self.top_line[p % w] && under_beam[p % w]);
    }
}

/// A pixel lies on a line within one pixel in this many of the image's width of one of
/// its dots, along the row ([`MIN_DOT_REACH`] at least): KITTI's HDL-64E returns a point
/// every 0.08° to 0.35° of azimuth, 1 to 4 px at its focal length of 721 px in 1242
/// columns, its dots 2 to 4 px apart on the road and twice that where one is lost; within
/// 3 px of a dot, a line whose dots are up to 7 px apart leaves no column off it.
const DOT_REACH_WIDTH: f64 = 400.0;
/// See [`DOT_REACH_WIDTH`]: the least reach, in pixels.
const MIN_DOT_REACH: usize = 3;

/// How far from a line's dot along its row a pixel lies on the line.
fn dot_reach(width: usize) -> usize {
    ((width as f64 / DOT_REACH_WIDTH).round() as usize).max(MIN_DOT_REACH)
}

/// Which pixels of `work` lie on a scan line: known, or within [`dot_reach`] of a known
/// pixel along the row (a line of a scanner's dots, not every column crossed).
fn on_lines(work: &[f32], (w, h): (usize, usize)) -> Vec<bool> {
    let reach = dot_reach(w);
    let mut on = vec![false; w * h];
    for (row, on) in work.chunks_exact(w).zip(on.chunks_exact_mut(w)) {
        for x in (0..w).filter(|&x| row[x].is_finite()) {
            on[x.saturating_sub(reach)..(x + reach + 1).min(w)].fill(true);
        }
    }
    on
}

/// The gaps between scan lines of `work` (unknown pixels NaN) and its top line, or `None`
/// when the map is not scanned ([`SCANNED_SHARE`], [`SCANNED_UNKNOWN_SHARE`]).
pub(crate) fn find_lines(work: &[f32], (w, h): (usize, usize)) -> Option<ScanLines> {
    let on = on_lines(work, (w, h));
    // Counted first: most maps are not scanned, and need no mask of their gaps.
    let (in_gaps, below_first, known) = walk_gaps(&on, (w, h), |_, _| {});
    let sparse = below_first as f64 >= SCANNED_UNKNOWN_SHARE * (below_first + known) as f64;
    let scanned = sparse && in_gaps as f64 >= SCANNED_SHARE * below_first as f64;
    scanned.then(|| {
        let mut gaps = vec![false; w * h];
        walk_gaps(&on, (w, h), |x, rows| {
            rows.for_each(|y| gaps[y * w + x] = true)
        });
        let top: Vec<Option<usize>> = (0..w)
            .map(|x| (0..h).find(|&y| work[y * w + x].is_finite()))
            .collect();
        ScanLines {
            gaps,
            own_top: top.iter().map(|t| t.unwrap_or(h)).collect(),
            top_line: top_line(&top, h),
        }
    })
}

/// Calls `gap(x, rows)` for each gap between the pixels `on` a line down column `x`, and
/// returns how many pixels lie in gaps, how many off and how many on a line lie below each
/// column's first pixel on one.
fn walk_gaps(
    on: &[bool],
    (w, h): (usize, usize),
    mut gap: impl FnMut(usize, std::ops::Range<usize>),
) -> (usize, usize, usize) {
    let longest = max_gap(h);
    let (mut in_gaps, mut below_first, mut known) = (0usize, 0usize, 0usize);
    for x in 0..w {
        let mut last_known: Option<usize> = None;
        for y in 0..h {
            if !on[y * w + x] {
                below_first += usize::from(last_known.is_some());
                continue;
            }
            known += usize::from(last_known.is_some());
            if let Some(above) = last_known.filter(|&a| y - a > 1 && y - a - 1 <= longest) {
                gap(x, above + 1..y);
                in_gaps += y - above - 1;
            }
            last_known = Some(y);
        }
    }
    (in_gaps, below_first, known)
}

/// The top beam is fitted to the topmost known row of this many bins across the width.
const BEAM_BINS: usize = 24;
/// A bin agrees with the beam's fit within this many rows.
const BEAM_TOLERANCE_ROWS: f64 = 2.0;
/// The beam's row is known when at least this share of the bins agree with its fit, the
/// first and the last quarter of the width among them: along a street the top beam meets
/// trees, houses and vans across most of the width (a real KITTI frame: 18 and 16 bins of
/// 24, its two cameras), in an open scene a few near towers, and a fit through them and
/// the boxes' tops below the beam agrees with fewer (brume's scene, 11 in view 2).
const BEAM_AGREEING_SHARE: f64 = 0.6;
/// Whether the upper beams met nothing over a column is the majority's of the columns
/// within this fraction of the width of it.
const BEAM_COLUMNS_FRACTION: f64 = 1.0 / 32.0;

/// The row of the scanner's top beam in each column: a quadratic in the column (the
/// beam's cone seen by the camera, tilted as the scanner is mounted: on a real KITTI frame
/// row 145 at the left, 122 at the right) fitted to the topmost known row of each of
/// [`BEAM_BINS`] bins across the width. A bin whose columns met nothing in the top beam
/// lies lower, so the fit is made again on the bins on or over it until none drops out.
/// `None` where too few bins agree ([`BEAM_AGREEING_SHARE`]): no surface within the reach
/// rose into the top beam across enough of the image to tell its row.
fn top_beam(own_top: &[usize], h: usize) -> Option<Vec<f64>> {
    let w = own_top.len();
    let bins: Vec<(f64, f64)> = (0..BEAM_BINS)
        .filter_map(|b| {
            let columns = b * w / BEAM_BINS..(b + 1) * w / BEAM_BINS;
            let x = columns
                .filter(|&x| own_top[x] < h)
                .min_by_key(|&x| own_top[x])?;
            Some((x as f64, own_top[x] as f64))
        })
        .collect();
    let mut kept = bins.clone();
    let fit = loop {
        let fit = quadratic_fit(&kept)?;
        // Taken from the bins kept so far: the set only shrinks, and the loop ends.
        let on_or_over: Vec<(f64, f64)> = kept
            .iter()
            .copied()
            .filter(|&(x, y)| y <= fit(x) + BEAM_TOLERANCE_ROWS)
            .collect();
        if on_or_over.len() == kept.len() {
            break fit;
        }
        kept = on_or_over;
    };
    let agreeing: Vec<f64> = bins
        .iter()
        .filter(|&&(x, y)| (y - fit(x)).abs() <= BEAM_TOLERANCE_ROWS)
        .map(|&(x, _)| x)
        .collect();
    let quarter = w as f64 / 4.0;
    let spread = agreeing.first().is_some_and(|&x| x < quarter)
        && agreeing.last().is_some_and(|&x| x >= 3.0 * quarter);
    let enough = agreeing.len() as f64 >= BEAM_AGREEING_SHARE * BEAM_BINS as f64;
    (spread && enough).then(|| (0..w).map(|x| fit(x as f64)).collect())
}

/// The least-squares quadratic through `points` (x, y), as a function of x; `None` for
/// fewer than three points or points that do not fix one.
fn quadratic_fit(points: &[(f64, f64)]) -> Option<impl Fn(f64) -> f64> {
    if points.len() < 3 {
        return None;
    }
    // x centred and scaled to about [-1, 1], for the normal equations' conditioning.
    let n = points.len() as f64;
    let mid = points.iter().map(|p| p.0).sum::<f64>() / n;
    let half = points
        .iter()
        .map(|p| (p.0 - mid).abs())
        .fold(0.0, f64::max)
        .max(1.0);
    let t = move |x: f64| (x - mid) / half;
    let mut a = [[0.0f64; 4]; 3];
    for &(x, y) in points {
        let powers = [1.0, t(x), t(x) * t(x)];
        for (row, &pi) in a.iter_mut().zip(&powers) {
            for (cell, &pj) in row.iter_mut().zip(&powers) {
                *cell += pi * pj;
            }
            row[3] += pi * y;
        }
    }
    let c = solve3(a)?;
    Some(move |x: f64| c[0] + c[1] * t(x) + c[2] * t(x) * t(x))
}

/// The solution of three linear equations (each row: three coefficients and the right
/// side), by Gaussian elimination with partial pivoting; `None` when they are singular.
fn solve3(mut a: [[f64; 4]; 3]) -> Option<[f64; 3]> {
    for col in 0..3 {
        let pivot = (col..3).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs() < 1e-12 {
            return None;
        }
        a.swap(col, pivot);
        let pivot_row = a[col];
        for row in a.iter_mut().skip(col + 1) {
            let f = row[col] / pivot_row[col];
            for (cell, &p) in row.iter_mut().zip(&pivot_row).skip(col) {
                *cell -= f * p;
            }
        }
    }
    let mut c = [0.0; 3];
    for row in (0..3).rev() {
        let rest: f64 = (row + 1..3).map(|k| a[row][k] * c[k]).sum();
        c[row] = (a[row][3] - rest) / a[row][row];
    }
    Some(c)
}

/// Each entry of `flags` replaced by the majority of those within `reach` of it (itself
/// included; a tie keeps it).
fn majority_round(flags: &[bool], reach: usize) -> Vec<bool> {
    let n = flags.len();
    let mut count = vec![0usize; n + 1];
    for (i, &f) in flags.iter().enumerate() {
        count[i + 1] = count[i] + usize::from(f);
    }
    (0..n)
        .map(|i| {
            let (lo, hi) = (i.saturating_sub(reach), (i + reach + 1).min(n));
            let set = count[hi] - count[lo];
            match (2 * set).cmp(&(hi - lo)) {
                std::cmp::Ordering::Greater => true,
                std::cmp::Ordering::Less => false,
                std::cmp::Ordering::Equal => flags[i],
            }
        })
        .collect()
}

/// Each column's top line ([`ScanLines::top_line`]) from its topmost known row `top`; `h`
/// where no column has a known pixel.
fn top_line(top: &[Option<usize>], h: usize) -> Vec<usize> {
    let w = top.len();
    let crossed: Vec<usize> = (0..w).filter(|&x| top[x].is_some()).collect();
    let nearest_line = |x: usize| {
        let i = crossed.partition_point(|&c| c < x);
        let candidates = [i.checked_sub(1), (i < crossed.len()).then_some(i)];
        candidates
            .into_iter()
            .flatten()
            .map(|i| crossed[i])
            .min_by_key(|&c| c.abs_diff(x))
            .and_then(|c| top[c])
            .unwrap_or(h)
    };
    let reach = max_gap(h);
    (0..w)
        .map(|x| {
            let window = x.saturating_sub(reach)..(x + reach + 1).min(w);
            window
                .filter_map(|c| top[c])
                .min()
                .unwrap_or_else(|| nearest_line(x))
        })
        .collect()
}

/// A point is unlike its colour's points round it when its 1/R is off their median by
/// more than this factor ...
const UNLIKE_RATIO: f32 = 1.5;
/// ... and they are at least this many.
const MIN_ALIKE: usize = 4;

/// Makes unknown the known pixels of `work` outside `sky` whose range is off by more than
/// [`UNLIKE_RATIO`] from the median of the known pixels of their own colour within
/// [`max_gap`] of them along the row (a quarter of that up and down: the range of the
/// ground near the horizon changes fast down the rows): the background a scanner above
/// and behind the camera sees past a nearer object's edge, projected onto the object's
/// face (the projection has no occlusion test), and the object's points projected onto
/// the background beside it. The ground receding and a face seen at a slant change slowly
/// along a row among points of one colour. Returns how many it dropped.
pub(crate) fn drop_points_unlike_their_colour(
    work: &mut [f32],
    sky: &[bool],
    guide: &ColourGuide,
    (w, h): (usize, usize),
) -> usize {
    let (rx, ry) = (max_gap(h), max_gap(h) / 4);
    let known = |p: usize| work[p].is_finite() && work[p] > 0.0 && !sky[p];
    let unlike: Vec<usize> = crate::parallel::indices_in_order_with(w * h, Vec::new, |alike, p| {
        if !known(p) {
            return false;
        }
        let (x, y) = (p % w, p / w);
        alike.clear();
        for qy in y.saturating_sub(ry)..(y + ry + 1).min(h) {
            for qx in x.saturating_sub(rx)..(x + rx + 1).min(w) {
                let q = qy * w + qx;
                if q != p && known(q) && guide.own_colour(p, q) {
                    alike.push(1.0 / work[q]);
                }
            }
        }
        if alike.len() < MIN_ALIKE {
            return false;
        }
        let mid = alike.len() / 2;
        let median = *alike.select_nth_unstable_by(mid, f32::total_cmp).1;
        let own = 1.0 / work[p];
        own * UNLIKE_RATIO < median || own > UNLIKE_RATIO * median
    });
    unlike.iter().for_each(|&p| work[p] = f32::NAN);
    unlike.len()
}

/// Fills the `gaps` of `work` outside `sky` from the known pixels at their ends (see the
/// module docs), once each line's dots are joined along their rows ([`join_dots`]);
/// `guide` splits a gap between two surfaces at its colour edge. Returns how many pixels
/// it filled.
pub(crate) fn fill_gaps(
    work: &mut [f32],
    gaps: &[bool],
    sky: &[bool],
    guide: Option<&ColourGuide>,
    (w, h): (usize, usize),
) -> usize {
    let mut filled = join_dots(work, sky, guide, (w, h));
    for run in super::reach::runs_of(gaps, w, h) {
        // A gap lies between two known pixels: `top - 1` and `end`.
        let (x, top, end) = (run.x, run.top, run.end);
        let (above, below) = ((top - 1) * w + x, end * w + x);
        let column = (top..end).map(|r| r * w + x);
        if column.clone().any(|p| sky[p]) || !(measured(work[above]) && measured(work[below])) {
            continue;
        }
        filled += fill_one(work, (above, below), column, guide);
    }
    filled
}

/// Whether `v` is a measured range (neither unknown, nor the scene beyond the reach, nor
/// the sky).
fn measured(v: f32) -> bool {
    v.is_finite() && v > 0.0
}

/// Fills the unknown pixels between two known dots of a line along its row, no more than
/// twice [`dot_reach`] apart and with nothing but unknown pixels (no sky, nothing beyond
/// the reach) between them, as [`fill_gaps`] fills a gap down a column. Returns how many
/// pixels it filled.
fn join_dots(
    work: &mut [f32],
    sky: &[bool],
    guide: Option<&ColourGuide>,
    (w, h): (usize, usize),
) -> usize {
    let longest = 2 * dot_reach(w);
    let mut filled = 0;
    for y in 0..h {
        let row = y * w..(y + 1) * w;
        let dots: Vec<usize> = row.filter(|&p| measured(work[p]) && !sky[p]).collect();
        for pair in dots.windows(2) {
            let (left, right) = (pair[0], pair[1]);
            let between = left + 1..right;
            let open = between.clone().all(|p| work[p].is_nan() && !sky[p]);
            if !between.is_empty() && between.len() <= longest && open {
                filled += fill_one(work, (left, right), between, guide);
            }
        }
    }
    filled
}

/// Fills one gap, `column` (or a run along a row), between the known pixels `ends` (above,
/// below; left, right); returns how many pixels it filled (0 when its ends are of two
/// surfaces and there is no image to tell where one meets the other).
fn fill_one(
    work: &mut [f32],
    (above, below): (usize, usize),
    column: impl Iterator<Item = usize> + Clone,
    guide: Option<&ColourGuide>,
) -> usize {
    let (a, b) = (work[above], work[below]);
    let one_surface = a.max(b) <= SAME_SURFACE_RATIO * a.min(b);
    let pixels: Vec<usize> = std::iter::once(above).chain(column).collect();
    let edge = guide.filter(|_| !one_surface).and_then(|guide| {
        let steps = pixels.iter().zip(pixels.iter().skip(1).chain([&below]));
        let (k, step) = steps
            .map(|(&p, &q)| guide.step(p, q))
            .enumerate()
            .max_by(|s, t| s.1.total_cmp(&t.1))?;
        Some((k, guide.is_edge(step)))
    });
    match edge {
        // Two surfaces: each keeps its side of the colour edge.
        Some((k, true)) => {
            for (i, &p) in pixels.iter().enumerate().skip(1) {
                work[p] = if i <= k { a } else { b };
            }
        }
        // One surface, or two the image does not tell apart: the ground near the horizon
        // recedes by a factor of two and more from one line to the next.
        Some((_, false)) => interpolate(work, &pixels[1..], a, b),
        None if one_surface => interpolate(work, &pixels[1..], a, b),
        None => return 0,
    }
    pixels.len() - 1
}

/// Fills `gap` (pixels down a column) between ends of range `a` (above) and `b` (below)
/// linearly in 1/R.
fn interpolate(work: &mut [f32], gap: &[usize], a: f32, b: f32) {
    let (ia, ib) = (1.0 / a, 1.0 / b);
    let rows = (gap.len() + 1) as f32;
    for (k, &p) in gap.iter().enumerate() {
        let t = (k + 1) as f32 / rows;
        work[p] = 1.0 / (ia + t * (ib - ia));
    }
}

#[cfg(test)]
#[path = "scan_tests.rs"]
mod tests;
