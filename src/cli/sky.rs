//! `brume sky` (a Preetham sky through a fisheye, to a file) and `brume turbidity` (the
//! turbidity of a fisheye sky image, paper 002 sec. 3.4). CPU only: no GL context.

use super::limits::{self, MAX_ESTIMATIONS, MAX_SAMPLES};
use super::sun::PlaceTimeArgs;
use brume::io::output::{self, Outputs};
use brume::photo::SkyTurbidity;
use brume::sky::clouds::CloudOptions;
use brume::sky::sun_position::PlacedSun;
use brume::sky::turbidity::{self, SunSource, TurbidityEstimate};
use brume::sky::{render_sky_photo, Fisheye, Lens, SkyExposure, SkyPhotoOptions, TurbidityOptions};
use brume::{Error, Result};
use clap::Args;
use serde_json::json;
use std::path::{Path, PathBuf};

/// The fisheye convention, shared by `brume sky` and `brume turbidity`.
#[derive(Args, Debug, Clone)]
pub struct FisheyeArgs {
    /// Fisheye lens mapping: equidistant (radius ∝ zenith angle), equisolid, orthographic
    /// or stereographic. The zenith is at the image centre, the horizon on the inscribed
    /// circle.
    #[arg(
        long,
        value_name = "LENS",
        default_value = "equidistant",
        allow_hyphen_values = true
    )]
    pub lens: Lens,

    /// Azimuth increases counter-clockwise in the image (default: clockwise, as on a
    /// map seen from above; a camera looking up sees the sky mirrored).
    #[arg(long)]
    pub counter_clockwise: bool,

    /// Azimuth at the top of the image, degrees.
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub azimuth_offset: f64,
}

impl FisheyeArgs {
    fn fisheye(&self) -> Result<Fisheye> {
        if !self.azimuth_offset.is_finite() {
            return Err(Error::invalid(
                "--azimuth-offset",
                self.azimuth_offset,
                "a finite angle in degrees",
            ));
        }
        Ok(Fisheye {
            lens: self.lens,
            counter_clockwise: self.counter_clockwise,
            azimuth_offset: self.azimuth_offset.to_radians(),
        })
    }
}

/// `brume sky`.
#[derive(Args, Debug)]
pub struct SkyArgs {
    /// Turbidity T in [1, 20] (1 pure air, 2 very clear, 3 clear, 6 hazy, 10+ very hazy).
    #[arg(long, value_name = "T", allow_hyphen_values = true)]
    pub turbidity: f64,

    /// Sun zenith angle θs in degrees, in [0, 90) (or --latitude/--longitude/--time).
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub sun_zenith: Option<f64>,

    /// Sun azimuth φs in degrees, in the fisheye's convention (0 at the top of the image,
    /// clockwise by default).
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub sun_azimuth: Option<f64>,

    #[command(flatten)]
    pub place: PlaceTimeArgs,

    /// Image side in pixels (the image is square, the sky on its inscribed circle).
    #[arg(
        long,
        value_name = "PX",
        default_value_t = 500,
        allow_hyphen_values = true
    )]
    pub size: i64,

    /// Output: .exr or .pfm (linear sRGB in kcd/m², the model's units: a pixel's Rec. 709
    /// luminance is the model's Y) or .png (8-bit sRGB, exposed so that the brightest channel of
    /// the sky more than 2° from the sun is 0.9: only the sun and its glow clip).
    #[arg(long, short, value_name = "PATH")]
    pub out: PathBuf,

    /// Also draw the sun as a white disc of this angular radius in degrees (0.27 is the
    /// real sun), at 1.6·10⁶ kcd/m²: it saturates any exposure, as in a photograph.
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub sun_disc: Option<f64>,

    /// Also cover this fraction of the sky with synthetic clouds (grey blobs 1.5 to 2.5
    /// times as bright as the sky), in [0, 0.9].
    #[arg(long, value_name = "FRACTION", allow_hyphen_values = true)]
    pub clouds: Option<f64>,

    /// Seed of the clouds, a whole number ≥ 0.
    #[arg(
        long,
        value_name = "N",
        default_value_t = 0,
        allow_hyphen_values = true
    )]
    pub cloud_seed: i128,

    #[command(flatten)]
    pub fisheye: FisheyeArgs,

    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// `brume turbidity`.
#[derive(Args, Debug)]
pub struct TurbidityArgs {
    /// Fisheye sky image: square, zenith at the centre, horizon on the inscribed circle.
    /// PNG/JPEG are read as sRGB, EXR/PFM as linear.
    #[arg(value_name = "PATH")]
    pub image: PathBuf,

