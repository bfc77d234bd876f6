//! Render targets: a float texture attached to its own framebuffer.

use super::texture::{f32_bytes_mut, Filter, TexelFormat, Texture};
use crate::error::{Error, Result};
use glow::HasContext;
use std::rc::Rc;

/// A texture that passes render into and later passes sample from.
pub struct RenderTarget {
    gl: Rc<glow::Context>,
    fbo: glow::Framebuffer,
    texture: Texture,
}

impl RenderTarget {
    /// A `width x height` float target, sampled bilinearly.
    pub fn new(
        gl: &Rc<glow::Context>,
        width: usize,
        height: usize,
        format: TexelFormat,
    ) -> Result<Self> {
        let texture = Texture::new(gl, width, height, format, Filter::Linear, None)?;
        // SAFETY: framebuffer creation on the current context; the attached texture is
        // owned by the returned target and outlives the framebuffer.
        unsafe {
            let fbo = gl.create_framebuffer().map_err(Error::Gl)?;
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                glow::COLOR_ATTACHMENT0,
                glow::TEXTURE_2D,
                Some(texture.raw()),
                0,
            );
            let status = gl.check_framebuffer_status(glow::FRAMEBUFFER);
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            let target = RenderTarget {
                gl: Rc::clone(gl),
                fbo,
                texture,
            };
            if status != glow::FRAMEBUFFER_COMPLETE {
                return Err(Error::Gl(format!(
                    "a {format:?} framebuffer is incomplete (status 0x{status:04X}): the driver \
                     cannot render to this format"
                )));
            }
            Ok(target)
        }
    }

    /// The texture to sample from.
    pub fn texture(&self) -> &Texture {
        &self.texture
    }

    /// Makes this target the destination of draws and sets the viewport to cover it.
    pub fn bind_for_drawing(&self) {
        // SAFETY: binding an owned framebuffer on the current context.
        unsafe {
            self.gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.fbo));
            self.gl.viewport(
                0,
                0,
                self.texture.width() as i32,
                self.texture.height() as i32,
            );
        }
    }

    /// Reads the whole target back as RGBA f32, row 0 first.
    pub fn read_rgba(&self) -> Result<Vec<[f32; 4]>> {
        let (w, h) = (self.texture.width(), self.texture.height());
        let mut out = vec![[0f32; 4]; w * h];
        // SAFETY: `out` holds w*h RGBA f32 values, which is what RGBA/FLOAT writes.
        unsafe {
            self.gl
                .bind_framebuffer(glow::READ_FRAMEBUFFER, Some(self.fbo));
            self.gl.pixel_store_i32(glow::PACK_ALIGNMENT, 4);
            self.gl.read_pixels(
                0,
                0,
                w as i32,
                h as i32,
                glow::RGBA,
                glow::FLOAT,
                glow::PixelPackData::Slice(Some(f32_bytes_mut(out.as_flattened_mut()))),
            );
            self.gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
        }
        super::check_gl(&self.gl, "reading back the result")?;
        Ok(out)
    }
}

impl Drop for RenderTarget {
    fn drop(&mut self) {
        // SAFETY: the framebuffer belongs to this wrapper; the context outlives it (Rc).
        unsafe { self.gl.delete_framebuffer(self.fbo) };
    }
}
