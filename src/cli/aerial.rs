//! `brume render --medium aerial`: paper 002's aerial perspective on a photo with depth,
//! from a turbidity given or estimated from a fisheye sky photo, and retargeting from the
//! turbidity a photo was taken at (sec. 7.2.3, eq. 25-26).

use super::args::{AerialBlur, RenderArgs, RetargetKind};
use super::photo_args::{look_from_args, PrepReport, Scene};
use super::sun::PlacedSun;
use brume::atmosphere::Sensitivity;
use brume::camera::Camera;
use brume::io::camera::Intrinsics;
use brume::io::output::Outputs;
use brume::medium::haze::Haze;
use brume::medium::{AerialPerspective, Medium};
use brume::photo::{
    pitch_for_horizon_row, turbidity_from_sky, AerialOptions, AerialPhoto, CaptureOptions,
    HorizonFrom, Insertion, Retarget, DEFAULT_HORIZON_ZENITH_DEG, MAX_PITCH_DEG,
};
use brume::sky::horizon_sectors::{DEFAULT_SECTORS, MAX_SECTORS};
use brume::Headless;
use brume::{Error, Result};
use serde_json::json;
use std::path::Path;

/// What the aerial render used, for the report.
pub struct AerialLook {
    pub medium: AerialPerspective,
    pub turbidity_source: &'static str,
    pub from_turbidity: Option<f64>,
    /// How the photo was retargeted (with `from_turbidity`).
    pub retarget: Retarget,
    /// The sun from place and time.
    pub sun: Option<PlacedSun>,
    /// The camera's sensitivity (the viewer rebuilds the tables from it as its controls
    /// change).
    #[cfg_attr(
        not(all(feature = "viewer", not(target_os = "android"))),
        allow(dead_code)
    )]
    pub sensitivity: Sensitivity,
}

/// The turbidity: `--turbidity`, or estimated from `--sky` (the sun from place and time
/// when given, else found from its saturated disc).
fn turbidity(args: &RenderArgs, sun: Option<&PlacedSun>) -> Result<(f64, &'static str)> {
    match (args.turbidity, &args.sky) {
        (Some(t), None) => Ok((t, "given")),
        (None, Some(path)) => {
            let estimate = turbidity_from_sky(path, sun.map(|s| [s.zenith, s.azimuth]))?;
            Ok((estimate.turbidity, "sky"))
        }
        (Some(_), Some(_)) => Err(Error::invalid(
            "--sky",
            "given with --turbidity",
            "one of --turbidity T or --sky SKY_IMAGE",
        )),
        (None, None) => Err(Error::invalid(
            "--turbidity",
            "(missing)",
            "a turbidity in [1, 20] (or --sky SKY_IMAGE to estimate it) for --medium aerial",
        )),
    }
}

/// The camera whose rays give each pixel's zenith angle, for an image `height` rows
/// tall: the vertical field of view from `--fov`, else from the depth's focal length
/// (`intrinsics`, e.g. a Cityscapes camera file) or `--focal`; the pitch from `--pitch`
/// or `--horizon-row`. With no field of view to be had it is an error: a guess would tilt
/// every pixel's zenith angle.
pub fn aerial_camera(
    args: &RenderArgs,
    height: usize,
    intrinsics: Option<&Intrinsics>,
) -> Result<Camera> {
    let focal = intrinsics.map(|i| i.fy).or(args.depth.focal);
    let fov_y_deg = match (args.depth.fov, focal) {
        (Some(fov), _) => fov,
        (None, Some(f)) if f.is_finite() && f > 0.0 => {
            (2.0 * (height as f64 / (2.0 * f)).atan()).to_degrees()
        }
        _ => {
            return Err(Error::invalid(
                "--fov",
                "(missing)",
                "the camera's vertical field of view in degrees for --medium aerial (or \
                 --focal in px, or a depth whose calibration gives it): each pixel's zenith \
                 angle depends on it",
            ))
        }
    };
    let pitch_deg = match args.horizon_row {
        Some(row) => {
            let pitch = pitch_for_horizon_row(row, height, fov_y_deg);
            if pitch.is_nan() || pitch.abs() > MAX_PITCH_DEG {
                return Err(Error::invalid(
                    "--horizon-row",
                    row,
                    format!(
                        "a row that puts the camera's pitch within ±{MAX_PITCH_DEG}° with this \
                         {height}-row image and a {fov_y_deg:.1}° field of view (it gives \
                         {pitch:.5}°; the horizon may lie a little outside the image)"
                    ),
                ));
            }
            pitch
        }
        None => args.pitch.unwrap_or(0.0),
    };
    let camera = Camera {
        pitch_deg,
        fov_y_deg,
        ..Camera::default()
    };
    camera.validate().map_err(|e| match e {
        Error::InvalidParameter {
            name,
            value,
            expected,
        } if name == "fov" && args.depth.fov.is_none() => Error::invalid(
            "--focal",
            focal.unwrap_or(f64::NAN),
            format!("a focal length giving a valid field of view: {value} is not {expected}"),
        ),
        e => e,
    })?;
    Ok(camera)
}

