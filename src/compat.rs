//! Foggy Cityscapes' conventions (Sakaridis, Dai and Van Gool, IJCV 2018, sec. 3), for
//! people who need data comparable with it: the fog blended in **sRGB code values**,
//! I = R·t + L·(1 − t) with R the clear image as stored (not linear light), t = exp(−βℓ),
//! no blur, and the atmospheric light L taken from the clear image by He, Sun and Tang's
//! dark-channel rule (CVPR 2009, sec. 4.4): among the 0.1 % brightest pixels of the dark
//! channel (the least channel over a 15 x 15 patch), the one of highest intensity.
//!
//! brume's own rendering blends in linear light, which is what a camera's sensor sees and
//! what visibility is defined on (luminance contrast): at the same β it looks denser than
//! Foggy Cityscapes, whose blend in code values keeps more of the clear image's mid-tones
//! (see the README's comparison).
//!
//! Also here: reading a given transmittance map (Foggy Cityscapes publishes them as
//! `{name}_leftImg8bit_transmittance_beta_{β}.png`, 8-bit) as the optical depth −ln t that
//! brume's fog renders from.

use crate::error::{Error, Result};
use crate::io::image::{linear_to_srgb, srgb_to_linear};
use crate::raster::{Grid, RgbImage, ScalarMap};
use std::path::Path;

/// Side of the dark channel's patch (He et al.: 15 x 15).
pub const DARK_CHANNEL_PATCH: usize = 15;
/// Fraction of the brightest dark-channel pixels the airlight is chosen among.
pub const DARK_CHANNEL_FRACTION: f64 = 0.001;

/// The atmospheric light of `image` (linear RGB) by the dark-channel rule, as sRGB code
/// values in [0, 1].
pub fn dark_channel_airlight(image: &RgbImage) -> [f32; 3] {
    let (w, h) = (image.width(), image.height());
    let encoded = image.map(|p| p.map(|v| linear_to_srgb(v.clamp(0.0, 1.0))));
    let least = encoded.map(|p| p[0].min(p[1]).min(p[2]));
    // The patch minimum, separably: rows, then columns (clamped at the borders).
    let r = DARK_CHANNEL_PATCH / 2;
    let rows = Grid::from_fn(w, h, |x, y| {
        (x.saturating_sub(r)..=(x + r).min(w - 1))
            .map(|i| *least.get(i, y))
            .fold(f32::INFINITY, f32::min)
    });
    let dark = Grid::from_fn(w, h, |x, y| {
        (y.saturating_sub(r)..=(y + r).min(h - 1))
            .map(|j| *rows.get(x, j))
            .fold(f32::INFINITY, f32::min)
    });
    let mut order: Vec<usize> = (0..w * h).collect();
    order.sort_by(|&a, &b| dark.as_slice()[b].total_cmp(&dark.as_slice()[a]));
    let take = ((w * h) as f64 * DARK_CHANNEL_FRACTION).ceil().max(1.0) as usize;
    let intensity = |p: &[f32; 3]| p[0] + p[1] + p[2];
    order[..take]
        .iter()
        .map(|&i| encoded.as_slice()[i])
        .max_by(|a, b| intensity(a).total_cmp(&intensity(b)))
        .unwrap_or([1.0; 3])
}

/// Foggy Cityscapes' blend: `image` (linear RGB) encoded to sRGB code values, blended
/// with `airlight` (code values) by the transmittance `tau` (same size), and returned as
/// linear RGB again (so that an 8-bit output holds exactly the blended code values).
pub fn blend_in_code_values(image: &RgbImage, tau: &ScalarMap, airlight: [f32; 3]) -> RgbImage {
    Grid::from_fn(image.width(), image.height(), |x, y| {
        let t = tau.get(x, y).clamp(0.0, 1.0);
        let p = image.get(x, y);
        std::array::from_fn(|c| {
            let r = linear_to_srgb(p[c].clamp(0.0, 1.0));
            srgb_to_linear(r * t + airlight[c] * (1.0 - t))
        })
    })
}

/// Foggy Cityscapes' fog of `image` (linear RGB) at `beta` (1/m) from `metres` (range in
/// metres, known everywhere): the blend in code values ([`blend_in_code_values`]) with
/// `airlight` (linear RGB, encoded) or, without one, the dark-channel airlight. Returns
/// the image (linear, alpha 1), the airlight in code values and where it came from
/// (`given` or `dark-channel`).
pub fn foggy_cityscapes(
    image: &RgbImage,
    metres: &ScalarMap,
    beta: f64,
    airlight: Option<[f32; 3]>,
) -> (crate::raster::RgbaImage, [f32; 3], &'static str) {
    let (airlight, source) = foggy_cityscapes_airlight(image, airlight);
    let tau = foggy_cityscapes_transmittance(metres, beta);
    (foggy_cityscapes_at(image, &tau, airlight), airlight, source)
}

/// The airlight of Foggy Cityscapes' blend of `image`, in sRGB code values, and where it
/// came from: `given` (linear RGB) encoded, or else the dark channel's. It does not depend
/// on β: a frame fogged at several β finds it once, for [`foggy_cityscapes_at`].
pub fn foggy_cityscapes_airlight(
    image: &RgbImage,
    given: Option<[f32; 3]>,
) -> ([f32; 3], &'static str) {
    match given {
        Some(l) => (l.map(linear_to_srgb), "given"),
        None => (dark_channel_airlight(image), "dark-channel"),
    }
}

