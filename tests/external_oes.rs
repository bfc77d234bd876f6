//! External (OES) colour images: a host binds an EGLImage to `GL_TEXTURE_EXTERNAL_OES`, as
//! a camera app does with a `SurfaceTexture` or an `AHardwareBuffer`, and brume imports
//! it with `Pipeline::import_external`. On Mesa the EGLImage is made from an ordinary
//! `GL_TEXTURE_2D` (`EGL_KHR_gl_texture_2D_image`) holding a known sRGB pattern, so the
//! copy can be checked texel for texel and a render from it compared with a render from
//! the plain texture.
//!
//! The host opens its own context with khronos-egl (brume's `GlContext` does not expose
//! its display, which `eglCreateImage` needs). A missing extension fails the test, never
//! skips it (brume's rule: a missing capability is a failure); Mesa's llvmpipe through EGL
//! surfaceless has every one of them.
use crate::common;

use brume::pipeline::{ExternalColour, IDENTITY, TEXTURE_BINDING_EXTERNAL_OES};
use brume::{Blur, Encoding, Error, Haze, Input, Output, Pipeline};
use glow::HasContext;
use khronos_egl as egl;
use std::ffi::c_void;
use std::sync::Arc;

/// Odd sizes, so that a half-texel or a row-length mistake shows.
const W: usize = 37;
const H: usize = 23;

const PLATFORM_SURFACELESS_MESA: egl::Enum = 0x31DD;
/// `EGL_GL_TEXTURE_2D` (EGL 1.5, `EGL_KHR_gl_texture_2D_image`).
const EGL_GL_TEXTURE_2D: egl::Enum = 0x30B1;
/// `EGL_GL_TEXTURE_LEVEL`.
const EGL_GL_TEXTURE_LEVEL: egl::Attrib = 0x30BC;

/// Android's usual camera transform: t' = 1 − t (column-major).
const FLIP_T: [f32; 16] = [
    1.0, 0.0, 0.0, 0.0, //
    0.0, -1.0, 0.0, 0.0, //
    0.0, 0.0, 1.0, 0.0, //
    0.0, 1.0, 0.0, 1.0,
];

/// `glEGLImageTargetTexture2DOES`, which glow does not wrap.
type ImageTargetTexture2D = unsafe extern "system" fn(target: u32, image: *const c_void);

/// The sRGB-encoded pattern: every code value of red, gradients in green, a product in
/// blue and a varying alpha, at texel (x, y) (row 0 first, as GL stores it).
fn pattern(x: usize, y: usize) -> [u8; 4] {
    [
        ((x + W * y) % 256) as u8,
        ((5 * x + 13 * y) % 256) as u8,
        (255 - (x * y) % 256) as u8,
        (128 + (3 * x + y) % 128) as u8,
    ]
}

fn pattern_bytes() -> Vec<u8> {
    (0..H)
        .flat_map(|y| (0..W).flat_map(move |x| pattern(x, y)))
        .collect()
}

/// A host with its own surfaceless context and EGL 1.5 (for `eglCreateImage`).
struct Host {
    gl: Arc<glow::Context>,
    egl: egl::DynamicInstance<egl::EGL1_5>,
    display: egl::Display,
    context: egl::Context,
}

impl Host {
    fn open() -> Host {
        // SAFETY: loading the system's libEGL.
        let egl =
            unsafe { egl::DynamicInstance::<egl::EGL1_5>::load_required() }.unwrap_or_else(|e| {
                panic!("cannot load libEGL with EGL 1.5 ({e}); run tools/setup.sh")
            });
        // SAFETY: Mesa's surfaceless platform takes a null native display.
        let display = unsafe {
            egl.get_platform_display(
                PLATFORM_SURFACELESS_MESA,
                std::ptr::null_mut(),
                &[egl::ATTRIB_NONE],
            )
        }
        .expect("a surfaceless EGL display");
        egl.initialize(display).expect("eglInitialize");
        egl.bind_api(egl::OPENGL_ES_API).expect("eglBindAPI");
        let config = egl
            .choose_first_config(
                display,
                &[
                    egl::RENDERABLE_TYPE,
                    egl::OPENGL_ES3_BIT,
                    egl::SURFACE_TYPE,
                    egl::PBUFFER_BIT,
                    egl::NONE,
                ],
            )
            .expect("eglChooseConfig")
            .expect("a GLES 3 config");
        let context = egl
            .create_context(
                display,
                config,
                None,
                &[
                    egl::CONTEXT_MAJOR_VERSION,
                    3,
                    egl::CONTEXT_MINOR_VERSION,
                    2,
                    egl::NONE,
                ],
            )
            .expect("a GLES 3.2 context");
        egl.make_current(display, None, None, Some(context))
            .expect("eglMakeCurrent");
        // SAFETY: the context is current; the pointers come from this libEGL.
        let gl = unsafe {
            glow::Context::from_loader_function(|name| {
                egl.get_proc_address(name)
                    .map_or(std::ptr::null(), |f| f as *const c_void)
            })
        };
        Host {
            gl: Arc::new(gl),
            egl,
            display,
            context,
        }
    }

