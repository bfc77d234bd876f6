//! `brume bench accuracy|speed`: the clap arguments and [`run`], which the CLI calls with
//! an open renderer. Lists and sizes are taken as text and checked here, so that a bad
//! value is an [`Error::invalid`] naming the option, like every other brume error.

use super::args::{parse_coarse_from, CoarseFrom};
use super::limits::{self, MAX_ESTIMATIONS, MAX_RUNS, MAX_SAMPLES, MAX_TURBIDITY_BENCH_SIDE};
use brume::bench::accuracy::{run_accuracy, AccuracyOptions};
use brume::bench::fog::{fog_table, run_fog_bench, FogBenchOptions};
use brume::bench::plot::{accuracy_plot_bytes, speed_plot_bytes, PlotFormat};
use brume::bench::refine::{refine_table, run_refine_bench};
use brume::bench::report;
use brume::bench::speed::{self, run_speed, SpeedOptions, Tau};
use brume::bench::turbidity::{run_turbidity_bench, turbidity_table, TurbidityBenchOptions};
use brume::bench::{Configs, Progress};
use brume::io::output::{self, Outputs};
use brume::raster::RgbImage;
use brume::{Error, Precision, Renderer, Result, Scheme};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::path::{Path, PathBuf};

/// The two experiments of paper 000, sec. 5.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum BenchCommand {
    /// Fig. 6: RMS error of each scheme and precision against the exact Gaussian, and the
    /// blur scale actually reached (impulse response), for each σref.
    Accuracy(AccuracyArgs),
    /// Fig. 7: time of the N + 2 passes for each σref, scheme and precision (median and
    /// standard deviation of several runs after a warm-up).
    Speed(SpeedArgs),
    /// Papers 001 and 003: the engine fogs on brume's scene (distance fog with noise and
    /// scattering, layered fog) with each blur, median of several runs after a warm-up.
    Fog(FogArgs),
    /// Paper 002's Table 1: the turbidity estimator on Preetham sky images (T = 2..9,
    /// 100 estimations of N = 100 points each), clear and with synthetic clouds; CPU only.
    Turbidity(TurbidityBenchArgs),
    /// Issue 19: the image-guided refinement of real depth: the guided filter at the image's
    /// size and joint bilateral upsampling of a range 4 and 8 times smaller.
    Refine(RefineBenchArgs),
}

/// `brume bench refine`.
#[derive(clap::Args, Debug, Clone)]
pub struct RefineBenchArgs {
    /// Image size WIDTHxHEIGHT in px.
    #[arg(
        long,
        value_name = "WxH",
        default_value = "2048x1024",
        allow_hyphen_values = true
    )]
    pub size: String,
    /// Timed runs per configuration, after one untimed run.
    #[arg(long, default_value_t = 5, allow_hyphen_values = true)]
    pub runs: i64,
    /// Print one JSON object on stdout instead of the table (the table goes to stderr).
    #[arg(long)]
    pub json: bool,
}

/// Bytes per pixel of a `bench turbidity` sky held in memory (measured, README).
const TURBIDITY_BENCH_BYTES_PER_PIXEL: u64 = 48;

/// Bytes per pixel of `--size` that `bench speed` and `bench refine` hold in system
/// memory on a software renderer, textures included: 92 and 85 (their peak RSS between
/// 2000 x 1500 and 4000 x 3000), rounded up (README's limits table).
const IMAGE_BENCH_BYTES_PER_PIXEL: u64 = 96;

