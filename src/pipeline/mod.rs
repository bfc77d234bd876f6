//! The GPU pipeline on a host's GL context: the host's colour and depth (or range)
//! textures in, the host's framebuffer or texture out, N + 2 fragment passes between
//! (paper 000, sec. 4.2) over float textures whose bindings swap (no copies).
//!
//! 1. **Medium pass** (`medium.frag` + the medium's GLSL): per pixel, the medium gives τ
//!    and σ; the pass writes F = (τ·E, τ_r), the diffusion rate ρ(σ) and, for a chromatic
//!    medium only, (τ_g, τ_b) — three render targets in one pass.
//! 2. **N × diffusion** (`diffuse.frag`, eq. 11-12): each reads one target and writes the
//!    other, neighbours read by one hardware-bilinear fetch each, the rate bilinear too;
//!    the offset h_k(x) comes from ρ(x) by the scheme's [`crate::schedule::OffsetLaw`].
//! 3. **Composite** (`composite.frag` + the medium's GLSL): F.rgb + (1 − τ_blurred)·L∞
//!    into the host's destination, L∞ evaluated by the medium at each pixel.
//!
//! The CPU computes per-frame constants only (N, the offset law, the medium's uniforms).
//!
//! [`Pipeline::fog`] and [`Pipeline::blend_fog`] run the engine passes of papers 001 and
//! 003 instead (one or two passes; [`FogBlur`] describes them). A medium with a camera
//! ([`Medium::camera`]) gets the eye-to-fragment ray from the vertex shader and the depth
//! constants as uniforms ([`crate::camera`]).
//!
//! **An RGB τ through the blur.** The paper blurs one τ, in the alpha of the
//! pre-multiplied colour. brume keeps τ_r there; a chromatic medium adds a second target
//! pair (RG, the same precision) holding (τ_g, τ_b), written by multiple render targets
//! with the same weights and offsets, so every channel's τ is blurred exactly as its
//! colour is. A grey medium (τ_r = τ_g = τ_b) compiles the passes without it and costs
//! what paper 000's pipeline costs. (An approximation — blur one mean τ and rescale by
//! the sharp channel ratios — would be cheaper, but it is wrong at depth edges, exactly
//! where the blur matters.)
//!
//! # The host's contract
//!
//! - **Context.** [`Pipeline::new`] and every call run on the host's context, which must
//!   be current on the calling thread (OpenGL ES 3.0 or later; float render targets need
//!   `EXT_color_buffer_float` or `EXT_color_buffer_half_float`, see
//!   [`Capabilities::require_precision`]). brume never creates, makes current or destroys
//!   a context.
//!   All of brume's GL objects belong to that context: drop the pipeline while it is
//!   current (or share lists).
//! - **Textures in.** The colour texture (RGB in `.rgb`: float, or 8-bit; sRGB-encoded
//!   8-bit values are decoded if [`Input::colour_encoding`] says so, `SRGB8_ALPHA8` is
//!   decoded by GL itself) and the depth or range texture (`.r`: `R32F`, `R16F`,
//!   `DEPTH_COMPONENT*` with `TEXTURE_COMPARE_MODE` off …) are read with `texelFetch` at
//!   level 0, so they must be complete (a `MIN_FILTER` that needs no mipmaps, or a full
//!   chain). brume never deletes or modifies them.
//! - **Camera frames.** An image the host can bind only to `GL_TEXTURE_EXTERNAL_OES` (an
//!   Android `SurfaceTexture`, an `AHardwareBuffer`) goes through
//!   [`Pipeline::import_external`] first, which copies it into a texture the pipeline
//!   owns (see [`ExternalColour`]); that copy is the input's colour.
//! - **Out.** [`Output::Framebuffer`] draws the `width x height` result with its lower-left
//!   corner at (x, y) of a host framebuffer (`None`: the default framebuffer, a window);
//!   [`Output::Texture`] draws into level 0 of a host texture of a colour-renderable
//!   format. Row 0 of the input lands on row y of the destination: brume does not flip.
//! - **State changed and left.** A render binds its own framebuffers, program, vertex
//!   array, and textures on units 0-2 and a medium's lookups from unit 3 (with no
//!   sampler objects, except its own bilinear one for paper 001's Gaussian); it disables `BLEND`,
//!   `DEPTH_TEST`, `STENCIL_TEST`, `SCISSOR_TEST`, `CULL_FACE`, `RASTERIZER_DISCARD`,
//!   `SAMPLE_ALPHA_TO_COVERAGE` and `SAMPLE_COVERAGE`, and sets the colour mask to all
//!   channels. On return the framebuffer binding (draw and read) is 0, no program and no
//!   vertex array are bound, units 0-6 have no texture and no sampler, the active unit is
//!   `TEXTURE0`, the viewport is the output rectangle, and the capabilities above stay
//!   disabled. Anything else (blend functions, clear colour, pixel store, buffers) is left
//!   as it was. The host sets again whatever it needs, as with egui_glow's painter.
//!   [`Pipeline::import_external`] leaves the same state (the viewport on its copy) and
//!   unit 0's `GL_TEXTURE_EXTERNAL_OES` target empty.
//! - **Timing** ([`Pipeline::set_timing`]). [`Timing::Off`], the default: no query, no
//!   `glFinish`, no wait; a call returns once its commands are issued (the GPU may still
//!   be drawing), with its times unavailable. [`Timing::Deferred`]: a `GL_TIME_ELAPSED`
//!   query around each pass (query objects kept between calls, up to
//!   [`timer::DEFERRED_IN_FLIGHT`] calls in flight), read on a later call only once its
//!   results are in (never waited for); a call returns the newest earlier call's figures
//!   not yet returned ([`PassTimes::calls_ago`] says how many calls back), or unavailable
//!   times. [`Timing::Blocking`]: the call's own figures, waiting for its queries' results
//!   (or, without `GL_EXT_disjoint_timer_query`, `glFinish` after every pass);
//!   [`Timing::BlockingWall`] always by `glFinish` and the wall clock. Figures flagged
//!   disjoint (`GL_GPU_DISJOINT_EXT`) or that cannot be right are reported unavailable:
//!   passes are never run again (a second `blend_fog` would fog the host's frame twice).
//!   The first call that begins queries waits once for a 1x1 draw ([`timer::warm_up`]).
//!   With queries, brume reads `GL_GPU_DISJOINT_EXT`, which clears it for the host too.
//! - **A host's own query.** If a `GL_TIME_ELAPSED` query is open when a call starts
//!   (`glGetQueryiv(GL_TIME_ELAPSED, GL_CURRENT_QUERY)` non-zero), brume begins none of its
//!   own for that call (its times are unavailable, except by the wall clock) and never ends,
//!   reads or deletes the host's; the host's query then measures brume's passes with its own
//!   work. Where `glGetQueryiv` cannot be found ([`timer::HostQueryProbe`]) brume begins no
//!   query at all: deferred times are unavailable, blocking ones by the wall clock.

