//! CPU buffers in, CPU buffers out: a thin wrapper over [`Pipeline`] that uploads the
//! image and the depth map as textures, renders into brume's own float target and reads
//! the result back. [`Headless`] pairs it with brume's own EGL context, for the CLI, the
//! benchmarks and the tests.

use crate::blur::{Blur, Precision};
use crate::camera::FrameInputs;
use crate::caps::{Capabilities, EglInfo};
use crate::egl::{GlContext, Platform};
use crate::error::{Error, Result};
use crate::gpu::framebuffer::Framebuffer;
use crate::gpu::texture::{TexelFormat, Texture};
use crate::gpu::timer::{Clock, PassTimes, Timing};
use crate::medium::Medium;
use crate::memory::Reservation;
use crate::pipeline::{Encoding, FogBlur, Frame, Input, Passes, Pipeline, RefineInput};
use crate::raster::{Grid, RgbImage, RgbaImage, ScalarMap};
use crate::refine::Refine;
use crate::schedule::Schedule;
use std::mem::ManuallyDrop;
use std::sync::Arc;

/// The result of one render from CPU buffers.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// Final linear RGB (alpha 1), in the input's row order.
    pub image: RgbaImage,
    /// The schedule that ran.
    pub schedule: Schedule,
    /// Which passes ran ([`Rendered::pass_names`] names them).
    pub passes: Passes,
    /// Per-pass times, with the clock that produced them (unavailable when the GPU
    /// timer's figures were rejected, or with timing off: see [`Renderer::set_timing`]).
    pub times: PassTimes,
}

impl Rendered {
    /// The name of each pass, one per entry of `times.pass_ms` ([`Frame::pass_names`]).
    pub fn pass_names(&self) -> Vec<String> {
        self.passes.names(self.schedule.steps)
    }
}

/// The pipeline with CPU-buffer input and output, on a context that is current. Its
/// timing is [`Timing::Blocking`] unless set otherwise: it waits for the read-back anyway,
/// and the `brume` program and its benchmarks report each call's times. Between calls it
/// keeps its targets and the last upload's textures (16 bytes per pixel) for the next
/// frame of the same size; dropping it frees them.
pub struct Renderer {
    pipeline: Pipeline,
    /// The uploads' textures, kept for the next call of the same size: allocating them
    /// anew each call cost a 2048x1024 frame ~50 ms on llvmpipe (zeroed pages).
    uploads: Uploads,
}

/// The textures a call uploads its buffers into, each reused while its size fits.
#[derive(Default)]
struct Uploads {
    /// The image, RGB32F.
    colour: Option<Texture>,
    /// The depth or range, R32F.
    scalar: Option<Texture>,
}

impl Uploads {
    /// Uploads `image` and `scalar` (a depth or range map) bottom row first, into the
    /// kept textures or new ones of their sizes; returns their GL names.
    fn upload(
        &mut self,
        gl: &Arc<glow::Context>,
        image: &RgbImage,
        scalar: &ScalarMap,
    ) -> Result<(glow::Texture, glow::Texture)> {
        // The uploads set the pixel store and unbind a host's pixel buffers for
        // themselves, and put them back (crate::gpu::state). Buffers hold the image's
        // top row first, GL textures the bottom row first: the rows are uploaded upside
        // down (row by row from the caller's buffers, no staging copy), so that a medium
        // with a camera sees the sky at the top.
        let colour = Texture::kept(
            &mut self.colour,
            gl,
            image.width(),
            image.height(),
            TexelFormat::Rgb32F,
        )?;
        colour.upload_flipped(image.as_slice().as_flattened());
        let colour = colour.raw();
        let depth = Texture::kept(
            &mut self.scalar,
            gl,
            scalar.width(),
            scalar.height(),
            TexelFormat::R32F,
        )?;
        depth.upload_flipped(scalar.as_slice());
        Ok((colour, depth.raw()))
    }

    /// Bytes of the kept textures, which the next upload reuses or frees before it
    /// allocates.
    fn bytes(&self) -> u64 {
        [&self.colour, &self.scalar]
            .into_iter()
            .flatten()
            .map(Texture::bytes)
            .sum()
    }
}

impl Renderer {
    /// Builds the pipeline on `gl`, which must be current on this thread, with
    /// [`Timing::Blocking`].
    pub fn new(gl: Arc<glow::Context>) -> Result<Self> {
        let mut pipeline = Pipeline::new(gl)?;
        pipeline.set_timing(Timing::Blocking);
        Ok(Renderer {
            pipeline,
            uploads: Uploads::default(),
        })
    }

    /// Sets when calls time their passes ([`Pipeline::set_timing`]).
    pub fn set_timing(&mut self, timing: Timing) {
        self.pipeline.set_timing(timing);
    }