/// `brume bench turbidity`.
#[derive(clap::Args, Debug, Clone)]
pub struct TurbidityBenchArgs {
    /// Side of the sky images in px.
    #[arg(
        long,
        value_name = "PX",
        default_value_t = 500,
        allow_hyphen_values = true
    )]
    pub size: i64,
    /// Turbidities of the sky models, comma-separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "2,3,4,5,6,7,8,9",
        allow_hyphen_values = true
    )]
    pub turbidities: Vec<String>,
    /// Estimations per image.
    #[arg(
        long,
        value_name = "K",
        default_value_t = 100,
        allow_hyphen_values = true
    )]
    pub estimations: i64,
    /// Random sample points per estimation.
    #[arg(
        long,
        value_name = "N",
        default_value_t = 100,
        allow_hyphen_values = true
    )]
    pub samples: i64,
    /// Cloud cover of the second pass, a fraction of the sky in [0, 0.9] (0: clear only).
    #[arg(
        long,
        value_name = "F",
        default_value_t = 0.2,
        allow_hyphen_values = true
    )]
    pub clouds: f64,
    /// Seed of the sampling and the clouds, a whole number ≥ 0.
    #[arg(
        long,
        value_name = "N",
        default_value_t = 0,
        allow_hyphen_values = true
    )]
    pub seed: i128,
    /// Quantise the sky images to 8-bit sRGB first, as a PNG written by `brume sky`
    /// (the paper's Fig. 7 images are 8-bit) and read back would be.
    #[arg(long)]
    pub eight_bit: bool,
    /// Fit the level of the ratios with T (`brume turbidity --fit-level`).
    #[arg(long)]
    pub fit_level: bool,
    /// Print one JSON object on stdout instead of the table (the table goes to stderr).
    #[arg(long)]
    pub json: bool,
}

impl TurbidityBenchArgs {
    /// The library options these arguments stand for.
    pub fn options(&self) -> Result<TurbidityBenchOptions> {
        let opts = TurbidityBenchOptions {
            size: limits::count("--size", self.size, 16, MAX_TURBIDITY_BENCH_SIDE, "px")?,
            turbidities: parse_list("--turbidities", &self.turbidities, |t| {
                t.parse::<f64>().ok()
            })?,
            estimations: limits::count(
                "--estimations",
                self.estimations,
                1,
                MAX_ESTIMATIONS,
                "estimations",
            )?,
            samples: limits::count("--samples", self.samples, 5, MAX_SAMPLES, "sample points")?,
            cloud_cover: self.clouds,
            seed: u64::try_from(self.seed).map_err(|_| {
                Error::invalid("--seed", self.seed, "a whole number from 0 to 2^64 - 1")
            })?,
            eight_bit: self.eight_bit,
            fit_level: self.fit_level,
            ..TurbidityBenchOptions::default()
        };
        limits::check_sample_points(
            "--estimations/--samples/--turbidities",
            opts.estimations,
            opts.samples,
            opts.turbidities.len(),
        )?;
        limits::check_memory(
            "--size",
            opts.size,
            opts.size,
            TURBIDITY_BENCH_BYTES_PER_PIXEL,
        )?;
        opts.validate().map_err(|e| {
            e.rename_options(|field| match field {
                "cloud_cover" => Some("--clouds".into()),
                "turbidity" => Some("--turbidities".into()),
                _ => None,
            })
        })?;
        Ok(opts)
    }
}

/// Runs `brume bench turbidity`: the experiment, then the table (or JSON) on stdout.
pub fn run_turbidity(args: &TurbidityBenchArgs) -> Result<()> {
    let opts = args.options()?;
    let bar = progress_bar("images");
    let report = run_turbidity_bench(&opts, &|done, total, what| {
        advance_count(&bar, done, total, what)
    })?;
    bar.finish_and_clear();
    print_report(args.json, &turbidity_table(&report), &report)
}

/// `brume bench fog`.
#[derive(clap::Args, Debug, Clone)]
pub struct FogArgs {
    /// Frame size WIDTHxHEIGHT in px.
    #[arg(
        long,
        value_name = "WxH",
        default_value = "1920x1080",
        allow_hyphen_values = true
    )]
    pub size: String,
    /// Timed runs per configuration, after two untimed warm-up renders.
    #[arg(long, default_value_t = brume::bench::fog::DEFAULT_RUNS as i64, allow_hyphen_values = true)]
    pub runs: i64,
    /// Print one JSON object on stdout instead of the table (the table goes to stderr).
    #[arg(long)]
    pub json: bool,
}

