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
//!    With [`Blur::coarse_from`], the last steps run at half resolution between a 2x2
//!    average and a blend back (`coarse.rs`: two passes more, a quarter of the pixels).
//! 3. **Composite** (`composite.frag` + the medium's GLSL): F.rgb + (1 − τ_blurred)·L∞
//!    into the host's destination, L∞ evaluated by the medium at each pixel.
//!
//! The CPU computes per-frame constants only (N, the offset law, the medium's uniforms).
//!
//! [`Pipeline::fog`] and [`Pipeline::blend_fog`] run the engine passes of papers 001 and
//! 003 instead (one or two passes; [`FogBlur`] describes them). A medium with a camera
//! ([`Medium::frame_camera`]: the camera of the frame, [`Input::frame`]) gets the
//! eye-to-fragment ray from the vertex shader and the depth constants as uniforms
//! ([`crate::camera`]). The camera and the time come with each frame: one medium value
//! renders every frame, with the same compiled programs.
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
//! **Two layouts.** Where the medium's L∞ is the same at every pixel
//! ([`Medium::uniform_inscatter`]: the haze, the layered fog, a uniform blur), the
//! composite F.rgb + (1 − τ_blurred)·L∞ equals L∞ + blur(τ·(E − L∞)): the diffusion is
//! linear (fixed rates and offsets), and blur(τ)·L∞ = blur(τ·L∞) for a constant L∞. The
//! pipeline then diffuses the **offset layout**, one RGBA target (τ·(E − L∞), ρ), ρ in the
//! alpha where τ_r was, constant over the steps: each neighbour is one fetch for its
//! colour and its rate (four per step where the **pre-multiplied layout** takes eight),
//! the rate and the (τ_g, τ_b) pair need no target, so a chromatic τ costs what a grey
//! one does and the coarse stage runs for it. Measured on llvmpipe: a third less time
//! per diffusion step, the same image to f32 rounding (`tests/offset_layout.rs`; README,
//! *Speed*). Other media (the distance fog's sun, the aerial perspective's sky) keep the
//! pre-multiplied layout. `Layout` (`targets.rs`) is the choice, made per frame from the
//! medium.
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
//! - **State: changed, then restored.** Every call that draws ([`Pipeline::render`],
//!   [`Pipeline::fog`], [`Pipeline::blend_fog`], [`Pipeline::import_external`], the
//!   refinement) saves, sets for its passes and, before it returns (also on an error),
//!   restores exactly as the host left them: the draw and read framebuffer bindings, the
//!   viewport, the current program, the vertex array, the active texture unit, the
//!   `TEXTURE_2D` binding and the sampler object of units 0-8 (brume's own textures on
//!   0-2, a medium's lookups, such as the distance fog's noise, on 3-6, the coarse
//!   stage's last blend on 7-8), unit 0's
//!   `GL_TEXTURE_EXTERNAL_OES` binding (an import), the capabilities `BLEND`,
//!   `DEPTH_TEST`, `STENCIL_TEST`, `SCISSOR_TEST`, `CULL_FACE`, `RASTERIZER_DISCARD`,
//!   `SAMPLE_ALPHA_TO_COVERAGE`, `SAMPLE_COVERAGE`, `POLYGON_OFFSET_FILL` and `DITHER`
//!   (all disabled during the passes: a float target must not be dithered), the colour
//!   mask (all channels during the passes), the blend functions and equations
//!   ([`Pipeline::blend_fog`] sets them), the depth function, write mask and range (the
//!   upsampling's depth test sets them), and on a desktop GL context
//!   `GL_FRAMEBUFFER_SRGB` (enabled during the passes, see [`crate::caps`]). Uploads,
//!   read-backs and brume's texture and framebuffer creation, inside a call or not
//!   ([`crate::Renderer`]'s uploads, [`Pipeline::refine_range`]'s output), bind on the
//!   active unit and put its `TEXTURE_2D` binding back, and set `UNPACK_ALIGNMENT`/
//!   `PACK_ALIGNMENT` 4, `*_ROW_LENGTH`, `*_SKIP_ROWS`, `*_SKIP_PIXELS` 0 and no
//!   `PIXEL_UNPACK_BUFFER`/`PIXEL_PACK_BUFFER` for the transfer and put the host's values
//!   back. Colour masks and blend state set per draw buffer (`glColorMaski`,
//!   `glBlendFunci`) come back as draw buffer 0's. Nothing else is touched (clear colour,
//!   stencil state, the depth clear value, `SAMPLE_MASK`, buffers); brume's clears use
//!   the host's clear colour on brume's own targets only. `tests/host_pipeline.rs` checks
//!   all of this against a hostile host.
//! - **Timing** ([`Pipeline::set_timing`]). [`Timing::Off`], the default: no query, no
//!   `glFinish`, no wait; a call returns once its commands are issued (the GPU may still
//!   be drawing), with its times unavailable. [`Timing::Deferred`]: a `GL_TIME_ELAPSED`
//!   query around each pass (query objects kept between calls, up to
//!   [`crate::gpu::timer::DEFERRED_IN_FLIGHT`] calls in flight), read on a later call only once its
//!   results are in (never waited for); a call returns the newest earlier call's figures
//!   not yet returned ([`PassTimes::calls_ago`] says how many calls back), or unavailable
//!   times. [`Timing::Blocking`]: the call's own figures, waiting for its queries' results
//!   (or, without `GL_EXT_disjoint_timer_query`, `glFinish` after every pass);
//!   [`Timing::BlockingWall`] always by `glFinish` and the wall clock. Figures flagged
//!   disjoint (`GL_GPU_DISJOINT_EXT`) or that cannot be right are reported unavailable:
//!   passes are never run again (a second `blend_fog` would fog the host's frame twice).
//!   The first call that begins queries waits once for a 1x1 draw ([`crate::gpu::timer::warm_up`]).
//!   With queries, brume reads `GL_GPU_DISJOINT_EXT`, which clears it for the host too.
//! - **A host's own query.** If a `GL_TIME_ELAPSED` query is open when a call starts
//!   (`glGetQueryiv(GL_TIME_ELAPSED, GL_CURRENT_QUERY)` non-zero), brume begins none of its
//!   own for that call (its times are unavailable, except by the wall clock) and never ends,
//!   reads or deletes the host's; the host's query then measures brume's passes with its own
//!   work. Where `glGetQueryiv` cannot be found ([`crate::gpu::timer::HostQueryProbe`]) brume begins no
//!   query at all: deferred times are unavailable, blocking ones by the wall clock.

