//! Argument definitions (clap derive). Help texts are the user manual: say units, defaults
//! and what each value does.
//!
//! Every option whose value is not a path takes `allow_hyphen_values`, so that `--seed -1`
//! or `--airlight -1,0,0` reaches the check that names the option instead of clap's
//! "unexpected argument '-1'" (a test in `cli` walks every option).

use super::bench::BenchCommand;
use brume::blur::{DEFAULT_RHO_MAX, DEFAULT_SIGMA0};
use brume::egl::Platform;
use brume::io::depth::{DepthFormat, DepthKind};
use brume::io::mask::SkyMaskFormat;
use brume::medium::haze;
use brume::{Precision, Scheme};
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

/// Add physically based haze and fog to RGBD images, on OpenGL ES 3.2 through EGL
/// (headless: no display needed).
///
/// Quick start: `brume render` renders the built-in demo scene to brume-demo.png.
#[derive(Parser, Debug)]
#[command(name = "brume", version, propagate_version = true)]
pub struct Cli {
    /// EGL display to open: surfaceless (Mesa, no window system), device (EGL device,
    /// the headless route on NVIDIA) or default (eglGetDisplay). Default: the first of
    /// these that works, in that order.
    #[arg(
        long,
        global = true,
        value_name = "PLATFORM",
        allow_hyphen_values = true
    )]
    pub egl: Option<Platform>,

    /// More log output on stderr (-v info, -vv debug). RUST_LOG overrides.
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    pub verbose: u8,

    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render haze into an image (no input: the built-in demo scene).
    Render(Box<RenderArgs>),
    /// Compare two images: SSIM and HSV-histogram correlation (paper 002, sec. 7.2.3).
    Compare(CompareArgs),
    /// Render brume's procedural 3D scene and fog it as an engine would (papers 001, 003):
    /// distance or layered fog, blurred by paper 001's Gaussian or brume's diffusion.
    Scene(SceneArgs),
    /// Show the EGL platform, GL driver and the capabilities brume uses.
    Info(InfoArgs),
    /// A window that re-renders the fog as its parameters move: the demo, a photo with
    /// depth (`view render …`) or brume's 3D scene (`view scene …`).
    #[cfg(all(feature = "viewer", not(target_os = "android")))]
    View(ViewArgs),
    /// Fog a dataset: Cityscapes frames found under folders, or a CSV manifest, for each
    /// β; resumable and sharded (Foggy Cityscapes' output names).
    Batch(BatchArgs),
    /// Pre-process a range map (fill holes, find the sky, matte the horizon) and write it.
    Prep(PrepArgs),
    /// Reproduce paper 000's accuracy (fig. 6) and speed (fig. 7) experiments, and
    /// paper 002's turbidity estimation (Table 1).
    #[command(subcommand)]
    Bench(BenchCommand),
    /// Render a Preetham clear sky (paper 002, sec. 3.2) as a fisheye image.
    Sky(super::sky::SkyArgs),
    /// Estimate the atmospheric turbidity of a fisheye sky image (paper 002, sec. 3.4).
    Turbidity(super::sky::TurbidityArgs),
}

/// `brume info`.
#[derive(Args, Clone, Debug)]
pub struct InfoArgs {
    /// Print one JSON object on stdout instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Where the depth comes from and how to read it.
#[derive(Args, Debug, Clone)]
pub struct DepthArgs {
    /// Depth, range or disparity map: Middlebury 2014 disp0.pfm (with --calib), 8-bit
    /// disparity PNG (Middlebury 2006), 16-bit PNG (KITTI, NYU, TUM, Android DEPTH16,
    /// ARCore, Cityscapes disparity with --camera, or --depth-scale), float EXR/TIFF/PFM,
    /// or .npy.
    #[arg(long, value_name = "PATH")]
    pub depth: Option<PathBuf>,

    /// Middlebury calib.txt with the intrinsics, baseline and doffs of the depth map.
    #[arg(long, value_name = "PATH")]
    pub calib: Option<PathBuf>,

    /// Cityscapes NAME_camera.json (baseline in metres, intrinsics fx, fy, u0, v0) of a
    /// NAME_disparity.png. Default: NAME_camera.json beside the disparity, or in the
    /// dataset's layout (camera/SPLIT/CITY/ for disparity/SPLIT/CITY/).
    #[arg(long, value_name = "PATH")]
    pub camera: Option<PathBuf>,

    /// What the depth values are: depth (along the optical axis), range (distance to the
    /// camera centre), disparity (px), or zbuffer (a rendered frame's OpenGL window depth
    /// in [0, 1], with --near, --far and --fov). Default: what the format implies.
    #[arg(long, value_name = "KIND", allow_hyphen_values = true)]
    pub depth_kind: Option<DepthKind>,

