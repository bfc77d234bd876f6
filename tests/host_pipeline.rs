//! The pipeline as a host drives it: the host's own textures in, the host's framebuffer
//! or texture out, the GL state it leaves, the host state it must not trip over, and
//! several headless contexts on one thread.
mod common;

use brume::egl::GlContext;
use brume::raster::{Grid, RgbImage, RgbaImage, ScalarMap};
use brume::{reference, Blur, Encoding, FogBlur, Haze, Input, Output, Pipeline};
use common::*;
use glow::HasContext;
use std::sync::Arc;

/// f32 budget per pass, as in gpu_vs_cpu.rs.
const F32_PER_PASS: f64 = 4e-7;

/// A host: a context of its own (brume's headless one is just a way to get it) and the
/// textures of one frame.
struct Host {
    gl: Arc<glow::Context>,
    image: RgbImage,
    range: ScalarMap,
    colour: glow::Texture,
    depth: glow::Texture,
    _ctx: GlContext,
}

impl Host {
    fn new(w: usize, h: usize) -> Host {
        let ctx = GlContext::new(None).expect("EGL context");
        let gl = Arc::clone(ctx.gl());
        let image = noise_image(w, h, 21);
        let range = ramp_range(w, h);
        let rgba: Vec<f32> = image
            .as_slice()
            .iter()
            .flat_map(|p| [p[0], p[1], p[2], 1.0])
            .collect();
        // SAFETY: texture creation on the current context.
        let (colour, depth) = unsafe {
            (
                texture(&gl, w, h, glow::RGBA32F, Upload::Float(glow::RGBA, &rgba)),
                texture(
                    &gl,
                    w,
                    h,
                    glow::R32F,
                    Upload::Float(glow::RED, range.as_slice()),
                ),
            )
        };
        Host {
            gl,
            image,
            range,
            colour,
            depth,
            _ctx: ctx,
        }
    }

    fn input(&self) -> Input {
        Input {
            colour: self.colour,
            colour_encoding: Encoding::Linear,
            depth: self.depth,
            width: self.image.width(),
            height: self.image.height(),
        }
    }

    fn expected(&self, haze: &Haze, blur: &Blur) -> RgbaImage {
        reference::render(&self.image, &self.range, haze, blur).unwrap()
    }
}

enum Upload<'a> {
    Float(u32, &'a [f32]),
    Bytes(u32, &'a [u8]),
    None,
}

unsafe fn texture(
    gl: &glow::Context,
    w: usize,
    h: usize,
    internal: u32,
    data: Upload,
) -> glow::Texture {
    let t = gl.create_texture().unwrap();
    gl.bind_texture(glow::TEXTURE_2D, Some(t));
    for p in [glow::TEXTURE_MIN_FILTER, glow::TEXTURE_MAG_FILTER] {
        gl.tex_parameter_i32(glow::TEXTURE_2D, p, glow::NEAREST as i32);
    }
    gl.tex_storage_2d(glow::TEXTURE_2D, 1, internal, w as i32, h as i32);
    let (format, kind, bytes): (u32, u32, Option<&[u8]>) = match data {
        Upload::Float(format, d) => (
            format,
            glow::FLOAT,
            Some(std::slice::from_raw_parts(d.as_ptr().cast(), d.len() * 4)),
        ),
        Upload::Bytes(format, d) => (format, glow::UNSIGNED_BYTE, Some(d)),
        Upload::None => (glow::RGBA, glow::FLOAT, None),
    };
    if let Some(bytes) = bytes {
        gl.pixel_store_i32(glow::UNPACK_ALIGNMENT, 1);
        gl.tex_sub_image_2d(
            glow::TEXTURE_2D,
            0,
            0,
            0,
            w as i32,
            h as i32,
            format,
            kind,
            glow::PixelUnpackData::Slice(Some(bytes)),
        );
    }
    gl.bind_texture(glow::TEXTURE_2D, None);
    t
}

unsafe fn framebuffer(gl: &glow::Context, target: glow::Texture) -> glow::Framebuffer {
    let fbo = gl.create_framebuffer().unwrap();
    gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
    gl.framebuffer_texture_2d(
        glow::FRAMEBUFFER,
        glow::COLOR_ATTACHMENT0,
        glow::TEXTURE_2D,
        Some(target),
        0,
    );
    assert_eq!(
        gl.check_framebuffer_status(glow::FRAMEBUFFER),
        glow::FRAMEBUFFER_COMPLETE
    );
    gl.bind_framebuffer(glow::FRAMEBUFFER, None);
    fbo
}

/// Reads a `w x h` rectangle at (x, y) of `fbo` as RGBA f32.
unsafe fn read(
    gl: &glow::Context,
    fbo: glow::Framebuffer,
    (x, y, w, h): (i32, i32, usize, usize),
) -> RgbaImage {
    let mut out = vec![[0f32; 4]; w * h];
    gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(fbo));
    gl.read_pixels(
        x,
        y,
        w as i32,
        h as i32,
        glow::RGBA,
        glow::FLOAT,
        glow::PixelPackData::Slice(Some(std::slice::from_raw_parts_mut(
            out.as_mut_ptr().cast(),
            out.len() * 16,
        ))),
    );
    gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
    assert_eq!(gl.get_error(), glow::NO_ERROR);
    Grid::from_vec(w, h, out)
}

