//! The ground beyond the sensor's reach, upsampled by interpolation.

use super::nearest_cell;
use crate::raster::{Grid, ScalarMap};

/// The cells of the ground receding beyond the reach and the sky's, on the range's grid.
pub type RecedingCells<'a> = (&'a Grid<bool>, &'a Grid<bool>);

/// Redraws the upsampled range `out` of the pixels whose cell of `range` is the ground
/// receding beyond the sensor's reach (`receding`, [`crate::prep::Prepared::receding`])
/// as the bilinear interpolation in log range of the four cells round each, where all four
/// are receding or sky: the fill is linear in log range up each column to the horizon,
/// which bilinear interpolation draws exactly at every pixel between the cells' centres.
/// The joint bilateral upsampling's Gaussian of one cell averaged the ramp with the sky's
/// constant range above the horizon (a kink), pulling the ground one to three cells below
/// the horizon nearer: where physical fog reads the fill as the ground's 1/R, its
/// transmittance there was up to 0.1 too high (a clear band along the far ground). The
/// fill's whole span is a few tenths of a nat, so the upsampling's mean shift could not
/// tell it from one surface either. Where a tap is another surface (something standing on
/// the ground, the scene in reach), the colour-guided upsampling is kept.
pub fn interpolate_receding(
    range: &ScalarMap,
    (receding, sky): RecedingCells,
    out: &mut ScalarMap,
) {
    let (lw, lh) = (range.width(), range.height());
    let (w, h) = (out.width(), out.height());
    if !receding.as_slice().iter().any(|&r| r) {
        return;
    }
    let scale = [lw as f64 / w as f64, lh as f64 / h as f64];
    let log_range = range.map(|&v| f64::from(v).ln());
    let fill = |(x, y): (usize, usize)| *receding.get(x, y) || *sky.get(x, y);
    let redrawn = Grid::par_from_fn(w, h, |x, y| {
        let keep = *out.get(x, y);
        let (cx, cy) = (
            (x as f64 + 0.5) * scale[0] - 0.5,
            (y as f64 + 0.5) * scale[1] - 0.5,
        );
        // The cell whose masks the pixel took ([`super::nearest_to_image_size`]).
        let own = (nearest_cell(x, scale[0], lw), nearest_cell(y, scale[1], lh));
        if !*receding.get(own.0, own.1) {
            return keep;
        }
        let ((x0, x1), tx) = (taps(cx, lw), cx.clamp(0.0, (lw - 1) as f64).fract());
        let ((y0, y1), ty) = (taps(cy, lh), cy.clamp(0.0, (lh - 1) as f64).fract());
        let corners = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)];
        if !corners.into_iter().all(fill) {
            return keep;
        }
        let l = |(x, y): (usize, usize)| *log_range.get(x, y);
        let bottom = l(corners[0]) + (l(corners[1]) - l(corners[0])) * tx;
        let top = l(corners[2]) + (l(corners[3]) - l(corners[2])) * tx;
        (bottom + (top - bottom) * ty).exp() as f32
    });
    *out = redrawn;
}

/// The two cells of a grid of `n` round coordinate `c` (the same one at the borders).
fn taps(c: f64, n: usize) -> (usize, usize) {
    let lo = (c.max(0.0).floor() as usize).min(n - 1);
    (lo, (lo + 1).min(n - 1))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cells 4 x 6, upsampled 4 times: the sky in row 0 at range 15, the ground receding
    /// in rows 1-4 (log range linear from 10 at row 4 up to the sky's 15 at row 0), the
    /// scene in reach in row 5, and cell (3, 2) something standing on the ground, held at
    /// its foot's range. The upsampling's output is a constant the step must replace (by
    /// the ramp, exactly) or keep (a pixel of another cell, or with another surface among
    /// its four taps).
    #[test]
    fn the_receding_ground_is_interpolated_between_its_cells() {
        let (lw, lh, f) = (4, 6, 4);
        let ramp = |c: f64| 10f64.ln() + (4.0 - c.clamp(0.0, 4.0)) / 4.0 * 1.5f64.ln();
        let held = (3, 2);
        let range = ScalarMap::from_fn(lw, lh, |x, y| match (x, y) {
            (_, 5) => 9.0,
            p if p == held => 11.0,
            (_, y) => ramp(y as f64).exp() as f32,
        });
        let sky = Grid::from_fn(lw, lh, |_, y| y == 0);
        let receding = Grid::from_fn(lw, lh, |x, y| (1..5).contains(&y) && (x, y) != held);
        let fill = |x: usize, y: usize| *sky.get(x, y) || *receding.get(x, y);
        let upsampled = 1.0f32;
        let mut out = ScalarMap::filled(lw * f, lh * f, upsampled);
        interpolate_receding(&range, (&receding, &sky), &mut out);
        let (mut redrawn, mut kept) = (0, 0);
        for (x, y) in (0..lw * f).flat_map(|x| (0..lh * f).map(move |y| (x, y))) {
            let centre = |p: usize| (p as f64 + 0.5) / f as f64 - 0.5;
            let (cx, cy) = (centre(x), centre(y));
            let (x0, y0) = (taps(cx, lw), taps(cy, lh));
            let four = [(x0.0, y0.0), (x0.1, y0.0), (x0.0, y0.1), (x0.1, y0.1)];
            let got = *out.get(x, y);
            if *receding.get(x / f, y / f) && four.iter().all(|&(i, j)| fill(i, j)) {
                let want = ramp(cy);
                let err = (f64::from(got).ln() - want).abs();
                assert!(err < 1e-6, "({x}, {y}): {got}, want {}", want.exp());
                redrawn += 1;
            } else {
                assert_eq!(got, upsampled, "({x}, {y}) kept");
                kept += 1;
            }
        }
        // Rows 4-17 (the receding cells' pixels above the last row between centres of
        // the ground), all 16 columns, less columns 10-15 of rows 6-13 (a tap in the
        // held cell).
        assert_eq!((redrawn, kept), (14 * 16 - 6 * 8, 24 * 16 - 176));
    }
}
