//! Stereo occlusions: in a left view's disparity, the background just left of a nearer
//! surface is seen by the left camera only, so a matcher leaves it unknown, a band as wide
//! as the two surfaces' disparities differ; in a right view's, the band lies right of the
//! nearer surface. Filled as any hole, it took the range of whatever won the vote on its
//! boundary, often the near surface beside it (on real Cityscapes frames about half of
//! such pixels took the nearer side's range), which drew a pole twice its width in clear
//! air: a halo. Here such a band is found row by row and the near surface beside it, the
//! *occluder*, is kept out of its fill (see [`find`]); the hole filling then continues the
//! background the band belongs to.
//!
//! Only the view's own side is looked at: on Middlebury 2006 Aloe's left view, the unknown
//! runs right of the leaves (the projector's shadows on the cloth, 9,031 px of runs that
//! pass the tests below) are no stereo occlusions, and continuing their rows' background
//! drew stripes across a hole where the next row's run was not one.

use crate::io::depth::StereoView;

/// How much nearer than the background side of an unknown run its other side must be, a ratio
/// of ranges, for the run to be taken as an occlusion: a disparity step of a quarter. A
/// textureless face turning away (a car's side) changes its range along a short run by
/// less, and where it does not the width test below tells it apart.
const OCCLUSION_NEARER: f32 = 1.25;

/// ... or a disparity step of at least this many pixels, whatever the ratio: at close
/// range a large step is a small ratio (Aloe's leaves are 1.2 times nearer than the cloth
/// behind them, 56 px of disparity apart).
const OCCLUSION_STEP_PX: f64 = 8.0;

/// An occlusion is about as wide as its sides' disparities differ, Δd = f·B·(1/R_right −
/// 1/R_left) pixels; a run is taken as one when at most `OCCLUSION_WIDTH_FACTOR · Δd +`
/// [`OCCLUSION_WIDTH_SLACK_PX`] wide. On three real Cityscapes frames the runs with a
/// nearer right side were 1.4 to 1.5 times Δd wide at the median (the matcher's consistency
/// check widens them) and 2.4 times at the upper quartile; a slanted face's run is 1/g
/// times its Δd for a disparity gradient g < 1, wider the more the face faces the camera.
const OCCLUSION_WIDTH_FACTOR: f64 = 2.0;

/// See [`OCCLUSION_WIDTH_FACTOR`]: narrow runs of a few pixels are occlusions whatever
/// their Δd, which range's stretch off the optical axis makes up to a quarter too small.
const OCCLUSION_WIDTH_SLACK_PX: f64 = 4.0;

/// The measured pixels of like range (within [`OCCLUSION_NEARER`]) the background beside
/// an occlusion must show in its row, next to it: a matcher's speck of a few pixels amid
/// the road is no background.
const OCCLUSION_BACKGROUND_PX: usize = 8;

/// The runs of unknown pixels that are stereo occlusions, and the known pixels that occlude
/// them.
#[derive(Debug, Default)]
pub(crate) struct Occlusions {
    /// Unknown pixels in a run taken as an occlusion.
    pub(crate) occluded: Vec<bool>,
    /// Known pixels of the near surface beside such a run (right of a left view's, left of
    /// a right view's): from the run's end for as many pixels as the run is wide, while
    /// they stay nearer than the geometric mean of the run's two sides (a thin pole's whole
    /// width, not the background beyond it).
    pub(crate) occluders: Vec<bool>,
    /// Whether the background is right of the runs (a right view's), not left of them.
    pub(crate) background_right: bool,
    /// How many pixels are in `occluded`.
    pub(crate) count: usize,
}

