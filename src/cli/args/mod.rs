//! Argument definitions (clap derive). Help texts are the user manual: say units, defaults
//! and what each value does.
//!
//! Every option whose value is not a path takes `allow_hyphen_values`, so that `--seed -1`
//! or `--airlight -1,0,0` reaches the check that names the option instead of clap's
//! "unexpected argument '-1'" (a test in `cli` walks every option).

use super::bench::BenchCommand;
use brume::blur::{DEFAULT_RHO_MAX, DEFAULT_SIGMA0};
use brume::egl::Platform;
use brume::io::camera::Mount;
use brume::io::depth::{DepthFormat, DepthKind, DepthLayout, StereoView};
use brume::io::mask::SkyMaskFormat;
use brume::medium::haze;
use brume::refine::RefineMode;
use brume::{Precision, Scheme};
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

mod batch;
mod render;
mod scene;
#[cfg(all(feature = "viewer", not(target_os = "android")))]
mod view;

pub use batch::BatchArgs;
pub use render::{
    parse_coarse_from, AerialBlur, CaptureArgs, CoarseFrom, Compat, MediumKind, RenderArgs,
    RetargetKind,
};
pub use scene::{BlurKind, DistanceArgs, FogKind, LayeredArgs, ProfileKind, SceneArgs};
#[cfg(all(feature = "viewer", not(target_os = "android")))]
pub use view::{ViewArgs, ViewSource, Zoom};

/// Add physically based haze and fog to RGBD images, on OpenGL ES 3.2 through EGL
/// (headless: no display needed).
///
/// Quick start: `brume render` renders the built-in demo scene to brume-demo.png.
#[derive(Parser, Debug)]
#[command(
    name = "brume",
    version = concat!(env!("CARGO_PKG_VERSION"), " (sources ", env!("BRUME_SOURCES"), ")"),
    propagate_version = true
)]
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
    /// The sun's zenith and azimuth from place and time (NREL's SPA, paper 002 sec. 3.4).
    Sun(super::sun::SunArgs),
    /// Print the shell's completion script for brume's commands and flags on stdout, e.g.
    /// `brume completions bash > ~/.local/share/bash-completion/completions/brume`.
    Completions(CompletionsArgs),
}

/// `brume completions`.
#[derive(Args, Clone, Debug)]
pub struct CompletionsArgs {
    /// The shell the script is for.
    #[arg(value_enum)]
    pub shell: clap_complete::Shell,
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
    /// Depth, range or disparity map: Middlebury 2014 disp0.pfm (or the right view's disp1.pfm,
    /// with cam1's intrinsics; --calib), 8-bit disparity PNG (Middlebury 2006), 16-bit PNG (KITTI,
    /// NYU, TUM, Android DEPTH16, ARCore, Cityscapes disparity with --camera, or --depth-scale),
    /// float EXR/TIFF/PFM, or NumPy .npy/.npz (float16/32/64; uint16 as a 16-bit PNG; an .npz's
    /// only array or the one named `depth`, as Depth Pro writes); a phone's portrait photo, whose
    /// JPEG carries its depth map (GDepth, Dynamic Depth, an iPhone's depth image: `render` and
    /// `view` read it from --image when --depth is not given). A photo without a depth sensor: a
    /// monocular model's relative inverse depth (MiDaS, DPT, Depth Anything) with --depth-kind
    /// inverse, or its affine-invariant depth (Marigold) with --depth-kind affine.
    #[arg(long, value_name = "PATH")]
    pub depth: Option<PathBuf>,

    /// Middlebury calib.txt with the intrinsics, baseline and doffs of the depth map.
    #[arg(long, value_name = "PATH")]
    pub calib: Option<PathBuf>,

    /// Cityscapes NAME_camera.json (baseline in metres, intrinsics fx, fy, u0, v0) of a
    /// NAME_disparity.png; its camera height and pitch (z, pitch, roll), when given, bound
    /// the range below the horizon by the level road's (false matches beyond are
    /// dropped). Default: NAME_camera.json beside the disparity, or in the dataset's
    /// layout (camera/SPLIT/CITY/ for disparity/SPLIT/CITY/).
    #[arg(long, value_name = "PATH")]
    pub camera: Option<PathBuf>,

    /// How the depth's values are read.
    #[command(flatten)]
    pub reading: DepthReadingArgs,
}

/// How a depth file's values are read: its format, what they measure, their scale and the
/// geometry that turns them into range (shared by `render`'s one depth and `batch`'s
/// every frame).
#[derive(Args, Debug, Clone)]
pub struct DepthReadingArgs {
    /// What the depth values are: depth (along the optical axis), range (distance to the
    /// camera centre), disparity (px), zbuffer (a rendered frame's OpenGL window depth in
    /// [0, 1], with --near, --far and --fov), inverse (a monocular estimator's relative
    /// inverse depth, MiDaS or Depth Anything: depth ∝ 1/(d + --disparity-offset), 0 the
    /// sky; metres with --depth-scale), or affine (a monocular estimator's affine-invariant
    /// depth, Marigold: 0 the scene's nearest depth, --near, and 1 its farthest, --far;
    /// a 16-bit PNG holds d·65535). Default: what the format implies.
    #[arg(long, value_name = "KIND", allow_hyphen_values = true)]
    pub depth_kind: Option<DepthKind>,

