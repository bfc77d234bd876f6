//! Left-right photoconsistency of a stereo disparity (Foggy Cityscapes, Sakaridis et al.
//! 2018, sec. 3): a left pixel whose colour differs from the right image's at its match,
//! x − d, by more than a threshold (12/255 of the code values there) is a mismatch the
//! matcher made, and its disparity is unreliable, whatever its neighbours say. A pixel whose
//! match falls outside the right image has no witness and is left alone: on the true
//! disparity of brume's scene, taking those as unreliable dropped the whole band the right
//! camera cannot see (8 % of the frame), all of it right.

use crate::error::{Error, Result};
use crate::io::depth::StereoView;
use crate::io::image::linear_to_srgb;
use crate::raster::{Grid, Orientation, RgbImage};

/// Foggy Cityscapes' threshold: 12 of 255 code values.
pub const DEFAULT_THRESHOLD: f32 = 12.0 / 255.0;

/// The pixels of `image` (linear RGB), the view `disparity` is aligned with (`view`), whose
/// disparity points to a colour of `other`, the pair's other image, that differs by more than
/// `threshold` in some channel's sRGB code value: [`inconsistent_pixels`] for a left view, and
/// for a right view the same check on the mirrored pair (its match lies at x + d in the left
/// image), its verdict mirrored back. Errors: sizes that differ, a threshold outside (0, 1].
pub fn mismatches_of_view(
    image: &RgbImage,
    other: &RgbImage,
    disparity: &Grid<f32>,
    view: StereoView,
    threshold: f32,
) -> Result<Grid<bool>> {
    if !(threshold > 0.0 && threshold <= 1.0) {
        return Err(Error::invalid(
            "threshold",
            threshold,
            "a code value difference in (0, 1] (Foggy Cityscapes: 12/255)",
        ));
    }
    match view {
        StereoView::Left => inconsistent_pixels(image, other, disparity, threshold),
        StereoView::Right => {
            let mirror = Orientation::MirrorLeftRight;
            inconsistent_pixels(
                &image.oriented(mirror),
                &other.oriented(mirror),
                &disparity.oriented(mirror),
                threshold,
            )
            .map(|bad| bad.into_oriented(mirror))
        }
    }
}

/// Whether the pixel in column `x` of a row `width` px wide, of `view`, has a disparity `d`
/// whose match lies inside the other image (at x − d for a left view, x + d for a right
/// view): the pixels the check compares; it leaves the others alone.
pub fn has_match_inside(x: usize, d: f32, width: usize, view: StereoView) -> bool {
    let from_edge = match view {
        StereoView::Left => x,
        StereoView::Right => width - 1 - x,
    };
    d.is_finite() && d > 0.0 && from_edge as f32 >= d
}

