//! A dataset's frames, fogged one after another at several extinctions: what `brume batch`
//! does per frame, for any host (a dataset tool, the Python package).
//!
//! ```no_run
//! use brume::dataset::find_cityscapes;
//! use brume::photo::{Frame, FrameOptions};
//! # fn main() -> brume::Result<()> {
//! let mut headless = brume::Headless::new(None)?;
//! let opts = FrameOptions::default();
//! for item in find_cityscapes("cityscapes/leftImg8bit/val".as_ref())? {
//!     let mut frame = Frame::load(&item?, &opts)?; // CPU only: a loader thread may run it
//!     frame.refine(&opts, headless.renderer()?)?;
//!     frame.fog_each(headless.renderer()?, &opts, &[0.005, 0.01, 0.02], |beta, fogged| {
//!         let name = format!("{}_beta_{beta}.png", frame.item.stem);
//!         brume::io::output::write_rgba(name.as_ref(), &fogged.image)
//!     })?;
//! }
//! # Ok(()) }
//! ```
//!
//! [`Frame::load`] decodes and pre-processes (holes, sky, airlight), [`Frame::refine`]
//! upsamples and refines the range once on the GPU, and [`Frame::fog_each`] renders every
//! β from one upload of the image and the range.

use super::{preprocess, FogOptions, Photo, PrepareOptions, PreparedPhoto};
use crate::compat;
use crate::dataset::Item;
use crate::error::{Error, Result};
use crate::io::depth::DepthOptions;
use crate::io::mask::{self, SkyMaskFormat};
use crate::medium::haze::Haze;
use crate::medium::physical::{self, PhysicalFog, DEFAULT_ALBEDO};
use crate::medium::Medium;
use crate::raster::{Grid, RgbaImage, ScalarMap};
use crate::refine::{RangeFilter, RefineMode, RefinePlan};
use crate::renderer::Renderer;
use std::path::PathBuf;
use std::time::Instant;

/// Whose conventions a frame's fog follows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Conventions {
    /// brume's: the haze on linear light with the diffusion blur.
    #[default]
    Brume,
    /// Foggy Cityscapes': the blend in sRGB code values with the dark-channel airlight (or
    /// the given one), no blur ([`crate::compat`]).
    FoggyCityscapes,
}

/// How every frame of a dataset is read, prepared and fogged.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FrameOptions {
    /// How depth files are read; a frame's own camera or calibration file replaces
    /// [`DepthOptions::camera`] and [`DepthOptions::calib`].
    pub depth: DepthOptions,
    /// Pre-processing, the refinement's window and the airlight policy. Its masks are
    /// ignored: masks are files, [`FrameOptions::sky_mask`] and the frame's own.
    pub prepare: PrepareOptions,
    /// A sky mask for the frames without their own ([`Item::sky_mask`]), read as
    /// [`FrameOptions::sky_mask_format`] (`None`: from its name).
    pub sky_mask: Option<PathBuf>,
    /// How [`FrameOptions::sky_mask`] encodes the sky.
    pub sky_mask_format: Option<SkyMaskFormat>,
    /// An ego-vehicle mask for every frame; `None` takes it from a frame's Cityscapes
    /// labelIds sky mask.
    pub ego_mask: Option<PathBuf>,
    /// The guided filter's mode; `None` takes the frame's depth format's default
    /// ([`RefineMode::default_for`]: `repair` for Cityscapes disparity).
    pub refine_mode: Option<RefineMode>,
    /// The blur and the tint; the extinction is each β's ([`Frame::fog_each`]).
    pub fog: FogOptions,
    /// The single-scattering albedo of every β.
    pub albedo: f64,
    /// brume's fog or Foggy Cityscapes' blend.
    pub conventions: Conventions,
}

impl Default for FrameOptions {
    /// Depth formats guessed, pre-processing and the airlight from the sky, each format's
    /// refinement, paper 000's blur, albedo 1, brume's conventions.
    fn default() -> Self {
        FrameOptions {
            depth: DepthOptions::default(),
            prepare: PrepareOptions::default(),
            sky_mask: None,
            sky_mask_format: None,
            ego_mask: None,
            refine_mode: None,
            fog: FogOptions::default(),
            albedo: DEFAULT_ALBEDO,
            conventions: Conventions::Brume,
        }
    }
}

impl FrameOptions {
    /// The fog of extinction `beta` (1/m) with these options' albedo, blur and tint.
    pub fn fog_at(&self, beta: f64) -> Result<FogOptions> {
        Ok(FogOptions {
            extinction: super::Extinction::Physical(PhysicalFog::new(beta, self.albedo)?),
            ..self.fog
        })
    }
}