    /// Sun zenith angle θs in degrees, in [0, 90). Without --sun-zenith and
    /// --sun-azimuth the sun is found as the centre of the saturated area.
    #[arg(
        long,
        value_name = "DEG",
        requires = "sun_azimuth",
        allow_hyphen_values = true
    )]
    pub sun_zenith: Option<f64>,

    /// Sun azimuth φs in degrees, in the fisheye's convention.
    #[arg(
        long,
        value_name = "DEG",
        requires = "sun_zenith",
        allow_hyphen_values = true
    )]
    pub sun_azimuth: Option<f64>,

    /// Reference point's zenith angle in degrees [default: 0, the zenith].
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub reference_zenith: Option<f64>,

    /// Reference point's azimuth in degrees [default: 0].
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub reference_azimuth: Option<f64>,

    /// Random sample points N per estimation.
    #[arg(long, value_name = "N", default_value_t = turbidity::DEFAULT_SAMPLES as i64, allow_hyphen_values = true)]
    pub samples: i64,

    /// Repeated estimations (each with its own N points): T is their mean, std their
    /// standard deviation (with 1, the fit's standard error).
    #[arg(long, value_name = "K", default_value_t = turbidity::DEFAULT_REPEATS as i64, allow_hyphen_values = true)]
    pub repeats: i64,

    /// Seed of the sampling, a whole number ≥ 0; a seed always gives the same result.
    #[arg(
        long,
        value_name = "N",
        default_value_t = 0,
        allow_hyphen_values = true
    )]
    pub seed: i128,

    /// No samples within this many degrees of the horizon.
    #[arg(long, value_name = "DEG", default_value_t = turbidity::DEFAULT_HORIZON_MARGIN_DEG, allow_hyphen_values = true)]
    pub horizon_margin: f64,

    /// No samples within this many degrees of the sun.
    #[arg(long, value_name = "DEG", default_value_t = turbidity::DEFAULT_SUN_EXCLUSION_DEG, allow_hyphen_values = true)]
    pub sun_exclusion: f64,

    /// RANSAC inlier threshold: largest relative difference between a sample's ratio
    /// and the model's, in (0, 1).
    #[arg(long, value_name = "F", default_value_t = turbidity::DEFAULT_THRESHOLD, allow_hyphen_values = true)]
    pub threshold: f64,

    /// Fit the level of the model's ratios with T (variable projection) instead of
    /// trusting the reference pixels exactly (eq. 8): robust to noise, 8-bit
    /// quantisation or thin cloud at the reference.
    #[arg(long)]
    pub fit_level: bool,

    #[command(flatten)]
    pub fisheye: FisheyeArgs,

    #[command(flatten)]
    pub place: PlaceTimeArgs,

    /// Print one JSON object on stdout (turbidity, std, fit_std, inliers, sun, ...).
    #[arg(long)]
    pub json: bool,
}

/// The fisheye and the sun's angles (degrees, the fisheye's convention): the angles
/// given, or the sun from --latitude/--longitude/--time, its compass azimuth taken in a
/// fisheye whose top points to --heading (north by default). Errors: both or part of
/// them given, --heading with --azimuth-offset.
fn fisheye_and_sun(
    fisheye: &FisheyeArgs,
    place: &PlaceTimeArgs,
    zenith: Option<f64>,
    azimuth: Option<f64>,
) -> Result<(Fisheye, [Option<f64>; 2], Option<PlacedSun>)> {
    let angles = match (zenith, azimuth) {
        (None, None) => None,
        (Some(_), None) => Some("--sun-zenith"),
        _ => Some("--sun-azimuth"),
    };
    let mut fish = fisheye.fisheye()?;
    let Some(placed) = place.sun(angles, 0.0)? else {
        return Ok((fish, [zenith, azimuth], None));
    };
    if fisheye.azimuth_offset != 0.0 && place.heading.is_some() {
        return Err(Error::invalid(
            "--heading",
            place.heading.unwrap_or_default(),
            "one of --heading (the compass direction at the image's top) or --azimuth-offset",
        ));
    }
    if place.heading.is_some() {
        fish.azimuth_offset = placed.heading;
    }
    let sun = [
        Some(placed.position.apparent_zenith_deg),
        Some(placed.position.azimuth_deg),
    ];
    Ok((fish, sun, Some(placed)))
}