    /// Depth file format: auto, middlebury2014, middlebury2006, kitti, nyu, tum, png16,
    /// float, android-depth16 (Camera2 DEPTH16 as a 16-bit PNG: low 13 bits range in mm,
    /// high 3 bits confidence, read as range), arcore (ARCore 16-bit depth PNG: mm along
    /// the optical axis, becomes range with --fov or --focal), cityscapes (16-bit
    /// disparity PNG, p > 0 is (p − 1)/256 px, with its camera file: see --camera; auto
    /// picks it for a 16-bit PNG whose camera file is given or found).
    #[arg(
        long,
        value_name = "FORMAT",
        allow_hyphen_values = true,
        default_value = "auto"
    )]
    pub depth_format: DepthFormat,

    /// Units per stored value of a 16-bit PNG (e.g. 0.001 for millimetres to metres).
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub depth_scale: Option<f64>,

    /// Focal length in px, for disparity to depth and depth to range (Middlebury 2006
    /// default: 3740).
    #[arg(long, value_name = "PX", allow_hyphen_values = true)]
    pub focal: Option<f64>,

    /// Stereo baseline in mm, for disparity to depth (Middlebury 2006 default: 160).
    #[arg(long, value_name = "MM", allow_hyphen_values = true)]
    pub baseline: Option<f64>,

    /// Disparity offset (doffs / dmin) in px added to every disparity (Middlebury 2006
    /// default: 270).
    #[arg(long, value_name = "PX", allow_hyphen_values = true)]
    pub disparity_offset: Option<f64>,

    /// Near clipping plane of the projection that wrote a z-buffer (--depth-kind zbuffer),
    /// in the scene's units.
    #[arg(long, value_name = "D", allow_hyphen_values = true)]
    pub near: Option<f64>,

    /// Far clipping plane of the projection that wrote a z-buffer.
    #[arg(long, value_name = "D", allow_hyphen_values = true)]
    pub far: Option<f64>,

    /// Vertical field of view in degrees: of a z-buffer's projection, or of a depth map
    /// (instead of --focal) to turn depth into range.
    #[arg(
        long,
        value_name = "DEG",
        allow_hyphen_values = true,
        conflicts_with = "focal"
    )]
    pub fov: Option<f64>,

    /// --depth-format android-depth16: samples whose DEPTH16 confidence is below this
    /// are unknown, from 0 (keep every measured sample) to 1 (only code 0, 100 %); code
    /// c ≥ 1 means (c − 1)/7 [default: 0.5].
    #[arg(long, value_name = "C", allow_hyphen_values = true)]
    pub min_confidence: Option<f64>,
}

/// Options of the range pre-processing (paper 000, sec. 4.1).
#[derive(Args, Debug, Clone)]
pub struct PrepOptionArgs {
    /// Width µ of the horizon margin matted into the sky, in px [default: 8].
    #[arg(long, value_name = "PX", allow_hyphen_values = true)]
    pub margin: Option<f64>,

    /// Sky range Smax as a multiple of the largest measured range Rmax, > 1 [default: 1.5].
    #[arg(long, value_name = "F", allow_hyphen_values = true)]
    pub sky_factor: Option<f64>,

    /// Never classify unknown regions as sky (fill every hole).
    #[arg(long)]
    pub no_sky: bool,

    /// Smallest area of an unknown region, as a fraction of the image, that can be sky
    /// [default: 0.01].
    #[arg(long, value_name = "FRACTION", allow_hyphen_values = true)]
    pub sky_min_area: Option<f64>,

    /// Seed of the RANSAC hole filling, a whole number ≥ 0; a given seed always gives the
    /// same result [default: 0].
    // Signed and wide, so that a negative seed reaches the range check that names it.
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub seed: Option<i128>,

    /// Sky mask PNG from semantic segmentation, the depth map's size: it is the sky,
    /// instead of detection (known range under it is replaced too).
    #[arg(long, value_name = "PATH.png", conflicts_with = "no_sky")]
    pub sky_mask: Option<PathBuf>,

    /// How --sky-mask encodes the sky: binary (non-zero = sky), cityscapes-labelids
    /// (Cityscapes label id 23) or cityscapes-trainids (train id 10) [default: from the
    /// name: *_labelIds.png → cityscapes-labelids, *_labelTrainIds.png →
    /// cityscapes-trainids, else binary].
    #[arg(
        long,
        value_name = "FORMAT",
        requires = "sky_mask",
        allow_hyphen_values = true
    )]
    pub sky_mask_format: Option<SkyMaskFormat>,

    /// Far outliers: known range above K × the 99th percentile of the range outside the
    /// sky, in a patch under 0.05 % of the image, is taken as unknown before the farthest
    /// range sets the scale; K ≥ 1, or 0 to keep every value [default: 2].
    #[arg(long, value_name = "K", allow_hyphen_values = true)]
    pub far_outlier_factor: Option<f64>,

    /// Local outliers: a patch of known range whose disparity (1/range) differs by more
    /// than F times from the median of its neighbourhood, at most 2.5 % of the image's
    /// longer side across (stereo mismatches: 200-550 m on a van 7 m away), is taken as
    /// unknown and filled from the surface round it; F > 1, or 0 to keep every value
    /// [default: 3].
    #[arg(long, value_name = "F", allow_hyphen_values = true)]
    pub local_outliers: Option<f64>,

    /// Ego-vehicle mask PNG, the depth map's size: binary (non-zero = the car's own hood)
    /// or, named *_labelIds.png, Cityscapes label ids (label 1 = ego vehicle). Its pixels
    /// get range 0 (never fogged) and their range is not used.
    #[arg(long, value_name = "PATH.png")]
    pub ego_mask: Option<PathBuf>,
}

/// `brume render`.
#[derive(Args, Clone, Debug)]
#[command(group(clap::ArgGroup::new("depth_source").args(["depth", "transmittance_map"])))]
pub struct RenderArgs {
    /// Colour image: PNG or JPEG (8- or 16-bit sRGB), or OpenEXR or PFM (linear float, as
    /// renderers and engines write). Without --image and --depth the built-in demo scene
    /// is rendered.
    #[arg(long, value_name = "PATH", requires = "depth_source")]
    pub image: Option<PathBuf>,

