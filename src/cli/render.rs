//! `brume render`: load (or the demo), pre-process, render on the GPU, write, report.

use super::args::{CaptureArgs, Compat, MediumKind, RenderArgs};
use super::inputs::{depth_inputs, load_depth, load_masks, prep_options};
use brume::blur::Blur;
use brume::egl::Platform;
use brume::io::depth::DepthKind;
use brume::io::output::{self, Outputs};
use brume::io::{demo, image};
use brume::medium::haze::{self, Haze};
use brume::medium::physical::{PhysicalFog, DEFAULT_ALBEDO};
use brume::medium::{Medium, UniformBlur};
use brume::photo::{self, CaptureOptions, Extinction, Insertion, SensorNoise, VirtualObject};
use brume::raster::ScalarMap;
use brume::Rendered;
use brume::{Error, Result};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

const DEMO_OUT: &str = "brume-demo.png";

/// The inputs of one render and where they came from (the library's photo).
pub use brume::photo::Photo as Scene;
/// What pre-processing and refinement made of the range, and the airlight.
pub use brume::photo::PreparedPhoto as PrepReport;

/// What is rendered: the medium (paper 000's haze, or a uniform blur) and the blur.
pub struct Look {
    pub haze: Haze,
    pub uniform: Option<UniformBlur>,
    pub blur: Blur,
}

impl Look {
    pub fn medium(&self) -> &dyn Medium {
        match &self.uniform {
            Some(u) => u,
            None => &self.haze,
        }
    }

    /// κa + κs as the render applies it (0 for a uniform blur).
    fn extinction(&self) -> f64 {
        if self.uniform.is_some() {
            0.0
        } else {
            self.haze.extinction()
        }
    }

    /// The airlight as the render applies it (black for a uniform blur).
    pub fn airlight(&self) -> [f32; 3] {
        if self.uniform.is_some() {
            [0.0; 3]
        } else {
            self.haze.airlight
        }
    }

    pub fn sigma_max(&self) -> f64 {
        self.medium().sigma_max(self.blur.sigma0)
    }
}

pub fn run(args: &RenderArgs, egl: Option<Platform>) -> Result<()> {
    super::options::check_options(args)?;
    let from_map;
    let args = match args.transmittance_map {
        Some(_) => {
            from_map = super::compat::transmittance_map_args(args);
            &from_map
        }
        None => args,
    };
    let out = output_path(args)?;
    output::check_image_output(&out, "--out")?;
    super::refuse_overlaps(&[("--out", &out)], &input_paths(args))?;
    let mut scene = load_scene(args)?;

    let mut prep = preprocess(args, &scene)?;
    let mut headless = super::open_renderer(egl)?;
    let depth_size = [scene.depth.range.width(), scene.depth.range.height()];
    let refine_mode = super::refine::mode_name(args.refine.options(scene.depth.format)?.mode);
    let refined = super::refine::refine_scene(args, &mut scene, &mut prep, headless.renderer()?)?;
    if args.transmittance_map.is_some() {
        // The map's τ as given: pre-processing found the sky for the airlight only.
        prep.range = scene.depth.range.clone();
    }
    let inserted = insert_object(args, &mut scene, &mut prep)?;
    let capture = capture_options(&args.capture, args.prep.seed)?;
    let range = &prep.range;
    if args.medium == MediumKind::Aerial {
        let extras = super::aerial::Extras {
            inserted: inserted.as_ref(),
            capture: &capture,
        };
        return super::aerial::run_aerial(args, &mut headless, &scene, &prep, &out, extras);
    }
    let fog = physical_from_args(args)?;
    if args.compat == Some(Compat::FoggyCityscapes) {
        let fog = fog.expect("checked: --compat foggy-cityscapes has physical fog");
        if !capture.is_off() {
            return Err(Error::invalid(
                "--compat",
                "foggy-cityscapes",
                "no capture options with it (--exposure-stops, --shot-noise-gain, \
                 --read-noise, --jpeg-quality): Foggy Cityscapes' images have none",
            ));
        }
        return super::compat::run_foggy_cityscapes(args, &scene, range, &fog, &out);
    }
    let (medium_range, range_divisor, look) = haze_inputs(args, &prep)?;
    let transmittance = transmittance_range(&look, &medium_range, &scene.depth.range);

    let renderer = &mut headless;
    let mut rendered = renderer.render(&scene.image, &medium_range, look.medium(), &look.blur)?;
    photo::capture(&mut rendered.image, &capture)?;
    let mut outputs = Outputs::new();
    outputs.stage_rgba(&out, &rendered.image)?;
    super::commit(outputs)?;

    let report = Report {
        scene: &scene,
        prep: &prep,
        look: &look,
        fog: fog.as_ref(),
        transmittance,
        rendered: &rendered,
        renderer: &renderer.caps().renderer,
        out: &out,
    };
    if args.json {
        let mut json = report.json(args, range_divisor);
        json["refine"] = json!({
            "mode": refine_mode,
            "depth_size": depth_size,
            "upsampled": refined.upsample,
            "guided": refined.guided.map(|r| json!({"radius_px": r.radius_px, "epsilon": r.epsilon})),
        });
        json["insert"] = insert_json(args, inserted.as_ref());
        json["capture"] = capture_json(&capture);
        outln!("{json}");
    } else {
        report.print_summary();
        print_insert_and_capture(args, inserted.as_ref(), &capture);
        if args.timings {
            print_timings(&rendered);
        }
    }
    Ok(())
}

