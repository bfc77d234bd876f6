//! Engine-style fog on the same pipeline: what papers 001 and 003 do to a frame an engine
//! has just rendered, for any medium, beside brume's diffusion blur.
//!
//! [`FogBlur`] picks how the fog is blurred:
//!
//! - `None`: one pass, `out = τ·C + (1 − τ)·L∞` (papers 001 and 003, no blur).
//! - `GaussSingle`: paper 001's single pass: the **fog-free** colour blurred by its 5 x 5
//!   Gaussian (σ = 1 px, table 1) and mixed with the sharp colour by the blur weight b,
//!   then fogged, in the same pass.
//! - `GaussSeparate`: paper 001's separate passes: the fog first (into a float target,
//!   b in alpha), then the **fogged** image blurred by the same kernel and mixed by b.
//! - `Diffusion`: brume's diffusion blur to the medium's σ (N + 2 passes, see the parent
//!   module), which grows with the fog's scattering optical depth.
//!
//! The blur weight of the Gaussian modes (paper 001 gives its parameters, not its formula:
//! "distance, falloff or maximum blur value … when the density is higher, the blurring
//! value of the scene is also increased"):
//!
//! ```text
//! b = min(maximum, density · (l / distance)^falloff),   density = 1 − mean(τ)
//! ```
//!
//! with l the Euclidean distance to the fragment, so the Gaussian modes need a medium with
//! a camera. [`Pipeline::blend_fog`] is paper 003's way: one pass drawn over the host's
//! framebuffer, which already holds the scene, blended by fixed-function GL.

use super::fog_blur::{FogBlur, GaussBlur};
use super::programs::MediumId;
use super::{
    bind_texture, draw_fullscreen, set_int, set_value, Destination, Encoding, Frame, Input, Output,
    Passes, Pipeline, ProgramKey, UNIT_DEPTH, UNIT_MAIN,
};
use crate::blur::Precision;
use crate::camera::FrameInputs;
use crate::error::{Error, Result};
use crate::gpu::framebuffer::Framebuffer;
use crate::gpu::texture::{Filter, TexelFormat, Texture};
use crate::gpu::timer::PassTimes;
use crate::medium::{Medium, UniformValue};
use crate::raster::{Grid, RgbaImage};
use crate::schedule::{Schedule, Scheme};
use glow::HasContext;
use std::sync::Arc;

const FOG_FRAG: &str = include_str!("../../glsl/fog.frag");
const GAUSS_BLUR_FRAG: &str = include_str!("../../glsl/gauss_blur.frag");
const FOG_BLEND_FRAG: &str = include_str!("../../glsl/fog_blend.frag");
const GAUSS5_GLSL: &str = include_str!("../../glsl/gauss5.glsl");

/// Paper 001's 1D Gaussian weights (σ = 1 px) at offsets 0, 1, 2, normalised to sum 1
/// over −2..2 (the same numbers as `glsl/gauss5.glsl`).
pub const GAUSS_WEIGHTS: [f64; 3] = [0.40261995, 0.24420134, 0.05448868];

impl FogBlur {
    /// The engine passes (`FogBlur::None` and the Gaussians); a diffusion render's depend
    /// on its schedule and coarse stage ([`Passes::Diffusion`]).
    fn engine_passes(&self) -> Passes {
        Passes::Engine(match self {
            FogBlur::None => &["fog"],
            FogBlur::GaussSingle(_) => &["fog+blur"],
            FogBlur::GaussSeparate(_) => &["fog", "blur"],
            FogBlur::Diffusion(_) => unreachable!("diffusion renders through Pipeline::render"),
        })
    }
}

/// One target of the engine passes: a texture and the framebuffer over it.
pub(super) struct EngineTarget {
    format: TexelFormat,
    texture: Texture,
    framebuffer: Framebuffer,
}

