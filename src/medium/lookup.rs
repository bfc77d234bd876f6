//! Lookup textures a medium samples: a tiling noise that varies a fog's density (paper
//! 001), a precomputed integral over distance (paper 002's attenuation). The medium holds
//! the values on the CPU; the pipeline uploads each lookup once (an `R32F` texture, or
//! `RGB32F` for a three-channel table, bilinear) and binds it for the passes that use the
//! medium. [`Lookup::sample`] is GL's bilinear filter in f64, for the CPU reference.
//!
//! A table of three values per texel (paper 002's Γ_r, Γ_g, Γ_b) is one `RGB32F` texture
//! rather than three rows of one: a shader reads it with one fetch instead of three.

use crate::error::{Error, Result};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// What a lookup does beyond its edges (GL's `TEXTURE_WRAP_S/T`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    /// Tiles: `REPEAT`.
    Repeat,
    /// Holds the edge texels: `CLAMP_TO_EDGE`.
    ClampToEdge,
}

/// A float table of one or three channels, sampled with normalised coordinates and
/// bilinear filtering. Cheap to clone (the values are shared); the GPU copy is keyed by
/// [`Lookup::id`].
#[derive(Clone, Debug)]
pub struct Lookup {
    id: u64,
    width: usize,
    height: usize,
    channels: usize,
    wrap: Wrap,
    values: Arc<Vec<f32>>,
}

impl Lookup {
    /// A `width x height` table of one channel (`.r` in GLSL), row 0 first (texture
    /// coordinate v = 0), from `values`.
    pub fn new(width: usize, height: usize, values: Vec<f32>, wrap: Wrap) -> Result<Self> {
        Self::with_channels(width, height, 1, values, wrap)
    }

    /// A `width x height` table of three channels (`.rgb` in GLSL), row 0 first, from
    /// `values`.
    pub fn rgb(width: usize, height: usize, values: &[[f32; 3]], wrap: Wrap) -> Result<Self> {
        Self::with_channels(width, height, 3, values.concat(), wrap)
    }

    fn with_channels(
        width: usize,
        height: usize,
        channels: usize,
        values: Vec<f32>,
        wrap: Wrap,
    ) -> Result<Self> {
        if width == 0 || height == 0 || values.len() != width * height * channels {
            return Err(Error::invalid(
                "lookup",
                format!(
                    "{width}x{height} of {channels} channels with {} values",
                    values.len()
                ),
                "a non-empty table with width x height x channels values",
            ));
        }
        if let Some(v) = values.iter().find(|v| !v.is_finite()) {
            return Err(Error::invalid("lookup", v, "finite values"));
        }
        static NEXT_ID: AtomicU64 = AtomicU64::new(1);
        Ok(Lookup {
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
            width,
            height,
            channels,
            wrap,
            values: Arc::new(values),
        })
    }

    /// Unique per table created (clones share it): the pipeline's cache key.
    pub fn id(&self) -> u64 {
        self.id
    }

    /// Width in texels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Channels per texel: 1 or 3.
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// The wrap mode.
    pub fn wrap(&self) -> Wrap {
        self.wrap
    }

    /// The values, row 0 first, a texel's channels together.
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// The first channel of the texel at integer coordinates, wrapped as the GPU does.
    pub fn texel(&self, x: i64, y: i64) -> f64 {
        self.texel_channel(x, y, 0)
    }

    /// Channel `c` of the texel at integer coordinates, wrapped as the GPU does.
    pub fn texel_channel(&self, x: i64, y: i64, c: usize) -> f64 {
        let fold = |i: i64, n: usize| match self.wrap {
            Wrap::Repeat => i.rem_euclid(n as i64) as usize,
            Wrap::ClampToEdge => i.clamp(0, n as i64 - 1) as usize,
        };
        let texel = fold(y, self.height) * self.width + fold(x, self.width);
        f64::from(self.values[texel * self.channels + c])
    }

    /// GL's bilinear sample of the first channel at normalised coordinates (u, v): texel
    /// centres at ((i + ½)/width, (j + ½)/height).
    pub fn sample(&self, u: f64, v: f64) -> f64 {
        self.sample_channel(u, v, 0)
    }

    /// [`Lookup::sample`] of channel `c`.
    pub fn sample_channel(&self, u: f64, v: f64, c: usize) -> f64 {
        let x = u * self.width as f64 - 0.5;
        let y = v * self.height as f64 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (i, j) = (x0 as i64, y0 as i64);
        let texel = |i, j| self.texel_channel(i, j, c);
        let row = |j| texel(i, j) * (1.0 - fx) + texel(i + 1, j) * fx;
        row(j) * (1.0 - fy) + row(j + 1) * fy
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_sample_hits_texel_centres_and_wraps() {
        let lookup = Lookup::new(2, 1, vec![0.0, 1.0], Wrap::Repeat).unwrap();
        assert_eq!(lookup.sample(0.25, 0.5), 0.0);
        assert_eq!(lookup.sample(0.75, 0.5), 1.0);
        assert!((lookup.sample(0.5, 0.5) - 0.5).abs() < 1e-12);
        // Half-way between the last texel and the first (wrapped).
        assert!((lookup.sample(1.0, 0.5) - 0.5).abs() < 1e-12);
        // u = −0.25 is u = 0.75 one tile to the left: texel 1.
        assert!((lookup.sample(-0.25, 0.5) - 1.0).abs() < 1e-12);
        let clamped = Lookup::new(2, 1, vec![0.0, 1.0], Wrap::ClampToEdge).unwrap();
        assert_eq!(clamped.sample(1.0, 0.5), 1.0);
        assert_ne!(lookup.id(), clamped.id());
    }

    #[test]
    fn bad_tables_are_refused() {
        assert!(Lookup::new(2, 2, vec![0.0; 3], Wrap::Repeat).is_err());
        assert!(Lookup::new(1, 1, vec![f32::NAN], Wrap::Repeat).is_err());
        assert!(Lookup::rgb(2, 1, &[[0.0; 3]], Wrap::Repeat).is_err());
    }

    /// Each channel of a three-channel table filters on its own, as one texel's
    /// channels do in an RGB texture.
    #[test]
    fn three_channels_sample_apart() {
        let texels = [[0.0, 10.0, 100.0], [1.0, 20.0, 300.0]];
        let lookup = Lookup::rgb(2, 1, &texels, Wrap::ClampToEdge).unwrap();
        assert_eq!(lookup.channels(), 3);
        assert_eq!(lookup.texel_channel(1, 0, 2), 300.0);
        let mid = [0.5, 15.0, 200.0];
        for (c, want) in mid.into_iter().enumerate() {
            assert!(
                (lookup.sample_channel(0.5, 0.5, c) - want).abs() < 1e-12,
                "{c}"
            );
        }
        assert_eq!(lookup.sample(0.75, 0.5), 1.0);
    }
}
