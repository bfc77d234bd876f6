//! brume inside a host's renderer: the host opens its own EGL context (with `khronos-egl`,
//! not brume's), owns its textures and framebuffer, and asks brume to fog one frame into
//! its framebuffer. Then it reads the frame back, compares it with brume's f64 CPU
//! reference, and checks that its own objects are still there and unchanged.
//!
//! Then the host acts as an engine (papers 001 and 003): it draws a 3D frame on its
//! context (with brume's procedural scene as its renderer: a colour texture, a depth
//! texture and a camera), copies the colour into its framebuffer and has brume blend
//! paper 003's layered fog over it from the depth buffer alone; and fogs the same frame
//! with paper 001's distance fog and 5 x 5 blur into a texture. Both are checked against
//! the CPU reference.
//!
//! ```sh
//! cargo run --example host_context
//! ```
//!
//! Exits 0 and prints the largest difference when it is within the tolerance (4e-7 per
//! pass in f32, as `tests/gpu_vs_cpu.rs` explains), 1 otherwise.

use brume::medium::haze::normalise_range;
use brume::raster::{Grid, RgbImage, ScalarMap};
use brume::{reference, Blur, Encoding, Haze, Input, Output, Pipeline};
use glow::HasContext;
use khronos_egl as egl;
use std::process::ExitCode;
use std::sync::Arc;

const WIDTH: usize = 96;
const HEIGHT: usize = 64;
const PLATFORM_SURFACELESS_MESA: egl::Enum = 0x31DD;

