//! Image-guided refinement of real depth: the range is filtered with the colour image as
//! guide, so that its edges follow the image's (a pole's silhouette, not the stereo
//! matcher's fattened one) and its noise is smoothed where the image is flat; a depth map
//! smaller than the image (phone depth: 160x120 to 640x480 under a 1080p frame) is
//! upsampled by the same filter, guided by the full-resolution image.
//!
//! **The filter** is He, Sun and Tang's guided filter (TPAMI 2013) in its fast form (He and
//! Sun, 2015): on a grid `subsample` times coarser than the image (or on the depth map's own
//! grid when it is smaller), each window of radius r fits the local linear model
//! p ≈ a·I + b between the guide's colour I (a 3-vector, so a is one too) and the input
//! p; the models' coefficients, averaged over the windows that cover a cell, are upsampled
//! bilinearly and applied to the full-resolution guide: q = ā·I + b̄. Three kinds of
//! fragment pass, six passes (`glsl/refine/`): pack (the 13 moments of I and p per cell,
//! into four textures at once), two box passes over the four (the second solves each
//! window's 3 x 3 system, `model.glsl`, and writes its model), two box passes over the
//! models, apply.
//!
//! **What is filtered: log range, once per frame.** Not τ per β, as Foggy Cityscapes does
//! (it guided-filters each transmittance map): every τ = exp(−βR) of a frame, at every β
//! and in every medium, is derived from the one refined range, so a batch refines a frame
//! once for all its β, and τ maps written with `--transmittance` are those of the range
//! that was rendered. In log range the filter's window averages relative errors, the same
//! at 5 m and 500 m, and its output exp(q) is a positive range; a linear filter of range
//! would let the sky's far range bleed metres into a near pole's edge, one of log range
//! lets it bleed a ratio.
//!
//! **The guide** is the image's colour in sRGB-encoded values (perceptual steps: a dark
//! edge counts like a bright one), as He et al.'s colour guided filter (eq. 14), so ε (1e-3
//! by default, as Foggy Cityscapes) is a variance of such values: windows whose colour
//! varies by much less than √ε ≈ 0.03 are smoothed, edges of more contrast are kept. The
//! colour matters on real photos: a light grey facade against a blue sky of the same
//! luminance is an edge to it, where a luminance guide mixed the sky's range into the
//! facade (measured on stereo-matched depth, `tools/stereo_refine_eval.py`: the guided
//! range's τ error where the matcher was right fell by 25-31 %, see the README).
//! It costs a 3 x 3 inverse per cell of the coarse grid and four times the box passes'
//! texture traffic.
//!
//! [`guided_range_reference`] is the same computation on the CPU in f64, the judge of the
//! GPU passes (`Pipeline::refine_range`).

mod beyond;
mod edges;
mod step;
mod upsample;

pub use edges::{
    median_at_depth_edges, EDGE_COLOUR_EVIDENCE, EDGE_REACH_PX, EDGE_SIGMA_COLOUR, EDGE_STEP,
    EDGE_WINDOW_PX,
};
pub use step::{
    refine_prepared, refine_range, repair, Combine, CpuFilter, RangeFilter, RefineMode,
    RefineOptions, RefinePlan, REPAIR_FILLED_WEIGHT, REPAIR_NEARER,
};
pub use upsample::{
    joint_bilateral_upsample_reference, DEFAULT_UPSAMPLE_SIGMA_COLOUR, UPSAMPLE_FLAT_SPREAD,
    UPSAMPLE_SHIFT_MIN_SPREAD, UPSAMPLE_SHIFT_SIGMA, UPSAMPLE_SHIFT_STEPS,
    UPSAMPLE_SMOOTH_CURVATURE,
};

use crate::error::{Error, Result};
use crate::io::image::linear_to_srgb;
use crate::raster::{Grid, RgbImage, ScalarMap};
use std::borrow::Cow;

