//! The scene beyond the sensor's reach: unknown pixels joined to the sky that the image
//! shows are not sky (see the module docs of [`crate::prep`], step 4).

use super::colour_guide::ColourGuide;
use super::components::{flood, label_mask};
use super::horizon;
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
/// A `scanned` map's (a LiDAR's, `scan.rs`) known pixels of the region's material below it
/// count too: above its top line the scanner does not look, and a near tower's face
/// measured below the line goes on up.
pub(crate) fn take_out_reached_in_part(
    work: &[f32],
    sky: &[bool],
    beyond: &mut Vec<usize>,
    guide: &ColourGuide,
    (w, h): (usize, usize),
    scanned: bool,
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
        let reached = |p: usize, q: usize| known(q) && one_material(guide, p, q);
        let under_reached = pixels
            .iter()
            .map(|&p| p as usize)
            .filter(|&p| {
                (p >= w && reached(p, p - w)) || (scanned && p + w < w * h && reached(p, p + w))
            })
            .count();
        let columns = c.bbox[2] + 1 - c.bbox[0];
        if under_reached as f64 >= MIN_REACHED_SHARE * columns as f64 {
            pixels.iter().for_each(|&p| state[p as usize] = 0);
        }
    }
    beyond.retain(|&p| state[p] != 0);
}

/// One vertical run of pixels (beyond the reach, or a gap between scan lines): column
/// `x`, rows `top..end`.
pub(super) struct Run {
    pub(super) x: usize,
    pub(super) top: usize,
    pub(super) end: usize,
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
/// the column's horizon ([`horizon::horizon_rows`]: the lowest row the sky reaching the
/// top row comes down to, along the tilt of the reach's contour on the ground where that
/// tells it, else level and nearby; between far towers), and is `s_max` above it; a run
/// with the sky (or the image's bottom border) below it is `s_max`. The horizon is shared
/// by neighbouring columns so that the ground below a far tower recedes as the ground
/// beside it (a column's own skyline would draw the tower's ghost down to the ground);
/// without one (no sky above any run nearby, or not above the run), the run recedes from
/// its lower end to its upper end. With the image, a run standing on something nearer than
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
    let reach = Reach::new(&runs, (work, sky), (w, h), r_max, guide);
    let contour: Vec<(usize, f64)> = reach.columns.iter().map(|c| (c.0, c.1)).collect();
    let horizon = horizon::horizon_rows(
        &skyline(&runs, |r| r.top > 0 && open_sky[(r.top - 1) * w + r.x], w),
        horizon::tilt_of_contour(&contour, w),
    );
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
        let on_something = !below_sky
            && (work[r.end * w + r.x] < AT_THE_REACH * r_max || reach.stands_on_something(r));
        if let Some(guide) = guide.filter(|_| on_something) {
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
    let Some(guide) = guide else {
        return Vec::new();
    };
    let mut held = stand_upright(work, (&runs, &reach), &horizon, sky, (w, h), guide);
    spread_along_rows(work, &mut held, beyond, w, guide);
    held
}

/// What stands is one object across its columns: a pixel beyond the reach beside a held
/// one, of its material, is held at its range too, along the row as far as the material
/// goes (a tower's edge columns, where the walk up the column met a blend or a box in
/// front of its foot, would otherwise fade into the sky beside the rest of it).
fn spread_along_rows(
    work: &mut [f32],
    held: &mut Vec<usize>,
    beyond: &[bool],
    w: usize,
    guide: &ColourGuide,
) {
    let mut is_held = vec![false; work.len()];
    held.iter().for_each(|&p| is_held[p] = true);
    let mut frontier = held.clone();
    for _ in 0..columns_in(SPREAD_WIDTH, w) {
        let mut next = Vec::new();
        for p in frontier {
            let (x, v) = (p % w, work[p]);
            for q in [(x > 0).then(|| p - 1), (x + 1 < w).then_some(p + 1)]
                .into_iter()
                .flatten()
            {
                if beyond[q] && !is_held[q] && work[q] > v && one_material(guide, q, p) {
                    work[q] = v;
                    is_held[q] = true;
                    next.push(q);
                }
            }
        }
        held.extend_from_slice(&next);
        frontier = next;
    }
}

/// How far [`spread_along_rows`] carries a held range beside the columns whose walk held
/// it, as a fraction of the image's width.
const SPREAD_WIDTH: f64 = 1.0 / 16.0;

/// Least share of `Rmax` that the scene just below a run has where the run meets the
/// ground at the sensor's reach (the noise of a phone's depth is a few per cent there);
/// a run meeting something nearer stands on it (a box's top edge, a pole's).
const AT_THE_REACH: f32 = 0.8;

/// Half the width of the window of columns whose contours at the reach a column's is
/// checked against, as a fraction of the image's width (wider than a box near the reach).
const CONTOUR_WINDOW: f64 = 1.0 / 8.0;

/// Most rows of the depth's grid that a column's contour at the reach may lie above the
/// third quartile of the contours in its window (the lower ones): the noise at the reach
/// makes the ground's contour ragged by a row or so; a box standing just within the reach
/// raises it by its height above the ground there.
const MAX_CONTOUR_RISE: f64 = 2.0;

/// The ground at the sensor's reach: the columns whose lowest run meets the scene at the
/// reach (at least [`AT_THE_REACH`] of `Rmax`) on the ground, left to right, each with its
/// contour (the boundary row above the scene) and the scene's pixel below it; with the
/// image, each column's ground colours. A column whose contour rises more than
/// [`MAX_CONTOUR_RISE`] above those round it meets something standing at the reach (a box
/// just within it), not the ground.
struct Reach {
    columns: Vec<(usize, f64, usize)>,
    raised: Vec<Option<usize>>,
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
        let at_reach: Vec<(usize, f64, usize)> = (lowest.iter().flatten())
            .map(|r| (r.x, r.end as f64 - 0.5, r.end * w + r.x))
            .filter(|&(_, _, below)| work[below] >= AT_THE_REACH * r_max)
            .collect();
        let half = columns_in(CONTOUR_WINDOW, w);
        let mut raised = vec![None; w];
        let mut columns = Vec::with_capacity(at_reach.len());
        for (i, &(x, contour, below)) in at_reach.iter().enumerate() {
            let from = at_reach[..i].partition_point(|c| c.0 + half < x);
            let to = i + at_reach[i..].partition_point(|c| c.0 <= x + half);
            let mut near: Vec<f64> = at_reach[from..to].iter().map(|c| c.1).collect();
            near.sort_by(f64::total_cmp);
            if contour < near[(3 * near.len()) / 4] - MAX_CONTOUR_RISE {
                raised[x] = Some(below / w);
            } else {
                columns.push((x, contour, below));
            }
        }
        let mut reach = Reach {
            columns,
            raised,
            ground: Vec::new(),
        };
        if let Some(guide) = guide {
            let half = columns_in(GROUND_WINDOW, w);
            reach.ground = (0..w).map(|x| reach.ground_near(x, half, guide)).collect();
        }
        reach
    }

