//! A synthetic fisheye sky photo: the Preetham sky through a fisheye, with seeded clouds
//! and a sun disc if asked, exposed for display if asked, with the horizon circle as its
//! alpha. What `brume sky` writes and Python's `brume.render_sky` returns; the turbidity
//! estimator's own test input.

use super::clouds::{add_clouds, CloudOptions, CloudReport};
use super::{display_exposure, draw_sun_disc, render_sky_image, Fisheye, PreethamSky};
use crate::error::{Error, Result};
use crate::raster::{Grid, RgbaImage};

/// The largest side of a sky photo, px.
pub const MAX_SIDE: usize = 16384;

/// Bytes per pixel a sky photo's rendering holds: the linear RGB sky, its RGBA copy and
/// an encoded file of it (measured, README's limits table).
pub const BYTES_PER_PIXEL: u64 = 56;

/// The largest angular radius of a drawn sun disc, radians (45°).
pub const MAX_SUN_DISC: f64 = std::f64::consts::FRAC_PI_4;

/// How [`render_sky_photo`] scales the model's values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SkyExposure {
    /// The model's units, kcd/m² (a pixel's Rec. 709 luminance is the model's Y): for EXR
    /// or PFM files and the turbidity estimator.
    #[default]
    Physical,
    /// Scaled so that the brightest channel of the sky more than 2° beyond the sun (and its
    /// disc) is 0.9 ([`display_exposure`]): only the sun and its glow clip, as in a photo
    /// exposed for the sky; for 8-bit files.
    Display,
}

/// What [`render_sky_photo`] draws. Angles in radians, as in the rest of [`crate::sky`].
#[derive(Clone, Debug, PartialEq)]
pub struct SkyPhotoOptions {
    /// Turbidity T in [1, 20].
    pub turbidity: f64,
    /// The sun's zenith angle θs, in [0, π/2).
    pub sun_zenith: f64,
    /// The sun's azimuth φs in the fisheye's convention.
    pub sun_azimuth: f64,
    /// The image's side in px (square, the sky on its inscribed circle), 1 to [`MAX_SIDE`].
    pub size: usize,
    /// The lens and the azimuth's convention.
    pub fisheye: Fisheye,
    /// A white disc of this angular radius around the sun, in [0, [`MAX_SUN_DISC`]], at
    /// [`super::SUN_DISC_LUMINANCE`] (0.27° is the real sun's); `None` draws none.
    pub sun_disc: Option<f64>,
    /// Synthetic clouds ([`add_clouds`]); `None` leaves the sky clear.
    pub clouds: Option<CloudOptions>,
    /// The model's units, or exposed for display.
    pub exposure: SkyExposure,
}

impl Default for SkyPhotoOptions {
    /// A clear sky (T = 3) under a sun 45° from the zenith at the image's top, 500 px,
    /// equidistant, in kcd/m².
    fn default() -> Self {
        SkyPhotoOptions {
            turbidity: 3.0,
            sun_zenith: std::f64::consts::FRAC_PI_4,
            sun_azimuth: 0.0,
            size: 500,
            fisheye: Fisheye::default(),
            sun_disc: None,
            clouds: None,
            exposure: SkyExposure::Physical,
        }
    }
}

/// A sky photo and what went into it.
#[derive(Clone, Debug)]
pub struct SkyPhoto {
    /// Linear sRGB (kcd/m², times `exposure` when exposed for display); alpha 1 inside the
    /// horizon circle, 0 outside, where the colour is black.
    pub image: RgbaImage,
    /// The factor applied for display; `None` in the model's units (or when no sky pixel
    /// is lit).
    pub exposure: Option<f64>,
    /// Pixels the sun disc covers, if one was drawn.
    pub sun_disc_pixels: Option<usize>,
    /// What the clouds cover, if any were drawn.
    pub clouds: Option<CloudReport>,
    /// The model's zenith luminance, kcd/m².
    pub zenith_luminance: f64,
    /// The model's zenith chromaticity (x, y).
    pub zenith_chromaticity: [f64; 2],
}

