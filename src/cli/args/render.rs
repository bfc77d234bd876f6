//! `brume render`'s arguments.

use super::*;

/// `brume render`.
#[derive(Args, Clone, Debug)]
pub struct RenderArgs {
    /// Colour image: PNG, JPEG, WebP or TIFF (8- or 16-bit sRGB, or by its ICC profile),
    /// or OpenEXR, PFM or float TIFF (linear float, as renderers and engines write). It
    /// needs --depth or --transmittance-map, but for a
    /// JPEG that carries its own depth map (GDepth, Dynamic Depth or an iPhone's depth
    /// image: a phone's portrait photo). Without --image and --depth the built-in demo scene is rendered.
    #[arg(long, value_name = "PATH")]
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

    /// Output file: .png (8-bit sRGB), .jpg/.jpeg (8-bit sRGB, quality 95), .pfm (float
    /// RGB, linear) or .exr (float RGBA, linear). A PNG or JPEG carries the photo's ICC
    /// colour profile (Display P3 ...) and EXIF (date, camera, place; orientation 1, as
    /// the output is upright). Default for the demo: brume-demo.png. Must not be one of
    /// the inputs.
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
    /// android-depth16, arcore, png16, a float map or a z-buffer with --depth-scale, or a
    /// disparity with --focal and --baseline.
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

    /// Airlight colour B as linear R,G,B (e.g. 0.8,0.82,0.85), or one value for a grey
    /// (0.8). Default: the median sky colour; with no sky, a neutral grey at the 99th
    /// percentile of the luminance.
    #[arg(long, value_name = "R,G,B", allow_hyphen_values = true, value_parser = parse_rgb)]
    pub airlight: Option<[f32; 3]>,

    /// Relative extinction per channel as R,G,B factors (default 1,1,1: grey haze, as
    /// paper 000). E.g. 0.8,1,1.3 makes a bluish veil: blue is attenuated, and replaced by
    /// airlight, most. A tint that is not grey blurs each channel's τ on its own, at the
    /// cost of a grey haze (the airlight is uniform: τ·(E − airlight) diffuses in one
    /// texture).
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

    /// Coarse to fine: once the most blurred pixel has reached PX px, run the remaining
    /// diffusion steps at half resolution, and at a quarter once that scale has doubled
    /// (matched scheme, haze of any tint; from 2 px, the default, about 65 % less GPU time at σmax
    /// 25 px and 35 % at 15 and 8 px on llvmpipe). Its error against the exact Gaussian away from the image's
    /// border stays within full resolution's, but the result is no longer the paper's
    /// pipeline to the bit, and near depth edges it departs from it by a few per cent of
    /// the blur's own effect: `off` runs every step at full resolution (what the f64 reference
    /// computes). PX ≥ 2; smaller is faster and less exact. With --uniform-sigma 10 or more
    /// the stage starts at step 0 whatever PX (a uniform blur keeps no full-resolution
    /// detail).
    #[arg(
        long,
        value_name = "off|PX",
        default_value_t = super::render::CoarseFrom(Some(brume::blur::DEFAULT_COARSE_FROM)),
        allow_hyphen_values = true,
        value_parser = parse_coarse_from
    )]
    pub coarse_from: CoarseFrom,

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

    /// Aerial: the camera's pitch in degrees, up positive, in (-90, 90) (with the field of
    /// view, each pixel's zenith angle) [default: a Cityscapes camera file's pitch, else
    /// 0].
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

    /// Aerial: azimuth sectors across the image for the horizon's light (paper 002 sec.
    /// 4: fog toward the sun is brighter), in [1, 64]; 1 takes one value for the whole
    /// image [default: 8].
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub horizon_sectors: Option<i64>,

    /// Aerial, with --from-turbidity: keep the normalised radiance ρ = I⁰/I∞ (eq. 25-26,
    /// the object's light follows the sky's) or the radiance I⁰ [default: normalised].
    #[arg(long, value_enum, value_name = "KIND", allow_hyphen_values = true)]
    pub retarget: Option<RetargetKind>,

    /// Aerial: the sun from place and time (NREL's SPA), for --sky's turbidity (the
    /// fisheye taken with north at its top) and the horizon's light by azimuth; --heading
    /// is the compass direction of the image centre.
    #[command(flatten)]
    pub place: super::super::sun::PlaceTimeArgs,

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

    #[command(flatten)]
    pub refine: RefineArgs,

    /// The right image of a stereo pair whose left view's disparity is --depth (any
    /// stereo disparity of the image's size: Cityscapes, Middlebury, a 16-bit PNG or float
    /// map read as --depth-kind disparity), or its left image with a right view's
    /// disparity (--stereo-view right): pixels whose colour differs from their match in
    /// it by more than 12/255 (Foggy Cityscapes' left-right photoconsistency) are
    /// unreliable, taken as unknown and filled from their reliable neighbours. Not found
    /// automatically: it also flags correct pixels, and on rendered stereo and on the real
    /// Aloe pair it made τ a little worse (see the README).
    #[arg(long, value_name = "PATH")]
    pub right: Option<PathBuf>,

    #[command(flatten)]
    pub prep: PrepOptionArgs,

    #[command(flatten)]
    pub insert: InsertArgs,

    #[command(flatten)]
    pub capture: CaptureArgs,

    /// Print the time of every pass.
    #[arg(long)]
    pub timings: bool,

    /// Print one JSON object on stdout (width, height, scheme, precision,
    /// diffusion_passes, renderer, clock, total_ms, pass_ms, out, ...).
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

