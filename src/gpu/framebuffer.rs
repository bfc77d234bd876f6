//! Framebuffers owned by brume: one GL framebuffer object with one or more colour
//! attachments (multiple render targets). The attached textures are not owned: they are
//! brume's own [`super::texture::Texture`]s, or a host's texture that brume renders into
//! and never deletes.
//!
//! Creating or re-attaching a framebuffer and reading one back put the host's
//! framebuffer bindings, pixel store and `PIXEL_PACK_BUFFER` back after
//! (`gpu::state`).

use super::state::{FramebufferBindings, PixelStore};
use super::texture::{f32_bytes_mut, Texture};
use crate::error::{Error, Result};
use glow::HasContext;
use std::sync::Arc;

/// An owned framebuffer object over textures that outlive it.
pub struct Framebuffer {
    gl: Arc<glow::Context>,
    fbo: glow::Framebuffer,
    width: usize,
    height: usize,
}

impl Framebuffer {
    /// A framebuffer drawing into `textures` (all `width x height`), attachment i being
    /// `COLOR_ATTACHMENTi` and draw buffer i. `what` names it in errors.
    pub fn new(
        gl: &Arc<glow::Context>,
        textures: &[glow::Texture],
        width: usize,
        height: usize,
        what: &str,
    ) -> Result<Self> {
        Self::with_depth(gl, textures, None, width, height, what)
    }

    /// The same with a depth texture (`DEPTH_COMPONENT*`, same size) on
    /// `DEPTH_ATTACHMENT`, for passes that draw geometry with the depth test.
    pub fn with_depth(
        gl: &Arc<glow::Context>,
        textures: &[glow::Texture],
        depth: Option<glow::Texture>,
        width: usize,
        height: usize,
        what: &str,
    ) -> Result<Self> {
        // SAFETY: framebuffer creation on the current context; the framebuffer is owned by
        // the returned value (deleted in Drop, also on the error path below).
        unsafe {
            let fbo = gl.create_framebuffer().map_err(Error::Gl)?;
            super::object_created();
            let framebuffer = Framebuffer {
                gl: Arc::clone(gl),
                fbo,
                width,
                height,
            };
            let bound = FramebufferBindings::save(gl);
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            let mut buffers = Vec::with_capacity(textures.len());
            for (i, &texture) in textures.iter().enumerate() {
                let attachment = glow::COLOR_ATTACHMENT0 + i as u32;
                gl.framebuffer_texture_2d(
                    glow::FRAMEBUFFER,
                    attachment,
                    glow::TEXTURE_2D,
                    Some(texture),
                    0,
                );
                buffers.push(attachment);
            }
            if let Some(depth) = depth {
                gl.framebuffer_texture_2d(
                    glow::FRAMEBUFFER,
                    glow::DEPTH_ATTACHMENT,
                    glow::TEXTURE_2D,
                    Some(depth),
                    0,
                );
            }
            gl.draw_buffers(&buffers);
            let status = gl.check_framebuffer_status(glow::FRAMEBUFFER);
            bound.restore(gl);
            check_complete(status, what)?;
            Ok(framebuffer)
        }
    }

