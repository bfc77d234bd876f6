//! The pipeline as a host drives it: the host's own textures in, the host's framebuffer
//! or texture out, the GL state it leaves, the host state it must not trip over, and
//! several headless contexts on one thread.
use crate::common;

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
            frame: brume::FrameInputs::default(),
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
    // With the coarse stage, whose last blend runs in the composite, the rectangle holds
    // exactly what a target of the frame's own size gets.
    let coarse = Blur {
        coarse_from: Some(2.0),
        ..Blur::default()
    };
    let frame = pipeline
        .render(&host.input(), &haze, &coarse, &output)
        .unwrap();
    assert!(frame.pass_names().contains(&"down 1/2".to_string()));
    // SAFETY: a target of the frame's size, read back, and the host's own objects.
    unsafe {
        let inside = read(gl, fbo, (x0, y0, w, h));
        let own = texture(gl, w, h, glow::RGBA32F, Upload::None);
        let own_fbo = framebuffer(gl, own);
        let at_origin = Output::Framebuffer {
            framebuffer: Some(own_fbo),
            x: 0,
            y: 0,
            encoding: Encoding::Linear,
        };
        pipeline
            .render(&host.input(), &haze, &coarse, &at_origin)
            .unwrap();
        assert_eq!(inside, read(gl, own_fbo, (0, 0, w, h)));
        gl.delete_framebuffer(own_fbo);
        gl.delete_texture(own);
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
    let sharp = reference::fog(
        &host.image,
        &host.range,
        &haze,
        &brume::FrameInputs::default(),
        &FogBlur::None,
    )
    .unwrap();
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

/// Capabilities the contract names: a hostile host leaves all of them on.
const CAPABILITIES: [u32; 10] = [
    glow::BLEND,
    glow::DEPTH_TEST,
    glow::STENCIL_TEST,
    glow::SCISSOR_TEST,
    glow::CULL_FACE,
    glow::RASTERIZER_DISCARD,
    glow::SAMPLE_ALPHA_TO_COVERAGE,
    glow::SAMPLE_COVERAGE,
    glow::POLYGON_OFFSET_FILL,
    glow::DITHER,
];

/// Units a hostile host binds textures and samplers on (brume uses 0-8; 9 is active).
const HOST_UNITS: [u32; 10] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9];

/// The host's objects that make up its hostile state.
struct Hostile {
    texture: glow::Texture,
    sampler: glow::Sampler,
    unpack: glow::Buffer,
    pack: glow::Buffer,
    vao: glow::VertexArray,
    draw_fbo: glow::Framebuffer,
    read_fbo: glow::Framebuffer,
    fbo_texture: glow::Texture,
}

impl Hostile {
    unsafe fn new(gl: &glow::Context) -> Hostile {
        let bound = texture(gl, 4, 4, glow::RGBA32F, Upload::None);
        let sampler = gl.create_sampler().unwrap();
        gl.sampler_parameter_i32(sampler, glow::TEXTURE_MIN_FILTER, glow::NEAREST as i32);
        gl.sampler_parameter_i32(sampler, glow::TEXTURE_MAG_FILTER, glow::NEAREST as i32);
        let buffer = |target| {
            let b = gl.create_buffer().unwrap();
            gl.bind_buffer(target, Some(b));
            gl.buffer_data_size(target, 1 << 16, glow::STREAM_DRAW);
            gl.bind_buffer(target, None);
            b
        };
        let unpack = buffer(glow::PIXEL_UNPACK_BUFFER);
        let pack = buffer(glow::PIXEL_PACK_BUFFER);
        let fbo_texture = texture(gl, 8, 8, glow::RGBA32F, Upload::None);
        Hostile {
            texture: bound,
            sampler,
            unpack,
            pack,
            vao: gl.create_vertex_array().unwrap(),
            draw_fbo: framebuffer(gl, fbo_texture),
            read_fbo: framebuffer(gl, fbo_texture),
            fbo_texture,
        }
    }