/// Finds the occlusions of `work` (row-major `w` x `h` range: known finite, unknown NaN,
/// anything else, as the sky's +∞, neither), a range from `view`'s stereo disparity with
/// `focal_baseline` = f·B (px·m, d ≈ f·B / R): per row, each run of unknown pixels with a
/// known pixel on both sides, one of them (the occluder's) at least [`OCCLUSION_NEARER`]
/// times nearer than the other (the background's) or [`OCCLUSION_STEP_PX`] of disparity
/// nearer, and at most `OCCLUSION_WIDTH_FACTOR · Δd + OCCLUSION_WIDTH_SLACK_PX` wide (range
/// taken as depth: off the optical axis Δd is up to a quarter too small at the corners of
/// a 50° frame, as the slack allows). Both sides must be measured, not `filled` (a border
/// band's continuation), the background's over [`OCCLUSION_BACKGROUND_PX`]: on a
/// Cityscapes frame a speck of 4 px at 22 m amid the road at 9 m, continued to the border
/// by the left band, was taken for the background of the road beside it, a white wedge.
/// A left view's runs have their background on the left; a right view's, found in the
/// mirrored row, on the right.
pub(crate) fn find(
    work: &[f32],
    filled: &[bool],
    (w, h): (usize, usize),
    (focal_baseline, view): (f64, StereoView),
) -> Occlusions {
    let mut found = Occlusions {
        occluded: vec![false; w * h],
        occluders: vec![false; w * h],
        background_right: view == StereoView::Right,
        count: 0,
    };
    let mut mirrored = found.background_right.then(|| MirroredRow::new(w));
    for (y, (row, filled)) in work.chunks_exact(w).zip(filled.chunks_exact(w)).enumerate() {
        let span = y * w..(y + 1) * w;
        let occluded = &mut found.occluded[span.clone()];
        let occluders = &mut found.occluders[span];
        found.count += match &mut mirrored {
            None => find_in_row(row, filled, focal_baseline, occluded, occluders),
            Some(m) => {
                m.load(row, filled);
                let count = find_in_row(&m.row, &m.filled, focal_baseline, occluded, occluders);
                // The marks were made in the mirrored row: turn them back.
                occluded.reverse();
                occluders.reverse();
                count
            }
        };
    }
    found
}

/// A row and its `filled` flags mirrored, where a right view's runs have their background
/// on the left, as [`find_in_row`] looks for them.
struct MirroredRow {
    row: Vec<f32>,
    filled: Vec<bool>,
}

impl MirroredRow {
    fn new(w: usize) -> Self {
        MirroredRow {
            row: vec![0.0; w],
            filled: vec![false; w],
        }
    }

    /// Holds `row` and `filled` mirrored.
    fn load(&mut self, row: &[f32], filled: &[bool]) {
        (self.row.iter_mut().zip(row.iter().rev())).for_each(|(m, &r)| *m = r);
        (self.filled.iter_mut().zip(filled.iter().rev())).for_each(|(m, &f)| *m = f);
    }
}

/// [`find`] in one row for the runs whose background is left of them, marking their pixels
/// in `occluded` and their occluders in `occluders`; returns how many pixels it took.
fn find_in_row(
    row: &[f32],
    filled: &[bool],
    focal_baseline: f64,
    occluded: &mut [bool],
    occluders: &mut [bool],
) -> usize {
    let w = row.len();
    let mut count = 0;
    let mut x = 0;
    while x < w {
        if !row[x].is_nan() {
            x += 1;
            continue;
        }
        let start = x;
        while x < w && row[x].is_nan() {
            x += 1;
        }
        if start == 0 || x == w || filled[x] {
            continue;
        }
        let (left, right) = (row[start - 1], row[x]);
        let width = x - start;
        if is_occlusion(left, right, width, focal_baseline)
            && is_background(&row[..start], &filled[..start])
        {
            mark(row, (start, x), occluded, occluders);
            count += width;
        }
    }
    count
}

/// Whether the last [`OCCLUSION_BACKGROUND_PX`] pixels of `row` (ending at an occlusion)
/// are measured and within [`OCCLUSION_NEARER`] of the last one.
fn is_background(row: &[f32], filled: &[bool]) -> bool {
    let Some(from) = row.len().checked_sub(OCCLUSION_BACKGROUND_PX) else {
        return false;
    };
    let last = row[row.len() - 1];
    (row[from..].iter().zip(&filled[from..])).all(|(&r, &f)| {
        !f && r.is_finite() && r < last * OCCLUSION_NEARER && r * OCCLUSION_NEARER > last
    })
}

/// Whether a run of `width` unknown pixels between known ranges `left` and `right` is an
/// occlusion (see [`find`]).
fn is_occlusion(left: f32, right: f32, width: usize, focal_baseline: f64) -> bool {
    if !(left.is_finite() && right.is_finite() && right > 0.0) {
        return false;
    }
    let step_px = focal_baseline * (1.0 / f64::from(right) - 1.0 / f64::from(left));
    (left >= right * OCCLUSION_NEARER || step_px >= OCCLUSION_STEP_PX)
        && width as f64 <= OCCLUSION_WIDTH_FACTOR * step_px + OCCLUSION_WIDTH_SLACK_PX
}