/// Everything a render reports, gathered once for the JSON and the text forms.
struct Report<'a> {
    scene: &'a Scene,
    prep: &'a PrepReport,
    look: &'a Look,
    /// The fog in physical units, when --beta or --visibility gave it.
    fog: Option<&'a PhysicalFog>,
    /// The least and the largest τ over the pixels of known range (none for a uniform blur).
    transmittance: Option<[f64; 2]>,
    rendered: &'a Rendered,
    renderer: &'a str,
    out: &'a Path,
}

/// Every file `args` reads: none of them may be an output.
pub fn input_paths(args: &RenderArgs) -> Vec<PathBuf> {
    args.image
        .iter()
        .cloned()
        .chain(depth_inputs(&args.depth))
        .chain(args.sky.iter().cloned())
        .chain(args.prep.sky_mask.iter().cloned())
        .chain(args.prep.ego_mask.iter().cloned())
        .chain(args.sensitivity.iter().cloned())
        .chain(args.transmittance_map.iter().cloned())
        .chain(args.right.iter().cloned())
        .chain(args.insert.insert.iter().cloned())
        .chain(args.insert.insert_depth.iter().cloned())
        .collect()
}

/// The haze of `args`: paper 000's in normalised range (--ka, --ks), or with --beta or
/// --visibility the same medium on range in metres ([`PhysicalFog::haze`]).
pub fn haze_from_args(args: &RenderArgs) -> Result<Haze> {
    let haze = Haze {
        ka: args.ka.unwrap_or(haze::DEFAULT_KA),
        ks: args.ks.unwrap_or(haze::DEFAULT_KS),
        lambda: args.lambda,
        airlight: args.airlight.unwrap_or(haze::DEFAULT_AIRLIGHT),
        tint: args.tint.unwrap_or([1.0; 3]),
        range_unit: 1.0,
    };
    haze.validate()?;
    let haze = match physical_from_args(args)? {
        Some(fog) => fog.haze(&haze),
        None => haze,
    };
    if !(args.sigma0.is_finite() && args.sigma0 > 0.0) {
        return Err(Error::invalid("sigma0", args.sigma0, "a finite number > 0"));
    }
    if !(args.rho_max > 0.0 && args.rho_max <= 0.25) {
        return Err(Error::invalid(
            "rho_max",
            args.rho_max,
            "a rate in (0, 0.25]",
        ));
    }
    if let Some(s) = args.uniform_sigma {
        if !(s.is_finite() && s >= args.sigma0) {
            return Err(Error::invalid(
                "uniform_sigma",
                s,
                format!("a finite scale ≥ --sigma0 ({} px)", args.sigma0),
            ));
        }
    }
    Ok(haze)
}

/// The range the haze reads (see [`haze_range`]), the range that counts as 1, and the
/// look, as `brume render` renders them.
pub fn haze_inputs(args: &RenderArgs, prep: &PrepReport) -> Result<(ScalarMap, f64, Look)> {
    let range = &prep.range;
    let haze = haze_from_args(args)?;
    let fog = physical_from_args(args)?;
    let (medium_range, range_divisor) = haze_range(fog.as_ref(), &haze, range)?;
    Ok((
        medium_range,
        range_divisor,
        look_from_args(args, &haze, prep.airlight),
    ))
}

