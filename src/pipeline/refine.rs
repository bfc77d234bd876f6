//! Image-guided refinement of a range texture on the GPU (see [`crate::refine`] for the
//! filter and why it works on log range): six fragment passes over brume's own
//! textures, from the host's colour texture and a range texture of the image's size or
//! smaller, into a new R32F range texture of the image's size (or, for the upsampling,
//! into one the caller keeps: [`Pipeline::upsample_range_into`]).
//!
//! **State.** A refinement changes and leaves the state a render does (see the parent
//! module). Its textures are made for the call and freed with it but the output, which the
//! caller owns.

use super::state::set_depth_test;
use super::{
    bind_texture, draw_fullscreen, set_int, set_value, Encoding, Pipeline, ProgramKey, UNIT_DEPTH,
    UNIT_MAIN, UNIT_SECOND,
};
use crate::error::Result;
use crate::gpu::framebuffer::Framebuffer;
use crate::gpu::program::Program;
use crate::gpu::texture::{Filter, TexelFormat, Texture};
use crate::gpu::timer::PassTimes;
use crate::medium::UniformValue;
use crate::refine::Refine;
use std::sync::Arc;

/// The passes' files, in `glsl/refine/`.
pub(super) const PACK_FRAG: &str = include_str!("../../glsl/refine/pack.frag");
pub(super) const BOX_FRAG: &str = include_str!("../../glsl/refine/box.frag");
pub(super) const MODEL_GLSL: &str = include_str!("../../glsl/refine/model.glsl");
pub(super) const APPLY_FRAG: &str = include_str!("../../glsl/refine/apply.frag");
pub(super) const CELLS_FRAG: &str = include_str!("../../glsl/refine/cells.frag");
pub(super) const UPSAMPLE_FRAG: &str = include_str!("../../glsl/refine/upsample.frag");
pub(super) const INTERPOLATE_FRAG: &str = include_str!("../../glsl/refine/interpolate.frag");

/// The uniforms of the box pass over the moments: first its sources, one per texture of
/// the [`LowTargets`] it reads (the box over one texture has the first), and last ε, only
/// in the pass that writes the windows' models.
const MOMENT_BOX_UNIFORMS: &[&str] = &[
    "u_source0",
    "u_source1",
    "u_source2",
    "u_source3",
    "u_size",
    "u_step",
    "u_radius",
    "u_epsilon",
];

/// The programs of the refinement.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) enum RefinePass {
    Pack,
    /// The box pass over the moments' four textures.
    BoxMoments,
    /// The box pass over the moments' four textures that writes the windows' models
    /// (`model.glsl`) instead of their means.
    BoxModels,
    /// The box pass over one texture (the models).
    Box,
    Apply,
    Cells,
    Interpolate,
    Upsample,
}

impl RefinePass {
    /// The file name, the source and the uniforms of the pass.
    pub(super) fn source(self) -> (&'static str, &'static str, &'static [&'static str]) {
        match self {
            RefinePass::Pack => (
                "refine/pack.frag",
                PACK_FRAG,
                &[
                    "u_colour",
                    "u_range",
                    "u_colour_size",
                    "u_cell",
                    "u_colour_srgb",
                    "u_range_full",
                ],
            ),
            RefinePass::BoxMoments => (
                "refine/box.frag",
                BOX_FRAG,
                MOMENT_BOX_UNIFORMS
                    .split_at(MOMENT_BOX_UNIFORMS.len() - 1)
                    .0,
            ),
            RefinePass::BoxModels => ("refine/box.frag", BOX_FRAG, MOMENT_BOX_UNIFORMS),
            RefinePass::Box => (
                "refine/box.frag",
                BOX_FRAG,
                &["u_source0", "u_size", "u_step", "u_radius"],
            ),
            RefinePass::Cells => (
                "refine/cells.frag",
                CELLS_FRAG,
                &[
                    "u_colour",
                    "u_range",
                    "u_colour_size",
                    "u_cell",
                    "u_colour_srgb",
                    "u_flat_spread",
                    "u_smooth_curvature",
                ],
            ),
            RefinePass::Interpolate => (
                "refine/interpolate.frag",
                INTERPOLATE_FRAG,
                &["u_cells", "u_interpolated", "u_low_size", "u_scale"],
            ),
            RefinePass::Upsample => (
                "refine/upsample.frag",
                UPSAMPLE_FRAG,
                &[
                    "u_colour",
                    "u_cells",
                    "u_low_size",
                    "u_scale",
                    "u_colour_srgb",
                    "u_sigma_colour",
                ],
            ),
            RefinePass::Apply => (
                "refine/apply.frag",
                APPLY_FRAG,
                &[
                    "u_colour",
                    "u_coefficients",
                    "u_low_size",
                    "u_scale",
                    "u_colour_srgb",
                ],
            ),
        }
    }
}

