//! `brume scene`'s arguments: the camera, the fog media and the blur.

use super::*;

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
    /// Any profile, from --density-csv (height_m,extinction_per_m; linear between rows).
    Table,
}

/// `brume scene`.
#[derive(Args, Clone, Debug)]
pub struct SceneArgs {
    /// Output: the fogged frame, .png or .jpg (8-bit sRGB), .pfm or .exr (linear). With
    /// --frames N > 1, numbered files NAME_0001.png … are written instead.
    #[arg(long, short, value_name = "PATH", default_value = "brume-scene.png")]
    pub out: PathBuf,

    /// Also write the raw depth buffer (OpenGL window depth in [0, 1], 1 = sky), .pfm or
    /// .exr: `brume render --depth-kind zbuffer --near --far --fov` reads it back.
    #[arg(long, value_name = "PATH")]
    pub depth_out: Option<PathBuf>,

    /// Also write the fog-free frame (.png, .jpg, .pfm or .exr).
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

    /// Fog colour as linear R,G,B, or one value for a grey [default: the model's].
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

    /// The table of `--profile table`: a CSV with the header `height_m,extinction_per_m`,
    /// heights increasing, linear between rows and constant beyond the ends.
    #[arg(long, value_name = "PATH.csv")]
    pub density_csv: Option<std::path::PathBuf>,
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

    /// Scattering colour as linear R,G,B, or one value for a grey [1,0.65,0.28].
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

    /// How much the noise varies the fog colour, in [0, 1]: the colour is scaled by
    /// 1 + S·(2·noise − 1) (paper 001 sec. 3.3) [0].
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub noise_colour_strength: Option<f64>,
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
