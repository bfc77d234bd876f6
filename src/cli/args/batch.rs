//! `brume batch`'s arguments.

use super::*;
use brume::photo::BetaDistribution;

/// `brume batch`.
#[derive(Args, Clone, Debug)]
#[command(
    after_help = "Outputs: {out}/{image folder relative to its input folder}/\
{name}_leftImg8bit_foggy_beta_{β}.png, and a log of every output (JSON lines) \
{out}/brume-batch-{K}-of-{N}.jsonl.\n\n\
Examples:\n  brume batch cityscapes/leftImg8bit/val --out foggy --beta 0.005,0.01,0.02\n  \
brume batch --manifest frames.csv --out foggy --shard 3/8\n  \
brume batch --manifest kitti.csv --depth-format kitti --focal 721 --out foggy\n  \
brume batch cityscapes --out foggy --shard $((SLURM_ARRAY_TASK_ID+1))/$SLURM_ARRAY_TASK_COUNT"
)]
pub struct BatchArgs {
    /// Folders searched recursively for Cityscapes frames: {name}_leftImg8bit.png with
    /// {name}_disparity.png and {name}_camera.json beside it or in Cityscapes' layout
    /// (disparity/ and camera/ beside leftImg8bit/); gtFine labelIds give the sky.
    #[arg(value_name = "FOLDER")]
    pub inputs: Vec<PathBuf>,

    /// A CSV manifest: header image,depth[,camera][,calib][,sky_mask], one frame per row,
    /// paths relative to the manifest. Its depth files are read as --depth-format,
    /// --depth-scale, --depth-kind and the geometry flags say, for every row (KITTI:
    /// --depth-format kitti; a float map in metres: --depth-scale 1). A phone's portrait
    /// JPEG without a depth cell (or column) is its own depth file.
    #[arg(long, value_name = "CSV", allow_hyphen_values = true)]
    pub manifest: Option<PathBuf>,

    /// Output folder (created); the input tree is mirrored under it. It records the
    /// settings its outputs are made with (brume-batch-settings.json): a run with other
    /// settings, which would mix two fogs in one dataset, is refused.
    #[arg(long, short, value_name = "DIR", allow_hyphen_values = true)]
    pub out: PathBuf,

    /// How every frame's depth is read (as `brume render`'s); a frame's own camera or
    /// calibration file comes from its manifest row or its Cityscapes layout.
    #[command(flatten)]
    pub depth: DepthReadingArgs,

    /// Extinction coefficients β in 1/m, comma-separated: one output per frame and β
    /// (Foggy Cityscapes: 0.005, 0.01, 0.02, visibility 600, 300, 150 m).
    #[arg(
        long,
        value_name = "B,B,…",
        default_value = "0.005,0.01,0.02",
        allow_hyphen_values = true
    )]
    pub beta: String,

    /// Draw one β per frame from a distribution instead of --beta: uniform:LOW,HIGH (1/m),
    /// lognormal:MU,SIGMA (ln β normal: median e^MU, e.g. lognormal:-4.6,0.5 around
    /// 0.01), or a fixed β. The draw depends on --seed and the frame's name only (not on
    /// the order, the shard or the other frames); it is rounded to 6 significant digits,
    /// names the output like --beta's and is written to the log ("beta").
    #[arg(
        long,
        value_name = "DIST",
        allow_hyphen_values = true,
        conflicts_with = "beta"
    )]
    pub beta_dist: Option<BetaDistribution>,

    /// Take shard K of N (1 ≤ K ≤ N): a deterministic share of the frames, by a hash of
    /// their names, so that N jobs split a dataset with no coordination.
    #[arg(long, value_name = "K/N", allow_hyphen_values = true)]
    pub shard: Option<String>,

    /// Loader threads decoding and pre-processing frames ahead of the GPU, each every N-th
    /// frame (1-16; each holds a frame in memory, a lone loader two) [default: a quarter
    /// of the cores, 1 to 4]. On a real GPU a single loader is what limits the rate.
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub loaders: Option<i64>,

    /// Writer threads capturing, encoding and writing outputs, each one at a time (1-16;
    /// each holds an output's image, 32 MB at 2048 x 1024; the log keeps the outputs'
    /// order) [default: a quarter of the cores, 1 to 4; at least 2 with --shot-noise-gain,
    /// --read-noise or --jpeg-quality]. With a real GPU and several loaders, one writer's
    /// PNG encoding is what limits the rate.
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub writers: Option<i64>,

    /// Check everything and list the fogged images a run would write, one per line, then
    /// a summary (frames found, outputs to write and already written, frames that cannot
    /// be read, the folder's settings): nothing is written, no folder made, no GL context
    /// opened. For a look before a long job or an array of them.
    #[arg(long)]
    pub dry_run: bool,

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

    /// Coarse to fine from PX px, or `off` (as `brume render --coarse-from`).
    #[arg(
        long,
        value_name = "off|PX",
        default_value_t = super::render::CoarseFrom(Some(brume::blur::DEFAULT_COARSE_FROM)),
        allow_hyphen_values = true,
        value_parser = super::render::parse_coarse_from
    )]
    pub coarse_from: super::render::CoarseFrom,

    /// Texture precision: f32 or f16.
    #[arg(long, value_name = "P", allow_hyphen_values = true)]
    pub precision: Option<Precision>,

    /// Airlight as linear R,G,B, or one value for a grey [default: from the sky found, per
    /// frame].
    #[arg(long, value_name = "R,G,B", allow_hyphen_values = true, value_parser = parse_rgb)]
    pub airlight: Option<[f32; 3]>,

    /// Whose conventions, as `brume render --compat`: brume or foggy-cityscapes (the
    /// blend in sRGB code values, no blur, the dark-channel airlight) [default: brume].
    #[arg(long, value_enum, allow_hyphen_values = true)]
    pub compat: Option<Compat>,

    #[command(flatten)]
    pub refine: RefineArgs,

    /// Skip hole filling and sky detection.
    #[arg(long)]
    pub no_prep: bool,

    #[command(flatten)]
    pub prep: PrepOptionArgs,

    #[command(flatten)]
    pub capture: CaptureArgs,
}
