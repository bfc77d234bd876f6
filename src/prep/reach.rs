//! The scene beyond the sensor's reach: unknown pixels joined to the sky that the image
//! shows are not sky (see the module docs of [`crate::prep`], step 4).

use super::components::{flood, label_mask};
use super::fill::ColourGuide;
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

/// Least share of a region's columns (of its bounding box) in which the sensor reached a
/// pixel of its material just above it, for [`take_out_reached_in_part`].
const MIN_REACHED_SHARE: f64 = 0.25;

/// Takes out of `beyond` the pixels of surfaces the sensor reached in part, which are
/// holes to fill from what was reached: a region of one material ([`one_material`], from
/// pixel to pixel) under known pixels of its own material in at least
/// [`MIN_REACHED_SHARE`] of its columns. Neither the ground nor an upright face is farther
/// below a point of it that was reached, so such a region is no scene beyond the reach: a
/// face just at the reach's limit (a box 8 m from a phone whose depth stops at 8.19 m) is
/// measured in some pixels and lost in others by the noise, and receding between its
/// measured pixels it would show as blotches. The ground at the reach's contour has a few
/// such pixels where the noise crosses the limit, over a region as wide as the image.
pub(crate) fn take_out_reached_in_part(
    work: &[f32],
    sky: &[bool],
    beyond: &mut Vec<usize>,
    guide: &ColourGuide,
    (w, h): (usize, usize),
) {
    // 0: not beyond (or taken out); 1: beyond, in no region yet; 2: in a region.
    let mut state = vec![0u8; w * h];
    beyond.iter().for_each(|&p| state[p] = 1);
    let known = |p: usize| work[p].is_finite() && !sky[p];
    let mut pixels = Vec::new();
    for &seed in beyond.iter() {
        if state[seed] != 1 {
            continue;
        }
        pixels.clear();
        let c = flood(w, h, seed, &mut pixels, |p, q| {
            let take = state[q] == 1 && (p == q || one_material(guide, p, q));
            if take {
                state[q] = 2;
            }
            take
        });
        let under_reached = pixels
            .iter()
            .map(|&p| p as usize)
            .filter(|&p| p >= w && known(p - w) && one_material(guide, p, p - w))
            .count();
        let columns = c.bbox[2] + 1 - c.bbox[0];
        if under_reached as f64 >= MIN_REACHED_SHARE * columns as f64 {
            pixels.iter().for_each(|&p| state[p as usize] = 0);
        }
    }
    beyond.retain(|&p| state[p] != 0);
}

/// Half the width of the window in which a column's horizon is looked for, as a fraction
/// of the image's width: wide enough that a far city hiding the horizon does not raise it
/// (in a street the sky comes down to the horizon only at the street's end, in the middle
/// of the frame; view 2 of the phone evaluation sees it only at its right edge, and a
/// quarter of the width put the horizon 3 rows of a 1/8 map too high on the left), narrow
/// enough that a horizon tilted by the camera's roll is taken near the column (the window
/// puts it up to half the width times the roll's slope too low: 9 px of a 1024 px frame
/// at 1°). Whole-width windows did better still on the (level) evaluation; 0.05 of the
/// width left DEPTH16 view 1 a third more wrong.
const HORIZON_WINDOW: f64 = 0.5;

/// One vertical run of pixels beyond the reach: column `x`, rows `top..end`.
struct Run {
    x: usize,
    top: usize,
    end: usize,
}