/// The pixels of `left` (linear RGB) whose disparity `disparity` (px, left image's; NaN
/// or ≤ 0 where unknown, and pixels whose match is outside the right image, are left
/// alone) points to a colour of `right` that differs
/// by more than `threshold` in some channel's sRGB code value (the right image sampled
/// linearly between its two nearest columns).
pub fn inconsistent_pixels(
    left: &RgbImage,
    right: &RgbImage,
    disparity: &Grid<f32>,
    threshold: f32,
) -> Result<Grid<bool>> {
    let (w, h) = (left.width(), left.height());
    for (what, size) in [
        ("right image", (right.width(), right.height())),
        ("disparity", (disparity.width(), disparity.height())),
    ] {
        if size != (w, h) {
            return Err(Error::size_mismatch(
                "left image",
                (w, h),
                what,
                (size.0, size.1),
            ));
        }
    }
    let encode = |p: [f32; 3]| p.map(|v| linear_to_srgb(v.clamp(0.0, 1.0)));
    let left_codes = left.map(|p| encode(*p));
    let right_codes = right.map(|p| encode(*p));
    Ok(Grid::from_fn(w, h, |x, y| {
        let d = *disparity.get(x, y);
        if !has_match_inside(x, d, w, StereoView::Left) {
            return false;
        }
        let xr = x as f32 - d;
        let x0 = xr.floor() as usize;
        let x1 = (x0 + 1).min(w - 1);
        let t = xr - x0 as f32;
        let (a, b) = (right_codes.get(x0, y), right_codes.get(x1, y));
        let l = left_codes.get(x, y);
        (0..3).any(|c| (l[c] - (a[c] + (b[c] - a[c]) * t)).abs() > threshold)
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A textured row seen by two cameras 4 px apart: the true disparity passes, a wrong
    /// one fails, a match outside the right image fails, unknown disparity is left alone.
    #[test]
    fn true_matches_pass_and_wrong_ones_fail() {
        let (w, h) = (40, 3);
        let texture = |u: f32| {
            let v = 0.5 + 0.4 * (u * 0.9).sin();
            [v, v * 0.8, 0.3]
        };
        let left = Grid::from_fn(w, h, |x, _| texture(x as f32));
        let right = Grid::from_fn(w, h, |x, _| texture(x as f32 + 4.0));
        let mut disparity = Grid::filled(w, h, 4.0f32);
        *disparity.get_mut(20, 1) = 9.0; // a mismatch
        *disparity.get_mut(21, 1) = f32::NAN;
        let bad = inconsistent_pixels(&left, &right, &disparity, DEFAULT_THRESHOLD).unwrap();
        assert!(*bad.get(20, 1), "the wrong disparity");
        assert!(!*bad.get(21, 1), "unknown is left alone");
        assert!(!*bad.get(2, 0), "x − d < 0 has no witness: left alone");
        let wrong = (4..w)
            .filter(|&x| x != 20)
            .filter(|&x| *bad.get(x, 1))
            .count();
        assert_eq!(wrong, 0, "true matches pass");
    }

    /// A right view's disparity points to x + d in the left image: the true disparity
    /// passes as a right view's and fails as a left view's; a wrong one fails; a threshold
    /// outside (0, 1] is refused by name.
    #[test]
    fn a_right_view_is_checked_against_the_left_image_at_x_plus_d() {
        let (w, h) = (40, 2);
        let texture = |u: f32| {
            let v = 0.5 + 0.4 * (u * 0.7).sin();
            [v, 0.2, v * 0.5]
        };
        let right = Grid::from_fn(w, h, |x, _| texture(x as f32));
        let left = Grid::from_fn(w, h, |x, _| texture(x as f32 - 3.0));
        let mut disparity = Grid::filled(w, h, 3.0f32);
        *disparity.get_mut(10, 0) = 7.0;
        let check =
            |view| mismatches_of_view(&right, &left, &disparity, view, DEFAULT_THRESHOLD).unwrap();
        let as_right = check(StereoView::Right);
        assert!(*as_right.get(10, 0), "the wrong disparity");
        let wrong = (0..w - 3)
            .filter(|&x| x != 10 && *as_right.get(x, 0))
            .count();
        assert_eq!(wrong, 0, "true matches pass");
        assert!(
            !*as_right.get(w - 2, 1),
            "x + d past the border has no witness"
        );
        let as_left = check(StereoView::Left);
        let flagged = (3..w).filter(|&x| *as_left.get(x, 1)).count();
        assert!(flagged > 20, "read as a left view, {flagged} px flagged");
        for threshold in [0.0, -1.0, 1.5, f32::NAN] {
            let err = mismatches_of_view(&right, &left, &disparity, StereoView::Right, threshold);
            assert!(err.unwrap_err().to_string().contains("threshold"));
        }
    }

    /// A match inside the other image: at x − d ≥ 0 for a left view, x + d ≤ w − 1 for a
    /// right one; unknown and non-positive disparities have none.
    #[test]
    fn a_match_lies_inside_the_other_image_or_not() {
        let w = 10;
        assert!(has_match_inside(3, 3.0, w, StereoView::Left));
        assert!(!has_match_inside(3, 3.5, w, StereoView::Left));
        assert!(has_match_inside(6, 3.0, w, StereoView::Right));
        assert!(!has_match_inside(7, 3.0, w, StereoView::Right));
        for d in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            assert!(!has_match_inside(5, d, w, StereoView::Left), "{d}");
            assert!(!has_match_inside(5, d, w, StereoView::Right), "{d}");
        }
    }
}
