//! The checks of `brume render`'s options before any file is read (also for `batch` and
//! `view`, which take render's options): values, and options that cannot take effect.

use super::args::{Compat, DepthReadingArgs, MediumKind, PrepOptionArgs, RenderArgs};
use super::photo_args::fog_options;
use brume::blur::{DEFAULT_RHO_MAX, DEFAULT_SIGMA0};
use brume::io::depth;
use brume::medium::haze;
use brume::{Error, Precision, Result, Scheme};
use std::path::PathBuf;

/// Checks `args` before any file is read: the medium's values and options that cannot
/// take effect together.
pub fn check_options(args: &RenderArgs) -> Result<()> {
    fog_options(args)?;
    check_medium_options(args)?;
    super::aerial::check_aerial_options(args)?;
    check_depth_options(&args.depth.reading)?;
    if args.no_prep {
        refuse_prep_options(&args.prep, args.capture.reads_seed())?;
    }
    if args.compat == Some(Compat::FoggyCityscapes) {
        let physical =
            args.beta.is_some() || args.visibility.is_some() || args.transmittance_map.is_some();
        if !physical || args.medium == MediumKind::Aerial {
            return Err(Error::invalid(
                "--compat",
                "foggy-cityscapes",
                "--beta, --visibility or --transmittance-map with it (Foggy Cityscapes' fog \
                 is τ = exp(−βR) on the haze medium)",
            ));
        }
        let changed = |flag, differs: bool, value: String| (flag, differs.then_some(value));
        refuse_with_foggy_cityscapes(&[
            changed(
                "--lambda",
                args.lambda != haze::DEFAULT_LAMBDA,
                args.lambda.to_string(),
            ),
            changed(
                "--sigma0",
                args.sigma0 != DEFAULT_SIGMA0,
                args.sigma0.to_string(),
            ),
            changed(
                "--rho-max",
                args.rho_max != DEFAULT_RHO_MAX,
                args.rho_max.to_string(),
            ),
            changed(
                "--scheme",
                args.scheme != Scheme::Matched,
                args.scheme.to_string(),
            ),
            changed(
                "--precision",
                args.precision != Precision::F32,
                args.precision.to_string(),
            ),
            ("--coarse-from", args.coarse_from.changed()),
            ("--albedo", shown(args.albedo)),
            ("--tint", shown3(args.tint)),
        ])?;
    }
    Ok(())
}

/// Refuses an option of brume's fog that Foggy Cityscapes' conventions (the blend in code
/// values, no blur) would ignore; `options` pairs each flag with its value where given.
pub(super) fn refuse_with_foggy_cityscapes(options: &[(&str, Option<String>)]) -> Result<()> {
    refuse_given(
        options,
        "no --compat foggy-cityscapes with it: Foggy Cityscapes' conventions blend τ = \
         exp(−βR) in code values, with no blur",
    )
}

/// An option that cannot take effect is an error, not a silent no-op: the options of the
/// other medium (`--turbidity` on haze, `--tint` on aerial, …).
fn check_medium_options(args: &RenderArgs) -> Result<()> {
    let path = |p: &Option<PathBuf>| p.as_ref().map(|p| p.display().to_string());
    let aerial_only = [
        ("--turbidity", shown(args.turbidity)),
        ("--sky", path(&args.sky)),
        ("--from-turbidity", shown(args.from_turbidity)),
        ("--altitude", shown(args.altitude)),
        ("--metres-per-unit", shown(args.metres_per_unit)),
        ("--pitch", shown(args.pitch)),
        ("--horizon-row", shown(args.horizon_row)),
        ("--horizon-zenith", shown(args.horizon_zenith)),
        ("--horizon-sectors", shown(args.horizon_sectors)),
        (
            "--retarget",
            args.retarget.map(|r| format!("{r:?}").to_lowercase()),
        ),
        ("--latitude", shown(args.place.latitude)),
        ("--longitude", shown(args.place.longitude)),
        ("--time", args.place.time.clone()),
        ("--heading", shown(args.place.heading)),
        ("--sensitivity", path(&args.sensitivity)),
        ("--blur", args.blur.map(|b| format!("{b:?}").to_lowercase())),
    ];
    let haze_only = [
        ("--ka", shown(args.ka)),
        ("--ks", shown(args.ks)),
        ("--tint", shown3(args.tint)),
        ("--uniform-sigma", shown(args.uniform_sigma)),
    ];
    let (others, wanted, this) = match args.medium {
        MediumKind::Haze => (&aerial_only[..], "aerial", "haze"),
        MediumKind::Aerial => (&haze_only[..], "haze", "aerial"),
    };
    refuse_given(
        others,
        &format!("--medium {wanted} with it: the {this} medium of this render does not read it"),
    )?;
    if args.uniform_sigma.is_some() {
        let fog = [&haze_only[..3], &[("--airlight", shown3(args.airlight))]].concat();
        refuse_given(
            &fog,
            "no --uniform-sigma with it: a uniform blur has no attenuation and no airlight",
        )?;
    }
    Ok(())
}

