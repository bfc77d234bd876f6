//! Joint bilateral upsampling of a depth map smaller than the image (Kopf, Cohen,
//! Lischinski and Uyttendaele, SIGGRAPH 2007): the CPU reference of
//! `glsl/refine/cells.frag`, `glsl/refine/interpolate.frag` and `glsl/refine/upsample.frag`.

use super::{cell_means, check_depth_size, check_positive};
use crate::error::Result;
use crate::io::image::linear_to_srgb;
use crate::raster::{Grid, RgbImage, ScalarMap};
use crate::reference::bilinear;

/// Default σ of the colour weight of [`joint_bilateral_upsample_reference`], in
/// sRGB-encoded values (measured on Aloe: 0.15 gives the smallest 95th-percentile error
/// at 1/8 size; 0.05 follows texture into the range, 0.3 blurs across edges).
pub const DEFAULT_UPSAMPLE_SIGMA_COLOUR: f64 = 0.15;

/// Joint bilateral upsampling (Kopf, Cohen, Lischinski and Uyttendaele, SIGGRAPH 2007) of
/// a range smaller than the image, the CPU reference of `glsl/refine/upsample.frag`: each
/// pixel's log range is the mean over the 6 x 6 cells around it of their log range,
/// weighted by a Gaussian of the distance (σ one cell) times a Gaussian of the colour
/// difference (σ `sigma_colour`, sRGB-encoded RGB) between the pixel and the cell's mean
/// colour, then moved toward the surface holding most of that weight by
/// [`UPSAMPLE_SHIFT_STEPS`] mean-shift steps. Where the coarse cells straddle an edge of
/// the image, a pixel takes the range of the cells on its side: on Aloe downsampled 8x
/// with noise its 95th-percentile error is 0.61x bilinear upsampling's, where the guided
/// filter's is 0.82x (tests/refine.rs).
///
/// Where the 6 x 6 cells' log ranges are within [`UPSAMPLE_FLAT_SPREAD`] of each other (the
/// sky, a wall facing the camera) or smooth, with no second difference between neighbouring
/// cells over [`UPSAMPLE_SMOOTH_CURVATURE`] (the ground receding), the pixel takes their
/// bilinear interpolation instead: with no depth edge for the colour to place, the joint
/// bilateral mean could only copy the image's texture into the range, and the bilinear
/// one reads 4 cells where the mean reads 36.
pub fn joint_bilateral_upsample_reference(
    image: &RgbImage,
    range: &ScalarMap,
    sigma_colour: f64,
) -> Result<ScalarMap> {
    upsample(image, range, sigma_colour, true)
}

/// The spread of log range (the largest less the least) over a pixel's 6 x 6 cells up to
/// which [`joint_bilateral_upsample_reference`] interpolates them bilinearly instead of
/// taking their joint bilateral mean: 0.005. Any mean of them, and the pixel's own range,
/// lie between the least and the largest: a range error of at most 0.5 %, which moves a
/// transmittance τ = e^(−βR) by at most 0.005·βR·τ ≤ 0.0019 (half an 8-bit level).
pub const UPSAMPLE_FLAT_SPREAD: f64 = 0.005;

/// The largest second difference of log range (|a − 2b + c| of three neighbouring cells in
/// a row or a column) over a pixel's 6 x 6 cells up to which
/// [`joint_bilateral_upsample_reference`] interpolates them bilinearly too: 0.005. The
/// interpolation of a field so bent errs by at most a quarter of it; a step between two
/// surfaces is a second difference of its height, so a step it smooths over is at most
/// 0.5 % of the range, the bound of [`UPSAMPLE_FLAT_SPREAD`]. On a street frame with sky and
/// its true range at 1/4 of 2048x1024, 41 % of the cells are flat (the sky, the walls
/// facing the camera) and 77 % smooth (the ground too).
pub const UPSAMPLE_SMOOTH_CURVATURE: f64 = 0.005;

