//! `brume sun` (the sun's position from time and place, NREL's SPA) and the
//! `--latitude/--longitude/--time/--heading` options that `sky`, `turbidity` and
//! `render --medium aerial` take instead of sun angles.

use brume::sky::sun_position::{
    Observer, Place, PlacedSun, DEFAULT_PRESSURE_HPA, DEFAULT_TEMPERATURE_C,
};
use brume::{Error, Result};
use clap::Args;
use serde_json::json;

/// `brume sun`.
#[derive(Args, Debug)]
pub struct SunArgs {
    /// Latitude in degrees, north positive, in [-90, 90].
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub latitude: f64,

    /// Longitude in degrees, east positive, in [-180, 180].
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub longitude: f64,

    /// The instant, RFC 3339 with its UTC offset: 2003-10-17T12:30:30-07:00 or
    /// 2024-06-21T10:00:00Z.
    #[arg(long, value_name = "RFC3339", allow_hyphen_values = true)]
    pub time: String,

    /// The observer's height above sea level, metres (parallax; negligible below
    /// mountains).
    #[arg(
        long,
        value_name = "M",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub altitude: f64,

    /// Mean local pressure, hPa, for the refraction of `apparent_zenith_deg`.
    #[arg(long, value_name = "HPA", default_value_t = DEFAULT_PRESSURE_HPA, allow_hyphen_values = true)]
    pub pressure: f64,

    /// Mean local temperature, °C, for the refraction.
    #[arg(long, value_name = "C", default_value_t = DEFAULT_TEMPERATURE_C, allow_hyphen_values = true)]
    pub temperature: f64,

    /// ΔT = TT − UT in seconds [default: Espenak & Meeus' estimate for the year, 64 s in
    /// 2000, 69 s in 2020].
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub delta_t: Option<f64>,

    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Runs `brume sun`.
pub fn run_sun(args: &SunArgs) -> Result<()> {
    let observer = Observer {
        latitude_deg: args.latitude,
        longitude_deg: args.longitude,
        altitude_m: args.altitude,
        pressure_hpa: args.pressure,
        temperature_c: args.temperature,
    };
    let sun = observer.sun_at(&args.time, args.delta_t)?;
    if args.json {
        outln!(
            "{}",
            super::stamped(json!({
                "time": args.time,
                "julian_day": sun.julian_day,
                "delta_t_s": sun.delta_t_s,
                "latitude_deg": args.latitude,
                "longitude_deg": args.longitude,
                "altitude_m": args.altitude,
                "zenith_deg": sun.zenith_deg,
                "apparent_zenith_deg": sun.apparent_zenith_deg,
                "azimuth_deg": sun.azimuth_deg,
                "right_ascension_deg": sun.right_ascension_deg,
                "declination_deg": sun.declination_deg,
            }))
        );
    } else {
        outln!(
            "sun at {}: zenith {:.5}° (apparent {:.5}°, refraction at {} hPa, {} °C), \
             azimuth {:.5}° from north (ΔT {:.1} s)",
            args.time,
            sun.zenith_deg,
            sun.apparent_zenith_deg,
            args.pressure,
            args.temperature,
            sun.azimuth_deg,
            sun.delta_t_s
        );
    }
    Ok(())
}

/// `--latitude/--longitude/--time/--heading`, flattened into the commands that take a
/// sun.
#[derive(Args, Debug, Clone, Default)]
pub struct PlaceTimeArgs {
    /// Where the photo or sky was taken: latitude in degrees, north positive (with
    /// --longitude and --time, instead of sun angles: the sun from NREL's SPA).
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub latitude: Option<f64>,

    /// Longitude in degrees, east positive (with --latitude and --time).
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub longitude: Option<f64>,

    /// When, RFC 3339 with its UTC offset, e.g. 2024-06-21T10:00:00+02:00 (with
    /// --latitude and --longitude).
    #[arg(long, value_name = "RFC3339", allow_hyphen_values = true)]
    pub time: Option<String>,

    /// The camera's heading, degrees clockwise from north: for a fisheye sky, the
    /// compass direction at the top of the image; for a photo, the direction of the
    /// image centre. Relates the sun's azimuth to the image [default: 0, north].
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub heading: Option<f64>,
}

/// The report's fields of a sun placed from `--latitude/--longitude/--time/--heading`.
pub fn placed_sun_json(sun: &PlacedSun) -> serde_json::Value {
    json!({
        "zenith_deg": sun.position.zenith_deg,
        "apparent_zenith_deg": sun.position.apparent_zenith_deg,
        "azimuth_deg": sun.position.azimuth_deg,
        "heading_deg": sun.heading_deg,
        "delta_t_s": sun.position.delta_t_s,
    })
}

impl PlaceTimeArgs {
    /// Whether any of the four was given.
    pub fn any(&self) -> bool {
        self.latitude.is_some()
            || self.longitude.is_some()
            || self.time.is_some()
            || self.heading.is_some()
    }

    /// The sun from the place and time, `None` when none of them was given; an error
    /// when only part of them was, or when `angles` (the sun-angle flags' names, given)
    /// were given too. `altitude_m` is the observer's height.
    pub fn sun(&self, angles: Option<&str>, altitude_m: f64) -> Result<Option<PlacedSun>> {
        if !self.any() {
            return Ok(None);
        }
        if let Some(flags) = angles {
            return Err(Error::invalid(
                flags,
                "given with --latitude/--longitude/--time",
                "either the sun's angles or the place and time, not both",
            ));
        }
        let (latitude, longitude, time) = match (self.latitude, self.longitude, &self.time) {
            (Some(la), Some(lo), Some(t)) => (la, lo, t),
            _ => {
                let missing: Vec<&str> = [
                    ("--latitude", self.latitude.is_none()),
                    ("--longitude", self.longitude.is_none()),
                    ("--time", self.time.is_none()),
                ]
                .iter()
                .filter(|(_, m)| *m)
                .map(|(f, _)| *f)
                .collect();
                return Err(Error::invalid(
                    missing.join(", "),
                    "(missing)",
                    "--latitude, --longitude and --time together to place the sun (--heading \
                     needs them too)",
                ));
            }
        };
        let place = Place {
            latitude_deg: latitude,
            longitude_deg: longitude,
            time: time.clone(),
            heading_deg: self.heading.unwrap_or(0.0),
            altitude_m,
        };
        place.sun().map(Some)
    }
}
