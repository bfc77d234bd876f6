//! What the GL driver can do, detected once per context and kept: strings, the float
//! render/filter extensions brume depends on, timer queries and the texture size limit.
//!
//! **Desktop OpenGL** (a host's or the viewer's GL 3.3+ core context) is decided here,
//! once, as wgpu-hal decides its workarounds: desktop GL has no `GL_EXT_*`/`GL_OES_*`
//! names for what is core there, so float render targets (GL 3.0), float bilinear
//! filtering (GL 3.0) and the half-float targets are taken from the version; brume's
//! GLSL ES 3.00 shaders need `GL_ARB_ES3_compatibility` (core in 4.3; Mesa exposes it on
//! 3.3 core contexts), checked by [`Capabilities::require_es3_shaders`]; external images
//! do not exist; timer queries are not used (desktop GL has no `GL_GPU_DISJOINT_EXT`:
//! timing is by `glFinish` and the wall clock); and the passes enable
//! `GL_FRAMEBUFFER_SRGB` (restored after) so that an `SRGB8_ALPHA8` destination is
//! encoded on write as GLES always does.

use crate::egl::GlContext;
use crate::error::{Error, Result};
use crate::Precision;
use glow::HasContext;

/// Where an EGL context came from: known for brume's own headless context, not for a
/// host's context.
#[derive(Clone, Debug, serde::Serialize)]
pub struct EglInfo {
    /// EGL platform the display was opened on.
    #[serde(rename = "egl_platform")]
    pub platform: String,
    /// `EGL_VENDOR`.
    #[serde(rename = "egl_vendor")]
    pub vendor: String,
    /// `EGL_VERSION`.
    #[serde(rename = "egl_version")]
    pub version: String,
}

impl EglInfo {
    /// The facts of brume's headless context.
    pub fn of(ctx: &GlContext) -> Self {
        EglInfo {
            platform: ctx.platform().name().to_string(),
            vendor: ctx.egl_vendor().to_string(),
            version: ctx.egl_version().to_string(),
        }
    }
}

/// The driver facts brume needs, read once after the context is made current.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Capabilities {
    /// The EGL display and platform, when brume opened the context itself.
    #[serde(flatten)]
    pub egl: Option<EglInfo>,
    /// `GL_VENDOR`.
    pub vendor: String,
    /// `GL_RENDERER`, e.g. `llvmpipe (LLVM 15.0.6, 256 bits)`.
    pub renderer: String,
    /// `GL_VERSION`, e.g. `OpenGL ES 3.2 Mesa 22.3.6`.
    pub version: String,
    /// `GL_SHADING_LANGUAGE_VERSION`.
    pub shading_language_version: String,
    /// major.minor of the context: its GLES version, or its desktop GL version where
    /// [`Capabilities::desktop`].
    pub gles_version: (u32, u32),
    /// A desktop OpenGL context (not GLES): capabilities decided from its version (module
    /// docs).
    pub desktop: bool,
    /// The context compiles brume's GLSL ES 3.00 shaders: always on GLES 3; on desktop GL
    /// with `GL_ARB_ES3_compatibility` or GL 4.3.
    pub es3_shaders: bool,
    /// `GL_EXT_color_buffer_float`: RGBA32F (and RGBA16F) are renderable.
    pub color_buffer_float: bool,
    /// `GL_EXT_color_buffer_half_float`: RGBA16F is renderable.
    pub color_buffer_half_float: bool,
    /// `GL_OES_texture_float_linear`: RGBA32F can be sampled with bilinear filtering.
    pub texture_float_linear: bool,
    /// `GL_EXT_disjoint_timer_query`: GL_TIME_ELAPSED queries.
    pub disjoint_timer_query: bool,
    /// `GL_OES_EGL_image_external_essl3`: GLSL ES 3 shaders can sample
    /// `samplerExternalOES` (camera frames, [`crate::pipeline::ExternalColour`]).
    pub egl_image_external_essl3: bool,
    /// `GL_OES_EGL_image_external`: external images exist, but without the `_essl3`
    /// extension only GLSL ES 1.00 shaders may sample them, which brume's are not.
    pub egl_image_external: bool,
    /// `GL_MAX_TEXTURE_SIZE`.
    pub max_texture_size: u32,
}