/// The fog of --beta or --visibility (with --albedo), or `None` for normalised κ. Refused
/// where it would be ignored: --albedo alone, the aerial medium, a uniform blur.
pub fn physical_from_args(args: &RenderArgs) -> Result<Option<PhysicalFog>> {
    let albedo = args.albedo.unwrap_or(DEFAULT_ALBEDO);
    let (fog, flag, value) = match (args.beta, args.visibility) {
        (Some(beta), _) => (PhysicalFog::new(beta, albedo)?, "beta", beta),
        (None, Some(v)) => (PhysicalFog::from_visibility(v, albedo)?, "visibility", v),
        (None, None) => {
            return match args.albedo {
                // --ka and --ks are absorption and scattering already.
                Some(a) => Err(Error::invalid(
                    "albedo",
                    a,
                    "--beta or --visibility with it (with --ka/--ks, κa and κs already \
                     split the extinction)",
                )),
                None => Ok(None),
            };
        }
    };
    if args.medium == MediumKind::Aerial {
        return Err(Error::invalid(
            flag,
            value,
            "--medium haze (the aerial medium's extinction comes from --turbidity)",
        ));
    }
    if args.uniform_sigma.is_some() {
        return Err(Error::invalid(
            flag,
            value,
            "no --uniform-sigma with it (a uniform blur has no fog)",
        ));
    }
    Ok(Some(fog))
}

/// Refuses physical fog on a range that is not in trustworthy metres
/// ([`LoadedDepth::metric`]), naming the depth, how it was read and what would do.
fn check_metric(args: &RenderArgs, scene: &Scene) -> Result<()> {
    let depth = &scene.depth;
    if args.medium == MediumKind::Aerial && !depth.metric && args.metres_per_unit.is_none() {
        return Err(Error::invalid(
            "--metres-per-unit",
            "(missing)",
            format!(
                "the scale of {}'s range for --medium aerial, which is in metres: it was read \
                 as {} {} in {}, not trustworthy metres (give --metres-per-unit, or a \
                 metric depth: --calib, --camera, a metric --depth-format)",
                scene.depth_name, depth.format, depth.kind, depth.units
            ),
        ));
    }
    let given = match (args.beta, args.visibility) {
        (Some(b), _) => ("beta", b),
        (None, Some(v)) => ("visibility", v),
        (None, None) => return Ok(()),
    };
    if depth.metric {
        return Ok(());
    }
    if args.depth.depth.is_none() {
        return Err(Error::invalid(
            given.0,
            given.1,
            "range in metres, but the built-in demo's is not (middlebury2006 with \
             approximate geometry, stretched): give --image and --depth with a metric depth \
             (--calib, --camera, or a metric --depth-format), or use --ka/--ks",
        ));
    }
    let why = if depth.units != "m" {
        format!("in {}", depth.units)
    } else {
        "with approximate default geometry (give --focal, --baseline and \
         --disparity-offset)"
            .to_string()
    };
    Err(Error::invalid(
        given.0,
        given.1,
        format!(
            "range in metres, but {} was read as {} {} {why}: give its calibration \
             (--calib calib.txt, --camera NAME_camera.json), a metric --depth-format \
             (cityscapes, kitti, nyu, tum, android-depth16, arcore) or --depth-scale in \
             metres per unit; or use --ka/--ks (normalised range)",
            scene.depth_name, depth.format, depth.kind
        ),
    ))
}

/// The range texture of the haze and the range that counts as 1 (`range_divisor`):
/// normalised by its largest value (paper 000), or kept in metres for physical fog, whose
/// unit is the visibility.
pub fn haze_range(
    fog: Option<&PhysicalFog>,
    haze: &Haze,
    range: &ScalarMap,
) -> Result<(ScalarMap, f64)> {
    let extinction = match fog {
        Some(f) => Extinction::Physical(*f),
        None => Extinction::Normalised {
            ka: haze.ka,
            ks: haze.ks,
        },
    };
    let (medium_range, r_max) = brume::photo::medium_range(&extinction, range)?;
    Ok((
        medium_range,
        if fog.is_some() {
            haze.range_unit
        } else {
            r_max
        },
    ))
}

