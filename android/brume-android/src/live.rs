//! The app's frame, free of Android: brume's haze on the demo image or on a camera frame,
//! drawn 1:1 and centred into a framebuffer (the window's default one on the phone, a
//! texture of its own in the host test), with the pass-time overlay on top. Every GL
//! object is made once, in [`Live::new`] or by the pipeline on its first frame: the frame
//! loop creates none (the host test counts them).

use crate::controls::Settings;
use crate::overlay::Overlay;
use brume::gpu::texture::{Filter, TexelFormat, Texture};
use brume::medium::haze::normalise_range;
use brume::{Blur, Encoding, Frame, Haze, Input, Output, Pipeline, Precision};
use glow::HasContext;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Where a frame is drawn: a framebuffer (`None`: the window's) of `width x height`.
#[derive(Clone, Copy, Debug)]
pub struct Target {
    /// The framebuffer object.
    pub framebuffer: Option<glow::Framebuffer>,
    /// Width (px).
    pub width: i32,
    /// Height (px).
    pub height: i32,
}

/// brume's demo RGBD image on the GPU: linear RGB and normalised range.
struct Demo {
    colour: Texture,
    range: Texture,
    width: usize,
    height: usize,
}

impl Demo {
    fn load(gl: &Arc<glow::Context>) -> brume::Result<Demo> {
        let image = brume::io::demo::demo_image()?;
        let (range, _) = normalise_range(&brume::io::demo::demo_range()?.range)?;
        let (width, height) = (image.width(), image.height());
        let rgb: Vec<f32> = image.as_slice().iter().flatten().copied().collect();
        // The image is stored top row first, GL textures bottom row first.
        let colour = Texture::new(
            gl,
            width,
            height,
            TexelFormat::Rgb32F,
            Filter::Nearest,
            None,
        )?;
        colour.upload_flipped(&rgb);
        let depth = Texture::new(gl, width, height, TexelFormat::R32F, Filter::Nearest, None)?;
        depth.upload_flipped(range.as_slice());
        Ok(Demo {
            colour,
            range: depth,
            width,
            height,
        })
    }

    fn input(&self) -> Input {
        Input {
            colour: self.colour.raw(),
            colour_encoding: Encoding::Linear,
            depth: self.range.raw(),
            width: self.width,
            height: self.height,
            frame: brume::FrameInputs::default(),
        }
    }
}

/// The pipeline, the demo and the overlay on the app's context.
pub struct Live {
    // Field order is drop order: everything holds the context, the pipeline included.
    demo: Demo,
    overlay: Overlay,
    pipeline: Pipeline,
    blur: Blur,
    stats: Stats,
    /// The newest pass times that came in (deferred: a frame or more late), drawn by the
    /// overlay until newer ones come.
    shown_ms: Vec<f64>,
    /// When the loop started: each frame's time is counted from it.
    started: Instant,
}

impl Live {
    /// Builds the pipeline on `gl` (current on this thread), uploads the demo and picks the
    /// precision the driver can render and filter: f32 where it can, else f16 (Mali GPUs
    /// often filter no f32 texture).
    pub fn new(gl: Arc<glow::Context>) -> brume::Result<Live> {
        let mut pipeline = Pipeline::new(Arc::clone(&gl))?;
        // The overlay's figures a frame or two late, never waiting for the GPU.
        pipeline.set_timing(brume::Timing::Deferred);
        let precision = if pipeline.caps().require_precision(Precision::F32).is_ok() {
            Precision::F32
        } else {
            pipeline.caps().require_precision(Precision::F16)?;
            Precision::F16
        };
        log::info!(
            "brume on {} ({}), precision {precision:?}, external images: {}",
            pipeline.caps().renderer,
            pipeline.caps().version,
            pipeline.supports_external()
        );
        Ok(Live {
            demo: Demo::load(&gl)?,
            overlay: Overlay::default(),
            pipeline,
            blur: Blur {
                precision,
                ..Blur::default()
            },
            stats: Stats::default(),
            shown_ms: Vec::new(),
            started: Instant::now(),
        })
    }

    /// The pipeline, for the camera's import.
    pub fn pipeline(&mut self) -> &mut Pipeline {
        &mut self.pipeline
    }

    /// Draws the demo image's haze with `settings` into `target`.
    pub fn draw_demo(&mut self, settings: &Settings, target: &Target) -> brume::Result<Frame> {
        let input = self.demo.input();
        self.draw(&input, &settings.haze(1.0), target)
    }

    /// Draws `input` fogged by `haze` into `target`: cleared to black, the result centred
    /// at 1:1, the overlay over it. Logs the frame rate and pass times once a second. The
    /// frame's time (seconds since the loop started) goes with it, as an engine passes
    /// it; the haze reads a range map and needs no camera.
    pub fn draw(&mut self, input: &Input, haze: &Haze, target: &Target) -> brume::Result<Frame> {
        let input = &Input {
            frame: brume::FrameInputs::at_time(self.started.elapsed().as_secs_f64()),
            ..*input
        };
        let gl = Arc::clone(self.pipeline.gl());
        clear(&gl, target);
        let output = Output::Framebuffer {
            framebuffer: target.framebuffer,
            x: (target.width - input.width as i32) / 2,
            y: (target.height - input.height as i32) / 2,
            // The window stores what it shows: the shader encodes sRGB.
            encoding: Encoding::Srgb,
        };
        let frame = self.pipeline.render(input, haze, &self.blur, &output)?;
        // SAFETY: binding the target again (brume leaves framebuffer 0 bound) and the
        // viewport over all of it, on the current context.
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, target.framebuffer);
            gl.viewport(0, 0, target.width, target.height);
        }
        if frame.times.is_available() {
            self.shown_ms.clone_from(&frame.times.pass_ms);
        }
        self.overlay
            .layout(&self.shown_ms, (target.width, target.height));
        self.overlay.draw(&gl);
        if let Some(line) = self.stats.record(&frame, Instant::now()) {
            log::info!("{line}");
        }
        Ok(frame)
    }
}