    /// Depth file format: auto, middlebury2014, middlebury2006, kitti, nyu, tum, png16,
    /// float, android-depth16 (Camera2 DEPTH16 as a 16-bit PNG: low 13 bits range in mm,
    /// high 3 bits confidence, read as range), arcore (ARCore 16-bit depth PNG: mm along
    /// the optical axis, becomes range with --fov or --focal), cityscapes (16-bit
    /// disparity PNG, p > 0 is (p − 1)/256 px, with its camera file: see --camera; auto
    /// picks it for a 16-bit PNG whose camera file is given or found), gdepth or
    /// dynamic-depth (a portrait photo's JPEG with its depth map in GDepth XMP or in a
    /// Dynamic Depth container: scaled by its own Near, Far and Units, depth or range as
    /// its MeasureType says), apple-depth (an iPhone's portrait JPEG: its disparity image
    /// after the photo, in 1/m; auto picks any of the three for a .jpg).
    #[arg(
        long,
        value_name = "FORMAT",
        allow_hyphen_values = true,
        default_value = "auto"
    )]
    pub depth_format: DepthFormat,

    /// Metres per stored value of a 16-bit PNG (e.g. 0.001 for millimetres), of a float
    /// map (1 for a map already in metres), per unit of a z-buffer's --near and --far (1
    /// when they are in metres; also affine depth's), the metres of 1/(d + offset) of
    /// inverse depth, or a factor on a portrait JPEG's metres (an iPhone's relative map
    /// rescaled to a distance known in the scene); a float map, a z-buffer, inverse or
    /// affine depth or a portrait JPEG then counts as metric, for --beta.
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
    /// default: 270); with --depth-kind inverse, the shift added to the inverse depth
    /// [default: 0].
    #[arg(long, value_name = "PX", allow_hyphen_values = true)]
    pub disparity_offset: Option<f64>,

    /// Near clipping plane of the projection that wrote a z-buffer (--depth-kind zbuffer),
    /// or the nearest depth in the scene, affine depth's 0 (--depth-kind affine), in the
    /// scene's units: the range comes out in them (metres, for --beta, with --depth-scale
    /// 1).
    #[arg(long, value_name = "D", allow_hyphen_values = true)]
    pub near: Option<f64>,

    /// Far clipping plane of the projection that wrote a z-buffer, inf for an infinite far
    /// plane; or the farthest depth in the scene, affine depth's 1.
    #[arg(long, value_name = "D", allow_hyphen_values = true)]
    pub far: Option<f64>,

    /// The z-buffer is reversed-Z: window depth 1 at --near and 0 at --far (Unreal, Bevy,
    /// Godot 4; usually with --far inf), nothing drawn at 0.
    #[arg(long)]
    pub reversed_z: bool,

    /// Vertical field of view in degrees: of a z-buffer's projection, or of a depth map
    /// (instead of --focal) to turn depth into range; of the photo as shown upright (see
    /// --depth-layout).
    #[arg(
        long,
        value_name = "DEG",
        allow_hyphen_values = true,
        conflicts_with = "focal"
    )]
    pub fov: Option<f64>,

    /// --depth-format android-depth16: samples whose DEPTH16 confidence is below this
    /// are unknown, from 0 (keep every measured sample) to 1 (only code 0, 100 %); code
    /// c ≥ 1 means (c − 1)/7 [default: 0.5]. A portrait photo's depth (gdepth,
    /// dynamic-depth) with a confidence map: samples below this in it are unknown
    /// [default: none dropped].
    #[arg(long, value_name = "C", allow_hyphen_values = true)]
    pub min_confidence: Option<f64>,

    /// Range at or beyond D is unknown, the sky (pre-processing then finds it with the
    /// image and takes the airlight from it), in the range's units (metres with
    /// --depth-scale): for a model that gives the sky a depth of its own, near its largest
    /// (Depth Anything's metric models saturate toward 20 or 80 m). Default: a float map's
    /// largest value is unknown when at least 1 % of its samples hold it exactly, 10 times
    /// beyond the mean of the others or more (Depth Pro's sky, clamped at 10 km; Blender's
    /// background, 1e10); inf keeps every value. Inverse and affine depth's far tail is
    /// looked at for sky without it.
    #[arg(long, value_name = "D", allow_hyphen_values = true)]
    pub sky_beyond: Option<f64>,

    /// How the depth map lies against an --image with an EXIF orientation (a phone photo
    /// stored sideways with a tag; brume turns the image upright, as viewers show it):
    /// stored (laid out as the image's stored pixels, as phones write depth: turned with
    /// it), upright (made from the image as viewers show it, e.g. read by OpenCV: not
    /// turned), or auto (stored, unless the map's shape fits only the upright image). --fov
    /// is the upright image's vertical field of view.
    #[arg(
        long,
        value_name = "LAYOUT",
        allow_hyphen_values = true,
        default_value = "auto"
    )]
    pub depth_layout: DepthLayout,

    /// The camera's height over a level road in metres and its pitch (down) and roll (left
    /// side up) in degrees, HEIGHT,PITCH[,ROLL], for depth from a car's camera without a
    /// Cityscapes camera file (or to replace that file's): below the horizon, small
    /// patches of range far beyond the level road's are dropped as false matches (the
    /// README's "The level road"). Needs the map's intrinsics (--focal, --fov or its
    /// calibration) and metres.
    #[arg(
        long,
        value_name = "HEIGHT,PITCH[,ROLL]",
        allow_hyphen_values = true,
        value_parser = parse_camera_mount
    )]
    pub camera_mount: Option<Mount>,

    /// Which camera of the stereo pair a disparity is aligned with, left or right: a
    /// matcher leaves unknown the background next to a nearer surface that the other camera
    /// cannot see, left of it in a left view, right of it in a right view, and that band
    /// is filled from its background. Default: right for a Middlebury 2014 disp1.pfm
    /// (read with cam1's intrinsics) or 2006 disp5.png, else left (Cityscapes, Middlebury's
    /// disp0.pfm and 2006 disp1.png, OpenCV's matchers).
    #[arg(long, value_name = "left|right", allow_hyphen_values = true)]
    pub stereo_view: Option<StereoView>,
}