/// The least and the largest τ (over channels) of the haze at the pixels whose range
/// was measured (`measured` known), as the medium computes it from its range texture;
/// `None` for a uniform blur.
fn transmittance_range(
    look: &Look,
    medium_range: &ScalarMap,
    measured: &ScalarMap,
) -> Option<[f64; 2]> {
    if look.uniform.is_some() {
        return None;
    }
    let haze = &look.haze;
    medium_range
        .as_slice()
        .iter()
        .zip(measured.as_slice())
        .filter(|(_, m)| m.is_finite() && **m > 0.0)
        .flat_map(|(r, _)| haze.transmission(f64::from(*r) / haze.range_unit))
        .fold(None, |acc: Option<[f64; 2]>, t| match acc {
            None => Some([t, t]),
            Some([lo, hi]) => Some([lo.min(t), hi.max(t)]),
        })
}

fn output_path(args: &RenderArgs) -> Result<PathBuf> {
    match (&args.out, &args.image) {
        (Some(out), _) => Ok(out.clone()),
        (None, None) if args.depth.depth.is_none() => Ok(PathBuf::from(DEMO_OUT)),
        _ => Err(Error::invalid(
            "--out",
            "(missing)",
            "an output path ending in .png, .pfm or .exr when --image/--depth are given",
        )),
    }
}

/// The photo and its range (or the demo), checked to be of one size and, for physical
/// fog, in metres.
pub fn load_scene(args: &RenderArgs) -> Result<Scene> {
    if let (Some(image_path), Some(map)) = (&args.image, &args.transmittance_map) {
        return super::compat::load_transmittance_scene(image_path, map);
    }
    match (&args.image, &args.depth.depth) {
        (None, None) => {
            let scene = Scene {
                image: demo::demo_image()?,
                depth: demo::demo_range()?,
                image_name: "built-in demo image".into(),
                depth_name: "built-in demo disparity".into(),
            };
            check_metric(args, &scene)?;
            Ok(scene)
        }
        (Some(image_path), Some(_)) => {
            brume::photo::check_memory_before_loading(image_path)?;
            let depth = load_depth(&args.depth)?;
            let scene = Scene {
                image: image::load_linear_rgb(image_path)?,
                depth,
                image_name: image_path.display().to_string(),
                depth_name: args
                    .depth
                    .depth
                    .as_ref()
                    .expect("checked")
                    .display()
                    .to_string(),
            };
            scene.check_depth_fits()?;
            check_metric(args, &scene)?;
            let mut scene = scene;
            super::refine::drop_left_right_mismatches(args, &mut scene)?;
            Ok(scene)
        }
        (None, Some(_)) => Err(Error::invalid(
            "--image",
            "(missing)",
            "a colour image to go with --depth",
        )),
        (Some(_), None) => Err(Error::invalid(
            "--depth",
            "(missing)",
            "a depth, range or disparity map to go with --image",
        )),
    }
}

/// Pre-processes the scene's range as `args` ask ([`brume::photo::preprocess`]): the
/// masks of `--sky-mask` and `--ego-mask` (checked against the depth map), the
/// pre-processing options, the airlight policy; nothing with `--no-prep` or a uniform blur
/// (which ignores range and airlight).
pub fn preprocess(args: &RenderArgs, scene: &Scene) -> Result<PrepReport> {
    let mut opts = brume::photo::PrepareOptions {
        airlight: args.airlight,
        ..Default::default()
    };
    if args.no_prep || args.uniform_sigma.is_some() {
        opts.prep = None;
        return brume::photo::preprocess(scene, &opts);
    }
    opts.prep = Some(prep_options(&args.prep)?);
    let masks = load_masks(&args.prep, &scene.depth.range, &scene.depth_name)?;
    (opts.sky_mask, opts.ego_mask) = (masks.sky, masks.ego);
    let started = Instant::now();
    let prepared = brume::photo::preprocess(scene, &opts)?;
    if let Some(p) = &prepared.prepared {
        log::info!(
            "pre-processing: {} holes ({} px) filled, {} sky px, {:.1} ms CPU",
            p.stats.holes,
            p.stats.hole_pixels,
            p.stats.sky_pixels,
            started.elapsed().as_secs_f64() * 1e3
        );
    }
    Ok(prepared)
}

pub fn look_from_args(args: &RenderArgs, haze: &Haze, airlight: [f32; 3]) -> Look {
    Look {
        haze: Haze { airlight, ..*haze },
        uniform: args.uniform_sigma.map(UniformBlur::new),
        blur: Blur {
            scheme: args.scheme,
            sigma0: args.sigma0,
            rho_max: args.rho_max,
            precision: args.precision,
            coarse_from: args.coarse_from.0,
            ..Blur::default()
        },
    }
}

