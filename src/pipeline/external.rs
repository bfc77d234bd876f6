//! Camera frames and other platform images that GL samples only through
//! `GL_TEXTURE_EXTERNAL_OES` (`samplerExternalOES`): an Android `SurfaceTexture` or an
//! `AHardwareBuffer` bound with `glEGLImageTargetTexture2DOES`. brume's passes read their
//! colour with `texelFetch` on a `sampler2D`, so an external image is first copied by one
//! import pass into a texture the pipeline owns and keeps between frames of the same size.
//!
//! **The copy.** Texel (x, y) of the copy (row 0 at the bottom, as GL stores it) is the
//! external image sampled at `transform · ((x + ½) / width, (y + ½) / height, 0, 1)`:
//! with [`IDENTITY`] and the image's own size that is the centre of source texel (x, y),
//! copied exactly (a bilinear filter returns that texel alone there). The value is taken
//! as sRGB-encoded (camera frames are), decoded to linear light and stored in
//! `SRGB8_ALPHA8`, which GL encodes on write and decodes on read: the passes see linear
//! values, at 8 bits a channel as the frame had.
//!
//! **The transform** is what Android's `SurfaceTexture.getTransformMatrix` returns:
//! column-major, applied to (s, t, 0, 1) in GL's texture coordinates (t = 0 at the first
//! row in memory). A camera's usually flips t (`t' = 1 − t`), so that the copy's row 0 is
//! the frame's bottom row and a render into the default framebuffer comes out upright.
//!
//! **State.** An import changes what a render does (see the parent module) and unit 0's
//! `GL_TEXTURE_EXTERNAL_OES` binding, and puts all of it back as the host left it.

use super::programs::{ProgramKey, PRELUDE_GLSL};
use super::state::HostState;
use super::{draw_fullscreen, Pipeline, UNIT_MAIN};
use crate::error::{Error, Result};
use crate::gpu::framebuffer::Framebuffer;
use crate::gpu::program::{Program, FULLSCREEN_VERT};
use crate::gpu::texture::{Filter, TexelFormat, Texture};
use glow::HasContext;
use std::sync::Arc;

const EXTERNAL_IMPORT_FRAG: &str = include_str!("../../glsl/external_import.frag");

/// `GL_TEXTURE_EXTERNAL_OES`, the target external images are bound to (glow does not
/// export it).
pub const TEXTURE_EXTERNAL_OES: u32 = 0x8D65;

/// `GL_TEXTURE_BINDING_EXTERNAL_OES`, the query of that target's binding.
pub const TEXTURE_BINDING_EXTERNAL_OES: u32 = 0x8D67;

/// A colour image bound to `GL_TEXTURE_EXTERNAL_OES` by the host. Not owned: brume never
/// deletes it.
#[derive(Clone, Copy, Debug)]
pub struct ExternalColour {
    /// The external texture object.
    pub texture: glow::Texture,
    /// Width of the image brume makes of it (px); the image's own width for an exact
    /// copy (any other size resamples it).
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

/// The uniforms of `external_import.frag`, all required.
const UNIFORMS: [&str; 3] = ["u_external", "u_transform", "u_size"];

/// The copy of the last external image imported, and the framebuffer over it.
pub(super) struct ImportTarget {
    // Field order is drop order: the framebuffer before the texture it draws into.
    framebuffer: Framebuffer,
    texture: Texture,
}

impl ImportTarget {
    fn new(gl: &Arc<glow::Context>, width: usize, height: usize) -> Result<Self> {
        // Linear: a host that samples the copy with texture() gets the filter it expects;
        // brume's passes use texelFetch, which ignores it.
        let texture = Texture::new(
            gl,
            width,
            height,
            TexelFormat::Srgb8Alpha8,
            Filter::Linear,
            None,
        )?;
        let framebuffer = Framebuffer::over(gl, &[&texture], "the external image's copy")?;
        Ok(ImportTarget {
            framebuffer,
            texture,
        })
    }

    fn fits(&self, width: usize, height: usize) -> bool {
        (self.texture.width(), self.texture.height()) == (width, height)
    }
}

impl Pipeline {
    /// Whether the context can sample external images
    /// (`GL_OES_EGL_image_external_essl3`), detected once in [`crate::caps::Capabilities`].
    pub fn supports_external(&self) -> bool {
        self.caps.egl_image_external_essl3
    }

