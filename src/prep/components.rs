//! Linear-time labelling of the 4-connected components of unknown (non-finite) pixels.
//!
//! One scan over the image starts a breadth-first flood fill at every unknown pixel not yet
//! visited. The queue of each flood fill *is* the component's pixel list, appended to one
//! shared vector, so the result is a compact list of lists (CSR layout) and no per-pixel
//! label image is needed: a pixel is marked visited by writing `+inf` into the working copy
//! of the range map (which is later overwritten by the fill anyway). Every pixel is pushed
//! once and looks at its four neighbours once: O(width x height).

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
            let comp = flood(width, height, seed, &mut out.pixels, |q| {
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

/// Labels the 4-connected components of the pixels where `mask` is true (same layout and
/// order as [`label_unknown`]), with a visited bitmap instead of overwriting the input.
pub(crate) fn label_mask(mask: &[bool], width: usize, height: usize) -> Components {
    assert_eq!(mask.len(), width * height);
    let mut seen = vec![false; mask.len()];
    let mut out = Components::default();
    for seed in 0..mask.len() {
        if mask[seed] && !seen[seed] {
            let comp = flood(width, height, seed, &mut out.pixels, |q| {
                let take = mask[q] && !seen[q];
                seen[q] |= take;
                take
            });
            out.list.push(comp);
        }
    }
    out
}

/// Breadth-first flood fill from `seed`, appending the pixels to `pixels`. `take(q)` says
/// whether pixel `q` joins the component, and marks it visited when it does; it is asked
/// once for the seed, which must join.
fn flood(
    width: usize,
    height: usize,
    seed: usize,
    pixels: &mut Vec<u32>,
    mut take: impl FnMut(usize) -> bool,
) -> Component {
    let start = pixels.len();
    let joined = take(seed);
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
            if take(q) {
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