    /// A transmittance map to apply instead of computing τ from a depth map: an 8- or
    /// 16-bit grey PNG of the image's size, such as Foggy Cityscapes'
    /// {name}_leftImg8bit_transmittance_beta_{β}.png. Rendered with brume's airlight and
    /// diffusion blur (the blur from the optical depth −ln τ; --lambda 0 for none), or
    /// with --compat foggy-cityscapes.
    #[arg(
        long,
        value_name = "PATH.png",
        requires = "image",
        conflicts_with_all = ["depth", "beta", "visibility", "ka", "ks", "medium"]
    )]
    pub transmittance_map: Option<PathBuf>,

    /// Whose conventions: brume (the default: the blend in linear light, the diffusion
    /// blur, the airlight from the sky found) or foggy-cityscapes (Sakaridis et al. 2018:
    /// the blend in sRGB code values, no blur, the airlight by the dark-channel rule), for
    /// data comparable with Foggy Cityscapes. foggy-cityscapes needs --beta or
    /// --visibility (or --transmittance-map).
    #[arg(long, value_enum, allow_hyphen_values = true)]
    pub compat: Option<Compat>,

    #[command(flatten)]
    pub depth: DepthArgs,

    /// Output file: .png (8-bit sRGB), .pfm (float RGB, linear) or .exr (float RGBA,
    /// linear). Default for the demo: brume-demo.png. Must not be one of the inputs.
    #[arg(long, short, value_name = "PATH")]
    pub out: Option<PathBuf>,

    /// Absorption coefficient κa per unit of normalised range (attenuation only): the
    /// frame's largest range counts as 1. For fog in metres see --beta [default: 0.25].
    #[arg(long, value_name = "K", allow_hyphen_values = true)]
    pub ka: Option<f64>,

    /// Scattering coefficient κs per unit of normalised range (attenuation and blur)
    /// [default: 0.75].
    #[arg(long, value_name = "K", allow_hyphen_values = true)]
    pub ks: Option<f64>,

    /// Extinction β in m⁻¹, instead of --ka/--ks: fog in physical units on range in
    /// metres, not normalised, so the same β is the same fog in every frame (Foggy
    /// Cityscapes: 0.005, 0.01, 0.02). τ = exp(−β·R); blur σ = σ0 +
    /// λ·√(a·ln 20)·min(β·R/ln 20, 1)^(3/2), a = --albedo. Needs metric range:
    /// middlebury2014 with calib.txt, cityscapes with its camera file, kitti, nyu, tum,
    /// android-depth16, arcore, png16 with --depth-scale, or a disparity with --focal and
    /// --baseline.
    #[arg(
        long,
        value_name = "PER_M",
        allow_hyphen_values = true,
        conflicts_with_all = ["ka", "ks", "visibility"]
    )]
    pub beta: Option<f64>,

    /// Meteorological visibility V in metres, instead of --beta: β = ln 20/V ≈ 2.996/V
    /// (τ falls to 5 % at V). Foggy Cityscapes: 600, 300, 150.
    #[arg(
        long,
        value_name = "M",
        allow_hyphen_values = true,
        conflicts_with_all = ["ka", "ks"]
    )]
    pub visibility: Option<f64>,

    /// With --beta or --visibility: single-scattering albedo a in [0, 1]; βs = a·β
    /// scatters (veils and blurs), βa = (1 − a)·β only absorbs [default: 1, pure
    /// scattering, as Foggy Cityscapes].
    #[arg(long, value_name = "A", allow_hyphen_values = true)]
    pub albedo: Option<f64>,

    /// Blur factor λ in px: the farthest point is blurred to σmax = σ0 + λ·√κs (with
    /// --beta: σ0 + λ·√(a·ln 20), reached at the visibility).
    #[arg(long, value_name = "PX", default_value_t = haze::DEFAULT_LAMBDA, allow_hyphen_values = true)]
    pub lambda: f64,

    /// Inner scale σ0 of the input image in px (its own blur).
    #[arg(long, value_name = "PX", default_value_t = DEFAULT_SIGMA0, allow_hyphen_values = true)]
    pub sigma0: f64,

    /// Largest diffusion rate per step, in (0, 0.25]; smaller means more, smaller steps.
    #[arg(long, value_name = "RHO", default_value_t = DEFAULT_RHO_MAX, allow_hyphen_values = true)]
    pub rho_max: f64,

    /// Airlight colour B as linear R,G,B (e.g. 0.8,0.82,0.85). Default: the median sky
    /// colour; with no sky, a neutral grey at the 99th percentile of the luminance.
    #[arg(long, value_name = "R,G,B", allow_hyphen_values = true, value_parser = parse_rgb)]
    pub airlight: Option<[f32; 3]>,

    /// Relative extinction per channel as R,G,B factors (default 1,1,1: grey haze, as
    /// paper 000). E.g. 0.8,1,1.3 makes a bluish veil: blue is attenuated, and replaced by
    /// airlight, most. A tint that is not grey blurs each channel's τ on its own (a second
    /// texture in every pass).
    #[arg(long, value_name = "R,G,B", allow_hyphen_values = true, value_parser = parse_tint)]
    pub tint: Option<[f64; 3]>,

    /// Diffusion scheme: matched (default; variance-matched, most accurate), invariant
    /// (paper eq. 18, literally; under-blurs) or euler (eq. 13; hundreds of passes).
    #[arg(
        long,
        value_name = "SCHEME",
        allow_hyphen_values = true,
        default_value = "matched"
    )]
    pub scheme: Scheme,

    /// Texture precision of the diffusion passes: f32 (RGBA32F) or f16 (RGBA16F).
    #[arg(
        long,
        value_name = "P",
        allow_hyphen_values = true,
        default_value = "f32"
    )]
    pub precision: Precision,

    /// Blur the whole image to scale S px, with no attenuation and no airlight (an
    /// accuracy check against a Gaussian of std sqrt(S² − σ0²)).
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub uniform_sigma: Option<f64>,

    /// The medium: haze (paper 000, normalised range) or aerial (paper 002: aerial
    /// perspective from the turbidity, range in metres, see --turbidity).
    #[arg(long, value_enum, default_value = "haze", allow_hyphen_values = true)]
    pub medium: MediumKind,

    /// Aerial: the atmosphere's turbidity T in [1, 20] (2 very clear, 3 clear, 6 hazy).
    /// The options marked "Aerial" are refused with --medium haze, which does not read
    /// them.
    #[arg(long, value_name = "T", allow_hyphen_values = true)]
    pub turbidity: Option<f64>,

    /// Aerial: estimate the turbidity from this fisheye sky photo instead (see `brume
    /// turbidity`; the sun is found from its saturated disc).
    #[arg(long, value_name = "PATH")]
    pub sky: Option<PathBuf>,

    /// Aerial: re-render a photo taken at this turbidity at --turbidity (retargeting):
    /// the haze-free radiance is recovered with this turbidity's attenuation first.
    #[arg(long, value_name = "T", allow_hyphen_values = true)]
    pub from_turbidity: Option<f64>,

    /// Aerial: the observer's altitude above sea level, metres, in [-500, 20000]
    /// [default: 0].
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    pub altitude: Option<f64>,

    /// Aerial: metres per unit of the range map: needed for a range that is not in
    /// metres (float maps, z-buffers, disparities without a calibration) [default: 1 for
    /// metric depth formats].
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    pub metres_per_unit: Option<f64>,

    /// Aerial: the camera's pitch in degrees, in (-90, 90) (with the field of view, each
    /// pixel's zenith angle) [default: 0].
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub pitch: Option<f64>,

    /// Aerial: the image row (0 at the top) where the horizon is, instead of --pitch: the
    /// pitch that puts the horizon there with --fov.
    #[arg(
        long,
        value_name = "ROW",
        allow_hyphen_values = true,
        conflicts_with = "pitch"
    )]
    pub horizon_row: Option<f64>,

    /// Aerial: zenith angle (degrees, in [0, 90]) where --airlight (or, with no sky
    /// found, the estimated airlight) is taken to be measured; with a sky, I∞ and its
    /// zenith angle come from the brightest sky of the horizon region [default: 85].
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub horizon_zenith: Option<f64>,

    /// Aerial: the camera's spectral sensitivity, CSV `lambda_nm,r,g,b` [default: CIE 1931
    /// observer to linear sRGB].
    #[arg(long, value_name = "PATH")]
    pub sensitivity: Option<PathBuf>,

    /// Aerial: blur by diffusion from the scattering optical depth (λ = --lambda) or none
    /// [default: diffusion].
    #[arg(long, value_enum, allow_hyphen_values = true)]
    pub blur: Option<AerialBlur>,

    /// Skip pre-processing: unknown range values are taken as the farthest range.
    #[arg(long)]
    pub no_prep: bool,

    /// Image-guided refinement of the range, on the GPU: guided (He et al.'s guided
    /// filter of log range, the image's luminance as guide: the range's edges follow the
    /// image's, its noise is smoothed where the image is flat) or none [default: none;
    /// measured on stereo-matched disparity it repairs the sky and the matcher's blunders
    /// but blurs correct depth: see the README]. A depth map smaller than the image (same
    /// aspect ratio, 1-16x smaller) is always upsampled, by joint bilateral upsampling
    /// guided by the image.
    #[arg(long, value_enum, allow_hyphen_values = true)]
    pub refine: Option<RefineMode>,

    /// The right image of a stereo pair whose left disparity is --depth (Cityscapes
    /// format): pixels whose colour differs from their match in it by more than 12/255
    /// (Foggy Cityscapes' left-right photoconsistency) are unreliable, taken as unknown
    /// and filled from their reliable neighbours (not found automatically: measured on
    /// rendered stereo it also flags correct pixels, see the README).
    #[arg(long, value_name = "PATH")]
    pub right: Option<PathBuf>,

    /// Window radius r of the guided refinement, px at the image's size [default: 20, as
    /// Foggy Cityscapes at 2048 x 1024].
    #[arg(long, value_name = "PX", allow_hyphen_values = true)]
    pub refine_radius: Option<f64>,

    /// Regularisation ε of the guided refinement, a variance of the sRGB-encoded
    /// luminance in (0, 1]: edges of less contrast than about √ε are smoothed across
    /// [default: 0.001].
    #[arg(long, value_name = "EPS", allow_hyphen_values = true)]
    pub refine_eps: Option<f64>,

    #[command(flatten)]
    pub prep: PrepOptionArgs,

    /// Print the time of every pass.
    #[arg(long)]
    pub timings: bool,

    /// Print one JSON object on stdout (width, height, scheme, precision,
    /// diffusion_passes, renderer, clock, total_ms, pass_ms, out, ...).
    #[arg(long)]
    pub json: bool,
}

