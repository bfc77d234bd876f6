//! Linear-time labelling of the 4-connected components of unknown (non-finite) pixels.
//!
//! One scan over the image starts a breadth-first flood fill at every unknown pixel not yet
//! visited. The queue of each flood fill *is* the component's pixel list, appended to one
//! shared vector, so the result is a compact list of lists (CSR layout) and no per-pixel
//! label image is needed: a pixel is marked visited by writing `+inf` into the working copy
//! of the range map (which is later overwritten by the fill anyway). Every pixel is pushed
//! once and looks at its four neighbours once: O(width x height). The hole filling reads
//! its components' pixels in that breadth-first order.
//!
//! A boolean mask's components ([`label_mask`]: the sky, the gaps in it) are labelled by
//! runs instead, with union-find: the same components in the same order, faster on large
//! regions, their pixels in raster order.

/// One 4-connected component of unknown pixels.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Component {
    /// Offset of its first pixel in [`Components::pixels`].
    pub start: usize,
    /// Number of pixels.
    pub len: usize,
    /// Number of its pixels in row 0 (the top row).
    pub top_pixels: usize,
    /// Bounding box, inclusive: `[x_min, y_min, x_max, y_max]`.
    pub bbox: [usize; 4],
}

impl Component {
    /// Area of the bounding box in pixels.
    pub fn bbox_area(&self) -> usize {
        (self.bbox[2] - self.bbox[0] + 1) * (self.bbox[3] - self.bbox[1] + 1)
    }

    /// Whether it has a pixel in the bottom row of an image `height` rows high. Never for a
    /// one-row image, whose only row is the top one too.
    pub fn reaches_bottom(&self, height: usize) -> bool {
        height > 1 && self.bbox[3] + 1 == height
    }
}

/// All components of unknown pixels of one map.
#[derive(Clone, Debug, Default)]
pub(crate) struct Components {
    /// Linear pixel indices (`y * width + x`), grouped by component.
    pub pixels: Vec<u32>,
    /// The components, in the order their first pixel appears in a raster scan.
    pub list: Vec<Component>,
}

impl Components {
    /// The pixel indices of component `c`.
    pub fn pixels_of(&self, c: &Component) -> &[u32] {
        &self.pixels[c.start..c.start + c.len]
    }
}

/// Labels the NaN pixels of `work` (a `width x height` map where unknown = NaN and every
/// other value is finite). Every NaN pixel is overwritten with `+inf` (visited).
pub(crate) fn label_unknown(work: &mut [f32], width: usize, height: usize) -> Components {
    assert_eq!(work.len(), width * height);
    let mut out = Components::default();
    for seed in 0..work.len() {
        if work[seed].is_nan() {
            let comp = flood(width, height, seed, &mut out.pixels, |_, q| {
                let take = work[q].is_nan();
                if take {
                    work[q] = f32::INFINITY;
                }
                take
            });
            out.list.push(comp);
        }
    }
    out
}

