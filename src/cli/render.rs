//! `brume render`: load (or the demo), pre-process, render on the GPU, write, report.

use super::args::{Compat, MediumKind, RenderArgs};
use super::capture::{capture_options, insert_json, insert_object, print_insert_and_capture};
use super::photo_args::{fog_options, input_paths, load_scene, preprocess, PrepReport, Scene};
use brume::egl::Platform;
use brume::io::output::{self, Outputs};
use brume::medium::haze::Haze;
use brume::medium::physical::PhysicalFog;
use brume::medium::{Medium, UniformBlur};
use brume::photo::{self, Extinction, FogOptions};
use brume::raster::ScalarMap;
use brume::Rendered;
use brume::{Error, Result};
use serde_json::json;
use std::path::{Path, PathBuf};

const DEMO_OUT: &str = "brume-demo.png";

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
    let stages = super::stages::Stages::start(match (&args.image, &args.depth.depth) {
        (None, None) => "making the built-in demo scene",
        _ => "reading the photo and its depth",
    });
    let mut scene = load_scene(args)?;

    stages.at("pre-processing the depth");
    let mut prep = preprocess(args, &scene)?;
    stages.at("opening the GL context and refining the depth");
    let mut headless = super::open_renderer(egl)?;
    let depth_size = [scene.depth.range.width(), scene.depth.range.height()];
    let refine_mode = args.refine.options(scene.depth.format)?.mode.name();
    let (refined, refine_ms) =
        super::refine::refine_scene(args, &mut scene, &mut prep, headless.renderer()?)?;
    if args.transmittance_map.is_some() {
        // The map's τ as given: pre-processing found the sky for the airlight only, and
        // put no sky at Smax in what the fog reads, so physical fog moves no sky out
        // (`PreparedPhoto::metres`) and the report says so.
        prep.range = scene.depth.range.clone();
        if let Some(p) = &mut prep.prepared {
            p.stats.s_max = None;
        }
    }
    stages.at("rendering");
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
    let opts = fog_options(args)?;
    if args.compat == Some(Compat::FoggyCityscapes) {
        let Extinction::Physical(fog) = opts.extinction else {
            unreachable!("checked: --compat foggy-cityscapes has physical fog")
        };
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
    let uniform = args.uniform_sigma.map(UniformBlur::new);
    let (mut rendered, haze, range_divisor, transmittance) = match &uniform {
        None => {
            let f = photo::fog(headless.renderer()?, &scene, &prep, &opts)?;
            let t = transmittance_range(&f.haze, &f.range, &scene.depth.range);
            (f.rendered, Some(f.haze), f.range_divisor, t)
        }
        Some(u) => {
            // The range is read as the fog would read it, and changes nothing.
            let (range, divisor) = photo::medium_range(&opts.extinction, &prep)?;
            let rendered = headless.render(&scene.image, &range, u, &opts.blur)?;
            (rendered, None, divisor, None)
        }
    };
    photo::capture(&mut rendered.image, &capture)?;
    stages.at(&format!("writing {}", out.display()));
    let mut outputs = Outputs::new();
    outputs.stage_photo(&out, &rendered.image, &scene.metadata)?;
    super::commit(outputs)?;

    let report = Report {
        scene: &scene,
        prep: &prep,
        medium: match (&uniform, &haze) {
            (Some(u), _) => u,
            (None, h) => h.as_ref().expect("the fog renders a haze"),
        },
        haze: haze.as_ref(),
        opts: &opts,
        transmittance,
        rendered: &rendered,
        renderer: &headless.caps().renderer,
        out: &out,
    };
    if args.json {
        let mut json = report.json(args, range_divisor);
        json["refine"] = json!({
            "mode": refine_mode,
            "depth_size": depth_size,
            "upsampled": refined.upsample,
            "edges": refined.edges,
            "guided": refined.guided.map(|r| json!({"radius_px": r.radius_px, "epsilon": r.epsilon})),
        });
        json["refine_ms"] = json!(refine_ms);
        json["insert"] = insert_json(args, inserted.as_ref());
        json["capture"] = capture.to_json();
        outln!("{}", super::stamped(json));
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
    /// The haze, or the uniform blur of `--uniform-sigma`.
    medium: &'a dyn Medium,
    /// The haze as rendered; `None` for a uniform blur.
    haze: Option<&'a Haze>,
    opts: &'a FogOptions,
    /// The least and the largest τ over the pixels of known range (none for a uniform blur).
    transmittance: Option<[f64; 2]>,
    rendered: &'a Rendered,
    renderer: &'a str,
    out: &'a Path,
}

/// The least and the largest τ (over channels) of `haze` at the pixels whose range was
/// measured (`measured` known), as the medium computes it from its range texture: τ at
/// the farthest and the nearest of their ranges (τ falls with range in every channel),
/// so that a 12 MP report takes no exponential a pixel (120 ms before).
fn transmittance_range(
    haze: &Haze,
    medium_range: &ScalarMap,
    measured: &ScalarMap,
) -> Option<[f64; 2]> {
    let [near, far] = medium_range
        .as_slice()
        .iter()
        .zip(measured.as_slice())
        .filter(|(_, m)| m.is_finite() && **m > 0.0)
        .fold([f32::INFINITY, f32::NEG_INFINITY], |[lo, hi], (&r, _)| {
            [lo.min(r), hi.max(r)]
        });
    if near > far {
        return None; // no pixel of known range
    }
    let tau = |r: f32| haze.transmission(f64::from(r) / haze.range_unit);
    let fold = |pick: fn(f64, f64) -> f64, r: f32| tau(r).into_iter().reduce(pick);
    Some([fold(f64::min, far)?, fold(f64::max, near)?])
}

fn output_path(args: &RenderArgs) -> Result<PathBuf> {
    match (&args.out, &args.image) {
        (Some(out), _) => Ok(out.clone()),
        (None, None) if args.depth.depth.is_none() => Ok(PathBuf::from(DEMO_OUT)),
        _ => Err(Error::invalid(
            "--out",
            "(missing)",
            "an output path ending in .png, .jpg, .pfm or .exr when --image/--depth are given",
        )),
    }
}

impl Report<'_> {
    /// The fog in physical units, when --beta or --visibility gave it.
    fn physical(&self) -> Option<&PhysicalFog> {
        match &self.opts.extinction {
            Extinction::Physical(fog) => Some(fog),
            Extinction::Normalised { .. } => None,
        }
    }

    /// κa + κs as the render applied it (0 for a uniform blur).
    fn extinction(&self) -> f64 {
        self.haze.map_or(0.0, Haze::extinction)
    }

    /// The airlight as the render applied it (black for a uniform blur).
    fn airlight(&self) -> [f32; 3] {
        self.haze.map_or([0.0; 3], |h| h.airlight)
    }

    /// Where the applied airlight came from (`none` for a uniform blur, which has none).
    fn airlight_source(&self) -> &'static str {
        match self.haze {
            Some(_) => self.prep.airlight_from.name(),
            None => "none",
        }
    }

    fn sigma_max(&self) -> f64 {
        self.medium.sigma_max(self.opts.blur.sigma0)
    }

    fn json(&self, args: &RenderArgs, range_divisor: f64) -> serde_json::Value {
        let Report {
            scene,
            prep,
            medium,
            opts,
            transmittance,
            rendered,
            renderer,
            out,
            ..
        } = *self;
        let fog = self.physical();
        let prep_json = prep.prepared.as_ref().map(|p| &p.stats);
        json!({
            "width": scene.image.width(),
            "height": scene.image.height(),
            "medium": medium.name(),
            "scheme": opts.blur.scheme,
            "precision": opts.blur.precision,
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
            "camera_mount": scene.depth.mount,
            "stereo_view": scene.depth.stereo_focal_baseline.map(|_| scene.depth.stereo_view),
            "colour_profile": scene.metadata.profile().map(|p| p.description()),
            "sigma0": opts.blur.sigma0,
            "sigma_max": self.sigma_max(),
            "uniform_sigma": args.uniform_sigma,
            "extinction": self.extinction(),
            "tint": opts.tint,
            "range_divisor": range_divisor,
            "sky_range_m": fog.and(prep.sky_range_m()),
            "beta": fog.map(|f| f.beta),
            "visibility_m": fog.map(PhysicalFog::visibility_m),
            "albedo": fog.map(|f| f.albedo),
            "transmittance_min": transmittance.map(|t| t[0]),
            "transmittance_max": transmittance.map(|t| t[1]),
            "airlight": self.airlight(),
            "airlight_source": self.airlight_source(),
            "prep": prep_json,
        })
    }

    fn print_summary(&self) {
        let Report {
            scene,
            prep,
            opts,
            transmittance,
            rendered,
            renderer,
            out,
            ..
        } = *self;
        let fog = self.physical();
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
        let b = self.airlight();
        outln!(
            "airlight {:.3},{:.3},{:.3} ({}), σmax {:.2} px, κ {:.3}",
            b[0],
            b[1],
            b[2],
            self.airlight_source(),
            self.sigma_max(),
            self.extinction()
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
            "wrote {} ({}x{}, {} {}, {} diffusion steps in {} passes, {} on {})",
            out.display(),
            scene.image.width(),
            scene.image.height(),
            opts.blur.scheme,
            opts.blur.precision,
            rendered.schedule.steps,
            rendered.pass_names().len(),
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
