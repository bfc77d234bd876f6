//! `brume scene`: render brume's procedural 3D scene into a colour and a depth texture,
//! fog it as an engine would (papers 001 and 003) on the same GL context, and write the
//! frame (or a numbered sequence), the raw depth buffer and the fog-free frame.

use super::args::{BlurKind, FogKind, ProfileKind, SceneArgs};
use super::limits;
use brume::camera::{Camera, FrameInputs};
use brume::egl::Platform;
use brume::io::output::{self, Outputs};
use brume::medium::{
    DensityTable, DistanceFog, FogNoise, HeightProfile, LayeredFog, Medium, ProfileValues,
};
use brume::raster::RgbaImage;
use brume::scene::SceneRenderer;
use brume::{Blur, Encoding, Error, FogBlur, GaussBlur, Input, Result};
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;
use std::path::{Path, PathBuf};

/// What one frame of the sequence did.
struct FrameReport {
    time: f64,
    out: PathBuf,
    pass_names: Vec<String>,
    pass_ms: Vec<f64>,
    total_ms: f64,
    clock: &'static str,
}

/// Bytes per pixel a scene render holds in system memory on a software renderer: the
/// scene's and the fog's textures and the read-back (measured, README's limits table).
pub const SCENE_BYTES_PER_PIXEL: u64 = 96;

pub fn run(args: &SceneArgs, egl: Option<Platform>) -> Result<()> {
    let (width, height) = limits::parse_image_size("--size", &args.size)?;
    limits::check_memory("--size", width, height, SCENE_BYTES_PER_PIXEL)?;
    let camera = camera_from_args(args);
    camera.validate()?;
    check_sequence(args)?;
    check_fog_options(args)?;
    let outs = frame_paths(&args.out, args.frames);
    check_outputs(args, &outs)?;
    let blur = fog_blur_from_args(args)?;
    if args.fog == FogKind::None && args.blur != BlurKind::None {
        log::warn!("--fog none: nothing to blur, --blur ignored");
    }

    let mut headless = super::open_renderer(egl)?;
    let renderer_name = headless.caps().renderer.clone();
    let renderer = headless.renderer()?;
    let gl = std::sync::Arc::clone(renderer.pipeline().gl());
    let mut scene = SceneRenderer::new(gl)?;
    let sun = scene.scene().sun_direction;

    let progress = progress_bar(args.frames);
    let mut reports = Vec::new();
    // One set for the whole sequence: a failure or an interrupt at any frame leaves none
    // of the frames, as every other command leaves none of its outputs.
    let mut outputs = Outputs::new();
    // One medium for the whole sequence, as an engine keeps one: each frame gives it the
    // camera and the time.
    let medium = medium_from_args(args, camera, sun)?;
    for (k, out) in outs.iter().enumerate() {
        let time = args.time + k as f64 / args.fps;
        let frame = scene.render(&camera, width, height, time)?;
        let input = Input {
            colour: frame.colour,
            colour_encoding: Encoding::Linear,
            depth: frame.depth,
            width,
            height,
            frame: FrameInputs::new(camera, time),
        };
        let report = match &medium {
            Some(m) => {
                let (done, image) = renderer
                    .pipeline()
                    .fog_to_image(&input, m.medium(), &blur)?;
                outputs.stage_rgba(out, &image)?;
                FrameReport {
                    time,
                    out: out.clone(),
                    pass_names: done.pass_names(),
                    pass_ms: done.times.pass_ms.clone(),
                    total_ms: done.times.total_ms,
                    clock: done.times.clock.name(),
                }
            }
            None => {
                outputs.stage_rgba(out, &top_first_rgba(&frame.read_colour()?))?;
                FrameReport {
                    time,
                    out: out.clone(),
                    pass_names: vec![],
                    pass_ms: vec![],
                    total_ms: 0.0,
                    clock: "none",
                }
            }
        };
        // The depth and the fog-free frame go with the first frame of a sequence.
        if k == 0 {
            if let Some(path) = &args.clear_out {
                outputs.stage_rgba(path, &top_first_rgba(&frame.read_colour()?))?;
            }
            if let Some(path) = &args.depth_out {
                let mut depth = frame.read_depth()?;
                depth.flip_rows();
                outputs.stage_scalar(path, &depth)?;
            }
        }
        reports.push(report);
        progress.inc(1);
    }
    progress.finish_and_clear();
    super::commit(outputs)?;

    if args.json {
        outln!(
            "{}",
            super::stamped(report_json(args, &camera, &blur, &renderer_name, &reports))
        );
    } else {
        print_summary(args, &blur, &renderer_name, &reports);
    }
    Ok(())
}

