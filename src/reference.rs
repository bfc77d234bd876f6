//! The CPU reference, in f64: the same three passes as the GPU pipeline (premultiply, N
//! diffusion steps, composite) from the same [`Schedule`] and per-pixel rates, with bilinear
//! reads that follow GL's clamp-to-edge rules exactly; and an exact Gaussian convolution
//! with clamp-to-edge borders to measure how close each scheme comes to a true blur.

use crate::blur::Blur;
use crate::camera::FrameInputs;
use crate::error::Result;
use crate::medium::{Medium, MediumSample, Pixel};
use crate::pipeline::{FogBlur, GAUSS_WEIGHTS};
use crate::raster::{Grid, RgbImage, RgbaImage, ScalarMap};
use crate::schedule::Schedule;

/// An RGBA image in f64, for the reference computations.
pub type Rgba64 = Grid<[f64; 4]>;

/// The diffused state in f64: τ·E (RGB) and τ (RGB). The GPU carries τ_r in the alpha of
/// the colour target and (τ_g, τ_b) in a second one only for a chromatic medium; for a
/// grey one the three are equal, so diffusing all six here is the same arithmetic.
pub type Field = Grid<[f64; 6]>;

/// The whole render of a photo on the CPU (no camera, time 0, as
/// [`crate::Renderer::render`]): what the GPU pipeline computes, in f64, through the same
/// seam (the medium per pixel, then the blur, then the composite). A frame's camera and
/// time: [`fog`] with [`FogBlur::Diffusion`].
pub fn render(
    image: &RgbImage,
    depth: &ScalarMap,
    medium: &dyn Medium,
    blur: &Blur,
) -> Result<RgbaImage> {
    render_frame(image, depth, medium, &FrameInputs::default(), blur)
}

/// [`render`] at `frame`'s camera and time.
fn render_frame(
    image: &RgbImage,
    depth: &ScalarMap,
    medium: &dyn Medium,
    frame: &FrameInputs,
    blur: &Blur,
) -> Result<RgbaImage> {
    let schedule = blur.schedule_for(medium)?;
    medium.validate_frame(frame)?;
    let samples = sample(depth, medium, frame, blur.sigma0);
    let rates = samples.map(|s| schedule.rate(s.sigma));
    let mut f = premultiply(image, &samples);
    diffuse(&mut f, &rates, &schedule);
    Ok(to_f32(&composite(&f, &samples)))
}

/// Engine fog on the CPU (see [`crate::pipeline::FogBlur`]): no blur, paper 001's
/// Gaussian in the fog's pass or in a second pass, or the diffusion blur (as [`render`]).
/// The blur weight's distance is rebuilt by the camera's inverse matrices (paper 002,
/// eq. 22-23), not by the GPU's rays, so that the comparison tests both. `frame` gives
/// the camera and the time, as to the pipeline.
pub fn fog(
    image: &RgbImage,
    depth: &ScalarMap,
    medium: &dyn Medium,
    frame: &FrameInputs,
    blur: &FogBlur,
) -> Result<RgbaImage> {
    let gauss = match blur {
        FogBlur::Diffusion(b) => return render_frame(image, depth, medium, frame, b),
        FogBlur::None => None,
        FogBlur::GaussSingle(g) | FogBlur::GaussSeparate(g) => Some(*g),
    };
    medium.validate()?;
    medium.validate_frame(frame)?;
    let samples = sample(depth, medium, frame, 1.0);
    let weights = match (gauss, medium.frame_camera(frame)) {
        (Some(g), Some(camera)) => {
            let (w, h) = (depth.width(), depth.height());
            let camera = camera.for_frame(w, h);
            Grid::from_fn(w, h, |x, y| {
                let d = f64::from(*depth.get(x, y));
                let p = camera.world_position_by_inverse(x, h - 1 - y, w, h, d);
                let tau = samples.get(x, y).transmission;
                let density = 1.0 - (tau[0] + tau[1] + tau[2]) / 3.0;
                g.weight(density, (p - camera.eye()).length())
            })
        }
        (Some(_), None) => {
            return Err(crate::Error::invalid(
                "blur",
                blur.name(),
                "a medium with a camera for the Gaussian blur",
            ))
        }
        _ => Grid::filled(depth.width(), depth.height(), 0.0),
    };
    let fog_over = |c: &Rgba64| {
        Grid::from_fn(c.width(), c.height(), |x, y| {
            let (m, e) = (samples.get(x, y), c.get(x, y));
            let mut out = [0.0, 0.0, 0.0, 1.0];
            for ch in 0..3 {
                let t = m.transmission[ch];
                out[ch] = t * e[ch] + (1.0 - t) * m.inscatter[ch];
            }
            out
        })
    };
    let mix_blurred = |c: &Rgba64| {
        let blurred = gauss5(c);
        Grid::from_fn(c.width(), c.height(), |x, y| {
            let b = *weights.get(x, y);
            <[f64; 4]>::lerp(*c.get(x, y), *blurred.get(x, y), b)
        })
    };
    let colour = rgba64_from_rgb(image);
    let out = match blur {
        FogBlur::GaussSingle(_) => fog_over(&mix_blurred(&colour)),
        FogBlur::GaussSeparate(_) => mix_blurred(&fog_over(&colour)),
        _ => fog_over(&colour),
    };
    Ok(to_f32(&out))
}