/// Default window radius in full-resolution pixels: Foggy Cityscapes' 20 at 2048 x 1024.
pub const DEFAULT_RADIUS_PX: f64 = 20.0;
/// Default regularisation ε: Foggy Cityscapes' 1e-3.
pub const DEFAULT_EPSILON: f64 = 1e-3;
/// Default coarsening of the fast guided filter (He and Sun suggest 4 for r = 20).
pub const DEFAULT_SUBSAMPLE: usize = 4;
/// The largest ratio of image to depth size accepted (per side).
pub const MAX_UPSAMPLING: f64 = 16.0;
/// How far the two sides' ratios of image to depth size may differ (relative): a depth
/// map of another aspect ratio covers another field of view and is refused.
pub const ASPECT_TOLERANCE: f64 = 0.01;

/// How to refine a range with its image.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Refine {
    /// Window radius r in full-resolution pixels (> 0).
    pub radius_px: f64,
    /// Regularisation ε, a variance of sRGB-encoded colour values (> 0): larger smooths
    /// across weaker edges.
    pub epsilon: f64,
    /// Coarsening of the grid the windows are fitted on, for a range of the image's size
    /// (1 to 16); a smaller range is fitted on its own grid.
    pub subsample: usize,
}

impl Default for Refine {
    fn default() -> Self {
        Refine {
            radius_px: DEFAULT_RADIUS_PX,
            epsilon: DEFAULT_EPSILON,
            subsample: DEFAULT_SUBSAMPLE,
        }
    }
}

/// Where the filter fits its windows, for an image and a range of given sizes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefineGrid {
    /// The low grid's size.
    pub width: usize,
    /// The low grid's size.
    pub height: usize,
    /// Full-resolution pixels per low-grid cell (x, y).
    pub cell: [f64; 2],
    /// Whether the range is at full resolution (averaged per cell) rather than on the low
    /// grid itself.
    pub range_full: bool,
    /// The window radius on the low grid, in cells (≥ 1).
    pub radius: usize,
}

impl Refine {
    /// Checks the values, naming the field.
    pub fn validate(&self) -> Result<()> {
        if !(self.radius_px.is_finite() && self.radius_px > 0.0 && self.radius_px <= 1000.0) {
            return Err(Error::invalid(
                "refine_radius",
                self.radius_px,
                "a window radius in (0, 1000] px",
            ));
        }
        if !(self.epsilon.is_finite() && self.epsilon > 0.0 && self.epsilon <= 1.0) {
            return Err(Error::invalid(
                "refine_eps",
                self.epsilon,
                "a regularisation in (0, 1] (a variance of sRGB-encoded colour values)",
            ));
        }
        if !(1..=16).contains(&self.subsample) {
            return Err(Error::invalid(
                "subsample",
                self.subsample,
                "a coarsening of 1 to 16",
            ));
        }
        Ok(())
    }

    /// The low grid for an image of `image` size and a range of `range` size: the image's
    /// coarsened by `subsample` when the range has the image's size, else the range's own
    /// grid (see [`check_depth_size`]).
    pub fn grid(&self, image: (usize, usize), range: (usize, usize)) -> Result<RefineGrid> {
        self.validate()?;
        let (w, h) = image;
        let (width, height, range_full) = if range == image {
            let s = self.subsample;
            (w.div_ceil(s), h.div_ceil(s), true)
        } else {
            check_depth_size(image, range)?;
            (range.0, range.1, false)
        };
        let cell = [w as f64 / width as f64, h as f64 / height as f64];
        let radius = (self.radius_px / cell[0].max(cell[1])).round().max(1.0) as usize;
        Ok(RefineGrid {
            width,
            height,
            cell,
            range_full,
            radius,
        })
    }
}