/// What to refine: the host's textures, read with `texelFetch` at level 0.
#[derive(Clone, Copy, Debug)]
pub struct RefineInput {
    /// Colour, RGB, of the image's size.
    pub colour: glow::Texture,
    /// How the colour's values are encoded.
    pub colour_encoding: Encoding,
    /// The image's size.
    pub width: usize,
    /// The image's size.
    pub height: usize,
    /// Range (> 0 everywhere) in `.r`, of the image's size or smaller by one factor
    /// ([`crate::refine::check_depth_size`]).
    pub range: glow::Texture,
    /// The range texture's size.
    pub range_width: usize,
    /// The range texture's size.
    pub range_height: usize,
}

/// Textures of the low grid written together, and the framebuffer over them (one
/// attachment each: the moments' four are written by one pass).
struct LowTargets {
    framebuffer: Framebuffer,
    textures: Vec<Texture>,
}

impl LowTargets {
    fn new(gl: &Arc<glow::Context>, width: usize, height: usize, count: usize) -> Result<Self> {
        let make = || {
            Texture::new(
                gl,
                width,
                height,
                TexelFormat::Rgba32F,
                Filter::Nearest,
                None,
            )
        };
        let textures = (0..count).map(|_| make()).collect::<Result<Vec<_>>>()?;
        let attached: Vec<&Texture> = textures.iter().collect();
        let framebuffer = Framebuffer::over(gl, &attached, "the refinement's low grid")?;
        Ok(LowTargets {
            framebuffer,
            textures,
        })
    }

    /// Binds the textures on units 0, 1, ... and points `names` (a sampler each) at them.
    fn bind_as(&self, gl: &glow::Context, program: &Program, names: &[&str]) {
        for (unit, (texture, name)) in self.textures.iter().zip(names).enumerate() {
            texture.bind(unit as u32);
            set_int(gl, program, name, unit as i32);
        }
    }
}

/// The textures the moments of a colour guide take (13 values: see `pack.frag`).
const MOMENT_TEXTURES: usize = 4;

/// The inputs of a refinement's first pass, the same for the guided filter's pack pass
/// and the upsampling's cells pass: the colour and the range on their units, the colour's
/// size, the cell (full-resolution pixels per low-grid cell) and the colour's encoding.
fn bind_cell_inputs(
    gl: &glow::Context,
    program: &Program,
    input: &RefineInput,
    cell: [f32; 2],
    srgb: i32,
) {
    bind_texture(gl, UNIT_MAIN, Some(input.colour));
    bind_texture(gl, UNIT_DEPTH, Some(input.range));
    set_int(gl, program, "u_colour", UNIT_MAIN as i32);
    set_int(gl, program, "u_range", UNIT_DEPTH as i32);
    let size = [input.width as i32, input.height as i32];
    set_value(gl, program, "u_colour_size", UniformValue::IVec2(size));
    set_value(gl, program, "u_cell", UniformValue::Vec2(cell));
    set_int(gl, program, "u_colour_srgb", srgb);
}