    /// Whether run `r` is the lowest of its column and meets something standing at the
    /// reach, not the ground (its contour rises above those round it).
    fn stands_on_something(&self, r: &Run) -> bool {
        self.raised[r.x] == Some(r.end)
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
/// column, as the ground's colour drifts with distance) is ground; the pixels of another
/// material just above ground are an object standing there, as far as its material goes
/// on, and take the range of its lowest pixel where that is nearer, if it is upright: it
/// rises above the horizon, or the ground is seen again above it (or above its top face,
/// which, seen from above, may be lit far brighter). A flat surface of another material
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
                && shaded_alike(guide, at(top - 1), at(top), FACE_LIGHTING)
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

/// How far an object's top face may differ from its front: [`MAX_FACE_SHADING`] in
/// brightness, and 1.5 times [`CHROMA_TOLERANCE`] in chromaticity (a face in the sun's
/// light and one in the sky's differ in tint: 0.042 on the phone evaluation's grey box).
const FACE_LIGHTING: (f32, f32) = (1.5 * CHROMA_TOLERANCE, MAX_FACE_SHADING);

/// Whether pixel `m`'s chromaticity lies between `a`'s and `b`'s in every channel (within
/// a tenth of their difference): a blend of the two, as an edge resampled to a coarser
/// grid is (a mixture's chromaticity lies between its parts'; its brightness need not,
/// where the object's shadow falls at its foot).
fn blends(guide: &ColourGuide, a: usize, m: usize, b: usize) -> bool {
    let chroma = |p: usize| shares(guide.colour_at(p));
    let (a, m, b) = (chroma(a), chroma(m), chroma(b));
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
    shaded_alike(guide, p, q, (CHROMA_TOLERANCE, MAX_SHADING))
}

/// Whether pixels `p` and `q` have the same chromaticity (each channel's share of the sum
/// within `tolerance`) and brightnesses within a factor `max_shading`.
fn shaded_alike(
    guide: &ColourGuide,
    p: usize,
    q: usize,
    (tolerance, max_shading): (f32, f32),
) -> bool {
    let (a, b) = (guide.colour_at(p), guide.colour_at(q));
    let (sa, sb) = (a.iter().sum::<f32>(), b.iter().sum::<f32>());
    let floor = 1e-4;
    if !(sa > floor && sb > floor) || sa.max(sb) > max_shading * sa.min(sb) {
        return false;
    }
    let (a, b) = (shares(a), shares(b));
    (0..3).all(|c| (a[c] - b[c]).abs() <= tolerance)
}

/// Each channel's share of the sum: a colour's chromaticity, whatever its brightness.
fn shares(c: [f32; 3]) -> [f32; 3] {
    let sum = (c[0] + c[1] + c[2]).max(1e-6);
    c.map(|v| v / sum)
}

/// The columns in a `share` of a frame `w` wide, at least one.
pub(super) fn columns_in(share: f64, w: usize) -> usize {
    ((share * w as f64).ceil() as usize).max(1)
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
pub(super) fn runs_of(mask: &[bool], w: usize, h: usize) -> Vec<Run> {
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

/// Per column, the first row of the lowest run that `under_sky` accepts (under the sky
/// that reaches the top row).
fn skyline(runs: &[Run], under_sky: impl Fn(&Run) -> bool, w: usize) -> Vec<Option<usize>> {
    let mut skyline: Vec<Option<usize>> = vec![None; w];
    for r in runs.iter().filter(|r| under_sky(r)) {
        skyline[r.x] = skyline[r.x].max(Some(r.top));
    }
    skyline
}

#[cfg(test)]
#[path = "reach_tests.rs"]
mod tests;