    /// When calls time their passes.
    pub fn timing(&self) -> Timing {
        self.pipeline.timing()
    }

    /// The driver's capabilities, detected once.
    pub fn caps(&self) -> &Capabilities {
        self.pipeline.caps()
    }

    /// The clock [`Timing::Blocking`] times with.
    pub fn preferred_clock(&self) -> Clock {
        self.pipeline.preferred_clock()
    }

    /// Bytes of system memory the uploads' kept textures hold: a software renderer's, none
    /// on a GPU (for the refinement's memory check).
    pub(crate) fn kept_upload_bytes(&self) -> u64 {
        if self.caps().software() {
            self.uploads.bytes()
        } else {
            0
        }
    }

    /// Bytes of the textures kept between frames ([`Renderer::free_kept_textures`]): the
    /// next frame reuses them, or frees them before it makes others, so its memory check
    /// does not count them again.
    pub fn kept_texture_bytes(&self) -> u64 {
        self.uploads.bytes() + self.pipeline.kept_diffusion_bytes()
    }

    /// Frees the textures kept between frames, the uploads' and the diffusion's targets
    /// (64 bytes per pixel of a haze frame in f32, in system memory on a software
    /// renderer); the next frame makes them again. For a host that needs the memory for
    /// other work between frames.
    pub fn free_kept_textures(&mut self) {
        self.uploads = Uploads::default();
        self.pipeline.free_kept_targets();
    }

    /// The texture-in, framebuffer-out pipeline underneath.
    pub fn pipeline(&mut self) -> &mut Pipeline {
        &mut self.pipeline
    }

    /// Renders `image` (linear RGB) fogged by `medium` from `depth` (what the medium
    /// reads: normalised range for [`crate::medium::Haze`] by default) and blurred as
    /// `blur` says: a photo's render, with no camera and time 0
    /// ([`FrameInputs::default`]; [`Renderer::render_fog`] takes them).
    pub fn render(
        &mut self,
        image: &RgbImage,
        depth: &ScalarMap,
        medium: &dyn Medium,
        blur: &Blur,
    ) -> Result<Rendered> {
        let blur = FogBlur::Diffusion(*blur);
        self.render_fog(image, depth, medium, &FrameInputs::default(), &blur)
    }

    /// Renders `image` fogged by `medium` at `frame`'s camera and time (a medium that
    /// needs a camera reads a depth buffer's window depth from `depth`) and blurred as
    /// `blur` says: paper 001's Gaussian modes, no blur, or the diffusion blur (see
    /// [`FogBlur`]). One medium value renders any number of frames.
    pub fn render_fog(
        &mut self,
        image: &RgbImage,
        depth: &ScalarMap,
        medium: &dyn Medium,
        frame: &FrameInputs,
        blur: &FogBlur,
    ) -> Result<Rendered> {
        self.check_frame(image, depth, medium, frame)?;
        let size = (image.width(), image.height());
        let _reserved = match blur {
            FogBlur::Diffusion(b) => self.check_memory(size, medium, b)?,
            _ => None,
        };
        self.with_textures(image, depth, frame, |pipeline, input| {
            pipeline.fog_and_read(input, medium, blur)
        })
    }

    /// [`Renderer::render`] of one photo with each of `media` in turn (a dataset's
    /// extinctions), the image and the range uploaded once; each result goes to `each`
    /// (with its index in `media`) as soon as it is read back. Stops at the first error.
    pub fn render_each(
        &mut self,
        image: &RgbImage,
        depth: &ScalarMap,
        media: &[&dyn Medium],
        blur: &Blur,
        mut each: impl FnMut(usize, Rendered) -> Result<()>,
    ) -> Result<()> {
        let frame = FrameInputs::default();
        // One reservation at a time, the last one held while the media render in turn on
        // the same textures (a dataset's are of one kind, and need the same).
        let mut reserved = None;
        for medium in media {
            self.check_frame(image, depth, *medium, &frame)?;
            drop(reserved.take());
            reserved = self.check_memory((image.width(), image.height()), *medium, blur)?;
        }
        let blur = FogBlur::Diffusion(*blur);
        let (w, h) = (image.width(), image.height());
        let (colour, depth_texture) = self.upload_frame(image, depth)?;
        let input = input_of(colour, depth_texture, w, h, frame);
        for (k, medium) in media.iter().enumerate() {
            let (frame, pixels) = self.pipeline.fog_and_read(&input, *medium, &blur)?;
            each(k, rendered_from(frame, pixels, w, h))?;
        }
        Ok(())
    }