/// `--retarget`, the paper's normalised radiance by default.
fn retarget(args: &RenderArgs) -> Retarget {
    match args.retarget {
        Some(RetargetKind::Radiance) => Retarget::Radiance,
        Some(RetargetKind::Normalised) | None => Retarget::Normalised,
    }
}

/// `--altitude`'s range, metres: the Dead Sea's shore to above any airliner.
pub const ALTITUDE_RANGE_M: (f64, f64) = (-500.0, 20_000.0);
/// The turbidities the model is fitted for (Preetham et al.'s range), for `--turbidity`
/// and `--from-turbidity`.
pub const TURBIDITY_RANGE: (f64, f64) = (1.0, 20.0);

/// Checks the aerial options' values before any file is read, naming each flag as given:
/// the library would name its own fields, some of which are other commands' flags.
pub fn check_aerial_options(args: &RenderArgs) -> Result<()> {
    let (t_lo, t_hi) = TURBIDITY_RANGE;
    for (flag, value) in [
        ("--turbidity", args.turbidity),
        ("--from-turbidity", args.from_turbidity),
    ] {
        if let Some(t) = value.filter(|t| !(t_lo..=t_hi).contains(t)) {
            return Err(Error::invalid(
                flag,
                t,
                format!("a turbidity in [{t_lo}, {t_hi}]"),
            ));
        }
    }
    if let Some(n) = args
        .horizon_sectors
        .filter(|n| !(1..=MAX_SECTORS as i64).contains(n))
    {
        return Err(Error::invalid(
            "--horizon-sectors",
            n,
            format!("a number of azimuth sectors in [1, {MAX_SECTORS}]"),
        ));
    }
    if let (Some(r), None) = (args.retarget, args.from_turbidity) {
        return Err(Error::invalid(
            "--retarget",
            format!("{r:?}").to_lowercase(),
            "--from-turbidity T with it: only a photo taken at a known turbidity is \
             retargeted",
        ));
    }
    let (a_lo, a_hi) = ALTITUDE_RANGE_M;
    let checks: [(&str, Option<f64>, bool, String); 5] = [
        (
            "--horizon-zenith",
            args.horizon_zenith,
            args.horizon_zenith
                .is_some_and(|z| (0.0..=90.0).contains(&z)),
            "a zenith angle in [0, 90] degrees (90 is the horizon)".into(),
        ),
        (
            "--altitude",
            args.altitude,
            args.altitude.is_some_and(|a| (a_lo..=a_hi).contains(&a)),
            format!("an altitude above sea level in [{a_lo}, {a_hi}] m"),
        ),
        (
            "--metres-per-unit",
            args.metres_per_unit,
            args.metres_per_unit
                .is_some_and(|m| m.is_finite() && m > 0.0),
            "metres per unit of range, > 0".into(),
        ),
        (
            "--pitch",
            args.pitch,
            args.pitch.is_some_and(|p| p.abs() <= MAX_PITCH_DEG),
            format!("a pitch in [-{MAX_PITCH_DEG}, {MAX_PITCH_DEG}] degrees"),
        ),
        (
            "--horizon-row",
            args.horizon_row,
            args.horizon_row.is_some_and(f64::is_finite),
            "an image row, 0 at the top".into(),
        ),
    ];
    for (flag, value, ok, expected) in checks {
        if let Some(v) = value.filter(|_| !ok) {
            return Err(Error::invalid(flag, v, expected));
        }
    }
    Ok(())
}

/// The aerial render's inputs, as `brume render` and `brume view` use them.
pub struct AerialJob {
    /// The image, range, medium and blur the renderer is given.
    pub photo: AerialPhoto,
    pub look: AerialLook,
    /// Where the horizon's light came from, for the report.
    pub light_source: &'static str,
}

