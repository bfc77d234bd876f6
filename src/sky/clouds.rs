//! Seeded synthetic clouds over a fisheye sky image, for the turbidity estimator's tests
//! and benchmark (paper 002 only says that RANSAC removes cloudy pixels; this makes sky
//! images where the cloudy pixels are known).
//!
//! A few smooth blobs are placed at random inside the horizon circle. Each blob is a
//! disc in the image whose radius is modulated by three low angular harmonics (so that
//! blobs are lumpy, not round), with a soft edge: the cloud opacity α falls from 1 to 0
//! over [`CloudOptions::edge_px`] px by a smoothstep. Where blobs overlap, the largest α
//! wins. A pixel's colour becomes
//!
//! ```text
//! (1 − α)·clear + α·(k·Y_clear, k·Y_clear, k·Y_clear)
//! ```
//!
//! a desaturated (grey) cloud whose luminance is k times the clear sky's behind it, k
//! drawn per blob in [`CloudOptions::brightness`] (real cumulus are 1.5 to 3 times as
//! bright as the blue sky around them). Its luminance is Y_clear·(1 + α(k − 1)): cloud
//! pixels are always brighter and greyer than the clear-sky model, as the estimator
//! assumes. The blobs' common size is set by bisection so that the fraction of the sky
//! circle's pixels with α > 0 is the coverage asked for.

use super::fisheye::Fisheye;
use crate::error::{Error, Result};
use crate::raster::RgbImage;
use crate::rng::SplitMix64;
use std::f64::consts::PI;

/// How [`add_clouds`] covers the sky.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CloudOptions {
    /// Fraction of the sky circle's pixels touched by cloud (α > 0), in [0, 0.9].
    pub coverage: f64,
    /// Number of blobs, ≥ 1.
    pub blobs: usize,
    /// Range [min, max] of the luminance factor k of a cloud over the clear sky.
    pub brightness: [f64; 2],
    /// Width of the soft edge of a blob, px.
    pub edge_px: f64,
    /// Seed: the same seed gives the same clouds.
    pub seed: u64,
}

impl Default for CloudOptions {
    /// 20 % of the sky in 5 blobs, 1.5 to 2.5 times as bright as the sky, 3 px edges.
    fn default() -> Self {
        CloudOptions {
            coverage: 0.2,
            blobs: 5,
            brightness: [1.5, 2.5],
            edge_px: 3.0,
            seed: 0,
        }
    }
}

/// What [`add_clouds`] did.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CloudReport {
    /// Fraction of the sky circle's pixels touched by cloud (α > 0).
    pub coverage: f64,
    /// Pixels touched by cloud.
    pub pixels: usize,
    /// Fraction of the sky circle's pixels that are fully cloud (α = 1).
    pub opaque: f64,
}

/// One blob: centre and base radius (px), harmonic amplitudes and phases, brightness.
struct Blob {
    cx: f64,
    cy: f64,
    radius: f64,
    harmonics: [(f64, f64); 3],
    k: f64,
}

impl Blob {
    /// Radius of the blob toward image angle `psi`, for a size scale `scale`.
    fn radius_at(&self, psi: f64, scale: f64) -> f64 {
        let lumps: f64 = self
            .harmonics
            .iter()
            .enumerate()
            .map(|(m, (a, phase))| a * ((m as f64 + 2.0) * psi + phase).cos())
            .sum();
        self.radius * scale * (1.0 + lumps)
    }

    /// Opacity at (x, y), for scale `scale` and edge width `edge`.
    fn alpha(&self, x: f64, y: f64, scale: f64, edge: f64) -> f64 {
        let (dx, dy) = (x - self.cx, y - self.cy);
        let d = (dx * dx + dy * dy).sqrt();
        let r = self.radius_at(dy.atan2(dx), scale);
        // 1 inside r − edge, 0 beyond r, smoothstep between.
        let t = ((r - d) / edge).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    }
}