/// Paper 001's 5 x 5 Gaussian (σ = 1 px, normalised), edges clamped.
pub fn gauss5(img: &Rgba64) -> Rgba64 {
    let (w, h) = (img.width() as i64, img.height() as i64);
    Grid::from_fn(img.width(), img.height(), |x, y| {
        let mut acc = [0.0; 4];
        for j in -2i64..=2 {
            for i in -2i64..=2 {
                let wt = GAUSS_WEIGHTS[i.unsigned_abs() as usize]
                    * GAUSS_WEIGHTS[j.unsigned_abs() as usize];
                let sx = (x as i64 + i).clamp(0, w - 1) as usize;
                let sy = (y as i64 + j).clamp(0, h - 1) as usize;
                let p = img.get(sx, sy);
                for c in 0..4 {
                    acc[c] += wt * p[c];
                }
            }
        }
        acc
    })
}

/// The medium at every pixel of `depth` for `frame` (top row first, as
/// [`crate::Renderer`] takes it: buffer row `y` is GL row `height − 1 − y`).
pub fn sample(
    depth: &ScalarMap,
    medium: &dyn Medium,
    frame: &FrameInputs,
    sigma0: f64,
) -> Grid<MediumSample> {
    let (width, height) = (depth.width(), depth.height());
    Grid::from_fn(width, height, |x, y| {
        medium.sample(
            Pixel {
                x,
                y: height - 1 - y,
                width,
                height,
                depth: f64::from(*depth.get(x, y)),
                sigma0,
            },
            frame,
        )
    })
}

/// Pass 1: F = (τ·E, τ) (eq. 1-2).
pub fn premultiply(image: &RgbImage, samples: &Grid<MediumSample>) -> Field {
    Grid::from_fn(image.width(), image.height(), |x, y| {
        let e = image.get(x, y);
        let tau = samples.get(x, y).transmission;
        [
            tau[0] * f64::from(e[0]),
            tau[1] * f64::from(e[1]),
            tau[2] * f64::from(e[2]),
            tau[0],
            tau[1],
            tau[2],
        ]
    })
}

/// Passes 2..N+1: N steps of eq. 11-12 with the offsets and rates of `schedule`.
pub fn diffuse<const C: usize>(f: &mut Grid<[f64; C]>, rates: &Grid<f64>, schedule: &Schedule) {
    for k in 0..schedule.steps {
        *f = diffusion_step(f, rates, schedule, k);
    }
}

