//! How a square fisheye sky image maps to directions of the sky hemisphere.
//!
//! # The default convention
//!
//! - The image is square, `size` x `size` px; the zenith (θ = 0) is at its centre
//!   (`size / 2`, `size / 2`) and the horizon (θ = 90°) on the inscribed circle of radius
//!   `size / 2`. Pixels whose centre lies outside that circle are not sky.
//! - **Equidistant** lens: the distance from the centre is proportional to the zenith
//!   angle, r = R·θ/(π/2) (the common "f-theta" fisheye, and the one of paper 002's
//!   Preetham images).
//! - **Azimuth** φ = 0 at the top of the image (row 0 side), increasing **clockwise** as
//!   the image is displayed (toward the right edge at φ = 90°), in (−180°, 180°].
//!
//! Pixel coordinates are continuous: (0, 0) is the top-left corner of the image, x to the
//! right, y down, and the centre of pixel (i, j) is (i + 0.5, j + 0.5).
//!
//! # Changing it
//!
//! - [`Lens`]: equisolid (r = R·sin(θ/2)/sin 45°, most photographic fisheyes),
//!   orthographic (r = R·sin θ) or stereographic (r = R·tan(θ/2)).
//! - `counter_clockwise`: azimuth increasing counter-clockwise instead. A camera looking
//!   up sees the sky mirrored with respect to a map seen from above, so a photograph
//!   with north at the top has east on the left: with azimuths measured from north
//!   through east, that is counter-clockwise.
//! - `azimuth_offset`: the azimuth at the top of the image (e.g. the camera's heading).
//!
//! The model only uses the azimuth relative to the sun's (through γ), so what matters is
//! that the sun's azimuth is given in the same convention as the image's.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
use std::str::FromStr;

/// The radial mapping of a fisheye lens: how the zenith angle θ sets the distance r from
/// the image centre, with the horizon (θ = 90°) at r = R in every case.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Lens {
    /// r = R·θ/(π/2): equal steps of zenith angle are equal steps in the image.
    #[default]
    Equidistant,
    /// r = R·sin(θ/2)/sin(π/4): equal areas of the sky are equal areas in the image.
    Equisolid,
    /// r = R·sin θ: the hemisphere projected straight down; squeezes the horizon.
    Orthographic,
    /// r = R·tan(θ/2): angles are kept; stretches the horizon.
    Stereographic,
}

impl Lens {
    /// Every lens, for messages and tests.
    pub const ALL: [Lens; 4] = [
        Lens::Equidistant,
        Lens::Equisolid,
        Lens::Orthographic,
        Lens::Stereographic,
    ];

    /// Its name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Lens::Equidistant => "equidistant",
            Lens::Equisolid => "equisolid",
            Lens::Orthographic => "orthographic",
            Lens::Stereographic => "stereographic",
        }
    }

    /// The distance from the centre, as a fraction of the horizon's radius, of the
    /// direction at zenith angle `theta` in [0, π/2].
    pub fn radius(self, theta: f64) -> f64 {
        match self {
            Lens::Equidistant => theta / FRAC_PI_2,
            Lens::Equisolid => (theta / 2.0).sin() / FRAC_PI_4.sin(),
            Lens::Orthographic => theta.sin(),
            Lens::Stereographic => (theta / 2.0).tan(),
        }
    }

    /// The zenith angle at relative distance `r` in [0, 1] from the centre: the inverse of
    /// [`Lens::radius`]. Values of r above 1 are beyond the horizon: `None`.
    pub fn zenith(self, r: f64) -> Option<f64> {
        if !(0.0..=1.0).contains(&r) {
            return None;
        }
        Some(match self {
            Lens::Equidistant => r * FRAC_PI_2,
            Lens::Equisolid => 2.0 * (r * FRAC_PI_4.sin()).min(1.0).asin(),
            Lens::Orthographic => r.asin(),
            Lens::Stereographic => 2.0 * r.atan(),
        })
    }
}

impl FromStr for Lens {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        Lens::ALL
            .into_iter()
            .find(|l| l.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| {
                format!(
                    "'{s}' is not a lens: equidistant, equisolid, orthographic or stereographic"
                )
            })
    }
}