mod engine;
mod external;
mod refine;

use engine::{EngineKey, EngineTargets};
pub use engine::{FogBlur, GaussBlur, GAUSS_WEIGHTS};
pub use external::{ExternalColour, IDENTITY, TEXTURE_BINDING_EXTERNAL_OES, TEXTURE_EXTERNAL_OES};
pub use refine::RefineInput;

use crate::blur::{Blur, Precision};
use crate::caps::Capabilities;
use crate::error::{Error, Result};
use crate::gpu::framebuffer::Framebuffer;
use crate::gpu::program::Program;
use crate::gpu::texture::{Filter, TexelFormat, Texture};
use crate::gpu::timer::{self, Clock, PassTimer, PassTimes, Timekeeper, Timing};
use crate::medium::{Lookup, Medium, UniformValue, Wrap, MAX_LOOKUPS, MEDIUM_API_GLSL};
use crate::schedule::{Schedule, Scheme};
use glow::HasContext;
use std::collections::HashMap;
use std::sync::Arc;

const PRELUDE_GLSL: &str = include_str!("../../glsl/prelude.glsl");
const MEDIUM_FRAG: &str = include_str!("../../glsl/medium.frag");
const DIFFUSE_FRAG: &str = include_str!("../../glsl/diffuse.frag");
const COMPOSITE_FRAG: &str = include_str!("../../glsl/composite.frag");

/// Texture units: the pipeline binds these, then a medium's lookups from `UNIT_LOOKUP`.
const UNIT_MAIN: u32 = 0;
const UNIT_DEPTH: u32 = 1;
const UNIT_SECOND: u32 = 2;
const UNIT_LOOKUP: u32 = 3;
const UNITS_USED: u32 = UNIT_LOOKUP + MAX_LOOKUPS as u32;

/// Capabilities disabled for the passes (see the module docs).
const DISABLED: [u32; 8] = [
    glow::BLEND,
    glow::DEPTH_TEST,
    glow::STENCIL_TEST,
    glow::SCISSOR_TEST,
    glow::CULL_FACE,
    glow::RASTERIZER_DISCARD,
    glow::SAMPLE_ALPHA_TO_COVERAGE,
    glow::SAMPLE_COVERAGE,
];

/// How colour values are encoded in a host texture or framebuffer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Encoding {
    /// Linear light (float textures, `SRGB8_ALPHA8`, which GL converts itself).
    #[default]
    Linear,
    /// sRGB-encoded values in a format GL does not convert (plain `RGBA8`).
    Srgb,
}

/// The host's textures for one frame. Not owned: brume never deletes them.
#[derive(Clone, Copy, Debug)]
pub struct Input {
    /// Colour, RGB in `.rgb`.
    pub colour: glow::Texture,
    /// How `colour` is encoded.
    pub colour_encoding: Encoding,
    /// Depth or range in `.r`, as the medium expects it.
    pub depth: glow::Texture,
    /// Width of both textures (px).
    pub width: usize,
    /// Height of both textures (px).
    pub height: usize,
}

/// Where the result goes. Not owned: brume never deletes it.
#[derive(Clone, Copy, Debug)]
pub enum Output {
    /// A host framebuffer (`None`: the default framebuffer), the result's lower-left
    /// corner at (`x`, `y`).
    Framebuffer {
        /// The framebuffer object.
        framebuffer: Option<glow::Framebuffer>,
        /// Left edge of the output rectangle (px).
        x: i32,
        /// Bottom edge of the output rectangle (px).
        y: i32,
        /// How to encode the colour written.
        encoding: Encoding,
    },
    /// Level 0 of a host texture of the input's size and a colour-renderable format.
    Texture {
        /// The texture object.
        texture: glow::Texture,
        /// How to encode the colour written.
        encoding: Encoding,
    },
}

/// What one render did.
#[derive(Clone, Debug)]
pub struct Frame {
    /// The schedule that ran.
    pub schedule: Schedule,
    /// Per-pass times (N + 2 for a render), with the clock that produced them, as
    /// [`Pipeline::timing`] gives them: this call's, an earlier call's
    /// ([`PassTimes::calls_ago`]), or unavailable ([`PassTimes::is_available`]).
    pub times: PassTimes,
}