/// Renders the sky `opts` asks for. Errors name the option (`size`, `sun_disc`, the
/// model's fields, `clouds` for the clouds' coverage, their other fields) and what was
/// expected; a size the machine's memory cannot hold is refused before anything is
/// allocated.
pub fn render_sky_photo(opts: &SkyPhotoOptions) -> Result<SkyPhoto> {
    let size = opts.size;
    if !(1..=MAX_SIDE).contains(&size) {
        let expected = format!("an image side from 1 to {MAX_SIDE} px");
        return Err(Error::invalid("size", size, expected));
    }
    if let Some(r) = opts
        .sun_disc
        .filter(|r| !(r.is_finite() && (0.0..=MAX_SUN_DISC).contains(r)))
    {
        return Err(Error::invalid(
            "sun_disc",
            format!("{}°", r.to_degrees()),
            "an angular radius in [0°, 45°]",
        ));
    }
    let pixels = (size * size) as u64;
    crate::memory::check_available(
        &format!("`size` {size}x{size}"),
        pixels.saturating_mul(BYTES_PER_PIXEL),
        &format!(
            "a sky photo holds about {BYTES_PER_PIXEL} bytes per pixel: give a smaller `size`"
        ),
    )?;
    let (zenith, azimuth) = (opts.sun_zenith, opts.sun_azimuth);
    let model = PreethamSky::new(opts.turbidity, zenith, azimuth)?;
    let fisheye = &opts.fisheye;
    let mut image = render_sky_image(&model, size, fisheye)?;
    // The coverage is what `clouds` sets; the hosts call it so.
    let coverage_as_clouds =
        |e: Error| e.rename_options(|f| (f == "coverage").then(|| "clouds".into()));
    let clouds = (opts.clouds.as_ref())
        .map(|c| add_clouds(&mut image, fisheye, c).map_err(coverage_as_clouds))
        .transpose()?;
    let sun_disc_pixels = (opts.sun_disc)
        .map(|r| draw_sun_disc(&mut image, fisheye, zenith, azimuth, r))
        .transpose()?;
    let exposure = match opts.exposure {
        SkyExposure::Physical => None,
        SkyExposure::Display => {
            let disc = opts.sun_disc.unwrap_or(0.0);
            display_exposure(&image, fisheye, zenith, azimuth, disc)
        }
    };
    let scale = exposure.unwrap_or(1.0) as f32;
    let image = Grid::from_fn(size, size, |x, y| {
        let [r, g, b] = image.get(x, y).map(|c| c * scale);
        let inside = fisheye.pixel_direction(size, x, y).is_some();
        [r, g, b, if inside { 1.0 } else { 0.0 }]
    });
    let (xz, yz) = model.zenith_chromaticity();
    Ok(SkyPhoto {
        image,
        exposure,
        sun_disc_pixels,
        clouds,
        zenith_luminance: model.zenith_luminance(),
        zenith_chromaticity: [xz, yz],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sky::luminance;

    /// The model's units: a pixel's luminance is the model's Y in its direction; alpha is
    /// the horizon circle; the display exposure puts the brightest channel away from the
    /// sun at 0.9 and the sun disc above 1.
    #[test]
    fn the_photo_is_the_model_in_its_units_or_exposed() {
        let opts = SkyPhotoOptions {
            size: 64,
            ..SkyPhotoOptions::default()
        };
        let photo = render_sky_photo(&opts).unwrap();
        let model = PreethamSky::new(3.0, opts.sun_zenith, 0.0).unwrap();
        let (x, y) = (40, 20);
        let (theta, phi) = opts.fisheye.pixel_direction(64, x, y).unwrap();
        let p = photo.image.get(x, y);
        let y_model = model.luminance(theta, phi);
        assert!((luminance([p[0], p[1], p[2]]) / y_model - 1.0).abs() < 1e-5);
        assert_eq!((p[3], photo.image.get(0, 0)[3]), (1.0, 0.0));
        assert_eq!(photo.exposure, None);

        let shown = render_sky_photo(&SkyPhotoOptions {
            exposure: SkyExposure::Display,
            sun_disc: Some(0.27f64.to_radians()),
            ..opts
        })
        .unwrap();
        let e = shown.exposure.unwrap() as f32;
        let q = shown.image.get(x, y);
        assert!((q[0] / p[0] - e).abs() < 1e-4 * e);
        assert!(shown.sun_disc_pixels.unwrap() >= 1);
        let brightest = shown
            .image
            .as_slice()
            .iter()
            .map(|p| p[0].max(p[1]).max(p[2]));
        assert!(brightest.fold(0.0, f32::max) > 1.0, "the sun clips");
    }

    /// Each bad option is refused by its name; the clouds' coverage as `clouds`.
    #[test]
    fn bad_options_are_named() {
        let cases = [
            (
                SkyPhotoOptions {
                    clouds: Some(CloudOptions {
                        coverage: 2.0,
                        ..CloudOptions::default()
                    }),
                    ..Default::default()
                },
                "invalid clouds = 2",
            ),
            (
                SkyPhotoOptions {
                    size: 0,
                    ..Default::default()
                },
                "size",
            ),
            (
                SkyPhotoOptions {
                    size: MAX_SIDE + 1,
                    ..Default::default()
                },
                "size",
            ),
            (
                SkyPhotoOptions {
                    sun_disc: Some(1.0),
                    ..Default::default()
                },
                "sun_disc",
            ),
            (
                SkyPhotoOptions {
                    sun_disc: Some(f64::NAN),
                    ..Default::default()
                },
                "sun_disc",
            ),
            (
                SkyPhotoOptions {
                    turbidity: 0.5,
                    ..Default::default()
                },
                "turbidity",
            ),
        ];
        for (opts, name) in cases {
            let err = render_sky_photo(&opts).unwrap_err().to_string();
            assert!(err.contains(name), "{name}: {err}");
        }
    }
}
