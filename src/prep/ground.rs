//! The level ground as a bound on measured range below the horizon.
//!
//! A ray that points below the level from a camera `h` above the road meets the road at
//! range `h / s`, `s` the sine of its angle below the level; whatever the ray sees stands
//! on the road or over it, so it is no farther than that, as long as the road does not
//! fall away. On Cityscapes' frames the measured road lies within 2 % of
//! that range ([`Mount`] from the camera file). A stereo matcher's false matches in the
//! band along the left border, which the right camera does not see, and a hood's
//! reflection of the street are at 100 m to infinitely far on rows whose road is 3 to 15 m
//! away: white streaks in the fog. A known value beyond the bound is dropped (then filled
//! as a hole) when its patch of such values is small; a road falling away beyond a crest
//! shows as a wide surface beyond the bound, and is kept. The bound is the road falling
//! away at [`FALL_GRADE`] and nothing more: it used to be at least twice the level road's
//! range as well, which kept blotches of 1.3 to 1.6 times it on the dark road by the car
//! (Cityscapes' Düsseldorf frame: light patches in the fog).

use super::components;
use crate::io::camera::{Intrinsics, LevelRays, Mount};
use crate::{Error, Result};

/// How steeply the road may fall away from the camera's level before the bound speaks:
/// a value is beyond it only past the range at which its ray is this grade below the
/// level, `h / (s − grade)`, so a ray less than 5 % below the level (the rows just
/// under the horizon) has no bound, and a crest's fall of 5 % within the view is kept.
/// This also covers the car's own pitch under braking (a degree or two: 0.02 to 0.035 of
/// sine), which the camera file's static pitch does not know.
const FALL_GRADE: f64 = 0.05;

/// A patch of values beyond the bound (4-connected) of this fraction of the image or more
/// is a surface, not noise: the road beyond a crest steeper than [`FALL_GRADE`], a quay's
/// edge over the water. Cityscapes' streaks of false matches are up to 0.03 % (624 px of
/// 2 Mpx).
const MAX_PATCH_FRACTION: f64 = 0.01;

/// The level ground under a camera of known mount, on the range map's grid
/// ([`super::PrepOptions::ground`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Ground {
    /// How the camera is mounted; its height in the range's units.
    pub mount: Mount,
    /// The camera's intrinsics on the range map's grid.
    pub intrinsics: Intrinsics,
}

impl Ground {
    /// Checks every field; an out-of-domain one gives [`Error::InvalidParameter`].
    pub fn validate(&self) -> Result<()> {
        let m = &self.mount;
        if !(m.height_m.is_finite() && m.height_m > 0.0) {
            return Err(Error::invalid(
                "ground.mount.height_m",
                m.height_m,
                "a finite height above the ground, greater than 0",
            ));
        }
        let quarter = std::f64::consts::FRAC_PI_2;
        for (name, v) in [
            ("ground.mount.pitch", m.pitch),
            ("ground.mount.roll", m.roll),
        ] {
            if !(v.is_finite() && v.abs() <= quarter) {
                return Err(Error::invalid(
                    name,
                    v,
                    "an angle in radians in [−π/2, π/2]",
                ));
            }
        }
        let k = &self.intrinsics;
        for (name, v) in [
            ("ground.intrinsics.fx", k.fx),
            ("ground.intrinsics.fy", k.fy),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::invalid(
                    name,
                    v,
                    "a finite focal length in pixels > 0",
                ));
            }
        }
        for (name, v) in [
            ("ground.intrinsics.cx", k.cx),
            ("ground.intrinsics.cy", k.cy),
        ] {
            if !v.is_finite() {
                return Err(Error::invalid(
                    name,
                    v,
                    "a finite principal point in pixels",
                ));
            }
        }
        Ok(())
    }

    /// The farthest range a ray of sine `s` below the level may measure, `+inf` where the
    /// bound does not speak (at or above [`FALL_GRADE`] below the level).
    fn bound(&self, s: f64) -> f64 {
        if s <= FALL_GRADE {
            return f64::INFINITY;
        }
        self.mount.height_m / (s - FALL_GRADE)
    }
}

/// The level road itself as a surface a hole may be filled with ([`super::fill`]): a
/// hole on the road (a wet road's reflection, water level with it, asphalt without
/// texture) that a matcher left, or filled with false matches of what stands beside it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Road {
    rays: LevelRays,
    height: f64,
}

impl Road {
    /// The road under `ground`'s camera.
    pub(crate) fn of(ground: &Ground) -> Road {
        Road {
            rays: ground.mount.rays(&ground.intrinsics),
            height: ground.mount.height_m,
        }
    }