impl Pipeline {
    /// Refines `input.range` with `input.colour` as guide and returns the refined range,
    /// an R32F texture of the image's size that the caller owns, with the passes' times
    /// (six passes). Upsamples a range smaller than the image on the way.
    ///
    /// Errors: [`crate::Error::InvalidParameter`] for bad options or sizes,
    /// [`crate::Error::TooLarge`] above `GL_MAX_TEXTURE_SIZE`, GL errors naming the pass.
    pub fn refine_range(
        &mut self,
        input: &RefineInput,
        opts: &Refine,
    ) -> Result<(Texture, PassTimes)> {
        let grid = opts.grid(
            (input.width, input.height),
            (input.range_width, input.range_height),
        )?;
        self.caps.require_size("image", input.width, input.height)?;
        for pass in [
            RefinePass::Pack,
            RefinePass::BoxMoments,
            RefinePass::BoxModels,
            RefinePass::Box,
            RefinePass::Apply,
        ] {
            self.program(ProgramKey::Refine(pass), None)?;
        }
        let gl = Arc::clone(&self.gl);
        // The moments and their horizontal means take four textures each; the windows'
        // models ping-pong between two of one.
        let make = |count| LowTargets::new(&gl, grid.width, grid.height, count);
        let (moments, moment_means) = (make(MOMENT_TEXTURES)?, make(MOMENT_TEXTURES)?);
        let models = [make(1)?, make(1)?];
        let srgb = i32::from(input.colour_encoding == Encoding::Srgb);
        let low_size = [grid.width as i32, grid.height as i32];
        self.passes_into_range(input, "refining the range", |pipeline, timer, output_fb| {
            let program = |pass| pipeline.compiled(ProgramKey::Refine(pass));
            let (pack, apply) = (program(RefinePass::Pack)?, program(RefinePass::Apply)?);
            timer.pass(|| {
                moments.framebuffer.bind_for_drawing();
                pipeline.use_program(pack);
                let cell = grid.cell.map(|c| c as f32);
                bind_cell_inputs(&gl, pack, input, cell, srgb);
                set_int(&gl, pack, "u_range_full", i32::from(grid.range_full));
                draw_fullscreen(&gl);
            })?;
            // One line of a box mean of every texture of `from` into `to` by `pass`.
            let box_pass = |timer: &mut crate::gpu::timer::PassTimer<'_>,
                            pass: RefinePass,
                            from: &LowTargets,
                            to: &LowTargets,
                            step: [i32; 2]|
             -> Result<()> {
                let boxes = program(pass)?;
                timer.pass(|| {
                    to.framebuffer.bind_for_drawing();
                    pipeline.use_program(boxes);
                    from.bind_as(&gl, boxes, &MOMENT_BOX_UNIFORMS[..from.textures.len()]);
                    set_value(&gl, boxes, "u_size", UniformValue::IVec2(low_size));
                    set_value(&gl, boxes, "u_step", UniformValue::IVec2(step));
                    set_int(&gl, boxes, "u_radius", grid.radius as i32);
                    if pass == RefinePass::BoxModels {
                        let epsilon = UniformValue::Float(opts.epsilon as f32);
                        set_value(&gl, boxes, "u_epsilon", epsilon);
                    }
                    draw_fullscreen(&gl);
                })
            };
            // The moments' means, then the windows' models, then their means.
            box_pass(
                timer,
                RefinePass::BoxMoments,
                &moments,
                &moment_means,
                [1, 0],
            )?;
            box_pass(
                timer,
                RefinePass::BoxModels,
                &moment_means,
                &models[0],
                [0, 1],
            )?;
            box_pass(timer, RefinePass::Box, &models[0], &models[1], [1, 0])?;
            box_pass(timer, RefinePass::Box, &models[1], &models[0], [0, 1])?;
            timer.pass(|| {
                output_fb.bind_for_drawing();
                pipeline.use_program(apply);
                bind_texture(&gl, UNIT_MAIN, Some(input.colour));
                models[0].textures[0].bind(UNIT_DEPTH);
                set_int(&gl, apply, "u_colour", UNIT_MAIN as i32);
                set_int(&gl, apply, "u_coefficients", UNIT_DEPTH as i32);
                set_value(&gl, apply, "u_low_size", UniformValue::IVec2(low_size));
                let scale = grid.cell.map(|c| (1.0 / c) as f32);
                set_value(&gl, apply, "u_scale", UniformValue::Vec2(scale));
                set_int(&gl, apply, "u_colour_srgb", srgb);
                draw_fullscreen(&gl);
            })?;
            Ok(())
        })
    }
}

impl Pipeline {
    /// Upsamples `input.range`, smaller than the image by one factor
    /// ([`crate::refine::check_depth_size`]), to the image's size by joint bilateral
    /// upsampling guided by `input.colour` (`sigma_colour` in sRGB-encoded values; see
    /// [`crate::refine::joint_bilateral_upsample_reference`]), in three passes. Returns an
    /// R32F texture of the image's size that the caller owns, with the passes' times.
    /// [`Pipeline::upsample_range_into`] writes into a texture the caller keeps instead.
    pub fn upsample_range(
        &mut self,
        input: &RefineInput,
        sigma_colour: f64,
    ) -> Result<(Texture, PassTimes)> {
        self.check_upsampling(input, sigma_colour)?;
        let (w, h) = (input.width, input.height);
        let output = Texture::new(&self.gl, w, h, TexelFormat::R32F, Filter::Nearest, None)?;
        let times = self.upsample_range_into(input, sigma_colour, &output)?;
        Ok((output, times))
    }