/// `brume prep`.
#[derive(Args, Clone, Debug)]
pub struct PrepArgs {
    #[command(flatten)]
    pub depth: DepthArgs,

    /// Colour image (optional): the sky is then found from the image and the range
    /// together, and the airlight estimated from it.
    #[arg(long, value_name = "PATH")]
    pub image: Option<PathBuf>,

    /// Output range map: .pfm (float, rows bottom to top) or .exr (float).
    #[arg(long, short, value_name = "PATH")]
    pub out: PathBuf,

    /// Also write a picture of the range before and after (near dark, far light, holes
    /// red), like paper 000's fig. 3.
    #[arg(long, value_name = "PATH.png")]
    pub vis: Option<PathBuf>,

    #[command(flatten)]
    pub prep: PrepOptionArgs,

    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Parses `R,G,B` into three floats.
fn parse_rgb(s: &str) -> Result<[f32; 3], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let values: Result<Vec<f32>, _> = parts.iter().map(|p| p.parse::<f32>()).collect();
    match values {
        Ok(v) if v.len() == 3 && v.iter().all(|c| c.is_finite() && *c >= 0.0) => {
            Ok([v[0], v[1], v[2]])
        }
        _ => Err(format!(
            "'{s}' is not three finite linear values ≥ 0 separated by commas, e.g. 0.8,0.8,0.8"
        )),
    }
}

