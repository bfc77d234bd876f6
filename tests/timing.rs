//! Timing as an option (`Pipeline::set_timing`): off issues no query and returns no
//! figures; deferred returns an earlier call's figures, saying which, without waiting;
//! a host's own `GL_TIME_ELAPSED` query survives blocking and deferred calls; and figures
//! that are rejected (a disjoint event, as phones' drivers flag) are reported unavailable
//! without running the passes again — `blend_fog` blends once onto the host's frame.
//! No test here asserts a duration.
use crate::common;

use brume::camera::Camera;
use brume::egl::GlContext;
use brume::gpu::framebuffer::Framebuffer;
use brume::gpu::texture::{Filter, TexelFormat, Texture};
use brume::gpu::timer::HostQueryProbe;
use brume::medium::LayeredFog;
use brume::{Blur, Clock, Encoding, FogBlur, Haze, Input, Output, PassTimes, Pipeline, Timing};
use common::*;
use glow::HasContext;
use std::sync::Arc;

const W: usize = 32;
const H: usize = 24;

/// A host: its own context and one frame's textures (colour, normalised range, and a
/// window depth for the engine fogs), GL rows bottom first.
struct Host {
    colour: Texture,
    range: Texture,
    depth: Texture,
    gl: Arc<glow::Context>,
    _ctx: GlContext,
}

impl Host {
    fn new() -> Host {
        let ctx = GlContext::new(None).expect("EGL context");
        let gl = Arc::clone(ctx.gl());
        let image = noise_image(W, H, 5);
        let rgb: Vec<f32> = image.as_slice().iter().flatten().copied().collect();
        let colour = Texture::new(&gl, W, H, TexelFormat::Rgb32F, Filter::Nearest, Some(&rgb))
            .expect("colour texture");
        let range = ramp_range(W, H);
        let range = Texture::new(
            &gl,
            W,
            H,
            TexelFormat::R32F,
            Filter::Nearest,
            Some(range.as_slice()),
        )
        .expect("range texture");
        let depth: Vec<f32> = (0..W * H)
            .map(|i| 0.6 + 0.39 * (i % W) as f32 / W as f32)
            .collect();
        let depth = Texture::new(&gl, W, H, TexelFormat::R32F, Filter::Nearest, Some(&depth))
            .expect("depth texture");
        Host {
            colour,
            range,
            depth,
            gl,
            _ctx: ctx,
        }
    }

    fn input(&self) -> Input {
        Input {
            colour: self.colour.raw(),
            colour_encoding: Encoding::Linear,
            depth: self.range.raw(),
            width: W,
            height: H,
            frame: brume::FrameInputs::default(),
        }
    }

    /// A float target of the frame's size holding the host's "scene" (a fixed colour)
    /// and its framebuffer.
    fn scene_target(&self) -> (Texture, Framebuffer) {
        let scene = [0.3f32, 0.5, 0.7, 1.0].repeat(W * H);
        let t = Texture::new(
            &self.gl,
            W,
            H,
            TexelFormat::Rgba32F,
            Filter::Nearest,
            Some(&scene),
        )
        .expect("target");
        let fb = Framebuffer::over(&self.gl, &[&t], "the host's target").expect("framebuffer");
        (t, fb)
    }

    /// `blend_fog` of the layered fog onto the host's scene (`target`, cleared to the
    /// scene's colour first, as a host draws its frame); the read-back.
    fn blend(&self, pipeline: &mut Pipeline, target: &Framebuffer) -> (PassTimes, Vec<[f32; 4]>) {
        // SAFETY: the host clears its own framebuffer on the current context.
        unsafe {
            self.gl
                .bind_framebuffer(glow::FRAMEBUFFER, Some(target.raw()));
            self.gl.viewport(0, 0, W as i32, H as i32);
            self.gl.clear_color(0.3, 0.5, 0.7, 1.0);
            self.gl.clear(glow::COLOR_BUFFER_BIT);
        }
        let output = Output::Framebuffer {
            framebuffer: Some(target.raw()),
            x: 0,
            y: 0,
            encoding: Encoding::Linear,
        };
        let frame = pipeline
            .blend_fog(self.depth.raw(), W, H, &fog(), &at(), &output)
            .expect("blend_fog");
        (frame.times, target.read_rgba().expect("read-back"))
    }
}