/// Options shared by both experiments.
#[derive(clap::Args, Debug, Clone)]
pub struct CommonArgs {
    /// Target blur scales σref in px, comma-separated; each must be ≥ σ0 = 1 px.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "1,2,3,5,8,12,16,20,25",
        allow_hyphen_values = true
    )]
    pub sigmas: Vec<String>,
    /// Diffusion schemes to run, comma-separated: euler (eq. 13), invariant (eq. 18 as
    /// written), matched (variance-matched offsets, the default renderer scheme).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "euler,invariant,matched",
        allow_hyphen_values = true
    )]
    pub schemes: Vec<String>,
    /// Texture precisions of the diffusion passes, comma-separated: f32 (RGBA32F) and/or
    /// f16 (RGBA16F).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "f32,f16",
        allow_hyphen_values = true
    )]
    pub precisions: Vec<String>,
    /// Also write the table as CSV to this file (header + one row per configuration).
    #[arg(long, value_name = "PATH")]
    pub csv: Option<PathBuf>,
    /// Print one JSON object on stdout instead of the table (the table goes to stderr).
    #[arg(long)]
    pub json: bool,
    /// Draw the paper's figure to this file; the extension picks the format (.png or .svg).
    #[arg(long, value_name = "PATH.png|PATH.svg")]
    pub plot: Option<PathBuf>,
    /// Coarse to fine (matched scheme): run the steps at half resolution once the
    /// blur has reached this scale in px (≥ 2), at a quarter once it has doubled; a σref of
    /// 10 px or more starts at step 0 whatever PX (a uniform blur keeps no full-resolution
    /// detail); `off`, the default here, runs every step at full resolution, the paper's
    /// pipeline (`render`, `batch` and `view` default to 2).
    #[arg(
        long,
        value_name = "off|PX",
        default_value_t = CoarseFrom(None),
        allow_hyphen_values = true,
        value_parser = parse_coarse_from
    )]
    pub coarse_from: CoarseFrom,
}

/// `brume bench accuracy`.
#[derive(clap::Args, Debug, Clone)]
pub struct AccuracyArgs {
    /// σ list, schemes, precisions and outputs.
    #[command(flatten)]
    pub common: CommonArgs,
    /// Image to blur (linear light is derived from sRGB as for `render`); default: the
    /// built-in demo image (Aloe).
    #[arg(long, value_name = "PATH")]
    pub image: Option<PathBuf>,
}

/// `brume bench speed`.
#[derive(clap::Args, Debug, Clone)]
pub struct SpeedArgs {
    /// σ list, schemes, precisions and outputs.
    #[command(flatten)]
    pub common: CommonArgs,
    /// Image size WIDTHxHEIGHT in px (the content is synthetic: it does not change the
    /// time of a pass).
    #[arg(
        long,
        value_name = "WxH",
        default_value = "1600x1120",
        allow_hyphen_values = true
    )]
    pub size: String,
    /// Timed runs per configuration, after one untimed warm-up render.
    // Counts are signed here so that a negative one reaches the check naming the option.
    #[arg(long, default_value_t = speed::DEFAULT_RUNS as i64, allow_hyphen_values = true)]
    pub runs: i64,
    /// Skip configurations with more than this many passes (N + 2), e.g. 200 to leave
    /// out Euler at large σ (1250 passes at σ = 25); skipped rows say so.
    #[arg(long, value_name = "P", allow_hyphen_values = true)]
    pub max_passes: Option<i64>,
    /// Transmission: grey (τ = 1, paper 000's pipeline) or rgb (τ = 0.9,0.8,0.6). A
    /// uniform blur has no in-scattered light, so both diffuse one RGBA texture, ρ in its
    /// alpha: what a grey or tinted haze costs (a medium whose in-scattered light varies,
    /// such as the aerial perspective, adds the rate's and a (τ_g, τ_b) texture).
    #[arg(long, value_name = "TAU", default_value = "grey", value_parser = parse_tau, allow_hyphen_values = true)]
    pub tau: Tau,
}

