//! The horizon's light by azimuth (paper 002, sec. 4): I∞(θ′) taken per azimuth sector
//! of the horizon region instead of one value for the whole image, so that fog toward
//! the sun is brighter than fog away from it.
//!
//! The image's horizontal extent is cut into sectors of equal azimuth (the camera's
//! field of view maps columns to azimuths); each sector's horizon light is found as
//! [`horizon_light`] finds the image's (the brightest sky of its horizon band), carried
//! to a common zenith angle by ζ (eq. 12-13), and expressed as a per-channel gain over
//! the whole image's light. The medium interpolates linearly between the sectors'
//! centres ([`crate::medium::aerial::HorizonSectors`]).
//!
//! Azimuths here are those of the camera's world frame: 0 along −z, 90° along +x
//! (clockwise seen from above, as a compass with −z to the north): [`ray_azimuth`].

use crate::atmosphere::{horizon_light, zeta, HorizonLight};
use crate::camera::Camera;
use crate::raster::{Grid, RgbImage};
use std::f64::consts::{PI, TAU};

/// Sectors across the image by default: about 7° each for a 60° wide view, fine
/// enough to follow the sky's brightness around the sun (the Preetham sky's horizon
/// varies over tens of degrees) and coarse enough that each holds sky to measure.
pub const DEFAULT_SECTORS: usize = 8;
/// The most sectors: beyond this, a sector holds a few columns of sky.
pub const MAX_SECTORS: usize = 64;

/// The azimuth of a world-space ray, radians: 0 along −z, π/2 along +x.
pub fn ray_azimuth(ray: glam::DVec3) -> f64 {
    ray.x.atan2(-ray.z)
}

/// `angle` brought into [−π, π).
pub fn wrap_pi(angle: f64) -> f64 {
    (angle + PI).rem_euclid(TAU) - PI
}

/// How a `width` x `height` image's columns map to azimuth sectors: `count` sectors of
/// `sector_width` radians, centred on `centre` (the image centre's azimuth).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SectorGeometry {
    /// Azimuth of the image centre's ray, radians ([`ray_azimuth`]).
    pub centre: f64,
    /// Each sector's width in azimuth, radians.
    pub sector_width: f64,
    /// How many sectors.
    pub count: usize,
}

impl SectorGeometry {
    /// `count` sectors over the azimuths that `camera` sees across an image of aspect
    /// `width`/`height`: from its left edge's ray to its right edge's, at mid-height.
    pub fn across(camera: &Camera, width: usize, height: usize, count: usize) -> Self {
        let aspect = width as f64 / height as f64;
        let centre = ray_azimuth(camera.ray_at_ndc(0.0, 0.0, aspect));
        let left = ray_azimuth(camera.ray_at_ndc(-1.0, 0.0, aspect));
        let right = ray_azimuth(camera.ray_at_ndc(1.0, 0.0, aspect));
        let span = wrap_pi(right - centre) - wrap_pi(left - centre);
        SectorGeometry {
            centre,
            sector_width: (span / count.max(1) as f64).max(1e-6),
            count: count.max(1),
        }
    }

    /// The sector holding azimuth `azimuth` (those beyond the image's edges go to the
    /// end sectors).
    pub fn sector(&self, azimuth: f64) -> usize {
        let pos = wrap_pi(azimuth - self.centre) / self.sector_width + self.count as f64 / 2.0;
        (pos.floor().max(0.0) as usize).min(self.count - 1)
    }

    /// The azimuth of sector `k`'s centre.
    pub fn sector_centre(&self, k: usize) -> f64 {
        self.centre + (k as f64 + 0.5 - self.count as f64 / 2.0) * self.sector_width
    }
}

/// The horizon's light per sector.
#[derive(Clone, Debug, PartialEq)]
pub struct HorizonByAzimuth {
    /// The sectors.
    pub geometry: SectorGeometry,
    /// The whole image's horizon light ([`horizon_light`]).
    pub overall: HorizonLight,
    /// Each sector's light as found in it, `None` where it shows no sky.
    pub found: Vec<Option<HorizonLight>>,
    /// Each sector's light over the overall one, per channel, both at the overall zenith
    /// angle θ′ (ζ carries a sector's to it); sectors without sky take their neighbours'
    /// by linear interpolation (the end ones, the nearest's).
    pub gains: Vec<[f32; 3]>,
}

