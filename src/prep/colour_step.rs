//! Colour steps between neighbouring pixels, relative to their luminance, and the
//! texture they add up to: what the image-guided sky detector and the colour-guided hole
//! fill ask of the photo.

use rayon::prelude::*;

/// Largest channel difference of `p` and `q` over the brighter one's luminance (at least
/// `eps`); NaN for non-finite colours, so that every test on it fails.
#[inline]
pub(crate) fn relative_step(colour: &[[f32; 3]], lum: &[f32], p: usize, q: usize, eps: f32) -> f32 {
    step_between(colour[p], colour[q], lum[p], lum[q], eps)
}

/// [`relative_step`] of two colours `a` and `b` of luminance `la` and `lb`.
#[inline]
fn step_between(a: [f32; 3], b: [f32; 3], la: f32, lb: f32, eps: f32) -> f32 {
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
    d / la.max(lb).max(eps)
}

/// Rec. 709 luminance of every pixel, clamped at 0 (a NaN sum becomes 0 too: `max`
/// returns its other argument).
pub(crate) fn luminance(colour: &[[f32; 3]]) -> Vec<f32> {
    colour
        .par_iter()
        .map(|&c| luminance_of(c).max(0.0))
        .collect()
}

/// The Rec. 709 luminance of one linear colour, not clamped.
#[inline]
pub(crate) fn luminance_of(c: [f32; 3]) -> f32 {
    let w = super::airlight::REC709_LUMA;
    w[0] * c[0] + w[1] * c[1] + w[2] * c[2]
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
    let mut largest = vec![0.0f32; colour.len()];
    // In bands of rows, each row's steps to the row below kept as the next row's steps
    // above (a step is symmetric), and every step of a row taken over whole slices, which
    // the compiler turns into vector code (with the box mean, 190 -> 120 ms at 12 MP on
    // two cores, where each pixel asked its neighbours by index).
    let band = TEXTURE_BAND_ROWS * width.max(1);
    largest
        .par_chunks_mut(band)
        .enumerate()
        .for_each(|(b, rows)| {
            let row = |y: usize| (&colour[y * width..][..width], &lum[y * width..][..width]);
            let vertical = |y: usize, out: &mut Vec<f32>| {
                let ((a, la), (c, lc)) = (row(y), row(y + 1));
                steps_between(a, la, c, lc, eps, out);
            };
            let (mut up, mut down, mut across) = (Vec::new(), Vec::new(), Vec::new());
            let first = b * TEXTURE_BAND_ROWS;
            if first > 0 {
                vertical(first - 1, &mut up);
            }
            for (i, out) in rows.chunks_mut(width).enumerate() {
                let y = first + i;
                let (c, l) = row(y);
                steps_between(
                    &c[1..],
                    &l[1..],
                    &c[..width - 1],
                    &l[..width - 1],
                    eps,
                    &mut across,
                );
                down.clear();
                if y + 1 < height {
                    vertical(y, &mut down);
                }
                largest_of_row(out, &across, &up, &down);
                std::mem::swap(&mut up, &mut down);
            }
        });
    box3(&largest, width, height)
}

/// Rows per parallel task of [`texture`]: each task measures the steps above its first row
/// once more.
const TEXTURE_BAND_ROWS: usize = 32;

/// The relative steps from each colour of `a` to the one of `b` beside it, into `out`.
fn steps_between(
    a: &[[f32; 3]],
    la: &[f32],
    b: &[[f32; 3]],
    lb: &[f32],
    eps: f32,
    out: &mut Vec<f32>,
) {
    out.clear();
    out.extend(
        a.iter()
            .zip(b)
            .zip(la.iter().zip(lb))
            .map(|((&a, &b), (&la, &lb))| step_between(a, b, la, lb, eps)),
    );
}

/// Each pixel's largest step of a row: `across[x]` between pixels x and x + 1 (empty for a
/// one-pixel row), `up` and `down` to the rows above and below (empty at the image's
/// edges), taken in the order left, right, up, down; a NaN is kept until a later step
/// replaces it.
fn largest_of_row(out: &mut [f32], across: &[f32], up: &[f32], down: &[f32]) {
    let keep = |m: f32, s: f32| if s.is_nan() { s } else { m.max(s) };
    out.fill(0.0);
    if let Some(right_of) = out.get_mut(1..) {
        right_of
            .iter_mut()
            .zip(across)
            .for_each(|(m, &s)| *m = keep(*m, s));
    }
    out.iter_mut()
        .zip(across)
        .for_each(|(m, &s)| *m = keep(*m, s));
    out.iter_mut().zip(up).for_each(|(m, &s)| *m = keep(*m, s));
    out.iter_mut()
        .zip(down)
        .for_each(|(m, &s)| *m = keep(*m, s));
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

    /// Each pixel's largest relative step to a 4-neighbour, pixel by pixel, in the order
    /// left, right, up, down.
    fn largest_steps_by_pixel(
        colour: &[[f32; 3]],
        lum: &[f32],
        width: usize,
        height: usize,
    ) -> Vec<f32> {
        (0..width * height)
            .map(|p| {
                let (x, y) = (p % width, p / width);
                let neighbours = [
                    (x > 0).then(|| p - 1),
                    (x + 1 < width).then(|| p + 1),
                    (y > 0).then(|| p - width),
                    (y + 1 < height).then(|| p + width),
                ];
                let mut m = 0.0f32;
                for q in neighbours.into_iter().flatten() {
                    let s = relative_step(colour, lum, p, q, 1e-3);
                    m = if s.is_nan() { s } else { m.max(s) };
                }
                m
            })
            .collect()
    }

    /// The banded, sliced texture equals its definition to the bit: sizes across the
    /// bands' edges, one-pixel rows and columns, and NaN and infinite colours, whose NaN
    /// steps a later neighbour may replace.
    #[test]
    fn the_texture_is_its_definition_to_the_bit() {
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 40) as f32 / (1u64 << 24) as f32
        };
        let sizes = [
            (1, 1),
            (1, 70),
            (70, 1),
            (2, 2),
            (17, 33),
            (9, 2 * TEXTURE_BAND_ROWS + 3),
        ];
        for (width, height) in sizes {
            let colour: Vec<[f32; 3]> = (0..width * height)
                .map(|_| match (next() * 40.0) as u32 {
                    0 => [f32::NAN, 0.5, 0.5],
                    1 => [0.5, f32::INFINITY, 0.5],
                    _ => [next(), next(), next()],
                })
                .collect();
            let lum = luminance(&colour);
            let got = texture(&colour, &lum, width, height, 1e-3);
            let want = box3(
                &largest_steps_by_pixel(&colour, &lum, width, height),
                width,
                height,
            );
            for (p, (g, w)) in got.iter().zip(&want).enumerate() {
                assert_eq!(
                    g.to_bits(),
                    w.to_bits(),
                    "{width}x{height}, pixel {p}: {g} against {w}"
                );
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