/// `--medium aerial`: paper 002's aerial perspective on the prepared range in metres
/// ([`brume::photo::aerial`]), the horizon's light from the sky found (or `--airlight`).
pub fn aerial_job(args: &RenderArgs, scene: &Scene, prep: &PrepReport) -> Result<AerialJob> {
    check_aerial_options(args)?;
    let sun = args.place.sun(None, args.altitude.unwrap_or(0.0))?;
    let (turbidity, turbidity_source) = turbidity(args, sun.as_ref())?;
    let sensitivity = match &args.sensitivity {
        Some(path) => Sensitivity::from_csv(path)?,
        None => Sensitivity::cie_srgb(),
    };
    let camera = aerial_camera(args, scene.image.height(), scene.depth.intrinsics.as_ref())?;
    let opts = AerialOptions {
        from_turbidity: args.from_turbidity,
        altitude_m: args.altitude.unwrap_or(0.0),
        metres_per_unit: args.metres_per_unit.unwrap_or(1.0),
        sensitivity,
        lambda: match args.blur.unwrap_or(AerialBlur::Diffusion) {
            AerialBlur::None => 0.0,
            AerialBlur::Diffusion => args.lambda,
        },
        horizon_zenith_deg: args.horizon_zenith.unwrap_or(DEFAULT_HORIZON_ZENITH_DEG),
        horizon_light: args.airlight,
        blur: look_from_args(args, &Haze::default(), prep.airlight).blur,
        horizon_sectors: args.horizon_sectors.map_or(DEFAULT_SECTORS, |n| n as usize),
        retarget: retarget(args),
        sun: sun.map(|s| [s.zenith, s.azimuth - s.heading]),
        ..AerialOptions::new(turbidity, camera)
    };
    let photo = brume::photo::aerial(scene, prep, &opts)?;
    let light_source = match photo.horizon_from {
        HorizonFrom::Airlight => prep.airlight_from.name(),
        from => from.name(),
    };
    Ok(AerialJob {
        look: AerialLook {
            medium: photo.medium.clone(),
            turbidity_source,
            from_turbidity: args.from_turbidity,
            retarget: opts.retarget,
            sun,
            sensitivity: opts.sensitivity,
        },
        light_source,
        photo,
    })
}

/// What the render did to the photo beside the fog, for the reports: `--insert`'s object
/// (composited before the fog) and the capture (after it).
pub struct Extras<'a> {
    pub inserted: Option<&'a Insertion>,
    pub capture: &'a CaptureOptions,
}

pub fn run_aerial(
    args: &RenderArgs,
    renderer: &mut Headless,
    scene: &Scene,
    prep: &PrepReport,
    out: &Path,
    extras: Extras,
) -> Result<()> {
    let job = aerial_job(args, scene, prep)?;
    let AerialJob {
        photo,
        look,
        light_source,
    } = &job;
    let AerialPhoto {
        image,
        range,
        max_range,
        blur,
        ..
    } = photo;
    let frame = brume::FrameInputs::default();
    let mut rendered =
        renderer.render_fog(image, range, &look.medium, &frame, &photo.fog_blur())?;
    brume::photo::capture(&mut rendered.image, extras.capture)?;
    let mut outputs = Outputs::new();
    outputs.stage_rgba(out, &rendered.image)?;
    super::commit(outputs)?;
    let m = &look.medium;
    let t = &rendered.times;
    if args.json {
        outln!(
            "{}",
            json!({
                "width": image.width(),
                "height": image.height(),
                "medium": "aerial",
                "turbidity": m.table.turbidity(),
                "turbidity_source": look.turbidity_source,
                "from_turbidity": look.from_turbidity,
                "retarget": look.from_turbidity.map(|_| look.retarget.name()),
                "sun": look.sun.map(|s| s.json()),
                "horizon_sectors": m.horizon_sectors.gains(),
                "altitude": m.table.altitude_m(),
                "metres_per_unit": m.metres_per_unit,
                "pitch": m.camera.pitch_deg,
                "fov": m.camera.fov_y_deg,
                "horizon_light": m.horizon_light,
                "horizon_light_source": light_source,
                "horizon_zenith": m.reference_zenith.to_degrees(),
                "max_range": max_range,
                "diffusion_passes": rendered.schedule.steps,
                "sigma_max": m.sigma_max(blur.sigma0),
                "renderer": renderer.caps().renderer,
                "clock": t.clock,
                "total_ms": t.total_ms,
                "pass_ms": t.pass_ms,
                "out": out.display().to_string(),
                "insert": super::capture::insert_json(args, extras.inserted),
                "capture": extras.capture.to_json(),
            })
        );
    } else {
        outln!(
            "wrote {} (aerial perspective, T = {:.2} ({}), {} diffusion steps in {} passes, {})",
            out.display(),
            m.table.turbidity(),
            look.turbidity_source,
            rendered.schedule.steps,
            rendered.pass_names().len(),
            t.describe(1)
        );
        super::capture::print_insert_and_capture(args, extras.inserted, extras.capture);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_horizon_row_gives_the_pitch_that_levels_its_ray() {
        let (h, fov) = (480, 50.0);
        for row in [0.0, 100.0, 239.5, 400.0, 479.0] {
            let pitch = pitch_for_horizon_row(row, h, fov);
            let camera = Camera {
                pitch_deg: pitch,
                fov_y_deg: fov,
                ..Camera::default()
            };
            // The ray through the row's centre (GL row h − 1 − row) is level.
            let ndc = 1.0 - 2.0 * (row + 0.5) / h as f64;
            let ray = camera.ray_at_ndc(0.0, ndc, 1.0);
            assert!(ray.y.abs() < 1e-12, "row {row}: {ray}");
        }
        assert_eq!(pitch_for_horizon_row(239.5, 480, 50.0), 0.0);
    }
}