/// `--camera-mount HEIGHT,PITCH[,ROLL]`: metres and degrees, as a [`Mount`] (radians).
pub fn parse_camera_mount(s: &str) -> std::result::Result<Mount, String> {
    Mount::parse_degrees(s).map_err(|e| match e {
        brume::Error::InvalidParameter { expected, .. } => format!("expected {expected}"),
        other => other.to_string(),
    })
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

    /// Seed of the RANSAC hole filling, of the capture's noise (--shot-noise-gain,
    /// --read-noise) and of batch's --beta-dist draws, a whole number ≥ 0; a given seed
    /// always gives the same result [default: 0].
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

/// How the range is refined with the image (`render`, `prep`, `batch`).
#[derive(Args, Clone, Debug, Default)]
pub struct RefineArgs {
    /// Image-guided refinement of the range: repair (the guided range where the measured
    /// range is far nearer than it, as a stereo matcher's false matches in the sky are,
    /// half of each where pre-processing filled the range, the measured range elsewhere),
    /// guided (He et al.'s guided filter of log range everywhere, the image's colour as
    /// guide), unreliable (the guided range only where pre-processing filled the range) or
    /// none [default: repair for Cityscapes disparity, none otherwise: measured on
    /// stereo-matched disparity, see the README]. On the GPU in render and batch, by its
    /// CPU reference in prep. A depth map smaller than the image (same aspect ratio, 1-16x
    /// smaller) is always upsampled, by joint bilateral upsampling guided by the image.
    #[arg(long = "refine", value_enum, allow_hyphen_values = true)]
    pub mode: Option<RefineMode>,

    /// Window radius r of the guided refinement, px at the image's size [default: 20, as
    /// Foggy Cityscapes at 2048 x 1024].
    #[arg(long = "refine-radius", value_name = "PX", allow_hyphen_values = true)]
    pub radius: Option<f64>,

    /// Regularisation ε of the guided refinement, a variance of sRGB-encoded colour values
    /// in (0, 1]: edges of less contrast than about √ε are smoothed across [default:
    /// 0.001].
    #[arg(long = "refine-eps", value_name = "EPS", allow_hyphen_values = true)]
    pub eps: Option<f64>,
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

    #[command(flatten)]
    pub refine: RefineArgs,

    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Parses `R,G,B` into three floats, or one value `V` into the grey `V,V,V`.
fn parse_rgb(s: &str) -> Result<[f32; 3], String> {
    let values: Result<Vec<f32>, _> = s.split(',').map(|p| p.trim().parse::<f32>()).collect();
    match values {
        Ok(v) if v.iter().all(|c| c.is_finite() && *c >= 0.0) => match v[..] {
            [grey] => Ok([grey; 3]),
            [r, g, b] => Ok([r, g, b]),
            _ => Err(format!("'{s}' has {} values", v.len()) + RGB_EXPECTED),
        },
        _ => Err(format!("'{s}' is not finite linear values ≥ 0") + RGB_EXPECTED),
    }
}

const RGB_EXPECTED: &str =
    ": expected three separated by commas (0.8,0.82,0.85) or one for a grey (0.8)";

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