    /// [`Pipeline::upsample_range`] into `output`, an R32F texture of the image's size
    /// that the caller made and keeps (a live app upsamples every frame, as the guide
    /// changes with each, without allocating an image-sized texture each time); every
    /// texel of `output` is written. Returns the passes' times (three passes). The low
    /// grid's textures and the framebuffers are made for the call and freed with it; the
    /// depth texture of the image's size (2 bytes a pixel: it marks the pixels the
    /// bilinear interpolation took, which the depth test keeps from the 36 taps' pass) is
    /// kept by the pipeline for the next call of that size.
    ///
    /// Errors: as [`Pipeline::upsample_range`], and [`crate::Error::InvalidParameter`]
    /// when `output` is not R32F or not of the image's size.
    pub fn upsample_range_into(
        &mut self,
        input: &RefineInput,
        sigma_colour: f64,
        output: &Texture,
    ) -> Result<PassTimes> {
        self.check_upsampling(input, sigma_colour)?;
        let (w, h) = (input.width, input.height);
        if output.format() != TexelFormat::R32F || (output.width(), output.height()) != (w, h) {
            return Err(crate::Error::invalid(
                "upsampling output",
                format!(
                    "a {:?} texture of {}x{}",
                    output.format(),
                    output.width(),
                    output.height()
                ),
                format!("an R32F texture of the image's size, {w}x{h}"),
            ));
        }
        let (lw, lh) = (input.range_width, input.range_height);
        self.program(ProgramKey::Refine(RefinePass::Cells), None)?;
        self.program(ProgramKey::Refine(RefinePass::Interpolate), None)?;
        self.program(ProgramKey::Refine(RefinePass::Upsample), None)?;
        let gl = Arc::clone(&self.gl);
        // The cells, and whether each one's window is flat or smooth.
        let low = LowTargets::new(&gl, lw, lh, 2)?;
        let srgb = i32::from(input.colour_encoding == Encoding::Srgb);
        let cell = [w as f32 / lw as f32, h as f32 / lh as f32];
        let marks = self.upsample_marks(w, h)?;
        let what = "the upsampled range";
        let target = Framebuffer::with_depth(&gl, &[output.raw()], Some(marks), w, h, what)?;
        let low_size = UniformValue::IVec2([lw as i32, lh as i32]);
        let scale = UniformValue::Vec2(cell.map(|c| 1.0 / c));
        let (times, ()) = self.timed("upsampling the range", |pipeline, timer| {
            let cells = pipeline.compiled(ProgramKey::Refine(RefinePass::Cells))?;
            let interpolate = pipeline.compiled(ProgramKey::Refine(RefinePass::Interpolate))?;
            let upsample = pipeline.compiled(ProgramKey::Refine(RefinePass::Upsample))?;
            timer.pass(|| {
                low.framebuffer.bind_for_drawing();
                pipeline.use_program(cells);
                bind_cell_inputs(&gl, cells, input, cell, srgb);
                let spread = crate::refine::UPSAMPLE_FLAT_SPREAD as f32;
                set_value(&gl, cells, "u_flat_spread", UniformValue::Float(spread));
                let bend = UniformValue::Float(crate::refine::UPSAMPLE_SMOOTH_CURVATURE as f32);
                set_value(&gl, cells, "u_smooth_curvature", bend);
                draw_fullscreen(&gl);
            })?;
            // Every pixel's depth written: 0 where it took the interpolation.
            timer.pass(|| {
                target.bind_for_drawing();
                pipeline.use_program(interpolate);
                low.textures[0].bind(UNIT_DEPTH);
                low.textures[1].bind(UNIT_SECOND);
                set_int(&gl, interpolate, "u_cells", UNIT_DEPTH as i32);
                set_int(&gl, interpolate, "u_interpolated", UNIT_SECOND as i32);
                set_value(&gl, interpolate, "u_low_size", low_size);
                set_value(&gl, interpolate, "u_scale", scale);
                set_depth_test(&gl, glow::ALWAYS, true);
                draw_fullscreen(&gl);
            })?;
            // The fullscreen triangle's depth, 0.5, passes only where 1 was written.
            timer.pass(|| {
                pipeline.use_program(upsample);
                bind_texture(&gl, UNIT_MAIN, Some(input.colour));
                set_int(&gl, upsample, "u_colour", UNIT_MAIN as i32);
                set_int(&gl, upsample, "u_cells", UNIT_DEPTH as i32);
                set_value(&gl, upsample, "u_low_size", low_size);
                set_value(&gl, upsample, "u_scale", scale);
                set_int(&gl, upsample, "u_colour_srgb", srgb);
                let sigma = UniformValue::Float(sigma_colour as f32);
                set_value(&gl, upsample, "u_sigma_colour", sigma);
                set_depth_test(&gl, glow::LESS, false);
                draw_fullscreen(&gl);
            })?;
            Ok(())
        })?;
        drop(target);
        Ok(times)
    }

