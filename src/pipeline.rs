//! The GPU haze pipeline of paper 000, sec. 4.2: N + 2 fragment passes over two float
//! textures whose bindings swap (no copies).
//!
//! 1. `premultiply.frag` writes F = τ·(E, 1) into target A.
//! 2. N × `diffuse.frag` reads one target and writes the other (eq. 11-12), neighbours
//!    read by one hardware-bilinear `texture()` fetch each; the per-pixel rate ρ lives in
//!    its own texture (bilinear too, for ρ(x + u)); the offset h_k(x) is computed from ρ(x)
//!    by the scheme's [`OffsetLaw`] (two uniforms per pass, and a compile-time switch).
//! 3. `composite.frag` writes F.rgb + (1 − F.a)·B into the free target, which is read back.
//!
//! Textures: image RGB32F and range R32F (texelFetch only); ping-pong targets and the rate
//! texture in the chosen precision (RGBA16F/R16F for `f16`, so that `f16` runs on drivers
//! without `OES_texture_float_linear`).

use crate::caps::Capabilities;
use crate::egl::{GlContext, Platform};
use crate::error::{Error, Result};
use crate::gpu::program::Program;
use crate::gpu::target::RenderTarget;
use crate::gpu::texture::{Filter, TexelFormat, Texture};
use crate::gpu::timer::{self, Clock, PassTimer, PassTimes, Rejected};
use crate::haze::RenderSpec;
use crate::raster::{Grid, RgbImage, RgbaImage, ScalarMap};
use crate::schedule::{OffsetLaw, Schedule};
use glow::HasContext;
use std::fmt;
use std::rc::Rc;
use std::str::FromStr;

/// Float precision of the diffusion textures.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// RGBA32F (IEEE single).
    #[default]
    F32,
    /// RGBA16F (IEEE half).
    F16,
}

impl Precision {
    /// Both precisions, f32 first.
    pub const ALL: [Precision; 2] = [Precision::F32, Precision::F16];

    /// `f32` or `f16`.
    pub fn name(self) -> &'static str {
        match self {
            Precision::F32 => "f32",
            Precision::F16 => "f16",
        }
    }

    fn colour_format(self) -> TexelFormat {
        match self {
            Precision::F32 => TexelFormat::Rgba32F,
            Precision::F16 => TexelFormat::Rgba16F,
        }
    }

    fn rate_format(self) -> TexelFormat {
        match self {
            Precision::F32 => TexelFormat::R32F,
            Precision::F16 => TexelFormat::R16F,
        }
    }
}

impl fmt::Display for Precision {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Precision {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Precision::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| Error::invalid("--precision", s, "f32 or f16"))
    }
}

/// The result of one render.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// Final linear RGB (alpha 1), row 0 at the top.
    pub image: RgbaImage,
    /// The schedule that ran.
    pub schedule: Schedule,
    /// Per-pass times, with the clock that produced them.
    pub times: PassTimes,
}

struct Programs {
    premultiply: Program,
    /// `diffuse.frag` for offsets h = t (euler, invariant).
    diffuse: Program,
    /// `diffuse.frag` for variance-matched offsets (matched).
    diffuse_matched: Program,
    composite: Program,
}

impl Programs {
    /// The diffusion program for `law`.
    fn diffuse(&self, law: &OffsetLaw) -> &Program {
        if law.matched {
            &self.diffuse_matched
        } else {
            &self.diffuse
        }
    }
}

/// The two ping-pong targets, kept between renders of the same size and precision.
struct Targets {
    pair: [RenderTarget; 2],
    width: usize,
    height: usize,
    precision: Precision,
}

/// A GL context with the programs compiled: renders any number of frames.
pub struct Renderer {
    // Field order is drop order: GL objects go before the context that owns them.
    programs: Programs,
    targets: Option<Targets>,
    vao: glow::VertexArray,
    caps: Capabilities,
    gl: Rc<glow::Context>,
    ctx: GlContext,
}

impl Renderer {
    /// Opens an EGL context (see [`GlContext::new`]), detects its capabilities once,
    /// compiles the shaders and spends the first timer query.
    pub fn new(platform: Option<Platform>) -> Result<Self> {
        let ctx = GlContext::new(platform)?;
        let caps = Capabilities::detect(&ctx);
        let gl = Rc::clone(ctx.gl());
        if caps.gles_version.0 < 3 {
            return Err(Error::MissingCapability {
                capability: "OpenGL ES 3.0".into(),
                renderer: caps.renderer.clone(),
                hint: format!("the context is {}; brume needs GLES 3.x", caps.version),
            });
        }
        let version_line = if caps.gles_version >= (3, 2) {
            "#version 320 es"
        } else {
            "#version 300 es"
        };
        let programs = Programs {
            premultiply: Program::new(
                &gl,
                version_line,
                ("premultiply.frag", include_str!("../glsl/premultiply.frag")),
                &["u_image", "u_range", "u_extinction"],
            )?,
            diffuse: diffuse_program(&gl, version_line, false)?,
            diffuse_matched: diffuse_program(&gl, version_line, true)?,
            composite: Program::new(
                &gl,
                version_line,
                ("composite.frag", include_str!("../glsl/composite.frag")),
                &["u_f", "u_airlight"],
            )?,
        };
        // SAFETY: an empty VAO is required to draw in GLES 3; owned and deleted in Drop.
        let vao = unsafe { gl.create_vertex_array().map_err(Error::Gl)? };
        // SAFETY: binding the VAO just created (the warm-up below draws with it).
        unsafe { gl.bind_vertex_array(Some(vao)) };
        if caps.disjoint_timer_query {
            warm_up_timer(&gl, &programs.composite)?;
        }
        Ok(Renderer {
            programs,
            targets: None,
            vao,
            caps,
            gl,
            ctx,
        })
    }

