//! What the range says about each pixel, for the image-guided sky detector: unknown,
//! noise its neighbours do not back up, beyond the far-outlier cut, or confident.

use rayon::prelude::*;

/// Relative tolerance within which two neighbouring ranges agree.
const AGREE: f32 = 0.05;

/// What the range says about one pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum RangeClass {
    /// No value.
    Unknown,
    /// A value its neighbours do not back up: noise.
    Unsupported,
    /// A value above the far-outlier cut.
    Far,
    /// A measured, backed-up value: not sky.
    Confident,
}

/// The range class of every pixel of `work` (NaN = unknown); `far_cut` as from
/// [`super::outliers::far_cut`].
pub(crate) fn range_classes(
    work: &[f32],
    width: usize,
    height: usize,
    far_cut: Option<f32>,
) -> Vec<RangeClass> {
    let mut classes = vec![RangeClass::Unknown; work.len()];
    // Row by row: each pixel's column and row without a division.
    classes
        .par_chunks_mut(width)
        .enumerate()
        .for_each(|(y, row)| {
            let range = Neighbourhood {
                work,
                width,
                height,
            };
            for (x, class) in row.iter_mut().enumerate() {
                *class = range.class(x, y, far_cut);
            }
        });
    classes
}

/// The range map, read at a pixel's neighbours.
struct Neighbourhood<'a> {
    work: &'a [f32],
    width: usize,
    height: usize,
}

impl Neighbourhood<'_> {
    /// The known value `dx, dy` from `(x, y)`, if in the map.
    #[inline]
    fn at(&self, x: usize, y: usize, dx: isize, dy: isize) -> Option<f32> {
        let nx = x.checked_add_signed(dx).filter(|&nx| nx < self.width)?;
        let ny = y.checked_add_signed(dy).filter(|&ny| ny < self.height)?;
        let v = self.work[ny * self.width + nx];
        v.is_finite().then_some(v)
    }

    /// The class of the pixel `(x, y)`.
    fn class(&self, x: usize, y: usize, far_cut: Option<f32>) -> RangeClass {
        let r = self.work[y * self.width + x];
        if !r.is_finite() {
            return RangeClass::Unknown;
        }
        if far_cut.is_some_and(|c| r > c) {
            return RangeClass::Far;
        }
        let (mut known, mut agree) = (0, 0);
        for (dx, dy) in NEIGHBOURS8 {
            if let Some(v) = self.at(x, y, dx, dy) {
                known += 1;
                agree += usize::from((v - r).abs() <= AGREE * r.abs());
            }
        }
        if (agree >= 2 && 2 * agree >= known) || self.on_a_slope(x, y, r) {
            RangeClass::Confident
        } else {
            RangeClass::Unsupported
        }
    }

    /// Whether the range `r` at `(x, y)` continues a surface that its neighbours on a line
    /// through it span: the mean of two opposite known neighbours within [`AGREE`] of it,
    /// on at least two of the four lines (a row, a column, the diagonals). Ground or water
    /// seen at a grazing angle changes range by more than 5 % from row to row near the
    /// horizon, so its vertical neighbours disagree with it, yet it lies between them; a
    /// matcher's noise does not.
    fn on_a_slope(&self, x: usize, y: usize, r: f32) -> bool {
        let lines = [(1, 0), (0, 1), (1, 1), (1, -1)]
            .into_iter()
            .filter(
                |&(dx, dy)| match (self.at(x, y, dx, dy), self.at(x, y, -dx, -dy)) {
                    (Some(a), Some(b)) => ((a + b) / 2.0 - r).abs() <= AGREE * r.abs(),
                    _ => false,
                },
            )
            .count();
        lines >= 2
    }
}

/// The 8 neighbours as (dx, dy).
const NEIGHBOURS8: [(isize, isize); 8] = [
    (-1, -1),
    (0, -1),
    (1, -1),
    (-1, 0),
    (1, 0),
    (-1, 1),
    (0, 1),
    (1, 1),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn range_classes_tell_noise_from_surfaces() {
        let n = f32::NAN;
        #[rustfmt::skip]
        let m = vec![
            10.0, 10.1, 10.2, n,
            10.0, 10.1, 500.0, n,
            10.0, 10.1, 10.2, 77.0,
        ];
        let c = range_classes(&m, 4, 3, Some(100.0));
        assert_eq!(c[0], RangeClass::Confident);
        assert_eq!(c[3], RangeClass::Unknown);
        assert_eq!(c[6], RangeClass::Far);
        assert_eq!(c[11], RangeClass::Unsupported, "no neighbour agrees");
    }

    /// Water at a grazing angle: range grows by 10 % a row, so no vertical neighbour
    /// agrees within 5 %, but each row lies between its neighbours: a surface, not noise.
    /// A spike on it is still noise.
    #[test]
    fn a_grazing_surface_is_supported_and_a_spike_on_it_is_not() {
        let (w, h) = (5, 5);
        let mut m: Vec<f32> = (0..w * h)
            .map(|p| 100.0 * 1.1f32.powi((p / w) as i32))
            .collect();
        let c = range_classes(&m, w, h, None);
        assert_eq!(c[2 * w + 2], RangeClass::Confident);
        m[2 * w + 2] *= 1.3;
        let c = range_classes(&m, w, h, None);
        assert_eq!(c[2 * w + 2], RangeClass::Unsupported);
    }
}
