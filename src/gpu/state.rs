//! The bits of GL state brume's upload, read-back and creation helpers touch, saved
//! before and restored after, so that a helper called at any time (inside a render or
//! not) leaves the host's state as it found it: the active unit's `TEXTURE_2D` binding,
//! the pixel store (`UNPACK_*`/`PACK_*` alignment, row length, skips), the pixel
//! buffer bindings and the framebuffer bindings. The active texture unit itself is never
//! changed by a helper: it binds on whatever unit is active and puts that unit's texture
//! back.

use glow::HasContext;

/// The texture bound to `TEXTURE_2D` on the active unit.
pub(crate) struct TextureBinding(Option<glow::Texture>);

impl TextureBinding {
    /// Saves the active unit's `TEXTURE_2D` binding.
    pub(crate) fn save(gl: &glow::Context) -> Self {
        // SAFETY: a state query on the current context.
        TextureBinding(unsafe { gl.get_parameter_texture(glow::TEXTURE_BINDING_2D) })
    }

    /// Binds it again on the active unit.
    pub(crate) fn restore(self, gl: &glow::Context) {
        // SAFETY: re-binding the handle that was bound (the host's, still alive).
        unsafe { gl.bind_texture(glow::TEXTURE_2D, self.0) };
    }
}

/// Both framebuffer bindings.
pub(crate) struct FramebufferBindings {
    draw: Option<glow::Framebuffer>,
    read: Option<glow::Framebuffer>,
}

impl FramebufferBindings {
    /// Saves the draw and read framebuffer bindings.
    pub(crate) fn save(gl: &glow::Context) -> Self {
        // SAFETY: state queries on the current context.
        unsafe {
            FramebufferBindings {
                draw: gl.get_parameter_framebuffer(glow::DRAW_FRAMEBUFFER_BINDING),
                read: gl.get_parameter_framebuffer(glow::READ_FRAMEBUFFER_BINDING),
            }
        }
    }

    /// Binds them again.
    pub(crate) fn restore(self, gl: &glow::Context) {
        // SAFETY: re-binding the handles that were bound.
        unsafe {
            gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, self.draw);
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, self.read);
        }
    }
}

/// The pixel store a tightly packed f32 upload needs (alignment 4, no row length, no
/// skips), with the value each had.
const UNPACK: [u32; 4] = [
    glow::UNPACK_ALIGNMENT,
    glow::UNPACK_ROW_LENGTH,
    glow::UNPACK_SKIP_ROWS,
    glow::UNPACK_SKIP_PIXELS,
];

/// The same for a read-back.
const PACK: [u32; 4] = [
    glow::PACK_ALIGNMENT,
    glow::PACK_ROW_LENGTH,
    glow::PACK_SKIP_ROWS,
    glow::PACK_SKIP_PIXELS,
];

/// The values brume transfers with, in the order of [`UNPACK`] and [`PACK`].
const TIGHT: [i32; 4] = [4, 0, 0, 0];

/// One direction of the pixel store and its pixel buffer binding, as the host left them.
/// (`UNPACK_IMAGE_HEIGHT` and `UNPACK_SKIP_IMAGES` apply to 3D textures only: brume's
/// uploads are 2D and never read them.)
pub(crate) struct PixelStore {
    params: &'static [u32; 4],
    saved: [i32; 4],
    buffer_target: u32,
    buffer: Option<glow::Buffer>,
}

impl PixelStore {
    /// Sets the pixel store for an upload from client memory (tight rows, no
    /// `PIXEL_UNPACK_BUFFER`), saving what was there.
    pub(crate) fn for_upload(gl: &glow::Context) -> Self {
        Self::set(
            gl,
            &UNPACK,
            glow::PIXEL_UNPACK_BUFFER,
            glow::PIXEL_UNPACK_BUFFER_BINDING,
        )
    }

    /// Sets the pixel store for a read-back into client memory (tight rows, no
    /// `PIXEL_PACK_BUFFER`), saving what was there.
    pub(crate) fn for_read_back(gl: &glow::Context) -> Self {
        Self::set(
            gl,
            &PACK,
            glow::PIXEL_PACK_BUFFER,
            glow::PIXEL_PACK_BUFFER_BINDING,
        )
    }

    fn set(gl: &glow::Context, params: &'static [u32; 4], target: u32, binding: u32) -> Self {
        // SAFETY: state queries and pixel-store settings on the current context.
        unsafe {
            let saved = params.map(|p| gl.get_parameter_i32(p));
            let buffer = gl.get_parameter_buffer(binding);
            for (&p, value) in params.iter().zip(TIGHT) {
                gl.pixel_store_i32(p, value);
            }
            if buffer.is_some() {
                gl.bind_buffer(target, None);
            }
            PixelStore {
                params,
                saved,
                buffer_target: target,
                buffer,
            }
        }
    }

    /// Puts back the host's values and pixel buffer.
    pub(crate) fn restore(self, gl: &glow::Context) {
        // SAFETY: pixel-store settings and the buffer that was bound, on the current
        // context.
        unsafe {
            for (&p, value) in self.params.iter().zip(self.saved) {
                gl.pixel_store_i32(p, value);
            }
            if self.buffer.is_some() {
                gl.bind_buffer(self.buffer_target, self.buffer);
            }
        }
    }
}