    /// The driver's capabilities, detected once.
    pub fn caps(&self) -> &Capabilities {
        &self.caps
    }

    /// The EGL context.
    pub fn context(&self) -> &GlContext {
        &self.ctx
    }

    /// The clock renders are timed with: the GPU timer where the driver has one.
    pub fn preferred_clock(&self) -> Clock {
        if self.caps.disjoint_timer_query {
            Clock::GpuTimer
        } else {
            Clock::Wall
        }
    }

    /// Renders `image` hazed by the normalised `range` map (R ∈ [0, 1]) as `spec` says.
    pub fn render(
        &mut self,
        image: &RgbImage,
        range: &ScalarMap,
        spec: &RenderSpec,
    ) -> Result<Rendered> {
        let schedule = spec.schedule()?;
        let rates = spec.packed_rates(range, &schedule);
        self.render_rates(image, range, &rates, spec, &schedule)
    }

    /// Like [`Self::render`] with the per-pixel rates of `schedule` already computed (the
    /// benchmarks reuse them across runs).
    pub fn render_rates(
        &mut self,
        image: &RgbImage,
        range: &ScalarMap,
        rates: &[f32],
        spec: &RenderSpec,
        schedule: &Schedule,
    ) -> Result<Rendered> {
        self.check_inputs(image, range, spec)?;
        assert_eq!(rates.len(), image.len(), "one rate per pixel");
        let inputs = Inputs::upload(&self.gl, image, range, rates, spec.precision)?;
        self.ensure_targets(image.width(), image.height(), spec.precision)?;
        let mut clock = self.preferred_clock();
        loop {
            let (last, outcome) = self.run_passes(&inputs, spec, schedule, clock)?;
            match outcome {
                Ok(times) => {
                    let pixels = self.targets()[last].read_rgba()?;
                    return Ok(Rendered {
                        image: Grid::from_vec(image.width(), image.height(), pixels),
                        schedule: *schedule,
                        times,
                    });
                }
                Err(rejected) => {
                    log::warn!(
                        "GPU timer figures rejected ({rejected:?}); timing again by wall clock"
                    );
                    clock = Clock::Wall;
                }
            }
        }
    }

    fn check_inputs(&self, image: &RgbImage, range: &ScalarMap, spec: &RenderSpec) -> Result<()> {
        spec.validate()?;
        self.caps.require_precision(spec.precision)?;
        self.caps
            .require_size("image", image.width(), image.height())?;
        if (image.width(), image.height()) != (range.width(), range.height()) {
            return Err(Error::SizeMismatch {
                a: "image".into(),
                aw: image.width() as u32,
                ah: image.height() as u32,
                b: "range map".into(),
                bw: range.width() as u32,
                bh: range.height() as u32,
            });
        }
        Ok(())
    }

    fn ensure_targets(&mut self, width: usize, height: usize, precision: Precision) -> Result<()> {
        let fits = self
            .targets
            .as_ref()
            .is_some_and(|t| (t.width, t.height, t.precision) == (width, height, precision));
        if !fits {
            self.targets = None; // free the old pair before allocating the new one
            let format = precision.colour_format();
            self.targets = Some(Targets {
                pair: [
                    RenderTarget::new(&self.gl, width, height, format)?,
                    RenderTarget::new(&self.gl, width, height, format)?,
                ],
                width,
                height,
                precision,
            });
        }
        Ok(())
    }

    fn targets(&self) -> &[RenderTarget; 2] {
        &self
            .targets
            .as_ref()
            .expect("targets allocated before passes")
            .pair
    }