/// Labels the 4-connected components of the pixels where `mask` is true: the components in
/// the order of [`label_unknown`] (by their first pixel in a raster scan), each one's
/// pixels in raster order.
///
/// By runs rather than a flood fill (its callers only ask which pixels, how many and
/// where): each row's runs of true pixels are joined to the runs they touch in the row
/// above (union-find over runs), then the pixels are listed run by run. A 2048x1024 sky
/// is a few thousand runs instead of a million queued pixels.
pub(crate) fn label_mask(mask: &[bool], width: usize, height: usize) -> Components {
    assert_eq!(mask.len(), width * height);
    let runs = mask_runs(mask, width, height);
    let mut parent: Vec<usize> = (0..runs.len()).collect();
    // The runs of the row above (`above`), walked once per row: both rows' runs are in
    // x order, so the first one that can touch a run never moves back.
    let (mut above, mut row_start) = (0..0, 0);
    for (i, run) in runs.iter().enumerate() {
        if i > 0 && runs[i - 1].y != run.y {
            let previous = row_start..i;
            above = if runs[row_start].y + 1 == run.y {
                previous
            } else {
                i..i
            };
            row_start = i;
        }
        while above.start < above.end && runs[above.start].x1 <= run.x0 {
            above.start += 1;
        }
        let mut j = above.start;
        while j < above.end && runs[j].x0 < run.x1 {
            union(&mut parent, i, j);
            j += 1;
        }
        // The last run touched may touch the next run of this row too.
        above.start = j.saturating_sub(1).max(above.start);
    }
    let mut out = Components::default();
    let mut index_of_root = vec![usize::MAX; runs.len()];
    let mut component_of_run = Vec::with_capacity(runs.len());
    for (i, run) in runs.iter().enumerate() {
        let root = find(&mut parent, i);
        if index_of_root[root] == usize::MAX {
            index_of_root[root] = out.list.len();
            out.list.push(Component {
                start: 0,
                len: 0,
                top_pixels: 0,
                bbox: [usize::MAX, usize::MAX, 0, 0],
            });
        }
        let c = &mut out.list[index_of_root[root]];
        c.len += run.x1 - run.x0;
        c.top_pixels += if run.y == 0 { run.x1 - run.x0 } else { 0 };
        c.bbox = [
            c.bbox[0].min(run.x0),
            c.bbox[1].min(run.y),
            c.bbox[2].max(run.x1 - 1),
            c.bbox[3].max(run.y),
        ];
        component_of_run.push(index_of_root[root]);
    }
    let mut next = 0;
    for c in &mut out.list {
        c.start = next;
        next += c.len;
    }
    let mut fill: Vec<usize> = out.list.iter().map(|c| c.start).collect();
    out.pixels = vec![0; next];
    for (run, &c) in runs.iter().zip(&component_of_run) {
        for x in run.x0..run.x1 {
            out.pixels[fill[c]] = (run.y * width + x) as u32;
            fill[c] += 1;
        }
    }
    out
}

/// A horizontal run of true mask pixels: row `y`, columns `x0..x1`.
struct Run {
    y: usize,
    x0: usize,
    x1: usize,
}

/// The runs of true pixels of `mask`, in raster order.
fn mask_runs(mask: &[bool], width: usize, height: usize) -> Vec<Run> {
    let mut runs = Vec::new();
    for (y, row) in mask.chunks_exact(width.max(1)).take(height).enumerate() {
        let mut x = 0;
        while x < width {
            if !row[x] {
                x += 1;
                continue;
            }
            let x0 = x;
            while x < width && row[x] {
                x += 1;
            }
            runs.push(Run { y, x0, x1: x });
        }
    }
    runs
}

/// The root of `i`'s set, halving the path on the way.
fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// Joins the sets of `a` and `b` under the smaller root, so that a set's root is its
/// first run in raster order.
fn union(parent: &mut [usize], a: usize, b: usize) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    let (lo, hi) = (ra.min(rb), ra.max(rb));
    parent[hi] = lo;
}