fn parse_tau(s: &str) -> std::result::Result<Tau, String> {
    match s {
        "grey" => Ok(Tau::Grey),
        "rgb" => Ok(Tau::Rgb),
        _ => Err(format!("'{s}' is not grey or rgb")),
    }
}

impl CommonArgs {
    /// The checked configuration list.
    pub fn configs(&self) -> Result<Configs> {
        let configs = Configs {
            sigmas: parse_list("--sigmas", &self.sigmas, |t| t.parse::<f64>().ok())?,
            schemes: parse_list("--schemes", &self.schemes, |t| t.parse::<Scheme>().ok())?,
            precisions: parse_list("--precisions", &self.precisions, |t| {
                t.parse::<Precision>().ok()
            })?,
            ..Configs::default()
        };
        configs.validate()?;
        Ok(configs)
    }

    /// Fails before any work if `--plot` has an unknown extension, an output cannot be
    /// renamed into place, an output is one of `inputs` or both outputs are one file (a
    /// benchmark can run for minutes).
    pub fn check_outputs(&self, inputs: &[PathBuf]) -> Result<()> {
        let mut outputs = Vec::new();
        if let Some(csv) = &self.csv {
            output::check_destination(csv, "--csv")?;
            outputs.push(("--csv", csv.as_path()));
        }
        if let Some(plot) = &self.plot {
            PlotFormat::from_path(plot)?;
            output::check_destination(plot, "--plot")?;
            outputs.push(("--plot", plot.as_path()));
        }
        super::refuse_overlaps(&outputs, inputs)
    }
}

impl AccuracyArgs {
    /// The library options these arguments stand for.
    pub fn options(&self) -> Result<AccuracyOptions> {
        let opts = AccuracyOptions {
            configs: self.common.configs()?,
            coarse_from: self.common.coarse_from.0,
        };
        opts.validate()?;
        Ok(opts)
    }
}

impl SpeedArgs {
    /// The library options these arguments stand for.
    pub fn options(&self) -> Result<SpeedOptions> {
        let (width, height) = limits::parse_image_size("--size", &self.size)?;
        limits::check_memory("--size", width, height, IMAGE_BENCH_BYTES_PER_PIXEL)?;
        let opts = SpeedOptions {
            configs: self.common.configs()?,
            width,
            height,
            runs: limits::count("--runs", self.runs, 1, MAX_RUNS, "timed runs")?,
            max_passes: self
                .max_passes
                .map(|p| count("--max-passes", p, "a number of passes ≥ 0"))
                .transpose()?,
            tau: self.tau,
            coarse_from: self.common.coarse_from.0,
        };
        opts.validate()?;
        Ok(opts)
    }
}

/// Runs a `brume bench` command: the experiment, then the table (or JSON) on stdout and
/// the CSV and plot files. `demo` gives the built-in image when `--image` is absent;
/// `load_image` reads `--image` as linear RGB.
pub fn run(
    cmd: &BenchCommand,
    renderer: &mut Renderer,
    demo: &dyn Fn() -> Result<RgbImage>,
    load_image: &dyn Fn(&Path) -> Result<RgbImage>,
) -> Result<()> {
    match cmd {
        BenchCommand::Accuracy(a) => {
            let opts = a.options()?;
            let inputs: Vec<PathBuf> = a.image.iter().cloned().collect();
            a.common.check_outputs(&inputs)?;
            let image = match &a.image {
                Some(path) => load_image(path)?,
                None => demo()?,
            };
            let bar = progress_bar("passes");
            let report = run_accuracy(renderer, &image, &opts, &|p| advance(&bar, p))?;
            bar.finish_and_clear();
            emit(
                &a.common,
                &report::accuracy_table(&report),
                || report::accuracy_json(&report),
                &report::accuracy_csv(&report),
                |path| accuracy_plot_bytes(&report, path),
            )
        }
        BenchCommand::Fog(f) => {
            let (width, height) = limits::parse_image_size("--size", &f.size)?;
            let opts = FogBenchOptions {
                width,
                height,
                runs: limits::count("--runs", f.runs, 1, MAX_RUNS, "timed runs")?,
                ..FogBenchOptions::default()
            };
            let bar = progress_bar("configurations");
            let report = run_fog_bench(renderer, &opts, &|done, total, what| {
                advance_count(&bar, done, total, what)
            })?;
            bar.finish_and_clear();
            print_report(f.json, &fog_table(&report), &report)
        }
        BenchCommand::Turbidity(t) => run_turbidity(t),
        BenchCommand::Refine(r) => {
            let (width, height) = limits::parse_image_size("--size", &r.size)?;
            limits::check_memory("--size", width, height, IMAGE_BENCH_BYTES_PER_PIXEL)?;
            let runs = limits::count("--runs", r.runs, 1, MAX_RUNS, "timed runs")?;
            let report = run_refine_bench(renderer, width, height, runs)?;
            print_report(r.json, &refine_table(&report), &report)
        }
        BenchCommand::Speed(s) => {
            let opts = s.options()?;
            s.common.check_outputs(&[])?;
            let bar = progress_bar("passes");
            let report = run_speed(renderer, &opts, &|p| advance(&bar, p))?;
            bar.finish_and_clear();
            emit(
                &s.common,
                &report::speed_table(&report),
                || report::speed_json(&report),
                &report::speed_csv(&report),
                |path| speed_plot_bytes(&report, path),
            )
        }
    }
}