/// Refuses an option that cannot take effect, as `brume render` refuses the other
/// medium's: the layered fog's with another fog, the distance fog's (its noise included)
/// with another, the noise's with `--noise none` (and `--noise-seed` with a noise file),
/// a fog's colour or λ with `--fog none`. (`brume view scene` takes them all: its panel
/// switches between the fogs.)
fn check_fog_options(args: &SceneArgs) -> Result<()> {
    use super::options::{shown, shown3};
    let (l, d) = (&args.layered, &args.distance);
    let layered = [
        (
            "--profile",
            (l.profile != ProfileKind::Exponential)
                .then(|| format!("{:?}", l.profile).to_lowercase()),
        ),
        ("--density", shown(l.density)),
        ("--base", shown(l.base)),
        ("--scale-height", shown(l.scale_height)),
        ("--thickness", shown(l.thickness)),
        ("--top", shown(l.top)),
        ("--albedo", shown(l.albedo)),
        (
            "--density-csv",
            l.density_csv.as_ref().map(|p| p.display().to_string()),
        ),
    ];
    let noise = [
        (
            "--noise-seed",
            (d.noise_seed != 0).then(|| d.noise_seed.to_string()),
        ),
        ("--noise-size", shown(d.noise_size)),
        ("--noise-speed", shown3(d.noise_speed)),
        ("--noise-low", shown(d.noise_low)),
        ("--noise-high", shown(d.noise_high)),
        ("--noise-colour-strength", shown(d.noise_colour_strength)),
    ];
    let distance = [
        ("--fog-start", shown(d.fog_start)),
        ("--fog-distance", shown(d.fog_distance)),
        ("--fog-exponent", shown(d.fog_exponent)),
        ("--max-density", shown(d.max_density)),
        ("--light-dir", shown3(d.light_dir)),
        ("--scatter-start", shown(d.scatter_start)),
        ("--scatter-exponent", shown(d.scatter_exponent)),
        ("--scatter-colour", shown3(d.scatter_colour)),
        ("--noise", (d.noise != "generated").then(|| d.noise.clone())),
    ];
    let refuse = super::options::refuse_given;
    if args.fog != FogKind::Layered {
        refuse(
            &layered,
            "--fog layered with it (an option of the layered fog)",
        )?;
    }
    if args.fog != FogKind::Distance {
        let expected = "--fog distance with it (an option of the distance fog)";
        refuse(&distance, expected)?;
        refuse(&noise, expected)?;
    }
    match d.noise.as_str() {
        "none" => refuse(&noise, "a noise with it, not --noise none")?,
        "generated" => {}
        _ => refuse(
            &noise[..1],
            "--noise generated with it (a noise file has no seed)",
        )?,
    }
    if args.fog == FogKind::None {
        let given = [
            ("--fog-colour", shown3(args.fog_colour)),
            ("--lambda", shown(args.blur_options.lambda)),
        ];
        refuse(&given, "a fog with it, not --fog none")?;
    }
    Ok(())
}

pub fn camera_from_args(args: &SceneArgs) -> Camera {
    Camera {
        position: args.position,
        yaw_deg: args.yaw,
        pitch_deg: args.pitch,
        fov_y_deg: args.fov,
        near: args.near,
        far: args.far,
    }
}

