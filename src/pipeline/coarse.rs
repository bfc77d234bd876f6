//! Coarse to fine (issue 21, [`crate::Blur::coarse_from`]): once the most blurred pixel
//! has reached a few px, the image holds almost nothing at the pixel scale, and the
//! remaining diffusion steps run at half resolution on a quarter of the pixels; once its
//! scale has doubled again, at a quarter of the resolution, and so on
//! ([`Schedule::coarse_levels`]).
//!
//! 1. **Down** (`coarse_down.frag`), at each level's first step kℓ: D and ρ of the finer
//!    level (F and ρ for the first) averaged over 2x2 blocks (one bilinear fetch each;
//!    one for both in the offset layout, ρ in alpha) into the level's D, a copy Dℓ(kℓ)
//!    and its rate.
//! 2. **Steps** kℓ..kℓ+1 at that level: `diffuse.frag` unchanged, with the offset law's
//!    scale divided by 2^ℓ. Exact in variance for the matched scheme: its offset inverts
//!    the bilinear moment, so a coarse step adds (in full-resolution px²) exactly what the
//!    full-resolution step would. Each level's resampling adds 4^(ℓ−1) px², taken off its
//!    own steps ([`Schedule::level_scale`]).
//! 3. **Blend** (`coarse_detail.glsl`), deepest level first, after step N: the finer
//!    level's D_N ≈ Dℓ,N↑ + a(x)·(D(kℓ) − Dℓ(kℓ)↑), the detail the average removed put
//!    back, attenuated by the remaining blur's transfer at the centre of that band
//!    ([`Schedule::level_detail_weight`]). The down-and-up sampling acts on the increment
//!    Dℓ,N − Dℓ(kℓ) only, which is already smooth, so it adds no variance of note. A
//!    blend between coarse levels is a pass of its own (`coarse_blend.frag`); the blend
//!    into full resolution is done by the composite (`composite.frag` with
//!    `COARSE_BLEND`), which saves a full-resolution pass: its write and the composite's
//!    read of a full-resolution RGBA32F target.

use super::programs::ProgramKey;
use crate::blur::{Precision, COARSE_PRECISION};
use crate::error::Result;
use crate::gpu::framebuffer::Framebuffer;
use crate::gpu::texture::{Filter, Texture};
use crate::schedule::Schedule;
use std::sync::Arc;

/// The coarse stage's levels' targets, made on first use, and the steps at which this
/// frame's levels start.
#[derive(Default)]
pub(super) struct Coarse {
    pub(super) targets: Option<CoarseTargets>,
    /// Level ℓ + 1 runs steps `starts[ℓ]..starts[ℓ + 1]` (the last one to N).
    pub(super) starts: Vec<u32>,
}

/// One coarse level's textures (one τ: grey, or any in the offset layout): level ℓ is the
/// finer level's size halved, rounded up (an odd last row or column averages its texel
/// with itself: clamp to edge).
pub(super) struct Level {
    /// Its size in texels.
    pub(super) size: (usize, usize),
    /// D, ping-pong.
    pub(super) d: [Texture; 2],
    /// D at the level's first step, for its blend.
    pub(super) d0: Texture,
    /// ρ averaged over 2x2 blocks of the finer level, in the pre-multiplied layout (the
    /// offset layout's is D's alpha).
    pub(super) rate: Option<Texture>,
    /// The down pass's destination: `D[0]`, `D_k0` and the rate where it has its own.
    pub(super) down: Framebuffer,
    /// The steps' and the finer level's blend's destinations: `D[i]`.
    pub(super) step: [Framebuffer; 2],
}

impl Level {
    fn new(
        gl: &Arc<glow::Context>,
        size: (usize, usize),
        precision: Precision,
        rate_in_alpha: bool,
    ) -> Result<Self> {
        let target = |format| Texture::new(gl, size.0, size.1, format, Filter::Linear, None);
        let d = [
            target(precision.colour_format())?,
            target(precision.colour_format())?,
        ];
        let d0 = target(precision.colour_format())?;
        let rate = if rate_in_alpha {
            None
        } else {
            Some(target(precision.rate_format())?)
        };
        let what = "the coarse stage";
        let attachments: Vec<&Texture> = [&d[0], &d0].into_iter().chain(&rate).collect();
        let down = Framebuffer::over(gl, &attachments, what)?;
        let step = [
            Framebuffer::over(gl, &[&d[0]], what)?,
            Framebuffer::over(gl, &[&d[1]], what)?,
        ];
        Ok(Level {
            size,
            d,
            d0,
            rate,
            down,
            step,
        })
    }

    /// 1 / its size.
    pub(super) fn texel(&self) -> [f32; 2] {
        [1.0 / self.size.0 as f32, 1.0 / self.size.1 as f32]
    }
}

/// The coarse levels of a `width x height` frame, finest (half resolution) first.
pub(super) struct CoarseTargets {
    /// Full-resolution size they serve.
    full: (usize, usize),
    precision: Precision,
    rate_in_alpha: bool,
    pub(super) levels: Vec<Level>,
}