/// Reads an RGBA8 framebuffer as bytes.
unsafe fn read_bytes(gl: &glow::Context, fbo: glow::Framebuffer, w: usize, h: usize) -> Vec<u8> {
    let mut out = vec![0u8; w * h * 4];
    gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(fbo));
    gl.read_pixels(
        0,
        0,
        w as i32,
        h as i32,
        glow::RGBA,
        glow::UNSIGNED_BYTE,
        glow::PixelPackData::Slice(Some(&mut out)),
    );
    gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
    out
}

fn srgb_encode(v: f64) -> f64 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.0031308 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

fn srgb_decode(v: f64) -> f64 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// The result lands in the output rectangle of a larger host framebuffer, matches the
/// reference there, and leaves the rest of the framebuffer as the host cleared it.
#[test]
fn renders_into_a_rectangle_of_the_hosts_framebuffer() {
    let _lock = gl_lock();
    let (w, h) = (40, 30);
    let host = Host::new(w, h);
    let gl = &host.gl;
    let (big_w, big_h, x0, y0) = (64, 48, 7, 5);
    // SAFETY: host objects on the current context.
    let (target, fbo) = unsafe {
        let target = texture(gl, big_w, big_h, glow::RGBA32F, Upload::None);
        let fbo = framebuffer(gl, target);
        gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
        gl.viewport(0, 0, big_w as i32, big_h as i32);
        gl.clear_color(0.25, 0.5, 0.75, 1.0);
        gl.clear(glow::COLOR_BUFFER_BIT);
        gl.bind_framebuffer(glow::FRAMEBUFFER, None);
        (target, fbo)
    };
    let mut pipeline = Pipeline::new(Arc::clone(gl)).unwrap();
    let (haze, blur) = (Haze::default(), Blur::default());
    let output = Output::Framebuffer {
        framebuffer: Some(fbo),
        x: x0,
        y: y0,
        encoding: Encoding::Linear,
    };
    let frame = pipeline
        .render(&host.input(), &haze, &blur, &output)
        .unwrap();
    // SAFETY: reading the host's framebuffer.
    let (inside, whole) = unsafe {
        (
            read(gl, fbo, (x0, y0, w, h)),
            read(gl, fbo, (0, 0, big_w, big_h)),
        )
    };
    let e = reference::rgb_error(&inside, &host.expected(&haze, &blur), 0);
    let tol = F32_PER_PASS * f64::from(frame.schedule.steps + 2);
    assert!(e.max_abs <= tol, "{e:?} > {tol}");
    for y in 0..big_h {
        for x in 0..big_w {
            let outside =
                x < x0 as usize || y < y0 as usize || x >= x0 as usize + w || y >= y0 as usize + h;
            if outside {
                assert_eq!(*whole.get(x, y), [0.25, 0.5, 0.75, 1.0], "({x}, {y})");
            }
        }
    }
    // SAFETY: the host's own objects.
    unsafe {
        assert!(gl.is_texture(target) && gl.is_texture(host.colour));
        gl.delete_framebuffer(fbo);
        gl.delete_texture(target);
    }
}