impl EngineTarget {
    /// Makes `slot` hold a `w x h` target of `format` (kept when it already does).
    fn ensure(
        slot: &mut Option<EngineTarget>,
        gl: &Arc<glow::Context>,
        (w, h): (usize, usize),
        format: TexelFormat,
        what: &str,
    ) -> Result<()> {
        if slot.as_ref().is_some_and(|t| t.fits(w, h, format)) {
            return Ok(());
        }
        *slot = None; // free the old texture before allocating the new one
        let texture = Texture::new(gl, w, h, format, Filter::Nearest, None)?;
        let framebuffer = Framebuffer::over(gl, &[&texture], what)?;
        *slot = Some(EngineTarget {
            format,
            texture,
            framebuffer,
        });
        Ok(())
    }

    fn fits(&self, w: usize, h: usize, format: TexelFormat) -> bool {
        (self.texture.width(), self.texture.height(), self.format) == (w, h, format)
    }
}

/// The targets of the engine passes, each made only when a call reads it and kept
/// between frames of the same size: the separate Gaussian's intermediate, the read-back
/// target of [`crate::Renderer`], and the copy of an sRGB-encoded destination that
/// [`Pipeline::blend_fog`] fogs. `fog(FogBlur::None)` and `blend_fog` into a linear
/// destination make none.
#[derive(Default)]
pub(super) struct EngineTargets {
    intermediate: Option<EngineTarget>,
    read_back: Option<EngineTarget>,
    blend_copy: Option<EngineTarget>,
}

/// Which engine targets a call needs.
#[derive(Clone, Copy, Default)]
struct Needs {
    intermediate: bool,
    read_back: bool,
    blend_copy: bool,
}

impl EngineTargets {
    /// Allocates what `needs` asks for at `w x h` and frees targets of another size.
    fn prepare(
        &mut self,
        gl: &Arc<glow::Context>,
        size: (usize, usize),
        precision: Precision,
        needs: Needs,
    ) -> Result<()> {
        let colour = precision.colour_format();
        for (slot, needed, format, what) in [
            (
                &mut self.intermediate,
                needs.intermediate,
                colour,
                "the fog's intermediate target",
            ),
            (
                &mut self.read_back,
                needs.read_back,
                colour,
                "the fog's read-back target",
            ),
            (
                &mut self.blend_copy,
                needs.blend_copy,
                TexelFormat::Rgba8,
                "the copy of the sRGB destination",
            ),
        ] {
            if needed {
                EngineTarget::ensure(slot, gl, size, format, what)?;
            } else if slot
                .as_ref()
                .is_some_and(|t| (t.texture.width(), t.texture.height()) != size)
            {
                *slot = None;
            }
        }
        Ok(())
    }

    fn get<'a>(slot: &'a Option<EngineTarget>, what: &str) -> Result<&'a EngineTarget> {
        slot.as_ref()
            .ok_or_else(|| Error::Gl(format!("internal: the fog's {what} not allocated")))
    }
}

/// The program keys of the engine passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) enum EngineKey {
    /// `fog.frag`.
    Fog {
        gauss_single: bool,
        write_weight: bool,
        srgb_in: bool,
        srgb_out: bool,
        bilinear: bool,
    },
    /// `gauss_blur.frag`.
    GaussBlur { srgb_out: bool, bilinear: bool },
    /// `fog_blend.frag`.
    Blend,
}

