//! The airlight of a photo's sky at the horizon (paper 002, sec. 4): I∞(θ') from "the
//! pixels in the horizon region that have the highest intensity", the horizon region
//! being the visible sky with the largest zenith angles. Eq. 12 then carries it to any
//! zenith angle by ζ.

use crate::camera::Camera;
use crate::raster::{Grid, RgbImage};

/// How far above the lowest sky (in zenith angle) the horizon region reaches.
pub const HORIZON_BAND_DEG: f64 = 10.0;
/// The brightest fraction of the horizon region that gives I∞.
pub const BRIGHTEST_FRACTION: f64 = 0.1;

/// I∞(θ') and θ'.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HorizonLight {
    /// The median colour of the brightest horizon-region sky pixels, linear RGB.
    pub rgb: [f32; 3],
    /// Their mean zenith angle θ' (radians), at most [`super::ZETA_MAX_ZENITH_RAD`].
    pub zenith: f64,
    /// How many pixels it came from.
    pub pixels: usize,
}

/// The horizon's light of `image` (top row first) from its `sky` mask, each pixel's zenith
/// angle from `camera`'s ray (pitch and vertical field of view); `None` without sky.
pub fn horizon_light(image: &RgbImage, sky: &Grid<bool>, camera: &Camera) -> Option<HorizonLight> {
    let (w, h) = (image.width(), image.height());
    let zenith = |x: usize, y: usize| {
        let ray = camera.pixel_ray(x, h - 1 - y, w, h).normalize();
        ray.y.clamp(-1.0, 1.0).acos()
    };
    let sky_pixels: Vec<(usize, f64)> = (0..w * h)
        .filter(|&i| sky.as_slice()[i] && image.as_slice()[i].iter().all(|v| v.is_finite()))
        .map(|i| (i, zenith(i % w, i / w)))
        .collect();
    let lowest = sky_pixels.iter().map(|&(_, t)| t).fold(f64::NAN, f64::max);
    if lowest.is_nan() {
        return None;
    }
    let band = HORIZON_BAND_DEG.to_radians();
    let luminance = |c: [f32; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    let mut region: Vec<(usize, f64)> = sky_pixels
        .into_iter()
        .filter(|&(_, t)| t >= lowest - band)
        .collect();
    region.sort_by(|a, b| {
        luminance(image.as_slice()[b.0]).total_cmp(&luminance(image.as_slice()[a.0]))
    });
    let keep = ((region.len() as f64 * BRIGHTEST_FRACTION).ceil() as usize).clamp(1, region.len());
    let brightest = &region[..keep];
    let rgb = std::array::from_fn(|c| {
        let mut v: Vec<f32> = brightest
            .iter()
            .map(|&(i, _)| image.as_slice()[i][c])
            .collect();
        v.sort_by(f32::total_cmp);
        v[v.len() / 2]
    });
    // Sky seen below the level line (from a hill, or with a wrong pitch) counts as the
    // horizon, as eq. 13's ζ clamps it.
    let zenith = (brightest.iter().map(|&(_, t)| t).sum::<f64>() / keep as f64)
        .min(super::ZETA_MAX_ZENITH_RAD);
    Some(HorizonLight {
        rgb,
        zenith,
        pixels: keep,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_brightest_sky_near_the_horizon_gives_the_airlight() {
        // A level camera; sky in the top half, brighter toward the horizon, with a dark
        // cloud high up and a brighter column near the horizon.
        let camera = Camera {
            fov_y_deg: 60.0,
            ..Camera::default()
        };
        let (w, h) = (40, 30);
        let image: RgbImage = Grid::from_fn(w, h, |x, y| {
            let v = 0.3 + 0.5 * y as f32 / 15.0;
            if y < 3 {
                [0.05; 3]
            } else if x == 7 && y >= 12 {
                [0.95, 0.96, 1.0]
            } else {
                [v, v, v * 1.1]
            }
        });
        let sky = Grid::from_fn(w, h, |_, y| y < 15);
        let light = horizon_light(&image, &sky, &camera).unwrap();
        assert!(
            light.zenith > 80f64.to_radians(),
            "{}",
            light.zenith.to_degrees()
        );
        assert!(light.rgb[0] > 0.7, "{:?}", light.rgb);
        let none = Grid::filled(w, h, false);
        assert!(horizon_light(&image, &none, &camera).is_none());
    }
}