/// Which program: the medium's two passes are compiled per medium, and every pass per
/// grey or chromatic τ.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum ProgramKey {
    Medium {
        medium: &'static str,
        chromatic: bool,
        log_rate: bool,
        half_rate: bool,
    },
    Diffuse {
        matched: bool,
        chromatic: bool,
    },
    Composite {
        medium: &'static str,
        chromatic: bool,
    },
    /// An engine pass (see [`engine`]) of a medium.
    Engine(&'static str, EngineKey),
    /// The import of an external image (see [`external`]).
    ExternalImport,
    /// A pass of the image-guided refinement (see [`refine`]).
    Refine(refine::RefinePass),
}

/// The diffusion textures, kept between frames of the same size, precision and kind of τ.
struct Targets {
    width: usize,
    height: usize,
    precision: Precision,
    chromatic: bool,
    /// Pre-multiplied colour F, ping-pong.
    f: [Texture; 2],
    /// (τ_g, τ_b) of a chromatic medium, ping-pong.
    tau_gb: Option<[Texture; 2]>,
    /// Per-pixel rate ρ.
    rate: Texture,
    /// The medium pass's destination: F[0], ρ and (τ_g, τ_b)[0].
    first: Framebuffer,
    /// The diffusion passes' destinations: F[i] and (τ_g, τ_b)[i].
    step: [Framebuffer; 2],
}

impl Targets {
    fn new(
        gl: &Arc<glow::Context>,
        width: usize,
        height: usize,
        precision: Precision,
        chromatic: bool,
    ) -> Result<Self> {
        let target = |format| Texture::new(gl, width, height, format, Filter::Linear, None);
        let f = [
            target(precision.colour_format())?,
            target(precision.colour_format())?,
        ];
        let tau_gb = if chromatic {
            Some([
                target(precision.pair_format())?,
                target(precision.pair_format())?,
            ])
        } else {
            None
        };
        let rate = target(precision.rate_format())?;
        let pair = |i: usize| tau_gb.as_ref().map(|p| &p[i]);
        let first = Framebuffer::over(
            gl,
            &attachments(&[&f[0], &rate], pair(0)),
            "the medium pass",
        )?;
        let step = [
            Framebuffer::over(gl, &attachments(&[&f[0]], pair(0)), "a diffusion pass")?,
            Framebuffer::over(gl, &attachments(&[&f[1]], pair(1)), "a diffusion pass")?,
        ];
        Ok(Targets {
            width,
            height,
            precision,
            chromatic,
            f,
            tau_gb,
            rate,
            first,
            step,
        })
    }

    fn fits(&self, width: usize, height: usize, precision: Precision, chromatic: bool) -> bool {
        (self.width, self.height, self.precision, self.chromatic)
            == (width, height, precision, chromatic)
    }
}

/// The medium pass's program for this frame.
fn medium_key(
    medium: &dyn Medium,
    precision: Precision,
    schedule: &Schedule,
    chromatic: bool,
) -> ProgramKey {
    ProgramKey::Medium {
        medium: medium.name(),
        chromatic,
        log_rate: schedule.scheme != Scheme::Euler,
        half_rate: precision == Precision::F16,
    }
}

/// `textures`, then `pair` if there is one: a framebuffer's attachments in order.
fn attachments<'a>(textures: &[&'a Texture], pair: Option<&'a Texture>) -> Vec<&'a Texture> {
    textures.iter().copied().chain(pair).collect()
}

/// Where the composite pass draws.
enum Destination<'a> {
    /// A host framebuffer at (x, y).
    Host {
        framebuffer: Option<glow::Framebuffer>,
        x: i32,
        y: i32,
        encoding: Encoding,
    },
    /// brume's framebuffer over a host texture.
    HostTexture(&'a Framebuffer, Encoding),
    /// brume's free ping-pong target, to be read back ([`crate::Renderer`]).
    Internal,
}

/// The brume pipeline on a host's GL context: compiles its programs once, keeps its
/// diffusion textures between frames, and renders any number of frames.
pub struct Pipeline {
    // Field order is drop order; `gl` last, as the objects above need it.
    programs: HashMap<ProgramKey, Program>,
    targets: Option<Targets>,
    /// The lookups of the last medium rendered, uploaded, by [`Lookup::id`].
    lookups: HashMap<u64, Texture>,
    engine_targets: Option<EngineTargets>,
    /// The framebuffer over the host's output texture ([`Output::Texture`]), re-attached
    /// each frame.
    host_target: Option<Framebuffer>,
    /// The timing option, its queries (reused from frame to frame) and the deferred calls
    /// in flight.
    timekeeper: Timekeeper,
    /// A 1x1 target cleared before a software renderer's timed call ([`Pipeline::timed`]),
    /// made with the first query.
    timer_anchor: std::cell::OnceCell<(Texture, Framebuffer)>,
    /// The copy of the last external image imported ([`Pipeline::import_external`]).
    imported: Option<external::ImportTarget>,
    /// LINEAR, CLAMP_TO_EDGE: the Gaussian's bilinear taps, whatever the texture's own
    /// filter.
    linear_sampler: glow::Sampler,
    vao: glow::VertexArray,
    caps: Capabilities,
    version_line: &'static str,
    gl: Arc<glow::Context>,
}