    /// The road's range along the ray through pixel position `(x, y)`, `+inf` at and
    /// above the horizon.
    pub(crate) fn range_at(&self, x: f64, y: f64) -> f64 {
        match self.rays.sine_below_level_at(x, y) {
            s if s > 0.0 => self.height / s,
            _ => f64::INFINITY,
        }
    }
}

/// Makes unknown (NaN) the known values of `work` outside `sky` beyond `ground`'s bound,
/// in patches under [`MAX_PATCH_FRACTION`] of the image. Returns how many.
pub(super) fn drop_below_ground(
    work: &mut [f32],
    sky: &[bool],
    (w, h): (usize, usize),
    ground: &Ground,
) -> usize {
    let rays = ground.mount.rays(&ground.intrinsics);
    let mut beyond = vec![false; w * h];
    for (y, row) in beyond.chunks_exact_mut(w).enumerate() {
        if !rays.row_may_reach(y, w, FALL_GRADE) {
            continue;
        }
        for (x, b) in row.iter_mut().enumerate() {
            let p = y * w + x;
            let v = f64::from(work[p]);
            *b = v.is_finite() && !sky[p] && v > ground.bound(rays.sine_below_level(x, y));
        }
    }
    let max_patch = (MAX_PATCH_FRACTION * (w * h) as f64).ceil() as usize;
    let patches = components::label_mask(&beyond, w, h);
    let mut dropped = 0;
    for patch in patches.list.iter().filter(|c| c.len < max_patch) {
        for &p in patches.pixels_of(patch) {
            work[p as usize] = f32::NAN;
        }
        dropped += patch.len;
    }
    dropped
}