/// Covers `image` (a square fisheye sky image, sky inside the inscribed circle) with
/// clouds as the module docs say, and returns the coverage reached (within 0.5 % of the
/// pixels of the one asked for, or an error).
pub fn add_clouds(
    image: &mut RgbImage,
    fisheye: &Fisheye,
    opts: &CloudOptions,
) -> Result<CloudReport> {
    check(image, opts)?;
    let size = image.width();
    let half = size as f64 / 2.0;
    let mut rng = SplitMix64::new(opts.seed);
    let blobs: Vec<Blob> = (0..opts.blobs)
        .map(|_| {
            // Uniform over the disc of radius 0.85 R: blobs may reach the horizon.
            let rho = half * 0.85 * rng.unit().sqrt();
            let angle = rng.range(-PI, PI);
            Blob {
                cx: half + rho * angle.cos(),
                cy: half + rho * angle.sin(),
                radius: rng.range(0.6, 1.4),
                harmonics: [0; 3].map(|_| (rng.range(0.0, 0.15), rng.range(-PI, PI))),
                k: rng.range(opts.brightness[0], opts.brightness[1]),
            }
        })
        .collect();
    let sky: Vec<(usize, usize)> = (0..size)
        .flat_map(|y| (0..size).map(move |x| (x, y)))
        .filter(|&(x, y)| fisheye.pixel_direction(size, x, y).is_some())
        .collect();
    if sky.is_empty() {
        return Err(Error::invalid(
            "size",
            size,
            "a sky image with pixels inside its circle",
        ));
    }
    let alpha_at = |x: usize, y: usize, scale: f64| -> (f64, usize) {
        let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
        let mut best = (0.0, 0);
        for (i, b) in blobs.iter().enumerate() {
            let a = b.alpha(px, py, scale, opts.edge_px);
            if a > best.0 {
                best = (a, i);
            }
        }
        best
    };
    let covered = |scale: f64| {
        sky.iter()
            .filter(|&&(x, y)| alpha_at(x, y, scale).0 > 0.0)
            .count()
    };
    let target = opts.coverage * sky.len() as f64;
    // Coverage grows with the scale: bisect it, from nothing to the whole image.
    let (mut lo, mut hi) = (0.0, 2.0 * size as f64);
    let mut scale = 0.0;
    if opts.coverage > 0.0 {
        for _ in 0..60 {
            scale = 0.5 * (lo + hi);
            let c = covered(scale) as f64;
            if (c - target).abs() <= 0.005 * sky.len() as f64 {
                break;
            }
            if c < target {
                lo = scale;
            } else {
                hi = scale;
            }
        }
    }
    let (mut pixels, mut opaque) = (0, 0);
    if opts.coverage > 0.0 {
        for &(x, y) in &sky {
            let (a, i) = alpha_at(x, y, scale);
            if a <= 0.0 {
                continue;
            }
            pixels += 1;
            if a >= 1.0 {
                opaque += 1;
            }
            let p = image.get_mut(x, y);
            let grey = (blobs[i].k * super::luminance(*p)) as f32;
            let a = a as f32;
            *p = p.map(|c| (1.0 - a) * c + a * grey);
        }
    }
    let report = CloudReport {
        coverage: pixels as f64 / sky.len() as f64,
        pixels,
        opaque: opaque as f64 / sky.len() as f64,
    };
    if (report.coverage - opts.coverage).abs() > 0.005 {
        return Err(Error::invalid(
            "coverage",
            opts.coverage,
            format!(
                "a coverage these {} blobs can reach (got {:.3})",
                opts.blobs, report.coverage
            ),
        ));
    }
    Ok(report)
}

fn check(image: &RgbImage, opts: &CloudOptions) -> Result<()> {
    if image.width() != image.height() || image.is_empty() {
        return Err(Error::invalid(
            "sky image size",
            format!("{}x{}", image.width(), image.height()),
            "a square fisheye image",
        ));
    }
    if !(opts.coverage.is_finite() && (0.0..=0.9).contains(&opts.coverage)) {
        return Err(Error::invalid(
            "coverage",
            opts.coverage,
            "a fraction in [0, 0.9]",
        ));
    }
    if opts.blobs == 0 {
        return Err(Error::invalid("blobs", 0, "at least 1 blob"));
    }
    let [lo, hi] = opts.brightness;
    if !(lo.is_finite() && hi.is_finite() && lo >= 1.0 && hi >= lo) {
        return Err(Error::invalid(
            "brightness",
            format!("{lo}..{hi}"),
            "a range of factors ≥ 1 (clouds brighter than the sky), min ≤ max",
        ));
    }
    if !(opts.edge_px.is_finite() && opts.edge_px > 0.0) {
        return Err(Error::invalid(
            "edge_px",
            opts.edge_px,
            "an edge width > 0 px",
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sky::{render_sky_image, PreethamSky};

    #[test]
    fn clouds_cover_what_is_asked_brighter_and_greyer() {
        let sky = PreethamSky::new(3.0, 1.0, 0.5).unwrap();
        let f = Fisheye::default();
        let clear = render_sky_image(&sky, 120, &f).unwrap();
        for coverage in [0.05, 0.2, 0.4] {
            let mut cloudy = clear.clone();
            let opts = CloudOptions {
                coverage,
                seed: 7,
                ..CloudOptions::default()
            };
            let r = add_clouds(&mut cloudy, &f, &opts).unwrap();
            assert!((r.coverage - coverage).abs() <= 0.005, "{r:?}");
            assert!(r.opaque > 0.0 && r.opaque <= r.coverage);
            let mut changed = 0;
            for (c, s) in cloudy.as_slice().iter().zip(clear.as_slice()) {
                if c != s {
                    changed += 1;
                    let (yc, ys) = (crate::sky::luminance(*c), crate::sky::luminance(*s));
                    assert!(yc >= ys * 0.9999, "cloud darker: {yc} < {ys}");
                    // Greyer: the blue-to-red ratio moves toward 1.
                    let tint = |p: &[f32; 3]| (p[2] / p[0].max(1e-9) - 1.0).abs();
                    assert!(tint(c) <= tint(s) + 1e-4, "{c:?} vs {s:?}");
                }
            }
            assert_eq!(changed, r.pixels);
            // Same seed, same clouds.
            let mut again = clear.clone();
            add_clouds(&mut again, &f, &opts).unwrap();
            assert_eq!(again, cloudy);
        }
    }

    #[test]
    fn bad_options_are_named() {
        let mut img = RgbImage::filled(10, 12, [0.0; 3]);
        let f = Fisheye::default();
        let e = add_clouds(&mut img, &f, &CloudOptions::default()).unwrap_err();
        assert!(e.to_string().contains("square"), "{e}");
        let mut img = RgbImage::filled(10, 10, [1.0; 3]);
        let opts = CloudOptions {
            coverage: 1.5,
            ..CloudOptions::default()
        };
        let e = add_clouds(&mut img, &f, &opts).unwrap_err();
        assert!(e.to_string().contains("coverage"), "{e}");
    }
}