/// Accepts a depth map of `range` size for an image of `image` size when it is the image's
/// size, or smaller by the same factor on both sides (within [`ASPECT_TOLERANCE`]) and at
/// most [`MAX_UPSAMPLING`] times: the same field of view, sampled more coarsely.
pub fn check_depth_size(image: (usize, usize), range: (usize, usize)) -> Result<()> {
    if image == range {
        return Ok(());
    }
    let (sx, sy) = (
        image.0 as f64 / range.0.max(1) as f64,
        image.1 as f64 / range.1.max(1) as f64,
    );
    let same_view = (sx - sy).abs() <= ASPECT_TOLERANCE * sx.max(sy);
    if range.0 == 0
        || range.1 == 0
        || sx < 1.0
        || sy < 1.0
        || sx.max(sy) > MAX_UPSAMPLING
        || !same_view
    {
        return Err(Error::invalid(
            "depth size",
            format!(
                "{}x{} for a {}x{} image",
                range.0, range.1, image.0, image.1
            ),
            format!(
                "the image's size, or smaller by one factor of 1 to {MAX_UPSAMPLING} on both \
                 sides (the same field of view; the sides' factors here are {sx:.3} and \
                 {sy:.3}): crop or resize the depth map to the image's aspect ratio"
            ),
        ));
    }
    Ok(())
}

/// `image` at a depth map's smaller size (`width` x `height`, accepted by
/// [`check_depth_size`]): each pixel the mean of its cell, the cells the refinement's (so
/// that pre-processing and the airlight estimate see the image the depth map was
/// measured against).
pub fn image_at_depth_size(image: &RgbImage, width: usize, height: usize) -> RgbImage {
    cell_means(image, width, height, f64::from).map(|m| m.map(|v| v as f32))
}

/// The mean over each cell of a `width` x `height` grid over `image` of `value` of each
/// channel, the cells the refinement's.
pub(super) fn cell_means(
    image: &RgbImage,
    width: usize,
    height: usize,
    value: impl Fn(f32) -> f64 + Sync,
) -> Grid<[f64; 3]> {
    let (w, h) = (image.width(), image.height());
    let cell = [w as f64 / width as f64, h as f64 / height as f64];
    Grid::par_from_fn(width, height, |i, j| {
        let (x0, x1) = cell_span(i, cell[0], w);
        let (y0, y1) = cell_span(j, cell[1], h);
        let mut sum = [0f64; 3];
        for y in y0..y1 {
            for x in x0..x1 {
                for (s, v) in sum.iter_mut().zip(image.get(x, y)) {
                    *s += value(*v);
                }
            }
        }
        let n = ((x1 - x0) * (y1 - y0)) as f64;
        sum.map(|s| s / n)
    })
}

/// `map` (on a depth map's grid) at the image's `width` x `height`, each pixel taking its
/// cell's value: the masks and the measured range that go with an upsampled range.
pub fn nearest_to_image_size<T: Copy + Send + Sync>(
    map: &Grid<T>,
    width: usize,
    height: usize,
) -> Grid<T> {
    if (map.width(), map.height()) == (width, height) {
        return map.clone();
    }
    let cells = |n: usize, to: usize| -> Vec<usize> {
        let scale = n as f64 / to as f64;
        (0..to).map(|p| nearest_cell(p, scale, n)).collect()
    };
    let (columns, rows) = (cells(map.width(), width), cells(map.height(), height));
    Grid::par_from_fn(width, height, |x, y| *map.get(columns[x], rows[y]))
}

/// [`nearest_to_image_size`], borrowed where `map` has that size already: no copy.
pub fn at_image_size<T: Copy + Send + Sync>(
    map: &Grid<T>,
    width: usize,
    height: usize,
) -> Cow<'_, Grid<T>> {
    if (map.width(), map.height()) == (width, height) {
        Cow::Borrowed(map)
    } else {
        Cow::Owned(nearest_to_image_size(map, width, height))
    }
}

/// The cell of a grid `n` wide (cells per pixel `scale`) whose value pixel `p` takes in
/// [`nearest_to_image_size`].
fn nearest_cell(p: usize, scale: f64, n: usize) -> usize {
    ((p as f64 * scale) as usize).min(n - 1)
}

