//! Clear-sky images from the Preetham, Shirley and Smits (1999) daylight model, and the
//! atmospheric turbidity of a fisheye sky photograph estimated against it (paper 002,
//! sec. 3.2 and 3.4). Pure CPU, f64.
//!
//! - [`preetham`]: the model. [`PreethamSky`] gives the luminance Y (kcd/m²), the CIE
//!   chromaticity (x, y) and linear sRGB of any direction (θ, φ) for a turbidity T and a
//!   sun position (θs, φs); [`preetham::Perez::eval`] is the Perez function F(θ, γ) of eq. 6.
//! - [`fisheye`]: how a square fisheye image maps to directions: [`Fisheye`] converts
//!   pixels to (θ, φ) and back under a documented default convention (equidistant,
//!   zenith at the centre, azimuth 0 at the top, clockwise), with options to change it.
//! - [`render_sky_image`] draws the model through a fisheye; [`clouds`] adds seeded
//!   synthetic clouds for the estimator's tests and benchmark; [`photo`] makes the whole
//!   synthetic sky photo (`brume sky`): clouds, a sun disc, an exposure, the horizon as
//!   alpha.
//! - [`turbidity`]: the estimator of sec. 3.4: random sample points, luminance ratios to a
//!   reference point against the model's F(θi, γi)/F(θref, γref) (eq. 6, 8), RANSAC
//!   against clouds, Levenberg-Marquardt refinement of T in [1, 20].
//! - [`sun_position`]: the sun's zenith and azimuth from time and place (NREL's SPA).
//! - [`horizon_sectors`]: a photo's horizon light by azimuth sector (sec. 4), or the
//!   Preetham sky's by the sun's azimuth when the photo shows no sky.
//! - [`image_circle`]: the sky's disc in a circular fisheye's rectangular frame.
//!
//! Angles are in radians throughout the library; the command line takes degrees.
//!
//! ```text
//! brume sky --turbidity 3 --sun-zenith 58.4 --sun-azimuth -179.4 --out sky.exr
//! brume turbidity sky.exr --sun-zenith 58.4 --sun-azimuth -179.4 --json
//! brume bench turbidity            # paper 002's Table 1, clear and with 20 % clouds
//! ```

pub mod clouds;
pub mod fisheye;
pub mod horizon_sectors;
pub mod image_circle;
pub mod photo;
pub mod preetham;
pub mod sun_position;
pub mod turbidity;

pub use fisheye::{Fisheye, Lens};
pub use photo::{render_sky_photo, SkyExposure, SkyPhoto, SkyPhotoOptions};
pub use preetham::PreethamSky;
pub use turbidity::{estimate_turbidity, TurbidityEstimate, TurbidityOptions};

use crate::error::{Error, Result};
use crate::raster::{Grid, RgbImage};

/// Renders `sky` as a `size` x `size` fisheye image through `fisheye`'s convention.
///
/// Pixels whose centre maps to a direction above the horizon hold the model's linear
/// sRGB ([`PreethamSky::rgb`]), in the model's units: Y in kcd/m², so that a pixel's
/// Rec. 709 luminance 0.2126 R + 0.7152 G + 0.0722 B is the model's Y. Pixels outside
/// the horizon circle are black. No sun disc is drawn (the model has none); see
/// [`draw_sun_disc`].
pub fn render_sky_image(sky: &PreethamSky, size: usize, fisheye: &Fisheye) -> Result<RgbImage> {
    if size == 0 {
        return Err(Error::invalid("size", 0, "an image side ≥ 1 px"));
    }
    Ok(Grid::from_fn(size, size, |x, y| {
        match fisheye.pixel_direction(size, x, y) {
            Some((theta, phi)) => sky.rgb(theta, phi).map(|c| c as f32),
            None => [0.0; 3],
        }
    }))
}

/// Luminance of a disc drawn for the sun by [`draw_sun_disc`], in kcd/m²: the order of
/// the real sun's (about 1.6·10⁹ cd/m² at a high sun), so that it saturates every
/// exposure that shows the sky, as the sun does in a photograph.
pub const SUN_DISC_LUMINANCE: f32 = 1.6e6;

