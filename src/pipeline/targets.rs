//! The diffusion's float targets, kept between frames of the same size: ping-pong
//! colour and, in the pre-multiplied layout, the rate and a chromatic medium's (τ_g, τ_b)
//! pair.

use crate::blur::Precision;
use crate::error::Result;
use crate::gpu::framebuffer::Framebuffer;
use crate::gpu::texture::{Filter, TexelFormat, Texture};
use crate::medium::Medium;
use std::sync::Arc;

/// How the diffused state lies in the targets (module docs of the parent, *Two layouts*).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Layout {
    /// Paper 000's F = (τ·E, τ_r) in RGBA, ρ in a target of its own and, for a chromatic
    /// medium, (τ_g, τ_b) in a third: any medium.
    Premultiplied { chromatic: bool },
    /// (τ·(E − L∞), ρ) in one RGBA target: a medium whose L∞ is the same at every pixel
    /// ([`Medium::uniform_inscatter`]), grey or chromatic.
    Offset,
}

impl Layout {
    /// The layout `medium` renders in: the offset one wherever it is exact.
    pub(crate) fn of(medium: &dyn Medium) -> Self {
        if medium.uniform_inscatter() {
            Layout::Offset
        } else {
            Layout::Premultiplied {
                chromatic: medium.chromatic(),
            }
        }
    }

    /// Whether (τ_g, τ_b) travel in a target pair of their own.
    pub(crate) fn tau_pair(self) -> bool {
        self == Layout::Premultiplied { chromatic: true }
    }

    /// Whether ρ travels in the alpha of the colour (the offset layout).
    pub(crate) fn rate_in_alpha(self) -> bool {
        self == Layout::Offset
    }

    /// Bytes per pixel of the targets at `precision`: two colour targets, and in the
    /// pre-multiplied layout the rate and, for a chromatic medium, two (τ_g, τ_b) targets.
    pub(super) fn bytes_per_pixel(self, precision: Precision) -> u64 {
        let texel = |format: TexelFormat| format.bytes_per_texel() as u64;
        let colour = 2 * texel(precision.colour_format());
        match self {
            Layout::Offset => colour,
            Layout::Premultiplied { chromatic } => {
                let pair = if chromatic {
                    2 * texel(precision.pair_format())
                } else {
                    0
                };
                colour + texel(precision.rate_format()) + pair
            }
        }
    }
}

/// The diffusion textures, kept between frames of the same size, precision and layout.
pub(super) struct Targets {
    pub(super) width: usize,
    pub(super) height: usize,
    pub(super) precision: Precision,
    pub(super) layout: Layout,
    /// The colour F (pre-multiplied, or offset with ρ in alpha), ping-pong.
    pub(super) f: [Texture; 2],
    /// (τ_g, τ_b) of a chromatic medium in the pre-multiplied layout, ping-pong.
    pub(super) tau_gb: Option<[Texture; 2]>,
    /// Per-pixel rate ρ, in the pre-multiplied layout.
    pub(super) rate: Option<Texture>,
    /// The medium pass's destination: `F[0]`, ρ and `(τ_g, τ_b)[0]` where they exist.
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
        layout: Layout,
    ) -> Result<Self> {
        let target = |format| Texture::new(gl, width, height, format, Filter::Linear, None);
        let f = [
            target(precision.colour_format())?,
            target(precision.colour_format())?,
        ];
        let tau_gb = if layout.tau_pair() {
            Some([
                target(precision.pair_format())?,
                target(precision.pair_format())?,
            ])
        } else {
            None
        };
        let rate = match layout {
            Layout::Premultiplied { .. } => Some(target(precision.rate_format())?),
            Layout::Offset => None,
        };
        let pair = |i: usize| tau_gb.as_ref().map(|p| &p[i]);
        let first = Framebuffer::over(
            gl,
            &attachments(&[&f[0]], rate.iter().chain(pair(0))),
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
            layout,
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
        layout: Layout,
    ) -> bool {
        (self.width, self.height, self.precision, self.layout) == (width, height, precision, layout)
    }

    /// Bytes of their texels.
    pub(super) fn bytes(&self) -> u64 {
        let pair = self.tau_gb.iter().flatten();
        self.f
            .iter()
            .chain(pair)
            .chain(&self.rate)
            .map(Texture::bytes)
            .sum()
    }
}

/// `textures`, then `more`: a framebuffer's attachments in order.
fn attachments<'a>(
    textures: &[&'a Texture],
    more: impl IntoIterator<Item = &'a Texture>,
) -> Vec<&'a Texture> {
    textures.iter().copied().chain(more).collect()
}