/// Writes the outputs that `common` asks for, all or none, then prints the table (or
/// the JSON).
fn emit(
    common: &CommonArgs,
    table: &str,
    json: impl FnOnce() -> Result<String>,
    csv: &str,
    plot: impl FnOnce(&Path) -> Result<Vec<u8>>,
) -> Result<()> {
    let json = if common.json { Some(json()?) } else { None };
    let mut outputs = Outputs::new();
    if let Some(path) = &common.csv {
        outputs.stage_bytes(path, csv.as_bytes())?;
    }
    if let Some(path) = &common.plot {
        outputs.stage_bytes(path, &plot(path)?)?;
    }
    super::commit(outputs)?;
    match json {
        Some(json) => {
            // stdout holds exactly one JSON object; the human table goes to stderr.
            err!("{table}");
            outln!("{json}");
        }
        None => out!("{table}"),
    }
    Ok(())
}

/// A bar on stderr; indicatif draws nothing when stderr is not a terminal, so logs and
/// pipes stay clean.
fn progress_bar(unit: &str) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
    let template =
        format!("{{bar:40}} {{pos}}/{{len}} {unit}  {{elapsed_precise}} (eta {{eta}})  {{msg}}");
    let style =
        ProgressStyle::with_template(&template).unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style);
    bar
}

/// [`advance`] for a benchmark that counts whole items (images, configurations).
fn advance_count(bar: &ProgressBar, done: usize, total: usize, what: &str) {
    advance(
        bar,
        Progress {
            done: done as u64,
            total: total as u64,
            what,
        },
    );
}

/// Prints a benchmark's table on stdout, or its JSON there and the table on stderr.
fn print_report(json: bool, table: &str, report: &impl serde::Serialize) -> Result<()> {
    if !json {
        out!("{table}");
        return Ok(());
    }
    let report = serde_json::to_value(report).map_err(|e| {
        Error::invalid(
            "report",
            "(not serialisable)",
            format!("serialisable data: {e}"),
        )
    })?;
    let text = serde_json::to_string_pretty(&super::stamped(report)).expect("values serialise");
    err!("{table}");
    outln!("{text}");
    Ok(())
}

fn advance(bar: &ProgressBar, p: Progress) {
    bar.set_length(p.total);
    bar.set_position(p.done);
    bar.set_message(p.what.to_string());
}

/// Parses every item of a comma list (surrounding spaces allowed), naming `option` in
/// the error; an empty list or an empty item is an error.
fn parse_list<T>(
    option: &str,
    items: &[String],
    parse: impl Fn(&str) -> Option<T>,
) -> Result<Vec<T>> {
    if items.is_empty() {
        return Err(Error::invalid(option, "(empty)", "a comma-separated list"));
    }
    items
        .iter()
        .map(|item| {
            parse(item.trim()).ok_or_else(|| Error::invalid(option, item, expected(option)))
        })
        .collect()
}

