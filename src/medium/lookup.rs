//! Lookup textures a medium samples: a tiling noise that varies a fog's density (paper
//! 001), a precomputed integral over distance (paper 002's attenuation). The medium holds
//! the values on the CPU; the pipeline uploads each lookup once (one `R32F` texture,
//! bilinear) and binds it for the passes that use the medium. [`Lookup::sample`] is GL's
//! bilinear filter in f64, for the CPU reference.

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

/// A one-channel float table, sampled with normalised coordinates and bilinear filtering.
/// Cheap to clone (the values are shared); the GPU copy is keyed by [`Lookup::id`].
#[derive(Clone, Debug)]
pub struct Lookup {
    id: u64,
    width: usize,
    height: usize,
    wrap: Wrap,
    values: Arc<Vec<f32>>,
}

impl Lookup {
    /// A `width x height` table, row 0 first (texture coordinate v = 0), from `values`.
    pub fn new(width: usize, height: usize, values: Vec<f32>, wrap: Wrap) -> Result<Self> {
        if width == 0 || height == 0 || values.len() != width * height {
            return Err(Error::invalid(
                "lookup",
                format!("{width}x{height} with {} values", values.len()),
                "a non-empty table with width x height values",
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

    /// The wrap mode.
    pub fn wrap(&self) -> Wrap {
        self.wrap
    }

    /// The values, row 0 first.
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// The texel at integer coordinates, wrapped as the GPU does.
    pub fn texel(&self, x: i64, y: i64) -> f64 {
        let fold = |i: i64, n: usize| match self.wrap {
            Wrap::Repeat => i.rem_euclid(n as i64) as usize,
            Wrap::ClampToEdge => i.clamp(0, n as i64 - 1) as usize,
        };
        f64::from(self.values[fold(y, self.height) * self.width + fold(x, self.width)])
    }

    /// GL's bilinear sample at normalised coordinates (u, v): texel centres at
    /// ((i + ½)/width, (j + ½)/height).
    pub fn sample(&self, u: f64, v: f64) -> f64 {
        let x = u * self.width as f64 - 0.5;
        let y = v * self.height as f64 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (i, j) = (x0 as i64, y0 as i64);
        let row = |j| self.texel(i, j) * (1.0 - fx) + self.texel(i + 1, j) * fx;
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
    }
}
