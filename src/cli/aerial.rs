//! `brume render --medium aerial`: paper 002's aerial perspective on a photo with depth,
//! from a turbidity given or estimated from a fisheye sky photo, and retargeting from the
//! turbidity a photo was taken at (sec. 7.2.3, eq. 25-26).

use super::args::{AerialBlur, RenderArgs, RetargetKind};
use super::photo_args::{blur_from_args, PrepReport, Scene};
use brume::atmosphere::Sensitivity;
use brume::blur::Blur;
use brume::camera::Camera;
use brume::io::output::Outputs;
use brume::medium::{AerialPerspective, Medium};
use brume::photo::{
    turbidity_from_sky, AerialOptions, AerialPhoto, CaptureOptions, HorizonFrom, Insertion,
    PhotoView, Retarget, DEFAULT_HORIZON_ZENITH_DEG, TURBIDITY_RANGE,
};
use brume::sky::horizon_sectors::{DEFAULT_SECTORS, MAX_SECTORS};
use brume::sky::sun_position::PlacedSun;
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

/// The camera whose rays give each pixel's zenith angle ([`PhotoView::camera`]): the
/// vertical field of view from `--fov`, else from the photo's focal length at its size
/// (the depth's intrinsics: a Cityscapes camera file; `--focal`; the photo's EXIF:
/// [`Scene::image_intrinsics`]); the pitch from `--pitch` or `--horizon-row`, else from
/// the camera file's mount (a vehicle's camera looks a little down), else level.
pub fn aerial_camera(args: &RenderArgs, scene: &Scene) -> Result<Camera> {
    let intrinsics = scene.image_intrinsics(args.depth.reading.focal, None);
    // The mount's pitch is down positive, the camera's up positive.
    let mounted = (scene.depth.mount)
        .filter(|_| args.horizon_row.is_none())
        .map(|m| -m.pitch.to_degrees());
    let view = PhotoView {
        fov_y_deg: args.depth.reading.fov,
        focal_px: intrinsics.map(|k| k.fy),
        pitch_deg: args.pitch.or(mounted),
        horizon_row: args.horizon_row,
    };
    view.camera(scene.image.height())
}

/// `--retarget`, the paper's normalised radiance by default.
fn retarget(args: &RenderArgs) -> Retarget {
    match args.retarget {
        Some(RetargetKind::Radiance) => Retarget::Radiance,
        Some(RetargetKind::Normalised) | None => Retarget::Normalised,
    }
}

/// Checks the aerial options' values before any file is read ([`AerialOptions::validate`],
/// whose field names [`super::name_flags`] turns into flags); the turbidity from `--sky`
/// and the camera are checked once the files are read.
pub fn check_aerial_options(args: &RenderArgs) -> Result<()> {
    if let (Some(r), None) = (args.retarget, args.from_turbidity) {
        return Err(Error::invalid(
            "--retarget",
            format!("{r:?}").to_lowercase(),
            "--from-turbidity T with it: only a photo taken at a known turbidity is \
             retargeted",
        ));
    }
    let turbidity = args.turbidity.unwrap_or(TURBIDITY_RANGE.0);
    let camera = Camera::default();
    aerial_options(
        args,
        turbidity,
        camera,
        Sensitivity::cie_srgb(),
        Blur::photo(),
    )?
    .validate()
}

/// The library's aerial options of `args`, with what the files give.
fn aerial_options(
    args: &RenderArgs,
    turbidity: f64,
    camera: Camera,
    sensitivity: Sensitivity,
    blur: Blur,
) -> Result<AerialOptions> {
    let horizon_sectors = match args.horizon_sectors {
        None => DEFAULT_SECTORS,
        Some(n) => usize::try_from(n).map_err(|_| {
            Error::invalid(
                "--horizon-sectors",
                n,
                format!("a number of azimuth sectors in [1, {MAX_SECTORS}]"),
            )
        })?,
    };
    Ok(AerialOptions {
        from_turbidity: args.from_turbidity,
        altitude_m: args.altitude.unwrap_or(0.0),
        metres_per_unit: args.metres_per_unit,
        sensitivity,
        lambda: match args.blur.unwrap_or(AerialBlur::Diffusion) {
            AerialBlur::None => 0.0,
            AerialBlur::Diffusion => args.lambda,
        },
        horizon_zenith_deg: args.horizon_zenith.unwrap_or(DEFAULT_HORIZON_ZENITH_DEG),
        horizon_light: args.airlight,
        blur,
        horizon_sectors,
        retarget: retarget(args),
        ..AerialOptions::new(turbidity, camera)
    })
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
/// ([`brume::photo::aerial`], which validates the options), the horizon's light from the
/// sky found (or `--airlight`). `args` have passed [`check_aerial_options`] (render and
/// view check every option before any file is read).
pub fn aerial_job(args: &RenderArgs, scene: &Scene, prep: &PrepReport) -> Result<AerialJob> {
    let sun = args.place.sun(None, args.altitude.unwrap_or(0.0))?;
    let (turbidity, turbidity_source) = turbidity(args, sun.as_ref())?;
    let sensitivity = match &args.sensitivity {
        Some(path) => Sensitivity::from_csv(path)?,
        None => Sensitivity::cie_srgb(),
    };
    let camera = aerial_camera(args, scene)?;
    let opts = AerialOptions {
        sun: sun.map(|s| [s.zenith, s.azimuth - s.heading]),
        ..aerial_options(args, turbidity, camera, sensitivity, blur_from_args(args))?
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
            sensitivity: photo.sensitivity.clone(),
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
    outputs.stage_photo(out, &rendered.image, &scene.metadata)?;
    super::commit(outputs)?;
    let m = &look.medium;
    let t = &rendered.times;
    if args.json {
        outln!(
            "{}",
            super::stamped(json!({
                "width": image.width(),
                "height": image.height(),
                "medium": "aerial",
                "turbidity": m.table.turbidity(),
                "turbidity_source": look.turbidity_source,
                "from_turbidity": look.from_turbidity,
                "retarget": look.from_turbidity.map(|_| look.retarget.name()),
                "sun": look.sun.as_ref().map(super::sun::placed_sun_json),
                "horizon_sectors": m.horizon_sectors.gains(),
                "altitude": m.table.altitude_m(),
                "metres_per_unit": m.metres_per_unit,
                "pitch": m.camera.pitch_deg,
                "camera_mount": scene.depth.mount,
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
            }))
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