/// One step k of eq. 11: F(x) += Σ_u ½(ρ(x+u) + ρ(x))·(F(x+u) − F(x)).
pub fn diffusion_step<const C: usize>(
    f: &Grid<[f64; C]>,
    rates: &Grid<f64>,
    schedule: &Schedule,
    k: u32,
) -> Grid<[f64; C]> {
    let law = schedule.offset_law();
    Grid::from_fn(f.width(), f.height(), |x, y| {
        let centre = *f.get(x, y);
        let rate = *rates.get(x, y);
        let h = law.offset(rate, k);
        let (px, py) = (x as f64, y as f64);
        let mut out = centre;
        for (sx, sy) in [(px + h, py), (px - h, py), (px, py + h), (px, py - h)] {
            let w = 0.5 * (bilinear(rates, sx, sy) + rate);
            let n = bilinear(f, sx, sy);
            for c in 0..C {
                out[c] += w * (n[c] - centre[c]);
            }
        }
        out
    })
}

/// Pass N+2: τE + (1 − τ_blurred)·L∞ per channel (eq. 4), alpha 1 as the GPU output.
pub fn composite(f: &Field, samples: &Grid<MediumSample>) -> Rgba64 {
    Grid::from_fn(f.width(), f.height(), |x, y| {
        let p = f.get(x, y);
        let l = samples.get(x, y).inscatter;
        [
            p[0] + (1.0 - p[3]) * l[0],
            p[1] + (1.0 - p[4]) * l[1],
            p[2] + (1.0 - p[5]) * l[2],
            1.0,
        ]
    })
}

/// Values that can be read bilinearly: f64 scalars and RGBA.
pub trait Lerp: Copy {
    /// (1 − t)·a + t·b.
    fn lerp(a: Self, b: Self, t: f64) -> Self;
}

impl Lerp for f64 {
    fn lerp(a: f64, b: f64, t: f64) -> f64 {
        a + t * (b - a)
    }
}

impl<const C: usize> Lerp for [f64; C] {
    fn lerp(a: Self, b: Self, t: f64) -> Self {
        std::array::from_fn(|c| a[c] + t * (b[c] - a[c]))
    }
}

/// Bilinear read at pixel coordinates (`x`, `y`) (pixel centres at integers), with
/// GL_CLAMP_TO_EDGE: the two texels on each axis are clamped into the grid.
pub fn bilinear<T: Lerp>(g: &Grid<T>, x: f64, y: f64) -> T {
    let (x0, fx) = split(x);
    let (y0, fy) = split(y);
    let cx = |i: i64| i.clamp(0, g.width() as i64 - 1) as usize;
    let cy = |i: i64| i.clamp(0, g.height() as i64 - 1) as usize;
    let row = |yy: i64| T::lerp(*g.get(cx(x0), cy(yy)), *g.get(cx(x0 + 1), cy(yy)), fx);
    if fy == 0.0 {
        row(y0)
    } else {
        T::lerp(row(y0), row(y0 + 1), fy)
    }
}

fn split(v: f64) -> (i64, f64) {
    let i = v.floor();
    (i as i64, v - i)
}

/// Exact separable Gaussian blur of standard deviation `sigma` px with clamp-to-edge
/// borders, taps out to ⌈6σ⌉ (the truncated mass is below 1e-8).
pub fn gaussian_blur(img: &Rgba64, sigma: f64) -> Rgba64 {
    if sigma <= 0.0 {
        return img.clone();
    }
    let radius = (6.0 * sigma).ceil() as i64;
    let weights: Vec<f64> = (-radius..=radius)
        .map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp())
        .collect();
    let norm: f64 = weights.iter().sum();
    let weights: Vec<f64> = weights.iter().map(|w| w / norm).collect();
    let (w, h) = (img.width() as i64, img.height() as i64);
    let pass = |src: &Rgba64, horizontal: bool| {
        Grid::from_fn(src.width(), src.height(), |x, y| {
            let mut acc = [0.0; 4];
            for (j, wt) in weights.iter().enumerate() {
                let d = j as i64 - radius;
                let (sx, sy) = if horizontal {
                    ((x as i64 + d).clamp(0, w - 1), y as i64)
                } else {
                    (x as i64, (y as i64 + d).clamp(0, h - 1))
                };
                let p = src.get(sx as usize, sy as usize);
                for c in 0..4 {
                    acc[c] += wt * p[c];
                }
            }
            acc
        })
    };
    pass(&pass(img, true), false)
}