/// A seed given on the command line.
fn seed(option: &str, value: i128) -> Result<u64> {
    u64::try_from(value)
        .map_err(|_| Error::invalid(option, value, "a whole number from 0 to 2^64 - 1"))
}

/// Runs `brume sky`.
pub fn run_sky(args: &SkyArgs) -> Result<()> {
    let (fisheye, [sun_zenith_deg, sun_azimuth_deg], placed) = fisheye_and_sun(
        &args.fisheye,
        &args.place,
        args.sun_zenith,
        args.sun_azimuth,
    )?;
    let [sun_zenith_deg, sun_azimuth_deg] = match (sun_zenith_deg, sun_azimuth_deg) {
        (Some(z), Some(a)) => [z, a],
        (z, _) => {
            return Err(Error::invalid(
                if z.is_none() {
                    "--sun-zenith"
                } else {
                    "--sun-azimuth"
                },
                "(missing)",
                "the sun's --sun-zenith and --sun-azimuth in degrees, or \
                 --latitude/--longitude/--time",
            ))
        }
    };
    let size = usize::try_from(args.size)
        .map_err(|_| Error::invalid("--size", args.size, "a side in px ≥ 1"))?;
    let cloud_seed = seed("--cloud-seed", args.cloud_seed)?;
    if args.clouds.is_none() && cloud_seed != 0 {
        return Err(Error::invalid(
            "--cloud-seed",
            cloud_seed,
            "--clouds FRACTION with it (without clouds there is nothing to seed)",
        ));
    }
    output::check_image_output(&args.out, "--out")?;
    let png = args
        .out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    let opts = SkyPhotoOptions {
        turbidity: args.turbidity,
        sun_zenith: sun_zenith_deg.to_radians(),
        sun_azimuth: sun_azimuth_deg.to_radians(),
        size,
        fisheye,
        sun_disc: args.sun_disc.map(f64::to_radians),
        clouds: args.clouds.map(|coverage| CloudOptions {
            coverage,
            seed: cloud_seed,
            ..CloudOptions::default()
        }),
        exposure: if png {
            SkyExposure::Display
        } else {
            SkyExposure::Physical
        },
    };
    let photo = render_sky_photo(&opts)?;
    let mut outputs = Outputs::new();
    outputs.stage_rgba(&args.out, &photo.image)?;
    super::commit(outputs)?;

    let [xz, yz] = photo.zenith_chromaticity;
    let exposure = photo.exposure;
    if args.json {
        let report = json!({
            "out": args.out.display().to_string(),
            "size": size,
            "turbidity": args.turbidity,
            "sun_zenith_deg": sun_zenith_deg,
            "sun_azimuth_deg": sun_azimuth_deg,
            "sun_from_place": placed.as_ref().map(super::sun::placed_sun_json),
            "fisheye": {
                "lens": fisheye.lens.name(),
                "counter_clockwise": fisheye.counter_clockwise,
                "azimuth_offset_deg": fisheye.azimuth_offset.to_degrees(),
            },
            "zenith_luminance_kcd_m2": photo.zenith_luminance,
            "zenith_chromaticity": [xz, yz],
            "units": if png { "sRGB 8-bit, scaled by exposure" } else { "linear sRGB, kcd/m2" },
            "exposure": exposure,
            "sun_disc_pixels": photo.sun_disc_pixels,
            "clouds": photo.clouds,
        });
        outln!("{}", super::stamped(report));
    } else {
        outln!(
            "{}: {size}x{size} {} fisheye, T = {}, sun at θs = {}°, φs = {}°; zenith {:.4} \
             kcd/m², x = {xz:.4}, y = {yz:.4}{}",
            args.out.display(),
            fisheye.lens.name(),
            args.turbidity,
            sun_zenith_deg,
            sun_azimuth_deg,
            photo.zenith_luminance,
            match exposure {
                Some(e) => format!("; PNG exposure ×{e:.4} (brightest sky 2° from the sun → 0.9)"),
                None if png => String::new(),
                None => "; values in kcd/m²".into(),
            }
        );
    }
    Ok(())
}