pub fn check_sequence(args: &SceneArgs) -> Result<()> {
    limits::check_frames(args.frames)?;
    if !(args.fps.is_finite() && args.fps > 0.0) {
        return Err(Error::invalid("--fps", args.fps, "a frame rate > 0"));
    }
    if !args.time.is_finite() {
        return Err(Error::invalid(
            "--time",
            args.time,
            "a finite time in seconds",
        ));
    }
    Ok(())
}

/// `out` itself for one frame; `NAME_0001.EXT` … for a sequence.
fn frame_paths(out: &Path, frames: u32) -> Vec<PathBuf> {
    if frames == 1 {
        return vec![out.to_path_buf()];
    }
    let stem = out
        .file_stem()
        .map_or("frame".into(), |s| s.to_string_lossy());
    let ext = out
        .extension()
        .map_or("png".into(), |e| e.to_string_lossy());
    (1..=frames)
        .map(|k| out.with_file_name(format!("{stem}_{k:04}.{ext}")))
        .collect()
}

/// The files `args` reads: the noise texture, if one is given.
pub fn input_paths(args: &SceneArgs) -> Vec<PathBuf> {
    match args.distance.noise.as_str() {
        "generated" | "none" => vec![],
        path => vec![PathBuf::from(path)],
    }
}

fn check_outputs(args: &SceneArgs, outs: &[PathBuf]) -> Result<()> {
    let mut all: Vec<(&str, &Path)> = outs.iter().map(|p| ("--out", p.as_path())).collect();
    for out in outs {
        output::check_image_output(out, "--out")?;
    }
    if let Some(p) = &args.clear_out {
        output::check_image_output(p, "--clear-out")?;
        all.push(("--clear-out", p));
    }
    if let Some(p) = &args.depth_out {
        output::check_scalar_output(p, "--depth-out")?;
        all.push(("--depth-out", p));
    }
    super::refuse_overlaps(&all, &input_paths(args))
}

/// The blur `--blur` chose, with its options ([`FogBlur::chosen`]); `--lambda` only with
/// the diffusion blur, which is the only one to read it.
pub fn fog_blur_from_args(args: &SceneArgs) -> Result<FogBlur> {
    let (gauss, diffusion) = blurs_from_args(args);
    let blur = FogBlur::chosen(&blur_name(args.blur), gauss, diffusion)?;
    blur.check_lambda(args.blur_options.lambda)?;
    Ok(blur)
}

/// `--blur`'s value as typed: the name [`FogBlur::chosen`] takes.
fn blur_name(blur: BlurKind) -> String {
    let value = clap::ValueEnum::to_possible_value(&blur).expect("no variant is skipped");
    value.get_name().to_owned()
}

/// The Gaussian and the diffusion blur the options describe, whichever `--blur` chose,
/// unchecked: [`FogBlur::chosen`] checks them for `brume scene`, and `brume view scene`
/// checks both (its panel switches between them).
pub fn blurs_from_args(args: &SceneArgs) -> (GaussBlur, Blur) {
    let b = &args.blur_options;
    let gauss = GaussBlur {
        distance: b.blur_distance,
        falloff: b.blur_falloff,
        maximum: b.blur_max,
        precision: b.precision,
    };
    let diffusion = Blur {
        scheme: b.scheme,
        sigma0: b.sigma0,
        rho_max: b.rho_max,
        precision: b.precision,
        ..Blur::default()
    };
    (gauss, diffusion)
}

/// The fog of a scene frame, kept concrete so that the viewer can edit it and move its time.
pub enum SceneMedium {
    /// Paper 003's layered fog.
    Layered(LayeredFog),
    /// Paper 001's distance fog.
    Distance(DistanceFog),
}

impl SceneMedium {
    /// The medium to render.
    pub fn medium(&self) -> &dyn Medium {
        match self {
            SceneMedium::Layered(f) => f,
            SceneMedium::Distance(f) => f,
        }
    }

    /// Checks the parameters, naming the flags that set them.
    pub fn validate(&self) -> Result<()> {
        self.medium().validate().map_err(distance_flags)
    }
}