/// An option's value as a refusal names it; `None` where it was not given.
pub(super) fn shown(value: Option<impl std::fmt::Display>) -> Option<String> {
    value.map(|v| v.to_string())
}

/// An R,G,B or X,Y,Z option's value as typed; `None` where it was not given.
pub(super) fn shown3<T: std::fmt::Display>(value: Option<[T; 3]>) -> Option<String> {
    value.map(|[a, b, c]| format!("{a},{b},{c}"))
}

/// Refuses the first option of `options` (flag, value if given) that was given.
pub(super) fn refuse_given(options: &[(&str, Option<String>)], expected: &str) -> Result<()> {
    match options
        .iter()
        .find_map(|(flag, v)| v.as_ref().map(|v| (*flag, v)))
    {
        Some((flag, value)) => Err(Error::invalid(flag, value, expected)),
        None => Ok(()),
    }
}

/// Depth options that only some inputs read, refused where none of them can.
pub fn check_depth_options(depth: &DepthReadingArgs) -> Result<()> {
    use depth::DepthKind::{Affine, ZBuffer};
    let zbuffer = depth.depth_kind == Some(ZBuffer);
    let planes = depth
        .depth_kind
        .is_some_and(|k| matches!(k, ZBuffer | Affine));
    let given = [
        ("--near", shown(depth.near.filter(|_| !planes))),
        ("--far", shown(depth.far.filter(|_| !planes))),
    ];
    refuse_given(
        &given,
        "--depth-kind zbuffer or affine with it: only a z-buffer's projection has clipping \
         planes, and only affine-invariant depth (Marigold) a nearest and farthest depth",
    )?;
    let reversed = [(
        "--reversed-z",
        (depth.reversed_z && !zbuffer).then(|| "given".to_string()),
    )];
    refuse_given(
        &reversed,
        "--depth-kind zbuffer with it: only a z-buffer's depth is reversed",
    )
}

/// With `--no-prep` nothing reads the pre-processing options: each one given is an error.
/// `seed_read_elsewhere`: --seed also seeds something else (the capture's noise, β
/// draws), so it is not refused.
pub fn refuse_prep_options(prep: &PrepOptionArgs, seed_read_elsewhere: bool) -> Result<()> {
    let given = [
        ("--margin", shown(prep.margin)),
        ("--sky-factor", shown(prep.sky_factor)),
        ("--no-sky", prep.no_sky.then(|| "given".to_string())),
        ("--sky-min-area", shown(prep.sky_min_area)),
        (
            "--seed",
            prep.seed
                .filter(|_| !seed_read_elsewhere)
                .map(|v| v.to_string()),
        ),
        (
            "--sky-mask",
            prep.sky_mask.as_ref().map(|p| p.display().to_string()),
        ),
        ("--far-outlier-factor", shown(prep.far_outlier_factor)),
        ("--local-outliers", shown(prep.local_outliers)),
        (
            "--ego-mask",
            prep.ego_mask.as_ref().map(|p| p.display().to_string()),
        ),
    ];
    refuse_given(
        &given,
        "no --no-prep with it: pre-processing is what reads it",
    )
}