impl EngineKey {
    /// The file and its `#define`s.
    pub(super) fn source(self) -> (&'static str, &'static str, Vec<(&'static str, bool)>) {
        match self {
            EngineKey::Fog {
                gauss_single,
                write_weight,
                srgb_in,
                srgb_out,
                bilinear,
            } => (
                "fog.frag",
                FOG_FRAG,
                vec![
                    ("GAUSS_SINGLE", gauss_single),
                    ("WRITE_BLUR_WEIGHT", write_weight),
                    ("COLOUR_SRGB", srgb_in),
                    ("OUTPUT_SRGB", srgb_out),
                    ("GAUSS_BILINEAR", bilinear),
                ],
            ),
            EngineKey::GaussBlur { srgb_out, bilinear } => (
                "gauss_blur.frag",
                GAUSS_BLUR_FRAG,
                vec![
                    ("COLOUR_SRGB", false),
                    ("OUTPUT_SRGB", srgb_out),
                    ("GAUSS_BILINEAR", bilinear),
                ],
            ),
            EngineKey::Blend => ("fog_blend.frag", FOG_BLEND_FRAG, vec![]),
        }
    }

    /// Whether `gauss5.glsl` goes before the pass.
    pub(super) fn needs_gauss(self) -> bool {
        self != EngineKey::Blend
    }

    /// Whether the pass samples its image through the pipeline's bilinear sampler.
    fn bilinear(self) -> bool {
        match self {
            EngineKey::Fog {
                gauss_single,
                bilinear,
                ..
            } => gauss_single && bilinear,
            EngineKey::GaussBlur { bilinear, .. } => bilinear,
            EngineKey::Blend => false,
        }
    }
}

/// The GLSL of `gauss5.glsl`, for the pipeline's shader assembly.
pub(super) const GAUSS5: &str = GAUSS5_GLSL;

/// The uniforms of the engine passes besides the medium's.
pub(super) const ENGINE_UNIFORMS: [&str; 6] = [
    "u_colour",
    "u_depth",
    "u_origin",
    "u_gauss",
    "u_f",
    "brume_size",
];

impl Pipeline {
    /// Fogs `input` with `medium` at the input's camera and time ([`Input::frame`]) and
    /// blurs it as `blur` says (module docs), into `output`. The diffusion mode is [`Pipeline::render`]. The GL state changed and left
    /// is the same as a render's (see the parent module).
    pub fn fog(
        &mut self,
        input: &Input,
        medium: &dyn Medium,
        blur: &FogBlur,
        output: &Output,
    ) -> Result<Frame> {
        if let FogBlur::Diffusion(b) = blur {
            return self.render(input, medium, b, output);
        }
        let keys = self.engine_keys(blur, input.colour_encoding, output_encoding(output));
        self.prepare_engine(input, medium, blur, &keys, false)?;
        let result = self.with_output(input, output, |pipeline, destination| {
            pipeline.run_engine(input, medium, blur, &keys, destination)
        });
        Ok(Frame {
            schedule: no_diffusion(),
            passes: blur.engine_passes(),
            times: result?,
        })
    }

    /// [`Pipeline::fog`] into brume's float target, read back (RGBA, texel row 0 first).
    pub(crate) fn fog_and_read(
        &mut self,
        input: &Input,
        medium: &dyn Medium,
        blur: &FogBlur,
    ) -> Result<(Frame, Vec<[f32; 4]>)> {
        if let FogBlur::Diffusion(b) = blur {
            return self.render_and_read(input, medium, b);
        }
        let keys = self.engine_keys(blur, input.colour_encoding, Encoding::Linear);
        self.prepare_engine(input, medium, blur, &keys, true)?;
        let result = self
            .run_engine(input, medium, blur, &keys, &Destination::Internal)
            .and_then(|times| {
                let target = EngineTargets::get(&self.engine_targets.read_back, "read-back")?;
                Ok((times, target.framebuffer.read_rgba()?))
            });
        let (times, pixels) = result?;
        Ok((
            Frame {
                schedule: no_diffusion(),
                passes: blur.engine_passes(),
                times,
            },
            pixels,
        ))
    }

    /// [`Pipeline::fog`] into brume's own float target, read back as an image whose top
    /// row is the frame's top (GL's last row): what a tool that writes files wants.
    pub fn fog_to_image(
        &mut self,
        input: &Input,
        medium: &dyn Medium,
        blur: &FogBlur,
    ) -> Result<(Frame, RgbaImage)> {
        let (frame, pixels) = self.fog_and_read(input, medium, blur)?;
        let mut image = Grid::from_vec(input.width, input.height, pixels);
        image.flip_rows();
        Ok((frame, image))
    }