impl Run {
    /// Whether the pixel below the run is the scene (not the sky, not the image's bottom
    /// border).
    fn meets_scene(&self, sky: &[bool], (w, h): (usize, usize)) -> bool {
        self.end < h && !sky[self.end * w + self.x]
    }
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
/// lower end to its upper end. With the image, a run standing on something nearer than
/// the reach (a box's top edge) recedes from the reach's contour on the ground ([`Reach`])
/// where it is the ground behind or rises over the horizon, and from halfway between
/// where it is something else whose foot the box hides. The known range beside a run (a
/// near pole) is not used: it says nothing of the background behind the pole, and
/// blending it in would draw a clear halo round the pole. Returns the pixels of what
/// stands on the ground, held at its foot's range ([`stand_upright`]); the others recede.
pub(crate) fn recede(
    work: &mut [f32],
    (sky, beyond): (&[bool], &[bool]),
    (w, h): (usize, usize),
    (r_max, s_max): (f32, f32),
    guide: Option<&ColourGuide>,
) -> Vec<usize> {
    let runs = runs_of(beyond, w, h);
    let open_sky = sky_from_the_top(sky, w, h);
    let horizon = horizon_rows(&runs, |r| r.top > 0 && open_sky[(r.top - 1) * w + r.x], w);
    let reach = Reach::new(&runs, (work, sky), (w, h), r_max, guide);
    let (lo, hi) = (f64::from(r_max).ln(), f64::from(s_max).ln());
    for r in &runs {
        let above_sky = r.top.checked_sub(1).is_none_or(|y| sky[y * w + r.x]);
        let below_sky = !r.meets_scene(sky, (w, h));
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
        // Boundaries between pixels: the contour with the scene below, the horizon. Above
        // something nearer (a box's top edge), the ground seen behind it recedes from the
        // reach's contour on the ground beside, and what rises over the horizon there,
        // its foot hidden, is at the sky's range, as it is where nothing hides its foot.
        // Another material below the horizon (a facade behind a pole) has its hidden foot
        // between the top edge and the reach's contour: it recedes from halfway between.
        let mut contour = r.end as f64 - 0.5;
        if let Some(guide) =
            guide.filter(|_| !below_sky && work[r.end * w + r.x] < AT_THE_REACH * r_max)
        {
            let lowest = (r.end - 1) * w + r.x;
            let over_horizon = horizon[r.x].is_some_and(|hz| contour < hz);
            let behind = reach.contour(r.x).unwrap_or(f64::MIN).max(contour);
            let ground = reach.ground_colours(r.x);
            if over_horizon || ground.iter().any(|&q| one_material(guide, lowest, q)) {
                contour = behind;
            } else {
                contour = 0.5 * (contour + behind);
            }
        }
        for y in r.top..r.end {
            let t = match horizon[r.x] {
                _ if below_sky => 1.0,
                Some(hz) if hz < contour => ((contour - y as f64) / (contour - hz)).min(1.0),
                _ => own(y),
            };
            work[y * w + r.x] = (lo + t * (hi - lo)).exp() as f32;
        }
    }
    match guide {
        Some(guide) => stand_upright(work, (&runs, &reach), &horizon, sky, (w, h), guide),
        None => Vec::new(),
    }
}

/// Least share of `Rmax` that the scene just below a run has where the run meets the
/// ground at the sensor's reach (the noise of a phone's depth is a few per cent there);
/// a run meeting something nearer stands on it (a box's top edge, a pole's).
const AT_THE_REACH: f32 = 0.8;

/// The ground at the sensor's reach: the columns whose lowest run meets the scene at the
/// reach (at least [`AT_THE_REACH`] of `Rmax`), left to right, each with its contour (the
/// boundary row above the scene) and the scene's pixel below it; with the image, each
/// column's ground colours.
struct Reach {
    columns: Vec<(usize, f64, usize)>,
    ground: Vec<Vec<usize>>,
}

impl Reach {
    fn new(
        runs: &[Run],
        (work, sky): (&[f32], &[bool]),
        (w, h): (usize, usize),
        r_max: f32,
        guide: Option<&ColourGuide>,
    ) -> Self {
        let mut lowest: Vec<Option<&Run>> = vec![None; w];
        for r in runs.iter().filter(|r| r.meets_scene(sky, (w, h))) {
            lowest[r.x] = Some(r);
        }
        let columns = (lowest.iter().flatten())
            .map(|r| (r.x, r.end as f64 - 0.5, r.end * w + r.x))
            .filter(|&(_, _, below)| work[below] >= AT_THE_REACH * r_max)
            .collect();
        let mut reach = Reach {
            columns,
            ground: Vec::new(),
        };
        if let Some(guide) = guide {
            let half = ((GROUND_WINDOW * w as f64).ceil() as usize).max(1);
            reach.ground = (0..w).map(|x| reach.ground_near(x, half, guide)).collect();
        }
        reach
    }