/// One frame of a dataset: its photo, prepared, with what loading it cost.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Where it came from (its files and output names).
    pub item: Item,
    /// The image and its range as loaded.
    pub photo: Photo,
    /// The range made ready for fog and the airlight.
    pub prepared: PreparedPhoto,
    /// Decoding the image and the depth, ms (wall).
    pub decode_ms: f64,
    /// Pre-processing, ms (wall).
    pub prep_ms: f64,
    /// The refinement and the range in metres, ms (wall), once [`Frame::refine`] ran.
    pub refine_ms: f64,
    /// The range in metres at the image's size, unknown pixels the farthest (in brume's
    /// conventions the sky at least [`super::SKY_RANGE_M`] away: [`PreparedPhoto::metres`]):
    /// what every β reads, made once by [`Frame::refine`].
    metres: Option<ScalarMap>,
    /// The depth's warnings ([`crate::io::depth::LoadedDepth::warnings`], which reads the
    /// map), worked out once: the frame's event and every output's log record give them.
    warnings: Vec<String>,
}

/// One β of a frame, fogged.
#[derive(Debug)]
pub struct FrameFog {
    /// The fogged image, linear RGB, alpha 1, row 0 at the top.
    pub image: RgbaImage,
    /// The haze as rendered (its `range_unit` the visibility in metres).
    pub haze: Haze,
    /// The largest σ of the blur, px.
    pub sigma_max: f64,
    /// Diffusion passes run (0 in Foggy Cityscapes' conventions).
    pub passes: u32,
    /// The GPU's time for the passes, ms; NaN where the timer's figures were rejected
    /// (0 without passes).
    pub gpu_ms: f64,
    /// The airlight as blended: linear RGB, or sRGB code values in Foggy Cityscapes'
    /// conventions.
    pub airlight: [f32; 3],
    /// Where the airlight came from (`sky`, `neutral`, `given`, `dark-channel` …).
    pub airlight_source: &'static str,
}

impl Frame {
    /// Loads `item`'s image, depth (in metres: its camera or calibration) and sky mask, and
    /// pre-processes the range (CPU only, so a loader thread can run it ahead of the GPU).
    ///
    /// Errors: the loaders', a depth not in metres, a sky mask of another size than the
    /// depth map or all sky, pre-processing's own.
    pub fn load(item: &Item, opts: &FrameOptions) -> Result<Frame> {
        let started = Instant::now();
        let depth_opts = frame_depth_options(&opts.depth, item);
        let photo = Photo::load(&item.image, &item.depth, &depth_opts)?;
        photo.require_metric_depth("depth", item.depth.display())?;
        let mut prepare = opts.prepare.clone();
        (prepare.sky_mask, prepare.ego_mask) = frame_masks(opts, item, &photo)?;
        let decode_ms = elapsed_ms(started);
        let started = Instant::now();
        let prepared = preprocess(&photo, &prepare)?;
        let warnings = photo.depth.warnings();
        Ok(Frame {
            item: item.clone(),
            photo,
            prepared,
            decode_ms,
            prep_ms: elapsed_ms(started),
            refine_ms: 0.0,
            metres: None,
            warnings,
        })
    }

    /// What the depth's loader says a user must see
    /// ([`crate::io::depth::LoadedDepth::warnings`] of the depth as loaded).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Upsamples and refines the range with the image (by `filter`: the GPU's
    /// [`Renderer`] or [`crate::refine::CpuFilter`]) and makes the range in metres every β
    /// reads. Returns the refinement that ran.
    pub fn refine(
        &mut self,
        opts: &FrameOptions,
        filter: &mut dyn RangeFilter,
    ) -> Result<RefinePlan> {
        let started = Instant::now();
        let mut refine = opts.prepare.refine;
        refine.mode = opts
            .refine_mode
            .unwrap_or(RefineMode::default_for(self.photo.depth.format));
        let plan = self.prepared.refine(&self.photo, &refine, filter)?;
        self.metres = Some(match opts.conventions {
            Conventions::Brume => self.prepared.metres()?,
            // Their τ = exp(−βR) of the range as made metric, the sky where pre-processing
            // put it.
            Conventions::FoggyCityscapes => physical::metric_range(&self.prepared.range)?.0,
        });
        self.refine_ms = elapsed_ms(started);
        Ok(plan)
    }

    /// The range in metres at the image's size that every β reads (unknown pixels the
    /// farthest); `None` until [`Frame::refine`] ran.
    pub fn metres(&self) -> Option<&ScalarMap> {
        self.metres.as_ref()
    }