/// Brings the values of `work` that the border bands `filled` (no value was measured
/// there) no farther than the level road along their ray, where `ground`'s bound speaks
/// (rays at least [`FALL_GRADE`] below the level). A band continues the surface its line
/// meets, and on the rows near the car a matcher's noise there, continued, stood up to
/// 1.2 times beyond the road (Cityscapes' bottom bands: the hood's unmeasured rows and
/// the road above them). Returns how many values it brought nearer.
pub(super) fn bands_on_the_road(
    work: &mut [f32],
    filled: &[bool],
    (w, h): (usize, usize),
    ground: &Ground,
) -> usize {
    let rays = ground.mount.rays(&ground.intrinsics);
    let mut nearer = 0;
    for y in (0..h).filter(|&y| rays.row_may_reach(y, w, FALL_GRADE)) {
        for x in (0..w).filter(|&x| filled[y * w + x]) {
            let s = rays.sine_below_level(x, y);
            let road = (ground.mount.height_m / s) as f32;
            if s > FALL_GRADE && work[y * w + x] > road {
                work[y * w + x] = road;
                nearer += 1;
            }
        }
    }
    nearer
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A camera 1.2 m over a level road, 4° down, square pixels of focal 100 on a 64x48
    /// grid, the horizon on row 24 − 100 tan 4° ≈ 17.
    fn street() -> (Ground, usize, usize) {
        let (w, h) = (64, 48);
        let ground = Ground {
            mount: Mount {
                height_m: 1.2,
                pitch: 4f64.to_radians(),
                roll: 0.0,
            },
            intrinsics: Intrinsics::centred(100.0, w, h),
        };
        (ground, w, h)
    }

    /// The road's own range along each ray, from the mount alone (an independent
    /// construction: the ray's point at height 0, by similar triangles in the camera's
    /// tilted frame).
    fn road_range(g: &Ground, x: usize, y: usize) -> f64 {
        let k = &g.intrinsics;
        let (u, v) = ((x as f64 - k.cx) / k.fx, (y as f64 - k.cy) / k.fy);
        let (p, hm) = (g.mount.pitch, g.mount.height_m);
        // Depth t along the axis: the ray's drop t (v cos p + sin p) equals the height.
        let t = hm / (v * p.cos() + p.sin());
        t * (1.0 + u * u + v * v).sqrt()
    }

    /// A road measured at its own range keeps every value; specks at 100x it below the
    /// horizon go, one on a row too near the horizon for the bound stays, and so does a
    /// speck in the sky.
    #[test]
    fn specks_below_the_road_go_and_the_road_stays() {
        let (g, w, h) = street();
        let rays = g.mount.rays(&g.intrinsics);
        let mut work: Vec<f32> = (0..w * h)
            .map(|p| {
                let (x, y) = (p % w, p / w);
                match rays.sine_below_level(x, y) > 0.0 {
                    true => road_range(&g, x, y) as f32,
                    false => 500.0,
                }
            })
            .collect();
        let sky: Vec<bool> = (0..w * h).map(|p| p / w < 10).collect();
        let road = work.clone();
        assert_eq!(drop_below_ground(&mut work, &sky, (w, h), &g), 0);
        assert_eq!(work, road);
        // Row 40: s ≈ 0.23, the road 5.2 m off; row 20: s ≈ 0.04, under the 5 % grade.
        for p in [40 * w + 3, 40 * w + 4, 41 * w + 50, 20 * w + 30, 5 * w + 5] {
            work[p] *= 100.0;
        }
        assert_eq!(drop_below_ground(&mut work, &sky, (w, h), &g), 3);
        assert!([40 * w + 3, 40 * w + 4, 41 * w + 50]
            .iter()
            .all(|&p| work[p].is_nan()));
        assert_eq!(work[20 * w + 30], road[20 * w + 30] * 100.0);
        assert_eq!(work[5 * w + 5], 50_000.0);
        // The bound is the road falling 5 % away: its ray's sine s = h / road, the range
        // h / (s − 0.05), 1.22x the road 4.4 m off on row 45. Just within it is kept,
        // just beyond it dropped, and so is a blotch of 1.5x (kept by a bound of 2x).
        let p = 45 * w + 10;
        let factor = 1.0 / (1.0 - 0.05 * road_range(&g, 10, 45) / 1.2);
        assert!((1.2..1.25).contains(&factor), "{factor}");
        for (times, dropped) in [(0.99, 0), (1.01, 1)] {
            work[p] = road[p] * (times * factor) as f32;
            assert_eq!(drop_below_ground(&mut work, &sky, (w, h), &g), dropped);
        }
        work[p] = road[p] * 1.5;
        assert_eq!(drop_below_ground(&mut work, &sky, (w, h), &g), 1);
    }

    /// Band pixels beyond the level road are brought onto it, nearer ones kept, and so
    /// are pixels that were measured and rows too near the horizon for the bound.
    #[test]
    fn bands_come_no_farther_than_the_road() {
        let (g, w, h) = street();
        let mut work = vec![100.0f32; w * h];
        let mut filled = vec![false; w * h];
        let (far, near, measured, high) = (44 * w + 5, 44 * w + 6, 44 * w + 7, 20 * w + 5);
        work[near] = 2.0;
        [far, near, high].iter().for_each(|&p| filled[p] = true);
        assert_eq!(bands_on_the_road(&mut work, &filled, (w, h), &g), 1);
        let road = road_range(&g, 5, 44) as f32;
        assert!(
            (work[far] / road - 1.0).abs() < 1e-5,
            "{} vs {road}",
            work[far]
        );
        assert_eq!(
            (work[near], work[measured], work[high]),
            (2.0, 100.0, 100.0)
        );
    }

    /// A road falling away beyond a crest is a wide surface beyond the bound: kept.
    #[test]
    fn a_wide_surface_beyond_the_bound_stays() {
        let (g, w, h) = street();
        let mut work: Vec<f32> = (0..w * h)
            .map(|p| (road_range(&g, p % w, p / w).max(0.0) * 3.0) as f32)
            .collect();
        let before = work.clone();
        assert_eq!(
            drop_below_ground(&mut work, &vec![false; w * h], (w, h), &g),
            0
        );
        assert_eq!(work, before);
    }

    /// The roll turns the horizon: with the left side up, the left of a row is nearer the
    /// horizon than its right, so its road is farther.
    #[test]
    fn roll_tilts_the_horizon() {
        let (mut g, _, _) = street();
        g.mount.roll = 0.1;
        let rays = g.mount.rays(&g.intrinsics);
        assert!(rays.sine_below_level(0, 30) < rays.sine_below_level(63, 30));
        // A row skipped has no pixel past the grade, rolled or not.
        for roll in [0.0, 0.3, -0.3] {
            g.mount.roll = roll;
            let rays = g.mount.rays(&g.intrinsics);
            let skipped: Vec<usize> = (0..48)
                .filter(|&y| !rays.row_may_reach(y, 64, FALL_GRADE))
                .collect();
            assert!(skipped.len() > 10, "{skipped:?}");
            for y in skipped {
                assert!((0..64).all(|x| rays.sine_below_level(x, y) <= FALL_GRADE));
            }
        }
        g.mount.roll = 0.0;
        let level = g.mount.rays(&g.intrinsics);
        assert!((level.sine_below_level(0, 30) - level.sine_below_level(63, 30)).abs() < 1e-12);
    }

    #[test]
    fn bad_mounts_are_refused_by_name() {
        let (g, _, _) = street();
        assert!(g.validate().is_ok());
        let mut bad = g;
        bad.mount.height_m = 0.0;
        assert!(bad.validate().unwrap_err().to_string().contains("height_m"));
        let mut bad = g;
        bad.mount.pitch = f64::NAN;
        assert!(bad.validate().unwrap_err().to_string().contains("pitch"));
        let mut bad = g;
        bad.intrinsics.fy = -1.0;
        assert!(bad.validate().unwrap_err().to_string().contains("fy"));
    }
}