fn main() -> ExitCode {
    match run() {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("host_context: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<bool, String> {
    // --- The host: its own context. ---
    let host = HostContext::open()?;
    let gl = Arc::clone(&host.gl);

    // --- The host's frame: a colour texture, a range texture, and its framebuffer. ---
    let image = test_image();
    let (range, _) = normalise_range(&test_range()).map_err(|e| e.to_string())?;
    let rgba: Vec<f32> = image
        .as_slice()
        .iter()
        .flat_map(|p| [p[0], p[1], p[2], 1.0])
        .collect();
    // SAFETY: plain texture and framebuffer creation on the host's current context.
    let (colour, depth, target, fbo) = unsafe {
        let colour = float_texture(&gl, glow::RGBA32F, glow::RGBA, Some(&rgba))?;
        let depth = float_texture(&gl, glow::R32F, glow::RED, Some(range.as_slice()))?;
        let target = float_texture(&gl, glow::RGBA32F, glow::RGBA, None)?;
        let fbo = framebuffer_over(&gl, target)?;
        (colour, depth, target, fbo)
    };

    // --- brume on the host's context: textures in, framebuffer out. ---
    let mut pipeline = Pipeline::new(Arc::clone(&gl)).map_err(|e| e.to_string())?;
    // Timing is off by default (no query, no wait); this host wants the figures now.
    pipeline.set_timing(brume::Timing::Blocking);
    let haze = Haze {
        ka: 0.5,
        ks: 1.5,
        lambda: 4.0,
        ..Haze::default()
    };
    let blur = Blur::default();
    let input = Input {
        colour,
        colour_encoding: Encoding::Linear,
        depth,
        width: WIDTH,
        height: HEIGHT,
        frame: brume::FrameInputs::default(),
    };
    let output = Output::Framebuffer {
        framebuffer: Some(fbo),
        x: 0,
        y: 0,
        encoding: Encoding::Linear,
    };
    let frame = pipeline
        .render(&input, &haze, &blur, &output)
        .map_err(|e| e.to_string())?;
    println!(
        "{} passes on {}: {}",
        frame.schedule.steps + 2,
        pipeline.caps().renderer,
        frame.times.describe(2)
    );

    // --- The host reads its framebuffer and checks brume against the CPU reference. ---
    // SAFETY: reading the host's framebuffer into a buffer of the right size.
    let fogged = unsafe { read_rgba(&gl, fbo) }?;
    let expected = reference::render(&image, &range, &haze, &blur).map_err(|e| e.to_string())?;
    let error = reference::rgb_error(&fogged, &expected, 0);
    let tolerance = 4e-7 * f64::from(frame.schedule.steps + 2);
    println!(
        "largest difference from the f64 reference: {:.3e} (rms {:.3e}, tolerance {tolerance:.1e})",
        error.max_abs, error.rms
    );

    // --- The host's objects are still its own: alive, and the input unchanged. ---
    // SAFETY: queries and a read-back of the host's own texture on its context.
    let (alive, colour_after) = unsafe {
        let alive = [colour, depth, target].iter().all(|&t| gl.is_texture(t));
        let probe = framebuffer_over(&gl, colour)?;
        let pixels = read_rgba(&gl, probe)?;
        gl.delete_framebuffer(probe);
        (alive, pixels)
    };
    let untouched = colour_after
        .as_slice()
        .iter()
        .zip(rgba.chunks_exact(4))
        .all(|(a, b)| a[..] == b[..]);
    println!("host textures alive: {alive}; colour texture unchanged: {untouched}");

    drop(pipeline); // brume's objects go; the host's stay
                    // SAFETY: the host deletes its own objects.
    unsafe {
        gl.delete_framebuffer(fbo);
        for t in [colour, depth, target] {
            gl.delete_texture(t);
        }
    }
    let engine_ok = engine_frame(&gl)?;
    Ok(error.max_abs <= tolerance && alive && untouched && engine_ok)
}

/// The host as an engine: a rendered frame fogged from its depth buffer and camera.
fn engine_frame(gl: &Arc<glow::Context>) -> Result<bool, String> {
    use brume::camera::{Camera, FrameInputs};
    use brume::medium::{DistanceFog, LayeredFog};
    use brume::scene::SceneRenderer;
    use brume::{FogBlur, GaussBlur};
    let err = |e: brume::Error| e.to_string();
    let camera = Camera {
        pitch_deg: -4.0,
        ..Camera::default()
    };
    let mut scene = SceneRenderer::new(Arc::clone(gl)).map_err(err)?;
    let frame = scene.render(&camera, WIDTH, HEIGHT, 0.0).map_err(err)?;
    // The CPU reference takes buffers top row first; GL's rows are bottom first.
    let mut colour = frame.read_colour().map_err(err)?;
    let mut depth = frame.read_depth().map_err(err)?;
    colour.flip_rows();
    depth.flip_rows();
    let mut pipeline = Pipeline::new(Arc::clone(gl)).map_err(err)?;

    // Paper 003: the frame is in the host's framebuffer; brume draws one blended pass.
    // SAFETY: the host's own texture, framebuffer and a blit of the scene's colour into it.
    let (target, fbo) = unsafe {
        let target = float_texture(gl, glow::RGBA32F, glow::RGBA, None)?;
        let fbo = framebuffer_over(gl, target)?;
        let read = framebuffer_over(gl, frame.colour)?;
        gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(fbo));
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(read));
        let (w, h) = (WIDTH as i32, HEIGHT as i32);
        gl.blit_framebuffer(
            0,
            0,
            w,
            h,
            0,
            0,
            w,
            h,
            glow::COLOR_BUFFER_BIT,
            glow::NEAREST,
        );
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        gl.delete_framebuffer(read);
        (target, fbo)
    };
    // One medium value fogs any number of frames: the camera (and the time) come with
    // each frame.
    let layered = LayeredFog::for_camera(camera, Default::default());
    let at = FrameInputs::new(camera, 0.0);
    let output = Output::Framebuffer {
        framebuffer: Some(fbo),
        x: 0,
        y: 0,
        encoding: Encoding::Linear,
    };
    pipeline
        .blend_fog(frame.depth, WIDTH, HEIGHT, &layered, &at, &output)
        .map_err(err)?;
    // SAFETY: reading the host's framebuffer.
    let mut blended = unsafe { read_rgba(gl, fbo) }?;
    blended.flip_rows();
    let expected = reference::fog(&colour, &depth, &layered, &at, &FogBlur::None).map_err(err)?;
    let blend_error = reference::rgb_error(&blended, &expected, 0).max_abs;

    // Paper 001: distance fog and the 5 x 5 blur of the fog-free frame, one pass.
    let distance = DistanceFog {
        noise: None,
        ..DistanceFog::default()
    };
    let blur = FogBlur::GaussSingle(GaussBlur::default());
    let input = Input {
        colour: frame.colour,
        colour_encoding: Encoding::Linear,
        depth: frame.depth,
        width: WIDTH,
        height: HEIGHT,
        frame: at,
    };
    let (_, fogged) = pipeline
        .fog_to_image(&input, &distance, &blur)
        .map_err(err)?;
    let expected = reference::fog(&colour, &depth, &distance, &at, &blur).map_err(err)?;
    let fog_error = reference::rgb_error(&fogged, &expected, 0).max_abs;

    // Tolerance as tests/engine_fog.rs: f32 distance from the depth buffer near the far
    // plane, a few ulps of the pass, on colours up to about 1.
    let tolerance = 2e-5;
    println!(
        "engine frame: layered fog blended over the host's frame, largest difference \
         {blend_error:.3e}; distance fog + 5x5 blur {fog_error:.3e} (tolerance {tolerance:.0e})"
    );
    drop(pipeline);
    drop(scene);
    // SAFETY: the host deletes its own objects.
    unsafe {
        gl.delete_framebuffer(fbo);
        gl.delete_texture(target);
    }
    Ok(blend_error <= tolerance && fog_error <= tolerance)
}

/// A colour test card: smooth ramps with sharp bars, in linear light.
fn test_image() -> RgbImage {
    Grid::from_fn(WIDTH, HEIGHT, |x, y| {
        let bar = if (x / 8) % 2 == 0 { 0.9 } else { 0.1 };
        [bar, y as f32 / HEIGHT as f32, 1.0 - x as f32 / WIDTH as f32]
    })
}

/// A range map: a floor receding to the top, a near post in the middle.
fn test_range() -> ScalarMap {
    Grid::from_fn(WIDTH, HEIGHT, |x, y| {
        if (40..56).contains(&x) {
            2.0
        } else {
            2.0 + 30.0 * y as f32 / HEIGHT as f32
        }
    })
}