/// [`joint_bilateral_upsample_reference`], the cells interpolated where they are flat or
/// smooth if `interpolate` (if not, the joint bilateral mean everywhere).
fn upsample(
    image: &RgbImage,
    range: &ScalarMap,
    sigma_colour: f64,
    interpolate: bool,
) -> Result<ScalarMap> {
    let (w, h) = (image.width(), image.height());
    let (lw, lh) = (range.width(), range.height());
    check_depth_size((w, h), (lw, lh))?;
    check_positive(range)?;
    let encoded = |p: [f32; 3]| p.map(|v| f64::from(linear_to_srgb(v.clamp(0.0, 1.0))));
    let cells = image_at_depth_size_srgb(image, lw, lh);
    // Once per cell, not at each of its 36 taps: a fifth less time.
    let log_ranges = Grid::from_fn(lw, lh, |x, y| f64::from(*range.get(x, y)).ln());
    let interpolated = interpolated_windows(&log_ranges, interpolate);
    let scale = [lw as f64 / w as f64, lh as f64 / h as f64];
    let inv = 1.0 / (2.0 * sigma_colour * sigma_colour);
    Ok(Grid::par_from_fn(w, h, |x, y| {
        let colour = encoded(*image.get(x, y));
        let centre = [
            (x as f64 + 0.5) * scale[0] - 0.5,
            (y as f64 + 0.5) * scale[1] - 0.5,
        ];
        let base = [centre[0].floor() as isize, centre[1].floor() as isize];
        // Only between the outer cells' centres: beyond them a window would be clamped, and
        // the GPU, whose rows run bottom to top, clamps the other way.
        let inner = |b: isize, cells: usize| b >= 0 && (b as usize) + 1 < cells;
        if inner(base[0], lw)
            && inner(base[1], lh)
            && *interpolated.get(base[0] as usize, base[1] as usize)
        {
            return bilinear(&log_ranges, centre[0], centre[1]).exp() as f32;
        }
        let mut taps = [(0.0f64, 0.0f64); 36];
        let mut n = 0;
        let (mut sum, mut weight) = (0.0, 0.0);
        let (mut nearest, mut nearest_d2) = (0.0, f64::INFINITY);
        for j in -2..=3 {
            for i in -2..=3 {
                let (qx, qy) = (base[0] + i, base[1] + j);
                if qx < 0 || qy < 0 || qx >= lw as isize || qy >= lh as isize {
                    continue;
                }
                let (qx, qy) = (qx as usize, qy as usize);
                let cell = cells.get(qx, qy);
                let log_range = *log_ranges.get(qx, qy);
                let d = [qx as f64 - centre[0], qy as f64 - centre[1]];
                let d2 = d[0] * d[0] + d[1] * d[1];
                let dc2: f64 = (0..3).map(|c| (colour[c] - cell[c]).powi(2)).sum();
                let wgt = (-0.5 * d2 - dc2 * inv).exp();
                sum += wgt * log_range;
                weight += wgt;
                taps[n] = (wgt, log_range);
                n += 1;
                if d2 < nearest_d2 {
                    nearest_d2 = d2;
                    nearest = log_range;
                }
            }
        }
        let log_range = if weight > 1e-30 {
            shift_to_dominant_surface(&taps[..n], sum / weight, weight)
        } else {
            nearest
        };
        log_range.exp() as f32
    }))
}

/// Whether the log ranges of the 6 x 6 cells from (x − 2, y − 2) to (x + 3, y + 3) (those
/// in the grid), the window of a pixel whose centre falls in [x, x + 1) x [y, y + 1), are
/// flat (within [`UPSAMPLE_FLAT_SPREAD`]) or smooth (no second difference over
/// [`UPSAMPLE_SMOOTH_CURVATURE`] of three cells in a row or a column of the window), where
/// `interpolate`.
fn interpolated_windows(log_ranges: &Grid<f64>, interpolate: bool) -> Grid<bool> {
    let (lw, lh) = (log_ranges.width(), log_ranges.height());
    if !interpolate {
        return Grid::filled(lw, lh, false);
    }
    let v = |x: usize, y: usize| *log_ranges.get(x, y);
    let bent = |a: f64, b: f64, c: f64| (a - 2.0 * b + c).abs() > UPSAMPLE_SMOOTH_CURVATURE;
    Grid::par_from_fn(lw, lh, |x, y| {
        let (x0, x1) = (x.saturating_sub(2), (x + 4).min(lw));
        let (y0, y1) = (y.saturating_sub(2), (y + 4).min(lh));
        let (mut least, mut largest) = (f64::INFINITY, f64::NEG_INFINITY);
        for qy in y0..y1 {
            for qx in x0..x1 {
                least = least.min(v(qx, qy));
                largest = largest.max(v(qx, qy));
            }
        }
        let flat = largest - least <= UPSAMPLE_FLAT_SPREAD;
        // Every cell of the window but its first and last of a line is a middle of three.
        let across = || {
            (y0..y1).any(|qy| {
                (x0 + 1..x1.saturating_sub(1))
                    .any(|qx| bent(v(qx - 1, qy), v(qx, qy), v(qx + 1, qy)))
            })
        };
        let down = || {
            (x0..x1).any(|qx| {
                (y0 + 1..y1.saturating_sub(1))
                    .any(|qy| bent(v(qx, qy - 1), v(qx, qy), v(qx, qy + 1)))
            })
        };
        flat || !(across() || down())
    })
}

