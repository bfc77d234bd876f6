//! What `brume render`'s arguments make of a photo, shared by `render`, `prep`, `view` and
//! the aerial and Foggy Cityscapes paths: the scene loaded (or the demo), its
//! pre-processing, and the haze and blur it is rendered with, each error naming its flag.

use super::args::{MediumKind, RenderArgs};
use super::inputs::{depth_inputs, depth_options, load_masks, prep_options, show_depth_notes};
use brume::blur::Blur;
use brume::medium::haze;
use brume::medium::physical::{PhysicalFog, DEFAULT_ALBEDO};
use brume::photo::{Extinction, FogOptions};
use brume::{Error, Result};
use std::path::PathBuf;
use std::time::Instant;

/// The inputs of one render and where they came from (the library's photo).
pub use brume::photo::Photo as Scene;
/// What pre-processing and refinement made of the range, and the airlight.
pub use brume::photo::PreparedPhoto as PrepReport;

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

/// `brume render`'s fog in the library's terms: paper 000's haze in normalised range
/// (--ka, --ks), or with --beta or --visibility the same medium on range in metres, with
/// --lambda, --tint and the blur. Every value is checked (--airlight's and
/// --uniform-sigma's too) before any file is read.
pub fn fog_options(args: &RenderArgs) -> Result<FogOptions> {
    let extinction = match physical_from_args(args)? {
        Some(fog) => Extinction::Physical(fog),
        None => Extinction::Normalised {
            ka: args.ka.unwrap_or(haze::DEFAULT_KA),
            ks: args.ks.unwrap_or(haze::DEFAULT_KS),
        },
    };
    let opts = FogOptions {
        extinction,
        lambda: args.lambda,
        tint: args.tint.unwrap_or([1.0; 3]),
        blur: blur_from_args(args),
    };
    opts.haze(args.airlight.unwrap_or(haze::DEFAULT_AIRLIGHT))?;
    opts.blur.validate()?;
    if let Some(s) = args.uniform_sigma {
        if !(s.is_finite() && s >= args.sigma0) {
            return Err(Error::invalid(
                "uniform_sigma",
                s,
                format!("a finite scale ≥ --sigma0 ({} px)", args.sigma0),
            ));
        }
    }
    Ok(opts)
}

/// The diffusion blur of `args`.
pub fn blur_from_args(args: &RenderArgs) -> Blur {
    Blur {
        scheme: args.scheme,
        sigma0: args.sigma0,
        rho_max: args.rho_max,
        precision: args.precision,
        coarse_from: args.coarse_from.0,
        ..Blur::default()
    }
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
    if args.medium == MediumKind::Aerial {
        brume::photo::metres_per_unit(scene, args.metres_per_unit)?;
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
    scene.require_metres(given.0, given.1)
}

/// The photo and its range (or the demo), checked to be of one size and, for physical
/// fog, in metres.
pub fn load_scene(args: &RenderArgs) -> Result<Scene> {
    if let (Some(image_path), Some(map)) = (&args.image, &args.transmittance_map) {
        return Scene::load_transmittance(image_path, map);
    }
    match (&args.image, &args.depth.depth) {
        (None, None) => {
            let scene = Scene::demo()?;
            check_metric(args, &scene)?;
            Ok(scene)
        }
        (Some(image_path), Some(depth_path)) => {
            let opts = depth_options(&args.depth);
            // The left-right check reads the disparity as stored, decoded with the range.
            let (mut scene, disparity) = match args.right {
                Some(_) => Scene::load_stereo(image_path, depth_path, &opts)?,
                None => (Scene::load(image_path, depth_path, &opts)?, None),
            };
            check_metric(args, &scene)?;
            if let Some(right) = &args.right {
                super::refine::drop_left_right_mismatches(&mut scene, disparity.as_ref(), right)?;
            }
            show_depth_notes(depth_path, &mut scene.depth);
            Ok(scene)
        }
        (None, Some(_)) => Err(Error::invalid(
            "--image",
            "(missing)",
            "a colour image to go with --depth",
        )),
        // A phone's portrait photo carries its own depth map (GDepth, Dynamic Depth, Apple's).
        (Some(image_path), None) if brume::io::depth::has_embedded_depth(image_path) => {
            log::info!("{}: its embedded depth map", image_path.display());
            let mut args = args.clone();
            args.depth.depth = Some(image_path.clone());
            load_scene(&args)
        }
        (Some(image_path), None) => {
            // A HEIC portrait carries its depth too, but brume cannot decode it: say so.
            brume::io::image::refuse_heif(image_path)?;
            Err(Error::invalid(
                "--depth",
                "(missing)",
                "a depth, range or disparity map to go with --image, or --transmittance-map \
                 (or --image a JPEG that carries its depth map, GDepth, Dynamic Depth or an \
                 iPhone's depth image, as a phone's portrait photo does)",
            ))
        }
    }
}

/// Pre-processes the scene's range as `args` ask ([`brume::photo::preprocess`]): the
/// masks of `--sky-mask` and `--ego-mask` (checked against the depth map), the
/// pre-processing options, the airlight policy; nothing with `--no-prep`. A uniform blur,
/// which reads neither range nor airlight, is prepared all the same: the refinement that
/// follows needs a range known everywhere, and every option given takes effect as it
/// would on the haze.
pub fn preprocess(args: &RenderArgs, scene: &Scene) -> Result<PrepReport> {
    let mut opts = brume::photo::PrepareOptions {
        airlight: args.airlight,
        ..Default::default()
    };
    if args.no_prep {
        opts.prep = None;
        return brume::photo::preprocess(scene, &opts);
    }
    opts.prep = Some(prep_options(&args.prep)?);
    let masks = load_masks(&args.prep, &scene.depth, &scene.depth_name)?;
    (opts.sky_mask, opts.ego_mask) = (masks.sky, masks.ego);
    let started = Instant::now();
    let prepared = brume::photo::preprocess(scene, &opts)?;
    if let Some(p) = &prepared.prepared {
        // Wall time of the whole step (the report's figure is the CPU time of its parts).
        log::info!(
            "pre-processing: {} holes ({} px) filled, {} sky px, {:.1} ms wall",
            p.stats.holes,
            p.stats.hole_pixels,
            p.stats.sky_pixels,
            started.elapsed().as_secs_f64() * 1e3
        );
    }
    Ok(prepared)
}