/// The medium the options describe (`None` for `--fog none`), its blur's range unit the
/// far plane of `camera`. The camera and the time are not part of it: each frame gives
/// them ([`FrameInputs`]).
pub fn medium_from_args(
    args: &SceneArgs,
    camera: Camera,
    sun: [f64; 3],
) -> Result<Option<SceneMedium>> {
    let lambda = args.blur_options.lambda;
    let medium = match args.fog {
        FogKind::None => return Ok(None),
        FogKind::Layered => {
            let l = &args.layered;
            let mut fog = LayeredFog::for_camera(camera, profile_from_args(l.profile, l)?);
            fog.colour = args.fog_colour.unwrap_or(fog.colour);
            fog.albedo = l.albedo.unwrap_or(fog.albedo);
            fog.lambda = lambda.unwrap_or(fog.lambda);
            SceneMedium::Layered(fog)
        }
        FogKind::Distance => {
            let d = &args.distance;
            let defaults = DistanceFog::default();
            SceneMedium::Distance(DistanceFog {
                start_distance: d.fog_start.unwrap_or(defaults.start_distance),
                distance: d.fog_distance.unwrap_or(defaults.distance),
                exponent: d.fog_exponent.unwrap_or(defaults.exponent),
                max_density: d.max_density.unwrap_or(defaults.max_density),
                colour: args.fog_colour.unwrap_or(defaults.colour),
                light_direction: d.light_dir.unwrap_or(sun),
                scatter_start: d.scatter_start.unwrap_or(defaults.scatter_start),
                scatter_exponent: d.scatter_exponent.unwrap_or(defaults.scatter_exponent),
                scatter_colour: d.scatter_colour.unwrap_or(defaults.scatter_colour),
                noise: noise_from_args(d)?,
                lambda: lambda.unwrap_or(defaults.lambda),
                range_unit: camera.far,
            })
        }
    };
    medium.validate()?;
    Ok(Some(medium))
}

/// The distance fog names its fields (`distance`, `noise size`); the flags that set them
/// are named differently (`--fog-distance`, `--noise-size`).
fn distance_flags(e: Error) -> Error {
    const FLAGS: [(&str, &str); 8] = [
        ("start_distance", "--fog-start"),
        ("distance", "--fog-distance"),
        ("exponent", "--fog-exponent"),
        ("light_direction", "--light-dir"),
        ("noise size", "--noise-size"),
        ("noise low", "--noise-low"),
        ("noise high", "--noise-high"),
        ("noise colour strength", "--noise-colour-strength"),
    ];
    e.rename_options(|field| {
        let flag = FLAGS.iter().find(|(f, _)| *f == field);
        flag.map(|(_, flag)| flag.to_string())
    })
}

/// The chosen profile: its preset (src/medium/layered/) or the table of `--density-csv`,
/// with the options given (refused where the profile does not have them).
fn profile_from_args(kind: ProfileKind, l: &super::args::LayeredArgs) -> Result<HeightProfile> {
    let profile = match (kind, &l.density_csv) {
        (ProfileKind::Table, Some(path)) => HeightProfile::Table(DensityTable::from_csv(path)?),
        (ProfileKind::Table, None) => {
            return Err(Error::invalid(
                "--profile",
                "table",
                "a table file too: --density-csv FILE.csv (header height_m,extinction_per_m)",
            ));
        }
        (_, Some(path)) => {
            return Err(Error::invalid(
                "--density-csv",
                path.display(),
                "--profile table with it (the analytic profiles take no table)",
            ));
        }
        (ProfileKind::Exponential, None) => HeightProfile::EXPONENTIAL,
        (ProfileKind::Band, None) => HeightProfile::SINE_BAND,
        (ProfileKind::Ramp, None) => HeightProfile::LINEAR_RAMP,
    };
    profile.with_checked(&ProfileValues {
        density: l.density,
        base: l.base,
        scale_height: l.scale_height,
        thickness: l.thickness,
        top: l.top,
    })
}