    /// Column `x`'s contour: its own, or interpolated between the nearest columns at the
    /// reach either side (a rolled camera tilts it); `None` without any.
    fn contour(&self, x: usize) -> Option<f64> {
        let i = self.columns.partition_point(|c| c.0 < x);
        match (
            i.checked_sub(1).map(|j| self.columns[j]),
            self.columns.get(i),
        ) {
            (Some((a, ca, _)), Some(&(b, cb, _))) => {
                Some(ca + (cb - ca) * (x - a) as f64 / (b - a) as f64)
            }
            (Some((_, c, _)), None) | (None, Some(&(_, c, _))) => Some(c),
            (None, None) => None,
        }
    }

    /// One pixel of each of the ground's materials ([`one_material`]) seen just below the
    /// reach near column `x` (given the image; empty without it).
    fn ground_colours(&self, x: usize) -> &[usize] {
        self.ground.get(x).map_or(&[], Vec::as_slice)
    }

    /// [`Reach::ground_colours`] of column `x`: within `half` columns of it, or else at the
    /// nearest columns at the reach either side (under a wide box).
    fn ground_near(&self, x: usize, half: usize, guide: &ColourGuide) -> Vec<usize> {
        let mut out = Vec::new();
        let from = self.columns.partition_point(|c| c.0 + half < x);
        let to = self.columns.partition_point(|c| c.0 <= x + half);
        let near = if from < to {
            &self.columns[from..to]
        } else {
            &self.columns[from.saturating_sub(1)..(from + 1).min(self.columns.len())]
        };
        for &(_, _, q) in near {
            if !out.iter().any(|&g| one_material(guide, g, q)) {
                out.push(q);
            }
        }
        out
    }
}

/// Half the width of the window whose scene just below the pixels beyond the reach gives
/// a column the ground's colours, as a fraction of the image's width (two tones of one
/// ground, a road and its markings, all seen somewhere along the reach's contour).
const GROUND_WINDOW: f64 = 1.0 / 32.0;

/// What stands on the ground beyond the reach stands where it meets the ground: a box, a
/// facade, a car are upright, so their range up a column is that of their foot, not the
/// ground's receding behind them ([`recede`] draws them as ground, fading into the sky
/// from the foot up). Walking up each run that meets the scene below, a pixel of the
/// ground's colours (one material, [`one_material`], with the ground just below the reach
/// nearby, [`Reach::ground_colours`], or with the last ground pixel below it in the
/// column, as the ground's colour drifts with distance) is ground; the pixels of another material just
/// above ground are an object standing there, as far as its material goes on, and take
/// the range of its lowest pixel where that is nearer, if it is upright: it rises above
/// the horizon, or the ground is seen again above it (or above its top face, which, seen
/// from above, may be lit far brighter). A flat surface of another material
/// reaching the far scene (water up to the far shore) is neither. What lies above an
/// object without ground between (a far tower behind a box, the box's top face) keeps
/// [`recede`]'s range: its foot is hidden. Returns the pixels held.
fn stand_upright(
    work: &mut [f32],
    (runs, reach): (&[Run], &Reach),
    horizon: &[Option<f64>],
    sky: &[bool],
    (w, h): (usize, usize),
    guide: &ColourGuide,
) -> Vec<usize> {
    let mut held = Vec::new();
    for r in runs.iter().filter(|r| r.meets_scene(sky, (w, h))) {
        let Some(hz) = horizon[r.x] else { continue };
        let ground = reach.ground_colours(r.x);
        let at = |y: usize| y * w + r.x;
        let of_the_ground: Vec<bool> = (r.top..r.end)
            .map(|y| ground.iter().any(|&q| one_material(guide, at(y), q)))
            .collect();
        // The ground's colour drifts as it recedes (aerial perspective, a texture averaged
        // to its mean): a pixel of the last ground seen below in the column is ground too.
        let is_ground =
            |y: usize, last: usize| of_the_ground[y - r.top] || one_material(guide, at(y), last);
        // Walking up: `y` the lowest row walked; whether it is ground, and the last ground
        // pixel (the scene below the run counts as what the first pixels stand on).
        let (mut y, mut on_ground, mut last) = (r.end, true, at(r.end));
        while y > r.top {
            let foot = y - 1;
            y = foot;
            if is_ground(foot, last) {
                (on_ground, last) = (true, at(foot));
                continue;
            }
            if !on_ground {
                continue;
            }
            // An object from `foot` up to `y`; the foot's pixel may blend the ground below
            // with the object above (an edge on the depth's grid).
            let blend = |y: usize| y == foot && blends(guide, at(foot + 1), at(foot), at(foot - 1));
            while y > r.top
                && !is_ground(y - 1, last)
                && (one_material(guide, at(y - 1), at(y)) || blend(y))
            {
                y -= 1;
            }
            let tall = foot + 1 - y >= MIN_OBJECT_ROWS;
            // Its top face, seen from above, may be lit far brighter than its front: up to
            // half as many rows of its chromaticity, each within MAX_FACE_SHADING of the
            // brightness of the one below, with the ground above.
            let mut top = y;
            while top > r.top
                && 2 * (y - (top - 1)) <= foot + 1 - y
                && !is_ground(top - 1, last)
                && shaded_alike(guide, at(top - 1), at(top), MAX_FACE_SHADING)
            {
                top -= 1;
            }
            if top < y && top > r.top && is_ground(top - 1, last) {
                y = top;
            }
            let near_foot = foot as f64 - hz >= MIN_FOOT_ROWS_BELOW_HORIZON;
            let over_horizon = (y as f64) < hz;
            let ground_above = y > r.top && is_ground(y - 1, last);
            if near_foot && tall && (over_horizon || ground_above) {
                let v = work[at(foot)];
                for p in (y..=foot).map(at) {
                    if work[p] > v {
                        work[p] = v;
                        held.push(p);
                    }
                }
            }
            on_ground = false;
        }
    }
    held
}

/// Least distance of an object's foot below the horizon, in rows of the depth's grid: the
/// range on the ground goes as 1/(rows below the horizon), and the foot and the horizon
/// are each known to about half a row, so at three rows the foot's range is known to about
/// a third; nearer the horizon a row more or less is a factor. (A sixteenth of the height,
/// 4 rows of a 1/8 map of a 512-row photo, left a tower 37 m from a phone reaching 8 m
/// fading into the sky; 2 rows held ARCore's far city across the water too near.)
const MIN_FOOT_ROWS_BELOW_HORIZON: f64 = 3.0;

/// Fewest rows an object's run in one column must have to be taken as standing: one or two
/// pixels of another material by the ground's far edge are the far scene's blend.
const MIN_OBJECT_ROWS: usize = 3;

/// Largest difference of chromaticity (each channel's share of the sum, linear RGB) between
/// two pixels of one material, lit or shaded.
const CHROMA_TOLERANCE: f32 = 0.04;
/// Largest ratio of two pixels' brightness (the sum) for one material.
const MAX_SHADING: f32 = 3.0;
/// Largest ratio of brightness between an object's front and its top face above it: a
/// box's sunlit top over its front in shade (3.7 times as bright on the phone evaluation's
/// red box, whose top face hid the ground seen above it).
const MAX_FACE_SHADING: f32 = 8.0;

/// Whether pixel `m` lies between `a` and `b` in every channel (within a tenth of their
/// difference): a blend of the two, as an edge resampled to a coarser grid is.
fn blends(guide: &ColourGuide, a: usize, m: usize, b: usize) -> bool {
    let (a, m, b) = (guide.colour_at(a), guide.colour_at(m), guide.colour_at(b));
    (0..3).all(|c| {
        let (lo, hi) = (a[c].min(b[c]), a[c].max(b[c]));
        let slack = 0.1 * (hi - lo) + 1e-4;
        (lo - slack..=hi + slack).contains(&m[c])
    })
}

/// Whether pixels `p` and `q` look like one material: the same chromaticity, brightness
/// within [`MAX_SHADING`] (a checkered or shaded ground, a face in light and shade), which
/// a colour step does not allow (two tones of one lawn differ by 30 %).
fn one_material(guide: &ColourGuide, p: usize, q: usize) -> bool {
    shaded_alike(guide, p, q, MAX_SHADING)
}

/// Whether pixels `p` and `q` have the same chromaticity (within [`CHROMA_TOLERANCE`]) and
/// brightnesses within a factor `max_shading`.
fn shaded_alike(guide: &ColourGuide, p: usize, q: usize, max_shading: f32) -> bool {
    let (a, b) = (guide.colour_at(p), guide.colour_at(q));
    let (sa, sb) = (a.iter().sum::<f32>(), b.iter().sum::<f32>());
    let floor = 1e-4;
    if !(sa > floor && sb > floor) || sa.max(sb) > max_shading * sa.min(sb) {
        return false;
    }
    (0..3).all(|c| (a[c] / sa - b[c] / sb).abs() <= CHROMA_TOLERANCE)
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
    use crate::raster::RgbImage;
    use std::ops::RangeInclusive;

    fn close(got: f32, want: f64) -> bool {
        (f64::from(got) - want).abs() < 1e-4 * want
    }

    /// A `w x h` frame whose last row is the scene at the reach (range 10, the tests'
    /// `Rmax`) and whose other pixels are sky where `is_sky`, else beyond the reach: the
    /// sky mask, the range, the mask of the pixels beyond.
    fn frame(
        w: usize,
        h: usize,
        is_sky: impl Fn(usize, usize) -> bool,
    ) -> (Vec<bool>, Vec<f32>, Vec<bool>) {
        let mut sky = vec![false; w * h];
        let mut work = vec![10.0f32; w * h];
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
        recede(&mut work, (&sky, &beyond), (1, 5), (8.0, 128.0), None);
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
        recede(&mut work, (&sky, &beyond), (w, h), (10.0, 15.0), None);
        assert!(close(work[2], 150f64.sqrt()), "{}", work[2]);
        assert_eq!(work[3], 15.0, "sky above and below: the sky's range");
    }

    #[test]
    fn the_ground_behind_a_box_recedes_as_beside_it() {
        // Three columns: the sky in row 0, beyond the reach rows 1-8 beside and 1-5 in the
        // middle, where a near box (range 3) stands in rows 6-9; row 9 beside is the
        // ground at the reach (range 10 = Rmax). Above the box the lawn behind it has the
        // range of the lawn beside it, not the reach's; a slate face behind the box (its
        // foot hidden) is farther than the reach at the box's top edge and nearer than the
        // lawn there.
        let (w, h) = (3, 10);
        let box_ = |x: usize, y: usize| x == 1 && y >= 6;
        let ground_behind = |behind: [f32; 3]| {
            let (sky, mut work, mut beyond) = frame(w, h, |_, y| y == 0);
            for p in (0..w * h).filter(|&p| box_(p % w, p / w)) {
                (beyond[p], work[p]) = (false, 3.0);
            }
            let image = RgbImage::from_fn(w, h, |x, y| match (x, y) {
                (_, 0) => [0.5, 0.6, 0.9],
                _ if box_(x, y) => [0.6, 0.5, 0.1],
                (1, _) => behind,
                _ => lawn(y),
            });
            guided_and_plain(work, (&sky, &beyond), (w, h), &image)
        };
        let (work, plain) = ground_behind(lawn(5));
        for y in 1..6 {
            let row = &work[y * w..y * w + 3];
            assert!(row[1] == row[0] && row[1] == row[2], "row {y}: {row:?}");
        }
        assert!(work[5 * w + 1] > plain[5 * w + 1], "{plain:?}");
        let lawn_behind = work[5 * w + 1];
        let (work, plain) = ground_behind([0.2, 0.25, 0.35]);
        let between = plain[5 * w + 1]..lawn_behind;
        assert!(between.contains(&work[5 * w + 1]), "{work:?} {between:?}");
    }

    #[test]
    fn the_horizon_is_looked_for_half_the_width_either_side() {
        // Ten columns under a far city that hides the sky below row 3, but for the
        // street's end in column 9, where the sky comes down to row 5: columns within
        // half the width of it (5 columns) have their horizon there, the others at the
        // city's skyline.
        let (w, h) = (10, 8);
        let (sky, _, beyond) = frame(w, h, |x, y| y < if x == 9 { 5 } else { 3 });
        let runs = runs_of(&beyond, w, h);
        let horizon = horizon_rows(&runs, |r| r.top > 0 && sky[(r.top - 1) * w + r.x], w);
        for (x, hz) in horizon.iter().enumerate() {
            assert_eq!(*hz, Some(if x >= 4 { 4.5 } else { 2.5 }), "column {x}");
        }
    }

    #[test]
    fn the_ground_below_a_far_tower_recedes_as_beside_it() {
        // Three columns, the middle one a far tower reaching row 1; the sky comes down to
        // row 1 beside it. Beyond the reach: rows 2-4 beside, 1-4 in the middle; row 5 the
        // scene.
        let (w, h) = (3, 6);
        let (sky, mut work, beyond) = frame(w, h, |x, y| y == 0 || (y == 1 && x != 1));
        recede(&mut work, (&sky, &beyond), (w, h), (10.0, 40.0), None);
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
        recede(&mut work, (&sky, &beyond), (w, h), (10.0, 40.0), None);
        // The horizon at 1.5, the contour at 6.5: row 4 is halfway up (the water's row
        // would have put the horizon at 5.5 and row 4 in the sky's range).
        let want = 10.0 * 4f64.powf(0.5);
        assert!(close(work[4 * w], want), "{} / {want}", work[4 * w]);
    }

    /// Two tones of one green lawn (the same chromaticity, 1.6 times as bright).
    fn lawn(y: usize) -> [f32; 3] {
        if (y / 3).is_multiple_of(2) {
            [0.05, 0.1, 0.02]
        } else {
            [0.08, 0.16, 0.032]
        }
    }

    /// [`recede`] on a `2 x 40` frame, the sky in rows 0-4 (of the right column, rows
    /// `0..right_sky`), the scene in row 39, beyond the reach between, coloured by
    /// `colour(x, y)` (the lawn where `None`); with the image as guide and without.
    fn recede_with_and_without_the_image(
        right_sky: usize,
        colour: impl Fn(usize, usize) -> Option<[f32; 3]>,
    ) -> (Vec<f32>, Vec<f32>) {
        let (w, h) = (2, 40);
        let is_sky = |x: usize, y: usize| y < if x == 1 { right_sky } else { 5 };
        let (sky, work, beyond) = frame(w, h, is_sky);
        let image = RgbImage::from_fn(w, h, |x, y| match colour(x, y) {
            _ if is_sky(x, y) => [0.5, 0.6, 0.9],
            Some(c) => c,
            None => lawn(y),
        });
        guided_and_plain(work, (&sky, &beyond), (w, h), &image)
    }

    /// [`recede`] of `work` (`Rmax` 10, `Smax` 40) with `image` as guide, and without.
    fn guided_and_plain(
        mut work: Vec<f32>,
        (sky, beyond): (&[bool], &[bool]),
        (w, h): (usize, usize),
        image: &RgbImage,
    ) -> (Vec<f32>, Vec<f32>) {
        let mut plain = work.clone();
        let guide = ColourGuide::new(image, 0.08);
        recede(&mut work, (sky, beyond), (w, h), (10.0, 40.0), Some(&guide));
        recede(&mut plain, (sky, beyond), (w, h), (10.0, 40.0), None);
        (work, plain)
    }

    /// Whether `work` is `plain` but in the right column's `rows`, which are `foot`.
    fn moved_only(work: &[f32], plain: &[f32], rows: RangeInclusive<usize>, foot: f32) -> bool {
        let standing = |p: usize| p % 2 == 1 && rows.contains(&(p / 2));
        (0..work.len()).all(|p| work[p] == if standing(p) { foot } else { plain[p] })
    }

    /// Asserts that with the image the right column's `rows` stand at the range of their
    /// lowest row, the frame of [`recede_with_and_without_the_image`] otherwise as
    /// without it.
    fn assert_stands(
        right_sky: usize,
        colour: impl Fn(usize, usize) -> Option<[f32; 3]>,
        rows: RangeInclusive<usize>,
    ) {
        let (work, plain) = recede_with_and_without_the_image(right_sky, colour);
        let foot = plain[2 * *rows.end() + 1];
        assert!(moved_only(&work, &plain, rows, foot), "{work:?}");
    }

    #[test]
    fn a_box_beyond_the_reach_stands_at_its_foot() {
        // The right column: a slate box in rows 20-30 on the lawn, the lawn seen above it.
        let (work, plain) = recede_with_and_without_the_image(5, |x, y| {
            (x == 1 && (20..=30).contains(&y)).then_some([0.2, 0.25, 0.35])
        });
        assert!(
            plain[2 * 20 + 1] > plain[2 * 30 + 1],
            "without the image it recedes"
        );
        assert!(
            moved_only(&work, &plain, 20..=30, plain[2 * 30 + 1]),
            "{work:?}"
        );
    }

    #[test]
    fn a_tower_over_the_horizon_stands_at_its_foot_and_hides_what_is_behind() {
        // The right column: a brown tower in rows 2-30 rising over the horizon (the sky
        // comes down to row 4 on the left); then one on a slate box (rows 20-30), which
        // neither rises over the horizon nor has the lawn above it: both recede.
        let brown = [0.3, 0.15, 0.05];
        assert_stands(
            2,
            |x, y| (x == 1 && (2..=30).contains(&y)).then_some(brown),
            2..=30,
        );
        let (work, plain) = recede_with_and_without_the_image(2, |x, y| match (x, y) {
            (1, 20..=30) => Some([0.2, 0.25, 0.35]),
            (1, 2..=19) => Some(brown),
            _ => None,
        });
        assert_eq!(work, plain);
    }

    #[test]
    fn a_box_stands_on_ground_whose_colour_drifts_with_distance() {
        // The lawn turns yellow as it recedes (0.003 of red's share per row, 0.06 over the
        // 20 rows up to the box): the ground below the reach no longer matches it there,
        // the ground just below the box does, and the ground above it.
        let drifted = |y: usize| {
            let [r, g, b] = lawn(y);
            let d = 0.0005 * (39 - y) as f32 * (r + g + b) / 0.17;
            [r + d, g - d, b]
        };
        let slate = [0.2, 0.25, 0.35];
        let box_ = |x: usize, y: usize| x == 1 && (12..=18).contains(&y);
        assert_stands(
            5,
            |x, y| Some(if box_(x, y) { slate } else { drifted(y) }),
            12..=18,
        );
    }

    #[test]
    fn a_box_seen_from_above_stands_with_its_top_face() {
        // The right column: a red box's front in shade (rows 20-30) under its sunlit top
        // face (row 19, 3.7 times as bright), the lawn seen above it.
        let front = [0.2, 0.06, 0.05];
        let colour = |x, y| match (x, y) {
            (1, 19) => Some(front.map(|c| 3.7 * c)),
            (1, 20..=30) => Some(front),
            _ => None,
        };
        assert_stands(5, colour, 19..=30);
    }

    #[test]
    fn a_foot_by_the_horizon_is_too_far_to_tell() {
        // The horizon at row 4.5; a brown tower rising over it from a foot 2.5 rows below
        // recedes, from 3.5 rows below it stands.
        let brown = [0.3, 0.15, 0.05];
        let tower = |foot: usize| {
            move |x: usize, y: usize| (x == 1 && (2..=foot).contains(&y)).then_some(brown)
        };
        let (work, plain) = recede_with_and_without_the_image(2, tower(7));
        assert_eq!(work, plain);
        assert_stands(2, tower(8), 2..=8);
    }

    #[test]
    fn water_up_to_the_far_shore_recedes() {
        // The right column: a far city in rows 5-7 above water (rows 8-20) on the lawn:
        // flat, below the horizon, no lawn above it.
        let (work, plain) = recede_with_and_without_the_image(5, |x, y| match (x, y) {
            (1, 5..=7) => Some([0.3, 0.3, 0.3]),
            (1, 8..=20) => Some([0.4, 0.5, 0.7]),
            _ => None,
        });
        assert_eq!(work, plain);
    }
}