/// Parses `R,G,B` into three factors > 0.
fn parse_tint(s: &str) -> Result<[f64; 3], String> {
    let values: Result<Vec<f64>, _> = s.split(',').map(|p| p.trim().parse::<f64>()).collect();
    match values {
        Ok(v) if v.len() == 3 && v.iter().all(|c| c.is_finite() && *c > 0.0) => {
            Ok([v[0], v[1], v[2]])
        }
        _ => Err(format!(
            "'{s}' is not three finite factors > 0 separated by commas, e.g. 0.8,1,1.3"
        )),
    }
}

/// Parses `X,Y,Z` into three finite numbers (a position or a direction).
fn parse_vec3(s: &str) -> Result<[f64; 3], String> {
    let values: Result<Vec<f64>, _> = s.split(',').map(|p| p.trim().parse::<f64>()).collect();
    match values {
        Ok(v) if v.len() == 3 && v.iter().all(|c| c.is_finite()) => Ok([v[0], v[1], v[2]]),
        _ => Err(format!(
            "'{s}' is not three finite numbers separated by commas, e.g. 0,1.7,0"
        )),
    }
}

/// Which engine fog `brume scene` adds.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum FogKind {
    /// Paper 001: distance fog with scattering toward the sun and drifting noise.
    Distance,
    /// Paper 003: height fog integrated along each view ray.
    Layered,
    /// No fog: the scene as rendered.
    None,
}

/// How `brume scene` blurs the fog.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlurKind {
    /// No blur.
    None,
    /// Paper 001: the fog-free image blurred by a 5x5 Gaussian in the fog's pass.
    GaussSingle,
    /// Paper 001: the fogged image blurred by the same Gaussian in a second pass.
    GaussSeparate,
    /// brume: diffusion to the scale the fog's scattering optical depth gives.
    Diffusion,
}

/// The height profile of the layered fog.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProfileKind {
    /// δ = density·e^(−(y − base)/scale-height): city haze thinning with height.
    Exponential,
    /// δ = density·sin(π(y − base)/thickness) between base and base + thickness: sea mist.
    Band,
    /// δ = density below base, falling linearly to 0 at top: dry-ice fog on a floor.
    Ramp,
}

/// `brume scene`.
#[derive(Args, Clone, Debug)]
pub struct SceneArgs {
    /// Output: the fogged frame, .png (8-bit sRGB), .pfm or .exr (linear). With --frames
    /// N > 1, numbered files NAME_0001.png … are written instead.
    #[arg(long, short, value_name = "PATH", default_value = "brume-scene.png")]
    pub out: PathBuf,

    /// Also write the raw depth buffer (OpenGL window depth in [0, 1], 1 = sky), .pfm or
    /// .exr: `brume render --depth-kind zbuffer --near --far --fov` reads it back.
    #[arg(long, value_name = "PATH")]
    pub depth_out: Option<PathBuf>,

    /// Also write the fog-free frame (.png, .pfm or .exr).
    #[arg(long, value_name = "PATH")]
    pub clear_out: Option<PathBuf>,