fn fog() -> LayeredFog {
    LayeredFog::for_camera(Camera::default(), Default::default())
}

/// The frame the layered fog is blended at: the default camera.
fn at() -> brume::FrameInputs {
    brume::FrameInputs::new(Camera::default(), 0.0)
}

fn assert_unavailable(t: &PassTimes, what: &str) {
    assert_eq!(t.clock, Clock::Unavailable, "{what}: {t:?}");
    assert!(
        !t.is_available() && t.pass_ms.is_empty() && t.total_ms.is_nan(),
        "{what}: {t:?}"
    );
    assert_eq!(t.total(), None, "{what}");
}

/// Figures that are there: finite, non-negative, summing to the total.
fn assert_measured(t: &PassTimes, passes: usize, what: &str) {
    assert_eq!(t.clock, Clock::GpuTimer, "{what}: {t:?}");
    assert_eq!(t.pass_ms.len(), passes, "{what}: {t:?}");
    assert!(
        t.pass_ms.iter().all(|ms| ms.is_finite() && *ms >= 0.0),
        "{what}: {t:?}"
    );
    let sum: f64 = t.pass_ms.iter().sum();
    assert!((sum - t.total_ms).abs() < 1e-9, "{what}: {t:?}");
}

/// A pipeline as a host builds it times nothing: no query begun (no query object made),
/// no figures, for the diffusion render, the engine fog and the blended fog.
#[test]
fn off_is_the_default_and_begins_no_query() {
    let _lock = gl_lock();
    let host = Host::new();
    let mut pipeline = Pipeline::new(Arc::clone(&host.gl)).unwrap();
    assert_eq!(pipeline.timing(), Timing::Off);
    let (_t, fb) = host.scene_target();
    let output = Output::Framebuffer {
        framebuffer: Some(fb.raw()),
        x: 0,
        y: 0,
        encoding: Encoding::Linear,
    };
    for round in 0..2 {
        let before = brume::gpu::objects_created();
        let render = pipeline
            .render(&host.input(), &Haze::default(), &Blur::default(), &output)
            .unwrap();
        assert_unavailable(&render.times, "render");
        let fogged = pipeline
            .fog(&host.input(), &Haze::default(), &FogBlur::None, &output)
            .unwrap();
        assert_unavailable(&fogged.times, "fog");
        let (blended, _) = host.blend(&mut pipeline, &fb);
        assert_unavailable(&blended, "blend_fog");
        if round == 1 {
            // The second round reuses every target: nothing created, so no query object.
            assert_eq!(brume::gpu::objects_created(), before, "round {round}");
        }
    }
    assert_eq!(pipeline.queries_begun(), 0);
    // SAFETY: glGetError on the current context.
    assert_eq!(unsafe { host.gl.get_error() }, glow::NO_ERROR);
}

