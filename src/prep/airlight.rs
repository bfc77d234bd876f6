//! Airlight estimation: the colour of the sky, or a neutral grey when there is none.

use super::Prepared;
use crate::raster::RgbImage;

/// Percentile of the known pixels' luminance that sets the neutral airlight's brightness.
/// High enough to reach the scene's bright end; below 1 so that the few brightest pixels
/// (lamps, specular highlights, clipped areas) do not set it on their own.
const NEUTRAL_PERCENTILE: f64 = 0.99;

/// Rec. 709 luminance weights of linear RGB. They sum to 1, so the grey `[y, y, y]` has
/// luminance `y`.
pub(crate) const REC709_LUMA: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// Which pixels an [`AirlightEstimate`] comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AirlightSource {
    /// The sky pixels (paper sec. 4.1: "estimated from sky regions").
    Sky,
    /// No sky: a neutral grey as bright as the 99th percentile of the luminance of the
    /// known (measured, not filled) pixels.
    Neutral,
}

/// The airlight colour and where it came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AirlightEstimate {
    /// Linear-light RGB: the per-channel median of the sky pixels, or, for
    /// [`AirlightSource::Neutral`], the same value in all three channels.
    pub rgb: [f32; 3],
    /// Which pixels were used.
    pub source: AirlightSource,
    /// How many pixels were used.
    pub pixels: usize,
}

/// Estimates the airlight of `image` from what [`prepare`](super::prepare) found.
///
/// - **Sky in view:** the per-channel median of the linear colour of the sky pixels. The
///   median (not the mean, not the maximum) ignores the sun, birds, wires and bright
///   leakage round foliage.
/// - **No sky:** a neutral grey `[y, y, y]`, where `y` is the 99th percentile (nearest
///   rank) of the Rec. 709 luminance `0.2126 R + 0.7152 G + 0.0722 B` of the known pixels
///   (measured range: neither sky nor filled; every pixel if none is known), clamped to
///   `>= 0`. Without sky nothing in the picture shows the colour of the light: the colour
///   of the farthest surface is its reflectance (a dark red wall would give a dark red
///   veil), so no tint is the honest choice. For the brightness, a lit surface reflects at
///   most the light that falls on it, so the brightest surfaces are the best estimate of
///   the light in the scene (the white-patch assumption); a veil that bright lifts distant
///   parts towards the light instead of darkening them. Taking the 99th percentile, not
///   the maximum, keeps the top 1 % (lamps, highlights, clipped pixels) from setting it
///   alone. Pixels without measured range are left out because scanners fail most on
///   exactly those: shiny, saturated or light-emitting areas. A black image gives black
///   (haze then only absorbs); an overexposed one gives white (or, for a float image, its
///   clipped level).
///
/// Pixels with a non-finite channel are skipped in both cases; with none left the result
/// is black and `pixels` is 0.
///
/// # Panics
/// If `image` and `prepared` differ in size.
pub fn estimate_airlight(image: &RgbImage, prepared: &Prepared) -> AirlightEstimate {
    let (w, h) = (prepared.range.width(), prepared.range.height());
    assert!(
        image.width() == w && image.height() == h,
        "estimate_airlight: image is {}x{} but the range is {w}x{h}",
        image.width(),
        image.height()
    );
    let (source, idx) = if prepared.stats.sky_pixels > 0 {
        (AirlightSource::Sky, sky_pixels(prepared))
    } else {
        (AirlightSource::Neutral, known_pixels(prepared))
    };
    let colours: Vec<[f32; 3]> = idx
        .iter()
        .map(|&i| image.as_slice()[i])
        .filter(|c| c.iter().all(|v| v.is_finite()))
        .collect();
    let rgb = match source {
        AirlightSource::Sky => median_rgb(&colours),
        AirlightSource::Neutral => [bright_luminance(&colours); 3],
    };
    AirlightEstimate {
        rgb,
        source,
        pixels: colours.len(),
    }
}

fn sky_pixels(p: &Prepared) -> Vec<usize> {
    (0..p.sky.len()).filter(|&i| p.sky.as_slice()[i]).collect()
}

/// Indices of the pixels with measured range (neither sky nor filled); every pixel if none.
fn known_pixels(p: &Prepared) -> Vec<usize> {
    let (sky, filled) = (p.sky.as_slice(), p.filled.as_slice());
    let known: Vec<usize> = (0..sky.len()).filter(|&i| !sky[i] && !filled[i]).collect();
    if known.is_empty() {
        (0..sky.len()).collect()
    } else {
        known
    }
}

/// The [`NEUTRAL_PERCENTILE`] (nearest rank) of the Rec. 709 luminance of `colours`,
/// clamped to `[0, f32::MAX]` (float inputs may hold negative values); 0 for no colour.
fn bright_luminance(colours: &[[f32; 3]]) -> f32 {
    let mut y: Vec<f32> = colours
        .iter()
        .map(|&c| super::colour_step::luminance_of(c))
        .collect();
    if y.is_empty() {
        return 0.0;
    }
    let rank = ((y.len() as f64 * NEUTRAL_PERCENTILE).ceil() as usize).clamp(1, y.len());
    // Finite channels can still overflow the weighted sum at f32::MAX.
    y.select_nth_unstable_by(rank - 1, f32::total_cmp)
        .1
        .clamp(0.0, f32::MAX)
}

/// Per-channel median (upper median); black for no colour.
fn median_rgb(colours: &[[f32; 3]]) -> [f32; 3] {
    if colours.is_empty() {
        return [0.0; 3];
    }
    let mut ch = vec![0.0f32; colours.len()];
    let mut out = [0.0; 3];
    for (c, o) in out.iter_mut().enumerate() {
        ch.iter_mut().zip(colours).for_each(|(v, col)| *v = col[c]);
        let mid = ch.len() / 2;
        *o = *ch.select_nth_unstable_by(mid, f32::total_cmp).1;
    }
    out
}