/// sRGB 8-bit in (decoded by the pipeline) and sRGB 8-bit out (encoded by it), as a
/// camera filter drawing to a window would run: within one 8-bit step of the reference.
#[test]
fn srgb_8_bit_textures_in_and_out() {
    let _lock = gl_lock();
    let (w, h) = (32, 24);
    let mut host = Host::new(w, h);
    let gl = Arc::clone(&host.gl);
    let bytes: Vec<u8> = host
        .image
        .as_slice()
        .iter()
        .flat_map(|p| {
            let b = |v: f32| (srgb_encode(f64::from(v)) * 255.0).round() as u8;
            [b(p[0]), b(p[1]), b(p[2]), 255]
        })
        .collect();
    // The reference sees exactly what the 8-bit texture holds, decoded.
    host.image = Grid::from_fn(w, h, |x, y| {
        let i = 4 * (y * w + x);
        [0, 1, 2].map(|c| srgb_decode(f64::from(bytes[i + c]) / 255.0) as f32)
    });
    // SAFETY: host objects on the current context.
    let (colour8, target8, fbo) = unsafe {
        let colour8 = texture(&gl, w, h, glow::RGBA8, Upload::Bytes(glow::RGBA, &bytes));
        let target8 = texture(&gl, w, h, glow::RGBA8, Upload::None);
        (colour8, target8, framebuffer(&gl, target8))
    };
    let input = Input {
        colour: colour8,
        colour_encoding: Encoding::Srgb,
        ..host.input()
    };
    let mut pipeline = Pipeline::new(Arc::clone(&gl)).unwrap();
    let (haze, blur) = (Haze::default(), Blur::default());
    let output = Output::Texture {
        texture: target8,
        encoding: Encoding::Srgb,
    };
    // The diffusion pipeline, then the engine pass (which compiles its conversions in).
    pipeline.render(&input, &haze, &blur, &output).unwrap();
    // SAFETY: reading the host's framebuffer over its texture.
    let diffused = unsafe { read_bytes(&gl, fbo, w, h) };
    pipeline
        .fog(&input, &haze, &FogBlur::None, &output)
        .unwrap();
    // SAFETY: as above.
    let fogged = unsafe { read_bytes(&gl, fbo, w, h) };
    let sharp = reference::fog(&host.image, &host.range, &haze, &FogBlur::None).unwrap();
    for (got, expected) in [(diffused, host.expected(&haze, &blur)), (fogged, sharp)] {
        let mut worst = 0.0f64;
        for (i, p) in expected.as_slice().iter().enumerate() {
            for c in 0..3 {
                let want = srgb_encode(f64::from(p[c])) * 255.0;
                worst = worst.max((f64::from(got[4 * i + c]) - want).abs());
            }
        }
        // One step of rounding, plus the decode of the 8-bit input in f32 on the GPU.
        assert!(worst <= 1.0, "largest difference {worst} steps of 255");
    }
}