/// Breadth-first flood fill from `seed`, appending the pixels to `pixels`. `take(p, q)`
/// says whether pixel `q`, reached from its 4-neighbour `p` in the component, joins it, and
/// marks it visited when it does; it is asked once for the seed as `take(seed, seed)`,
/// which must join.
pub(crate) fn flood(
    width: usize,
    height: usize,
    seed: usize,
    pixels: &mut Vec<u32>,
    mut take: impl FnMut(usize, usize) -> bool,
) -> Component {
    let start = pixels.len();
    let joined = take(seed, seed);
    debug_assert!(joined, "the seed of a flood fill must join it");
    pixels.push(seed as u32);
    let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
    let mut top_pixels = 0;
    let mut head = start;
    while head < pixels.len() {
        let p = pixels[head] as usize;
        head += 1;
        let (x, y) = (p % width, p / width);
        (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
        top_pixels += usize::from(y == 0);
        for q in neighbours4(p, x, y, width, height).into_iter().flatten() {
            if take(p, q) {
                pixels.push(q as u32);
            }
        }
    }
    Component {
        start,
        len: pixels.len() - start,
        top_pixels,
        bbox: [x0, y0, x1, y1],
    }
}

/// The in-image 4-neighbours of pixel `p = y * width + x` (left, right, up, down).
#[inline]
pub(crate) fn neighbours4(
    p: usize,
    x: usize,
    y: usize,
    width: usize,
    height: usize,
) -> [Option<usize>; 4] {
    [
        (x > 0).then(|| p - 1),
        (x + 1 < width).then(|| p + 1),
        (y > 0).then(|| p - width),
        (y + 1 < height).then(|| p + width),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_components_and_bbox() {
        let n = f32::NAN;
        #[rustfmt::skip]
        let mut m = vec![
            n, n, 1.0, 1.0,
            1.0, n, 1.0, n,
            1.0, 1.0, 1.0, n,
        ];
        let c = label_unknown(&mut m, 4, 3);
        assert_eq!(c.list.len(), 2);
        assert_eq!(c.list[0].len, 3);
        assert_eq!(c.list[0].top_pixels, 2);
        assert_eq!(c.list[0].bbox, [0, 0, 1, 1]);
        assert_eq!(c.list[1].len, 2);
        assert_eq!(c.list[1].bbox, [3, 1, 3, 2]);
        assert!(m.iter().all(|v| !v.is_nan()));
    }

    /// The flood-fill labelling the runs replaced, as the oracle: the same components in
    /// the same order, the same pixels (the runs list them in raster order).
    fn label_mask_by_flood(mask: &[bool], width: usize, height: usize) -> Components {
        let mut seen = vec![false; mask.len()];
        let mut out = Components::default();
        for seed in 0..mask.len() {
            if mask[seed] && !seen[seed] {
                let comp = flood(width, height, seed, &mut out.pixels, |_, q| {
                    let take = mask[q] && !seen[q];
                    seen[q] |= take;
                    take
                });
                out.list.push(comp);
            }
        }
        out
    }

    #[test]
    fn runs_label_as_the_flood_fill_does() {
        let mut rng = crate::rng::SplitMix64::new(11);
        for case in 0..300 {
            let (w, h) = (1 + case % 23, 1 + case / 7 % 19);
            // From sparse specks to nearly full, with long runs and U shapes among them.
            let density = (case % 10) as f64 / 9.0;
            let mask: Vec<bool> = (0..w * h).map(|_| rng.unit() < density).collect();
            let (runs, flood) = (label_mask(&mask, w, h), label_mask_by_flood(&mask, w, h));
            assert_eq!(runs.list.len(), flood.list.len(), "case {case}");
            for (a, b) in runs.list.iter().zip(&flood.list) {
                assert_eq!((a.len, a.top_pixels, a.bbox), (b.len, b.top_pixels, b.bbox));
                let mut pixels = flood.pixels_of(b).to_vec();
                pixels.sort_unstable();
                assert_eq!(runs.pixels_of(a), pixels.as_slice(), "case {case}");
            }
        }
        // A U: two runs that meet only in the last row, the later one's root joined late.
        #[rustfmt::skip]
        let u = [
            true, false, true,
            true, false, true,
            true, true, true,
        ];
        assert_eq!(label_mask(&u, 3, 3).list.len(), 1);
    }

    #[test]
    fn mask_components_match_unknown_components() {
        #[rustfmt::skip]
        let mask = vec![
            true, true, false, false,
            false, true, false, true,
            false, false, false, true,
        ];
        let c = label_mask(&mask, 4, 3);
        assert_eq!(c.list.len(), 2);
        assert_eq!((c.list[0].len, c.list[0].top_pixels), (3, 2));
        assert_eq!(c.list[1].bbox, [3, 1, 3, 2]);
        assert_eq!(c.pixels_of(&c.list[1]), &[7, 11]);
    }
}