/// The guide of one pixel: its sRGB-encoded colour, clamped to [0, 1], less
/// [`GUIDE_CENTRE`] (as the shaders).
fn guide(rgb: [f32; 3]) -> [f64; 3] {
    rgb.map(|v| f64::from(linear_to_srgb(v.clamp(0.0, 1.0))) - GUIDE_CENTRE)
}

/// Subtracted from every guide value: the filter's output does not depend on an offset of
/// the guide (b absorbs it), and moments of values centred on 0 lose less to f32
/// cancellation in `var = E[I²] − E[I]²` on the GPU.
pub const GUIDE_CENTRE: f64 = 0.5;

/// The moments one cell contributes to the windows' means, in the order of the four
/// textures `pack.frag` writes: (I_r, I_g, I_b, p), (I_r·p, I_g·p, I_b·p, I_r·I_r),
/// (I_r·I_g, I_r·I_b, I_g·I_g, I_g·I_b), (I_b·I_b, 0, 0, 0).
fn cell_moments(i: [f64; 3], p: f64) -> [f64; 16] {
    let [r, g, b] = i;
    [
        r,
        g,
        b,
        p,
        r * p,
        g * p,
        b * p,
        r * r,
        r * g,
        r * b,
        g * g,
        g * b,
        b * b,
        0.0,
        0.0,
        0.0,
    ]
}

/// One window's linear model q = a·I + b from the means of [`cell_moments`] (He et al.
/// 2013, eq. 14): a = (Σ + εU)⁻¹ cov(I, p), b = mean(p) − a·mean(I), where Σ is the 3 x 3
/// covariance of the guide's colour in the window. Returns (a_r, a_g, a_b, b).
fn window_model(m: &[f64; 16], epsilon: f64) -> [f64; 4] {
    let mean = glam::DVec3::new(m[0], m[1], m[2]);
    let p = m[3];
    let cov_ip = glam::DVec3::new(m[4], m[5], m[6]) - mean * p;
    let (rr, rg, rb, gg, gb, bb) = (m[7], m[8], m[9], m[10], m[11], m[12]);
    let sigma = glam::DMat3::from_cols_array(&[rr, rg, rb, rg, gg, gb, rb, gb, bb])
        - glam::DMat3::from_cols(mean * mean.x, mean * mean.y, mean * mean.z)
        + glam::DMat3::from_diagonal(glam::DVec3::splat(epsilon));
    let a = sigma.inverse() * cov_ip;
    [a.x, a.y, a.z, p - a.dot(mean)]
}

