//! The GL-state guard: every call that draws saves the host's state it is about to
//! change ([`HostState::save`]), sets what its passes rely on ([`Pipeline::enter_state`])
//! and puts the host's state back before it returns, on errors too
//! ([`HostState::restore`]). The parent module's docs list the state (*State*).

use super::programs::ProgramKey;
use super::{draw_fullscreen, Pipeline, TEXTURE_BINDING_EXTERNAL_OES, TEXTURE_EXTERNAL_OES};
use super::{UNITS_USED, UNIT_MAIN};
use crate::error::Result;
use crate::gpu::framebuffer::Framebuffer;
use crate::gpu::texture::{Filter, TexelFormat, Texture};
use crate::gpu::timer::{self, PassTimer, PassTimes};
use glow::HasContext;

/// Capabilities disabled for the passes and restored after (see the module docs).
/// `DITHER` is on by default in GL: a float target must not be dithered.
pub(super) const DISABLED: [u32; 10] = [
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

/// `GL_FRAMEBUFFER_SRGB` (desktop GL only): enabled during a desktop context's passes so
/// that `SRGB8_ALPHA8` destinations are encoded on write, as GLES always does.
pub(super) const FRAMEBUFFER_SRGB: u32 = 0x8DB9;

/// The host's state a call changes, as it was when the call began.
pub(super) struct HostState {
    draw_framebuffer: Option<glow::Framebuffer>,
    read_framebuffer: Option<glow::Framebuffer>,
    viewport: [i32; 4],
    program: Option<glow::Program>,
    vertex_array: Option<glow::VertexArray>,
    active_texture: u32,
    /// `TEXTURE_2D` binding and sampler of units `0..UNITS_USED`.
    units: Vec<(Option<glow::Texture>, Option<glow::Sampler>)>,
    /// Unit 0's `TEXTURE_EXTERNAL_OES` binding, where the driver has external images.
    external: Option<Option<glow::Texture>>,
    enabled: [bool; DISABLED.len()],
    framebuffer_srgb: Option<bool>,
    colour_mask: [bool; 4],
    /// Source and destination factors, colour then alpha, and the two equations.
    blend: [i32; 6],
    /// `DEPTH_FUNC`, `DEPTH_WRITEMASK` and `DEPTH_RANGE` (the upsampling's depth test).
    depth: (u32, bool, [f32; 2]),
}

/// Which optional pieces of state a call saves.
#[derive(Clone, Copy)]
pub(super) struct Scope {
    /// The call binds unit 0's `TEXTURE_EXTERNAL_OES` target.
    pub(super) external: bool,
    /// A desktop context: `FRAMEBUFFER_SRGB` is enabled during the passes.
    pub(super) desktop: bool,
}

const BLEND_STATE: [u32; 6] = [
    glow::BLEND_SRC_RGB,
    glow::BLEND_DST_RGB,
    glow::BLEND_SRC_ALPHA,
    glow::BLEND_DST_ALPHA,
    glow::BLEND_EQUATION_RGB,
    glow::BLEND_EQUATION_ALPHA,
];

impl HostState {
    /// Reads the state a call may change, on the current context.
    pub(super) fn save(gl: &glow::Context, scope: Scope) -> Self {
        // SAFETY: state queries on the current context; the active unit is switched to
        // read each unit's bindings and put back by `restore`.
        unsafe {
            let mut viewport = [0; 4];
            gl.get_parameter_i32_slice(glow::VIEWPORT, &mut viewport);
            let active_texture = gl.get_parameter_i32(glow::ACTIVE_TEXTURE) as u32;
            let units = (0..UNITS_USED)
                .map(|unit| {
                    gl.active_texture(glow::TEXTURE0 + unit);
                    (
                        gl.get_parameter_texture(glow::TEXTURE_BINDING_2D),
                        gl.get_parameter_sampler(glow::SAMPLER_BINDING),
                    )
                })
                .collect();
            let external = scope.external.then(|| {
                gl.active_texture(glow::TEXTURE0 + UNIT_MAIN);
                gl.get_parameter_texture(TEXTURE_BINDING_EXTERNAL_OES)
            });
            gl.active_texture(active_texture);
            HostState {
                draw_framebuffer: gl.get_parameter_framebuffer(glow::DRAW_FRAMEBUFFER_BINDING),
                read_framebuffer: gl.get_parameter_framebuffer(glow::READ_FRAMEBUFFER_BINDING),
                viewport,
                program: gl.get_parameter_program(glow::CURRENT_PROGRAM),
                vertex_array: gl.get_parameter_vertex_array(glow::VERTEX_ARRAY_BINDING),
                active_texture,
                units,
                external,
                enabled: DISABLED.map(|cap| gl.is_enabled(cap)),
                framebuffer_srgb: scope.desktop.then(|| gl.is_enabled(FRAMEBUFFER_SRGB)),
                colour_mask: gl.get_parameter_bool_array::<4>(glow::COLOR_WRITEMASK),
                blend: BLEND_STATE.map(|p| gl.get_parameter_i32(p)),
                depth: (
                    gl.get_parameter_i32(glow::DEPTH_FUNC) as u32,
                    gl.get_parameter_bool(glow::DEPTH_WRITEMASK),
                    depth_range(gl),
                ),
            }
        }
    }

    /// Puts the saved state back.
    pub(super) fn restore(&self, gl: &glow::Context) {
        // SAFETY: state setters on the current context, with the host's own handles and
        // values as read by `save`.
        unsafe {
            gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, self.draw_framebuffer);
            gl.bind_framebuffer(glow::READ_FRAMEBUFFER, self.read_framebuffer);
            let [x, y, w, h] = self.viewport;
            gl.viewport(x, y, w, h);
            gl.use_program(self.program);
            gl.bind_vertex_array(self.vertex_array);
            for (unit, &(texture, sampler)) in (0..).zip(&self.units) {
                gl.active_texture(glow::TEXTURE0 + unit);
                gl.bind_texture(glow::TEXTURE_2D, texture);
                gl.bind_sampler(unit, sampler);
            }
            if let Some(texture) = self.external {
                gl.active_texture(glow::TEXTURE0 + UNIT_MAIN);
                gl.bind_texture(TEXTURE_EXTERNAL_OES, texture);
            }
            gl.active_texture(self.active_texture);
            for (cap, on) in DISABLED.into_iter().zip(self.enabled) {
                set_enabled(gl, cap, on);
            }
            if let Some(on) = self.framebuffer_srgb {
                set_enabled(gl, FRAMEBUFFER_SRGB, on);
            }
            let [r, g, b, a] = self.colour_mask;
            gl.color_mask(r, g, b, a);
            let [src_rgb, dst_rgb, src_alpha, dst_alpha, eq_rgb, eq_alpha] =
                self.blend.map(|v| v as u32);
            gl.blend_func_separate(src_rgb, dst_rgb, src_alpha, dst_alpha);
            gl.blend_equation_separate(eq_rgb, eq_alpha);
            let (func, write, [near, far]) = self.depth;
            gl.depth_func(func);
            gl.depth_mask(write);
            gl.depth_range_f32(near, far);
        }
    }
}

