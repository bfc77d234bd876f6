//! A synthetic outdoor range map, for tests and benchmarks of [`crate::prep`].

use crate::raster::ScalarMap;
use crate::rng::SplitMix64;

/// Camera height above the ground plane, metres.
const CAMERA_HEIGHT: f64 = 1.6;

/// A deterministic outdoor range map of `width x height` pixels (range in metres, NaN =
/// unknown), the same for the same `seed`:
///
/// - a ground plane seen from 1.6 m up, its horizon at 42 % of the height;
/// - a tree line about 300 m away whose top is a ragged "foliage" horizon (two sines, a
///   per-column random walk and triangular tree crowns, 8 to 30 % of the height above the
///   horizon), with ragged unknown pockets along it, so the sky interface is complicated;
/// - NaN sky above it, touching the whole top row (plus a few known "leaf" pixels just
///   above the tree line);
/// - a few closer objects: planar building fronts (tilted, their tops at most 25 % of the
///   height above the horizon, so the sky stays one region along the top row) and spheres;
/// - small round holes (radius 2 to 10 px, scaled with the image) below the horizon until
///   they cover about 5 % of the image;
/// - a small deterministic measurement noise (about 0.2 %).
///
/// Every dimension scales with the image size (reference 1600 x 1120), so small maps for
/// tests look like the large one for the benchmark. Both sizes must be at least 16.
pub fn outdoor_scene(width: usize, height: usize, seed: u64) -> ScalarMap {
    assert!(
        width >= 16 && height >= 16,
        "outdoor_scene needs at least 16x16 pixels"
    );
    let mut rng = SplitMix64::new(seed);
    let s = Scale::new(width, height);
    let top = tree_line(&s, &mut rng);
    let far: Vec<f64> = (0..width).map(|_| rng.range(290.0, 310.0)).collect();
    let mut r = vec![f32::NAN; width * height];
    for y in 0..height {
        for x in 0..width {
            if (y as f64) >= top[x] {
                r[y * width + x] = background(&s, x, y, far[x]) as f32;
            }
        }
    }
    ragged_interface(&mut r, &s, &top, &far, &mut rng);
    objects(&mut r, &s, &mut rng);
    noise(&mut r, &mut rng);
    holes(&mut r, &s, &mut rng);
    ScalarMap::from_vec(width, height, r)
}

/// Image size and derived scales.
struct Scale {
    w: usize,
    h: usize,
    /// Pixels per reference pixel (1600 x 1120 reference).
    k: f64,
    /// Focal length in pixels.
    f: f64,
    /// Row of the ground horizon.
    yv: f64,
}

impl Scale {
    fn new(w: usize, h: usize) -> Self {
        let k = (w as f64 / 1600.0).min(h as f64 / 1120.0);
        Scale {
            w,
            h,
            k,
            f: w as f64,
            yv: 0.42 * h as f64,
        }
    }
}

/// Row where the sky ends, per column (real-valued).
fn tree_line(s: &Scale, rng: &mut SplitMix64) -> Vec<f64> {
    let (p1, p2) = (rng.range(0.0, 6.3), rng.range(0.0, 6.3));
    let trees: Vec<(f64, f64, f64)> = (0..12)
        .map(|_| {
            let cx = rng.range(0.0, s.w as f64);
            (
                cx,
                rng.range(20.0, 90.0) * s.k,
                rng.range(0.03, 0.12) * s.h as f64,
            )
        })
        .collect();
    let mut walk = 0.0f64;
    (0..s.w)
        .map(|x| {
            let xf = x as f64;
            walk = (walk + rng.range(-1.5, 1.5) * s.k).clamp(-6.0 * s.k, 6.0 * s.k);
            let crowns: f64 = trees
                .iter()
                .map(|&(cx, hw, ht)| ht * (1.0 - (xf - cx).abs() / hw).max(0.0))
                .fold(0.0, f64::max);
            let base = 0.12 * s.h as f64
                + 0.02 * s.h as f64 * (xf / (90.0 * s.k) + p1).sin()
                + 0.01 * s.h as f64 * (xf / (23.0 * s.k) + p2).sin();
            let above = (base + walk + crowns).clamp(0.08 * s.h as f64, 0.30 * s.h as f64);
            s.yv - above
        })
        .collect()
}

/// Range of the ground, or of the tree line where the ground is farther.
fn background(s: &Scale, x: usize, y: usize, far: f64) -> f64 {
    let dy = y as f64 + 0.5 - s.yv;
    let ground = if dy > 0.0 {
        s.f * CAMERA_HEIGHT / dy
    } else {
        f64::INFINITY
    };
    let dx = (x as f64 - 0.5 * s.w as f64) / s.f;
    if ground < far {
        ground * (1.0 + dx * dx).sqrt()
    } else {
        far + 3.0 * ((x as f64 * 0.37).sin() + (y as f64 * 0.23).cos())
    }
}