/// The smallest side (texels) of a coarse level below the first: a level smaller than this
/// is mostly border, where clamp-to-edge makes its average differ from the finer level's.
pub const MIN_LEVEL_SIDE: usize = 8;

impl CoarseTargets {
    /// Half of `width x height`, rounded up.
    pub(super) fn half(width: usize, height: usize) -> (usize, usize) {
        (width.div_ceil(2), height.div_ceil(2))
    }

    /// The size of coarse level `level` (1: half) of a `width x height` frame.
    pub(super) fn level_size(width: usize, height: usize, level: u32) -> (usize, usize) {
        (0..level).fold((width, height), |(w, h), _| Self::half(w, h))
    }

    /// How many of `wanted` levels a `width x height` frame has room for: the first
    /// always, each further one while both its sides are at least [`MIN_LEVEL_SIDE`].
    pub(super) fn levels_that_fit(width: usize, height: usize, wanted: usize) -> usize {
        (1..=wanted)
            .take_while(|&l| {
                let (w, h) = Self::level_size(width, height, l as u32);
                l == 1 || w.min(h) >= MIN_LEVEL_SIDE
            })
            .count()
    }

    pub(super) fn new(
        gl: &Arc<glow::Context>,
        width: usize,
        height: usize,
        precision: Precision,
        rate_in_alpha: bool,
        count: usize,
    ) -> Result<Self> {
        let levels = (1..=count as u32)
            .map(|l| {
                let size = Self::level_size(width, height, l);
                Level::new(gl, size, COARSE_PRECISION, rate_in_alpha)
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(CoarseTargets {
            full: (width, height),
            precision,
            rate_in_alpha,
            levels,
        })
    }

    /// Whether these targets serve a `width x height` frame at `precision` in a layout
    /// with ρ in alpha or not, with (at least) `count` levels: more are kept, so that a
    /// viewer whose σmax moves does not reallocate at every change.
    pub(super) fn fits(
        &self,
        width: usize,
        height: usize,
        precision: Precision,
        rate_in_alpha: bool,
        count: usize,
    ) -> bool {
        (self.full, self.precision, self.rate_in_alpha)
            == ((width, height), precision, rate_in_alpha)
            && self.levels.len() >= count
    }

    /// Bytes of their levels' texels.
    pub(super) fn bytes(&self) -> u64 {
        let level = |l: &Level| -> u64 {
            l.d.iter()
                .chain([&l.d0])
                .chain(&l.rate)
                .map(Texture::bytes)
                .sum()
        };
        self.levels.iter().map(level).sum()
    }
}

impl super::Pipeline {
    /// Compiles the coarse stage's programs once per layout, plans this frame's levels
    /// from the first level's start `first` ([`Schedule::coarse_levels`], as many as the
    /// frame has room for) and sizes their targets.
    pub(super) fn prepare_coarse(
        &mut self,
        width: usize,
        height: usize,
        precision: Precision,
        rate_in_alpha: bool,
        schedule: &Schedule,
    ) -> Result<()> {
        let Some(first) = self.coarse_start else {
            self.coarse.starts.clear();
            return Ok(());
        };
        self.program(ProgramKey::CoarseDown { rate_in_alpha }, None)?;
        self.program(ProgramKey::CoarseBlend { rate_in_alpha }, None)?;
        let mut starts = schedule.coarse_levels(first);
        starts.truncate(CoarseTargets::levels_that_fit(width, height, starts.len()));
        let fits = self
            .coarse
            .targets
            .as_ref()
            .is_some_and(|t| t.fits(width, height, precision, rate_in_alpha, starts.len()));
        if !fits {
            self.coarse.targets = None; // free the old textures first
            self.coarse.targets = Some(CoarseTargets::new(
                &self.gl,
                width,
                height,
                precision,
                rate_in_alpha,
                starts.len(),
            )?);
        }
        self.coarse.starts = starts;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn level_sizes_halve_rounding_up() {
        assert_eq!(CoarseTargets::level_size(641, 555, 1), (321, 278));
        assert_eq!(CoarseTargets::level_size(641, 555, 3), (81, 70));
        assert_eq!(CoarseTargets::level_size(1, 1, 4), (1, 1));
    }

    #[test]
    fn levels_stop_before_a_side_falls_under_the_minimum() {
        // 1600x1120: 800x560, 400x280, … 25x17.5 → 13x9 at level 7: all six fit.
        assert_eq!(CoarseTargets::levels_that_fit(1600, 1120, 6), 6);
        // 40x40: 20, 10, 5: the third level is too small.
        assert_eq!(CoarseTargets::levels_that_fit(40, 40, 3), 2);
        // The first level always runs (a 4x4 image keeps the one-level stage).
        assert_eq!(CoarseTargets::levels_that_fit(4, 4, 3), 1);
        assert_eq!(CoarseTargets::levels_that_fit(4, 4, 0), 0);
    }
}