    /// Sets every piece of state the contract names to something unusual.
    unsafe fn apply(&self, gl: &glow::Context) {
        for cap in CAPABILITIES {
            gl.enable(cap);
        }
        gl.scissor(0, 0, 1, 1);
        gl.cull_face(glow::FRONT_AND_BACK);
        gl.polygon_offset(3.0, 5.0);
        gl.sample_coverage(0.25, true);
        gl.color_mask(false, true, true, false);
        gl.blend_func_separate(glow::ONE, glow::ONE, glow::DST_COLOR, glow::ZERO);
        gl.blend_equation_separate(glow::FUNC_SUBTRACT, glow::FUNC_REVERSE_SUBTRACT);
        gl.depth_func(glow::GREATER);
        gl.depth_mask(false);
        gl.depth_range_f32(0.25, 0.75);
        gl.viewport(1, 2, 3, 4);
        gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(self.draw_fbo));
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(self.read_fbo));
        gl.bind_vertex_array(Some(self.vao));
        for unit in HOST_UNITS {
            gl.active_texture(glow::TEXTURE0 + unit);
            gl.bind_texture(glow::TEXTURE_2D, Some(self.texture));
            gl.bind_sampler(unit, Some(self.sampler));
        }
        gl.active_texture(glow::TEXTURE9);
        for (p, v) in [
            (glow::UNPACK_ALIGNMENT, 1),
            (glow::UNPACK_ROW_LENGTH, 7),
            (glow::UNPACK_SKIP_ROWS, 2),
            (glow::UNPACK_SKIP_PIXELS, 3),
            (glow::PACK_ALIGNMENT, 1),
            (glow::PACK_ROW_LENGTH, 5),
            (glow::PACK_SKIP_ROWS, 1),
            (glow::PACK_SKIP_PIXELS, 2),
        ] {
            gl.pixel_store_i32(p, v);
        }
        gl.bind_buffer(glow::PIXEL_UNPACK_BUFFER, Some(self.unpack));
        gl.bind_buffer(glow::PIXEL_PACK_BUFFER, Some(self.pack));
        assert_eq!(gl.get_error(), glow::NO_ERROR);
    }

    unsafe fn delete(self, gl: &glow::Context) {
        gl.delete_framebuffer(self.draw_fbo);
        gl.delete_framebuffer(self.read_fbo);
        gl.delete_texture(self.fbo_texture);
        gl.delete_texture(self.texture);
        gl.delete_sampler(self.sampler);
        gl.delete_buffer(self.unpack);
        gl.delete_buffer(self.pack);
        gl.delete_vertex_array(self.vao);
    }
}

/// GL's default state for what [`Hostile::apply`] changes (what a clean host has).
unsafe fn calm(gl: &glow::Context, w: usize, h: usize) {
    for cap in CAPABILITIES {
        gl.disable(cap);
    }
    gl.enable(glow::DITHER);
    gl.color_mask(true, true, true, true);
    gl.blend_func(glow::ONE, glow::ZERO);
    gl.blend_equation(glow::FUNC_ADD);
    gl.depth_func(glow::LESS);
    gl.depth_mask(true);
    gl.depth_range_f32(0.0, 1.0);
    gl.viewport(0, 0, w as i32, h as i32);
    gl.bind_framebuffer(glow::FRAMEBUFFER, None);
    gl.bind_vertex_array(None);
    for unit in HOST_UNITS {
        gl.active_texture(glow::TEXTURE0 + unit);
        gl.bind_texture(glow::TEXTURE_2D, None);
        gl.bind_sampler(unit, None);
    }
    gl.active_texture(glow::TEXTURE0);
    for p in [glow::UNPACK_ALIGNMENT, glow::PACK_ALIGNMENT] {
        gl.pixel_store_i32(p, 4);
    }
    for p in [
        glow::UNPACK_ROW_LENGTH,
        glow::UNPACK_SKIP_ROWS,
        glow::UNPACK_SKIP_PIXELS,
        glow::PACK_ROW_LENGTH,
        glow::PACK_SKIP_ROWS,
        glow::PACK_SKIP_PIXELS,
    ] {
        gl.pixel_store_i32(p, 0);
    }
    gl.bind_buffer(glow::PIXEL_UNPACK_BUFFER, None);
    gl.bind_buffer(glow::PIXEL_PACK_BUFFER, None);
}