mod coarse;
mod diffusion;
mod engine;
mod external;
mod fog_blur;
mod programs;
mod refine;
mod state;
mod targets;
mod uniforms;

use engine::EngineTargets;
pub use engine::GAUSS_WEIGHTS;
pub use external::{ExternalColour, IDENTITY, TEXTURE_BINDING_EXTERNAL_OES, TEXTURE_EXTERNAL_OES};
pub use fog_blur::{FogBlur, GaussBlur};
use programs::{medium_key, ProgramKey};
pub use refine::RefineInput;
pub(crate) use targets::Layout;
use targets::Targets;
use uniforms::{bind_texture, set_int, set_value};

use crate::blur::{Blur, Precision};
use crate::camera::FrameInputs;
use crate::caps::Capabilities;
use crate::error::{Error, Result};
use crate::gpu::framebuffer::Framebuffer;
use crate::gpu::program::Program;
use crate::gpu::texture::Texture;
use crate::gpu::timer::{Clock, PassTimes, Timekeeper, Timing};
use crate::medium::{Medium, MAX_LOOKUPS};
use crate::schedule::{Schedule, Scheme};
use glow::HasContext;
use std::collections::HashMap;
use std::sync::Arc;

/// Texture units: the pipeline binds these, then a medium's lookups from `UNIT_LOOKUP`.
const UNIT_MAIN: u32 = 0;
const UNIT_DEPTH: u32 = 1;
const UNIT_SECOND: u32 = 2;
const UNIT_LOOKUP: u32 = 3;
/// The coarse stage's blend's finer rate and coarse D at its first step: after the
/// medium's lookups, because the blend into full resolution is fused with the composite,
/// which reads those too.
const UNIT_BLEND_RATE: u32 = UNIT_LOOKUP + MAX_LOOKUPS as u32;
const UNIT_BLEND_START: u32 = UNIT_BLEND_RATE + 1;
const UNITS_USED: u32 = UNIT_BLEND_START + 1;

/// How colour values are encoded in a host texture or framebuffer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Encoding {
    /// Linear light (float textures, `SRGB8_ALPHA8`, which GL converts itself).
    #[default]
    Linear,
    /// sRGB-encoded values in a format GL does not convert (plain `RGBA8`).
    Srgb,
}