/// Runs `brume turbidity`.
pub fn run_turbidity(args: &TurbidityArgs) -> Result<()> {
    let sky = brume::photo::estimate_sky_photo(&args.image, &turbidity_options(args)?)?;
    if args.json {
        outln!("{}", super::stamped(report_json(&sky, &args.image)));
    } else {
        print_report(&sky.estimate, &args.image);
        if let Some(c) = sky.circle {
            let [w, h] = sky.size;
            outln!(
                "  the image circle of the {w}x{h} frame: {} px wide at ({}, {})",
                c.side,
                c.x,
                c.y
            );
        }
        if let Some(name) = &sky.colour_profile {
            let [r, g, b] = sky.luminance;
            let weights = format!("Y = {r:.4} R + {g:.4} G + {b:.4} B");
            outln!("  luminance in its profile's primaries ({name}): {weights}");
        }
    }
    Ok(())
}

fn turbidity_options(args: &TurbidityArgs) -> Result<TurbidityOptions> {
    let deg = |v: Option<f64>| v.map(f64::to_radians);
    let (fisheye, [zenith, azimuth], _) = fisheye_and_sun(
        &args.fisheye,
        &args.place,
        args.sun_zenith,
        args.sun_azimuth,
    )?;
    let sun = match (deg(zenith), deg(azimuth)) {
        (Some(z), Some(a)) => Some([z, a]),
        _ => None,
    };
    let reference = match (deg(args.reference_zenith), deg(args.reference_azimuth)) {
        (None, None) => None,
        (z, a) => Some([z.unwrap_or(0.0), a.unwrap_or(0.0)]),
    };
    let opts = TurbidityOptions {
        fisheye,
        sun,
        reference,
        samples: limits::count("--samples", args.samples, 5, MAX_SAMPLES, "sample points")?,
        repeats: limits::count("--repeats", args.repeats, 1, MAX_ESTIMATIONS, "estimations")?,
        seed: seed("--seed", args.seed)?,
        horizon_margin: args.horizon_margin.to_radians(),
        sun_exclusion: args.sun_exclusion.to_radians(),
        threshold: args.threshold,
        fit_level: args.fit_level,
        ..TurbidityOptions::default()
    };
    limits::check_sample_points("--repeats/--samples", opts.repeats, opts.samples, 1)?;
    opts.validate()?;
    Ok(opts)
}

fn report_json(sky: &SkyTurbidity, path: &Path) -> serde_json::Value {
    let e = &sky.estimate;
    let blob = match e.sun_source {
        SunSource::Given => None,
        SunSource::Detected { pixels } => Some(pixels),
    };
    json!({
        "image": path.display().to_string(),
        "width": sky.size[0],
        "height": sky.size[1],
        "turbidity": e.turbidity,
        "std": e.std,
        "std_of": if e.repeats > 1 { "repeats" } else { "fit" },
        "fit_std": e.fit_std,
        "repeats": e.repeats,
        "samples": e.samples,
        "inliers": e.inliers,
        "level": e.level,
        "sun_zenith_deg": e.sun_zenith.to_degrees(),
        "sun_azimuth_deg": e.sun_azimuth.to_degrees(),
        "sun_source": e.sun_source.name(),
        "sun_pixels": blob,
        "reference_zenith_deg": e.reference[0].to_degrees(),
        "reference_azimuth_deg": e.reference[1].to_degrees(),
        "reference_fallbacks": e.reference_fallbacks,
        "usable_pixels": e.usable_pixels,
        "ms_per_estimation": e.ms_per_estimation,
        "prepare_ms": e.prepare_ms,
        "estimates": e.estimates.iter().map(|s| s.turbidity).collect::<Vec<_>>(),
        "colour_profile": sky.colour_profile,
        "luminance_weights": sky.luminance,
        "linear_light": sky.linear_light,
        "image_circle": sky.circle,
    })
}

fn print_report(e: &TurbidityEstimate, path: &Path) {
    outln!(
        "{}: turbidity T = {:.4} ± {:.4} ({} of {} estimations of N = {} points; fit std {:.4})",
        path.display(),
        e.turbidity,
        e.std,
        if e.repeats > 1 { "std" } else { "fit std" },
        e.repeats,
        e.samples,
        e.fit_std,
    );
    let source = match e.sun_source {
        SunSource::Given => "given".to_string(),
        SunSource::Detected { pixels } => format!("found from {pixels} saturated pixels"),
    };
    outln!(
        "  sun θs = {:.2}°, φs = {:.2}° ({source}); {:.1} inliers of {} on average; {} \
         usable pixels; reference replaced in {} estimations; {:.2} ms per estimation",
        e.sun_zenith.to_degrees(),
        e.sun_azimuth.to_degrees(),
        e.inliers,
        e.samples,
        e.usable_pixels,
        e.reference_fallbacks,
        e.ms_per_estimation,
    );
}