/// σ of the mean shift's Gaussian in log range (a factor 1.35): taps of the pixel's own
/// surface are within it, those of a surface behind or in front are not.
pub const UPSAMPLE_SHIFT_SIGMA: f64 = 0.3;
/// Mean-shift steps after the weighted mean.
pub const UPSAMPLE_SHIFT_STEPS: usize = 2;
/// The taps' weighted standard deviation in log range below which the mean is kept as it
/// is (one surface: the steps would move it by less than 0.03 %).
pub const UPSAMPLE_SHIFT_MIN_SPREAD: f64 = 0.03;

/// The joint bilateral mean `mean` of the `(weight, log range)` taps, moved by mean shift
/// (Comaniciu and Meer, TPAMI 2002) toward the surface that holds most of the weight: where
/// the colour weights let taps of two surfaces through (the same colour on both sides of a
/// depth edge, a coarse cell that averages both), the mean is a range neither surface has,
/// which fog shows as a halo round the nearer one. Each step re-weights the taps by a
/// Gaussian of their distance to the current estimate; the estimate starts nearer to the
/// heavier surface, so it goes there. Where the taps agree it stays put; it is continuous
/// in the taps (no choice of a winner). Measured on the phone evaluation
/// (`tools/phone_depth_eval.py`): 3-11 % less transmittance error over the frame, 4-10 %
/// near depth edges. `total` is the sum of the taps' weights, which the mean was taken with.
fn shift_to_dominant_surface(taps: &[(f64, f64)], mean: f64, total: f64) -> f64 {
    // Taps of one surface (a spread s much less than σ) would move the mean by about
    // s³/σ², 3e-4 in log range at the cutoff: not worth the steps, which make the pass
    // 1.7 times as long on llvmpipe where every pixel takes them.
    let spread: f64 = taps.iter().map(|&(w, v)| w * (v - mean) * (v - mean)).sum();
    if spread <= UPSAMPLE_SHIFT_MIN_SPREAD * UPSAMPLE_SHIFT_MIN_SPREAD * total {
        return mean;
    }
    let inv = 1.0 / (2.0 * UPSAMPLE_SHIFT_SIGMA * UPSAMPLE_SHIFT_SIGMA);
    let mut m = mean;
    for _ in 0..UPSAMPLE_SHIFT_STEPS {
        let (mut sum, mut weight) = (0.0, 0.0);
        for &(w, v) in taps {
            let wv = w * (-(v - m) * (v - m) * inv).exp();
            sum += wv * (v - m);
            weight += wv;
        }
        // Every tap too far from the estimate to count: keep it.
        if weight <= 1e-30 {
            break;
        }
        m += sum / weight;
    }
    m
}