/// A fisheye convention (see the module docs): the lens, the sense of the azimuth and the
/// azimuth at the top of the image. The image size is given to each conversion, so one
/// convention serves images of any size.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Fisheye {
    /// The radial mapping.
    pub lens: Lens,
    /// Azimuth increasing counter-clockwise in the displayed image (default: clockwise).
    pub counter_clockwise: bool,
    /// Azimuth at the top of the image, radians (default 0).
    pub azimuth_offset: f64,
}

impl Fisheye {
    /// The direction (θ, φ) seen at continuous pixel coordinates (`px`, `py`) of a
    /// `size` x `size` image, or `None` beyond the horizon circle. φ is in (−π, π].
    pub fn direction(&self, size: usize, px: f64, py: f64) -> Option<(f64, f64)> {
        let half = size as f64 / 2.0;
        if half <= 0.0 {
            return None;
        }
        let (dx, dy) = (px - half, py - half);
        let r = (dx * dx + dy * dy).sqrt() / half;
        // A point put on the horizon by `pixel` may come back a rounding error beyond it.
        let r = if r > 1.0 && r <= 1.0 + 1e-12 { 1.0 } else { r };
        let theta = self.lens.zenith(r)?;
        // Image angle: 0 at the top, clockwise as displayed (y points down).
        let image_angle = if r > 0.0 { dx.atan2(-dy) } else { 0.0 };
        let turn = if self.counter_clockwise {
            -image_angle
        } else {
            image_angle
        };
        Some((theta, wrap_angle(self.azimuth_offset + turn)))
    }

    /// The direction at the centre of pixel (`x`, `y`), or `None` when that centre is
    /// beyond the horizon circle.
    pub fn pixel_direction(&self, size: usize, x: usize, y: usize) -> Option<(f64, f64)> {
        self.direction(size, x as f64 + 0.5, y as f64 + 0.5)
    }

    /// The continuous pixel coordinates where direction (`theta`, `phi`) appears in a
    /// `size` x `size` image, or `None` below the horizon (θ outside [0, π/2]) or for a
    /// non-finite angle.
    pub fn pixel(&self, size: usize, theta: f64, phi: f64) -> Option<(f64, f64)> {
        if !(0.0..=FRAC_PI_2).contains(&theta) || !phi.is_finite() {
            return None;
        }
        let half = size as f64 / 2.0;
        let r = self.lens.radius(theta) * half;
        let turn = phi - self.azimuth_offset;
        let image_angle = if self.counter_clockwise { -turn } else { turn };
        Some((half + r * image_angle.sin(), half - r * image_angle.cos()))
    }
}