    /// Runs the N + 2 passes; returns the index of the target holding the result.
    fn run_passes(
        &self,
        inputs: &Inputs,
        spec: &RenderSpec,
        schedule: &Schedule,
        clock: Clock,
    ) -> Result<(usize, std::result::Result<PassTimes, Rejected>)> {
        let gl = &self.gl;
        let targets = self.targets();
        let (w, h) = (inputs.image.width() as f32, inputs.image.height() as f32);
        // SAFETY: binding owned objects on the current context.
        unsafe {
            gl.bind_vertex_array(Some(self.vao));
            gl.disable(glow::BLEND);
        }
        let mut timer = PassTimer::start(gl, clock);

        let p = &self.programs.premultiply;
        timer.pass(|| {
            targets[0].bind_for_drawing();
            use_program(gl, p);
            inputs.image.bind(0);
            inputs.range.bind(1);
            // SAFETY: uniforms of the bound program.
            unsafe {
                gl.uniform_1_i32(Some(p.uniform("u_image")), 0);
                gl.uniform_1_i32(Some(p.uniform("u_range")), 1);
                gl.uniform_1_f32(Some(p.uniform("u_extinction")), spec.extinction as f32);
            }
            draw_fullscreen(gl);
        })?;

        let law = schedule.offset_law();
        let d = self.programs.diffuse(&law);
        let mut current = 0;
        for k in 0..schedule.steps {
            let (src, dst) = (current, 1 - current);
            timer.pass(|| {
                targets[dst].bind_for_drawing();
                use_program(gl, d);
                targets[src].texture().bind(0);
                inputs.rate.bind(1);
                let [scale, coefficient] = law.uniform(k);
                // SAFETY: uniforms of the bound program.
                unsafe {
                    gl.uniform_1_i32(Some(d.uniform("u_f")), 0);
                    gl.uniform_1_i32(Some(d.uniform("u_rate")), 1);
                    gl.uniform_2_f32(Some(d.uniform("u_law")), scale, coefficient);
                    gl.uniform_2_f32(Some(d.uniform("u_texel")), 1.0 / w, 1.0 / h);
                }
                draw_fullscreen(gl);
            })?;
            current = dst;
        }

        let c = &self.programs.composite;
        let out = 1 - current;
        timer.pass(|| {
            targets[out].bind_for_drawing();
            use_program(gl, c);
            targets[current].texture().bind(0);
            let b = spec.airlight;
            // SAFETY: uniforms of the bound program.
            unsafe {
                gl.uniform_1_i32(Some(c.uniform("u_f")), 0);
                gl.uniform_3_f32(Some(c.uniform("u_airlight")), b[0], b[1], b[2]);
            }
            draw_fullscreen(gl);
        })?;
        crate::gpu::check_gl(gl, "running the haze passes")?;
        Ok((out, timer.finish()?))
    }
}

impl Drop for Renderer {
    fn drop(&mut self) {
        // SAFETY: the VAO belongs to this renderer; the context is still alive (dropped
        // after this body, as the last field).
        unsafe { self.gl.delete_vertex_array(self.vao) };
    }
}

/// The textures uploaded for one render.
struct Inputs {
    image: Texture,
    range: Texture,
    rate: Texture,
}

impl Inputs {
    fn upload(
        gl: &Rc<glow::Context>,
        image: &RgbImage,
        range: &ScalarMap,
        rates: &[f32],
        precision: Precision,
    ) -> Result<Self> {
        let (w, h) = (image.width(), image.height());
        // Uploaded from the caller's buffers as they are: no staging copies.
        Ok(Inputs {
            image: Texture::new(
                gl,
                w,
                h,
                TexelFormat::Rgb32F,
                Filter::Nearest,
                Some(image.as_slice().as_flattened()),
            )?,
            range: Texture::new(
                gl,
                w,
                h,
                TexelFormat::R32F,
                Filter::Nearest,
                Some(range.as_slice()),
            )?,
            rate: Texture::new(
                gl,
                w,
                h,
                precision.rate_format(),
                Filter::Linear,
                Some(rates),
            )?,
        })
    }
}

/// `diffuse.frag` compiled with or without the variance-matched offsets.
fn diffuse_program(gl: &Rc<glow::Context>, version_line: &str, matched: bool) -> Result<Program> {
    Program::new(
        gl,
        &format!(
            "{version_line}\n#define VARIANCE_MATCHED {}",
            i32::from(matched)
        ),
        ("diffuse.frag", include_str!("../glsl/diffuse.frag")),
        &["u_f", "u_rate", "u_law", "u_texel"],
    )
}

/// Spends the first timer query on a real 1x1 draw (see [`timer::warm_up`]).
fn warm_up_timer(gl: &Rc<glow::Context>, program: &Program) -> Result<()> {
    let target = RenderTarget::new(gl, 1, 1, TexelFormat::Rgba16F)?;
    timer::warm_up(gl, || {
        target.bind_for_drawing();
        use_program(gl, program);
        draw_fullscreen(gl);
    })?;
    // SAFETY: unbinding on the current context before the target is dropped.
    unsafe { gl.bind_framebuffer(glow::FRAMEBUFFER, None) };
    Ok(())
}

fn use_program(gl: &glow::Context, p: &Program) {
    // SAFETY: an owned, linked program on the current context.
    unsafe { gl.use_program(Some(p.raw())) };
}

fn draw_fullscreen(gl: &glow::Context) {
    // SAFETY: the empty VAO is bound; the vertex shader uses gl_VertexID only.
    unsafe { gl.draw_arrays(glow::TRIANGLES, 0, 3) };
}