/// The host's textures for one frame, and the camera and time it was drawn at. The
/// textures are not owned: brume never deletes them.
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
    /// The frame's camera and time, for the medium ([`FrameInputs::default`]: none and 0,
    /// for a medium that reads a range map).
    pub frame: FrameInputs,
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
    /// Which passes ran ([`Frame::pass_names`] names them).
    pub passes: Passes,
    /// Per-pass times (N + 2 for a render; with the coarse stage's L levels N + 1 + 2L: a
    /// down and a blend each, the half-resolution one's blend fused with the composite),
    /// with the clock that produced them, as
    /// [`Pipeline::timing`] gives them: this call's, an earlier call's
    /// ([`PassTimes::calls_ago`]), or unavailable ([`PassTimes::is_available`]).
    pub times: PassTimes,
}

/// Which passes a frame ran, in the order of its `times.pass_ms`: kept as a description,
/// so that a host's frame loop builds no names it does not ask for.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Passes {
    /// The medium pass, the schedule's N diffusion steps with the coarse stage's levels
    /// starting at the steps `coarse_starts` (none: every step at full resolution), the
    /// composite.
    Diffusion {
        /// The first step of each coarse level, half resolution first.
        coarse_starts: Vec<u32>,
    },
    /// Engine passes, by name.
    Engine(&'static [&'static str]),
}

impl Frame {
    /// The name of each pass, one per entry of `times.pass_ms`: `medium`, `diffuse k`
    /// (k = 1..N; `diffuse k (1/2)` on a coarse level), the coarse stage's `down 1/2`,
    /// `blend 1/4` …, `composite` (`blend 1/2 + composite` with the coarse stage); or the
    /// engine passes' names.
    pub fn pass_names(&self) -> Vec<String> {
        self.passes.names(self.schedule.steps)
    }
}