/// The sun's angular radius seen from the ground, 0.2666° (0.533° diameter), in radians.
pub const SUN_ANGULAR_RADIUS: f64 = 0.2666 * std::f64::consts::PI / 180.0;

/// Paints a white disc of angular radius `radius` (radians) around the sun direction
/// (`sun_zenith`, `sun_azimuth`) at [`SUN_DISC_LUMINANCE`], over the pixels whose centre
/// is inside it, and over the pixel holding the sun's centre in any case, so that even a
/// disc smaller than a pixel leaves a saturated spot to find. Returns the number of
/// pixels painted. Pixels outside the horizon circle are left black.
pub fn draw_sun_disc(
    image: &mut RgbImage,
    fisheye: &Fisheye,
    sun_zenith: f64,
    sun_azimuth: f64,
    radius: f64,
) -> Result<usize> {
    if !(radius.is_finite() && radius >= 0.0) {
        return Err(Error::invalid("sun_disc", radius, "an angular radius ≥ 0"));
    }
    if image.width() != image.height() {
        return Err(Error::invalid(
            "sky image size",
            format!("{}x{}", image.width(), image.height()),
            "a square fisheye image",
        ));
    }
    let size = image.width();
    let sun = preetham::unit_vector(sun_zenith, sun_azimuth);
    let cos_radius = radius.cos();
    let mut painted = 0;
    for y in 0..image.height() {
        for x in 0..image.width() {
            if let Some((theta, phi)) = fisheye.pixel_direction(size, x, y) {
                let v = preetham::unit_vector(theta, phi);
                if dot(v, sun) >= cos_radius {
                    *image.get_mut(x, y) = [SUN_DISC_LUMINANCE; 3];
                    painted += 1;
                }
            }
        }
    }
    if let Some((px, py)) = fisheye.pixel(size, sun_zenith, sun_azimuth) {
        let (x, y) = (px.floor() as usize, py.floor() as usize);
        if x < image.width() && y < image.height() && fisheye.pixel_direction(size, x, y).is_some()
        {
            let p = image.get_mut(x, y);
            if *p != [SUN_DISC_LUMINANCE; 3] {
                *p = [SUN_DISC_LUMINANCE; 3];
                painted += 1;
            }
        }
    }
    Ok(painted)
}

/// Rec. 709 / sRGB luminance of linear RGB: the Y row of the sRGB to XYZ matrix
/// (IEC 61966-2-1), the inverse of the matrix [`PreethamSky::rgb`] uses.
pub fn luminance(rgb: [f32; 3]) -> f64 {
    weighted_luminance(REC709_LUMINANCE, rgb)
}

/// The weights of [`luminance`]: linear R, G, B to Y for sRGB primaries.
pub const REC709_LUMINANCE: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// The luminance of linear RGB by `weights`, the Y row of its primaries' RGB to XYZ.
pub fn weighted_luminance(weights: [f64; 3], rgb: [f32; 3]) -> f64 {
    dot(weights, rgb.map(f64::from))
}

pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Pixels within this angle of the sun (beyond a drawn disc's radius) are left out of
/// [`display_exposure`]: the circumsolar glow would set it otherwise.
pub const EXPOSURE_SUN_MARGIN: f64 = 2.0 * std::f64::consts::PI / 180.0;

/// The percentile of the pixels' largest channel that [`display_exposure`] maps to
/// [`EXPOSURE_WHITE`]: the maximum.
pub const EXPOSURE_PERCENTILE: f64 = 1.0;

/// The display value given to the [`EXPOSURE_PERCENTILE`] luminance: below the
/// estimator's near-maximal level ([`turbidity::NEAR_MAX`]), so that the sky is never
/// taken for the sun.
pub const EXPOSURE_WHITE: f64 = 0.9;

/// The factor that makes a sky image displayable (an 8-bit PNG that is not all white):
/// the largest channel of the sky pixels farther than `sun_radius` +
/// [`EXPOSURE_SUN_MARGIN`] (2°) from the sun maps to 0.9, so that only the sun and its
/// glow within 2° clip, as in a photograph exposed for the sky. (Channels, not
/// luminance: the blue of a clear sky exceeds its luminance and would clip first.) (A lower percentile, e.g. the 99th at 0.9, looks brighter but
/// clips the brightest 1 % of the sky, which for a clear sky is the horizon band below
/// the sun: the saturated area then merges with the sun's and no longer marks it.)
/// `None` when no such pixel is lit.
pub fn display_exposure(
    image: &RgbImage,
    fisheye: &Fisheye,
    sun_zenith: f64,
    sun_azimuth: f64,
    sun_radius: f64,
) -> Option<f64> {
    let size = image.width();
    let cos_limit = (sun_radius + EXPOSURE_SUN_MARGIN)
        .min(std::f64::consts::PI)
        .cos();
    let sun = preetham::unit_vector(sun_zenith, sun_azimuth);
    let mut lum: Vec<f64> = Vec::new();
    for y in 0..image.height() {
        for x in 0..size {
            let Some((theta, phi)) = fisheye.pixel_direction(size, x, y) else {
                continue;
            };
            if dot(preetham::unit_vector(theta, phi), sun) > cos_limit {
                continue;
            }
            let p = image.get(x, y);
            let l = p[0].max(p[1]).max(p[2]) as f64;
            if l > 0.0 && l.is_finite() {
                lum.push(l);
            }
        }
    }
    if lum.is_empty() {
        return None;
    }
    let k = ((lum.len() - 1) as f64 * EXPOSURE_PERCENTILE).round() as usize;
    let (_, p, _) = lum.select_nth_unstable_by(k, f64::total_cmp);
    Some(EXPOSURE_WHITE / *p)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sky_images_are_black_outside_the_circle_and_the_model_inside() {
        let sky = PreethamSky::new(4.0, 0.8, -1.0).unwrap();
        let f = Fisheye::default();
        let img = render_sky_image(&sky, 64, &f).unwrap();
        assert_eq!(*img.get(0, 0), [0.0; 3]);
        assert_eq!(*img.get(63, 63), [0.0; 3]);
        let (t, p) = f.pixel_direction(64, 10, 30).unwrap();
        let want = sky.luminance(t, p);
        assert!((luminance(*img.get(10, 30)) - want).abs() < 1e-4 * want);
        assert!(render_sky_image(&sky, 0, &f).is_err());
    }

    #[test]
    fn exposure_clips_only_the_sun_and_its_glow() {
        let sky = PreethamSky::new(3.0, 1.0, 0.0).unwrap();
        let f = Fisheye::default();
        let mut img = render_sky_image(&sky, 100, &f).unwrap();
        let painted = draw_sun_disc(&mut img, &f, 1.0, 0.0, 0.05).unwrap();
        assert!(painted > 0);
        let s = display_exposure(&img, &f, 1.0, 0.0, 0.05).unwrap();
        let (mut clipped, mut far_max) = (0, 0.0f64);
        for y in 0..100 {
            for x in 0..100 {
                let Some((t, phi)) = f.pixel_direction(100, x, y) else {
                    continue;
                };
                let p = img.get(x, y);
                let l = p[0].max(p[1]).max(p[2]) as f64 * s;
                if sky.sun_angle(t, phi) > 0.05 + EXPOSURE_SUN_MARGIN {
                    far_max = far_max.max(l);
                } else if l > 1.0 {
                    clipped += 1;
                }
            }
        }
        assert!((far_max - EXPOSURE_WHITE).abs() < 1e-5, "{far_max}");
        assert!(clipped >= painted, "{clipped} < {painted}");
        // A tiny disc still marks the sun's pixel.
        let mut img = render_sky_image(&sky, 50, &f).unwrap();
        assert_eq!(draw_sun_disc(&mut img, &f, 1.0, 0.0, 0.0).unwrap(), 1);
    }
}