/// Every piece of state the contract names, by name, as the host sees it now.
unsafe fn snapshot(gl: &glow::Context) -> Vec<(String, Vec<i32>)> {
    let mut out = Vec::new();
    let mut int = |name: &str, p: u32, n: usize| {
        let mut v = vec![0; n];
        gl.get_parameter_i32_slice(p, &mut v);
        out.push((name.to_string(), v));
    };
    for (name, p, n) in [
        ("draw framebuffer", glow::DRAW_FRAMEBUFFER_BINDING, 1),
        ("read framebuffer", glow::READ_FRAMEBUFFER_BINDING, 1),
        ("viewport", glow::VIEWPORT, 4),
        ("scissor box", glow::SCISSOR_BOX, 4),
        ("program", glow::CURRENT_PROGRAM, 1),
        ("vertex array", glow::VERTEX_ARRAY_BINDING, 1),
        ("active texture", glow::ACTIVE_TEXTURE, 1),
        ("blend src rgb", glow::BLEND_SRC_RGB, 1),
        ("blend dst rgb", glow::BLEND_DST_RGB, 1),
        ("blend src alpha", glow::BLEND_SRC_ALPHA, 1),
        ("blend dst alpha", glow::BLEND_DST_ALPHA, 1),
        ("blend equation rgb", glow::BLEND_EQUATION_RGB, 1),
        ("blend equation alpha", glow::BLEND_EQUATION_ALPHA, 1),
        ("cull face mode", glow::CULL_FACE_MODE, 1),
        ("depth func", glow::DEPTH_FUNC, 1),
        ("depth write mask", glow::DEPTH_WRITEMASK, 1),
        ("depth range", glow::DEPTH_RANGE, 2),
        ("unpack alignment", glow::UNPACK_ALIGNMENT, 1),
        ("unpack row length", glow::UNPACK_ROW_LENGTH, 1),
        ("unpack skip rows", glow::UNPACK_SKIP_ROWS, 1),
        ("unpack skip pixels", glow::UNPACK_SKIP_PIXELS, 1),
        ("pack alignment", glow::PACK_ALIGNMENT, 1),
        ("pack row length", glow::PACK_ROW_LENGTH, 1),
        ("pack skip rows", glow::PACK_SKIP_ROWS, 1),
        ("pack skip pixels", glow::PACK_SKIP_PIXELS, 1),
        ("pixel unpack buffer", glow::PIXEL_UNPACK_BUFFER_BINDING, 1),
        ("pixel pack buffer", glow::PIXEL_PACK_BUFFER_BINDING, 1),
    ] {
        int(name, p, n);
    }
    let mask = gl.get_parameter_bool_array::<4>(glow::COLOR_WRITEMASK);
    out.push(("colour mask".into(), mask.map(i32::from).to_vec()));
    for cap in CAPABILITIES {
        out.push((
            format!("enabled 0x{cap:04X}"),
            vec![i32::from(gl.is_enabled(cap))],
        ));
    }
    let active = gl.get_parameter_i32(glow::ACTIVE_TEXTURE) as u32;
    for unit in 0..10 {
        gl.active_texture(glow::TEXTURE0 + unit);
        out.push((
            format!("unit {unit} texture, sampler"),
            vec![
                gl.get_parameter_i32(glow::TEXTURE_BINDING_2D),
                gl.get_parameter_i32(glow::SAMPLER_BINDING),
            ],
        ));
    }
    gl.active_texture(active);
    out
}

/// Asserts that `after` is the host's state `before`, naming what changed.
fn assert_same_state(before: &[(String, Vec<i32>)], after: &[(String, Vec<i32>)], what: &str) {
    for ((name, was), (_, now)) in before.iter().zip(after) {
        assert_eq!(was, now, "{what}: {name} changed");
    }
}