/// The CPU reference of the GPU refinement, in f64: `image` linear RGB, `range` > 0
/// everywhere, of the image's size or smaller ([`check_depth_size`]). Returns the refined
/// range at the image's size.
pub fn guided_range_reference(
    image: &RgbImage,
    range: &ScalarMap,
    opts: &Refine,
) -> Result<ScalarMap> {
    let (w, h) = (image.width(), image.height());
    let g = opts.grid((w, h), (range.width(), range.height()))?;
    check_positive(range)?;
    let (gw, gh) = (g.width, g.height);
    let moments = Grid::par_from_fn(gw, gh, |i, j| {
        let (x0, x1) = cell_span(i, g.cell[0], w);
        let (y0, y1) = cell_span(j, g.cell[1], h);
        let (mut gi, mut lp) = ([0.0; 3], 0.0);
        for y in y0..y1 {
            for x in x0..x1 {
                for (s, v) in gi.iter_mut().zip(guide(*image.get(x, y))) {
                    *s += v;
                }
                if g.range_full {
                    lp += f64::from(*range.get(x, y)).ln();
                }
            }
        }
        let n = ((x1 - x0) * (y1 - y0)) as f64;
        let p = if g.range_full {
            lp / n
        } else {
            f64::from(*range.get(i, j)).ln()
        };
        cell_moments(gi.map(|s| s / n), p)
    });
    let means = box_mean(&box_mean(&moments, g.radius, true), g.radius, false);
    let coefficients = means.map(|m| window_model(m, opts.epsilon));
    let ab = box_mean(&box_mean(&coefficients, g.radius, true), g.radius, false);
    let at = |x: isize, y: isize| {
        *ab.get(
            x.clamp(0, gw as isize - 1) as usize,
            y.clamp(0, gh as isize - 1) as usize,
        )
    };
    Ok(Grid::par_from_fn(w, h, |x, y| {
        let cx = (x as f64 + 0.5) / g.cell[0] - 0.5;
        let cy = (y as f64 + 0.5) / g.cell[1] - 0.5;
        let (fx, fy) = (cx.floor(), cy.floor());
        let (tx, ty) = (cx - fx, cy - fy);
        let (qx, qy) = (fx as isize, fy as isize);
        let lerp =
            |a: [f64; 4], b: [f64; 4], t: f64| std::array::from_fn(|k| a[k] + (b[k] - a[k]) * t);
        let bottom = lerp(at(qx, qy), at(qx + 1, qy), tx);
        let top = lerp(at(qx, qy + 1), at(qx + 1, qy + 1), tx);
        let [a_r, a_g, a_b, b] = lerp(bottom, top, ty);
        let [r, g, bl] = guide(*image.get(x, y));
        (a_r * r + a_g * g + a_b * bl + b).exp() as f32
    }))
}

/// Refuses a range with a value that is not finite and > 0: refinement reads log range,
/// and pre-processing is what fills unknown values.
pub fn check_positive(range: &ScalarMap) -> Result<()> {
    match range
        .as_slice()
        .iter()
        .position(|v| !(v.is_finite() && *v > 0.0))
    {
        Some(at) => Err(Error::invalid(
            "range map",
            range.as_slice()[at],
            format!(
                "a range > 0 at every pixel for refinement (pixel {} of {}x{} is not): \
                 pre-processing fills unknown values, so refine a prepared range",
                at,
                range.width(),
                range.height()
            ),
        )),
        None => Ok(()),
    }
}

/// Cell `i`'s full-resolution span [floor(i·s), floor((i + 1)·s)), at least one pixel, as
/// `pack.frag` takes it.
fn cell_span(i: usize, s: f64, n: usize) -> (usize, usize) {
    let lo = (i as f64 * s).floor() as usize;
    let hi = (((i + 1) as f64 * s).floor() as usize).max(lo + 1).min(n);
    (lo, hi)
}