    /// Paper 003's post-process: draws the fog of a **grey** `medium`, at `frame`'s
    /// camera and time, over the host's framebuffer (which holds the scene),
    /// `C = τ·C + (1 − τ)·L∞`, reading only the depth texture. A destination of linear light ([`Encoding::Linear`]: a float or
    /// `SRGB8_ALPHA8` target) is blended by fixed-function GL in one pass (blend function
    /// `SRC_ALPHA, ONE_MINUS_SRC_ALPHA` for colour, `ZERO, ONE` for alpha, equation
    /// `FUNC_ADD`, all restored after). A destination holding sRGB-encoded values
    /// ([`Encoding::Srgb`]: plain 8-bit) cannot be blended by GL in linear light: its
    /// output rectangle is copied (`glBlitFramebuffer`) into an RGBA8 texture brume keeps
    /// between frames, which the fog pass decodes, fogs and encodes back over the
    /// destination, as [`Pipeline::fog`] does.
    pub fn blend_fog(
        &mut self,
        depth: glow::Texture,
        width: usize,
        height: usize,
        medium: &dyn Medium,
        frame: &FrameInputs,
        output: &Output,
    ) -> Result<Frame> {
        if medium.chromatic() {
            return Err(Error::invalid(
                "medium",
                medium.name(),
                "a grey medium for blending (one alpha cannot attenuate three channels \
                 differently); use Pipeline::fog",
            ));
        }
        let srgb = output_encoding(output) == Encoding::Srgb;
        let key = if srgb {
            EngineKey::Fog {
                gauss_single: false,
                write_weight: false,
                srgb_in: true,
                srgb_out: true,
                bilinear: false,
            }
        } else {
            EngineKey::Blend
        };
        let needs = Needs {
            blend_copy: srgb,
            ..Needs::default()
        };
        let mut input = Input {
            colour: depth,
            colour_encoding: Encoding::Linear,
            depth,
            width,
            height,
            frame: *frame,
        };
        self.prepare_engine_with(&input, medium, &FogBlur::None, &[key], needs)?;
        if let Some(copy) = &self.engine_targets.blend_copy {
            if srgb {
                input.colour = copy.texture.raw();
            }
        }
        let result = self.with_output(&input, output, |pipeline, destination| {
            pipeline.run_blend(&input, medium, key, destination)
        });
        Ok(Frame {
            schedule: no_diffusion(),
            passes: Passes::Engine(&["fog (blended)"]),
            times: result?,
        })
    }

    /// Checks the frame, compiles the passes `keys` and makes the targets they read:
    /// the intermediate of the separate Gaussian, and the read-back target when
    /// `read_back`.
    fn prepare_engine(
        &mut self,
        input: &Input,
        medium: &dyn Medium,
        blur: &FogBlur,
        keys: &[EngineKey],
        read_back: bool,
    ) -> Result<()> {
        let needs = Needs {
            intermediate: keys.len() == 2,
            read_back,
            blend_copy: false,
        };
        self.prepare_engine_with(input, medium, blur, keys, needs)
    }

    fn prepare_engine_with(
        &mut self,
        input: &Input,
        medium: &dyn Medium,
        blur: &FogBlur,
        keys: &[EngineKey],
        needs: Needs,
    ) -> Result<()> {
        medium.validate()?;
        medium.validate_frame(&input.frame)?;
        self.caps.require_size("input", input.width, input.height)?;
        let gauss = match blur {
            FogBlur::GaussSingle(g) | FogBlur::GaussSeparate(g) => {
                g.validate()?;
                if medium.frame_camera(&input.frame).is_none() {
                    return Err(Error::invalid(
                        "blur",
                        blur.name(),
                        format!(
                            "a medium with a camera (the Gaussian blur's weight grows with \
                             distance; {} has no camera): use none or diffusion",
                            medium.name()
                        ),
                    ));
                }
                Some(g)
            }
            _ => None,
        };
        let precision = gauss.map_or(Precision::F32, |g| g.precision);
        // The engine's float targets are read by texelFetch, or bilinearly only where
        // the driver filters them (engine_keys): rendering to them is all they need.
        if needs.intermediate || needs.read_back {
            self.caps.require_renderable(precision)?;
        }
        for &key in keys {
            self.program(ProgramKey::Engine(MediumId::of(medium), key), Some(medium))?;
        }
        self.upload_lookups(medium)?;
        self.engine_targets
            .prepare(&self.gl, (input.width, input.height), precision, needs)
    }

    /// brume's framebuffer for an internal destination, if `destination` is one.
    fn internal_target(&self, destination: &Destination) -> Result<Option<&Framebuffer>> {
        match destination {
            Destination::Internal => Ok(Some(
                &EngineTargets::get(&self.engine_targets.read_back, "read-back")?.framebuffer,
            )),
            _ => Ok(None),
        }
    }