/// Clears all of `target` to black (the result covers only its own rectangle).
fn clear(gl: &glow::Context, target: &Target) {
    // SAFETY: state setters and a clear on the current context.
    unsafe {
        gl.bind_framebuffer(glow::FRAMEBUFFER, target.framebuffer);
        gl.viewport(0, 0, target.width, target.height);
        gl.disable(glow::SCISSOR_TEST);
        gl.clear_color(0.0, 0.0, 0.0, 1.0);
        gl.clear(glow::COLOR_BUFFER_BIT);
    }
}

/// Frame times summed over a second, for one log line.
#[derive(Debug, Default)]
pub struct Stats {
    since: Option<Instant>,
    /// Frames whose pass times are summed.
    frames: u32,
    /// Frames drawn without figures (deferred ones not in yet, or rejected).
    unmeasured: u32,
    pass_ms: Vec<f64>,
}

impl Stats {
    /// How often a line is logged.
    pub const PERIOD: Duration = Duration::from_secs(1);

    /// Adds `frame`, drawn at `now`; returns a line to log once a period has passed.
    pub fn record(&mut self, frame: &Frame, now: Instant) -> Option<String> {
        let since = *self.since.get_or_insert(now);
        let times = &frame.times.pass_ms;
        if !frame.times.is_available() {
            // Deferred figures not in yet (or rejected): the frame counts for the rate only.
            self.unmeasured += 1;
        } else if self.pass_ms.len() != times.len() {
            // Another pass count (the blur changed): start the averages again.
            self.pass_ms.clear();
            self.pass_ms.resize(times.len(), 0.0);
            self.frames = 0;
        }
        if frame.times.is_available() {
            for (sum, t) in self.pass_ms.iter_mut().zip(times) {
                *sum += t;
            }
            self.frames += 1;
        }
        let drawn = self.frames + self.unmeasured;
        let elapsed = now.duration_since(since);
        if elapsed < Self::PERIOD {
            return None;
        }
        let n = f64::from(self.frames.max(1));
        let mean: Vec<f64> = self.pass_ms.iter().map(|s| s / n).collect();
        let rate = f64::from(drawn) / elapsed.as_secs_f64();
        let line = summary(&mean, rate, frame.times.clock.name());
        *self = Stats::default();
        self.since = Some(now);
        Some(line)
    }
}