fn expected(option: &str) -> &'static str {
    match option {
        "--schemes" => "a comma list of euler, invariant, matched",
        "--precisions" => "a comma list of f32, f16",
        _ => "a comma list of numbers, e.g. 1,2,3,5",
    }
}

/// A count given on the command line, refused (naming `option`) when negative or too
/// large for `T`.
fn count<T: TryFrom<i64>>(option: &str, value: i64, expected: &str) -> Result<T> {
    T::try_from(value).map_err(|_| Error::invalid(option, value, expected))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cli::{name_flags, Cli, Command};
    use brume::bench::DEFAULT_SIGMAS;
    use clap::Parser;

    fn parse(args: &[&str]) -> BenchCommand {
        let argv = ["brume", "bench"].into_iter().chain(args.iter().copied());
        match Cli::try_parse_from(argv).unwrap().command {
            Command::Bench(cmd) => cmd,
            _ => panic!("not a bench command"),
        }
    }

    #[test]
    fn defaults_are_the_papers() {
        let BenchCommand::Accuracy(a) = parse(&["accuracy"]) else {
            panic!("not accuracy")
        };
        let c = a.options().unwrap().configs;
        assert_eq!(c.sigmas, DEFAULT_SIGMAS.to_vec());
        assert_eq!(c.schemes, Scheme::ALL.to_vec());
        assert_eq!(c.precisions, Precision::ALL.to_vec());
        let BenchCommand::Speed(s) = parse(&["speed"]) else {
            panic!("not speed")
        };
        let o = s.options().unwrap();
        assert_eq!(
            (o.width, o.height, o.runs, o.max_passes),
            (1600, 1120, 5, None)
        );
    }

    #[test]
    fn bad_values_name_their_option() {
        let cases: [(&[&str], &str); 6] = [
            (&["speed", "--sigmas", "0.5"], "--sigmas"),
            (&["speed", "--sigmas", "2,x"], "--sigmas"),
            (&["speed", "--schemes", "fast"], "--schemes"),
            (&["speed", "--precisions", "f64"], "--precisions"),
            (&["speed", "--size", "0x10"], "--size"),
            (&["speed", "--runs", "0"], "--runs"),
        ];
        for (args, option) in cases {
            let BenchCommand::Speed(s) = parse(args) else {
                panic!()
            };
            let err = name_flags(s.options().unwrap_err()).to_string();
            assert!(err.contains(option), "{args:?}: {err}");
        }
        let BenchCommand::Accuracy(a) = parse(&["accuracy", "--plot", "x.jpg"]) else {
            panic!()
        };
        let err = name_flags(a.common.check_outputs(&[]).unwrap_err()).to_string();
        assert!(err.contains("--plot"), "{err}");
    }

    #[test]
    fn turbidity_defaults_are_table_1() {
        let BenchCommand::Turbidity(t) = parse(&["turbidity"]) else {
            panic!("not turbidity")
        };
        let o = t.options().unwrap();
        assert_eq!((o.size, o.estimations, o.samples), (500, 100, 100));
        assert_eq!(o.turbidities, (2..=9).map(f64::from).collect::<Vec<_>>());
        assert_eq!((o.sun_zenith_deg, o.sun_azimuth_deg), (58.4, -179.4));
        assert_eq!(o.cloud_cover, 0.2);
        let BenchCommand::Turbidity(t) = parse(&["turbidity", "--turbidities", "2,x"]) else {
            panic!()
        };
        let err = name_flags(t.options().unwrap_err()).to_string();
        assert!(err.contains("--turbidities"), "{err}");
    }

    #[test]
    fn sizes_parse() {
        let parse = |t| limits::parse_image_size("--size", t);
        assert_eq!(parse("400x280").unwrap(), (400, 280));
        assert_eq!(parse(" 16X8 ").unwrap(), (16, 8));
        assert!(parse("400").is_err());
        assert!(parse("-1x3").is_err());
    }
}