    /// The one or two passes (`keys`, from [`Self::engine_keys`]) of a Gaussian or no-blur fog.
    fn run_engine(
        &self,
        input: &Input,
        medium: &dyn Medium,
        blur: &FogBlur,
        keys: &[EngineKey],
        destination: &Destination,
    ) -> Result<PassTimes> {
        let internal = self.internal_target(destination)?;
        let intermediate = match keys.len() {
            2 => Some(EngineTargets::get(
                &self.engine_targets.intermediate,
                "intermediate",
            )?),
            _ => None,
        };
        self.timed("running the fog passes", |pipeline, timer| {
            let gauss = match blur {
                FogBlur::GaussSingle(g) | FogBlur::GaussSeparate(g) => *g,
                _ => GaussBlur::default(),
            };
            let p = pipeline.compiled(ProgramKey::Engine(MediumId::of(medium), keys[0]))?;
            timer.pass(|| {
                // The encoding is compiled into the program (engine_keys).
                let origin = match intermediate {
                    Some(target) => {
                        target.framebuffer.bind_for_drawing();
                        [0, 0]
                    }
                    None => pipeline.bind_destination(destination, input, internal).0,
                };
                pipeline.use_program(p);
                bind_texture(&pipeline.gl, UNIT_MAIN, Some(input.colour));
                pipeline.bind_gauss_sampler(keys[0]);
                bind_texture(&pipeline.gl, UNIT_DEPTH, Some(input.depth));
                pipeline.set_engine_uniforms(p, medium, input, origin, gauss);
                draw_fullscreen(&pipeline.gl);
            })?;
            if let (Some(&blur_key), Some(target)) = (keys.get(1), intermediate) {
                let b = pipeline.compiled(ProgramKey::Engine(MediumId::of(medium), blur_key))?;
                timer.pass(|| {
                    let (origin, _) = pipeline.bind_destination(destination, input, internal);
                    pipeline.use_program(b);
                    target.texture.bind(UNIT_MAIN);
                    pipeline.bind_gauss_sampler(blur_key);
                    set_int(&pipeline.gl, b, "u_f", UNIT_MAIN as i32);
                    pipeline.set_engine_uniforms(b, medium, input, origin, gauss);
                    draw_fullscreen(&pipeline.gl);
                })?;
            }
            Ok(())
        })
        .map(|(times, ())| times)
    }

    /// Paper 003's pass: blended by GL over a linear destination ([`EngineKey::Blend`]),
    /// or, over an sRGB-encoded one, the destination's rectangle copied into
    /// `input.colour` (brume's RGBA8 copy) and fogged from it (`key` the sRGB fog pass).
    fn run_blend(
        &self,
        input: &Input,
        medium: &dyn Medium,
        key: EngineKey,
        destination: &Destination,
    ) -> Result<PassTimes> {
        let internal = self.internal_target(destination)?;
        let copy = match key {
            EngineKey::Blend => None,
            _ => Some(EngineTargets::get(
                &self.engine_targets.blend_copy,
                "sRGB copy",
            )?),
        };
        self.timed("running the fog passes", |pipeline, timer| {
            let gl = &pipeline.gl;
            let p = pipeline.compiled(ProgramKey::Engine(MediumId::of(medium), key))?;
            timer.pass(|| {
                let (origin, _) = pipeline.bind_destination(destination, input, internal);
                let (w, h) = (input.width as i32, input.height as i32);
                pipeline.use_program(p);
                if let Some(copy) = copy {
                    let [x, y] = origin;
                    // SAFETY: the destination (bound for reading just above) copied into
                    // brume's own RGBA8 target of the rectangle's size, then the
                    // destination bound for drawing again; scissor and rasterizer
                    // discard are off (enter_state).
                    unsafe {
                        gl.bind_framebuffer(glow::DRAW_FRAMEBUFFER, Some(copy.framebuffer.raw()));
                        gl.blit_framebuffer(
                            x,
                            y,
                            x + w,
                            y + h,
                            0,
                            0,
                            w,
                            h,
                            glow::COLOR_BUFFER_BIT,
                            glow::NEAREST,
                        );
                    }
                    pipeline.bind_destination(destination, input, internal);
                    bind_texture(gl, UNIT_MAIN, Some(input.colour));
                } else {
                    // SAFETY: blend state on the current context, restored by the
                    // caller's guard (documented in blend_fog).
                    unsafe {
                        gl.enable(glow::BLEND);
                        gl.blend_equation(glow::FUNC_ADD);
                        gl.blend_func_separate(
                            glow::SRC_ALPHA,
                            glow::ONE_MINUS_SRC_ALPHA,
                            glow::ZERO,
                            glow::ONE,
                        );
                    }
                }
                bind_texture(gl, UNIT_DEPTH, Some(input.depth));
                pipeline.set_engine_uniforms(p, medium, input, origin, GaussBlur::default());
                draw_fullscreen(gl);
            })
        })
        .map(|(times, ())| times)
    }