    /// Refines `range` (> 0 everywhere, of the image's size or smaller by one factor) with
    /// `image` (linear RGB) as guide, on the GPU ([`crate::refine`]): the refined range at
    /// the image's size, row 0 at the top as given, and the passes' times.
    pub fn refine(
        &mut self,
        image: &RgbImage,
        range: &ScalarMap,
        opts: &Refine,
    ) -> Result<(ScalarMap, PassTimes)> {
        opts.grid(
            (image.width(), image.height()),
            (range.width(), range.height()),
        )?;
        self.on_range_textures(image, range, |pipeline, input| {
            pipeline.refine_range(input, opts)
        })
    }

    /// Upsamples `range` (> 0 everywhere, smaller than `image` by one factor) to the
    /// image's size by joint bilateral upsampling on the GPU
    /// ([`crate::refine::joint_bilateral_upsample_reference`]), row 0 at the top.
    pub fn upsample(
        &mut self,
        image: &RgbImage,
        range: &ScalarMap,
        sigma_colour: f64,
    ) -> Result<(ScalarMap, PassTimes)> {
        self.on_range_textures(image, range, |pipeline, input| {
            pipeline.upsample_range(input, sigma_colour)
        })
    }

    /// Uploads the image and the range, runs `pass` on them and reads its R32F range back.
    fn on_range_textures(
        &mut self,
        image: &RgbImage,
        range: &ScalarMap,
        pass: impl FnOnce(&mut Pipeline, &RefineInput) -> Result<(Texture, PassTimes)>,
    ) -> Result<(ScalarMap, PassTimes)> {
        let (w, h) = (image.width(), image.height());
        self.caps().require_size("image", w, h)?;
        crate::refine::check_positive(range)?;
        let gl = Arc::clone(self.pipeline.gl());
        let (colour, range_texture) = self.uploads.upload(&gl, image, range)?;
        let (rw, rh) = (range.width(), range.height());
        let input = RefineInput {
            colour,
            colour_encoding: Encoding::Linear,
            width: w,
            height: h,
            range: range_texture,
            range_width: rw,
            range_height: rh,
        };
        let (refined, times) = pass(&mut self.pipeline, &input)?;
        let framebuffer = Framebuffer::over(&gl, &[&refined], "the refined range")?;
        let texels = framebuffer.read_red()?;
        let mut out = Grid::from_vec(w, h, texels);
        out.flip_rows();
        Ok((out, times))
    }

    fn check_frame(
        &self,
        image: &RgbImage,
        depth: &ScalarMap,
        medium: &dyn Medium,
        frame: &FrameInputs,
    ) -> Result<()> {
        let (w, h) = (image.width(), image.height());
        self.caps().require_size("image", w, h)?;
        if (w, h) != (depth.width(), depth.height()) {
            return Err(Error::size_mismatch(
                "image",
                (w, h),
                "range map",
                (depth.width(), depth.height()),
            ));
        }
        medium.validate()?;
        medium.validate_frame(frame)
    }

    /// Uploads the buffers, runs `render` on them and reads the result back.
    fn with_textures(
        &mut self,
        image: &RgbImage,
        depth: &ScalarMap,
        frame: &FrameInputs,
        render: impl FnOnce(&mut Pipeline, &Input) -> Result<(Frame, Vec<[f32; 4]>)>,
    ) -> Result<Rendered> {
        let (w, h) = (image.width(), image.height());
        let (colour, depth_texture) = self.upload_frame(image, depth)?;
        let input = input_of(colour, depth_texture, w, h, *frame);
        let (frame, pixels) = render(&mut self.pipeline, &input)?;
        Ok(rendered_from(frame, pixels, w, h))
    }

    /// The image (RGB32F) and the depth (R32F) uploaded, bottom row first, into the
    /// kept textures ([`Uploads`]).
    fn upload_frame(
        &mut self,
        image: &RgbImage,
        depth: &ScalarMap,
    ) -> Result<(glow::Texture, glow::Texture)> {
        let gl = Arc::clone(self.pipeline.gl());
        self.uploads.upload(&gl, image, depth)
    }

    /// On a software renderer, refuses a frame whose textures and read-back would not fit
    /// in the memory left, before allocating any of it (see [`crate::memory`]), and
    /// reserves that memory while the frame renders. The textures kept from the last frame
    /// are not counted twice: the frame reuses them, or frees them before it allocates
    /// others.
    fn check_memory(
        &self,
        (w, h): (usize, usize),
        medium: &dyn Medium,
        blur: &Blur,
    ) -> Result<Option<Reservation>> {
        if !self.caps().software() {
            return Ok(None);
        }
        let coarse = blur.coarse_bytes_per_pixel(medium);
        let per_pixel = bytes_per_pixel(blur.precision, medium) + coarse;
        let kept = self.kept_texture_bytes();
        let needed = (per_pixel * (w as u64) * (h as u64)).saturating_sub(kept);
        let mut hint = format!(
            "this renderer keeps textures in system memory ({per_pixel} bytes per pixel here); "
        );
        if blur.precision == Precision::F32 {
            let half = bytes_per_pixel(Precision::F16, medium) + coarse;
            hint.push_str(&format!("use precision f16 ({half} bytes per pixel) or "));
        } else {
            hint.push_str("use ");
        }
        hint.push_str("a smaller image");
        crate::memory::reserve(&format!("a {w}x{h} render"), needed, &hint).map(Some)
    }
}

