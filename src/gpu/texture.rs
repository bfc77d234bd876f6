//! 2D textures owned by brume: float images uploaded from the CPU, the float render
//! targets of the passes and the `SRGB8_ALPHA8` copy of an imported camera frame. The
//! host's textures are never wrapped in this type (brume must not delete them); they are
//! used by their raw `glow::Texture` handle.
//!
//! Creating, filling and configuring a texture binds it on the **active** unit and puts
//! that unit's binding back after, and sets the pixel store and `PIXEL_UNPACK_BUFFER`
//! for the upload and puts the host's values back (`gpu::state`): a host may call
//! these with any state of its own.

use super::state::{PixelStore, TextureBinding};
use crate::error::{Error, Result};
use glow::HasContext;
use std::sync::Arc;

/// A texel format brume uses, with its GL triple.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TexelFormat {
    /// RGBA 32-bit float.
    Rgba32F,
    /// RGBA 16-bit float.
    Rgba16F,
    /// One 32-bit float channel.
    R32F,
    /// One 16-bit float channel.
    R16F,
    /// Two 32-bit float channels.
    Rg32F,
    /// Two 16-bit float channels.
    Rg16F,
    /// Three 32-bit float channels (sampled only: RGB32F is not colour-renderable).
    Rgb32F,
    /// 8-bit sRGB-encoded RGB with linear alpha (`SRGB8_ALPHA8`): GL encodes on write and
    /// decodes on read, so shaders see linear values. Rendered to, never uploaded from f32.
    Srgb8Alpha8,
    /// 32-bit float depth (`DEPTH_COMPONENT32F`), a depth attachment; created with
    /// `TEXTURE_COMPARE_MODE` `NONE` so that shaders read the depth with `texelFetch`.
    Depth32F,
    /// 16-bit depth (`DEPTH_COMPONENT16`), a depth attachment filled by drawing only (no
    /// upload from f32): half the memory of [`TexelFormat::Depth32F`] where 0, ½ and 1
    /// are all a pass compares.
    Depth16,
    /// RGBA 8-bit unsigned normalised: a display target, filled by rendering only (no
    /// upload from f32).
    Rgba8,
}

impl TexelFormat {
    fn internal(self) -> u32 {
        match self {
            TexelFormat::Rgba32F => glow::RGBA32F,
            TexelFormat::Rgba16F => glow::RGBA16F,
            TexelFormat::R32F => glow::R32F,
            TexelFormat::R16F => glow::R16F,
            TexelFormat::Rg32F => glow::RG32F,
            TexelFormat::Rg16F => glow::RG16F,
            TexelFormat::Rgb32F => glow::RGB32F,
            TexelFormat::Srgb8Alpha8 => glow::SRGB8_ALPHA8,
            TexelFormat::Depth32F => glow::DEPTH_COMPONENT32F,
            TexelFormat::Depth16 => glow::DEPTH_COMPONENT16,
            TexelFormat::Rgba8 => glow::RGBA8,
        }
    }

    /// The client format of data uploaded as f32.
    fn client_format(self) -> u32 {
        match self {
            TexelFormat::Rgba32F
            | TexelFormat::Rgba16F
            | TexelFormat::Rgba8
            | TexelFormat::Srgb8Alpha8 => glow::RGBA,
            TexelFormat::R32F | TexelFormat::R16F => glow::RED,
            TexelFormat::Rg32F | TexelFormat::Rg16F => glow::RG,
            TexelFormat::Rgb32F => glow::RGB,
            TexelFormat::Depth32F | TexelFormat::Depth16 => glow::DEPTH_COMPONENT,
        }
    }

    /// Filled by rendering only: f32 data is not uploaded to it.
    fn drawn_only(self) -> bool {
        matches!(
            self,
            TexelFormat::Rgba8 | TexelFormat::Srgb8Alpha8 | TexelFormat::Depth16
        )
    }

    /// Bytes per texel.
    pub fn bytes_per_texel(self) -> usize {
        let channel = match self {
            TexelFormat::Rgba8 | TexelFormat::Srgb8Alpha8 => 1,
            TexelFormat::Rgba16F
            | TexelFormat::R16F
            | TexelFormat::Rg16F
            | TexelFormat::Depth16 => 2,
            _ => 4,
        };
        channel * self.channels()
    }