    /// The upsampling's depth texture of `w x h` (written by the interpolation pass, read
    /// by the depth test of the 36 taps' pass): the one kept from an earlier call of that
    /// size, or a new one in its place.
    fn upsample_marks(&mut self, w: usize, h: usize) -> Result<glow::Texture> {
        let marks = Texture::kept(
            &mut self.upsample_marks,
            &self.gl,
            w,
            h,
            TexelFormat::Depth16,
        )?;
        Ok(marks.raw())
    }

    /// The upsampling's sizes and σ, before anything is made.
    fn check_upsampling(&self, input: &RefineInput, sigma_colour: f64) -> Result<()> {
        let (w, h) = (input.width, input.height);
        crate::refine::check_depth_size((w, h), (input.range_width, input.range_height))?;
        if !(sigma_colour.is_finite() && sigma_colour > 0.0) {
            return Err(crate::Error::invalid(
                "sigma_colour",
                sigma_colour,
                "a colour σ > 0 (sRGB-encoded values)",
            ));
        }
        self.caps.require_size("image", w, h)
    }
}

impl Pipeline {
    /// Runs `passes` (timed, in the passes' GL state), the last of which draws into the
    /// framebuffer it is given: over a new R32F texture of the image's size, which is
    /// returned with the passes' times. `what` names the passes in a GL error.
    fn passes_into_range(
        &self,
        input: &RefineInput,
        what: &str,
        passes: impl Fn(&Self, &mut crate::gpu::timer::PassTimer<'_>, &Framebuffer) -> Result<()>,
    ) -> Result<(Texture, PassTimes)> {
        let (w, h) = (input.width, input.height);
        let output = Texture::new(&self.gl, w, h, TexelFormat::R32F, Filter::Nearest, None)?;
        let times = self.passes_into(&output, what, passes)?;
        Ok((output, times))
    }

    /// [`Pipeline::passes_into_range`] into the caller's `output`: the framebuffer over
    /// it is made for the call and freed with it.
    fn passes_into(
        &self,
        output: &Texture,
        what: &str,
        passes: impl Fn(&Self, &mut crate::gpu::timer::PassTimer<'_>, &Framebuffer) -> Result<()>,
    ) -> Result<PassTimes> {
        let framebuffer = Framebuffer::over(&self.gl, &[output], "the refined range")?;
        let result = self.timed(what, |pipeline, timer| {
            passes(pipeline, timer, &framebuffer)
        });
        let (times, ()) = result?;
        drop(framebuffer);
        Ok(times)
    }
}

/// Compiles one pass of the refinement: the prelude, then its file.
pub(super) fn compile(
    gl: &Arc<glow::Context>,
    version_line: &str,
    prelude: &str,
    pass: RefinePass,
) -> Result<Program> {
    let (file, source, uniforms) = pass.source();
    let layers = match pass {
        RefinePass::BoxMoments | RefinePass::BoxModels => MOMENT_TEXTURES,
        _ => 1,
    };
    // model.glsl defines WINDOW_MODEL, which turns box.frag's last pass over the moments
    // into the one that writes the models.
    let model = if pass == RefinePass::BoxModels {
        MODEL_GLSL
    } else {
        ""
    };
    let header = format!("{version_line}\n#define LAYERS {layers}\n{prelude}\n{model}");
    Program::new(gl, &header, (file, source), uniforms, &[])
}