    /// The passes of a fog blurred by `blur` (not diffusion), compiled for the colour's
    /// and the destination's encodings: the sRGB conversions are compile-time switches
    /// because a run-time choice costs every pixel both ways on a software rasteriser
    /// (three `pow` per tap of the Gaussian). The Gaussian reads its image by bilinear
    /// fetches where the image is surely filterable and linear: a host's colour when the
    /// driver filters float textures (a host's RGBA32F could not be filtered otherwise;
    /// brume cannot ask a GLES 3.0 driver a texture's format) and is not sRGB-encoded
    /// RGBA8; brume's own intermediate when it is RGBA16F or float filtering exists.
    fn engine_keys(
        &self,
        blur: &FogBlur,
        colour: Encoding,
        destination: Encoding,
    ) -> Vec<EngineKey> {
        let (srgb_in, srgb_out) = (colour == Encoding::Srgb, destination == Encoding::Srgb);
        let float_linear = self.caps.texture_float_linear;
        match blur {
            FogBlur::GaussSeparate(g) => vec![
                EngineKey::Fog {
                    gauss_single: false,
                    write_weight: true,
                    srgb_in,
                    srgb_out: false,
                    bilinear: false,
                },
                EngineKey::GaussBlur {
                    srgb_out,
                    bilinear: float_linear || g.precision == crate::blur::Precision::F16,
                },
            ],
            _ => vec![EngineKey::Fog {
                gauss_single: matches!(blur, FogBlur::GaussSingle(_)),
                write_weight: false,
                srgb_in,
                srgb_out,
                bilinear: float_linear && !srgb_in,
            }],
        }
    }

    /// Binds the bilinear sampler on the image unit for a pass that wants it.
    fn bind_gauss_sampler(&self, key: EngineKey) {
        if key.bilinear() {
            // SAFETY: the pipeline's own sampler object on the current context.
            unsafe { self.gl.bind_sampler(UNIT_MAIN, Some(self.linear_sampler)) };
        }
    }

    fn set_engine_uniforms(
        &self,
        p: &crate::gpu::program::Program,
        medium: &dyn Medium,
        input: &Input,
        origin: [i32; 2],
        gauss: GaussBlur,
    ) {
        let gl = &self.gl;
        set_int(gl, p, "u_colour", UNIT_MAIN as i32);
        set_int(gl, p, "u_depth", UNIT_DEPTH as i32);
        set_value(gl, p, "u_origin", UniformValue::IVec2(origin));
        set_value(gl, p, "u_gauss", gauss.uniform());
        // σ0 does not matter without diffusion; 1 px keeps media's σ finite.
        self.set_medium_uniforms(p, medium, input, 1.0);
    }
}

/// The encoding an output asks for.
fn output_encoding(output: &Output) -> Encoding {
    match *output {
        Output::Framebuffer { encoding, .. } | Output::Texture { encoding, .. } => encoding,
    }
}

/// The schedule of a render without diffusion: zero steps.
fn no_diffusion() -> Schedule {
    Schedule::new(Scheme::Matched, 1.0, 1.0, 0.25).expect("a valid empty schedule")
}