impl Report<'_> {
    fn json(&self, args: &RenderArgs, range_divisor: f64) -> serde_json::Value {
        let Report {
            scene,
            prep,
            look,
            fog,
            transmittance,
            rendered,
            renderer,
            out,
        } = *self;
        let prep_json = prep.prepared.as_ref().map(|p| &p.stats);
        json!({
            "width": scene.image.width(),
            "height": scene.image.height(),
            "medium": look.medium().name(),
            "scheme": look.blur.scheme,
            "precision": look.blur.precision,
            "diffusion_passes": rendered.schedule.steps,
            "passes": rendered.times.pass_ms.len(),
            "renderer": renderer,
            "clock": rendered.times.clock,
            "total_ms": rendered.times.total_ms,
            "pass_ms": rendered.times.pass_ms,
            "out": out.display().to_string(),
            "image": scene.image_name,
            "depth": scene.depth_name,
            "depth_format": scene.depth.format.to_string(),
            "depth_kind": scene.depth.kind.to_string(),
            "depth_notes": scene.depth.notes,
            "sigma0": look.blur.sigma0,
            "sigma_max": look.sigma_max(),
            "uniform_sigma": args.uniform_sigma,
            "extinction": look.extinction(),
            "tint": look.haze.tint,
            "range_divisor": range_divisor,
            "beta": fog.map(|f| f.beta),
            "visibility_m": fog.map(PhysicalFog::visibility_m),
            "albedo": fog.map(|f| f.albedo),
            "transmittance_min": transmittance.map(|t| t[0]),
            "transmittance_max": transmittance.map(|t| t[1]),
            "airlight": look.airlight(),
            "airlight_source": prep.airlight_from.name(),
            "prep": prep_json,
        })
    }

    fn print_summary(&self) {
        let Report {
            scene,
            prep,
            look,
            fog,
            transmittance,
            rendered,
            renderer,
            out,
        } = *self;
        let t = &rendered.times;
        if let Some(p) = &prep.prepared {
            let s = &p.stats;
            outln!(
                "pre-processing: {} holes ({} px) filled, {} sky px, {:.1} ms CPU",
                s.holes,
                s.hole_pixels,
                s.sky_pixels,
                s.total_ms
            );
        }
        let b = look.airlight();
        outln!(
            "airlight {:.3},{:.3},{:.3} ({}), σmax {:.2} px, κ {:.3}",
            b[0],
            b[1],
            b[2],
            prep.airlight_from.name(),
            look.sigma_max(),
            look.extinction()
        );
        if let Some(f) = fog {
            outln!(
                "fog β {} m⁻¹ (visibility {:.1} m, albedo {})",
                f.beta,
                f.visibility_m(),
                f.albedo
            );
        }
        if let Some([lo, hi]) = transmittance {
            outln!("τ from {lo:.4} to {hi:.4} over the pixels of known range");
        }
        outln!(
            "wrote {} ({}x{}, {} {}, {} diffusion passes + 2, {} on {})",
            out.display(),
            scene.image.width(),
            scene.image.height(),
            look.blur.scheme,
            look.blur.precision,
            rendered.schedule.steps,
            t.describe(1),
            renderer
        );
    }
}

fn print_timings(rendered: &Rendered) {
    let t = &rendered.times;
    if !t.is_available() {
        outln!("pass times n/a (the GPU timer's figures were rejected)");
        return;
    }
    outln!("{:>6}  {:<20} {:>10}", "pass", "shader", "ms");
    for (i, (name, ms)) in rendered.pass_names().iter().zip(&t.pass_ms).enumerate() {
        outln!("{:>6}  {:<20} {:>10.3}", i + 1, name, ms);
    }
    outln!(
        "{:>6}  {:<20} {:>10.3}  ({})",
        "total",
        "",
        t.total_ms,
        t.clock.name()
    );
}