/// Widens an f32 RGB image to f64 RGBA with alpha 1.
pub fn rgba64_from_rgb(img: &RgbImage) -> Rgba64 {
    img.map(|p| [f64::from(p[0]), f64::from(p[1]), f64::from(p[2]), 1.0])
}

/// Narrows to f32.
pub fn to_f32(img: &Rgba64) -> RgbaImage {
    img.map(|p| p.map(|v| v as f32))
}

/// RMS and maximum absolute difference of the RGB channels of `a` and `b` over the window
/// that leaves `margin` px out on every side.
pub fn rgb_error(a: &RgbaImage, b: &RgbaImage, margin: usize) -> ErrorStats {
    assert_eq!(
        (a.width(), a.height()),
        (b.width(), b.height()),
        "error of different sizes"
    );
    let mut sum_sq = 0.0;
    let mut max_abs: f64 = 0.0;
    let mut n = 0usize;
    for y in margin..a.height().saturating_sub(margin) {
        for x in margin..a.width().saturating_sub(margin) {
            let (p, q) = (a.get(x, y), b.get(x, y));
            for c in 0..3 {
                let d = f64::from(p[c]) - f64::from(q[c]);
                sum_sq += d * d;
                max_abs = max_abs.max(d.abs());
                n += 1;
            }
        }
    }
    ErrorStats {
        rms: if n == 0 {
            0.0
        } else {
            (sum_sq / n as f64).sqrt()
        },
        max_abs,
        samples: n,
    }
}

/// Error figures between two images.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ErrorStats {
    /// Root mean square difference.
    pub rms: f64,
    /// Largest absolute difference.
    pub max_abs: f64,
    /// Number of channel samples compared.
    pub samples: usize,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::schedule::Scheme;

    #[test]
    fn bilinear_matches_gl_clamp_to_edge() {
        let g = Grid::from_vec(3, 1, vec![1.0, 2.0, 4.0]);
        assert_eq!(bilinear(&g, 0.5, 0.0), 1.5);
        assert_eq!(bilinear(&g, -3.0, 0.0), 1.0);
        assert_eq!(bilinear(&g, 2.25, 0.0), 4.0);
        assert_eq!(bilinear(&g, 1.75, 0.0), 3.5);
    }

    #[test]
    fn gaussian_preserves_mean_of_constant() {
        let img = Grid::filled(9, 7, [0.25, 0.5, 0.75, 1.0]);
        let out = gaussian_blur(&img, 2.0);
        for p in out.as_slice() {
            for (v, want) in p.iter().zip(img.get(0, 0)) {
                assert!((v - want).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn euler_on_impulse_reaches_target_variance() {
        // Far from borders, N Euler steps add exactly σ² − σ0² of variance per axis.
        let (n, c) = (61, 30);
        let mut f = Grid::from_fn(
            n,
            n,
            |x, y| {
                if (x, y) == (c, c) {
                    [1.0; 4]
                } else {
                    [0.0; 4]
                }
            },
        );
        let blur = Blur {
            scheme: Scheme::Euler,
            ..Blur::default()
        };
        let schedule = blur.schedule(3.0, "sigma").unwrap();
        let rates = Grid::filled(n, n, schedule.rate(3.0));
        diffuse(&mut f, &rates, &schedule);
        let var_x: f64 = (0..n)
            .flat_map(|y| (0..n).map(move |x| (x, y)))
            .map(|(x, y)| f.get(x, y)[0] * ((x as f64 - c as f64).powi(2)))
            .sum();
        assert!((var_x - 8.0).abs() < 1e-9, "variance {var_x}");
    }
}