/// Foliage: unknown pockets just below the tree line, known leaves just above it.
fn ragged_interface(r: &mut [f32], s: &Scale, top: &[f64], far: &[f64], rng: &mut SplitMix64) {
    let band = (4.0 * s.k).max(2.0);
    for x in 0..s.w {
        let t = top[x];
        let y0 = (t - band).max(1.0) as usize;
        let y1 = ((t + band) as usize).min(s.h - 1);
        for y in y0..=y1 {
            let i = y * s.w + x;
            let u = rng.unit();
            if (y as f64) >= t && u < 0.25 {
                r[i] = f32::NAN;
            } else if (y as f64) < t && u < 0.08 {
                r[i] = (far[x] + rng.range(-5.0, 5.0)) as f32;
            }
        }
    }
}

/// Building fronts (tilted planes) and spheres in front of the background.
fn objects(r: &mut [f32], s: &Scale, rng: &mut SplitMix64) {
    for _ in 0..3 {
        let (cx, bw) = (
            rng.range(0.1, 0.9) * s.w as f64,
            rng.range(80.0, 220.0) * s.k,
        );
        let d = rng.range(25.0, 80.0);
        let (gx, gy) = (rng.range(-0.05, 0.05), rng.range(-0.02, 0.02));
        let foot = s.yv + s.f * CAMERA_HEIGHT / d;
        let y_top = (foot - s.f * rng.range(6.0, 15.0) / d).max(s.yv - 0.25 * s.h as f64);
        paint(r, s, cx - bw / 2.0, y_top, cx + bw / 2.0, foot, |x, y| {
            d + gx * (x - cx) + gy * (y - foot)
        });
    }
    for _ in 0..3 {
        let d = rng.range(8.0, 40.0);
        let rad_m = rng.range(1.0, 3.0);
        let rad = s.f * rad_m / d;
        let (cx, cy) = (
            rng.range(0.1, 0.9) * s.w as f64,
            s.yv + s.f * (CAMERA_HEIGHT) / d - rad,
        );
        paint(r, s, cx - rad, cy - rad, cx + rad, cy + rad, |x, y| {
            let q = ((x - cx).powi(2) + (y - cy).powi(2)) / (rad * rad);
            if q <= 1.0 {
                d - rad_m * (1.0 - q).sqrt()
            } else {
                f64::INFINITY
            }
        });
    }
}

/// Writes `min(r, f(x, y))` over a box (clipped to the image); NaN pixels are covered too.
fn paint(
    r: &mut [f32],
    s: &Scale,
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
    f: impl Fn(f64, f64) -> f64,
) {
    let cx = |v: f64| (v.max(0.0) as usize).min(s.w);
    let cy = |v: f64| (v.max(0.0) as usize).min(s.h);
    for y in cy(y0)..cy(y1) {
        for x in cx(x0)..cx(x1) {
            let v = f(x as f64, y as f64);
            let i = y * s.w + x;
            if v.is_finite() && (r[i].is_nan() || (v as f32) < r[i]) {
                r[i] = v as f32;
            }
        }
    }
}

/// Multiplicative noise of about 0.2 % on every known value.
fn noise(r: &mut [f32], rng: &mut SplitMix64) {
    for v in r.iter_mut().filter(|v| v.is_finite()) {
        *v *= (1.0 + 0.002 * rng.range(-1.0, 1.0)) as f32;
    }
}

/// Round holes below the horizon until about 5 % of the image is covered.
fn holes(r: &mut [f32], s: &Scale, rng: &mut SplitMix64) {
    let target = (0.05 * (s.w * s.h) as f64) as usize;
    let y_min = s.yv + 4.0;
    let mut made = 0;
    let mut attempts = 0;
    while made < target && attempts < 100_000 {
        attempts += 1;
        let rad = (rng.range(2.0, 10.0) * s.k).max(1.0);
        let (cx, cy) = (rng.range(0.0, s.w as f64), rng.range(y_min, s.h as f64));
        let (x0, x1) = (
            (cx - rad).max(0.0) as usize,
            ((cx + rad) as usize).min(s.w - 1),
        );
        let (y0, y1) = (
            (cy - rad).max(y_min) as usize,
            ((cy + rad) as usize).min(s.h - 1),
        );
        for y in y0..=y1 {
            for x in x0..=x1 {
                let i = y * s.w + x;
                let inside = (x as f64 - cx).powi(2) + (y as f64 - cy).powi(2) <= rad * rad;
                if inside && r[i].is_finite() {
                    r[i] = f32::NAN;
                    made += 1;
                }
            }
        }
    }
}
