//! egui on the viewer's window: input from winit, drawing with glow on the viewer's
//! context (egui_glow's painter). What `egui_glow::EguiGlow` does, but with the painter's
//! failure returned as an error instead of a panic.

use brume::{Error, Result};
use std::sync::Arc;
use winit::event::WindowEvent;
use winit::event_loop::ActiveEventLoop;
use winit::window::Window;

/// egui's state between frames.
pub struct Ui {
    pub ctx: egui::Context,
    winit: egui_winit::State,
    pub painter: egui_glow::Painter,
    shapes: Vec<egui::epaint::ClippedShape>,
    textures: egui::TexturesDelta,
    pixels_per_point: f32,
}

impl Ui {
    /// egui on `gl`, which must be current. No dithering: the window shows brume's 8-bit
    /// frame texel for texel.
    pub fn new(
        event_loop: &ActiveEventLoop,
        gl: Arc<glow::Context>,
        window: &Window,
    ) -> Result<Self> {
        let painter = egui_glow::Painter::new(gl, "", None, false).map_err(|e| Error::Window {
            what: "setting up the user interface (egui_glow)".into(),
            detail: e.to_string(),
            hint: "the GL context cannot run egui's shaders; use `brume render`".into(),
        })?;
        let ctx = egui::Context::default();
        let winit = egui_winit::State::new(
            ctx.clone(),
            egui::ViewportId::ROOT,
            event_loop,
            Some(window.scale_factor() as f32),
            event_loop.system_theme(),
            Some(painter.max_texture_side()),
        );
        Ok(Ui {
            ctx,
            winit,
            painter,
            shapes: Vec::new(),
            textures: egui::TexturesDelta::default(),
            pixels_per_point: window.scale_factor() as f32,
        })
    }

    /// Passes a window event to egui; true when egui used it (a click on the panel, typing
    /// in a field) and the viewer should not act on it too.
    pub fn on_event(&mut self, window: &Window, event: &WindowEvent) -> (bool, bool) {
        let r = self.winit.on_window_event(window, event);
        (r.consumed, r.repaint)
    }

    /// Runs the user interface for one frame; [`Ui::paint`] draws it.
    pub fn run(&mut self, window: &Window, build: impl FnMut(&egui::Context)) {
        let input = self.winit.take_egui_input(window);
        let output = self.ctx.run(input, build);
        self.winit
            .handle_platform_output(window, output.platform_output);
        self.shapes = output.shapes;
        self.pixels_per_point = output.pixels_per_point;
        self.textures.append(output.textures_delta);
    }

    /// Draws the last [`Ui::run`] into the default framebuffer of `size` physical px.
    pub fn paint(&mut self, size: [u32; 2]) {
        let textures = std::mem::take(&mut self.textures);
        for (id, delta) in &textures.set {
            self.painter.set_texture(*id, delta);
        }
        let shapes = std::mem::take(&mut self.shapes);
        let primitives = self.ctx.tessellate(shapes, self.pixels_per_point);
        self.painter
            .paint_primitives(size, self.pixels_per_point, &primitives);
        for id in &textures.free {
            self.painter.free_texture(*id);
        }
    }
}

impl Drop for Ui {
    fn drop(&mut self) {
        self.painter.destroy();
    }
}