    /// Points colour attachment 0 at `texture` (`width x height`) instead of what it had:
    /// one framebuffer serves a host's output textures frame after frame, with no GL object
    /// created per frame. `what` names it in errors.
    pub fn attach(
        &mut self,
        texture: Option<glow::Texture>,
        width: usize,
        height: usize,
        what: &str,
    ) -> Result<()> {
        // SAFETY: re-attaches a texture to the framebuffer this value owns.
        let status = unsafe {
            let bound = FramebufferBindings::save(&self.gl);
            self.gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.fbo));
            self.gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                glow::COLOR_ATTACHMENT0,
                glow::TEXTURE_2D,
                texture,
                0,
            );
            let status = self.gl.check_framebuffer_status(glow::FRAMEBUFFER);
            bound.restore(&self.gl);
            status
        };
        self.width = width;
        self.height = height;
        match texture {
            Some(_) => check_complete(status, what),
            None => Ok(()),
        }
    }

    /// A framebuffer over brume's own `textures`.
    pub fn over(gl: &Arc<glow::Context>, textures: &[&Texture], what: &str) -> Result<Self> {
        let first = textures.first().expect("at least one attachment");
        let raw: Vec<glow::Texture> = textures.iter().map(|t| t.raw()).collect();
        Self::new(gl, &raw, first.width(), first.height(), what)
    }

    /// The GL framebuffer object.
    pub fn raw(&self) -> glow::Framebuffer {
        self.fbo
    }

    /// Makes this framebuffer the destination of draws and sets the viewport to cover it
    /// (inside a pass, whose caller restores the host's bindings and viewport).
    pub fn bind_for_drawing(&self) {
        // SAFETY: binding an owned framebuffer on the current context.
        unsafe {
            self.gl.bind_framebuffer(glow::FRAMEBUFFER, Some(self.fbo));
            self.gl
                .viewport(0, 0, self.width as i32, self.height as i32);
        }
    }

    /// Reads attachment 0 back as RGBA f32, texel row 0 first.
    pub fn read_rgba(&self) -> Result<Vec<[f32; 4]>> {
        let mut out = vec![[0f32; 4]; self.width * self.height];
        self.read_attachment0(glow::RGBA, out.as_flattened_mut());
        super::check_gl(&self.gl, "reading back the result")?;
        Ok(out)
    }

    /// Reads the red channel of attachment 0 (an R32F texture's values) back as f32,
    /// texel row 0 first: as `RED`/`FLOAT` where the driver offers that pair for this
    /// framebuffer (a quarter of the bytes of RGBA: 48 MB less at 12 MP), else through
    /// RGBA. GLES guarantees only RGBA/FLOAT for float buffers; the second pair is the
    /// driver's choice for the bound buffer's format, so it is asked here, per buffer.
    pub fn read_red(&self) -> Result<Vec<f32>> {
        if !self.reads_red_floats() {
            return Ok(self.read_rgba()?.iter().map(|t| t[0]).collect());
        }
        let mut out = vec![0f32; self.width * self.height];
        self.read_attachment0(glow::RED, &mut out);
        super::check_gl(&self.gl, "reading back the result")?;
        Ok(out)
    }

    /// Whether `glReadPixels` takes `RED`/`FLOAT` from this framebuffer's attachment 0.
    fn reads_red_floats(&self) -> bool {
        // SAFETY: binds an owned framebuffer for reading and puts the host's back.
        unsafe {
            let bound = FramebufferBindings::save(&self.gl);
            self.gl
                .bind_framebuffer(glow::READ_FRAMEBUFFER, Some(self.fbo));
            self.gl.read_buffer(glow::COLOR_ATTACHMENT0);
            let format = self
                .gl
                .get_parameter_i32(glow::IMPLEMENTATION_COLOR_READ_FORMAT);
            let kind = self
                .gl
                .get_parameter_i32(glow::IMPLEMENTATION_COLOR_READ_TYPE);
            bound.restore(&self.gl);
            format as u32 == glow::RED && kind as u32 == glow::FLOAT
        }
    }

    /// Reads attachment 0 into `out` as `format` floats (RGBA or RED: `out` holds four or
    /// one a texel), with the host's pixel store and bindings put back after.
    fn read_attachment0(&self, format: u32, out: &mut [f32]) {
        let channels = if format == glow::RED { 1 } else { 4 };
        assert_eq!(out.len(), self.width * self.height * channels);
        // SAFETY: `out` holds w*h texels of `channels` f32 values (asserted), which is
        // what `format`/FLOAT writes with the tight rows `for_read_back` sets.
        unsafe {
            let bound = FramebufferBindings::save(&self.gl);
            let store = PixelStore::for_read_back(&self.gl);
            self.gl
                .bind_framebuffer(glow::READ_FRAMEBUFFER, Some(self.fbo));
            self.gl.read_buffer(glow::COLOR_ATTACHMENT0);
            self.gl.read_pixels(
                0,
                0,
                self.width as i32,
                self.height as i32,
                format,
                glow::FLOAT,
                glow::PixelPackData::Slice(Some(f32_bytes_mut(out))),
            );
            store.restore(&self.gl);
            bound.restore(&self.gl);
        }
    }
}

impl Drop for Framebuffer {
    fn drop(&mut self) {
        // SAFETY: the framebuffer belongs to this wrapper; the context outlives it (Arc).
        unsafe { self.gl.delete_framebuffer(self.fbo) };
        super::object_deleted();
    }
}

/// The error of a framebuffer whose `glCheckFramebufferStatus` is not complete.
fn check_complete(status: u32, what: &str) -> Result<()> {
    if status == glow::FRAMEBUFFER_COMPLETE {
        return Ok(());
    }
    Err(Error::Gl(format!(
        "the framebuffer for {what} is incomplete (status 0x{status:04X}): the driver \
         cannot render to its texture format"
    )))
}