    fn egl_has(&self, name: &str) -> bool {
        self.egl
            .query_string(Some(self.display), egl::EXTENSIONS)
            .map(|s| s.to_string_lossy().split_whitespace().any(|e| e == name))
            .unwrap_or(false)
    }

    fn gl_has(&self, name: &str) -> bool {
        self.gl.supported_extensions().contains(name)
    }

    /// Fails the test, naming what is missing, unless the driver has every extension
    /// these tests need; prints what it found.
    fn require_external_images(&self) {
        let found = [
            (
                "GL_OES_EGL_image_external_essl3",
                self.gl_has("GL_OES_EGL_image_external_essl3"),
            ),
            (
                "GL_OES_EGL_image_external",
                self.gl_has("GL_OES_EGL_image_external"),
            ),
            ("GL_OES_EGL_image", self.gl_has("GL_OES_EGL_image")),
            ("EGL_KHR_image_base", self.egl_has("EGL_KHR_image_base")),
            (
                "EGL_KHR_gl_texture_2D_image",
                self.egl_has("EGL_KHR_gl_texture_2D_image"),
            ),
        ];
        eprintln!("external-image extensions on this driver: {found:?}");
        let needed = [
            "GL_OES_EGL_image_external_essl3",
            "GL_OES_EGL_image",
            "EGL_KHR_gl_texture_2D_image",
        ];
        let missing: Vec<&str> = found
            .iter()
            .filter(|(name, present)| needed.contains(name) && !present)
            .map(|(name, _)| *name)
            .collect();
        assert!(
            missing.is_empty(),
            "the driver ({}) lacks {}: external images cannot be tested (a missing \
             capability is a failure, not a skip; Mesa's llvmpipe through EGL surfaceless has \
             them: run tools/setup.sh)",
            self.gl_renderer(),
            missing.join(", ")
        );
    }

    fn gl_renderer(&self) -> String {
        // SAFETY: a string query on the host's context, current since `open`.
        unsafe { self.gl.get_parameter_string(glow::RENDERER) }
    }
}

impl Drop for Host {
    fn drop(&mut self) {
        let _ = self.egl.make_current(self.display, None, None, None);
        let _ = self.egl.destroy_context(self.display, self.context);
    }
}

/// An RGBA8 `GL_TEXTURE_2D` holding the pattern, an EGLImage of it, and that image bound
/// to a texture on `GL_TEXTURE_EXTERNAL_OES`: what a camera app holds each frame.
struct ExternalFrame {
    source: glow::Texture,
    image: egl::Image,
    external: glow::Texture,
}

impl ExternalFrame {
    fn new(host: &Host) -> ExternalFrame {
        let gl = &host.gl;
        let source = pattern_texture(gl, glow::RGBA8);
        // SAFETY: the buffer of an EGL_GL_TEXTURE_2D image is the texture's name.
        let buffer = unsafe { egl::ClientBuffer::from_ptr(source.0.get() as usize as *mut c_void) };
        let image = host
            .egl
            .create_image(
                host.display,
                host.context,
                EGL_GL_TEXTURE_2D,
                buffer,
                &[EGL_GL_TEXTURE_LEVEL, 0, egl::ATTRIB_NONE],
            )
            .unwrap_or_else(|e| panic!("eglCreateImage(EGL_GL_TEXTURE_2D): {e}"));
        let target_texture = host
            .egl
            .get_proc_address("glEGLImageTargetTexture2DOES")
            .expect("glEGLImageTargetTexture2DOES");
        // SAFETY: the entry point's signature from OES_EGL_image; the image is live and
        // the external texture is bound to its target on the current context.
        let external = unsafe {
            let bind: ImageTargetTexture2D = std::mem::transmute(target_texture);
            let t = gl.create_texture().expect("a texture");
            gl.bind_texture(brume::pipeline::TEXTURE_EXTERNAL_OES, Some(t));
            bind(brume::pipeline::TEXTURE_EXTERNAL_OES, image.as_ptr());
            gl.bind_texture(brume::pipeline::TEXTURE_EXTERNAL_OES, None);
            assert_eq!(
                gl.get_error(),
                glow::NO_ERROR,
                "glEGLImageTargetTexture2DOES"
            );
            t
        };
        ExternalFrame {
            source,
            image,
            external,
        }
    }