/// The horizon's light of `image` (top row first) per azimuth sector: `count` sectors
/// across the image, each pixel's zenith angle and azimuth from `camera`'s ray, ζ at
/// `turbidity` carrying each sector's light to the overall zenith angle. `None` when
/// the `sky` mask holds no sky.
pub fn horizon_light_by_azimuth(
    image: &RgbImage,
    sky: &Grid<bool>,
    camera: &Camera,
    count: usize,
    turbidity: f64,
) -> Option<HorizonByAzimuth> {
    let overall = horizon_light(image, sky, camera)?;
    let (w, h) = (image.width(), image.height());
    let geometry = SectorGeometry::across(camera, w, h, count);
    let sector_of = Grid::from_fn(w, h, |x, y| {
        geometry.sector(ray_azimuth(camera.pixel_ray(x, h - 1 - y, w, h)))
    });
    let found: Vec<Option<HorizonLight>> = (0..geometry.count)
        .map(|k| {
            let mask = Grid::from_fn(w, h, |x, y| *sky.get(x, y) && *sector_of.get(x, y) == k);
            horizon_light(image, &mask, camera)
        })
        .collect();
    let measured: Vec<Option<[f32; 3]>> = found
        .iter()
        .map(|f| {
            f.map(|s| {
                let z = zeta(turbidity, overall.zenith, s.zenith);
                std::array::from_fn(|c| {
                    let o = overall.rgb[c];
                    if o > 0.0 {
                        (f64::from(s.rgb[c]) * z / f64::from(o)) as f32
                    } else {
                        1.0
                    }
                })
            })
        })
        .collect();
    Some(HorizonByAzimuth {
        geometry,
        overall,
        gains: fill_gaps(&measured),
        found,
    })
}

/// Per-sector gains of the horizon's light from the Preetham sky's luminance (eq. 6)
/// when the photo shows no sky to measure: the sun at zenith angle `sun_zenith` and at
/// `sun_azimuth` (radians, clockwise) from the image centre's azimuth, the sky's
/// luminance at zenith angle `horizon_zenith` toward each sector's centre, over its value
/// toward the image centre (so the light given or estimated is the centre's). Grey gains:
/// the model's chromaticity varies far less than its luminance.
pub fn sun_gains(
    geometry: &SectorGeometry,
    turbidity: f64,
    sun_zenith: f64,
    sun_azimuth: f64,
    horizon_zenith: f64,
) -> crate::Result<Vec<[f32; 3]>> {
    let sky = super::PreethamSky::new(turbidity, sun_zenith, sun_azimuth)?;
    let centre = sky.luminance(horizon_zenith, 0.0);
    Ok((0..geometry.count)
        .map(|k| {
            let phi = geometry.sector_centre(k) - geometry.centre;
            [(sky.luminance(horizon_zenith, phi) / centre) as f32; 3]
        })
        .collect())
}

/// Missing entries by linear interpolation between the nearest present ones (the ends
/// take the nearest). All missing cannot happen (the overall light came from some
/// sector), but gives gains of 1.
fn fill_gaps(values: &[Option<[f32; 3]>]) -> Vec<[f32; 3]> {
    let known: Vec<(usize, [f32; 3])> = values
        .iter()
        .enumerate()
        .filter_map(|(i, v)| v.map(|v| (i, v)))
        .collect();
    (0..values.len())
        .map(|i| {
            let before = known.iter().rev().find(|(k, _)| *k <= i);
            let after = known.iter().find(|(k, _)| *k >= i);
            match (before, after) {
                (Some(&(a, va)), Some(&(b, vb))) if b > a => {
                    let t = (i - a) as f32 / (b - a) as f32;
                    std::array::from_fn(|c| va[c] + t * (vb[c] - va[c]))
                }
                (Some(&(_, v)), _) | (None, Some(&(_, v))) => v,
                (None, None) => [1.0; 3],
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sectors_cover_the_image_from_left_to_right() {
        let camera = Camera {
            yaw_deg: 30.0,
            fov_y_deg: 50.0,
            ..Camera::default()
        };
        let g = SectorGeometry::across(&camera, 160, 100, 8);
        assert!((g.centre - 30f64.to_radians()).abs() < 1e-12);
        let half = ((50f64.to_radians() / 2.0).tan() * 1.6).atan();
        assert!((g.sector_width * 8.0 - 2.0 * half).abs() < 1e-12);
        assert_eq!(g.sector(g.centre - half + 1e-9), 0);
        assert_eq!(g.sector(g.centre + half - 1e-9), 7);
        assert_eq!(g.sector(g.centre + 3.0), 7);
        assert_eq!(g.sector(g.sector_centre(3)), 3);
    }

    #[test]
    fn gaps_are_filled_linearly() {
        let v = [None, Some([1.0; 3]), None, Some([2.0; 3]), None];
        let f = fill_gaps(&v);
        assert_eq!(f, vec![[1.0; 3], [1.0; 3], [1.5; 3], [2.0; 3], [2.0; 3]]);
    }
}
