//! The scene beyond the sensor's reach: unknown pixels joined to the sky that the image
//! shows are not sky (see the module docs of [`crate::prep`], step 4).

use super::components::label_mask;
use super::ImageSkyRules;

/// The pixels of the depth rules' sky left out of `sky`: the scene beyond the sensor's
/// reach. A piece of them no larger than a gap in the sky ([`ImageSkyRules::max_gap_fraction`]
/// of the image) is sky after all: a glint, a bird, a far tower too thin for a sensor to
/// see.
pub(crate) fn beyond_reach(
    rules: &ImageSkyRules,
    sky: &mut [bool],
    depth_sky: &[bool],
    width: usize,
    height: usize,
) -> Vec<usize> {
    let left_out: Vec<bool> = (0..sky.len()).map(|p| depth_sky[p] && !sky[p]).collect();
    let comps = label_mask(&left_out, width, height);
    let max_gap = rules.max_gap_fraction * (width * height) as f64;
    let mut beyond = Vec::new();
    for c in &comps.list {
        let pixels = comps.pixels_of(c).iter().map(|&p| p as usize);
        if c.len as f64 <= max_gap {
            pixels.for_each(|p| sky[p] = true);
        } else {
            beyond.extend(pixels);
        }
    }
    beyond
}

/// Half the width of the window in which a column's horizon is looked for, as a fraction
/// of the image's width: wide enough that a city dense over several towers' width does
/// not hide the horizon behind it, narrow enough that a horizon tilted by the camera's
/// roll is taken near the column (on the phone evaluation a whole-width window and 0.25
/// did equally; 0.05 left DEPTH16 view 1 a third more wrong, 0.0315 against 0.0237).
const HORIZON_WINDOW: f64 = 0.25;

/// One vertical run of pixels beyond the reach: column `x`, rows `top..end`.
struct Run {
    x: usize,
    top: usize,
    end: usize,
}

/// Fills the pixels `beyond` (not sky) of `work`, linearly in log range from `r_max` (at
/// least as far as the farthest range measured) to `s_max` (the sky's): what the sensor
/// did not reach is the ground receding toward the horizon and what stands on it. In each
/// column the fill goes from `r_max` where a run meets the scene below it to `s_max` at
/// the column's horizon, the lowest row the sky reaching the top row comes down to within
/// [`HORIZON_WINDOW`] of it (between far towers), and is `s_max` above it; a run with the
/// sky (or the image's bottom border) below it is `s_max`. The horizon is shared by
/// neighbouring columns so that the ground below a far tower recedes as the ground beside
/// it (a column's own skyline would draw the tower's ghost down to the ground); without
/// one (no sky above any run nearby, or not above the run), the run recedes from its
/// lower end to its upper end. The known
/// range beside a run (a near pole) is not used: it says nothing of the background behind
/// the pole, and blending it in would draw a clear halo round the pole.
pub(crate) fn recede(
    work: &mut [f32],
    (sky, beyond): (&[bool], &[bool]),
    (w, h): (usize, usize),
    (r_max, s_max): (f32, f32),
) {
    let runs = runs_of(beyond, w, h);
    let is_sky = |y: Option<usize>, x: usize| y.is_none_or(|y| y >= h || sky[y * w + x]);
    let open_sky = sky_from_the_top(sky, w, h);
    let horizon = horizon_rows(&runs, |r| r.top > 0 && open_sky[(r.top - 1) * w + r.x], w);
    let (lo, hi) = (f64::from(r_max).ln(), f64::from(s_max).ln());
    for r in &runs {
        let above_sky = is_sky(r.top.checked_sub(1), r.x);
        let below_sky = is_sky(Some(r.end), r.x);
        // The run's own ends: where each meets the scene or the sky.
        let own = |y: usize| {
            let (a, b) = (
                f64::from(u8::from(above_sky)),
                f64::from(u8::from(below_sky)),
            );
            let n = (r.end - r.top) as f64;
            let k = (y - r.top) as f64;
            let up = (n - k) / (n + 1.0); // 1 at the upper end's neighbour
            b + up * (a - b)
        };
        // Boundaries between pixels: the contour with the scene below, the horizon.
        let contour = r.end as f64 - 0.5;
        for y in r.top..r.end {
            let t = match horizon[r.x] {
                _ if below_sky => 1.0,
                Some(hz) if hz < contour => ((contour - y as f64) / (contour - hz)).min(1.0),
                _ => own(y),
            };
            work[y * w + r.x] = (lo + t * (hi - lo)).exp() as f32;
        }
    }
}

/// The sky's components that reach the top row: sky seen in water below the horizon (a
/// lake that looks like sky) is not where the horizon is.
fn sky_from_the_top(sky: &[bool], w: usize, h: usize) -> Vec<bool> {
    let comps = label_mask(sky, w, h);
    let mut open = vec![false; w * h];
    for c in comps.list.iter().filter(|c| c.bbox[1] == 0) {
        comps
            .pixels_of(c)
            .iter()
            .for_each(|&p| open[p as usize] = true);
    }
    open
}

/// The vertical runs of `mask`, column by column.
fn runs_of(mask: &[bool], w: usize, h: usize) -> Vec<Run> {
    let mut runs = Vec::new();
    for x in 0..w {
        let mut y = 0;
        while y < h {
            if !mask[y * w + x] {
                y += 1;
                continue;
            }
            let top = y;
            while y < h && mask[y * w + x] {
                y += 1;
            }
            runs.push(Run { x, top, end: y });
        }
    }
    runs
}

