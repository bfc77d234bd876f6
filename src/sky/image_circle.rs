//! The image circle of a circular fisheye photo: a camera with a circular fisheye lens
//! writes a rectangular frame (6000 x 4000, say) with the sky's disc in its middle and
//! black around it, where the estimator takes a square whose inscribed circle is the
//! horizon. [`find_image_circle`] finds the disc's bounding square from the black
//! around it, so that such a photo is estimated as it comes from the camera.

use crate::error::{Error, Result};
use crate::raster::RgbImage;

/// A pixel brighter than this (linear, largest channel) is part of the picture: a lens's
/// black surround stays below it (about code 13 in 8-bit sRGB), with JPEG's noise, while
/// the darkest sky and the obstacles at the horizon are above it.
pub const SURROUND_MAX: f32 = 0.004;

/// A row or column holds the picture where at least this many of its pixels are above
/// [`SURROUND_MAX`]: a hot pixel or two in the surround do not widen the disc.
const MIN_PICTURE_PIXELS: usize = 3;

/// How much the picture's bounding box may differ in width and height, as a share of the
/// larger, for it to be a disc.
const ROUND_TOLERANCE: f64 = 0.03;

/// Where a fisheye's image circle lies in its frame: the square `side` px wide whose
/// top-left corner is (`x`, `y`), the circle inscribed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct ImageCircle {
    /// Left column of the square.
    pub x: usize,
    /// Top row of the square.
    pub y: usize,
    /// Side of the square, px.
    pub side: usize,
}

impl ImageCircle {
    /// The square of the frame `image` holding the circle.
    pub fn crop(&self, image: &RgbImage) -> RgbImage {
        image.crop(self.x, self.y, self.side, self.side)
    }
}

/// The image circle of the non-square fisheye frame `image` (named `name` in errors): the
/// bounding box of the pixels above [`SURROUND_MAX`], which must be as wide as it is
/// tall (within 3 %) and lie inside the frame; the square is the box's larger side,
/// centred on it. Errors: no picture, or one that is not a disc (a rectangular photo, a
/// full-frame fisheye, a disc cut by the frame's edges), saying to crop it by hand.
pub fn find_image_circle(image: &RgbImage, name: &str) -> Result<ImageCircle> {
    let (w, h) = (image.width(), image.height());
    let refuse = |what: String| {
        Error::format(
            name,
            format!(
                "is {w}x{h}: a fisheye sky image must be square with the horizon circle \
                 inscribed, or a circular fisheye's frame with black around its image \
                 circle, and {what} (crop it to the circle's bounding square)"
            ),
        )
    };
    if image.is_empty() {
        return Err(refuse("it is empty".into()));
    }
    let mut rows = vec![0usize; h];
    let mut columns = vec![0usize; w];
    for (y, row) in image.as_slice().chunks_exact(w).enumerate() {
        for (x, p) in row.iter().enumerate() {
            if p[0].max(p[1]).max(p[2]) > SURROUND_MAX {
                rows[y] += 1;
                columns[x] += 1;
            }
        }
    }
    let extent = |counts: &[usize]| {
        let first = counts.iter().position(|&n| n >= MIN_PICTURE_PIXELS)?;
        let last = counts.iter().rposition(|&n| n >= MIN_PICTURE_PIXELS)?;
        Some((first, last + 1 - first))
    };
    let (Some((x0, bw)), Some((y0, bh))) = (extent(&columns), extent(&rows)) else {
        return Err(refuse("every pixel is black".into()));
    };
    let side = bw.max(bh);
    if (bw.abs_diff(bh) as f64) > ROUND_TOLERANCE * side as f64 {
        return Err(refuse(format!("its picture is {bw}x{bh} px, not a disc")));
    }
    // The square centred on the box, its centre at the box's (in doubled pixels).
    let (cx2, cy2) = (2 * x0 + bw, 2 * y0 + bh);
    let (x, y) = (cx2.checked_sub(side), cy2.checked_sub(side));
    match (x.map(|x| x / 2), y.map(|y| y / 2)) {
        (Some(x), Some(y)) if x + side <= w && y + side <= h => Ok(ImageCircle { x, y, side }),
        _ => Err(refuse(format!(
            "its disc ({side} px wide at {}, {}) is cut by the frame's edges",
            cx2 / 2,
            cy2 / 2
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::Grid;

    /// A disc of radius `r` centred at (cx, cy) in a black `w x h` frame.
    fn disc(w: usize, h: usize, cx: f64, cy: f64, r: f64) -> RgbImage {
        Grid::from_fn(w, h, |x, y| {
            let (dx, dy) = (x as f64 + 0.5 - cx, y as f64 + 0.5 - cy);
            if dx * dx + dy * dy <= r * r {
                [0.2, 0.3, 0.5]
            } else {
                [0.001; 3]
            }
        })
    }

    #[test]
    fn a_disc_in_a_black_frame_is_found() {
        let found = find_image_circle(&disc(300, 200, 160.0, 100.0, 90.0), "f").unwrap();
        assert_eq!(
            found,
            ImageCircle {
                x: 70,
                y: 10,
                side: 180
            }
        );
        // Hot pixels in the surround change nothing.
        let mut image = disc(300, 200, 160.0, 100.0, 90.0);
        *image.get_mut(2, 2) = [1.0; 3];
        *image.get_mut(297, 190) = [1.0; 3];
        assert_eq!(find_image_circle(&image, "f").unwrap(), found);
    }

    #[test]
    fn pictures_that_are_not_discs_are_refused() {
        let sky: RgbImage = Grid::from_fn(300, 200, |_, _| [0.2, 0.3, 0.5]);
        let e = find_image_circle(&sky, "wide.jpg").unwrap_err().to_string();
        assert!(
            e.contains("wide.jpg") && e.contains("300x200 px, not a disc"),
            "{e}"
        );
        let cut = disc(300, 200, 280.0, 100.0, 90.0);
        let e = find_image_circle(&cut, "cut.jpg").unwrap_err().to_string();
        assert!(e.contains("not a disc") || e.contains("cut by"), "{e}");
        let black: RgbImage = Grid::from_fn(30, 20, |_, _| [0.0; 3]);
        let e = find_image_circle(&black, "night.jpg")
            .unwrap_err()
            .to_string();
        assert!(e.contains("every pixel is black"), "{e}");
    }
}