/// `DEPTH_RANGE`, near and far.
fn depth_range(gl: &glow::Context) -> [f32; 2] {
    let mut range = [0.0; 2];
    // SAFETY: a state query on the current context.
    unsafe { gl.get_parameter_f32_slice(glow::DEPTH_RANGE, &mut range) };
    range
}

/// Enables the depth test of a pass with `func`, writing depth where `write`, over the
/// whole depth range (the fullscreen triangle's depth is then 0.5), inside a
/// [`HostState`] guard.
pub(super) fn set_depth_test(gl: &glow::Context, func: u32, write: bool) {
    // SAFETY: state setters on the current context.
    unsafe {
        gl.enable(glow::DEPTH_TEST);
        gl.depth_func(func);
        gl.depth_mask(write);
        gl.depth_range_f32(0.0, 1.0);
    }
}

/// Enables or disables `cap`.
fn set_enabled(gl: &glow::Context, cap: u32, on: bool) {
    // SAFETY: a capability switch on the current context.
    unsafe {
        if on {
            gl.enable(cap);
        } else {
            gl.disable(cap);
        }
    }
}

impl Pipeline {
    /// What [`HostState::save`] must save for this context.
    pub(super) fn state_scope(&self, external: bool) -> Scope {
        Scope {
            external,
            desktop: self.caps.desktop,
        }
    }