/// The mean over a (2r + 1)-tap line of in-grid values, horizontal or vertical.
fn box_mean<const N: usize>(src: &Grid<[f64; N]>, r: usize, horizontal: bool) -> Grid<[f64; N]> {
    let (w, h) = (src.width(), src.height());
    Grid::par_from_fn(w, h, |x, y| {
        let (c, n) = if horizontal { (x, w) } else { (y, h) };
        let (lo, hi) = (c.saturating_sub(r), (c + r).min(n - 1));
        let mut sum = [0.0; N];
        for k in lo..=hi {
            let v = if horizontal {
                src.get(k, y)
            } else {
                src.get(x, k)
            };
            for (s, v) in sum.iter_mut().zip(v) {
                *s += v;
            }
        }
        sum.map(|s| s / (hi - lo + 1) as f64)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_sizes_accepted_and_refused() {
        assert!(check_depth_size((1920, 1080), (1920, 1080)).is_ok());
        assert!(check_depth_size((1920, 1080), (480, 270)).is_ok());
        assert!(check_depth_size((2048, 1024), (256, 128)).is_ok());
        // 4:3 depth under a 16:9 frame: another field of view.
        let e = check_depth_size((1920, 1080), (640, 480))
            .unwrap_err()
            .to_string();
        assert!(e.contains("640x480") && e.contains("1920x1080"), "{e}");
        assert!(check_depth_size((1920, 1080), (60, 34)).is_err(), "32x");
        assert!(check_depth_size((100, 100), (200, 200)).is_err(), "larger");
    }

    /// A flat range stays flat, whatever the image: q = a·I + b with a = 0.
    #[test]
    fn a_constant_range_is_kept() {
        let image = Grid::from_fn(40, 30, |x, y| {
            [(x % 7) as f32 / 7.0, (y % 5) as f32 / 5.0, 0.3]
        });
        let range = Grid::filled(40, 30, 12.5f32);
        let out = guided_range_reference(&image, &range, &Refine::default()).unwrap();
        for v in out.as_slice() {
            assert!((v - 12.5).abs() < 1e-4, "{v}");
        }
    }

    /// He et al.'s colour guided filter (TPAMI 2013, eq. 14) computed directly, as a judge
    /// of the reference: each window's sums taken pixel by pixel (not by separable box
    /// means), its 3 x 3 system solved by Cramer's rule (not an inverse), the guide not
    /// centred, and each pixel's q the mean of a and b over the windows that hold it.
    fn he_et_al(image: &RgbImage, range: &ScalarMap, r: usize, eps: f64) -> Vec<f64> {
        let (w, h) = (image.width(), image.height());
        let srgb = |x: usize, y: usize| -> [f64; 3] {
            image
                .get(x, y)
                .map(|v| f64::from(linear_to_srgb(v.clamp(0.0, 1.0))))
        };
        let span = |c: usize, n: usize| c.saturating_sub(r)..(c + r + 1).min(n);
        let det = |m: [[f64; 3]; 3]| {
            m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
        };
        let mut models = vec![[0.0; 4]; w * h];
        for ky in 0..h {
            for kx in 0..w {
                let (mut n, mut si, mut sp, mut sip, mut sii) =
                    (0.0, [0.0; 3], 0.0, [0.0; 3], [[0.0; 3]; 3]);
                for y in span(ky, h) {
                    for x in span(kx, w) {
                        let (i, p) = (srgb(x, y), f64::from(*range.get(x, y)).ln());
                        n += 1.0;
                        sp += p;
                        for c in 0..3 {
                            si[c] += i[c];
                            sip[c] += i[c] * p;
                            for d in 0..3 {
                                sii[c][d] += i[c] * i[d];
                            }
                        }
                    }
                }
                let mean = si.map(|v| v / n);
                let cov: [f64; 3] = std::array::from_fn(|c| sip[c] / n - mean[c] * sp / n);
                let sigma: [[f64; 3]; 3] = std::array::from_fn(|c| {
                    std::array::from_fn(|d| {
                        sii[c][d] / n - mean[c] * mean[d] + if c == d { eps } else { 0.0 }
                    })
                });
                let a: [f64; 3] = std::array::from_fn(|col| {
                    let mut m = sigma;
                    for (row, v) in m.iter_mut().zip(cov) {
                        row[col] = v;
                    }
                    det(m) / det(sigma)
                });
                let b = sp / n - (0..3).map(|c| a[c] * mean[c]).sum::<f64>();
                models[ky * w + kx] = [a[0], a[1], a[2], b];
            }
        }
        let mut q = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let (mut n, mut m) = (0.0, [0.0; 4]);
                for ky in span(y, h) {
                    for kx in span(x, w) {
                        n += 1.0;
                        for (s, v) in m.iter_mut().zip(models[ky * w + kx]) {
                            *s += v;
                        }
                    }
                }
                let i = srgb(x, y);
                q.push((0..3).map(|c| m[c] / n * i[c]).sum::<f64>() + m[3] / n);
            }
        }
        q
    }

    /// At a coarsening of 1 the fast filter is the guided filter itself: the reference
    /// equals the direct computation of eq. 14 within f64 rounding.
    #[test]
    fn the_reference_is_the_colour_guided_filter() {
        let (w, h) = (23, 17);
        let image = Grid::from_fn(w, h, |x, y| {
            let t = (x * 7 + y * 13) % 11;
            [
                t as f32 / 11.0,
                ((x * y) % 5) as f32 / 5.0,
                if x > 12 { 0.9 } else { 0.2 },
            ]
        });
        let range = Grid::from_fn(w, h, |x, y| {
            if x > 12 && y < 9 {
                400.0
            } else {
                5.0 + ((x * 3 + y) % 7) as f32
            }
        });
        let opts = Refine {
            radius_px: 3.0,
            epsilon: 1e-3,
            subsample: 1,
        };
        let out = guided_range_reference(&image, &range, &opts).unwrap();
        let direct = he_et_al(&image, &range, 3, 1e-3);
        for (k, (v, q)) in out.as_slice().iter().zip(&direct).enumerate() {
            let diff = (f64::from(*v).ln() - q).abs();
            assert!(diff < 1e-5, "pixel {k}: {v} against exp({q})");
        }
    }

    /// Two colours of one luminance are an edge to the colour guide: a light grey facade
    /// against a blue sky keeps its own range two pixels from the sky (a luminance guide
    /// sees no edge there and gives both sides the log-mean of the window).
    #[test]
    fn an_edge_between_colours_of_one_luminance_is_kept() {
        let (w, h) = (96, 64);
        let sky = [0.30f32, 0.45, 0.85];
        let luminance = |c: [f32; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
        let grey = [luminance(sky); 3];
        let image = Grid::from_fn(w, h, |x, _| if x < 48 { sky } else { grey });
        let range = Grid::from_fn(w, h, |x, _| if x < 48 { 1000.0f32 } else { 60.0 });
        let opts = Refine {
            radius_px: 8.0,
            ..Refine::default()
        };
        let out = guided_range_reference(&image, &range, &opts).unwrap();
        for y in 0..h {
            let (s, f) = (*out.get(45, y), *out.get(50, y));
            assert!((s / 1000.0 - 1.0).abs() < 0.1, "sky side {s}");
            assert!((f / 60.0 - 1.0).abs() < 0.1, "facade side {f}");
        }
    }

    /// An edge in the range that the image also has is kept sharp; range noise where the
    /// image is flat is smoothed.
    #[test]
    fn edges_the_image_has_are_kept_and_noise_is_smoothed() {
        let (w, h) = (96, 64);
        let image = Grid::from_fn(w, h, |x, _| if x < 48 { [0.05; 3] } else { [0.8; 3] });
        let truth = |x: usize| if x < 48 { 5.0f32 } else { 50.0 };
        let mut rng = 1u64;
        let noisy = Grid::from_fn(w, h, |x, _| {
            rng = rng
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let n = ((rng >> 33) as f32 / (1u64 << 31) as f32 - 0.5) * 0.2;
            truth(x) * (1.0 + n)
        });
        let opts = Refine {
            radius_px: 8.0,
            ..Refine::default()
        };
        let out = guided_range_reference(&image, &noisy, &opts).unwrap();
        let err = |m: &ScalarMap| {
            let mut e = 0.0;
            for y in 0..h {
                for x in 0..w {
                    e += (f64::from(*m.get(x, y)) / f64::from(truth(x)) - 1.0).abs();
                }
            }
            e / (w * h) as f64
        };
        let (before, after) = (err(&noisy), err(&out));
        assert!(
            after < 0.3 * before,
            "mean relative error {before:.4} → {after:.4}"
        );
        // Two pixels from a 10x step, within 10 % of its own side (a box filter of the
        // same window would give the log-mean of both sides there, 2.7x off).
        for y in 0..h {
            assert!(
                (out.get(46, y) / 5.0 - 1.0).abs() < 0.1,
                "{}",
                out.get(46, y)
            );
            assert!(
                (out.get(49, y) / 50.0 - 1.0).abs() < 0.1,
                "{}",
                out.get(49, y)
            );
        }
    }
}