/// Each column's horizon: the boundary row (between pixel rows, so `top - 0.5`) below
/// the lowest sky pixel over a run that `under_sky` accepts (the sky reaching the top
/// row above it), within [`HORIZON_WINDOW`] of the column; `None` without such a run
/// nearby.
fn horizon_rows(runs: &[Run], under_sky: impl Fn(&Run) -> bool, w: usize) -> Vec<Option<f64>> {
    let mut skyline: Vec<Option<usize>> = vec![None; w];
    for r in runs.iter().filter(|r| under_sky(r)) {
        skyline[r.x] = skyline[r.x].max(Some(r.top));
    }
    let half = ((HORIZON_WINDOW * w as f64).ceil() as usize).max(1);
    (0..w)
        .map(|x| {
            let window = &skyline[x.saturating_sub(half)..(x + half + 1).min(w)];
            let lowest = window.iter().flatten().max()?;
            Some(*lowest as f64 - 0.5)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(got: f32, want: f64) -> bool {
        (f64::from(got) - want).abs() < 1e-4 * want
    }

    /// A `w x h` frame whose last row is the scene (range 5) and whose other pixels are
    /// sky where `is_sky`, else beyond the reach: the sky mask, the range, the mask of the
    /// pixels beyond.
    fn frame(
        w: usize,
        h: usize,
        is_sky: impl Fn(usize, usize) -> bool,
    ) -> (Vec<bool>, Vec<f32>, Vec<bool>) {
        let mut sky = vec![false; w * h];
        let mut work = vec![5.0f32; w * h];
        let mut beyond = vec![false; w * h];
        for p in 0..w * (h - 1) {
            if is_sky(p % w, p / w) {
                sky[p] = true;
                work[p] = f32::INFINITY;
            } else {
                beyond[p] = true;
                work[p] = f32::NAN;
            }
        }
        (sky, work, beyond)
    }

    #[test]
    fn a_column_recedes_from_the_reach_to_its_horizon_in_log_range() {
        // One column: sky, three pixels beyond the reach, the scene (a near pole at 2).
        let sky = [true, false, false, false, false];
        let mut work = [f32::INFINITY, f32::NAN, f32::NAN, f32::NAN, 2.0];
        let beyond = [false, true, true, true, false];
        recede(&mut work, (&sky, &beyond), (1, 5), (8.0, 128.0));
        // The contour at row 3.5, the horizon at 0.5: t = 5/6, 1/2, 1/6 of ln 16 over ln 8.
        for (got, t) in work[1..4].iter().zip([5.0 / 6.0, 0.5, 1.0 / 6.0]) {
            let want = 8.0 * 16f64.powf(t);
            assert!(close(*got, want), "{got} / {want}");
        }
        assert_eq!(work[4], 2.0, "the known pixel is left alone");
    }

    #[test]
    fn the_range_beside_a_run_is_not_used() {
        // Two columns: the left one's run meets a near pole (range 1) below, the right
        // one's the sky at both ends; the pole's range goes nowhere.
        let (w, h) = (2, 3);
        let sky = [true, true, false, false, false, true];
        let mut work = [
            f32::INFINITY,
            f32::INFINITY,
            f32::NAN,
            f32::NAN,
            1.0,
            f32::INFINITY,
        ];
        let beyond = [false, false, true, true, false, false];
        recede(&mut work, (&sky, &beyond), (w, h), (10.0, 15.0));
        assert!(close(work[2], 150f64.sqrt()), "{}", work[2]);
        assert_eq!(work[3], 15.0, "sky above and below: the sky's range");
    }

    #[test]
    fn the_ground_below_a_far_tower_recedes_as_beside_it() {
        // Three columns, the middle one a far tower reaching row 1; the sky comes down to
        // row 1 beside it. Beyond the reach: rows 2-4 beside, 1-4 in the middle; row 5 the
        // scene.
        let (w, h) = (3, 6);
        let (sky, mut work, beyond) = frame(w, h, |x, y| y == 0 || (y == 1 && x != 1));
        recede(&mut work, (&sky, &beyond), (w, h), (10.0, 40.0));
        for y in 2..5 {
            let row = &work[y * w..y * w + 3];
            assert!(row[1] == row[0] && row[1] == row[2], "row {y}: {row:?}");
        }
        assert_eq!(
            work[w + 1],
            40.0,
            "the tower above the horizon: the sky's range"
        );
        assert!(work[2 * w] > work[4 * w], "farther up: {work:?}");
    }

    #[test]
    fn sky_in_the_water_is_not_the_horizon() {
        // Three columns: the sky in rows 0-1, beyond the reach rows 2-6, the scene row 7;
        // in the right column row 5 is sky seen in water, not joined to the sky above.
        let (w, h) = (3, 8);
        let (sky, mut work, beyond) = frame(w, h, |x, y| y < 2 || (x, y) == (2, 5));
        recede(&mut work, (&sky, &beyond), (w, h), (10.0, 40.0));
        // The horizon at 1.5, the contour at 6.5: row 4 is halfway up (the water's row
        // would have put the horizon at 5.5 and row 4 in the sky's range).
        let want = 10.0 * 4f64.powf(0.5);
        assert!(close(work[4 * w], want), "{} / {want}", work[4 * w]);
    }
}