/// Foggy Cityscapes' transmittance t = exp(−βR) of `metres` at `beta` (1/m); 0 where the
/// range is not finite. Also the label a dehazing dataset keeps.
pub fn foggy_cityscapes_transmittance(metres: &ScalarMap, beta: f64) -> ScalarMap {
    metres.map(|&r| {
        if r.is_finite() {
            (-beta * f64::from(r)).exp() as f32
        } else {
            0.0
        }
    })
}

/// [`foggy_cityscapes`] with its transmittance `tau` ([`foggy_cityscapes_transmittance`])
/// and its airlight in code values ([`foggy_cityscapes_airlight`]) already found: the
/// image, linear, alpha 1.
pub fn foggy_cityscapes_at(
    image: &RgbImage,
    tau: &ScalarMap,
    airlight: [f32; 3],
) -> crate::raster::RgbaImage {
    let fogged = blend_in_code_values(image, tau, airlight);
    fogged.opaque()
}

/// The optical depth of τ = 1.
const MIN_OPTICAL_DEPTH: f32 = 1e-6;

/// The smallest transmittance read from a map: an 8-bit 0 is "less than half a step",
/// taken as half a step so that its optical depth is finite.
fn floor_of(max_code: f32) -> f32 {
    0.5 / max_code
}

/// Reads a transmittance map (8- or 16-bit grey PNG; an RGB one must be grey), as the
/// optical depth −ln t per pixel (row 0 at the top), for brume's fog at β = 1.
pub fn load_optical_depth(path: &Path) -> Result<ScalarMap> {
    let bytes = crate::io::limits::read_file(path)?;
    decode_optical_depth(&bytes, &path.display().to_string())
}

/// [`load_optical_depth`] of bytes in memory; `name` stands for the file in messages. The
/// bytes go through the checks every brume image reader makes before decoding (the size
/// against `io::limits`, a PNG's palette, a JPEG's length), so that a hostile file is an
/// error naming it, never a panic or a huge allocation.
pub fn decode_optical_depth(bytes: &[u8], name: &str) -> Result<ScalarMap> {
    let path = Path::new(name);
    let img = crate::io::image::decode_any(bytes, name)?;
    let (w, h) = (img.width(), img.height());
    let (values, max_code): (Vec<f32>, f32) = match img {
        image::DynamicImage::ImageLuma8(g) => {
            (g.pixels().map(|p| f32::from(p[0])).collect(), 255.0)
        }
        image::DynamicImage::ImageLuma16(g) => {
            (g.pixels().map(|p| f32::from(p[0])).collect(), 65535.0)
        }
        image::DynamicImage::ImageRgb8(g) => {
            if g.pixels().any(|p| p[0] != p[1] || p[1] != p[2]) {
                return Err(Error::format(
                    path,
                    "an RGB transmittance map whose channels differ: expected a grey map \
                     (Foggy Cityscapes' are 8-bit grey)",
                ));
            }
            (g.pixels().map(|p| f32::from(p[0])).collect(), 255.0)
        }
        other => {
            return Err(Error::format(
                path,
                format!(
                    "a {:?} image: expected an 8- or 16-bit grey transmittance map",
                    other.color()
                ),
            ))
        }
    };
    let floor = floor_of(max_code);
    Ok(Grid::from_vec(
        w as usize,
        h as usize,
        values
            .into_iter()
            // τ = 1 as an optical depth of 1e-6 (τ within 1e-6): a range of 0 is an
            // unknown range to brume's loaders.
            .map(|v| (-(v / max_code).max(floor).ln()).max(MIN_OPTICAL_DEPTH))
            .collect(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// He et al.'s rule picks the haze-opaque sky over a bright but coloured object: a
    /// white car has a dark channel near its own minimum only if every channel is bright.
    #[test]
    fn the_airlight_is_the_brightest_of_the_haziest_pixels() {
        let (w, h) = (60, 40);
        let image = Grid::from_fn(w, h, |x, y| {
            if y < 10 {
                [0.6, 0.65, 0.7] // sky
            } else if (20..30).contains(&x) && y > 25 {
                [1.0, 0.05, 0.05] // a bright red car: dark channel 0.05
            } else {
                [0.1, 0.1, 0.08] // road
            }
        });
        let l = dark_channel_airlight(&image);
        let want = [0.6f32, 0.65, 0.7].map(linear_to_srgb);
        for c in 0..3 {
            assert!((l[c] - want[c]).abs() < 1e-6, "{l:?} vs {want:?}");
        }
    }

    /// The blend in code values: t = 1 keeps the image, t = 0 is the airlight, t = ½ is the
    /// mean of their code values (not of their linear values).
    #[test]
    fn blending_is_in_code_values() {
        let image = Grid::filled(3, 1, [0.2f32, 0.2, 0.2]);
        let tau = Grid::from_vec(3, 1, vec![1.0, 0.0, 0.5]);
        let out = blend_in_code_values(&image, &tau, [1.0; 3]);
        assert!((out.get(0, 0)[0] - 0.2).abs() < 1e-6);
        assert!((out.get(1, 0)[0] - 1.0).abs() < 1e-6);
        let half = srgb_to_linear((linear_to_srgb(0.2) + 1.0) / 2.0);
        assert!((out.get(2, 0)[0] - half).abs() < 1e-6);
        // In linear light the same t gives 0.6: denser fog.
        assert!(half < 0.55, "{half}");
    }
}