impl Pipeline {
    /// Builds the pipeline on the host's context `gl`, which must be current on this
    /// thread: detects its capabilities once and compiles the diffusion programs. Timing
    /// is [`Timing::Off`]: see [`Pipeline::set_timing`].
    pub fn new(gl: Arc<glow::Context>) -> Result<Self> {
        let caps = Capabilities::detect(&gl);
        if caps.gles_version.0 < 3 {
            return Err(Error::MissingCapability {
                capability: "OpenGL ES 3.0".into(),
                renderer: caps.renderer.clone(),
                hint: format!("the context is {}; brume needs GLES 3.x", caps.version),
            });
        }
        // GLSL ES 3.20 only on a GLES 3.2 context: a desktop context reports 4.x and
        // takes ES shaders at 3.00 (ARB_ES3_compatibility).
        let version_line = if gl.version().is_embedded && caps.gles_version >= (3, 2) {
            "#version 320 es"
        } else {
            "#version 300 es"
        };
        // SAFETY: an empty VAO is required to draw in GLES 3; owned and deleted in Drop.
        let vao = unsafe { gl.create_vertex_array().map_err(Error::Gl)? };
        crate::gpu::object_created();
        let linear_sampler = match linear_sampler(&gl) {
            Ok(s) => s,
            Err(e) => {
                // SAFETY: the VAO made just above, on the current context.
                unsafe { gl.delete_vertex_array(vao) };
                crate::gpu::object_deleted();
                return Err(e);
            }
        };
        let mut pipeline = Pipeline {
            programs: HashMap::new(),
            targets: None,
            lookups: HashMap::new(),
            engine_targets: None,
            host_target: None,
            timekeeper: Timekeeper::new(&gl, caps.disjoint_timer_query),
            imported: None,
            timer_anchor: std::cell::OnceCell::new(),
            linear_sampler,
            vao,
            caps,
            version_line,
            gl,
        };
        for matched in [false, true] {
            pipeline.program(
                ProgramKey::Diffuse {
                    matched,
                    chromatic: false,
                },
                None,
            )?;
        }
        Ok(pipeline)
    }

    /// The driver's capabilities, detected once.
    pub fn caps(&self) -> &Capabilities {
        &self.caps
    }

    /// Mutable capabilities, for an owner that knows more (brume's headless context adds
    /// its EGL facts).
    pub(crate) fn caps_mut(&mut self) -> &mut Capabilities {
        &mut self.caps
    }

    /// Bytes per pixel of the textures the pipeline allocates for a frame: two colour
    /// targets, the rate, and for a chromatic medium two (τ_g, τ_b) targets.
    pub fn bytes_per_pixel(precision: Precision, chromatic: bool) -> u64 {
        let texel = |format: TexelFormat| format.bytes_per_texel() as u64;
        let pair = if chromatic {
            2 * texel(precision.pair_format())
        } else {
            0
        };
        2 * texel(precision.colour_format()) + texel(precision.rate_format()) + pair
    }

    /// The host's context.
    pub fn gl(&self) -> &Arc<glow::Context> {
        &self.gl
    }

    /// The clock [`Timing::Blocking`] times with: the GPU timer where the driver has one.
    pub fn preferred_clock(&self) -> Clock {
        self.timekeeper.preferred_clock()
    }

    /// Sets when calls time their passes (module docs, *Timing*): [`Timing::Off`] (the
    /// default), [`Timing::Deferred`], [`Timing::Blocking`] or [`Timing::BlockingWall`].
    /// Deferred figures not yet returned are dropped when the option changes. Makes no GL
    /// call.
    pub fn set_timing(&mut self, timing: Timing) {
        self.timekeeper.set_timing(timing);
    }

    /// When calls time their passes.
    pub fn timing(&self) -> Timing {
        self.timekeeper.timing()
    }

    /// For tests: the next timer figures read are rejected as if the driver had flagged a
    /// disjoint event (`GL_GPU_DISJOINT_EXT`), as phones' drivers do.
    #[doc(hidden)]
    pub fn simulate_disjoint(&self) {
        self.timekeeper.simulate_disjoint();
    }

    /// The `GL_TIME_ELAPSED` queries this pipeline has begun (none with
    /// [`Timing::Off`]): what a host or a test checks.
    pub fn queries_begun(&self) -> u64 {
        self.timekeeper.queries_begun()
    }

    /// Renders one frame: `input` fogged by `medium` and blurred as `blur` says, into
    /// `output`. The host's context must be current; see the module docs for the GL state
    /// this changes.
    pub fn render(
        &mut self,
        input: &Input,
        medium: &dyn Medium,
        blur: &Blur,
        output: &Output,
    ) -> Result<Frame> {
        let schedule = self.prepare(input, medium, blur)?;
        let result = self.with_output(input, output, |pipeline, destination| {
            Ok(pipeline.run(input, medium, &schedule, destination)?.0)
        });
        self.leave_state();
        Ok(Frame {
            schedule,
            times: result?,
        })
    }

    /// Renders into brume's own float target and reads it back (RGBA, texel row 0
    /// first): the CPU-buffer path of [`crate::Renderer`].
    pub(crate) fn render_and_read(
        &mut self,
        input: &Input,
        medium: &dyn Medium,
        blur: &Blur,
    ) -> Result<(Frame, Vec<[f32; 4]>)> {
        let schedule = self.prepare(input, medium, blur)?;
        let result = self
            .run(input, medium, &schedule, &Destination::Internal)
            .and_then(|(times, out)| {
                let pixels = self.targets()?.step[out].read_rgba()?;
                Ok((times, pixels))
            });
        self.leave_state();
        let (times, pixels) = result?;
        Ok((Frame { schedule, times }, pixels))
    }