/// The host's headless EGL context, opened with `khronos-egl` alone.
struct HostContext {
    gl: Arc<glow::Context>,
    egl: egl::DynamicInstance<egl::EGL1_5>,
    display: egl::Display,
    context: egl::Context,
}

impl HostContext {
    fn open() -> Result<Self, String> {
        // SAFETY: loading the system's libEGL.
        let egl = unsafe { egl::DynamicInstance::<egl::EGL1_5>::load_required() }
            .map_err(|e| format!("cannot load libEGL.so.1 ({e}); run tools/setup.sh"))?;
        // SAFETY: Mesa's surfaceless platform takes a null native display.
        let display = unsafe {
            egl.get_platform_display(
                PLATFORM_SURFACELESS_MESA,
                std::ptr::null_mut(),
                &[egl::ATTRIB_NONE],
            )
        }
        .map_err(|e| format!("no surfaceless EGL display: {e}"))?;
        egl.initialize(display).map_err(|e| e.to_string())?;
        egl.bind_api(egl::OPENGL_ES_API)
            .map_err(|e| e.to_string())?;
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
            .map_err(|e| e.to_string())?
            .ok_or("no GLES 3 EGL config")?;
        let context = egl
            .create_context(
                display,
                config,
                None,
                &[egl::CONTEXT_MAJOR_VERSION, 3, egl::NONE],
            )
            .map_err(|e| e.to_string())?;
        egl.make_current(display, None, None, Some(context))
            .map_err(|e| e.to_string())?;
        // SAFETY: the context is current; the pointers come from this libEGL.
        let gl = unsafe {
            glow::Context::from_loader_function(|name| {
                egl.get_proc_address(name)
                    .map_or(std::ptr::null(), |f| f as *const std::ffi::c_void)
            })
        };
        Ok(HostContext {
            gl: Arc::new(gl),
            egl,
            display,
            context,
        })
    }
}

impl Drop for HostContext {
    fn drop(&mut self) {
        let _ = self.egl.make_current(self.display, None, None, None);
        let _ = self.egl.destroy_context(self.display, self.context);
    }
}

/// A `WIDTH x HEIGHT` float texture with nearest filtering, filled from `data` if given.
unsafe fn float_texture(
    gl: &glow::Context,
    internal: u32,
    format: u32,
    data: Option<&[f32]>,
) -> Result<glow::Texture, String> {
    let t = gl.create_texture()?;
    gl.bind_texture(glow::TEXTURE_2D, Some(t));
    gl.tex_parameter_i32(
        glow::TEXTURE_2D,
        glow::TEXTURE_MIN_FILTER,
        glow::NEAREST as i32,
    );
    gl.tex_parameter_i32(
        glow::TEXTURE_2D,
        glow::TEXTURE_MAG_FILTER,
        glow::NEAREST as i32,
    );
    gl.tex_storage_2d(glow::TEXTURE_2D, 1, internal, WIDTH as i32, HEIGHT as i32);
    if let Some(data) = data {
        let bytes = std::slice::from_raw_parts(data.as_ptr().cast::<u8>(), data.len() * 4);
        gl.tex_sub_image_2d(
            glow::TEXTURE_2D,
            0,
            0,
            0,
            WIDTH as i32,
            HEIGHT as i32,
            format,
            glow::FLOAT,
            glow::PixelUnpackData::Slice(Some(bytes)),
        );
    }
    gl.bind_texture(glow::TEXTURE_2D, None);
    Ok(t)
}

/// A framebuffer with `texture` as its colour attachment 0 (left unbound).
unsafe fn framebuffer_over(
    gl: &glow::Context,
    texture: glow::Texture,
) -> Result<glow::Framebuffer, String> {
    let fbo = gl.create_framebuffer()?;
    gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
    gl.framebuffer_texture_2d(
        glow::FRAMEBUFFER,
        glow::COLOR_ATTACHMENT0,
        glow::TEXTURE_2D,
        Some(texture),
        0,
    );
    gl.bind_framebuffer(glow::FRAMEBUFFER, None);
    Ok(fbo)
}

/// Reads attachment 0 of `fbo` as RGBA f32.
unsafe fn read_rgba(gl: &glow::Context, fbo: glow::Framebuffer) -> Result<Grid<[f32; 4]>, String> {
    let mut out = vec![[0f32; 4]; WIDTH * HEIGHT];
    let bytes = std::slice::from_raw_parts_mut(out.as_mut_ptr().cast::<u8>(), out.len() * 16);
    gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(fbo));
    gl.read_pixels(
        0,
        0,
        WIDTH as i32,
        HEIGHT as i32,
        glow::RGBA,
        glow::FLOAT,
        glow::PixelPackData::Slice(Some(bytes)),
    );
    gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
    match gl.get_error() {
        glow::NO_ERROR => Ok(Grid::from_vec(WIDTH, HEIGHT, out)),
        code => Err(format!("glReadPixels failed: 0x{code:04X}")),
    }
}