    /// Frame size in pixels.
    #[arg(
        long,
        value_name = "WxH",
        default_value = "960x540",
        allow_hyphen_values = true
    )]
    pub size: String,

    /// Eye position X,Y,Z in metres (y up).
    #[arg(long, value_name = "X,Y,Z", default_value = "0,1.7,0", allow_hyphen_values = true, value_parser = parse_vec3)]
    pub position: [f64; 3],

    /// Heading in degrees: 0 looks along −z, 90 along +x (the sun is at 120).
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub yaw: f64,

    /// Elevation of the view in degrees, −89..89 (positive looks up).
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub pitch: f64,

    /// Vertical field of view in degrees.
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 60.0,
        allow_hyphen_values = true
    )]
    pub fov: f64,

    /// Near clipping plane in metres.
    #[arg(
        long,
        value_name = "M",
        default_value_t = 0.1,
        allow_hyphen_values = true
    )]
    pub near: f64,

    /// Far clipping plane in metres.
    #[arg(
        long,
        value_name = "M",
        default_value_t = 1000.0,
        allow_hyphen_values = true
    )]
    pub far: f64,

    /// The fog model.
    #[arg(
        long,
        value_enum,
        default_value = "distance",
        allow_hyphen_values = true
    )]
    pub fog: FogKind,

    /// How the fog blurs the scene [default: diffusion; none with --fog none].
    #[arg(
        long,
        value_enum,
        default_value = "diffusion",
        default_value_if("fog", "none", "none"),
        hide_default_value = true,
        allow_hyphen_values = true
    )]
    pub blur: BlurKind,

    /// Time in seconds: moves the distance fog's noise and the water's waves.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub time: f64,

    /// Number of frames of an animated sequence (numbered outputs), from --time on.
    #[arg(
        long,
        value_name = "N",
        default_value_t = 1,
        allow_hyphen_values = true
    )]
    pub frames: u32,

    /// Frames per second of the sequence.
    #[arg(
        long,
        value_name = "F",
        default_value_t = 24.0,
        allow_hyphen_values = true
    )]
    pub fps: f64,

    /// Fog colour as linear R,G,B [default: the model's].
    #[arg(long, value_name = "R,G,B", allow_hyphen_values = true, value_parser = parse_rgb)]
    pub fog_colour: Option<[f32; 3]>,

    #[command(flatten)]
    pub layered: LayeredArgs,

    #[command(flatten)]
    pub distance: DistanceArgs,

    #[command(flatten)]
    pub blur_options: SceneBlurArgs,

    /// Print one JSON object on stdout (sizes, camera, per-pass GPU times, outputs).
    #[arg(long)]
    pub json: bool,
}

/// Options of the layered fog (paper 003); defaults from the chosen profile.
#[derive(Args, Clone, Debug)]
pub struct LayeredArgs {
    /// Height profile of the density.
    #[arg(
        long,
        value_enum,
        default_value = "exponential",
        allow_hyphen_values = true
    )]
    pub profile: ProfileKind,

    /// Extinction at the base of the layer, per metre [exponential 0.01, band 0.01, ramp 1].
    #[arg(long, value_name = "PER_M", allow_hyphen_values = true)]
    pub density: Option<f64>,

    /// Height of the layer's base (exponential, band) or floor (ramp), metres [0].
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    pub base: Option<f64>,

    /// Scale height H of the exponential profile, metres [20].
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    pub scale_height: Option<f64>,

    /// Thickness of the band, metres [5].
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    pub thickness: Option<f64>,

    /// Height where the ramp reaches 0, metres [1].
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    pub top: Option<f64>,

    /// Fraction of the extinction that scatters (drives the blur), in [0, 1] [1].
    #[arg(long, value_name = "A", allow_hyphen_values = true)]
    pub albedo: Option<f64>,
}

/// Options of the distance fog (paper 001); defaults are its Listing 1 in metres.
#[derive(Args, Clone, Debug)]
pub struct DistanceArgs {
    /// Distance where the fog starts, metres (eq. 2's StartDistance) [0].
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    pub fog_start: Option<f64>,

    /// Blend distance, metres (eq. 2's Distance) [100].
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    pub fog_distance: Option<f64>,

    /// Falloff exponent of the distance (eq. 2's Exponent) [0.55].
    #[arg(long, value_name = "E", allow_hyphen_values = true)]
    pub fog_exponent: Option<f64>,

    /// Largest fog density, in [0, 1) (eq. 3's FogDensity) [0.5].
    #[arg(long, value_name = "F", allow_hyphen_values = true)]
    pub max_density: Option<f64>,

    /// Direction toward the light X,Y,Z [default: the scene's sun].
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true, value_parser = parse_vec3)]
    pub light_dir: Option<[f64; 3]>,

    /// Distance beyond which the fog scatters the light's colour, metres [10].
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    pub scatter_start: Option<f64>,

    /// Falloff exponent of the scattering lobe (eq. 7) [4].
    #[arg(long, value_name = "E", allow_hyphen_values = true)]
    pub scatter_exponent: Option<f64>,

    /// Scattering colour as linear R,G,B [1,0.65,0.28].
    #[arg(long, value_name = "R,G,B", allow_hyphen_values = true, value_parser = parse_rgb)]
    pub scatter_colour: Option<[f32; 3]>,

    /// Density noise: `generated` (periodic Perlin noise from --noise-seed), `none`, or a
    /// greyscale PNG that tiles.
    #[arg(
        long,
        value_name = "generated|none|PATH.png",
        default_value = "generated"
    )]
    pub noise: String,

    /// Seed of the generated noise.
    #[arg(
        long,
        value_name = "N",
        default_value_t = 0,
        allow_hyphen_values = true
    )]
    pub noise_seed: u64,

    /// Metres per noise tile [100].
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    pub noise_size: Option<f64>,

    /// Drift of the noise, metres per second X,Y,Z (x and z count) [2,0,0.25].
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true, value_parser = parse_vec3)]
    pub noise_speed: Option<[f64; 3]>,

    /// Density factor where the noise is 0 [0.12].
    #[arg(long, value_name = "K", allow_hyphen_values = true)]
    pub noise_low: Option<f64>,

    /// Density factor where the noise is 1 [0.18].
    #[arg(long, value_name = "K", allow_hyphen_values = true)]
    pub noise_high: Option<f64>,
}