impl Capabilities {
    /// Reads the driver strings and extensions of the context current on this thread.
    pub fn detect(gl: &glow::Context) -> Self {
        let exts = gl.supported_extensions();
        let has = |name: &str| exts.contains(name);
        // SAFETY: plain state queries on the context that is current on this thread.
        let (vendor, renderer, version, glsl, max_texture_size) = unsafe {
            (
                gl.get_parameter_string(glow::VENDOR),
                gl.get_parameter_string(glow::RENDERER),
                gl.get_parameter_string(glow::VERSION),
                gl.get_parameter_string(glow::SHADING_LANGUAGE_VERSION),
                gl.get_parameter_i32(glow::MAX_TEXTURE_SIZE).max(0) as u32,
            )
        };
        let v = gl.version();
        let version_pair = (v.major, v.minor);
        let desktop = !v.is_embedded;
        // Desktop GL 3.0 made float textures renderable and filterable (module docs).
        let core_float = desktop && version_pair >= (3, 0);
        Capabilities {
            egl: None,
            vendor,
            renderer,
            version,
            shading_language_version: glsl,
            gles_version: version_pair,
            desktop,
            es3_shaders: if desktop {
                version_pair >= (4, 3) || has("GL_ARB_ES3_compatibility")
            } else {
                version_pair >= (3, 0)
            },
            color_buffer_float: core_float || has("GL_EXT_color_buffer_float"),
            color_buffer_half_float: core_float || has("GL_EXT_color_buffer_half_float"),
            texture_float_linear: core_float || has("GL_OES_texture_float_linear"),
            disjoint_timer_query: !desktop && has("GL_EXT_disjoint_timer_query"),
            egl_image_external_essl3: !desktop && has("GL_OES_EGL_image_external_essl3"),
            egl_image_external: !desktop && has("GL_OES_EGL_image_external"),
            max_texture_size,
        }
    }

    /// Checks that the context is GLES 3 or a desktop GL that compiles GLSL ES 3.00
    /// (module docs), which every pass is written in.
    pub fn require_es3_shaders(&self) -> Result<()> {
        if self.es3_shaders {
            return Ok(());
        }
        if self.desktop {
            return Err(self.missing(
                "GL_ARB_ES3_compatibility",
                &format!(
                    "the context is desktop {}; brume's shaders are GLSL ES 3.00, which a \
                     desktop context compiles from OpenGL 4.3 or with \
                     GL_ARB_ES3_compatibility: make a GLES 3 context (EGL_OPENGL_ES_API) or \
                     a 4.3 core one",
                    self.version
                ),
            ));
        }
        Err(Error::MissingCapability {
            capability: "OpenGL ES 3.0".into(),
            renderer: self.renderer.clone(),
            hint: format!("the context is {}; brume needs GLES 3.x", self.version),
        })
    }

    /// Checks that textures of `precision` can be rendered to and filtered, so that a
    /// missing extension is reported here and not as a GL error later.
    pub fn require_precision(&self, precision: Precision) -> Result<()> {
        self.require_renderable(precision)?;
        if precision == Precision::F32 && !self.texture_float_linear {
            return Err(self.missing(
                "GL_OES_texture_float_linear",
                "RGBA32F cannot be sampled bilinearly (common on Mali); use precision f16",
            ));
        }
        Ok(())
    }

    /// Checks that textures of `precision` can be rendered to (and read back), for
    /// targets that are never filtered: the engine passes' (many Mali GPUs render RGBA32F
    /// but do not filter it).
    pub fn require_renderable(&self, precision: Precision) -> Result<()> {
        match precision {
            Precision::F32 => {
                if !self.color_buffer_float {
                    return Err(self.missing(
                        "GL_EXT_color_buffer_float",
                        "RGBA32F cannot be rendered to; use precision f16",
                    ));
                }
            }
            Precision::F16 => {
                if !(self.color_buffer_half_float || self.color_buffer_float) {
                    return Err(self.missing(
                        "GL_EXT_color_buffer_half_float",
                        "RGBA16F cannot be rendered to on this driver; no float precision is available",
                    ));
                }
            }
        }
        Ok(())
    }