    /// Channels per texel.
    pub fn channels(self) -> usize {
        match self {
            TexelFormat::Rgba32F
            | TexelFormat::Rgba16F
            | TexelFormat::Rgba8
            | TexelFormat::Srgb8Alpha8 => 4,
            TexelFormat::R32F
            | TexelFormat::R16F
            | TexelFormat::Depth32F
            | TexelFormat::Depth16 => 1,
            TexelFormat::Rg32F | TexelFormat::Rg16F => 2,
            TexelFormat::Rgb32F => 3,
        }
    }
}

/// How a texture is sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Filter {
    /// Exact texel reads (texelFetch).
    Nearest,
    /// Hardware bilinear interpolation.
    Linear,
}

/// An owned 2D texture, clamped to its edges unless [`Texture::set_repeat`] says otherwise.
pub struct Texture {
    gl: Arc<glow::Context>,
    raw: glow::Texture,
    width: usize,
    height: usize,
    format: TexelFormat,
}

impl Texture {
    /// The texture in `slot` if it is `width x height`, else a new one of `format`
    /// (nearest filtering, undefined content) put there, the old one freed first: for the
    /// textures a caller keeps between calls of one size.
    pub(crate) fn kept<'s>(
        slot: &'s mut Option<Texture>,
        gl: &Arc<glow::Context>,
        width: usize,
        height: usize,
        format: TexelFormat,
    ) -> Result<&'s Texture> {
        if slot
            .as_ref()
            .is_some_and(|t| (t.width(), t.height()) != (width, height))
        {
            *slot = None;
        }
        if slot.is_none() {
            *slot = Some(Texture::new(
                gl,
                width,
                height,
                format,
                Filter::Nearest,
                None,
            )?);
        }
        Ok(slot.as_ref().expect("just made"))
    }

    /// Allocates a `width x height` texture and fills it from `data` (f32, row 0 first,
    /// `format.channels()` per texel) or leaves it undefined when `data` is `None`.
    pub fn new(
        gl: &Arc<glow::Context>,
        width: usize,
        height: usize,
        format: TexelFormat,
        filter: Filter,
        data: Option<&[f32]>,
    ) -> Result<Self> {
        if format.drawn_only() && data.is_some() {
            return Err(Error::invalid(
                "texture data",
                "f32 values",
                format!("none: a {format:?} texture is filled by rendering"),
            ));
        }
        if let Some(d) = data {
            assert_eq!(
                d.len(),
                width * height * format.channels(),
                "texture data size"
            );
        }
        let filter = match filter {
            Filter::Nearest => glow::NEAREST,
            Filter::Linear => glow::LINEAR,
        } as i32;
        // SAFETY: texture creation and upload on the current context; `data` has exactly
        // width*height*channels f32 values (asserted above).
        unsafe {
            let raw = gl.create_texture().map_err(Error::Gl)?;
            let bound = TextureBinding::save(gl);
            gl.bind_texture(glow::TEXTURE_2D, Some(raw));
            for (param, value) in [
                (glow::TEXTURE_MIN_FILTER, filter),
                (glow::TEXTURE_MAG_FILTER, filter),
                (glow::TEXTURE_WRAP_S, glow::CLAMP_TO_EDGE as i32),
                (glow::TEXTURE_WRAP_T, glow::CLAMP_TO_EDGE as i32),
            ] {
                gl.tex_parameter_i32(glow::TEXTURE_2D, param, value);
            }
            if matches!(format, TexelFormat::Depth32F | TexelFormat::Depth16) {
                gl.tex_parameter_i32(
                    glow::TEXTURE_2D,
                    glow::TEXTURE_COMPARE_MODE,
                    glow::NONE as i32,
                );
            }
            gl.tex_storage_2d(
                glow::TEXTURE_2D,
                1,
                format.internal(),
                width as i32,
                height as i32,
            );
            if let Some(d) = data {
                let store = PixelStore::for_upload(gl);
                gl.tex_sub_image_2d(
                    glow::TEXTURE_2D,
                    0,
                    0,
                    0,
                    width as i32,
                    height as i32,
                    format.client_format(),
                    glow::FLOAT,
                    glow::PixelUnpackData::Slice(Some(f32_bytes(d))),
                );
                store.restore(gl);
            }
            bound.restore(gl);
            super::object_created();
            let tex = Texture {
                gl: Arc::clone(gl),
                raw,
                width,
                height,
                format,
            };
            super::check_gl(
                gl,
                &format!("creating a {width}x{height} {format:?} texture"),
            )?;
            Ok(tex)
        }
    }

    /// Fills the texture from `data` (f32, `format.channels()` per texel) whose first row
    /// is the texture's last: an image stored top row first becomes a GL texture stored
    /// bottom row first. One upload per row, no staging copy.
    pub fn upload_flipped(&self, data: &[f32]) {
        assert!(
            !self.format.drawn_only(),
            "f32 data cannot be uploaded to a {:?} texture",
            self.format
        );
        let row = self.width * self.format.channels();
        assert_eq!(data.len(), row * self.height, "texture data size");
        // SAFETY: each upload writes one row of `row` f32 values, inside the texture.
        unsafe {
            let bound = TextureBinding::save(&self.gl);
            let store = PixelStore::for_upload(&self.gl);
            self.gl.bind_texture(glow::TEXTURE_2D, Some(self.raw));
            for (i, values) in data.chunks_exact(row).enumerate() {
                self.gl.tex_sub_image_2d(
                    glow::TEXTURE_2D,
                    0,
                    0,
                    (self.height - 1 - i) as i32,
                    self.width as i32,
                    1,
                    self.format.client_format(),
                    glow::FLOAT,
                    glow::PixelUnpackData::Slice(Some(f32_bytes(values))),
                );
            }
            store.restore(&self.gl);
            bound.restore(&self.gl);
        }
    }

    /// Makes the texture tile (`REPEAT` in s and t) instead of clamping to its edges.
    pub fn set_repeat(&self) {
        // SAFETY: parameters of an owned texture on the current context.
        unsafe {
            let bound = TextureBinding::save(&self.gl);
            self.gl.bind_texture(glow::TEXTURE_2D, Some(self.raw));
            for param in [glow::TEXTURE_WRAP_S, glow::TEXTURE_WRAP_T] {
                self.gl
                    .tex_parameter_i32(glow::TEXTURE_2D, param, glow::REPEAT as i32);
            }
            bound.restore(&self.gl);
        }
    }

    /// The GL texture object.
    pub fn raw(&self) -> glow::Texture {
        self.raw
    }

    /// Width in texels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Texel format.
    pub fn format(&self) -> TexelFormat {
        self.format
    }

    /// Bytes of its texels.
    pub(crate) fn bytes(&self) -> u64 {
        (self.width * self.height * self.format.bytes_per_texel()) as u64
    }

    /// Binds the texture to texture unit `unit` and makes `unit` active (inside a pass,
    /// whose caller restores the host's units).
    pub fn bind(&self, unit: u32) {
        // SAFETY: binding an owned texture on the current context.
        unsafe {
            self.gl.active_texture(glow::TEXTURE0 + unit);
            self.gl.bind_texture(glow::TEXTURE_2D, Some(self.raw));
        }
    }
}

impl Drop for Texture {
    fn drop(&mut self) {
        // SAFETY: the texture belongs to this wrapper; the context outlives it (Rc).
        unsafe { self.gl.delete_texture(self.raw) };
        super::object_deleted();
    }
}

/// Views f32 data as bytes for upload.
pub fn f32_bytes(data: &[f32]) -> &[u8] {
    // SAFETY: f32 has no padding and every byte pattern is a valid u8.
    unsafe { std::slice::from_raw_parts(data.as_ptr().cast::<u8>(), std::mem::size_of_val(data)) }
}

/// Views f32 data as mutable bytes for read-back.
pub fn f32_bytes_mut(data: &mut [f32]) -> &mut [u8] {
    // SAFETY: as above; any bytes written form valid f32 values.
    unsafe {
        std::slice::from_raw_parts_mut(data.as_mut_ptr().cast::<u8>(), std::mem::size_of_val(data))
    }
}