    /// Runs `passes` (which return the index of the target holding an internal result, or
    /// nothing) once, timed as [`Pipeline::timing`] says: the figures are this call's, an
    /// earlier call's ([`crate::Timing::Deferred`]) or unavailable, never a second run's.
    /// `what` names the passes in a GL error. The host's state is saved before and put
    /// back after, also when a pass fails.
    pub(super) fn timed<T>(
        &self,
        what: &str,
        passes: impl FnOnce(&Self, &mut PassTimer) -> Result<T>,
    ) -> Result<(PassTimes, T)> {
        let saved = HostState::save(&self.gl, self.state_scope(false));
        let result = self.timed_in_state(what, passes);
        saved.restore(&self.gl);
        result
    }

    fn timed_in_state<T>(
        &self,
        what: &str,
        passes: impl FnOnce(&Self, &mut PassTimer) -> Result<T>,
    ) -> Result<(PassTimes, T)> {
        let plan = self.timekeeper.plan();
        if plan.warm_up {
            self.warm_up_timer()?;
            self.timekeeper.warmed_up();
        }
        self.enter_state();
        if plan.uses_queries() && self.caps.software() {
            self.anchor_timer()?;
        }
        let mut timer = self.timekeeper.start(plan);
        let result = passes(self, &mut timer)?;
        crate::gpu::check_gl(&self.gl, what)?;
        let times = self.timekeeper.finish(timer)?;
        Ok((times, result))
    }

    /// The state every pass relies on (module docs), inside a [`HostState`] guard.
    pub(super) fn enter_state(&self) {
        let gl = &self.gl;
        // SAFETY: state setters on the current context; the VAO is owned.
        unsafe {
            gl.bind_vertex_array(Some(self.vao));
            for cap in DISABLED {
                gl.disable(cap);
            }
            if self.caps.desktop {
                gl.enable(FRAMEBUFFER_SRGB);
            }
            gl.color_mask(true, true, true, true);
            for unit in 0..UNITS_USED {
                gl.bind_sampler(unit, None);
            }
        }
    }

    /// llvmpipe records the start of a TIME_ELAPSED query in the scene of the framebuffer
    /// its state last validated; when that framebuffer has since been deleted (a
    /// texture made and dropped between calls: a host's target, the refinement's
    /// output), the query's start is never recorded and its figure comes back as about
    /// the system uptime (rejected, so unavailable). Clearing brume's own 1x1 target
    /// first gives the query's beginning a live framebuffer. (Measured on Mesa 22.3.)
    pub(super) fn anchor_timer(&self) -> Result<()> {
        if self.timer_anchor.get().is_none() {
            let gl = &self.gl;
            let texture = Texture::new(gl, 1, 1, TexelFormat::Rgba16F, Filter::Nearest, None)?;
            let target = Framebuffer::over(gl, &[&texture], "the timer's anchor")?;
            let _ = self.timer_anchor.set((texture, target));
        }
        let (_, target) = self.timer_anchor.get().expect("set just above");
        target.bind_for_drawing();
        // SAFETY: a clear of brume's own 1x1 target (colour mask all on, scissor off:
        // enter_state), with the host's clear colour, on the current context.
        unsafe { self.gl.clear(glow::COLOR_BUFFER_BIT) };
        Ok(())
    }

    /// Spends the first timer query on a real 1x1 draw (see [`timer::warm_up`]), inside
    /// the caller's [`HostState`] guard.
    pub(super) fn warm_up_timer(&self) -> Result<()> {
        let gl = &self.gl;
        let texture = Texture::new(gl, 1, 1, TexelFormat::Rgba16F, Filter::Nearest, None)?;
        let target = Framebuffer::over(gl, &[&texture], "the timer warm-up")?;
        let program = self.compiled(ProgramKey::Diffuse {
            matched: false,
            layout: super::Layout::Premultiplied { chromatic: false },
        })?;
        self.enter_state();
        timer::warm_up(gl, || {
            target.bind_for_drawing();
            self.use_program(program);
            draw_fullscreen(gl);
        })
    }
}