fn noise_from_args(d: &super::args::DistanceArgs) -> Result<Option<FogNoise>> {
    let mut noise = match d.noise.as_str() {
        "none" => return Ok(None),
        "generated" if d.noise_seed == 0 => FogNoise::default(),
        "generated" => FogNoise::generate(256, d.noise_seed)?,
        // A missing file names the option too (format errors already say "noise texture").
        path => FogNoise::from_png(Path::new(path)).map_err(|e| match e {
            Error::Io { path, source } => {
                Error::format(path, format!("cannot read the --noise texture: {source}"))
            }
            other => other,
        })?,
    };
    noise.size = d.noise_size.unwrap_or(noise.size);
    noise.speed = d.noise_speed.unwrap_or(noise.speed);
    noise.low = d.noise_low.unwrap_or(noise.low);
    noise.high = d.noise_high.unwrap_or(noise.high);
    noise.colour_strength = d.noise_colour_strength.unwrap_or(noise.colour_strength);
    Ok(Some(noise))
}

/// A frame read back from GL (bottom row first) as an RGBA image whose top row is first.
fn top_first_rgba(rgb: &brume::raster::RgbImage) -> RgbaImage {
    let mut image = rgb.opaque();
    image.flip_rows();
    image
}

fn progress_bar(frames: u32) -> ProgressBar {
    if frames <= 1 {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(u64::from(frames));
    if let Ok(style) = ProgressStyle::with_template("{bar:40} {pos}/{len} frames, {eta} left") {
        bar.set_style(style);
    }
    bar
}

fn fog_name(fog: FogKind) -> &'static str {
    match fog {
        FogKind::Distance => "distance",
        FogKind::Layered => "layered",
        FogKind::None => "none",
    }
}

fn report_json(
    args: &SceneArgs,
    camera: &Camera,
    blur: &FogBlur,
    renderer: &str,
    reports: &[FrameReport],
) -> serde_json::Value {
    let frames: Vec<serde_json::Value> = reports
        .iter()
        .map(|r| {
            let passes: Vec<serde_json::Value> = r
                .pass_names
                .iter()
                .zip(&r.pass_ms)
                .map(|(name, ms)| json!({ "pass": name, "ms": ms }))
                .collect();
            json!({
                "time": r.time,
                "out": r.out.display().to_string(),
                "total_ms": r.total_ms,
                "clock": r.clock,
                "passes": passes,
            })
        })
        .collect();
    json!({
        "size": args.size,
        "fog": fog_name(args.fog),
        "blur": blur.name(),
        "camera": {
            "position": camera.position,
            "yaw": camera.yaw_deg,
            "pitch": camera.pitch_deg,
            "fov": camera.fov_y_deg,
            "near": camera.near,
            "far": camera.far,
        },
        "renderer": renderer,
        "depth_out": args.depth_out.as_ref().map(|p| p.display().to_string()),
        "clear_out": args.clear_out.as_ref().map(|p| p.display().to_string()),
        "frames": frames,
    })
}

fn print_summary(args: &SceneArgs, blur: &FogBlur, renderer: &str, reports: &[FrameReport]) {
    for r in reports {
        let passes: Vec<String> = r
            .pass_names
            .iter()
            .zip(&r.pass_ms)
            .map(|(name, ms)| format!("{name} {ms:.2}"))
            .collect();
        let summary = if passes.len() > 4 {
            format!("{} passes", passes.len())
        } else {
            passes.join(", ")
        };
        let time = if r.total_ms.is_finite() {
            format!("{:.1} ms by {}", r.total_ms, r.clock)
        } else {
            // The GPU timer's figures were rejected.
            "time n/a".to_string()
        };
        outln!(
            "wrote {} ({} fog, blur {}, {time} on {renderer}: {summary})",
            r.out.display(),
            fog_name(args.fog),
            blur.name(),
        );
    }
    for (option, path) in [
        ("depth buffer", &args.depth_out),
        ("fog-free frame", &args.clear_out),
    ] {
        if let Some(p) = path {
            outln!("wrote {option} {}", p.display());
        }
    }
}