    /// Fogs the frame at each extinction of `betas` (1/m), handing each result to `each`
    /// as it is read back; the image and the range are uploaded once. Stops at the first
    /// error (of the render or of `each`).
    pub fn fog_each(
        &self,
        renderer: &mut Renderer,
        opts: &FrameOptions,
        betas: &[f64],
        mut each: impl FnMut(f64, FrameFog) -> Result<()>,
    ) -> Result<()> {
        let metres = self.metres.as_ref().ok_or_else(|| {
            Error::invalid(
                "frame",
                &self.item.stem,
                "a refined frame: call Frame::refine before Frame::fog_each",
            )
        })?;
        let fogs: Vec<FogOptions> = betas
            .iter()
            .map(|&b| opts.fog_at(b))
            .collect::<Result<_>>()?;
        let hazes: Vec<Haze> = fogs
            .iter()
            .map(|f| f.haze(self.prepared.airlight))
            .collect::<Result<_>>()?;
        if opts.conventions == Conventions::FoggyCityscapes {
            let (airlight, source) =
                compat::foggy_cityscapes_airlight(&self.photo.image, opts.prepare.airlight);
            for ((&beta, haze), fog) in betas.iter().zip(&hazes).zip(&fogs) {
                let tau = compat::foggy_cityscapes_transmittance(metres, beta);
                let image = compat::foggy_cityscapes_at(&self.photo.image, &tau, airlight);
                each(
                    beta,
                    FrameFog {
                        image,
                        haze: *haze,
                        sigma_max: haze.sigma_max(fog.blur.sigma0),
                        passes: 0,
                        gpu_ms: 0.0,
                        airlight,
                        airlight_source: source,
                    },
                )?;
            }
            return Ok(());
        }
        let media: Vec<&dyn Medium> = hazes.iter().map(|h| h as &dyn Medium).collect();
        let source = self.prepared.airlight_from.name();
        renderer.render_each(&self.photo.image, metres, &media, &opts.fog.blur, |k, r| {
            let haze = hazes[k];
            each(
                betas[k],
                FrameFog {
                    image: r.image,
                    haze,
                    sigma_max: haze.sigma_max(opts.fog.blur.sigma0),
                    passes: r.schedule.steps,
                    gpu_ms: r.times.total_ms,
                    airlight: haze.airlight,
                    airlight_source: source,
                },
            )
        })
    }
}

/// `opts` with `item`'s camera and calibration files.
fn frame_depth_options(opts: &DepthOptions, item: &Item) -> DepthOptions {
    let mut opts = opts.clone();
    if item.camera.is_some() {
        opts.camera = item.camera.clone();
    }
    if item.calib.is_some() {
        opts.calib = item.calib.clone();
    }
    opts
}

/// The sky and ego-vehicle masks of `item` under `opts`, checked against the depth map:
/// the frame's own sky mask, else the shared one (none without pre-processing or sky
/// detection); the shared ego mask, else the ego vehicle of the frame's Cityscapes
/// labelIds.
fn frame_masks(opts: &FrameOptions, item: &Item, photo: &Photo) -> Result<Masks> {
    let Some(prep) = &opts.prepare.prep else {
        return Ok((None, None));
    };
    let own = item.sky_mask.as_deref().map(|p| (p, None));
    let shared = opts.sky_mask.as_deref().map(|p| (p, opts.sky_mask_format));
    let sky = own.or(shared).filter(|_| prep.detect_sky);
    let labels = item
        .sky_mask
        .as_deref()
        .filter(|p| SkyMaskFormat::from_file_name(p) == SkyMaskFormat::CityscapesLabelIds);
    let ego = opts.ego_mask.as_deref().or(labels);
    let masks = mask::load_range_masks(sky, ego, &photo.depth, &photo.depth_name)?;
    Ok((masks.sky, masks.ego))
}

/// A frame's sky and ego-vehicle masks.
type Masks = (Option<Grid<bool>>, Option<Grid<bool>>);

fn elapsed_ms(started: Instant) -> f64 {
    started.elapsed().as_secs_f64() * 1e3
}

/// τ as an 8-bit grey image (top row first) of `haze` on `metres`.
pub fn transmittance_rgb8(haze: &Haze, metres: &ScalarMap) -> Vec<[u8; 3]> {
    metres
        .as_slice()
        .iter()
        .map(|&r| {
            let t = if r.is_finite() {
                haze.transmission(f64::from(r) / haze.range_unit)[1]
            } else {
                0.0
            };
            let v = (t.clamp(0.0, 1.0) * 255.0).round() as u8;
            [v, v, v]
        })
        .collect()
}