/// One line: frame rate, then the mean time of each pass (medium, the diffusion passes as
/// their count and sum, composite).
fn summary(mean_ms: &[f64], fps: f64, clock: &str) -> String {
    let total: f64 = mean_ms.iter().sum();
    let passes = match mean_ms {
        [medium, diffusion @ .., composite] => format!(
            "medium {medium:.2} ms, {} diffusion passes {:.2} ms, composite {composite:.2} ms",
            diffusion.len(),
            diffusion.iter().sum::<f64>()
        ),
        [single] => format!("one pass {single:.2} ms"),
        [] => "no pass".to_string(),
    };
    format!("{fps:.1} fps; brume {total:.2} ms a frame ({clock}): {passes}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use brume::egl::GlContext;
    use brume::gpu::timer::{Clock, PassTimes};

    fn frame(pass_ms: Vec<f64>) -> Frame {
        let total_ms = pass_ms.iter().sum();
        Frame {
            schedule: brume::schedule::Schedule::new(brume::Scheme::Matched, 1.0, 1.0, 0.25)
                .unwrap(),
            passes: brume::pipeline::Passes::Diffusion {
                coarse_starts: Vec::new(),
            },
            times: PassTimes {
                clock: Clock::GpuTimer,
                pass_ms,
                total_ms,
                calls_ago: 0,
            },
        }
    }

    #[test]
    fn one_line_a_second_with_mean_pass_times() {
        let mut stats = Stats::default();
        let t0 = Instant::now();
        assert!(stats.record(&frame(vec![1.0, 2.0, 2.0, 1.0]), t0).is_none());
        let t = t0 + Duration::from_millis(500);
        assert!(stats.record(&frame(vec![3.0, 2.0, 2.0, 1.0]), t).is_none());
        let line = stats
            .record(
                &frame(vec![2.0, 2.0, 2.0, 1.0]),
                t0 + Duration::from_secs(1),
            )
            .expect("a line after a second");
        assert_eq!(
            line,
            "3.0 fps; brume 7.00 ms a frame (gpu-timer): medium 2.00 ms, 2 diffusion passes \
             4.00 ms, composite 1.00 ms"
        );
        assert_eq!(
            summary(&[0.5], 60.0, "wall"),
            "60.0 fps; brume 0.50 ms a frame (wall): one pass 0.50 ms"
        );
    }

    /// The app's frame on llvmpipe: the demo's haze centred in a framebuffer larger than
    /// it, black around it, the overlay's bar at the bottom-left, and no GL object created
    /// by the frames after the first.
    #[test]
    fn the_frame_loop_draws_the_demo_and_creates_no_gl_objects() {
        let ctx = GlContext::new(None).unwrap_or_else(|e| panic!("cannot open a GL context: {e}"));
        let gl = Arc::clone(ctx.gl());
        let (width, height) = (800, 700);
        // SAFETY: the test's own RGBA8 texture and framebuffer on the current context.
        let (texture, fbo) = unsafe {
            let t = gl.create_texture().unwrap();
            gl.bind_texture(glow::TEXTURE_2D, Some(t));
            gl.tex_storage_2d(glow::TEXTURE_2D, 1, glow::RGBA8, width, height);
            let fbo = gl.create_framebuffer().unwrap();
            gl.bind_framebuffer(glow::FRAMEBUFFER, Some(fbo));
            gl.framebuffer_texture_2d(
                glow::FRAMEBUFFER,
                glow::COLOR_ATTACHMENT0,
                glow::TEXTURE_2D,
                Some(t),
                0,
            );
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            (t, fbo)
        };
        let target = Target {
            framebuffer: Some(fbo),
            width,
            height,
        };
        let mut live = Live::new(Arc::clone(&gl)).expect("the app's pipeline");
        let settings = Settings::default();
        live.draw_demo(&settings, &target).expect("the first frame");
        // Deferred timing: the query sets of the calls in flight are made in the first
        // frames, then reused.
        for _ in 0..5 {
            live.draw_demo(&settings, &target).expect("a warm-up frame");
        }
        let objects = brume::gpu::live_objects();
        let mut timed = 0;
        for _ in 0..5 {
            let frame = live.draw_demo(&settings, &target).expect("a frame");
            if frame.times.is_available() {
                assert!(frame.times.pass_ms.len() >= 2 && frame.times.calls_ago >= 1);
                timed += 1;
            }
            assert_eq!(
                brume::gpu::live_objects(),
                objects,
                "GL objects created per frame"
            );
        }
        assert!(timed > 0, "no deferred figures came in over 5 frames");
        let mut pixels = vec![0u8; (width * height * 4) as usize];
        // SAFETY: reading the test's framebuffer into a buffer of its size.
        unsafe {
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, Some(fbo));
            gl.read_pixels(
                0,
                0,
                width,
                height,
                glow::RGBA,
                glow::UNSIGNED_BYTE,
                glow::PixelPackData::Slice(Some(&mut pixels)),
            );
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
            assert_eq!(gl.get_error(), glow::NO_ERROR);
        }
        let at = |x: i32, y: i32| {
            let i = 4 * (y * width + x) as usize;
            [pixels[i], pixels[i + 1], pixels[i + 2]]
        };
        // The demo (641 x 555) is centred: hazy (bright) in the middle, black outside.
        let centre = at(width / 2, height / 2);
        assert!(centre.iter().all(|&c| c > 40), "centre {centre:?}");
        assert_eq!(at(10, height - 10), [0, 0, 0], "outside the image");
        // The overlay: the medium pass's red segment starts at the bar's left end.
        let margin = (width / 60).max(8);
        let red = at(margin + 1, margin + 1);
        assert!(
            red[0] > 200 && red[1] < 100,
            "the medium segment is {red:?}"
        );
        drop(live);
        // SAFETY: the test's own objects.
        unsafe {
            gl.delete_framebuffer(fbo);
            gl.delete_texture(texture);
        }
    }
}