    /// Checks the frame, plans its schedule, compiles what it needs and sizes the targets.
    fn prepare(&mut self, input: &Input, medium: &dyn Medium, blur: &Blur) -> Result<Schedule> {
        let schedule = blur.schedule_for(medium)?;
        self.caps.require_precision(blur.precision)?;
        self.caps.require_size("input", input.width, input.height)?;
        let chromatic = medium.chromatic();
        let keys = [
            medium_key(medium, blur.precision, &schedule, chromatic),
            ProgramKey::Diffuse {
                matched: schedule.scheme == Scheme::Matched,
                chromatic,
            },
            ProgramKey::Composite {
                medium: medium.name(),
                chromatic,
            },
        ];
        for key in keys {
            self.program(key, Some(medium))?;
        }
        self.check_medium_uniforms(medium, keys[0], keys[2])?;
        self.upload_lookups(medium)?;
        let fits = self
            .targets
            .as_ref()
            .is_some_and(|t| t.fits(input.width, input.height, blur.precision, chromatic));
        if !fits {
            self.targets = None; // free the old textures before allocating new ones
            self.targets = Some(Targets::new(
                &self.gl,
                input.width,
                input.height,
                blur.precision,
                chromatic,
            )?);
        }
        Ok(schedule)
    }

    /// Runs the passes, timed as [`Pipeline::timing`] says. Returns the times and the
    /// index of the ping-pong target holding an internal result.
    fn run(
        &self,
        input: &Input,
        medium: &dyn Medium,
        schedule: &Schedule,
        destination: &Destination,
    ) -> Result<(PassTimes, usize)> {
        self.timed("running the passes", |pipeline, timer| {
            pipeline.run_passes(input, medium, schedule, destination, timer)
        })
    }

