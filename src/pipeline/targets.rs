//! The diffusion's float targets: ping-pong colour, the rate and, for a chromatic
//! medium, the (τ_g, τ_b) pair, kept between frames of the same size.

use crate::blur::Precision;
use crate::error::Result;
use crate::gpu::framebuffer::Framebuffer;
use crate::gpu::texture::{Filter, Texture};
use std::sync::Arc;

/// The diffusion textures, kept between frames of the same size, precision and kind of τ.
pub(super) struct Targets {
    pub(super) width: usize,
    pub(super) height: usize,
    pub(super) precision: Precision,
    pub(super) chromatic: bool,
    /// Pre-multiplied colour F, ping-pong.
    pub(super) f: [Texture; 2],
    /// (τ_g, τ_b) of a chromatic medium, ping-pong.
    pub(super) tau_gb: Option<[Texture; 2]>,
    /// Per-pixel rate ρ.
    pub(super) rate: Texture,
    /// The medium pass's destination: `F[0]`, ρ and `(τ_g, τ_b)[0]`.
    pub(super) first: Framebuffer,
    /// The diffusion passes' destinations: `F[i]` and `(τ_g, τ_b)[i]`.
    pub(super) step: [Framebuffer; 2],
}

impl Targets {
    pub(super) fn new(
        gl: &Arc<glow::Context>,
        width: usize,
        height: usize,
        precision: Precision,
        chromatic: bool,
    ) -> Result<Self> {
        let target = |format| Texture::new(gl, width, height, format, Filter::Linear, None);
        let f = [
            target(precision.colour_format())?,
            target(precision.colour_format())?,
        ];
        let tau_gb = if chromatic {
            Some([
                target(precision.pair_format())?,
                target(precision.pair_format())?,
            ])
        } else {
            None
        };
        let rate = target(precision.rate_format())?;
        let pair = |i: usize| tau_gb.as_ref().map(|p| &p[i]);
        let first = Framebuffer::over(
            gl,
            &attachments(&[&f[0], &rate], pair(0)),
            "the medium pass",
        )?;
        let step = [
            Framebuffer::over(gl, &attachments(&[&f[0]], pair(0)), "a diffusion pass")?,
            Framebuffer::over(gl, &attachments(&[&f[1]], pair(1)), "a diffusion pass")?,
        ];
        Ok(Targets {
            width,
            height,
            precision,
            chromatic,
            f,
            tau_gb,
            rate,
            first,
            step,
        })
    }

    pub(super) fn fits(
        &self,
        width: usize,
        height: usize,
        precision: Precision,
        chromatic: bool,
    ) -> bool {
        (self.width, self.height, self.precision, self.chromatic)
            == (width, height, precision, chromatic)
    }
}

/// `textures`, then `pair` if there is one: a framebuffer's attachments in order.
fn attachments<'a>(textures: &[&'a Texture], pair: Option<&'a Texture>) -> Vec<&'a Texture> {
    textures.iter().copied().chain(pair).collect()
}