/// The capture after the fog that `capture` asks for (all off by default), its noise
/// seeded by `seed` (--seed, which also seeds the hole filling).
pub fn capture_options(capture: &CaptureArgs, seed: Option<i128>) -> Result<CaptureOptions> {
    let seed = u64::try_from(seed.unwrap_or(0)).map_err(|_| {
        Error::invalid(
            "--seed",
            seed.unwrap_or(0),
            "a whole number from 0 to 2^64 - 1",
        )
    })?;
    let noise = match (capture.shot_noise_gain, capture.read_noise) {
        (None, None) => None,
        (gain, read) => Some(SensorNoise {
            gain: gain.unwrap_or(0.0),
            read_noise: read.unwrap_or(0.0),
        }),
    };
    let jpeg_quality = match capture.jpeg_quality {
        None => None,
        Some(q) => Some(
            u8::try_from(q)
                .ok()
                .filter(|q| (1..=100).contains(q))
                .ok_or_else(|| {
                    Error::invalid("--jpeg-quality", q, "a JPEG quality from 1 to 100")
                })?,
        ),
    };
    let opts = CaptureOptions {
        exposure_stops: capture.exposure_stops.unwrap_or(0.0),
        noise,
        jpeg_quality,
        seed,
    };
    opts.validate().map_err(|e| match e {
        // The library names its fields; the user typed flags.
        Error::InvalidParameter {
            name,
            value,
            expected,
        } => Error::InvalidParameter {
            name: format!("--{}", name.replace('_', "-")),
            value,
            expected,
        },
        e => e,
    })?;
    Ok(opts)
}

/// The capture options as the JSON report gives them (`null` when off).
pub fn capture_json(capture: &CaptureOptions) -> serde_json::Value {
    if capture.is_off() {
        return serde_json::Value::Null;
    }
    json!({
        "exposure_stops": capture.exposure_stops,
        "shot_noise_gain": capture.noise.map(|n| n.gain),
        "read_noise": capture.noise.map(|n| n.read_noise),
        "jpeg_quality": capture.jpeg_quality,
        "seed": capture.seed,
    })
}

/// Loads --insert and composites it into the photo and its prepared range (at the
/// image's size by now), before the fog; `None` without --insert.
fn insert_object(
    args: &RenderArgs,
    scene: &mut Scene,
    prep: &mut PrepReport,
) -> Result<Option<Insertion>> {
    let Some(path) = &args.insert.insert else {
        return Ok(None);
    };
    if let Some(t) = args.from_turbidity {
        return Err(Error::invalid(
            "--from-turbidity",
            t,
            "no --insert with it: retargeting first removes the photo's haze, which the \
             object, rendered clear, does not have",
        ));
    }
    let kind = args.insert.insert_depth_kind.unwrap_or(DepthKind::Depth);
    let intrinsics = photo_intrinsics(args, scene);
    let object = VirtualObject::load(
        path,
        args.insert.insert_depth.as_deref(),
        kind,
        intrinsics.as_ref(),
    )?;
    Ok(Some(photo::insert(scene, prep, &object)?))
}

/// The photo's pinhole intrinsics at the image's size: those its depth was read with
/// (scaled from the depth map's grid), else from --focal or --fov with the principal
/// point at the centre.
fn photo_intrinsics(args: &RenderArgs, scene: &Scene) -> Option<brume::io::depth::Intrinsics> {
    use brume::io::depth::Intrinsics;
    let (w, h) = (scene.image.width(), scene.image.height());
    if let Some(k) = scene.depth.intrinsics {
        let s = w as f64 / scene.depth.range.width() as f64;
        let at_image = |c: f64| (c + 0.5) * s - 0.5;
        return Some(Intrinsics {
            fx: k.fx * s,
            fy: k.fy * s,
            cx: at_image(k.cx),
            cy: at_image(k.cy),
        });
    }
    let focal = args.depth.focal.or_else(|| {
        args.depth
            .fov
            .map(|fov| h as f64 / 2.0 / (fov.to_radians() / 2.0).tan())
    })?;
    Some(Intrinsics::centred(focal, w, h))
}

/// --insert's report (`null` without it).
pub(super) fn insert_json(args: &RenderArgs, inserted: Option<&Insertion>) -> serde_json::Value {
    match (inserted, &args.insert.insert) {
        (Some(i), Some(path)) => json!({
            "object": path.display().to_string(),
            "pixels_in_front": i.in_front,
            "pixels_partial": i.partial,
            "pixels_hidden": i.hidden,
        }),
        _ => serde_json::Value::Null,
    }
}

/// The text report's lines for --insert and the capture.
pub(super) fn print_insert_and_capture(
    args: &RenderArgs,
    inserted: Option<&Insertion>,
    capture: &CaptureOptions,
) {
    if let (Some(i), Some(path)) = (inserted, &args.insert.insert) {
        outln!(
            "inserted {}: {} px in front ({} partly covered), {} px hidden by the photo",
            path.display(),
            i.in_front + i.partial,
            i.partial,
            i.hidden
        );
    }
    if !capture.is_off() {
        outln!("capture: {}", capture_json(capture));
    }
}
