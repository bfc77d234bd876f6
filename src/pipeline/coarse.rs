//! Coarse to fine (issue 21, [`crate::Blur::coarse_from`]): once the most blurred pixel
//! has reached a few px, the image holds almost nothing at the pixel scale, and the
//! remaining diffusion steps run at half resolution on a quarter of the pixels.
//!
//! 1. **Down** (`coarse_down.frag`): F and ρ at step k0 averaged over 2x2 blocks (one
//!    bilinear fetch each) into D, a copy D_k0 and the half-resolution rate.
//! 2. **Steps k0..N** at half resolution: `diffuse.frag` unchanged, with the offset law's
//!    scale halved. Exact in variance for the matched scheme: its offset inverts the
//!    bilinear moment, so a half-resolution step adds (in full-resolution px²) exactly
//!    what the full-resolution step would.
//! 3. **Blend** (`coarse_blend.frag`): F_N ≈ D_N↑ + a(x)·(F_k0 − D_k0↑), the detail the
//!    average removed put back, attenuated by the remaining blur's transfer
//!    ([`crate::schedule::Schedule::detail_weight`]). The down-and-up sampling acts on the
//!    increment D_N − D_k0 only, which is already smooth, so it adds no variance of note.

use super::programs::PRELUDE_GLSL;
use crate::blur::Precision;
use crate::error::Result;
use crate::gpu::framebuffer::Framebuffer;
use crate::gpu::program::Program;
use crate::gpu::texture::{Filter, Texture};
use std::sync::Arc;

const DOWN_FRAG: &str = include_str!("../../glsl/coarse_down.frag");
const BLEND_FRAG: &str = include_str!("../../glsl/coarse_blend.frag");

/// The coarse stage's two programs and half-resolution targets, made on first use.
#[derive(Default)]
pub(super) struct Coarse {
    pub(super) programs: Option<CoarsePrograms>,
    pub(super) targets: Option<CoarseTargets>,
}

/// The down and blend passes.
pub(super) struct CoarsePrograms {
    pub(super) down: Program,
    pub(super) blend: Program,
}

impl CoarsePrograms {
    pub(super) fn compile(gl: &Arc<glow::Context>, version_line: &str) -> Result<Self> {
        let header = format!("{version_line}\n{PRELUDE_GLSL}");
        Ok(CoarsePrograms {
            down: Program::new(
                gl,
                &header,
                ("coarse_down.frag", DOWN_FRAG),
                &["u_f", "u_rate", "u_texel"],
                &[],
            )?,
            blend: Program::new(
                gl,
                &header,
                ("coarse_blend.frag", BLEND_FRAG),
                &[
                    "u_f",
                    "u_rate",
                    "u_coarse",
                    "u_coarse0",
                    "u_half_texel",
                    "u_detail",
                ],
                &[],
            )?,
        })
    }
}

/// The half-resolution textures of a `width x height` frame (grey τ only).
pub(super) struct CoarseTargets {
    /// Full-resolution size they serve.
    full: (usize, usize),
    precision: Precision,
    /// D, ping-pong.
    pub(super) d: [Texture; 2],
    /// D at step k0, for the blend.
    pub(super) d0: Texture,
    /// ρ averaged over 2x2 blocks.
    pub(super) rate: Texture,
    /// The down pass's destination: D[0], D_k0 and the rate.
    pub(super) down: Framebuffer,
    /// The half-resolution steps' destinations: D[i].
    pub(super) step: [Framebuffer; 2],
}

impl CoarseTargets {
    /// Half of `width x height`, rounded up (an odd last row or column averages its
    /// texel with itself: clamp to edge).
    pub(super) fn half(width: usize, height: usize) -> (usize, usize) {
        (width.div_ceil(2), height.div_ceil(2))
    }

    pub(super) fn new(
        gl: &Arc<glow::Context>,
        width: usize,
        height: usize,
        precision: Precision,
    ) -> Result<Self> {
        let (w, h) = Self::half(width, height);
        let target = |format| Texture::new(gl, w, h, format, Filter::Linear, None);
        let d = [
            target(precision.colour_format())?,
            target(precision.colour_format())?,
        ];
        let d0 = target(precision.colour_format())?;
        let rate = target(precision.rate_format())?;
        let what = "the coarse stage";
        let down = Framebuffer::over(gl, &[&d[0], &d0, &rate], what)?;
        let step = [
            Framebuffer::over(gl, &[&d[0]], what)?,
            Framebuffer::over(gl, &[&d[1]], what)?,
        ];
        Ok(CoarseTargets {
            full: (width, height),
            precision,
            d,
            d0,
            rate,
            down,
            step,
        })
    }

    pub(super) fn fits(&self, width: usize, height: usize, precision: Precision) -> bool {
        (self.full, self.precision) == ((width, height), precision)
    }

    /// 1 / the half-resolution size.
    pub(super) fn texel(&self) -> [f32; 2] {
        let (w, h) = Self::half(self.full.0, self.full.1);
        [1.0 / w as f32, 1.0 / h as f32]
    }
}

impl super::Pipeline {
    /// Compiles the coarse stage's programs once and sizes its targets for this frame.
    pub(super) fn prepare_coarse(
        &mut self,
        width: usize,
        height: usize,
        precision: Precision,
    ) -> Result<()> {
        if self.coarse.programs.is_none() {
            self.coarse.programs = Some(CoarsePrograms::compile(&self.gl, self.version_line)?);
        }
        let fits = self
            .coarse
            .targets
            .as_ref()
            .is_some_and(|t| t.fits(width, height, precision));
        if !fits {
            self.coarse.targets = None; // free the old textures first
            self.coarse.targets = Some(CoarseTargets::new(&self.gl, width, height, precision)?);
        }
        Ok(())
    }
}