impl Passes {
    /// The passes' names, for a schedule of `steps` diffusion steps.
    pub fn names(&self, steps: u32) -> Vec<String> {
        match self {
            Passes::Diffusion { coarse_starts } => diffusion_pass_names(steps, coarse_starts),
            Passes::Engine(names) => names.iter().map(|n| n.to_string()).collect(),
        }
    }
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
    /// The coarse-to-fine stage's programs and half-resolution targets, and where this
    /// frame's schedule starts it ([`Blur::coarse_from`]).
    coarse: coarse::Coarse,
    coarse_start: Option<u32>,
    /// The lookups of the last medium rendered, uploaded, by [`crate::medium::Lookup::id`].
    lookups: HashMap<u64, Texture>,
    engine_targets: EngineTargets,
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
    /// The upsampling's depth texture ([`Pipeline::upsample_range_into`]), kept between
    /// calls of one image size.
    upsample_marks: Option<Texture>,
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
        caps.require_es3_shaders()?;
        // GLSL ES 3.20 only on a GLES 3.2 context: a desktop context takes ES shaders at
        // 3.00 (ARB_ES3_compatibility; see crate::caps).
        let version_line = if !caps.desktop && caps.gles_version >= (3, 2) {
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
            coarse: coarse::Coarse::default(),
            coarse_start: None,
            lookups: HashMap::new(),
            engine_targets: EngineTargets::default(),
            host_target: None,
            timekeeper: Timekeeper::new(&gl, caps.disjoint_timer_query),
            imported: None,
            upsample_marks: None,
            timer_anchor: std::cell::OnceCell::new(),
            linear_sampler,
            vao,
            caps,
            version_line,
            gl,
        };
        for matched in [false, true] {
            let layout = Layout::Premultiplied { chromatic: false };
            pipeline.program(ProgramKey::Diffuse { matched, layout }, None)?;
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

    /// Bytes per pixel of the textures the pipeline allocates for a frame of `medium`:
    /// two colour targets, and, unless its in-scattered light is uniform
    /// ([`Medium::uniform_inscatter`]), the rate and for a chromatic τ two (τ_g, τ_b)
    /// targets (module docs, *Two layouts*).
    pub fn bytes_per_pixel(precision: Precision, medium: &dyn Medium) -> u64 {
        Layout::of(medium).bytes_per_pixel(precision)
    }

    /// Bytes of the diffusion's targets kept from the last frame (its coarse levels'
    /// too), which the next frame reuses or frees before it allocates others.
    pub(crate) fn kept_diffusion_bytes(&self) -> u64 {
        let coarse = self.coarse.targets.as_ref().map_or(0, |c| c.bytes());
        self.targets.as_ref().map_or(0, Targets::bytes) + coarse
    }

    /// Frees the diffusion's kept targets (its coarse levels' too): the next frame makes
    /// them again.
    pub(crate) fn free_kept_targets(&mut self) {
        self.targets = None;
        self.coarse.targets = None;
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

    /// The programs compiled so far (one per pass, medium GLSL and variant): a host checks
    /// that its frames, with their new cameras and times, compile nothing.
    pub fn program_count(&self) -> usize {
        self.programs.len()
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
        Ok(Frame {
            passes: self.diffusion_passes(),
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
        let (times, pixels) = result?;
        Ok((
            Frame {
                schedule,
                passes: self.diffusion_passes(),
                times,
            },
            pixels,
        ))
    }

    /// Checks the frame, plans its schedule, compiles what it needs and sizes the targets.
    fn prepare(&mut self, input: &Input, medium: &dyn Medium, blur: &Blur) -> Result<Schedule> {
        let schedule = blur.schedule_for(medium)?;
        medium.validate_frame(&input.frame)?;
        self.caps.require_precision(blur.precision)?;
        self.caps.require_size("input", input.width, input.height)?;
        let layout = Layout::of(medium);
        self.coarse_start = blur.coarse_start(&schedule, medium)?;
        let keys = [
            medium_key(medium, blur.precision, &schedule, layout),
            ProgramKey::Diffuse {
                matched: schedule.scheme == Scheme::Matched,
                layout,
            },
            ProgramKey::Composite {
                medium: programs::MediumId::of(medium),
                layout,
                coarse: self.coarse_start.is_some(),
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
            .is_some_and(|t| t.fits(input.width, input.height, blur.precision, layout));
        if !fits {
            self.targets = None; // free the old textures before allocating new ones
            self.targets = Some(Targets::new(
                &self.gl,
                input.width,
                input.height,
                blur.precision,
                layout,
            )?);
        }
        if self.coarse_start.is_some() {
            let (w, h) = (input.width, input.height);
            let in_alpha = layout.rate_in_alpha();
            self.prepare_coarse(w, h, blur.precision, in_alpha, &schedule)?;
        }
        Ok(schedule)
    }

    /// The passes [`Pipeline::run`] runs, with the coarse stage's levels where this frame
    /// runs it.
    fn diffusion_passes(&self) -> Passes {
        Passes::Diffusion {
            coarse_starts: match self.coarse_start {
                Some(_) => self.coarse.starts.clone(),
                None => Vec::new(),
            },
        }
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

    /// Binds the last pass's destination and sets its viewport; returns the output
    /// rectangle's corner and the encoding to write. `internal` is brume's target for
    /// [`Destination::Internal`] (the caller made it; nothing is bound without it).
    fn bind_destination(
        &self,
        destination: &Destination,
        input: &Input,
        internal: Option<&Framebuffer>,
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
                if let Some(internal) = internal {
                    internal.bind_for_drawing();
                }
                ([0, 0], Encoding::Linear)
            }
        }
    }

    fn targets(&self) -> Result<&Targets> {
        self.targets
            .as_ref()
            .ok_or_else(|| Error::Gl("internal: diffusion targets not allocated".into()))
    }

    fn use_program(&self, p: &Program) {
        // SAFETY: an owned, linked program on the current context.
        unsafe { self.gl.use_program(Some(p.raw())) };
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

fn draw_fullscreen(gl: &glow::Context) {
    // SAFETY: the empty VAO is bound; the vertex shader uses gl_VertexID only.
    unsafe { gl.draw_arrays(glow::TRIANGLES, 0, 3) };
}

/// The names of a diffusion render's passes in the order they run, for `steps` steps and
/// the coarse stage's levels starting at the steps `coarse_starts` (empty: none): the
/// medium, the full-resolution steps, for each level its down pass and its steps, the
/// blends between levels from the deepest up, the composite (fused with the
/// half-resolution level's blend: `blend 1/2 + composite`).
pub fn diffusion_pass_names(steps: u32, coarse_starts: &[u32]) -> Vec<String> {
    let full_steps = coarse_starts.first().copied().unwrap_or(steps);
    let scale = |level: usize| format!("1/{}", 1u32 << level);
    let mut names = vec!["medium".to_string()];
    names.extend((1..=full_steps).map(|k| format!("diffuse {k}")));
    for (l, &start) in coarse_starts.iter().enumerate() {
        let end = coarse_starts.get(l + 1).copied().unwrap_or(steps);
        names.push(format!("down {}", scale(l + 1)));
        names.extend((start + 1..=end).map(|k| format!("diffuse {k} ({})", scale(l + 1))));
    }
    names.extend(
        (2..=coarse_starts.len())
            .rev()
            .map(|l| format!("blend {}", scale(l))),
    );
    names.push(match coarse_starts {
        [] => "composite".to_string(),
        _ => format!("blend {} + composite", scale(1)),
    });
    names
}