/// `--retarget`: what a photo's retargeting keeps (paper 002, eq. 25-26).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum RetargetKind {
    /// The normalised radiance ρ = I⁰/I∞, as the paper (eq. 26).
    Normalised,
    /// The radiance I⁰.
    Radiance,
}

/// The blur of the aerial medium.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum AerialBlur {
    /// Diffusion to the scale the scattering optical depth gives.
    Diffusion,
    /// No blur.
    None,
}

/// A virtual object composited into the photo before the fog (paper 002, sec. 6-7).
#[derive(Args, Clone, Debug)]
pub struct InsertArgs {
    /// A rendered object to insert before the fog: an OpenEXR of the photo's size, made
    /// with the photo's camera (e.g. Blender with a transparent film), its colour linear
    /// and premultiplied by alpha (R, G, B, A, flat or a layer's such as
    /// ViewLayer.Combined), with a depth channel (Z, ViewLayer.Depth.Z) or --insert-depth.
    /// It is shown where it is nearer than the photo's range and then fogged with the
    /// photo, by the same medium.
    #[arg(long, value_name = "PATH.exr", conflicts_with_all = ["transmittance_map", "compat"])]
    pub insert: Option<PathBuf>,

    /// The object's depth map, if its EXR has no depth channel: a float .exr, .npy or
    /// one-channel .pfm of its size, in the photo's range units (metres for metric depth);
    /// values ≤ 0, infinite or NaN where there is no object.
    #[arg(long, value_name = "PATH", requires = "insert")]
    pub insert_depth: Option<PathBuf>,

    /// What the object's depth measures: depth (along the optical axis, as Blender's Z
    /// pass; turned into range with the photo's intrinsics, --focal or --fov) or range
    /// (distance to the camera centre) [default: depth].
    #[arg(
        long,
        value_name = "KIND",
        requires = "insert",
        allow_hyphen_values = true
    )]
    pub insert_depth_kind: Option<DepthKind>,
}

/// What the camera does after the fog (`brume::photo::capture`): all off by default.
#[derive(Args, Clone, Debug, Default)]
pub struct CaptureArgs {
    /// Capture: exposure change in stops after the fog (the linear image times 2^STOPS),
    /// in [-20, 20]; the result is clipped to full scale.
    #[arg(long, value_name = "STOPS", allow_hyphen_values = true)]
    pub exposure_stops: Option<f64>,

    /// Capture: shot noise, as the linear value K of one photo-electron (1 / full-well
    /// electrons: 0.00025 is a 4000 e⁻ well). A value v collects Poisson(v/K) electrons:
    /// noise variance K·v. Seeded by --seed.
    #[arg(long, value_name = "K", allow_hyphen_values = true)]
    pub shot_noise_gain: Option<f64>,

    /// Capture: Gaussian read noise's standard deviation, in linear value units (e.g.
    /// 0.002), added to the shot noise [default with --shot-noise-gain: 0].
    #[arg(long, value_name = "SIGMA", allow_hyphen_values = true)]
    pub read_noise: Option<f64>,

    /// Capture: JPEG quality 1-100 of an encode-decode round trip after the noise, so that
    /// the block artefacts are in the file written (whatever its format).
    #[arg(long, value_name = "Q", allow_hyphen_values = true)]
    pub jpeg_quality: Option<i64>,
}

impl CaptureArgs {
    /// Whether the capture draws noise, which --seed seeds.
    pub fn reads_seed(&self) -> bool {
        self.shot_noise_gain.is_some() || self.read_noise.is_some()
    }
}

/// `--coarse-from`: the scale (px) from which the diffusion runs coarse to fine, or `None`
/// for `off` ([`brume::Blur::coarse_from`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoarseFrom(pub Option<f64>);

impl std::fmt::Display for CoarseFrom {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.0 {
            Some(px) => write!(f, "{px}"),
            None => f.write_str("off"),
        }
    }
}

impl CoarseFrom {
    /// The value as typed where it is not the default (2 px), for a refusal.
    pub fn changed(self) -> Option<String> {
        (self.0 != Some(brume::blur::DEFAULT_COARSE_FROM)).then(|| self.to_string())
    }
}

/// `off`, or a finite scale ≥ [`brume::blur::MIN_COARSE_FROM`] px.
pub fn parse_coarse_from(s: &str) -> Result<CoarseFrom, String> {
    if s == "off" {
        return Ok(CoarseFrom(None));
    }
    let min = brume::blur::MIN_COARSE_FROM;
    match s.parse::<f64>() {
        Ok(px) if px.is_finite() && px >= min => Ok(CoarseFrom(Some(px))),
        _ => Err(format!(
            "expected `off` or a scale in px ≥ {min} (below it the half resolution aliases \
             detail), got `{s}`"
        )),
    }
}