/// Options of the blur of `brume scene`.
#[derive(Args, Clone, Debug)]
pub struct SceneBlurArgs {
    /// Diffusion: blur factor λ in px, σ = σ0 + λ·r·√(scattering optical depth) [8].
    #[arg(long, value_name = "PX", allow_hyphen_values = true)]
    pub lambda: Option<f64>,

    /// Diffusion scheme: matched, invariant or euler.
    #[arg(
        long,
        value_name = "SCHEME",
        allow_hyphen_values = true,
        default_value = "matched"
    )]
    pub scheme: Scheme,

    /// Texture precision: f32 or f16 (diffusion, and the Gaussian's intermediate target).
    #[arg(
        long,
        value_name = "P",
        allow_hyphen_values = true,
        default_value = "f32"
    )]
    pub precision: Precision,

    /// Inner scale σ0 of the rendered frame in px.
    #[arg(long, value_name = "PX", default_value_t = DEFAULT_SIGMA0, allow_hyphen_values = true)]
    pub sigma0: f64,

    /// Largest diffusion rate per step, in (0, 0.25].
    #[arg(long, value_name = "RHO", default_value_t = DEFAULT_RHO_MAX, allow_hyphen_values = true)]
    pub rho_max: f64,

    /// Gaussian modes: distance (metres) at which the blur weight equals the fog density.
    #[arg(
        long,
        value_name = "M",
        default_value_t = 100.0,
        allow_hyphen_values = true
    )]
    pub blur_distance: f64,

    /// Gaussian modes: exponent of the distance in the blur weight.
    #[arg(
        long,
        value_name = "E",
        default_value_t = 1.0,
        allow_hyphen_values = true
    )]
    pub blur_falloff: f64,

    /// Gaussian modes: largest blur weight, in [0, 1].
    #[arg(
        long,
        value_name = "W",
        default_value_t = 1.0,
        allow_hyphen_values = true
    )]
    pub blur_max: f64,
}

/// `brume compare`.
#[derive(Args, Clone, Debug)]
pub struct CompareArgs {
    /// One image (PNG/JPEG sRGB, or EXR/PFM linear).
    #[arg(value_name = "A")]
    pub a: PathBuf,

    /// The other, of the same size.
    #[arg(value_name = "B")]
    pub b: PathBuf,

    /// Print one JSON object on stdout (ssim, ssim_rgb, hsv_correlation,
    /// hsv_correlation_hsv).
    #[arg(long)]
    pub json: bool,
}

/// The medium of `brume render`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum MediumKind {
    /// Paper 000's haze.
    Haze,
    /// Paper 002's aerial perspective from turbidity.
    Aerial,
}

/// `--compat`: whose conventions a render follows.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compat {
    /// brume's: the blend in linear light, the diffusion blur, the sky's airlight.
    Brume,
    /// Foggy Cityscapes': the blend in sRGB code values, no blur, the dark-channel
    /// airlight.
    FoggyCityscapes,
}

/// `--refine`: whether the range is refined with the image as guide.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum RefineMode {
    /// No refinement (a smaller depth map is still upsampled, guided).
    None,
    /// The guided filter, everywhere.
    Guided,
    /// The guided filter where the range is unreliable only: where pre-processing filled
    /// it (holes, outliers, left-right mismatches with --right, border bands); elsewhere
    /// the range is kept as measured.
    Unreliable,
}

/// The blur of the aerial medium.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum AerialBlur {
    /// Diffusion to the scale the scattering optical depth gives.
    Diffusion,
    /// No blur.
    None,
}

/// `brume view`.
#[derive(Args, Clone, Debug)]
#[command(
    after_help = "Keys: S saves the frame as PNG, E as EXR (next to --save, numbered, \
never overwriting), R resets the parameters, Q or Escape quits.\n\n\
Examples:\n  brume view\n  brume view render --image photo.png --depth depth.png --ka 0.5\n  \
brume view scene --fog layered\n  brume view --frames 10 --screenshot shot.png --stats stats.json"
)]
pub struct ViewArgs {
    /// Render N frames, save --screenshot and --stats, and exit (N >= 1). Without it the
    /// window stays until closed.
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = clap::value_parser!(u32).range(1..))]
    pub frames: Option<u32>,

    /// With --frames: the window's contents after the last frame, as PNG.
    #[arg(long, value_name = "PATH", requires = "frames")]
    pub screenshot: Option<PathBuf>,

    /// With --frames: per-frame GPU and wall-clock times, the image's place in the
    /// screenshot and the GL objects created after the first frame, as JSON.
    #[arg(long, value_name = "PATH", requires = "frames")]
    pub stats: Option<PathBuf>,

    /// Image scale: fit (to the window) or a factor of physical pixels per image pixel.
    #[arg(long, value_name = "fit|F", default_value = "fit", allow_hyphen_values = true, value_parser = parse_zoom)]
    pub zoom: Zoom,

    /// First window size in logical pixels [default: the panel and the image].
    #[arg(long, value_name = "WxH", allow_hyphen_values = true)]
    pub window: Option<String>,

    /// Where S and E save the frame (the extension is theirs).
    #[arg(long, value_name = "PATH", default_value = "brume-view.png")]
    pub save: PathBuf,

    /// What to show [default: the demo, as `brume render` renders it].
    #[command(subcommand)]
    pub source: Option<ViewSource>,
}