    fn colour(&self, transform: [f32; 16]) -> ExternalColour {
        ExternalColour {
            texture: self.external,
            width: W,
            height: H,
            transform,
        }
    }

    fn delete(self, host: &Host) {
        // SAFETY: the host's own objects on its current context.
        unsafe {
            host.gl.delete_texture(self.external);
            host.gl.delete_texture(self.source);
        }
        host.egl
            .destroy_image(host.display, self.image)
            .expect("eglDestroyImage");
    }
}

/// Reads a `W x H` texture of the host's context (row 0 first) through a framebuffer.
/// 8-bit formats come back as their stored bytes (sRGB-encoded for `SRGB8_ALPHA8`).
fn read_texture<T: Copy + Default>(
    gl: &glow::Context,
    texture: glow::Texture,
    data_type: u32,
) -> Vec<T> {
    let mut out = vec![T::default(); W * H * 4];
    // SAFETY: `out` holds W * H RGBA values of the type read.
    unsafe {
        let fbo = gl.create_framebuffer().expect("a framebuffer");
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
        gl.framebuffer_texture_2d(
            glow::FRAMEBUFFER,
            glow::COLOR_ATTACHMENT0,
            glow::TEXTURE_2D,
            Some(texture),
            0,
        );
        gl.pixel_store_i32(glow::PACK_ALIGNMENT, 1);
        let bytes = std::slice::from_raw_parts_mut(
            out.as_mut_ptr().cast::<u8>(),
            std::mem::size_of_val(out.as_slice()),
        );
        gl.read_pixels(
            0,
            0,
            W as i32,
            H as i32,
            glow::RGBA,
            data_type,
            glow::PixelPackData::Slice(Some(bytes)),
        );
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        gl.delete_framebuffer(fbo);
        assert_eq!(gl.get_error(), glow::NO_ERROR, "reading a texture back");
    }
    out
}

/// The largest difference, in 8-bit code values, between the copy and the pattern with
/// its rows mapped by `row` (copy row → pattern row).
fn code_value_error(copy: &[u8], row: impl Fn(usize) -> usize) -> u8 {
    let mut worst = 0;
    for y in 0..H {
        for x in 0..W {
            let want = pattern(x, row(y));
            let got = &copy[4 * (y * W + x)..][..4];
            for c in 0..4 {
                worst = worst.max(want[c].abs_diff(got[c]));
            }
        }
    }
    worst
}

/// What one render gave: RGBA f32 (row 0 first) and its diffusion steps.
struct Rendered {
    pixels: Vec<f32>,
    steps: u32,
}

/// The haze of the render tests: absorption and scattering, blurred.
fn haze() -> Haze {
    Haze {
        ka: 0.5,
        ks: 1.5,
        lambda: 4.0,
        ..Haze::default()
    }
}

/// No medium: τ = 1, so a render writes the decoded colour.
fn clear() -> Haze {
    Haze {
        ka: 0.0,
        ks: 0.0,
        lambda: 0.0,
        ..Haze::default()
    }
}

/// Renders `colour` over `depth` through `medium` into a new RGBA32F texture, read back.
fn render(
    pipeline: &mut Pipeline,
    gl: &glow::Context,
    (colour, colour_encoding): (glow::Texture, Encoding),
    depth: glow::Texture,
    medium: &Haze,
) -> Rendered {
    // SAFETY: a host texture for the output on the current context.
    let target = unsafe {
        let t = gl.create_texture().expect("a texture");
        gl.bind_texture(glow::TEXTURE_2D, Some(t));
        gl.tex_storage_2d(glow::TEXTURE_2D, 1, glow::RGBA32F, W as i32, H as i32);
        gl.bind_texture(glow::TEXTURE_2D, None);
        t
    };
    let input = Input {
        colour,
        colour_encoding,
        depth,
        width: W,
        height: H,
        frame: brume::FrameInputs::default(),
    };
    let output = Output::Texture {
        texture: target,
        encoding: Encoding::Linear,
    };
    let frame = pipeline
        .render(&input, medium, &Blur::default(), &output)
        .expect("a render");
    let pixels = read_texture::<f32>(gl, target, glow::FLOAT);
    // SAFETY: the host's own texture.
    unsafe { gl.delete_texture(target) };
    Rendered {
        pixels,
        steps: frame.schedule.steps,
    }
}