    /// Runs `passes` (which return the index of the target holding an internal result, or
    /// nothing) once, timed as [`Pipeline::timing`] says: the figures are this call's, an
    /// earlier call's ([`Timing::Deferred`]) or unavailable, never a second run's. `what`
    /// names the passes in a GL error.
    fn timed<T>(
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

    /// Runs `run` with the destination `output` names.
    fn with_output(
        &mut self,
        input: &Input,
        output: &Output,
        run: impl FnOnce(&Self, &Destination) -> Result<PassTimes>,
    ) -> Result<PassTimes> {
        match *output {
            Output::Framebuffer {
                framebuffer,
                x,
                y,
                encoding,
            } => run(
                self,
                &Destination::Host {
                    framebuffer,
                    x,
                    y,
                    encoding,
                },
            ),
            Output::Texture { texture, encoding } => {
                let what = "the output texture";
                let (w, h) = (input.width, input.height);
                let mut fb = match self.host_target.take() {
                    Some(mut fb) => {
                        let attached = fb.attach(Some(texture), w, h, what);
                        self.host_target = Some(fb);
                        attached?;
                        self.host_target.take().expect("put back just above")
                    }
                    None => Framebuffer::new(&self.gl, &[texture], w, h, what)?,
                };
                let result = run(self, &Destination::HostTexture(&fb, encoding));
                // Detached so that brume holds no reference to the host's texture.
                let detached = fb.attach(None, w, h, what);
                self.host_target = Some(fb);
                let times = result?;
                detached?;
                Ok(times)
            }
        }
    }

    /// The N + 2 passes, timed by `timer`; returns the ping-pong target that is free for
    /// an internal result.
    fn run_passes(
        &self,
        input: &Input,
        medium: &dyn Medium,
        schedule: &Schedule,
        destination: &Destination,
        timer: &mut PassTimer,
    ) -> Result<usize> {
        let gl = &self.gl;
        let targets = self.targets()?;
        let chromatic = targets.tau_gb.is_some();

        let p = self.compiled(medium_key(medium, targets.precision, schedule, chromatic))?;
        timer.pass(|| {
            targets.first.bind_for_drawing();
            self.use_program(p);
            bind_texture(gl, UNIT_MAIN, Some(input.colour));
            bind_texture(gl, UNIT_DEPTH, Some(input.depth));
            set_int(gl, p, "u_colour", UNIT_MAIN as i32);
            set_int(gl, p, "u_depth", UNIT_DEPTH as i32);
            set_int(
                gl,
                p,
                "u_colour_srgb",
                i32::from(input.colour_encoding == Encoding::Srgb),
            );
            let inverse_steps = if schedule.steps == 0 {
                0.0
            } else {
                1.0 / f64::from(schedule.steps)
            };
            set_value(
                gl,
                p,
                "u_schedule",
                UniformValue::Vec2([schedule.sigma_max as f32, inverse_steps as f32]),
            );
            self.set_medium_uniforms(p, medium, input, schedule.sigma0);
            draw_fullscreen(gl);
        })?;

        let law = schedule.offset_law();
        let d = self.compiled(ProgramKey::Diffuse {
            matched: law.matched,
            chromatic,
        })?;
        let texel = [1.0 / input.width as f32, 1.0 / input.height as f32];
        let mut current = 0;
        for k in 0..schedule.steps {
            let (src, dst) = (current, 1 - current);
            timer.pass(|| {
                targets.step[dst].bind_for_drawing();
                self.use_program(d);
                targets.f[src].bind(UNIT_MAIN);
                targets.rate.bind(UNIT_DEPTH);
                if let Some(pair) = &targets.tau_gb {
                    pair[src].bind(UNIT_SECOND);
                }
                let [scale, coefficient] = law.uniform(k);
                set_int(gl, d, "u_f", UNIT_MAIN as i32);
                set_int(gl, d, "u_rate", UNIT_DEPTH as i32);
                set_int(gl, d, "u_tau_gb", UNIT_SECOND as i32);
                set_value(gl, d, "u_law", UniformValue::Vec2([scale, coefficient]));
                set_value(gl, d, "u_texel", UniformValue::Vec2(texel));
                draw_fullscreen(gl);
            })?;
            current = dst;
        }

        let c = self.compiled(ProgramKey::Composite {
            medium: medium.name(),
            chromatic,
        })?;
        let free = 1 - current;
        timer.pass(|| {
            let (origin, encoding) = self.bind_destination(destination, input, &targets.step[free]);
            self.use_program(c);
            targets.f[current].bind(UNIT_MAIN);
            bind_texture(gl, UNIT_DEPTH, Some(input.depth));
            if let Some(pair) = &targets.tau_gb {
                pair[current].bind(UNIT_SECOND);
            }
            set_int(gl, c, "u_f", UNIT_MAIN as i32);
            set_int(gl, c, "u_depth", UNIT_DEPTH as i32);
            set_int(gl, c, "u_tau_gb", UNIT_SECOND as i32);
            set_value(gl, c, "u_origin", UniformValue::IVec2(origin));
            set_int(
                gl,
                c,
                "u_output_srgb",
                i32::from(encoding == Encoding::Srgb),
            );
            self.set_medium_uniforms(c, medium, input, schedule.sigma0);
            draw_fullscreen(gl);
        })?;
        Ok(free)
    }

    /// Binds the composite's destination and sets its viewport; returns the output
    /// rectangle's corner and the encoding to write.
    fn bind_destination(
        &self,
        destination: &Destination,
        input: &Input,
        internal: &Framebuffer,
    ) -> ([i32; 2], Encoding) {
        match *destination {
            Destination::Host {
                framebuffer,
                x,
                y,
                encoding,
            } => {
                // SAFETY: binding the host's framebuffer (or the default one) and setting
                // the viewport on the current context.
                unsafe {
                    self.gl.bind_framebuffer(glow::FRAMEBUFFER, framebuffer);
                    self.gl
                        .viewport(x, y, input.width as i32, input.height as i32);
                }
                ([x, y], encoding)
            }
            Destination::HostTexture(fb, encoding) => {
                fb.bind_for_drawing();
                ([0, 0], encoding)
            }
            Destination::Internal => {
                internal.bind_for_drawing();
                ([0, 0], Encoding::Linear)
            }
        }
    }

    fn targets(&self) -> Result<&Targets> {
        self.targets
            .as_ref()
            .ok_or_else(|| Error::Gl("internal: diffusion targets not allocated".into()))
    }

    fn compiled(&self, key: ProgramKey) -> Result<&Program> {
        self.programs
            .get(&key)
            .ok_or_else(|| Error::Gl(format!("internal: program {key:?} not compiled")))
    }

    /// The program for `key`, compiled on first use (`medium` is needed for the medium
    /// and composite passes).
    fn program(&mut self, key: ProgramKey, medium: Option<&dyn Medium>) -> Result<&Program> {
        if !self.programs.contains_key(&key) {
            let program = self.compile(key, medium)?;
            self.programs.insert(key, program);
        }
        self.compiled(key)
    }

    fn compile(&self, key: ProgramKey, medium: Option<&dyn Medium>) -> Result<Program> {
        let defines = |pairs: &[(&str, bool)]| {
            let mut header = self.version_line.to_string();
            for (name, on) in pairs {
                header.push_str(&format!("\n#define {name} {}", i32::from(*on)));
            }
            header.push('\n');
            header.push_str(PRELUDE_GLSL);
            header
        };
        let with_medium = |pass: &str| {
            let m = medium.expect("the medium passes need a medium");
            format!("{MEDIUM_API_GLSL}\n{}\n{pass}", m.glsl())
        };
        let names = |pass: &str| {
            let m = medium.expect("the medium passes need a medium");
            format!("{pass} with glsl/medium/{}.glsl", m.name())
        };
        let optional = |extra: &[&'static str]| {
            let mut list: Vec<&'static str> = MEDIUM_API_UNIFORMS.to_vec();
            list.extend_from_slice(extra);
            if let Some(m) = medium {
                list.extend(m.uniforms().into_iter().map(|(name, _)| name));
                list.extend(m.lookups().into_iter().map(|(name, _)| name));
            }
            list
        };
        match key {
            ProgramKey::Medium {
                chromatic,
                log_rate,
                half_rate,
                ..
            } => Program::new(
                &self.gl,
                &defines(&[
                    ("CHROMATIC", chromatic),
                    ("RATE_LAW_LOG", log_rate),
                    ("RATE_HALF", half_rate),
                ]),
                (&names("medium.frag"), &with_medium(MEDIUM_FRAG)),
                &["u_colour"],
                &optional(&["u_depth", "u_colour_srgb", "u_schedule"]),
            ),
            ProgramKey::Diffuse { matched, chromatic } => Program::new(
                &self.gl,
                &defines(&[("VARIANCE_MATCHED", matched), ("CHROMATIC", chromatic)]),
                ("diffuse.frag", DIFFUSE_FRAG),
                &["u_f", "u_rate", "u_law", "u_texel"],
                &["u_tau_gb"],
            ),
            ProgramKey::Composite { chromatic, .. } => Program::new(
                &self.gl,
                &defines(&[("CHROMATIC", chromatic)]),
                (&names("composite.frag"), &with_medium(COMPOSITE_FRAG)),
                &["u_f"],
                &optional(&["u_depth", "u_tau_gb", "u_origin", "u_output_srgb"]),
            ),
            ProgramKey::Engine(_, key) => {
                let (file, source, pairs) = key.source();
                let gauss = if key.needs_gauss() {
                    engine::GAUSS5
                } else {
                    ""
                };
                Program::new(
                    &self.gl,
                    &defines(&pairs),
                    (&names(file), &with_medium(&format!("{gauss}\n{source}"))),
                    &[],
                    &optional(&engine::ENGINE_UNIFORMS),
                )
            }
            ProgramKey::ExternalImport => external::compile(&self.gl, self.version_line),
            ProgramKey::Refine(pass) => {
                refine::compile(&self.gl, self.version_line, PRELUDE_GLSL, pass)
            }
        }
    }

    /// A medium uniform that neither of its passes uses is misspelled (or dead): say so
    /// instead of rendering with a default value.
    fn check_medium_uniforms(
        &self,
        medium: &dyn Medium,
        first: ProgramKey,
        last: ProgramKey,
    ) -> Result<()> {
        let (first, last) = (self.compiled(first)?, self.compiled(last)?);
        for (name, _) in medium.uniforms() {
            if first.optional_uniform(name).is_none() && last.optional_uniform(name).is_none() {
                return Err(Error::Gl(format!(
                    "glsl/medium/{}.glsl: uniform {name} is not used by the shader \
                     (misspelled, or not declared)",
                    medium.name()
                )));
            }
        }
        Ok(())
    }

    /// Sets the medium's uniforms, the pipeline's `brume_*` ones and the camera's, and
    /// binds the medium's lookups, for the bound program `p`.
    fn set_medium_uniforms(&self, p: &Program, medium: &dyn Medium, input: &Input, sigma0: f64) {
        let gl = &self.gl;
        set_value(gl, p, "brume_sigma0", UniformValue::Float(sigma0 as f32));
        set_value(
            gl,
            p,
            "brume_size",
            UniformValue::IVec2([input.width as i32, input.height as i32]),
        );
        for (name, value) in camera_uniforms(medium, input.width, input.height) {
            set_value(gl, p, name, value);
        }
        for (name, value) in medium.uniforms() {
            set_value(gl, p, name, value);
        }
        for (unit, (name, lookup)) in (UNIT_LOOKUP..).zip(medium.lookups()) {
            if let Some(texture) = self.lookups.get(&lookup.id()) {
                texture.bind(unit);
                set_int(gl, p, name, unit as i32);
            }
        }
    }

    /// Uploads the medium's lookups not yet on the GPU, and frees those of earlier media.
    fn upload_lookups(&mut self, medium: &dyn Medium) -> Result<()> {
        let lookups = medium.lookups();
        if lookups.len() > MAX_LOOKUPS {
            return Err(Error::Gl(format!(
                "glsl/medium/{}.glsl: {} lookup textures, at most {MAX_LOOKUPS}",
                medium.name(),
                lookups.len()
            )));
        }
        self.lookups
            .retain(|id, _| lookups.iter().any(|(_, l)| l.id() == *id));
        for (_, lookup) in lookups {
            if !self.lookups.contains_key(&lookup.id()) {
                let texture = upload_lookup(&self.gl, &lookup)?;
                self.lookups.insert(lookup.id(), texture);
            }
        }
        Ok(())
    }

    fn use_program(&self, p: &Program) {
        // SAFETY: an owned, linked program on the current context.
        unsafe { self.gl.use_program(Some(p.raw())) };
    }

    /// The state every pass relies on (module docs).
    fn enter_state(&self) {
        let gl = &self.gl;
        // SAFETY: state setters on the current context; the VAO is owned.
        unsafe {
            gl.bind_vertex_array(Some(self.vao));
            for cap in DISABLED {
                gl.disable(cap);
            }
            gl.color_mask(true, true, true, true);
            for unit in 0..UNITS_USED {
                gl.bind_sampler(unit, None);
            }
        }
    }

    /// The state a render leaves (module docs).
    fn leave_state(&self) {
        let gl = &self.gl;
        // SAFETY: unbinding on the current context.
        unsafe {
            gl.bind_framebuffer(glow::FRAMEBUFFER, None);
            gl.use_program(None);
            gl.bind_vertex_array(None);
            for unit in 0..UNITS_USED {
                bind_texture(gl, unit, None);
                gl.bind_sampler(unit, None);
            }
            gl.active_texture(glow::TEXTURE0);
        }
    }

    /// llvmpipe records the start of a TIME_ELAPSED query in the scene of the framebuffer
    /// its state last validated; when that framebuffer has since been deleted (a
    /// texture made and dropped between calls: a host's target, the refinement's
    /// output), the query's start is never recorded and its figure comes back as about
    /// the system uptime (rejected, so unavailable). Clearing brume's own 1x1 target
    /// first gives the query's beginning a live framebuffer. (Measured on Mesa 22.3.)
    fn anchor_timer(&self) -> Result<()> {
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

    /// Spends the first timer query on a real 1x1 draw (see [`timer::warm_up`]).
    fn warm_up_timer(&self) -> Result<()> {
        let gl = &self.gl;
        let texture = Texture::new(gl, 1, 1, TexelFormat::Rgba16F, Filter::Nearest, None)?;
        let target = Framebuffer::over(gl, &[&texture], "the timer warm-up")?;
        let program = self.compiled(ProgramKey::Diffuse {
            matched: false,
            chromatic: false,
        })?;
        self.enter_state();
        let warmed = timer::warm_up(gl, || {
            target.bind_for_drawing();
            self.use_program(program);
            draw_fullscreen(gl);
        });
        self.leave_state();
        warmed
    }
}

impl Drop for Pipeline {
    fn drop(&mut self) {
        // SAFETY: the VAO and the sampler belong to this pipeline, on the host's context
        // (module docs).
        unsafe {
            self.gl.delete_vertex_array(self.vao);
            self.gl.delete_sampler(self.linear_sampler);
        }
        crate::gpu::object_deleted();
        crate::gpu::object_deleted();
    }
}

/// A sampler object with bilinear filtering and clamped edges, counted as a GL object.
fn linear_sampler(gl: &glow::Context) -> Result<glow::Sampler> {
    // SAFETY: sampler creation and parameters on the current context.
    unsafe {
        let sampler = gl.create_sampler().map_err(Error::Gl)?;
        for (param, value) in [
            (glow::TEXTURE_MIN_FILTER, glow::LINEAR),
            (glow::TEXTURE_MAG_FILTER, glow::LINEAR),
            (glow::TEXTURE_WRAP_S, glow::CLAMP_TO_EDGE),
            (glow::TEXTURE_WRAP_T, glow::CLAMP_TO_EDGE),
        ] {
            gl.sampler_parameter_i32(sampler, param, value as i32);
        }
        crate::gpu::object_created();
        Ok(sampler)
    }
}

/// The uniforms of `glsl/medium_api.glsl` and `glsl/fullscreen.vert` that the pipeline
/// sets for every medium pass (unused ones are optimised out).
const MEDIUM_API_UNIFORMS: [&str; 5] = [
    "brume_sigma0",
    "brume_size",
    "brume_corner_rays",
    "brume_depth_constants",
    "brume_eye",
];

/// The camera's per-frame constants (see [`crate::camera`]); zero without a camera.
fn camera_uniforms(
    medium: &dyn Medium,
    width: usize,
    height: usize,
) -> [(&'static str, UniformValue); 3] {
    let (rays, constants, eye) = match medium.camera() {
        Some(camera) => {
            let corners = camera.corner_rays(width as f64 / height as f64);
            let mut rays = [0f32; 9];
            for (i, ray) in corners.iter().enumerate() {
                rays[3 * i..3 * i + 3].copy_from_slice(&ray.as_vec3().to_array());
            }
            let [a, b] = camera.shader_depth_constants();
            (
                rays,
                [a as f32, b as f32],
                camera.position.map(|v| v as f32),
            )
        }
        None => ([0.0; 9], [0.0; 2], [0.0; 3]),
    };
    [
        ("brume_corner_rays", UniformValue::Mat3(rays)),
        ("brume_depth_constants", UniformValue::Vec2(constants)),
        ("brume_eye", UniformValue::Vec3(eye)),
    ]
}

/// A lookup as an `R32F` bilinear texture with its wrap mode.
fn upload_lookup(gl: &Arc<glow::Context>, lookup: &Lookup) -> Result<Texture> {
    let texture = Texture::new(
        gl,
        lookup.width(),
        lookup.height(),
        TexelFormat::R32F,
        Filter::Linear,
        Some(lookup.values()),
    )?;
    if lookup.wrap() == Wrap::Repeat {
        texture.set_repeat();
    }
    Ok(texture)
}

/// Sets a uniform of the bound program `p` if the program uses it.
fn set_value(gl: &glow::Context, p: &Program, name: &str, value: UniformValue) {
    let Some(location) = p.optional_uniform(name) else {
        return;
    };
    let location = Some(location);
    // SAFETY: a uniform of the bound program, with the type the shader declares.
    unsafe {
        match value {
            UniformValue::Float(v) => gl.uniform_1_f32(location, v),
            UniformValue::Vec2([a, b]) => gl.uniform_2_f32(location, a, b),
            UniformValue::Vec3([a, b, c]) => gl.uniform_3_f32(location, a, b, c),
            UniformValue::Vec4([a, b, c, d]) => gl.uniform_4_f32(location, a, b, c, d),
            UniformValue::IVec2([a, b]) => gl.uniform_2_i32(location, a, b),
            UniformValue::Mat3(m) => gl.uniform_matrix_3_f32_slice(location, false, &m),
        }
    }
}

fn set_int(gl: &glow::Context, p: &Program, name: &str, value: i32) {
    if let Some(location) = p.optional_uniform(name) {
        // SAFETY: an int or sampler uniform of the bound program.
        unsafe { gl.uniform_1_i32(Some(location), value) };
    }
}

/// Binds a texture (brume's or the host's, by handle) to `unit`.
fn bind_texture(gl: &glow::Context, unit: u32, texture: Option<glow::Texture>) {
    // SAFETY: binding a texture handle of the current context.
    unsafe {
        gl.active_texture(glow::TEXTURE0 + unit);
        gl.bind_texture(glow::TEXTURE_2D, texture);
    }
}

fn draw_fullscreen(gl: &glow::Context) {
    // SAFETY: the empty VAO is bound; the vertex shader uses gl_VertexID only.
    unsafe { gl.draw_arrays(glow::TRIANGLES, 0, 3) };
}
