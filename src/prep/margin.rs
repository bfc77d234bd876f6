//! The horizon margin: sky pixels within `µ` of the scene, relaxed by Jacobi iterations.

use super::components::neighbours4;
use super::edt::{squared_edt_with, NO_SITE};
use rayon::prelude::*;

/// Sky pixels whose Euclidean distance to the nearest scene (non-sky) pixel is at most
/// `mu`, as linear indices in raster order.
///
/// The distance transform runs on the bounding box of the sky dilated by `ceil(mu)` only:
/// a scene pixel within `mu` of a sky pixel lies inside that window, so the thresholded
/// result is exact while the work and memory scale with the sky's extent, not the image's.
pub(crate) fn margin_pixels(
    sky: &[bool],
    width: usize,
    height: usize,
    sky_bbox: [usize; 4],
    mu: f32,
) -> Vec<u32> {
    let r = mu.ceil() as usize;
    let (x0, y0) = (sky_bbox[0].saturating_sub(r), sky_bbox[1].saturating_sub(r));
    let (x1, y1) = (
        sky_bbox[2].saturating_add(r).min(width - 1),
        sky_bbox[3].saturating_add(r).min(height - 1),
    );
    let (ww, wh) = (x1 - x0 + 1, y1 - y0 + 1);
    let d2 = squared_edt_with(ww, wh, |x, y| !sky[(y + y0) * width + x + x0]);
    let mu2 = (mu as f64) * (mu as f64);
    let mut out = Vec::new();
    for (i, &d) in d2.iter().enumerate() {
        if d != 0 && d != NO_SITE && d as f64 <= mu2 {
            out.push(((i / ww + y0) * width + i % ww + x0) as u32);
        }
    }
    out
}

/// Jacobi iterations of the discrete Laplace equation on the `margin` pixels of `work`:
/// each sweep replaces every margin value by the mean of its in-image 4-neighbours, all
/// read from the previous sweep. Pixels outside `margin` are the Dirichlet boundary (scene
/// values on one side, `Smax` on the other) and never change.
pub(crate) fn jacobi(
    work: &mut [f32],
    width: usize,
    height: usize,
    margin: &[u32],
    iterations: usize,
) {
    let mut next = vec![0.0f32; margin.len()];
    for _ in 0..iterations {
        let read: &[f32] = work;
        next.par_iter_mut()
            .zip(margin)
            .for_each(|(n, &p)| *n = neighbour_mean(read, width, height, p as usize));
        for (&v, &p) in next.iter().zip(margin) {
            work[p as usize] = v;
        }
    }
}

/// Mean of the in-image 4-neighbours of pixel `p`.
#[inline]
fn neighbour_mean(work: &[f32], width: usize, height: usize, p: usize) -> f32 {
    let (mut sum, mut n) = (0.0f32, 0.0f32);
    for q in neighbours4(p, p % width, p / width, width, height)
        .into_iter()
        .flatten()
    {
        sum += work[q];
        n += 1.0;
    }
    sum / n
}
