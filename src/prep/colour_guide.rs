//! The colour image as the hole filling and the border bands read it: a hole split into
//! regions of one colour ([`split`]), a known pixel of a region's own colour, two sets of
//! pixels of one material ([`ColourGuide::alike`]).

use super::colour_step::{luminance, luminance_of, relative_step};
use super::components::flood;
use super::fill::median_in_place;
use crate::raster::RgbImage;

/// A pixel as [`split`] sees it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) enum Pixel {
    /// Not in the hole being split.
    #[default]
    Other,
    /// In the hole, not yet in a region.
    InHole,
    /// In the hole and in a region.
    InRegion,
}

/// See [`ColourGuide::alike`]: the largest difference of chromaticity (a channel over the
/// sum of the three) of one material.
const MATERIAL_CHROMA_STEP: f32 = 0.03;

/// See [`ColourGuide::alike`]: the largest ratio of the luminances of one material.
const MATERIAL_LUMINANCE_RATIO: f32 = 2.0;

/// The colour image as the hole fill reads it.
pub(crate) struct ColourGuide<'a> {
    colour: &'a [[f32; 3]],
    lum: Vec<f32>,
    /// Smallest luminance a relative step is measured against.
    eps: f32,
    /// Largest relative step between two pixels of one region.
    region_step: f32,
    /// Largest relative step between a region's pixel and a known pixel of its colour.
    own_step: f32,
}

impl<'a> ColourGuide<'a> {
    /// The guide of `image`; `step` is the image-guided sky growth's colour step, which
    /// also bounds one region (a known pixel of its colour may be twice as far).
    pub(crate) fn new(image: &'a RgbImage, step: f64) -> Self {
        let colour = image.as_slice();
        let lum = luminance(colour);
        // The median of every 16th pixel: the scale of the image, at a 16th of the cost.
        let mut sample: Vec<f32> = lum.iter().step_by(16).copied().collect();
        let eps = match sample.len() {
            0 => 1e-6,
            n => (0.01 * *sample.select_nth_unstable_by(n / 2, f32::total_cmp).1).max(1e-6),
        };
        ColourGuide {
            colour,
            lum,
            eps,
            region_step: step as f32,
            own_step: 2.0 * step as f32,
        }
    }

    /// Whether known pixel `q` has the colour of hole pixel `p`.
    pub(super) fn own_colour(&self, p: usize, q: usize) -> bool {
        relative_step(self.colour, &self.lum, p, q, self.eps) <= self.own_step
    }

    /// The relative colour step from pixel `p` to pixel `q`.
    pub(super) fn step(&self, p: usize, q: usize) -> f32 {
        relative_step(self.colour, &self.lum, p, q, self.eps)
    }

    /// Whether a [`ColourGuide::step`] is more than one region takes: an edge.
    pub(super) fn is_edge(&self, step: f32) -> bool {
        step > self.region_step
    }

    /// The colour (linear RGB) of pixel `p`.
    pub(crate) fn colour_at(&self, p: usize) -> [f32; 3] {
        self.colour[p]
    }

    /// Whether the pixels `a` and `b` look of one material: their median colours (per
    /// channel) of one chromaticity, within [`MATERIAL_CHROMA_STEP`] in each of r, g, b
    /// over r + g + b, and within [`MATERIAL_LUMINANCE_RATIO`] of each other's luminance
    /// (a face's shading changes across it: a glass facade of a Cityscapes frame was a
    /// quarter brighter at the border than 40 px inward, of the same chromaticity).
    pub(crate) fn alike(&self, a: &[usize], b: &[usize]) -> bool {
        let (ca, cb) = (self.median_colour(a), self.median_colour(b));
        let lum = |c: [f32; 3]| luminance_of(c).max(self.eps);
        let chroma = |c: [f32; 3]| {
            let sum = (c[0] + c[1] + c[2]).max(self.eps);
            c.map(|v| v / sum)
        };
        let (la, lb) = (lum(ca), lum(cb));
        let (xa, xb) = (chroma(ca), chroma(cb));
        la.max(lb) <= MATERIAL_LUMINANCE_RATIO * la.min(lb)
            && (0..3).all(|i| (xa[i] - xb[i]).abs() <= MATERIAL_CHROMA_STEP)
    }

    /// The per-channel median colour of `pixels` (at least one).
    fn median_colour(&self, pixels: &[usize]) -> [f32; 3] {
        let mut channel = Vec::with_capacity(pixels.len());
        [0, 1, 2].map(|c| {
            channel.clear();
            channel.extend(pixels.iter().map(|&p| f64::from(self.colour[p][c])));
            median_in_place(&mut channel) as f32
        })
    }

    /// The hole `pixels` split into 4-connected regions of one colour (steps of at most
    /// `region_step` between neighbours).
    pub(super) fn regions(
        &self,
        size: (usize, usize),
        pixels: &[u32],
        state: &mut [Pixel],
    ) -> Regions {
        split(size, pixels, state, |p, q| {
            relative_step(self.colour, &self.lum, p, q, self.eps) <= self.region_step
        })
    }
}

/// Regions of pixels, one after the other in one list, and where each ends: a hole of a
/// noisy image is a region per pixel, and [`super::components::Components`] would keep 56
/// bytes for each.
pub(super) struct Regions {
    pixels: Vec<u32>,
    ends: Vec<usize>,
}

impl Regions {
    /// Each region's pixels.
    pub(super) fn iter(&self) -> impl Iterator<Item = &[u32]> {
        let starts = std::iter::once(0).chain(self.ends.iter().copied());
        starts.zip(&self.ends).map(|(a, &b)| &self.pixels[a..b])
    }
}

/// `pixels` split into 4-connected regions, two neighbours joined when `joined(p, q)`.
/// `state` is scratch, [`Pixel::Other`] or [`Pixel::InRegion`] outside `pixels`.
pub(super) fn split(
    (width, height): (usize, usize),
    pixels: &[u32],
    state: &mut [Pixel],
    joined: impl Fn(usize, usize) -> bool,
) -> Regions {
    pixels
        .iter()
        .for_each(|&p| state[p as usize] = Pixel::InHole);
    let mut regions = Regions {
        pixels: Vec::with_capacity(pixels.len()),
        ends: Vec::new(),
    };
    for &seed in pixels {
        if state[seed as usize] != Pixel::InHole {
            continue;
        }
        let region = flood(width, height, seed as usize, &mut regions.pixels, |p, q| {
            let take = state[q] == Pixel::InHole && (p == q || joined(p, q));
            if take {
                state[q] = Pixel::InRegion;
            }
            take
        });
        regions.ends.push(region.start + region.len);
    }
    regions
}