/// The hostile host (the contract's module docs): unit 9 active with a texture bound
/// there, textures and sampler objects on every unit brume uses, `UNPACK_ROW_LENGTH` 7,
/// alignment 1 and skips for unpack and pack, bound unpack and pack buffers, every
/// capability the contract names on (`DITHER` too), a colour mask, blend state, depth
/// function, write mask and range, a viewport, a scissor box, a vertex array and draw and
/// read framebuffers of its own. Through a render (Haze, diffusion; and with the coarse
/// stage), the engine passes with a medium that has a lookup texture (the distance fog
/// and its noise: `fog` without blur, with each Gaussian, and `blend_fog`), the
/// CPU-buffer `Renderer` (uploads and a read-back) and the upsampling (its depth test),
/// each call on a fresh pipeline (so that its first upload of the lookups meets the
/// host's pixel store): the host's state is exactly as it left it after each, and the
/// result is what a clean host gets, bit for bit.
#[test]
fn gl_state_contract() {
    use brume::medium::{DistanceFog, Medium};
    use brume::GaussBlur;
    let _lock = gl_lock();
    let (w, h) = (24, 16);
    let host = Host::new(w, h);
    let gl = &host.gl;
    let fog = DistanceFog::default();
    let fog_depth_map = synthetic_depth_buffer(&brume::camera::Camera::default(), w, h);
    // SAFETY: host objects and state on the current context.
    let (target, fbo, fog_depth, hostile) = unsafe {
        let target = texture(gl, w, h, glow::RGBA32F, Upload::None);
        let fog_depth = texture(
            gl,
            w,
            h,
            glow::R32F,
            Upload::Float(glow::RED, fog_depth_map.as_slice()),
        );
        (target, framebuffer(gl, target), fog_depth, Hostile::new(gl))
    };
    let at = brume::FrameInputs::new(brume::camera::Camera::default(), 0.0);
    let fog_input = Input {
        depth: fog_depth,
        frame: at,
        ..host.input()
    };
    let (haze, blur) = (Haze::default(), Blur::default());
    // From 2 px, so that this small frame's σmax reaches it: the blend into full
    // resolution reads units 7 and 8, after a medium's lookups.
    let coarse = Blur {
        coarse_from: Some(2.0),
        ..Blur::default()
    };
    let output = Output::Framebuffer {
        framebuffer: Some(fbo),
        x: 0,
        y: 0,
        encoding: Encoding::Linear,
    };
    let gauss = GaussBlur::default();
    type Call<'a> = Box<dyn Fn(&mut Pipeline) + 'a>;
    let calls: Vec<(&str, Call)> = vec![
        (
            "render",
            Box::new(|p| {
                p.render(&host.input(), &haze, &blur, &output).unwrap();
            }),
        ),
        (
            "render with the coarse stage",
            Box::new(|p| {
                let frame = p.render(&host.input(), &haze, &coarse, &output).unwrap();
                let names = frame.pass_names();
                assert_eq!(names.last().unwrap(), "blend 1/2 + composite", "{names:?}");
            }),
        ),
        (
            "fog none",
            Box::new(|p| {
                p.fog(&fog_input, &fog, &FogBlur::None, &output).unwrap();
            }),
        ),
        (
            "fog gauss-single",
            Box::new(|p| {
                p.fog(&fog_input, &fog, &FogBlur::GaussSingle(gauss), &output)
                    .unwrap();
            }),
        ),
        (
            "fog gauss-separate",
            Box::new(|p| {
                p.fog(&fog_input, &fog, &FogBlur::GaussSeparate(gauss), &output)
                    .unwrap();
            }),
        ),
        (
            "blend_fog",
            Box::new(|p| {
                p.blend_fog(fog_depth, w, h, &fog, &at, &output).unwrap();
            }),
        ),
    ];
    assert!(!fog.lookups().is_empty(), "the distance fog has its noise");
    for (what, call) in &calls {
        let mut results = Vec::new();
        for hostile_host in [false, true] {
            let mut pipeline = Pipeline::new(Arc::clone(gl)).unwrap();
            // SAFETY: state and a clear of the host's target on the current context.
            let before = unsafe {
                calm(gl, w, h);
                gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
                gl.clear_color(0.25, 0.5, 0.75, 1.0);
                gl.clear(glow::COLOR_BUFFER_BIT);
                gl.bind_framebuffer(glow::FRAMEBUFFER, None);
                if hostile_host {
                    hostile.apply(gl);
                }
                snapshot(gl)
            };
            call(&mut pipeline);
            // SAFETY: state queries and a read-back on the current context.
            unsafe {
                assert_same_state(&before, &snapshot(gl), what);
                assert_eq!(gl.get_error(), glow::NO_ERROR, "{what}");
                calm(gl, w, h);
                results.push(read(gl, fbo, (0, 0, w, h)));
            }
        }
        assert_eq!(
            results[0].as_slice(),
            results[1].as_slice(),
            "{what}: the hostile host's result differs"
        );
    }
    // Renderer: brume's uploads and read-back under the host's pixel store and buffers.
    let mut results = Vec::new();
    for hostile_host in [false, true] {
        let mut renderer = brume::Renderer::new(Arc::clone(gl)).unwrap();
        // SAFETY: state on the current context.
        let before = unsafe {
            calm(gl, w, h);
            if hostile_host {
                hostile.apply(gl);
            }
            snapshot(gl)
        };
        let out = renderer
            .render_fog(&host.image, &fog_depth_map, &fog, &at, &FogBlur::None)
            .unwrap();
        // SAFETY: state queries on the current context.
        unsafe {
            assert_same_state(&before, &snapshot(gl), "Renderer::render_fog");
            calm(gl, w, h);
        }
        results.push(out.image);
    }
    assert_eq!(results[0].as_slice(), results[1].as_slice(), "Renderer");
    // The upsampling (its passes' depth test) into an R32F texture the host keeps, from
    // the range at half size.
    let low = Grid::from_fn(w / 2, h / 2, |x, y| *host.range.get(2 * x, 2 * y));
    let upsampled = brume::gpu::texture::Texture::new(
        gl,
        w,
        h,
        brume::gpu::texture::TexelFormat::R32F,
        brume::gpu::texture::Filter::Nearest,
        None,
    )
    .unwrap();
    // SAFETY: host objects on the current context.
    let (low_texture, upsampled_fbo) = unsafe {
        let low_data = Upload::Float(glow::RED, low.as_slice());
        let low_texture = texture(gl, w / 2, h / 2, glow::R32F, low_data);
        (low_texture, framebuffer(gl, upsampled.raw()))
    };
    let refine_input = brume::pipeline::RefineInput {
        colour: host.colour,
        colour_encoding: Encoding::Linear,
        width: w,
        height: h,
        range: low_texture,
        range_width: w / 2,
        range_height: h / 2,
    };
    let mut results = Vec::new();
    for hostile_host in [false, true] {
        let mut pipeline = Pipeline::new(Arc::clone(gl)).unwrap();
        // SAFETY: state on the current context.
        let before = unsafe {
            calm(gl, w, h);
            if hostile_host {
                hostile.apply(gl);
            }
            snapshot(gl)
        };
        let sigma = brume::refine::DEFAULT_UPSAMPLE_SIGMA_COLOUR;
        pipeline
            .upsample_range_into(&refine_input, sigma, &upsampled)
            .unwrap();
        // SAFETY: state queries and a read-back on the current context.
        unsafe {
            assert_same_state(&before, &snapshot(gl), "upsample_range_into");
            calm(gl, w, h);
            results.push(read(gl, upsampled_fbo, (0, 0, w, h)));
        }
    }
    assert!(results[0].as_slice().iter().all(|p| p[0] > 0.0));
    assert_eq!(results[0].as_slice(), results[1].as_slice(), "upsampling");
    // The diffusion result is still right against the CPU reference.
    let haze_result = {
        let mut pipeline = Pipeline::new(Arc::clone(gl)).unwrap();
        // SAFETY: host state on the current context.
        unsafe { hostile.apply(gl) };
        let frame = pipeline
            .render(&host.input(), &haze, &blur, &output)
            .unwrap();
        // SAFETY: a read-back on the current context.
        let got = unsafe {
            calm(gl, w, h);
            read(gl, fbo, (0, 0, w, h))
        };
        (frame, got)
    };
    let e = reference::rgb_error(&haze_result.1, &host.expected(&haze, &blur), 0);
    let tol = F32_PER_PASS * f64::from(haze_result.0.schedule.steps + 2);
    assert!(e.max_abs <= tol, "{e:?} > {tol}");
    // SAFETY: the host's own objects.
    unsafe {
        assert!(gl.is_texture(target) && gl.is_texture(hostile.texture));
        hostile.delete(gl);
        gl.delete_framebuffer(fbo);
        gl.delete_texture(target);
        gl.delete_texture(fog_depth);
        gl.delete_framebuffer(upsampled_fbo);
        gl.delete_texture(low_texture);
    }
}