    /// Copies `source` into a pipeline-owned `SRGB8_ALPHA8` texture of its size (kept
    /// between frames of the same size) and returns that texture, to be given to
    /// [`Pipeline::render`] or [`Pipeline::fog`] as [`super::Input::colour`] with
    /// [`super::Encoding::Linear`]. The external image is taken as sRGB-encoded, as camera
    /// frames are (module docs: the copy, the transform and the GL state left).
    ///
    /// Errors: [`Error::MissingCapability`] on a context without
    /// `GL_OES_EGL_image_external_essl3` (upload the frame as a `GL_TEXTURE_2D` instead),
    /// [`Error::InvalidParameter`] for an empty size or a transform that is not finite,
    /// [`Error::TooLarge`] above `GL_MAX_TEXTURE_SIZE`.
    pub fn import_external(&mut self, source: &ExternalColour) -> Result<glow::Texture> {
        self.caps.require_external_images()?;
        self.caps
            .require_size("external image", source.width, source.height)?;
        check_transform(&source.transform)?;
        self.program(ProgramKey::ExternalImport, None)?;
        let fits = self
            .imported
            .as_ref()
            .is_some_and(|t| t.fits(source.width, source.height));
        if !fits {
            self.imported = None; // free the old copy before allocating the new one
            self.imported = Some(ImportTarget::new(&self.gl, source.width, source.height)?);
        }
        // The extension is present (checked above): unit 0's external binding is saved.
        let saved = HostState::save(&self.gl, self.state_scope(true));
        self.enter_state();
        let result = self.run_import(source);
        saved.restore(&self.gl);
        result
    }

    /// The import pass: draws the copy of `source` and returns it.
    fn run_import(&self, source: &ExternalColour) -> Result<glow::Texture> {
        let gl = &self.gl;
        let target = self
            .imported
            .as_ref()
            .ok_or_else(|| Error::Gl("internal: the external image's copy not allocated".into()))?;
        let p = self.compiled(ProgramKey::ExternalImport)?;
        target.framebuffer.bind_for_drawing();
        self.use_program(p);
        // SAFETY: the host's external texture bound to its target on the current context;
        // the uniforms are the program's, with the types the shader declares.
        unsafe {
            gl.active_texture(glow::TEXTURE0 + UNIT_MAIN);
            gl.bind_texture(TEXTURE_EXTERNAL_OES, Some(source.texture));
            gl.uniform_1_i32(Some(p.uniform("u_external")), UNIT_MAIN as i32);
            gl.uniform_matrix_4_f32_slice(Some(p.uniform("u_transform")), false, &source.transform);
            gl.uniform_2_f32(
                Some(p.uniform("u_size")),
                source.width as f32,
                source.height as f32,
            );
        }
        draw_fullscreen(gl);
        crate::gpu::check_gl(gl, "importing an external image")?;
        Ok(target.texture.raw())
    }
}

/// Compiles the import pass: the shared vertex shader, and `external_import.frag` with its
/// `#extension` line before the prelude (GLSL ES allows no other token before it).
pub(super) fn compile(gl: &Arc<glow::Context>, version_line: &str) -> Result<Program> {
    let vertex_header = format!("{version_line}\n{PRELUDE_GLSL}");
    let fragment = after_extensions(EXTERNAL_IMPORT_FRAG, PRELUDE_GLSL);
    Program::with_vertex(
        gl,
        (&vertex_header, FULLSCREEN_VERT),
        (version_line, ("external_import.frag", &fragment)),
        &UNIFORMS,
        &[],
    )
}

/// `source` with `insert` put after its last `#extension` line (at the start if it has
/// none).
fn after_extensions(source: &str, insert: &str) -> String {
    let lines: Vec<&str> = source.lines().collect();
    let split = lines
        .iter()
        .rposition(|line| line.trim_start().starts_with("#extension"))
        .map_or(0, |i| i + 1);
    let (head, tail) = lines.split_at(split);
    format!("{}\n{insert}\n{}\n", head.join("\n"), tail.join("\n"))
}

/// Rejects a transform with a NaN or infinite element by name.
fn check_transform(transform: &[f32; 16]) -> Result<()> {
    match transform.iter().find(|v| !v.is_finite()) {
        None => Ok(()),
        Some(v) => Err(Error::invalid(
            "ExternalColour::transform",
            format!("a matrix holding {v}"),
            "16 finite numbers (column-major)",
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_prelude_goes_after_the_extension_line() {
        let source = "// a comment\n#extension GL_X : require\nuniform float a;\n";
        let spliced = after_extensions(source, "precision highp float;");
        assert_eq!(
            spliced,
            "// a comment\n#extension GL_X : require\nprecision highp float;\nuniform float a;\n"
        );
        assert!(after_extensions("void main() {}", "P").starts_with("\nP\nvoid main"));
    }

    #[test]
    fn the_import_shader_declares_its_extension_first() {
        let spliced = after_extensions(EXTERNAL_IMPORT_FRAG, PRELUDE_GLSL);
        let extension = spliced
            .find("#extension GL_OES_EGL_image_external_essl3 : require")
            .expect("the extension line");
        assert!(extension < spliced.find("precision highp float;").expect("the prelude"));
        assert!(spliced.contains("samplerExternalOES"));
    }

    #[test]
    fn transforms_must_be_finite() {
        assert!(check_transform(&IDENTITY).is_ok());
        let mut bad = IDENTITY;
        bad[13] = f32::NAN;
        let text = check_transform(&bad).unwrap_err().to_string();
        assert!(text.contains("ExternalColour::transform"), "{text}");
    }
}