/// `angle` brought into (−π, π].
pub fn wrap_angle(angle: f64) -> f64 {
    let a = (angle + PI).rem_euclid(2.0 * PI) - PI;
    if a <= -PI {
        a + 2.0 * PI
    } else {
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn default_convention_is_equidistant_top_clockwise() {
        let f = Fisheye::default();
        let size = 200;
        // Centre: the zenith.
        let (t, _) = f.direction(size, 100.0, 100.0).unwrap();
        assert_eq!(t, 0.0);
        // Top edge: horizon at azimuth 0.
        let (t, p) = f.direction(size, 100.0, 0.0).unwrap();
        assert!(
            close(t, FRAC_PI_2, 1e-12) && close(p, 0.0, 1e-12),
            "{t} {p}"
        );
        // Right edge: azimuth +90° (clockwise as displayed).
        let (t, p) = f.direction(size, 200.0, 100.0).unwrap();
        assert!(
            close(t, FRAC_PI_2, 1e-12) && close(p, FRAC_PI_2, 1e-12),
            "{t} {p}"
        );
        // Halfway to the left edge: 45° zenith angle, azimuth −90°.
        let (t, p) = f.direction(size, 50.0, 100.0).unwrap();
        assert!(
            close(t, FRAC_PI_4, 1e-12) && close(p, -FRAC_PI_2, 1e-12),
            "{t} {p}"
        );
        // Bottom: azimuth 180°, never −180°.
        let (_, p) = f.direction(size, 100.0, 150.0).unwrap();
        assert!(close(p, PI, 1e-12), "{p}");
        // Corners are beyond the horizon.
        assert!(f.direction(size, 1.0, 1.0).is_none());
        assert!(f.pixel_direction(size, 0, 0).is_none());
    }

    #[test]
    fn options_turn_and_mirror_the_azimuth() {
        let f = Fisheye {
            counter_clockwise: true,
            azimuth_offset: 0.5,
            ..Fisheye::default()
        };
        let (_, p) = f.direction(100, 100.0, 50.0).unwrap(); // right edge
        assert!(close(p, 0.5 - FRAC_PI_2, 1e-12), "{p}");
        let (_, p) = f.direction(100, 50.0, 0.0).unwrap(); // top edge
        assert!(close(p, 0.5, 1e-12), "{p}");
    }

    #[test]
    fn lenses_put_the_horizon_on_the_circle_and_invert() {
        for lens in Lens::ALL {
            assert!(close(lens.radius(0.0), 0.0, 1e-15), "{lens:?}");
            assert!(close(lens.radius(FRAC_PI_2), 1.0, 1e-12), "{lens:?}");
            for i in 0..=90 {
                let theta = (i as f64).to_radians();
                let back = lens.zenith(lens.radius(theta)).unwrap();
                assert!(close(back, theta, 1e-9), "{lens:?} {i}°: {back}");
            }
            assert!(lens.zenith(1.01).is_none());
            assert_eq!(lens.name().parse::<Lens>().unwrap(), lens);
        }
        // Equisolid squeezes the horizon less than orthographic, more than equidistant.
        let t = 80f64.to_radians();
        let (d, s, o) = (
            Lens::Equidistant.radius(t),
            Lens::Equisolid.radius(t),
            Lens::Orthographic.radius(t),
        );
        assert!(d < s && s < o, "{d} {s} {o}");
    }

    #[test]
    fn pixels_and_directions_round_trip() {
        let sizes = [7usize, 200, 501];
        for lens in Lens::ALL {
            for ccw in [false, true] {
                let f = Fisheye {
                    lens,
                    counter_clockwise: ccw,
                    azimuth_offset: -2.0,
                };
                for size in sizes {
                    // Pixel → direction → pixel, every pixel centre inside the circle.
                    let mut inside = 0;
                    for y in 0..size {
                        for x in 0..size {
                            let Some((t, p)) = f.pixel_direction(size, x, y) else {
                                continue;
                            };
                            inside += 1;
                            let (px, py) = f.pixel(size, t, p).unwrap();
                            assert!(
                                close(px, x as f64 + 0.5, 1e-6) && close(py, y as f64 + 0.5, 1e-6),
                                "{lens:?} ccw={ccw} {size}: ({x}, {y}) → ({px}, {py})"
                            );
                        }
                    }
                    // About π/4 of the square is sky.
                    let fraction = inside as f64 / (size * size) as f64;
                    assert!((fraction - PI / 4.0).abs() < 0.1, "{fraction}");
                }
                // Direction → pixel → direction.
                for i in 0..=18 {
                    for j in -9..=9 {
                        let (t, p) = (
                            (i as f64 * 5.0).to_radians(),
                            (j as f64 * 20.0).to_radians(),
                        );
                        let (px, py) = f.pixel(500, t, p).unwrap();
                        let (t2, p2) = f.direction(500, px, py).unwrap();
                        // asin is ill-conditioned at 1: the orthographic horizon comes back
                        // to √ε ≈ 1e-8 rad.
                        assert!(close(t2, t, 1e-7), "{lens:?} θ {t} → {t2}");
                        if i > 0 {
                            assert!(
                                close(wrap_angle(p2 - p), 0.0, 1e-9),
                                "{lens:?} φ {p} → {p2}"
                            );
                        }
                    }
                }
            }
        }
        assert!(Fisheye::default().pixel(100, 1.6, 0.0).is_none());
        assert!(Fisheye::default().pixel(100, -0.1, 0.0).is_none());
    }

    #[test]
    fn angles_wrap_into_the_half_open_turn() {
        assert!(close(wrap_angle(3.0 * PI), PI, 1e-12));
        assert!(close(wrap_angle(-PI), PI, 1e-12));
        assert!(close(
            wrap_angle(-179.4f64.to_radians()),
            -179.4f64.to_radians(),
            1e-12
        ));
        assert!(close(wrap_angle(2.0 * PI + 0.1), 0.1, 1e-12));
    }
}