/// What a render leaves (the pipeline's documented contract), and host state it must not
/// trip over: blending, a scissor box, and sampler objects on its texture units.
#[test]
fn gl_state_contract() {
    let _lock = gl_lock();
    let (w, h) = (24, 16);
    let host = Host::new(w, h);
    let gl = &host.gl;
    // SAFETY: host objects and state on the current context.
    let (target, fbo, sampler) = unsafe {
        let target = texture(gl, w, h, glow::RGBA32F, Upload::None);
        let fbo = framebuffer(gl, target);
        gl.enable(glow::BLEND);
        gl.blend_func(glow::ONE, glow::ONE);
        gl.enable(glow::SCISSOR_TEST);
        gl.scissor(0, 0, 1, 1);
        gl.enable(glow::DEPTH_TEST);
        gl.enable(glow::CULL_FACE);
        gl.cull_face(glow::FRONT_AND_BACK);
        gl.color_mask(false, true, true, false);
        let sampler = gl.create_sampler().unwrap();
        gl.sampler_parameter_i32(sampler, glow::TEXTURE_MIN_FILTER, glow::NEAREST as i32);
        gl.sampler_parameter_i32(sampler, glow::TEXTURE_MAG_FILTER, glow::NEAREST as i32);
        for unit in 0..3 {
            gl.bind_sampler(unit, Some(sampler));
        }
        gl.active_texture(glow::TEXTURE5);
        (target, fbo, sampler)
    };
    let mut pipeline = Pipeline::new(Arc::clone(gl)).unwrap();
    let (haze, blur) = (Haze::default(), Blur::default());
    let output = Output::Framebuffer {
        framebuffer: Some(fbo),
        x: 0,
        y: 0,
        encoding: Encoding::Linear,
    };
    let frame = pipeline
        .render(&host.input(), &haze, &blur, &output)
        .unwrap();
    // SAFETY: state queries and a read-back on the current context.
    unsafe {
        assert_eq!(gl.get_parameter_i32(glow::DRAW_FRAMEBUFFER_BINDING), 0);
        assert_eq!(gl.get_parameter_i32(glow::READ_FRAMEBUFFER_BINDING), 0);
        assert_eq!(gl.get_parameter_i32(glow::CURRENT_PROGRAM), 0);
        assert_eq!(gl.get_parameter_i32(glow::VERTEX_ARRAY_BINDING), 0);
        assert_eq!(
            gl.get_parameter_i32(glow::ACTIVE_TEXTURE),
            glow::TEXTURE0 as i32
        );
        for unit in 0..3 {
            gl.active_texture(glow::TEXTURE0 + unit);
            assert_eq!(gl.get_parameter_i32(glow::TEXTURE_BINDING_2D), 0);
            assert_eq!(gl.get_parameter_i32(glow::SAMPLER_BINDING), 0);
        }
        let mut viewport = [0i32; 4];
        gl.get_parameter_i32_slice(glow::VIEWPORT, &mut viewport);
        assert_eq!(viewport, [0, 0, w as i32, h as i32]);
        for cap in [
            glow::BLEND,
            glow::SCISSOR_TEST,
            glow::DEPTH_TEST,
            glow::CULL_FACE,
        ] {
            assert!(!gl.is_enabled(cap), "0x{cap:04X} left enabled");
        }
        let got = read(gl, fbo, (0, 0, w, h));
        let e = reference::rgb_error(&got, &host.expected(&haze, &blur), 0);
        let tol = F32_PER_PASS * f64::from(frame.schedule.steps + 2);
        assert!(e.max_abs <= tol, "{e:?} > {tol}");
        assert!(gl.is_texture(target));
        gl.delete_sampler(sampler);
        gl.delete_framebuffer(fbo);
        gl.delete_texture(target);
    }
}

/// Two headless renderers on one thread: dropping either leaves the other working (it
/// makes its context current again), and the context current before a drop stays current.
#[test]
fn two_headless_contexts_survive_dropping_either() {
    let _lock = gl_lock();
    let (w, h) = (32, 24);
    let image = noise_image(w, h, 3);
    let range = ramp_range(w, h);
    let (haze, blur) = (Haze::default(), Blur::default());
    let expected = reference::render(&image, &range, &haze, &blur).unwrap();
    let check = |r: &mut brume::Headless| {
        let out = r.render(&image, &range, &haze, &blur).expect("render");
        let e = reference::rgb_error(&out.image, &expected, 0);
        let tol = F32_PER_PASS * f64::from(out.schedule.steps + 2);
        assert!(e.max_abs <= tol, "{e:?} > {tol}");
    };
    for drop_newer in [true, false] {
        let mut a = headless();
        let mut b = headless();
        check(&mut a);
        check(&mut b);
        let mut kept = if drop_newer {
            drop(b);
            a
        } else {
            // b is current; dropping a must not take it away.
            drop(a);
            assert!(b.context().is_current(), "dropping a released b");
            b
        };
        check(&mut kept);
        check(&mut kept);
    }
}