/// The mean sRGB-encoded colour of each cell of a `width` x `height` grid over `image`
/// (what `cells.frag` packs).
fn image_at_depth_size_srgb(image: &RgbImage, width: usize, height: usize) -> Grid<[f64; 3]> {
    cell_means(image, width, height, |v| {
        f64::from(linear_to_srgb(v.clamp(0.0, 1.0)))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    // A depth edge the image does not show (one grey on both sides): the colour weights
    // let both surfaces' cells through, and the joint bilateral mean of a pixel near the
    // edge was a range neither surface has (a halo under fog). The mean shift takes each
    // pixel a quarter of a cell or more from the edge to its own side's range.
    #[test]
    fn upsampling_takes_a_side_of_an_edge_the_colour_does_not_show() {
        let (near, far) = (5.0f32, 50.0f32);
        let low = Grid::from_fn(8, 4, |x, _| if x < 4 { near } else { far });
        let image = RgbImage::from_fn(64, 32, |_, _| [0.5; 3]);
        let up = joint_bilateral_upsample_reference(&image, &low, 0.15).unwrap();
        // The plain mean at x = 29 (cell coordinate 3.25, the edge at 3.5): Gaussian
        // weights of one cell at the cells' distances, 1.51 on the near side, 0.99 far.
        let centre = (29.0 + 0.5) / 8.0 - 0.5;
        let (mut sum, mut weight) = (0.0, 0.0);
        for q in 1..=6 {
            let d = f64::from(q) - centre;
            let w = (-0.5 * d * d).exp();
            sum += w * f64::from(if q < 4 { near } else { far }).ln();
            weight += w;
        }
        let plain = (sum / weight).exp();
        assert!(plain > 2.0 * f64::from(near), "{plain}");
        for x in (0..64).filter(|&x| !(30..34).contains(&x)) {
            let side = if x < 32 { near } else { far };
            let got = *up.get(x, 16);
            assert!((got / side - 1.0).abs() < 0.01, "x = {x}: {got} for {side}");
        }
    }

    /// A textured image: each pixel's colour from a pattern that repeats every 11 pixels.
    fn textured(w: usize, h: usize) -> RgbImage {
        Grid::from_fn(w, h, |x, y| {
            let t = ((x * 7 + y * 13) % 11) as f32 / 11.0;
            [t, 1.0 - t, 0.5 * t]
        })
    }

    /// The upsampling of `low` under `image` with the interpolation and without (the joint
    /// bilateral mean everywhere), asserted within [`UPSAMPLE_FLAT_SPREAD`] of each other
    /// everywhere, and how many pixels differ.
    fn interpolated_within_spread(
        image: &RgbImage,
        low: &ScalarMap,
    ) -> (ScalarMap, ScalarMap, usize) {
        let fast = joint_bilateral_upsample_reference(image, low, 0.15).unwrap();
        let exact = upsample(image, low, 0.15, false).unwrap();
        let mut interpolated = 0;
        for (f, e) in fast.as_slice().iter().zip(exact.as_slice()) {
            let d = (f64::from(*f) / f64::from(*e)).ln().abs();
            assert!(d <= UPSAMPLE_FLAT_SPREAD, "{f} against {e}");
            interpolated += usize::from(f != e);
        }
        (fast, exact, interpolated)
    }

    /// Where the cells around a pixel agree to within a spread, the bilinear interpolation
    /// stands in for the joint bilateral mean: within that spread of it, however the colour
    /// varies; by a depth edge nothing changes.
    #[test]
    fn a_flat_window_is_interpolated_within_its_spread() {
        // A sky of one range at the top, a wall with a slope of 0.04 % a cell, a near box.
        let low = Grid::from_fn(16, 12, |x, y| match (x, y) {
            (_, 0..=3) => 900.0,
            (5..=8, 7..=10) => 4.0,
            _ => 40.0 * (1.0 + 0.0004 * x as f32),
        });
        let image = textured(128, 96);
        let (fast, exact, interpolated) = interpolated_within_spread(&image, &low);
        assert!(interpolated > 128 * 96 / 8, "{interpolated}");
        // By the box's edge the cells differ: the joint bilateral mean, to the bit.
        for (x, y) in [(44, 60), (70, 86), (38, 70)] {
            assert_eq!(fast.get(x, y), exact.get(x, y), "({x}, {y})");
        }
        // The sky is its range, the wall's slope is smooth: the interpolation.
        assert_eq!(*fast.get(60, 5), 900.0);
        let wall = |x| f64::from(*fast.get(x, 90));
        let step = |x| wall(x + 1) - wall(x);
        assert!(
            (step(100) / step(101) - 1.0).abs() < 0.01,
            "{} {}",
            step(100),
            step(101)
        );
    }

    /// A rough wall facing the camera (its cells within 0.5 % of each other, but with second
    /// differences up to 1 %): flat though not smooth, interpolated all the same.
    #[test]
    fn a_rough_flat_window_is_interpolated() {
        let low = Grid::from_fn(12, 12, |x, y| {
            40.0 * (1.0 + 0.0012 * ((x * 7 + y * 13) % 5) as f32)
        });
        let image = textured(96, 96);
        let (_, _, interpolated) = interpolated_within_spread(&image, &low);
        assert!(interpolated > 96 * 96 * 3 / 4, "{interpolated}");
    }

    /// The ground receding under a textured image: its cells span far more than a flat
    /// spread but bend by less than [`UPSAMPLE_SMOOTH_CURVATURE`], so the pixels take their
    /// interpolation, within an eighth of that bend (along the one axis that bends) of the
    /// ground's own log range, where the joint bilateral mean follows the texture off it.
    #[test]
    fn a_smooth_window_is_interpolated_not_textured() {
        // Log range falling 0.08 a row, bending by 0.002 a row (second difference 0.004).
        let ground = |x: f64, y: f64| 4.0 + 0.001 * x - 0.08 * y + 0.002 * y * y;
        let low = Grid::from_fn(16, 12, |x, y| ground(x as f64, y as f64).exp() as f32);
        let image = textured(128, 96);
        let fast = joint_bilateral_upsample_reference(&image, &low, 0.15).unwrap();
        let exact = upsample(&image, &low, 0.15, false).unwrap();
        let (mut worst_fast, mut worst_exact) = (0.0f64, 0.0f64);
        // Between the first and last cells' centres, where the interpolation does not clamp.
        for y in 4..92 {
            for x in 4..124 {
                let truth = ground((x as f64 + 0.5) / 8.0 - 0.5, (y as f64 + 0.5) / 8.0 - 0.5);
                worst_fast = worst_fast.max((f64::from(*fast.get(x, y)).ln() - truth).abs());
                worst_exact = worst_exact.max((f64::from(*exact.get(x, y)).ln() - truth).abs());
            }
        }
        assert!(
            worst_fast <= 0.004 / 8.0 + 1e-6,
            "interpolated: {worst_fast}"
        );
        assert!(worst_exact > 4.0 * worst_fast, "mean: {worst_exact}");
    }
}