/// The largest RGB difference of two renders.
fn rgb_difference(a: &Rendered, b: &Rendered) -> f32 {
    a.pixels
        .chunks_exact(4)
        .zip(b.pixels.chunks_exact(4))
        .flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).abs()))
        .fold(0.0, f32::max)
}

/// The exact sRGB decode of an 8-bit code value.
fn decode(code: u8) -> f64 {
    let c = f64::from(code) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// How far a render with no medium is from the exact decode of the pattern: the largest
/// absolute error, and the largest error as a fraction of the step to the nearer
/// neighbouring code value.
fn decode_error(clear: &Rendered) -> (f64, f64) {
    let (mut absolute, mut steps) = (0f64, 0f64);
    for y in 0..H {
        for x in 0..W {
            let want = pattern(x, y);
            for (c, &code) in want.iter().take(3).enumerate() {
                let error = (f64::from(clear.pixels[4 * (y * W + x) + c]) - decode(code)).abs();
                let below = code.checked_sub(1).map(|n| decode(code) - decode(n));
                let above = code.checked_add(1).map(|n| decode(n) - decode(code));
                let step = below.into_iter().chain(above).fold(f64::INFINITY, f64::min);
                absolute = absolute.max(error);
                steps = steps.max(error / step);
            }
        }
    }
    (absolute, steps)
}

/// The pattern in a 2D texture of 8-bit RGBA `format`: `RGBA8` for the external image's
/// source, or `SRGB8_ALPHA8`, which GL decodes as it does the copy.
fn pattern_texture(gl: &glow::Context, format: u32) -> glow::Texture {
    // SAFETY: texture creation and upload of W * H * 4 bytes on the current context.
    unsafe {
        let t = gl.create_texture().expect("a texture");
        gl.bind_texture(glow::TEXTURE_2D, Some(t));
        for (param, value) in [
            (glow::TEXTURE_MIN_FILTER, glow::NEAREST),
            (glow::TEXTURE_MAG_FILTER, glow::NEAREST),
        ] {
            gl.tex_parameter_i32(glow::TEXTURE_2D, param, value as i32);
        }
        gl.tex_storage_2d(glow::TEXTURE_2D, 1, format, W as i32, H as i32);
        gl.pixel_store_i32(glow::UNPACK_ALIGNMENT, 1);
        gl.tex_sub_image_2d(
            glow::TEXTURE_2D,
            0,
            0,
            0,
            W as i32,
            H as i32,
            glow::RGBA,
            glow::UNSIGNED_BYTE,
            glow::PixelUnpackData::Slice(Some(&pattern_bytes())),
        );
        gl.bind_texture(glow::TEXTURE_2D, None);
        t
    }
}

/// The ramp range of the other tests as an R32F texture.
fn range_texture(gl: &glow::Context) -> glow::Texture {
    let range = common::ramp_range(W, H);
    // SAFETY: texture creation and upload of W * H f32 values on the current context.
    unsafe {
        let t = gl.create_texture().expect("a texture");
        gl.bind_texture(glow::TEXTURE_2D, Some(t));
        gl.tex_storage_2d(glow::TEXTURE_2D, 1, glow::R32F, W as i32, H as i32);
        let values = range.as_slice();
        let bytes = std::slice::from_raw_parts(values.as_ptr().cast::<u8>(), values.len() * 4);
        gl.tex_sub_image_2d(
            glow::TEXTURE_2D,
            0,
            0,
            0,
            W as i32,
            H as i32,
            glow::RED,
            glow::FLOAT,
            glow::PixelUnpackData::Slice(Some(bytes)),
        );
        gl.bind_texture(glow::TEXTURE_2D, None);
        t
    }
}

/// The GL state an import leaves (module docs of `brume::pipeline`): the host's, as it
/// was before (this host sets none: GL's defaults).
fn assert_state_left(gl: &glow::Context) {
    // SAFETY: state queries on the current context.
    unsafe {
        assert_eq!(gl.get_parameter_i32(glow::FRAMEBUFFER_BINDING), 0);
        assert_eq!(gl.get_parameter_i32(glow::CURRENT_PROGRAM), 0);
        assert_eq!(gl.get_parameter_i32(glow::VERTEX_ARRAY_BINDING), 0);
        assert_eq!(
            gl.get_parameter_i32(glow::ACTIVE_TEXTURE),
            glow::TEXTURE0 as i32
        );
        assert_eq!(gl.get_parameter_i32(TEXTURE_BINDING_EXTERNAL_OES), 0);
        assert_eq!(gl.get_parameter_i32(glow::TEXTURE_BINDING_2D), 0);
        let mut viewport = [0; 4];
        gl.get_parameter_i32_slice(glow::VIEWPORT, &mut viewport);
        // A surfaceless context starts with an empty viewport; brume puts it back.
        assert_eq!(viewport, [0, 0, 0, 0]);
        assert_eq!(gl.get_error(), glow::NO_ERROR);
    }
}

#[test]
fn an_external_image_is_imported_texel_for_texel_and_renders_like_the_plain_texture() {
    let _lock = common::gl_lock();
    let host = Host::open();
    host.require_external_images();
    let gl = Arc::clone(&host.gl);
    let frame = ExternalFrame::new(&host);
    let depth = range_texture(&gl);
    let mut pipeline = Pipeline::new(Arc::clone(&gl)).expect("a pipeline");
    assert!(pipeline.supports_external());
    assert!(pipeline.caps().egl_image_external_essl3);

    // Identity: the copy holds the pattern, re-encoded by GL from the decoded values. A
    // decode (f32) then an 8-bit sRGB encode returns the code value it started from; one
    // code value of slack allows a driver whose encoder rounds differently (GLES leaves
    // the sRGB conversions' precision to the implementation).
    let copy = pipeline
        .import_external(&frame.colour(IDENTITY))
        .expect("an import");
    assert_state_left(&gl);
    let stored = read_texture::<u8>(&gl, copy, glow::UNSIGNED_BYTE);
    let error = code_value_error(&stored, |y| y);
    eprintln!("identity import: largest difference {error} code values");
    assert!(error <= 1, "identity import differs by {error} code values");

    // Android's vertical flip: row y of the copy is row H − 1 − y of the frame.
    let flipped = pipeline
        .import_external(&frame.colour(FLIP_T))
        .expect("an import");
    assert_eq!(
        flipped, copy,
        "the same copy is reused for a frame of the same size"
    );
    let stored = read_texture::<u8>(&gl, flipped, glow::UNSIGNED_BYTE);
    let error = code_value_error(&stored, |y| H - 1 - y);
    assert!(error <= 1, "flipped import differs by {error} code values");

    // Haze renders from the copy against the same renders from plain 2D textures holding
    // the pattern: an SRGB8_ALPHA8 one (decoded by GL as the copy is: the same bytes, so
    // the same floats) and the RGBA8 source (decoded by the medium pass's shader).
    let copy = pipeline
        .import_external(&frame.colour(IDENTITY))
        .expect("an import");
    let srgb_plain = pattern_texture(&gl, glow::SRGB8_ALPHA8);
    let copied = (copy, Encoding::Linear);
    let plain_srgb8 = (srgb_plain, Encoding::Linear);
    let plain_rgba8 = (frame.source, Encoding::Srgb);
    let from_copy = render(&mut pipeline, &gl, copied, depth, &haze());
    let from_srgb8 = render(&mut pipeline, &gl, plain_srgb8, depth, &haze());
    let from_rgba8 = render(&mut pipeline, &gl, plain_rgba8, depth, &haze());
    let same_decode = rgb_difference(&from_copy, &from_srgb8);
    eprintln!("haze from the copy vs from a plain SRGB8_ALPHA8 texture: {same_decode:.3e}");
    assert!(same_decode <= 1e-6, "renders differ by {same_decode:.3e}");

    // The two decodes, seen through a render with no medium (τ = 1: the output is the
    // decoded colour): the shader's pow within f32 rounding of the exact f64 decode; GL's
    // table or polynomial within half a code step (llvmpipe's polynomial is off by up to
    // 1.2e-3, a third of a step: distinct codes stay distinct).
    let by_gl = render(&mut pipeline, &gl, copied, depth, &clear());
    let by_shader = render(&mut pipeline, &gl, plain_rgba8, depth, &clear());
    let (gl_error, gl_steps) = decode_error(&by_gl);
    let (shader_error, _) = decode_error(&by_shader);
    eprintln!(
        "sRGB decode against f64: GL's (SRGB8_ALPHA8) {gl_error:.3e} ({gl_steps:.2} of a code \
         step), the shader's (RGBA8) {shader_error:.3e}"
    );
    assert!(
        shader_error <= 1e-6,
        "shader decode off by {shader_error:.3e}"
    );
    assert!(
        gl_steps < 0.5,
        "GL's decode is off by {gl_steps:.2} of a code step"
    );

    // The passes are linear in the colour and do not amplify a difference (τ ≤ 1, blur
    // weights sum to 1): the haze renders differ by at most the decodes' difference, plus
    // the f32 budget of gpu_vs_cpu.rs (4e-7 a pass) for each render.
    let decodes = f64::from(rgb_difference(&by_gl, &by_shader));
    let budget = decodes + 2.0 * 4e-7 * f64::from(from_copy.steps + 2);
    let across = f64::from(rgb_difference(&from_copy, &from_rgba8));
    eprintln!(
        "haze from the copy vs from the RGBA8 source: {across:.3e} (the decodes differ by \
         {decodes:.3e}; bound {budget:.3e})"
    );
    assert!(
        across <= budget,
        "renders differ by {across:.3e} > {budget:.3e}"
    );

    // Frames after the first create no GL objects: the copy, its framebuffer and the
    // import program are kept.
    let objects = brume::gpu::live_objects();
    for _ in 0..8 {
        let copy = pipeline
            .import_external(&frame.colour(FLIP_T))
            .expect("an import");
        render(&mut pipeline, &gl, (copy, Encoding::Linear), depth, &haze());
        assert_eq!(
            brume::gpu::live_objects(),
            objects,
            "GL objects created per frame"
        );
    }
    // A frame of another size replaces the copy (one texture and one framebuffer, still).
    let resized = ExternalColour {
        width: 2 * W,
        height: H / 2,
        ..frame.colour(IDENTITY)
    };
    pipeline
        .import_external(&resized)
        .expect("a resampled import");
    assert_eq!(brume::gpu::live_objects(), objects);

    drop(pipeline);
    // SAFETY: the host's own textures.
    unsafe {
        gl.delete_texture(depth);
        gl.delete_texture(srgb_plain);
    }
    frame.delete(&host);
}

#[test]
fn bad_sizes_and_transforms_are_refused_by_name() {
    let _lock = common::gl_lock();
    let host = Host::open();
    host.require_external_images();
    let frame = ExternalFrame::new(&host);
    let mut pipeline = Pipeline::new(Arc::clone(&host.gl)).expect("a pipeline");
    let max = pipeline.caps().max_texture_size as usize;
    let objects = brume::gpu::live_objects();
    let attempt = |pipeline: &mut Pipeline, width, height, transform| {
        let source = ExternalColour {
            width,
            height,
            transform,
            ..frame.colour(IDENTITY)
        };
        pipeline.import_external(&source).unwrap_err()
    };
    for (w, h) in [(0, H), (W, 0)] {
        let e = attempt(&mut pipeline, w, h, IDENTITY);
        assert!(matches!(e, Error::InvalidParameter { .. }), "{e:?}");
        assert!(e.to_string().contains("external image"), "{e}");
    }
    let e = attempt(&mut pipeline, max + 1, H, IDENTITY);
    assert!(matches!(e, Error::TooLarge { .. }), "{e:?}");
    assert!(e.to_string().contains("GL_MAX_TEXTURE_SIZE"), "{e}");
    let mut transform = IDENTITY;
    transform[0] = f32::INFINITY;
    let e = attempt(&mut pipeline, W, H, transform);
    assert!(e.to_string().contains("transform"), "{e}");
    assert_eq!(
        brume::gpu::live_objects(),
        objects,
        "a refused import allocates nothing"
    );
    // A GL_TEXTURE_2D where an external texture belongs: GL refuses the binding, and the
    // import says so instead of copying garbage.
    let not_external = ExternalColour {
        texture: frame.source,
        ..frame.colour(IDENTITY)
    };
    let e = pipeline.import_external(&not_external).unwrap_err();
    assert!(matches!(e, Error::Gl(_)), "{e:?}");
    assert!(e.to_string().contains("importing an external image"), "{e}");
    drop(pipeline);
    frame.delete(&host);
}