    /// Checks that external images (`GL_TEXTURE_EXTERNAL_OES`) can be sampled by brume's
    /// GLSL ES 3 shaders: [`crate::Pipeline::import_external`] needs it.
    pub fn require_external_images(&self) -> Result<()> {
        if self.egl_image_external_essl3 {
            return Ok(());
        }
        let found = if self.egl_image_external {
            "the driver has GL_OES_EGL_image_external, which lets only GLSL ES 1.00 \
             shaders sample external images, and brume's shaders are GLSL ES 3"
        } else {
            "the driver cannot sample GL_TEXTURE_EXTERNAL_OES images at all"
        };
        Err(self.missing(
            "GL_OES_EGL_image_external_essl3",
            &format!(
                "{found}; upload the frame as a GL_TEXTURE_2D instead (glTexSubImage2D from \
                 the frame's CPU buffer, or its EGLImage bound to GL_TEXTURE_2D where the \
                 driver allows that) and give that texture to Pipeline::render as \
                 Input::colour"
            ),
        ))
    }

    /// Whether the renderer runs on the CPU (llvmpipe, softpipe, SwiftShader): its
    /// textures then live in system memory, which [`crate::memory`] can measure.
    pub fn software(&self) -> bool {
        let r = self.renderer.to_ascii_lowercase();
        ["llvmpipe", "softpipe", "swiftshader", "swrast"]
            .iter()
            .any(|name| r.contains(name))
    }

    /// Checks a `width x height` image against `GL_MAX_TEXTURE_SIZE`.
    pub fn require_size(&self, what: &str, width: usize, height: usize) -> Result<()> {
        let max = self.max_texture_size as usize;
        if width == 0 || height == 0 {
            return Err(Error::invalid(
                what,
                format!("{width}x{height}"),
                "a non-empty image",
            ));
        }
        if width > max || height > max {
            return Err(Error::TooLarge {
                what: what.to_string(),
                width: width as u32,
                height: height as u32,
                max: self.max_texture_size,
                renderer: self.renderer.clone(),
            });
        }
        Ok(())
    }

    fn missing(&self, capability: &str, hint: &str) -> Error {
        Error::MissingCapability {
            capability: capability.to_string(),
            renderer: self.renderer.clone(),
            hint: hint.to_string(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// llvmpipe's capabilities with the external-image extensions as given.
    fn caps(essl3: bool, essl1: bool) -> Capabilities {
        Capabilities {
            egl: None,
            vendor: "Mesa".into(),
            renderer: "llvmpipe".into(),
            version: "OpenGL ES 3.2 Mesa".into(),
            shading_language_version: "OpenGL ES GLSL ES 3.20".into(),
            gles_version: (3, 2),
            desktop: false,
            es3_shaders: true,
            color_buffer_float: true,
            color_buffer_half_float: true,
            texture_float_linear: true,
            disjoint_timer_query: true,
            egl_image_external_essl3: essl3,
            egl_image_external: essl1,
            max_texture_size: 16384,
        }
    }

    #[test]
    fn missing_external_images_are_a_typed_error_that_says_what_to_do() {
        assert!(caps(true, true).require_external_images().is_ok());
        for essl1 in [false, true] {
            let error = caps(false, essl1).require_external_images().unwrap_err();
            let Error::MissingCapability { capability, .. } = &error else {
                panic!("not a missing capability: {error:?}");
            };
            assert_eq!(capability, "GL_OES_EGL_image_external_essl3");
            let text = error.to_string();
            assert!(text.contains("llvmpipe"), "{text}");
            assert!(text.contains("GL_TEXTURE_2D"), "{text}");
            assert!(text.contains("Input::colour"), "{text}");
            assert_eq!(text.contains("GLSL ES 1.00"), essl1, "{text}");
        }
    }
}
