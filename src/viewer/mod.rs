//! `brume view`: a window that shows a photo with depth (or the demo, or brume's 3D scene)
//! under a medium, re-rendered as its parameters move (paper 000's interactive demo).
//! Controls in a side panel (egui), the GPU time of each pass of the last frame under
//! them. Keys: S saves the frame as PNG, E as EXR, R resets the parameters, Q or Escape
//! quits.
//!
//! `--frames N` renders N frames and exits, after saving the window (`--screenshot`) and
//! the frames' figures (`--stats`): how CI runs it under Xvfb.

mod source;
mod ui;
mod window;

use crate::cli::args::{ViewArgs, ViewSource, Zoom};
use crate::cli::limits::{self, MAX_WINDOW_SIDE};
use brume::gpu::texture::{Filter, TexelFormat, Texture};
use brume::io::output::Outputs;
use brume::{Error, Pipeline, Result};
use glow::HasContext;
use serde_json::json;
use source::{FrameTimes, Photo, SceneView, Source};
use std::path::{Path, PathBuf};
use std::time::Instant;
use ui::Ui;
use window::ViewerWindow;
use winit::application::ApplicationHandler;
use winit::dpi::LogicalSize;
use winit::event::{ElementState, KeyEvent, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::WindowId;

/// Width of the control panel (logical px).
const PANEL_WIDTH: f32 = 320.0;
/// The panel's controls need about this much height (logical px).
const PANEL_HEIGHT: f64 = 720.0;

/// Opens the window and runs until it is closed (or `--frames` are done); `args` are
/// checked by the caller (`cli::view::check_args`).
pub fn run(args: ViewArgs) -> Result<()> {
    if !window::display_named() {
        return Err(no_display("DISPLAY and WAYLAND_DISPLAY are unset"));
    }
    let event_loop = EventLoop::new().map_err(|e| no_display(&e.to_string()))?;
    let mut app = App {
        args,
        viewer: None,
        error: None,
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| no_display(&e.to_string()))?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

fn no_display(detail: &str) -> Error {
    Error::Window {
        what: "opening a window".into(),
        detail: format!("no display ({detail})"),
        hint: "run `brume view` in a desktop session or under Xvfb (`xvfb-run -a brume view`), \
               or render to a file without a display with `brume render`"
            .into(),
    }
}

/// The event loop's state: the viewer once the window is open, or what stopped it.
struct App {
    args: ViewArgs,
    viewer: Option<Viewer>,
    error: Option<Error>,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.viewer.is_some() {
            return;
        }
        match Viewer::open(event_loop, &self.args) {
            Ok(v) => {
                v.window.window.request_redraw();
                self.viewer = Some(v);
            }
            Err(e) => self.stop(event_loop, Some(e)),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(viewer) = self.viewer.as_mut() else {
            return;
        };
        let (consumed, repaint) = viewer.ui.on_event(&viewer.window.window, &event);
        if repaint {
            viewer.window.window.request_redraw();
        }
        let outcome = match event {
            WindowEvent::CloseRequested => Ok(Flow::Quit),
            WindowEvent::Resized(_) => {
                viewer.window.resize();
                Ok(Flow::Go)
            }
            WindowEvent::KeyboardInput { event, .. } if !consumed => Ok(viewer.key(&event)),
            WindowEvent::RedrawRequested => viewer.redraw(&self.args),
            _ => Ok(Flow::Go),
        };
        match outcome {
            Ok(Flow::Go) => {}
            Ok(Flow::Quit) => self.stop(event_loop, None),
            Err(e) => self.stop(event_loop, Some(e)),
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let Some(viewer) = self.viewer.as_ref() else {
            return;
        };
        if viewer.scripted() || viewer.source.animated() {
            event_loop.set_control_flow(ControlFlow::Poll);
            viewer.window.window.request_redraw();
        } else {
            event_loop.set_control_flow(ControlFlow::Wait);
        }
    }
}

impl App {
    /// Ends the loop, freeing the viewer's GL objects while its context is current, and
    /// writes the figures of a scripted run.
    fn stop(&mut self, event_loop: &ActiveEventLoop, error: Option<Error>) {
        let mut error = error;
        if let Some(viewer) = self.viewer.take() {
            if error.is_none() {
                error = viewer.finish(&self.args).err();
            }
        }
        if self.error.is_none() {
            self.error = error;
        }
        event_loop.exit();
    }
}

/// What a handled event asks of the loop.
enum Flow {
    Go,
    Quit,
}

/// The open viewer. Field order is drop order: egui's and brume's GL objects before the
/// window and its context.
struct Viewer {
    ui: Ui,
    source: Source,
    display: Texture,
    display_id: egui::TextureId,
    pipeline: Pipeline,
    window: ViewerWindow,
    /// `--frames`: render this many frames, then stop.
    frames: Option<u32>,
    zoom: Zoom,
    save_base: PathBuf,
    /// The frame needs rendering again (a parameter moved).
    dirty: bool,
    started: Instant,
    /// Scene time of the first frame, and frames per second of a scripted run.
    time0: f64,
    fps: f64,
    frames_done: u32,
    /// GL objects brume had created when the first frame was done.
    objects_after_first: usize,
    stats: Vec<FrameStat>,
    last: Option<FrameTimes>,
    /// What the last key or render said, and whether it is an error.
    message: Option<(String, bool)>,
    renderer: String,
    /// The image's rectangle in the window (physical px, top row first: x, y, w, h).
    image_rect: [i64; 4],
    screenshot: Option<RgbaBytes>,
}

/// An RGBA8 read-back, top row first.
struct RgbaBytes {
    width: usize,
    height: usize,
    pixels: Vec<u8>,
}

/// One frame's figures.
#[derive(serde::Serialize)]
struct FrameStat {
    /// brume's passes on the GPU clock (ms).
    gpu_ms: f64,
    /// The whole redraw on the wall clock: brume, the panel, presenting (ms).
    wall_ms: f64,
}

impl Viewer {
    fn open(event_loop: &ActiveEventLoop, args: &ViewArgs) -> Result<Self> {
        let size = match &args.window {
            Some(s) => {
                let (w, h) = limits::parse_size("--window", s, MAX_WINDOW_SIDE)?;
                LogicalSize::new(w as f64, h as f64)
            }
            None => LogicalSize::new(PANEL_WIDTH as f64 + 960.0, PANEL_HEIGHT),
        };
        let window = ViewerWindow::open(event_loop, "brume view", size, args.frames.is_none())?;
        let gl = std::sync::Arc::clone(&window.gl);
        let mut pipeline = Pipeline::new(std::sync::Arc::clone(&gl))?;
        // The panel shows each redraw's own pass times.
        pipeline.set_timing(brume::Timing::Blocking);
        let (source, time0, fps) = match &args.source {
            Some(ViewSource::Scene(a)) => (
                Source::Scene(Box::new(SceneView::new(a, &gl)?)),
                a.time,
                a.fps,
            ),
            Some(ViewSource::Render(a)) => {
                (Source::Photo(Box::new(Photo::load(a, &gl)?)), 0.0, 24.0)
            }
            None => (
                Source::Photo(Box::new(Photo::load(
                    &crate::cli::view::default_render_args(),
                    &gl,
                )?)),
                0.0,
                24.0,
            ),
        };
        let (w, h) = source.size();
        pipeline.caps().require_size("image", w, h)?;
        if args.window.is_none() {
            let _ = window
                .window
                .request_inner_size(initial_size(w, h, args.zoom));
        }
        window
            .window
            .set_title(&format!("brume view: {}", source.describe()));
        let display = Texture::new(&gl, w, h, TexelFormat::Rgba8, Filter::Linear, None)?;
        let mut ui = Ui::new(event_loop, std::sync::Arc::clone(&gl), &window.window)?;
        let display_id = ui.painter.register_native_texture(display.raw());
        let renderer = pipeline.caps().renderer.clone();
        Ok(Viewer {
            ui,
            source,
            display,
            display_id,
            pipeline,
            window,
            frames: args.frames,
            zoom: args.zoom,
            save_base: args.save.clone(),
            dirty: true,
            started: Instant::now(),
            time0,
            fps,
            frames_done: 0,
            objects_after_first: 0,
            stats: Vec::new(),
            last: None,
            message: None,
            renderer,
            image_rect: [0; 4],
            screenshot: None,
        })
    }

    /// Whether the run is scripted (`--frames`): every frame renders, until the last.
    fn scripted(&self) -> bool {
        self.frames.is_some()
    }

    /// Scene time of the next frame: frame k of a scripted run is at time0 + k / fps, as
    /// `brume scene --frames` has it; otherwise the wall clock since start.
    fn time(&self) -> f64 {
        if self.scripted() {
            self.time0 + f64::from(self.frames_done) / self.fps
        } else {
            self.time0 + self.started.elapsed().as_secs_f64()
        }
    }

    fn key(&mut self, event: &KeyEvent) -> Flow {
        if event.state != ElementState::Pressed || event.repeat {
            return Flow::Go;
        }
        match &event.logical_key {
            Key::Named(NamedKey::Escape) => return Flow::Quit,
            Key::Character(c) => match c.to_lowercase().as_str() {
                "q" => return Flow::Quit,
                "r" => {
                    self.source.reset();
                    self.dirty = true;
                    self.message = Some(("parameters reset".into(), false));
                }
                "s" => self.save("png"),
                "e" => self.save("exr"),
                _ => {}
            },
            _ => {}
        }
        self.window.window.request_redraw();
        Flow::Go
    }

    /// Saves the current frame, rendered again in float, under `--save`'s name (numbered
    /// when the file exists: nothing is overwritten).
    fn save(&mut self, extension: &str) {
        let path = free_path(&self.save_base, extension);
        let time = self.time();
        let result = self
            .source
            .render_to_image(&mut self.pipeline, time)
            .and_then(|image| {
                let mut outputs = Outputs::new();
                outputs.stage_photo(&path, &image, &self.source.metadata())?;
                crate::cli::commit(outputs)
            });
        self.message = Some(match result {
            Ok(()) => (format!("saved {}", path.display()), false),
            Err(e) => (format!("not saved: {e}"), true),
        });
    }

    /// Renders the frame where needed, draws the panel and the image, presents.
    fn redraw(&mut self, args: &ViewArgs) -> Result<Flow> {
        let began = Instant::now();
        let render_now = self.dirty || self.scripted() || self.source.animated();
        let mut gpu_ms = 0.0;
        if render_now {
            let time = self.time();
            match self.source.render(&mut self.pipeline, &self.display, time) {
                Ok(t) => {
                    gpu_ms = t.total_ms;
                    self.last = Some(t);
                    if self.message.as_ref().is_some_and(|m| m.1) {
                        self.message = None;
                    }
                }
                // A scripted run stops at the first error; a person sees it in the panel
                // and moves the slider back.
                Err(e) if self.scripted() => return Err(e),
                Err(e) => self.message = Some((e.to_string(), true)),
            }
            self.dirty = false;
        }
        self.draw_window();
        let last_frame = self
            .frames
            .is_some_and(|n| self.frames_done + 1 >= n.max(1));
        if last_frame && args.screenshot.is_some() {
            self.screenshot = Some(read_window(
                &self.window.gl,
                self.window.window.inner_size().into(),
            )?);
        }
        self.window.swap()?;
        if render_now {
            self.frames_done += 1;
            if self.frames_done == 1 {
                self.objects_after_first = brume::gpu::objects_created();
            }
            self.stats.push(FrameStat {
                gpu_ms,
                wall_ms: began.elapsed().as_secs_f64() * 1e3,
            });
        }
        Ok(if last_frame { Flow::Quit } else { Flow::Go })
    }

    /// The panel and the image, painted into the window's back buffer.
    fn draw_window(&mut self) {
        let size: [u32; 2] = self.window.window.inner_size().into();
        let gl = std::sync::Arc::clone(&self.window.gl);
        // SAFETY: plain state on the viewer's current context.
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            gl.viewport(0, 0, size[0] as i32, size[1] as i32);
            gl.disable(glow::SCISSOR_TEST);
            gl.clear_color(0.09, 0.09, 0.09, 1.0);
            gl.clear(glow::COLOR_BUFFER_BIT);
        }
        let mut changed = false;
        let mut image_rect = self.image_rect;
        let (w, h) = self.source.size();
        let window = &self.window.window;
        let Viewer {
            ui,
            source,
            last,
            message,
            renderer,
            display_id,
            zoom,
            stats,
            ..
        } = self;
        ui.run(window, |ctx| {
            egui::SidePanel::left("controls")
                .resizable(false)
                .exact_width(PANEL_WIDTH)
                .show(ctx, |ui| {
                    egui::ScrollArea::vertical().show(ui, |ui| {
                        ui.label(source.describe());
                        changed |= source.controls(ui);
                        ui.separator();
                        timings_panel(ui, last.as_ref(), stats, renderer);
                        if let Some((m, error)) = message {
                            let colour = if *error {
                                egui::Color32::from_rgb(255, 110, 100)
                            } else {
                                egui::Color32::LIGHT_GREEN
                            };
                            ui.colored_label(colour, m.as_str());
                        }
                        ui.label("S: save PNG · E: save EXR · R: reset · Q/Esc: quit");
                    });
                });
            egui::CentralPanel::default()
                .frame(egui::Frame::NONE)
                .show(ctx, |ui| {
                    let ppp = ctx.pixels_per_point();
                    let rect = place_image(ui.max_rect(), (w, h), *zoom, ppp);
                    image_rect = [
                        (rect.min.x * ppp).round() as i64,
                        (rect.min.y * ppp).round() as i64,
                        (rect.width() * ppp).round() as i64,
                        (rect.height() * ppp).round() as i64,
                    ];
                    // GL textures hold the bottom row first: v runs upwards.
                    let uv = egui::Rect::from_min_max(egui::pos2(0.0, 1.0), egui::pos2(1.0, 0.0));
                    ui.painter()
                        .image(*display_id, rect, uv, egui::Color32::WHITE);
                });
        });
        self.image_rect = image_rect;
        self.ui.paint(size);
        if changed {
            self.dirty = true;
            self.window.window.request_redraw();
        }
    }

    /// Writes the scripted run's screenshot and figures, then frees the GL objects.
    fn finish(mut self, args: &ViewArgs) -> Result<()> {
        if self.scripted() {
            let mut outputs = Outputs::new();
            if let (Some(path), Some(shot)) = (&args.screenshot, &self.screenshot) {
                let rgb: Vec<[u8; 3]> = shot
                    .pixels
                    .chunks_exact(4)
                    .map(|p| [p[0], p[1], p[2]])
                    .collect();
                outputs.stage_png_rgb8(path, shot.width, shot.height, &rgb)?;
            }
            if let Some(path) = &args.stats {
                let json = self.stats_json(args);
                outputs.stage_bytes(path, format!("{json:#}\n").as_bytes())?;
            }
            crate::cli::commit(outputs)?;
            self.print_summary();
        }
        self.ui.painter.free_texture(self.display_id);
        Ok(())
    }

    fn stats_json(&mut self, args: &ViewArgs) -> serde_json::Value {
        let size = self.window.window.inner_size();
        let (w, h) = self.source.size();
        let (gpu, wall) = self.steady_medians();
        json!({
            "brume": brume::VERSION,
            "sources": brume::SOURCES,
            "renderer": self.renderer,
            "source": self.source.describe(),
            "image": [w, h],
            "window": [size.width, size.height],
            "scale_factor": self.window.window.scale_factor(),
            "image_rect": self.image_rect,
            "frames": self.frames_done,
            "frame_stats": self.stats,
            "median_gpu_ms": gpu,
            "median_frame_ms": wall,
            "fps": wall.map(|ms| 1e3 / ms),
            "last_frame": self.last,
            "gl_objects_created_after_first_frame":
                brume::gpu::objects_created() - self.objects_after_first,
            "screenshot": args.screenshot.as_ref().map(|p| p.display().to_string()),
        })
    }

    /// Median GPU and wall-clock times (ms) of the frames after the first, which compiles
    /// the programs.
    fn steady_medians(&self) -> (Option<f64>, Option<f64>) {
        let steady = &self.stats[self.stats.len().min(1)..];
        (
            // A frame whose GPU timer figures were rejected has none (NaN).
            median(
                steady
                    .iter()
                    .map(|s| s.gpu_ms)
                    .filter(|ms| ms.is_finite())
                    .collect(),
            ),
            median(steady.iter().map(|s| s.wall_ms).collect()),
        )
    }

    fn print_summary(&self) {
        let (gpu, wall) = self.steady_medians();
        let (w, h) = self.source.size();
        outln!(
            "{} frames of {w}x{h} on {}: median {} ms GPU, {} ms per frame ({} fps) after the first",
            self.frames_done,
            self.renderer,
            gpu.map_or("-".into(), |v| format!("{v:.1}")),
            wall.map_or("-".into(), |v| format!("{v:.1}")),
            wall.map_or("-".into(), |v| format!("{:.1}", 1e3 / v)),
        );
    }
}

/// The panel's figures: per-pass GPU times of the last frame (the diffusion passes summed),
/// and the frame rate.
fn timings_panel(
    ui: &mut egui::Ui,
    last: Option<&FrameTimes>,
    stats: &[FrameStat],
    renderer: &str,
) {
    ui.heading("Last frame");
    if let Some(t) = last {
        egui::Grid::new("passes").striped(true).show(ui, |ui| {
            for (name, ms) in grouped_passes(t) {
                ui.label(name);
                ui.label(format!("{ms:.2} ms"));
                ui.end_row();
            }
            ui.strong("total");
            ui.strong(if t.total_ms.is_finite() {
                format!("{:.2} ms ({})", t.total_ms, t.clock)
            } else {
                "n/a".to_string()
            });
            ui.end_row();
        });
    }
    if let Some(s) = stats.last() {
        ui.label(format!(
            "frame {:.1} ms on the wall clock ({:.1} fps)",
            s.wall_ms,
            1e3 / s.wall_ms.max(1e-3)
        ));
    }
    ui.small(renderer);
}

/// The passes of a frame, the diffusion passes as one row.
fn grouped_passes(t: &FrameTimes) -> Vec<(String, f64)> {
    let mut rows: Vec<(String, f64)> = Vec::new();
    let mut diffusion = (0u32, 0.0);
    for (name, ms) in t.pass_names.iter().zip(&t.pass_ms) {
        if name.starts_with("diffuse") {
            diffusion.0 += 1;
            diffusion.1 += ms;
        } else {
            if diffusion.0 > 0 && name.ends_with("composite") {
                rows.push((format!("diffusion ({} passes)", diffusion.0), diffusion.1));
            }
            rows.push((name.clone(), *ms));
        }
    }
    rows
}

/// Where the image goes in `area` (logical px): centred, its corners on whole physical
/// pixels so that zoom 1 shows it texel for texel.
fn place_image(area: egui::Rect, (w, h): (usize, usize), zoom: Zoom, ppp: f32) -> egui::Rect {
    let scale = match zoom {
        Zoom::Fit => (area.width() * ppp / w as f32).min(area.height() * ppp / h as f32),
        Zoom::Factor(f) => f,
    };
    let (pw, ph) = ((w as f32 * scale).round(), (h as f32 * scale).round());
    let x = (area.center().x * ppp - pw / 2.0)
        .round()
        .max(area.min.x * ppp);
    let y = (area.center().y * ppp - ph / 2.0)
        .round()
        .max(area.min.y * ppp);
    egui::Rect::from_min_size(egui::pos2(x / ppp, y / ppp), egui::vec2(pw / ppp, ph / ppp))
}

/// A first window size that shows the panel and the image at the zoom asked (fit: at
/// most 1:1), within a common screen.
fn initial_size(w: usize, h: usize, zoom: Zoom) -> LogicalSize<f64> {
    let scale = match zoom {
        Zoom::Fit => 1.0,
        Zoom::Factor(f) => f64::from(f),
    };
    let width = (PANEL_WIDTH as f64 + w as f64 * scale).min(1900.0);
    let height = (h as f64 * scale).clamp(PANEL_HEIGHT, 1060.0);
    LogicalSize::new(width, height)
}

/// The window's back buffer as RGBA8, top row first.
fn read_window(gl: &glow::Context, [w, h]: [u32; 2]) -> Result<RgbaBytes> {
    let (width, height) = (w as usize, h as usize);
    let mut pixels = vec![0u8; width * height * 4];
    // SAFETY: reads w x h RGBA8 pixels into a buffer of exactly that size.
    unsafe {
        gl.bind_framebuffer(glow::READ_FRAMEBUFFER, None);
        gl.bind_buffer(glow::PIXEL_PACK_BUFFER, None);
        gl.pixel_store_i32(glow::PACK_ALIGNMENT, 1);
        gl.read_pixels(
            0,
            0,
            w as i32,
            h as i32,
            glow::RGBA,
            glow::UNSIGNED_BYTE,
            glow::PixelPackData::Slice(Some(&mut pixels)),
        );
    }
    brume::gpu::check_gl(gl, "reading the window back")?;
    // GL reads the bottom row first.
    let flipped: Vec<u8> = pixels
        .chunks_exact(width * 4)
        .rev()
        .flatten()
        .copied()
        .collect();
    Ok(RgbaBytes {
        width,
        height,
        pixels: flipped,
    })
}

/// `base` with `extension`, or with -1, -2, … before it when that file exists.
fn free_path(base: &Path, extension: &str) -> PathBuf {
    let first = base.with_extension(extension);
    if !first.exists() {
        return first;
    }
    let stem = base
        .file_stem()
        .map_or("brume-view".into(), |s| s.to_string_lossy().into_owned());
    (1..)
        .map(|k| base.with_file_name(format!("{stem}-{k}.{extension}")))
        .find(|p| !p.exists())
        .expect("some numbered name is free")
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}