/// Marks the run `[start, end)` of `row` in `occluded`, and its occluder right of it in
/// `occluders`.
fn mark(row: &[f32], (start, end): (usize, usize), occluded: &mut [bool], occluders: &mut [bool]) {
    occluded[start..end].fill(true);
    let (left, right) = (f64::from(row[start - 1]), f64::from(row[end]));
    let nearer_than = (left * right).sqrt();
    for x in (end..row.len()).take(end - start) {
        let r = row[x];
        if !(r.is_finite() && f64::from(r) < nearer_than) {
            break;
        }
        occluders[x] = true;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const NAN: f32 = f32::NAN;
    /// Columns of background before each test's row: a pole at 5 m has a disparity of
    /// 100 / 5 = 20 px, and is in the right camera's view from column 20.
    const LEAD: usize = 24;

    /// A row of `LEAD` px of background at 20 m, then `parts` (value, count) in turn.
    fn row(parts: &[(f32, usize)]) -> Vec<f32> {
        let mut v = vec![20.0; LEAD];
        for &(value, n) in parts {
            v.extend(std::iter::repeat_n(value, n));
        }
        v
    }

    fn find_in(values: &[f32]) -> Occlusions {
        find_as(values, StereoView::Left)
    }

    /// [`find`] in `values`, one row of `view`'s disparity with f·B = 100 px·m.
    fn find_as(values: &[f32], view: StereoView) -> Occlusions {
        find(
            values,
            &vec![false; values.len()],
            (values.len(), 1),
            (100.0, view),
        )
    }

    /// A background at 20 m, a pole at 5 m: Δd = 100·(1/5 − 1/20) = 15 px; the run left of
    /// the pole is an occlusion and the pole its occluder, up to the background beyond.
    #[test]
    fn a_run_left_of_a_nearer_pole_is_an_occlusion() {
        let o = find_in(&row(&[(NAN, 12), (5.0, 3), (20.0, 4)]));
        let (run, pole) = (LEAD..LEAD + 12, LEAD + 12..LEAD + 15);
        assert_eq!(o.count, 12);
        assert!(o.occluded[run.clone()].iter().all(|&b| b));
        assert!(o.occluders[pole.clone()].iter().all(|&b| b));
        assert!(!o.occluders[pole.end], "the background beyond the pole");
        assert!(!o.occluders[run.start - 1] && !o.occluded[run.start - 1]);
    }

    /// The same run with the near side on the left is no occlusion of a left view, but
    /// one of a right view: its background (measured over as many pixels as a left view's
    /// must be) is right of it, its occluder the pole left of it. A run whose sides are
    /// within the ratio is none, nor is one far wider than the disparity step.
    #[test]
    fn other_runs_are_not_occlusions() {
        let mirrored = row(&[(5.0, 3), (NAN, 12), (20.0, OCCLUSION_BACKGROUND_PX)]);
        assert_eq!(find_in(&mirrored).count, 0);
        let o = find_as(&mirrored, StereoView::Right);
        let (pole, run) = (LEAD..LEAD + 3, LEAD + 3..LEAD + 15);
        assert_eq!(o.count, 12);
        assert!(o.background_right && run.clone().all(|x| o.occluded[x]));
        assert!(pole.clone().all(|x| o.occluders[x]));
        assert!(
            !o.occluders[pole.start - 1],
            "the background left of the pole"
        );
        let left_view_run = row(&[(NAN, 12), (5.0, 3), (20.0, 4)]);
        assert_eq!(find_as(&left_view_run, StereoView::Right).count, 0);
        let close = row(&[(NAN, 6), (17.0, 4)]);
        assert_eq!(find_in(&close).count, 0);
        // Δd = 100·(1/10 − 1/20) = 5 px: up to 14 px wide.
        let wide = |n: usize| row(&[(NAN, n), (10.0, 4)]);
        assert_eq!(find_in(&wide(14)).count, 14);
        assert_eq!(find_in(&wide(15)).count, 0);
    }

    /// A right view's row is found as the mirrored left view's: every row of these tests
    /// mirrored has the same row's occlusions and occluders, mirrored.
    #[test]
    fn a_right_view_is_a_mirrored_left_view() {
        let rows = [
            row(&[(NAN, 12), (5.0, 3), (20.0, 4)]),
            row(&[(NAN, 3), (5.0, 10)]),
            row(&[(NAN, 6), (17.0, 4)]),
            row(&[(5.0, 3), (NAN, 12), (20.0, 30)]),
            row(&[(NAN, 5), (8.0, 4), (NAN, 4), (30.0, 9)]),
        ];
        let flip = |v: &[bool]| v.iter().rev().copied().collect::<Vec<_>>();
        for values in rows {
            let left = find_in(&values);
            let mirrored: Vec<f32> = values.iter().rev().copied().collect();
            let right = find_as(&mirrored, StereoView::Right);
            assert_eq!(flip(&right.occluded), left.occluded, "{values:?}");
            assert_eq!(flip(&right.occluders), left.occluders, "{values:?}");
            assert_eq!(right.count, left.count);
            assert!(right.background_right && !left.background_right);
        }
    }

    /// At close range a large disparity step is a small ratio: a surface 1.18 times
    /// nearer than the background (17 m against 20) is 8.8 px of disparity nearer with
    /// f·B = 1000 px·m, and the run beside it is an occlusion; with f·B = 100 (0.9 px, a
    /// face turning away) it is not.
    #[test]
    fn a_large_disparity_step_is_an_occlusion_below_the_ratio() {
        let values = row(&[(NAN, 12), (17.0, 4)]);
        let found = |fb: f64| {
            find(
                &values,
                &vec![false; values.len()],
                (values.len(), 1),
                (fb, StereoView::Left),
            )
        };
        assert_eq!(found(1000.0).count, 12);
        assert_eq!(found(100.0).count, 0);
        // Wider than 2 · 8.8 + 4 px: no occlusion, whatever the step.
        let wide = row(&[(NAN, 22), (17.0, 4)]);
        assert_eq!(
            find(
                &wide,
                &vec![false; wide.len()],
                (wide.len(), 1),
                (1000.0, StereoView::Left)
            )
            .count,
            0
        );
    }

    /// A run at the border, or beside the sky (+∞), has no two known sides.
    #[test]
    fn runs_without_two_known_sides_are_left() {
        let at_border: Vec<f32> = [NAN; 5].into_iter().chain([5.0; 3]).collect();
        assert_eq!(find_in(&at_border).count, 0);
        let by_sky = row(&[(f32::INFINITY, 2), (NAN, 5), (5.0, 3)]);
        assert_eq!(find_in(&by_sky).count, 0);
    }

    /// The background must be a surface measured over `OCCLUSION_BACKGROUND_PX` pixels:
    /// not a speck of a few pixels amid the near surface, not a border band's continuation
    /// (`filled`); nor may the near side be filled.
    #[test]
    fn the_background_is_a_measured_surface() {
        let speck = |n: usize| -> Vec<f32> {
            let mut v = vec![5.0; LEAD];
            v.extend(std::iter::repeat_n(20.0, n));
            v.extend([NAN; 6]);
            v.extend([5.0; 3]);
            v
        };
        assert_eq!(find_in(&speck(OCCLUSION_BACKGROUND_PX - 1)).count, 0);
        assert_eq!(find_in(&speck(OCCLUSION_BACKGROUND_PX)).count, 6);
        let v = row(&[(NAN, 6), (5.0, 3)]);
        let with_filled = |f: &dyn Fn(usize) -> bool| {
            let filled: Vec<bool> = (0..v.len()).map(f).collect();
            find(&v, &filled, (v.len(), 1), (100.0, StereoView::Left)).count
        };
        assert_eq!(with_filled(&|_| false), 6);
        assert_eq!(with_filled(&|x| x < LEAD), 0, "a band's continuation");
        assert_eq!(with_filled(&|x| x == LEAD + 6), 0, "a filled near side");
        // A surface that varies within the ratio is one.
        let mut sloped = v.clone();
        (0..LEAD).for_each(|x| sloped[x] = 18.0 + x as f32 * 0.1);
        assert_eq!(find_in(&sloped).count, 6);
    }

    /// The occluder is marked for as many pixels as the run is wide, no farther.
    #[test]
    fn the_occluder_spans_the_runs_width() {
        let o = find_in(&row(&[(NAN, 3), (5.0, 10)]));
        assert_eq!(o.occluders.iter().filter(|&&b| b).count(), 3);
        assert!(o.occluders[LEAD + 3..LEAD + 6].iter().all(|&b| b));
    }
}