/// Deferred: a call returns an earlier call's figures, with how many calls back it ran,
/// or none; never its own. With the host waiting for the GPU between calls (its own
/// business), each call returns exactly the previous one's.
#[test]
fn deferred_returns_an_earlier_calls_figures_and_says_which() {
    let _lock = gl_lock();
    let host = Host::new();
    let gl = &host.gl;
    let mut pipeline = Pipeline::new(Arc::clone(gl)).unwrap();
    pipeline.set_timing(Timing::Deferred);
    let (_t, fb) = host.scene_target();
    let output = Output::Framebuffer {
        framebuffer: Some(fb.raw()),
        x: 0,
        y: 0,
        encoding: Encoding::Linear,
    };
    let (haze, blur) = (Haze::default(), Blur::default());
    let first = pipeline
        .render(&host.input(), &haze, &blur, &output)
        .unwrap();
    assert_unavailable(&first.times, "the first call (nothing earlier)");
    let passes = first.schedule.steps as usize + 2;
    let mut begun = pipeline.queries_begun();
    assert_eq!(begun, passes as u64, "one query per pass");
    for call in 2..6 {
        // SAFETY: the host waits for its GPU work (brume never does, when deferred).
        unsafe { gl.finish() };
        let frame = pipeline
            .render(&host.input(), &haze, &blur, &output)
            .unwrap();
        assert_measured(&frame.times, passes, &format!("call {call}"));
        assert_eq!(frame.times.calls_ago, 1, "call {call}");
        begun += passes as u64;
        assert_eq!(pipeline.queries_begun(), begun);
    }
    // Another kind of call gets the render's figures and can tell by `calls_ago` (and
    // the pass count).
    // SAFETY: as above.
    unsafe { gl.finish() };
    let fogged = pipeline
        .fog(&host.input(), &haze, &FogBlur::None, &output)
        .unwrap();
    assert_measured(&fogged.times, passes, "the fog after a render");
    assert_eq!(fogged.times.calls_ago, 1);
    // Without waiting: whatever comes back is an earlier call's, and says so.
    for call in 0..20 {
        let frame = pipeline
            .render(&host.input(), &haze, &blur, &output)
            .unwrap();
        if frame.times.is_available() {
            assert!(frame.times.calls_ago >= 1, "call {call}: {:?}", frame.times);
        } else {
            assert_unavailable(&frame.times, "a call whose earlier figures are not in");
        }
    }
    // Switching timing drops what was in flight; off begins nothing more.
    pipeline.set_timing(Timing::Off);
    let begun = pipeline.queries_begun();
    let off = pipeline
        .render(&host.input(), &haze, &blur, &output)
        .unwrap();
    assert_unavailable(&off.times, "off after deferred");
    assert_eq!(pipeline.queries_begun(), begun);
    // SAFETY: glGetError on the current context.
    assert_eq!(unsafe { gl.get_error() }, glow::NO_ERROR);
}

/// A host that has its own TIME_ELAPSED query open around brume's call: brume begins
/// none (times unavailable, except by the wall clock), leaves the host's open, and the
/// host ends and reads it as usual.
#[test]
fn a_hosts_open_query_survives_blocking_and_deferred_calls() {
    let _lock = gl_lock();
    let host = Host::new();
    let gl = &host.gl;
    let probe = HostQueryProbe::load();
    let mut pipeline = Pipeline::new(Arc::clone(gl)).unwrap();
    let (_t, fb) = host.scene_target();
    let output = Output::Framebuffer {
        framebuffer: Some(fb.raw()),
        x: 0,
        y: 0,
        encoding: Encoding::Linear,
    };
    let (haze, blur) = (Haze::default(), Blur::default());
    for timing in [
        Timing::Blocking,
        Timing::Deferred,
        Timing::BlockingWall,
        Timing::Off,
    ] {
        pipeline.set_timing(timing);
        let begun = pipeline.queries_begun();
        // SAFETY: the host's query on the current context (which has
        // GL_EXT_disjoint_timer_query: gpu_vs_cpu.rs requires it of llvmpipe).
        let query = unsafe {
            let q = gl.create_query().unwrap();
            gl.begin_query(glow::TIME_ELAPSED, q);
            assert_eq!(probe.time_elapsed_open(), Some(true), "{timing:?}");
            q
        };
        for call in 0..3 {
            let frame = pipeline
                .render(&host.input(), &haze, &blur, &output)
                .unwrap();
            let blended = host.blend(&mut pipeline, &fb).0;
            for (what, t) in [("render", &frame.times), ("blend_fog", &blended)] {
                if timing == Timing::BlockingWall {
                    assert_eq!(t.clock, Clock::Wall, "{timing:?} {what} {call}");
                } else {
                    // Deferred too: none of brume's queries in flight, none coming back.
                    assert_unavailable(t, &format!("{timing:?} {what} {call}"));
                }
            }
        }
        assert_eq!(
            pipeline.queries_begun(),
            begun,
            "{timing:?}: brume began a query"
        );
        // SAFETY: the host ends and reads its own query: ending is valid only while it is
        // the active one, reading only while it exists (INVALID_OPERATION otherwise).
        unsafe {
            assert_eq!(probe.time_elapsed_open(), Some(true), "{timing:?}");
            gl.end_query(glow::TIME_ELAPSED);
            assert_eq!(
                gl.get_error(),
                glow::NO_ERROR,
                "{timing:?}: ending the host's query"
            );
            assert_eq!(probe.time_elapsed_open(), Some(false), "{timing:?}");
            while gl.get_query_parameter_u32(query, glow::QUERY_RESULT_AVAILABLE) == 0 {
                std::thread::yield_now();
            }
            let mut ns: u64 = 0;
            gl.get_query_parameter_u64_with_offset(
                query,
                glow::QUERY_RESULT,
                std::ptr::addr_of_mut!(ns) as usize,
            );
            assert_eq!(
                gl.get_error(),
                glow::NO_ERROR,
                "{timing:?}: reading the host's query"
            );
            assert!(ns > 0, "{timing:?}: the host's query measured nothing");
            gl.delete_query(query);
        }
    }
    // The host's query closed: brume times again.
    pipeline.set_timing(Timing::Blocking);
    let frame = pipeline
        .render(&host.input(), &haze, &blur, &output)
        .unwrap();
    assert_measured(
        &frame.times,
        frame.schedule.steps as usize + 2,
        "blocking with no host query",
    );
}