/// What `brume view` shows.
#[derive(clap::Subcommand, Clone, Debug)]
pub enum ViewSource {
    /// A photo with depth, or the demo, with `brume render`'s options (--out is ignored).
    Render(Box<RenderArgs>),
    /// brume's 3D scene, with `brume scene`'s options (--out, --frames are ignored).
    Scene(Box<SceneArgs>),
}

/// How big the viewer shows the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Zoom {
    /// As large as the window allows.
    Fit,
    /// Physical pixels per image pixel.
    Factor(f32),
}

fn parse_zoom(s: &str) -> Result<Zoom, String> {
    if s == "fit" {
        return Ok(Zoom::Fit);
    }
    match s.parse::<f32>() {
        Ok(f) if f.is_finite() && (0.05..=16.0).contains(&f) => Ok(Zoom::Factor(f)),
        _ => Err(format!(
            "expected `fit` or a factor in [0.05, 16], got `{s}`"
        )),
    }
}

/// `brume batch`.
#[derive(Args, Clone, Debug)]
#[command(
    after_help = "Outputs: {out}/{image folder relative to its input folder}/\
{name}_leftImg8bit_foggy_beta_{β}.png, and a log of every output (JSON lines) \
{out}/brume-batch-{K}-of-{N}.jsonl.\n\n\
Examples:\n  brume batch cityscapes/leftImg8bit/val --out foggy --beta 0.005,0.01,0.02\n  \
brume batch --manifest frames.csv --out foggy --shard 3/8\n  \
brume batch cityscapes --out foggy --shard $((SLURM_ARRAY_TASK_ID+1))/$SLURM_ARRAY_TASK_COUNT"
)]
pub struct BatchArgs {
    /// Folders searched recursively for Cityscapes frames: {name}_leftImg8bit.png with
    /// {name}_disparity.png and {name}_camera.json beside it or in Cityscapes' layout
    /// (disparity/ and camera/ beside leftImg8bit/); gtFine labelIds give the sky.
    #[arg(value_name = "FOLDER")]
    pub inputs: Vec<PathBuf>,

    /// A CSV manifest: header image,depth[,camera][,calib][,sky_mask], one frame per row,
    /// paths relative to the manifest.
    #[arg(long, value_name = "CSV", allow_hyphen_values = true)]
    pub manifest: Option<PathBuf>,

    /// Output folder (created); the input tree is mirrored under it.
    #[arg(long, short, value_name = "DIR", allow_hyphen_values = true)]
    pub out: PathBuf,

    /// Extinction coefficients β in 1/m, comma-separated: one output per frame and β
    /// (Foggy Cityscapes: 0.005, 0.01, 0.02, visibility 600, 300, 150 m).
    #[arg(
        long,
        value_name = "B,B,…",
        default_value = "0.005,0.01,0.02",
        allow_hyphen_values = true
    )]
    pub beta: String,

    /// Take shard K of N (1 ≤ K ≤ N): a deterministic share of the frames, by a hash of
    /// their names, so that N jobs split a dataset with no coordination.
    #[arg(long, value_name = "K/N", allow_hyphen_values = true)]
    pub shard: Option<String>,

    /// Also write each output's transmittance τ as an 8-bit grey PNG
    /// ({name}_transmittance_beta_{β}.png).
    #[arg(long)]
    pub transmittance: bool,

    /// Single-scattering albedo a: scattering a·β, absorption (1 − a)·β [default: 1].
    #[arg(long, value_name = "A", allow_hyphen_values = true)]
    pub albedo: Option<f64>,

    /// Blur factor λ in px (as `brume render --lambda`).
    #[arg(long, value_name = "PX", allow_hyphen_values = true)]
    pub lambda: Option<f64>,

    /// Diffusion scheme: matched, invariant or euler.
    #[arg(long, value_name = "SCHEME", allow_hyphen_values = true)]
    pub scheme: Option<Scheme>,

    /// Texture precision: f32 or f16.
    #[arg(long, value_name = "P", allow_hyphen_values = true)]
    pub precision: Option<Precision>,

    /// Airlight as linear R,G,B [default: from the sky found, per frame].
    #[arg(long, value_name = "R,G,B", allow_hyphen_values = true, value_parser = parse_rgb)]
    pub airlight: Option<[f32; 3]>,

    /// Whose conventions, as `brume render --compat`: brume or foggy-cityscapes (the
    /// blend in sRGB code values, no blur, the dark-channel airlight) [default: brume].
    #[arg(long, value_enum, allow_hyphen_values = true)]
    pub compat: Option<Compat>,

    /// Image-guided refinement of the range, as `brume render --refine` [default: none].
    #[arg(long, value_enum, allow_hyphen_values = true)]
    pub refine: Option<RefineMode>,

    /// Window radius of the guided refinement, px [default: 20].
    #[arg(long, value_name = "PX", allow_hyphen_values = true)]
    pub refine_radius: Option<f64>,

    /// Regularisation ε of the guided refinement [default: 0.001].
    #[arg(long, value_name = "EPS", allow_hyphen_values = true)]
    pub refine_eps: Option<f64>,

    /// Skip hole filling and sky detection.
    #[arg(long)]
    pub no_prep: bool,

    #[command(flatten)]
    pub prep: PrepOptionArgs,
}
