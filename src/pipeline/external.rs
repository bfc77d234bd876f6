//! Camera frames and other platform images that GL samples only through
//! `GL_TEXTURE_EXTERNAL_OES` (`samplerExternalOES`): an Android `SurfaceTexture` or an
//! `AHardwareBuffer` bound with `glEGLImageTargetTexture2DOES`. brume's passes read their
//! colour with `texelFetch` on a `sampler2D`, so an external image is first copied by one
//! import pass into a texture the pipeline owns and keeps between frames of the same size.

use super::Pipeline;
use crate::error::Result;

/// A colour image bound to `GL_TEXTURE_EXTERNAL_OES` by the host. Not owned: brume never
/// deletes it.
#[derive(Clone, Copy, Debug)]
pub struct ExternalColour {
    /// The external texture object.
    pub texture: glow::Texture,
    /// Width of the image brume makes of it (px).
    pub width: usize,
    /// Height of the image brume makes of it (px).
    pub height: usize,
    /// Column-major 4 x 4 transform of texture coordinates, as Android's
    /// `SurfaceTexture.getTransformMatrix` gives it ([`IDENTITY`] where there is none).
    pub transform: [f32; 16],
}

/// The identity transform of [`ExternalColour::transform`].
pub const IDENTITY: [f32; 16] = [
    1.0, 0.0, 0.0, 0.0, //
    0.0, 1.0, 0.0, 0.0, //
    0.0, 0.0, 1.0, 0.0, //
    0.0, 0.0, 0.0, 1.0,
];

impl Pipeline {
    /// Whether the context can sample external images
    /// (`GL_OES_EGL_image_external_essl3`).
    pub fn supports_external(&self) -> bool {
        unimplemented!("work in progress: external OES import")
    }

    /// Copies `source` into a pipeline-owned `SRGB8_ALPHA8` texture of its size (kept
    /// between frames of the same size) and returns that texture, to be given to
    /// [`Pipeline::render`] or [`Pipeline::fog`] as [`super::Input::colour`] with
    /// [`super::Encoding::Linear`]. The external image is taken as sRGB-encoded, as camera
    /// frames are.
    pub fn import_external(&mut self, source: &ExternalColour) -> Result<glow::Texture> {
        let _ = source;
        unimplemented!("work in progress: external OES import")
    }
}