/// Rejected figures (a disjoint event) make the times unavailable; the passes ran once.
/// `blend_fog` onto the host's frame equals one blend (a second run would fog it twice),
/// for blocking and deferred timing.
#[test]
fn rejected_figures_are_unavailable_and_passes_run_once() {
    let _lock = gl_lock();
    let host = Host::new();
    let mut pipeline = Pipeline::new(Arc::clone(&host.gl)).unwrap();
    let (_t, fb) = host.scene_target();
    let (off_times, once) = host.blend(&mut pipeline, &fb);
    assert_unavailable(&off_times, "off");
    // What blending twice gives: the test can tell the two apart.
    host.blend(&mut pipeline, &fb);
    let output = Output::Framebuffer {
        framebuffer: Some(fb.raw()),
        x: 0,
        y: 0,
        encoding: Encoding::Linear,
    };
    pipeline
        .blend_fog(host.depth.raw(), W, H, &fog(), &at(), &output)
        .unwrap();
    let twice = fb.read_rgba().unwrap();
    let largest = |a: &[[f32; 4]], b: &[[f32; 4]]| {
        a.iter()
            .zip(b)
            .flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).abs()))
            .fold(0f32, f32::max)
    };
    assert!(largest(&once, &twice) > 0.01, "the fog is too thin to tell");

    pipeline.set_timing(Timing::Blocking);
    let (measured, blended) = host.blend(&mut pipeline, &fb);
    assert_measured(&measured, 1, "blocking, not rejected");
    assert_eq!(largest(&blended, &once), 0.0);
    pipeline.simulate_disjoint();
    let (rejected, blended) = host.blend(&mut pipeline, &fb);
    assert_unavailable(&rejected, "blocking, rejected");
    assert_eq!(
        largest(&blended, &once),
        0.0,
        "blocking: blended more than once"
    );

    pipeline.set_timing(Timing::Deferred);
    host.blend(&mut pipeline, &fb);
    // SAFETY: the host waits for its GPU (the earlier call's results are in).
    unsafe { host.gl.finish() };
    pipeline.simulate_disjoint();
    let (rejected, blended) = host.blend(&mut pipeline, &fb);
    assert_unavailable(&rejected, "deferred, rejected");
    assert_eq!(
        largest(&blended, &once),
        0.0,
        "deferred: blended more than once"
    );
    // The call that saw the event began its queries after it: its figures come back.
    // SAFETY: as above.
    unsafe { host.gl.finish() };
    let (later, _) = host.blend(&mut pipeline, &fb);
    assert_measured(&later, 1, "deferred, the call after the event");
    assert_eq!(later.calls_ago, 1);
}