/// The pipeline's input over uploaded textures, for `frame`.
fn input_of(
    colour: glow::Texture,
    depth: glow::Texture,
    width: usize,
    height: usize,
    frame: FrameInputs,
) -> Input {
    Input {
        colour,
        colour_encoding: Encoding::Linear,
        depth,
        width,
        height,
        frame,
    }
}

/// A read-back (bottom row first) as a render's result, top row first.
fn rendered_from(frame: Frame, pixels: Vec<[f32; 4]>, w: usize, h: usize) -> Rendered {
    let mut image = Grid::from_vec(w, h, pixels);
    image.flip_rows();
    Rendered {
        image,
        schedule: frame.schedule,
        passes: frame.passes,
        times: frame.times,
    }
}

/// Bytes per pixel of one CPU-buffer render: the uploads (RGB32F colour, R32F depth), the
/// read-back and the pipeline's own textures.
fn bytes_per_pixel(precision: Precision, medium: &dyn Medium) -> u64 {
    12 + 4 + READ_BACK_BYTES_PER_PIXEL + Pipeline::bytes_per_pixel(precision, medium)
}

/// Bytes per pixel of a render's read-back (RGBA32F, 16) and what its caller makes of it:
/// `brume render`'s resident memory grew by 18.7 bytes per pixel besides the textures from
/// the render's memory check to its peak writing a 4000x3000 PNG, 23.7 an EXR (its float
/// channels); up to 12 more than the read-back, a float RGB copy.
const READ_BACK_BYTES_PER_PIXEL: u64 = 28;

/// brume's own headless context (EGL, no window) with a [`Renderer`] on it. Every call
/// makes the context current first, so several may live on one thread; dropping one
/// deletes its objects on its own context and leaves the current context as it was.
pub struct Headless {
    // Dropped by hand in Drop, with the context current; `ctx` after it.
    renderer: ManuallyDrop<Renderer>,
    ctx: GlContext,
}

impl Headless {
    /// Opens an EGL context (see [`GlContext::new`]) and builds the renderer on it.
    pub fn new(platform: Option<Platform>) -> Result<Self> {
        let ctx = GlContext::new(platform)?;
        let mut renderer = Renderer::new(Arc::clone(ctx.gl()))?;
        renderer.pipeline.caps_mut().egl = Some(EglInfo::of(&ctx));
        Ok(Headless {
            renderer: ManuallyDrop::new(renderer),
            ctx,
        })
    }

    /// The renderer, with this context made current.
    pub fn renderer(&mut self) -> Result<&mut Renderer> {
        self.ctx.make_current()?;
        Ok(&mut self.renderer)
    }

    /// [`Renderer::render`] on this context.
    pub fn render(
        &mut self,
        image: &RgbImage,
        depth: &ScalarMap,
        medium: &dyn Medium,
        blur: &Blur,
    ) -> Result<Rendered> {
        self.renderer()?.render(image, depth, medium, blur)
    }

    /// [`Renderer::render_fog`] on this context.
    pub fn render_fog(
        &mut self,
        image: &RgbImage,
        depth: &ScalarMap,
        medium: &dyn Medium,
        frame: &FrameInputs,
        blur: &FogBlur,
    ) -> Result<Rendered> {
        self.renderer()?
            .render_fog(image, depth, medium, frame, blur)
    }

    /// The driver's capabilities, with the EGL facts.
    pub fn caps(&self) -> &Capabilities {
        self.renderer.caps()
    }

    /// The clock [`Timing::Blocking`] times with.
    pub fn preferred_clock(&self) -> Clock {
        self.renderer.preferred_clock()
    }

    /// Sets when calls time their passes ([`Renderer::set_timing`]; makes no GL call).
    pub fn set_timing(&mut self, timing: Timing) {
        self.renderer.set_timing(timing);
    }

    /// The EGL context.
    pub fn context(&self) -> &GlContext {
        &self.ctx
    }
}

impl Drop for Headless {
    fn drop(&mut self) {
        let renderer = &mut self.renderer;
        // SAFETY: dropped once, here, with its own context current so that the GL names
        // it deletes are its own and not another context's.
        let dropped = self
            .ctx
            .with_current(|| unsafe { ManuallyDrop::drop(renderer) });
        if let Err(e) = dropped {
            // Its objects go with the context, destroyed next.
            log::warn!("could not make the context current to free its objects: {e}");
        }
    }
}
