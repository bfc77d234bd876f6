//! Colour steps between neighbouring pixels, relative to their luminance, and the
//! texture they add up to: what the image-guided sky detector and the colour-guided hole
//! fill ask of the photo.

use rayon::prelude::*;

/// Largest channel difference of `p` and `q` over the brighter one's luminance (at least
/// `eps`); NaN for non-finite colours, so that every test on it fails.
#[inline]
pub(crate) fn relative_step(colour: &[[f32; 3]], lum: &[f32], p: usize, q: usize, eps: f32) -> f32 {
    let (a, b) = (colour[p], colour[q]);
    let d = (a[0] - b[0])
        .abs()
        .max((a[1] - b[1]).abs())
        .max((a[2] - b[2]).abs());
    // `&`, not `&&`: six tests without branches.
    let finite = a[0].is_finite()
        & a[1].is_finite()
        & a[2].is_finite()
        & b[0].is_finite()
        & b[1].is_finite()
        & b[2].is_finite();
    let d = if finite { d } else { f32::NAN };
    d / lum[p].max(lum[q]).max(eps)
}

/// Rec. 709 luminance of every pixel, clamped at 0 (a NaN sum becomes 0 too: `max`
/// returns its other argument).
pub(crate) fn luminance(colour: &[[f32; 3]]) -> Vec<f32> {
    let w = super::airlight::REC709_LUMA;
    colour
        .par_iter()
        .map(|c| (w[0] * c[0] + w[1] * c[1] + w[2] * c[2]).max(0.0))
        .collect()
}

/// The 3 x 3 mean (clipped at the borders) of each pixel's largest relative step to a
/// 4-neighbour (a NaN step is kept unless a later neighbour's step, in the order left,
/// right, up, down, replaces it).
pub(crate) fn texture(
    colour: &[[f32; 3]],
    lum: &[f32],
    width: usize,
    height: usize,
    eps: f32,
) -> Vec<f32> {
    let step = |p: usize, q: usize| relative_step(colour, lum, p, q, eps);
    // A step is symmetric: each pair of neighbours is measured once, the vertical pairs
    // here (the step from each pixel to the one below it), the horizontal ones per row.
    let mut down = vec![0.0f32; width * height.saturating_sub(1)];
    down.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        for (x, out) in row.iter_mut().enumerate() {
            let p = y * width + x;
            *out = step(p, p + width);
        }
    });
    let mut largest = vec![0.0f32; colour.len()];
    largest
        .par_chunks_mut(width)
        .enumerate()
        .for_each(|(y, row)| {
            let across: Vec<f32> = (1..width)
                .map(|x| step(y * width + x - 1, y * width + x))
                .collect();
            for (x, out) in row.iter_mut().enumerate() {
                let neighbours = [
                    x.checked_sub(1).map(|l| across[l]),
                    across.get(x).copied(),
                    y.checked_sub(1).map(|u| down[u * width + x]),
                    (y + 1 < height).then(|| down[y * width + x]),
                ];
                *out = neighbours.into_iter().flatten().fold(0.0f32, |m, s| {
                    if s.is_nan() {
                        s
                    } else {
                        m.max(s)
                    }
                });
            }
        });
    box3(&largest, width, height)
}

/// Mean over the 3 x 3 window clipped to the image, by two 1D passes.
fn box3(v: &[f32], width: usize, height: usize) -> Vec<f32> {
    let mut rows = vec![0.0f32; v.len()];
    rows.par_chunks_mut(width)
        .zip(v.par_chunks(width))
        .for_each(|(out, row)| mean3(row, out));
    let mut out = vec![0.0f32; v.len()];
    out.par_chunks_mut(width).enumerate().for_each(|(y, out)| {
        let row = |j: usize| &rows[j * width..(j + 1) * width];
        let here = row(y);
        match (
            y.checked_sub(1).map(row),
            (y + 1 < height).then(|| row(y + 1)),
        ) {
            (Some(up), Some(down)) => {
                for (((o, &a), &b), &c) in out.iter_mut().zip(up).zip(here).zip(down) {
                    *o = (a + b + c) / 3.0;
                }
            }
            (Some(other), None) | (None, Some(other)) => {
                // In the order of the rows, as the 3-row sum adds them.
                let (first, second) = if y == 0 { (here, other) } else { (other, here) };
                for ((o, &a), &b) in out.iter_mut().zip(first).zip(second) {
                    *o = (a + b) / 2.0;
                }
            }
            (None, None) => out.copy_from_slice(here),
        }
    });
    out
}

/// The mean of each value and its neighbours in `row` (two at the ends), into `out`.
fn mean3(row: &[f32], out: &mut [f32]) {
    let n = row.len();
    if n == 1 {
        out[0] = row[0];
        return;
    }
    out[0] = (row[0] + row[1]) / 2.0;
    out[n - 1] = (row[n - 2] + row[n - 1]) / 2.0;
    for (o, w) in out[1..n - 1].iter_mut().zip(row.windows(3)) {
        *o = (w[0] + w[1] + w[2]) / 3.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mean of the 3 x 3 window clipped to the image, pixel by pixel.
    fn clipped_mean(v: &[f32], width: usize, height: usize, x: usize, y: usize) -> f32 {
        let (mut sum, mut n) = (0.0, 0.0);
        for j in y.saturating_sub(1)..(y + 2).min(height) {
            for i in x.saturating_sub(1)..(x + 2).min(width) {
                sum += v[j * width + i];
                n += 1.0;
            }
        }
        sum / n
    }

    #[test]
    fn box3_is_a_clipped_mean() {
        for (width, height) in [(3, 2), (5, 4), (1, 4), (4, 1), (1, 1)] {
            // Small whole numbers: every mean is exact whichever way it is summed.
            let v: Vec<f32> = (0..width * height).map(|i| (i * i % 7) as f32).collect();
            let b = box3(&v, width, height);
            for y in 0..height {
                for x in 0..width {
                    let want = clipped_mean(&v, width, height, x, y);
                    let got = b[y * width + x];
                    assert!((got - want).abs() < 1e-6, "{width}x{height} ({x}, {y})");
                }
            }
        }
    }

    #[test]
    fn the_texture_is_the_mean_of_the_largest_steps() {
        // Grey, with one pixel twice as bright in the middle of a 3 x 3 image.
        let mut colour = vec![[0.2f32; 3]; 9];
        colour[4] = [0.4; 3];
        let lum = luminance(&colour);
        let t = texture(&colour, &lum, 3, 3, 1e-6);
        // The centre and its 4 neighbours step by 0.2 over the brighter 0.4; corners by 0.
        let largest = [0.0, 0.5, 0.0, 0.5, 0.5, 0.5, 0.0, 0.5, 0.0];
        for (p, &got) in t.iter().enumerate() {
            let want = clipped_mean(&largest, 3, 3, p % 3, p / 3);
            assert!((got - want).abs() < 1e-6, "pixel {p}: {got} against {want}");
        }
    }
}