/// `fog(FogBlur::None)` and `blend_fog` into a host's target allocate no GL object (the
/// float targets they never read are not made), and `blend_fog` into an 8-bit target
/// holding sRGB values (`Encoding::Srgb`) gives the linear result encoded.
#[test]
fn engine_passes_without_blur_allocate_nothing_and_blend_in_srgb() {
    use brume::medium::DistanceFog;
    let _lock = gl_lock();
    let (w, h) = (24, 16);
    let host = Host::new(w, h);
    let gl = Arc::clone(&host.gl);
    let fog = DistanceFog {
        noise: None,
        ..DistanceFog::default()
    };
    let depth_map = synthetic_depth_buffer(&brume::camera::Camera::default(), w, h);
    let bytes: Vec<u8> = host
        .image
        .as_slice()
        .iter()
        .flat_map(|p| {
            let b = |v: f32| (srgb_encode(f64::from(v)) * 255.0).round() as u8;
            [b(p[0]), b(p[1]), b(p[2]), 255]
        })
        .collect();
    let linear: Vec<f32> = bytes
        .iter()
        .map(|&b| srgb_decode(f64::from(b) / 255.0) as f32)
        .collect();
    // SAFETY: host objects on the current context.
    let (scene, depth, target32, fbo32, target8, fbo8) = unsafe {
        let depth = texture(
            &gl,
            w,
            h,
            glow::R32F,
            Upload::Float(glow::RED, depth_map.as_slice()),
        );
        let target32 = texture(&gl, w, h, glow::RGBA32F, Upload::Float(glow::RGBA, &linear));
        let target8 = texture(&gl, w, h, glow::RGBA8, Upload::Bytes(glow::RGBA, &bytes));
        (
            texture(&gl, w, h, glow::RGBA32F, Upload::Float(glow::RGBA, &linear)),
            depth,
            target32,
            framebuffer(&gl, target32),
            target8,
            framebuffer(&gl, target8),
        )
    };
    let mut pipeline = Pipeline::new(Arc::clone(&gl)).unwrap();
    let made_before = brume::gpu::objects_created();
    let linear_out = Output::Texture {
        texture: target32,
        encoding: Encoding::Linear,
    };
    let at = brume::FrameInputs::new(brume::camera::Camera::default(), 0.0);
    let input = Input {
        colour: scene,
        depth,
        frame: at,
        ..host.input()
    };
    // The first calls compile; the objects counted are the second calls'.
    pipeline
        .fog(&input, &fog, &FogBlur::None, &linear_out)
        .unwrap();
    pipeline
        .blend_fog(depth, w, h, &fog, &at, &linear_out)
        .unwrap();
    pipeline
        .fog(&input, &fog, &FogBlur::None, &linear_out)
        .unwrap();
    // Two programs, the framebuffer over the host's texture and the medium's 1x1
    // placeholder noise lookup: no image-sized texture.
    assert_eq!(
        brume::gpu::objects_created(),
        made_before + 4,
        "fog made objects"
    );
    let live = brume::gpu::live_objects();
    let made = brume::gpu::objects_created();
    // SAFETY: reading the host's target, then putting its scene back.
    let fogged = unsafe {
        let got = read(&gl, fbo32, (0, 0, w, h));
        texture_refill(&gl, target32, w, h, &linear);
        got
    };
    pipeline
        .blend_fog(depth, w, h, &fog, &at, &linear_out)
        .unwrap();
    assert_eq!(
        brume::gpu::objects_created(),
        made,
        "blend_fog made objects"
    );
    assert_eq!(brume::gpu::live_objects(), live);
    // SAFETY: as above.
    let blended = unsafe { read(&gl, fbo32, (0, 0, w, h)) };
    let e = reference::rgb_error(&blended, &fogged, 0);
    assert!(e.max_abs <= 1e-5, "blend_fog and fog differ: {e:?}");
    // sRGB: the 8-bit target holds the same scene encoded.
    let srgb_out = Output::Texture {
        texture: target8,
        encoding: Encoding::Srgb,
    };
    pipeline
        .blend_fog(depth, w, h, &fog, &at, &srgb_out)
        .unwrap();
    // SAFETY: reading the host's 8-bit target.
    let got = unsafe { read_bytes(&gl, fbo8, w, h) };
    let mut worst = 0.0f64;
    for (i, p) in fogged.as_slice().iter().enumerate() {
        for c in 0..3 {
            let want = srgb_encode(f64::from(p[c])) * 255.0;
            worst = worst.max((f64::from(got[4 * i + c]) - want).abs());
        }
    }
    assert!(
        worst <= 1.0,
        "sRGB blend_fog: {worst} steps of 255 from the linear result encoded"
    );
    // SAFETY: the host's own objects.
    unsafe {
        gl.delete_framebuffer(fbo32);
        gl.delete_framebuffer(fbo8);
        for t in [scene, depth, target32, target8] {
            gl.delete_texture(t);
        }
    }
}

/// Uploads `data` (RGBA f32) into the host's texture again.
unsafe fn texture_refill(gl: &glow::Context, t: glow::Texture, w: usize, h: usize, data: &[f32]) {
    gl.bind_texture(glow::TEXTURE_2D, Some(t));
    gl.tex_sub_image_2d(
        glow::TEXTURE_2D,
        0,
        0,
        0,
        w as i32,
        h as i32,
        glow::RGBA,
        glow::FLOAT,
        glow::PixelUnpackData::Slice(Some(std::slice::from_raw_parts(
            data.as_ptr().cast(),
            data.len() * 4,
        ))),
    );
    gl.bind_texture(glow::TEXTURE_2D, None);
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
