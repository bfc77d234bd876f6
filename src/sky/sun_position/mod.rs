//! The sun's position from time and place: NREL's Solar Position Algorithm (Reda &
//! Andreas 2004, "Solar position algorithm for solar radiation applications", Solar
//! Energy 76, 577-589), the full algorithm with its periodic-term tables, stated
//! uncertainty ±0.0003° for the years −2000 to 6000 (given ΔT). Paper 002 (sec. 3.4)
//! needs the sun's zenith and azimuth to fit the sky model.
//!
//! - [`parse_rfc3339`] reads a time such as `2003-10-17T12:30:30-07:00` into a
//!   [`UtcTime`] (hand-parsed: RFC 3339's grammar is a fixed layout, and a date crate
//!   would add a dependency for thirty lines).
//! - [`delta_t_estimate`] gives ΔT = TT − UT (seconds) by Espenak & Meeus' polynomials
//!   (NASA's eclipse site; the ones pvlib uses), within 2.5 s of the observed values
//!   for 2000-2024; an error of 10 s in ΔT moves the sun by about 0.0001°.
//! - [`sun_position`] returns the topocentric zenith angle without and with refraction
//!   and the azimuth clockwise from north (east = 90°).
//!
//! Angles here are in degrees, as the algorithm and the command line state them.

mod tables;

use crate::error::{Error, Result};
use tables::{B0, B1, L0, L1, L2, L3, L4, L5, NUTATION, R0, R1, R2, R3, R4};

/// Julian day of 2000-01-01 12:00 TT (J2000.0).
const J2000: f64 = 2_451_545.0;
/// Julian day of 1970-01-01 00:00 UTC.
const UNIX_EPOCH_JD: f64 = 2_440_587.5;
/// The years the algorithm is valid for (Reda & Andreas, sec. 1).
pub const VALID_YEARS: (i32, i32) = (-2000, 6000);
/// Standard pressure, hPa (mbar): refraction's default.
pub const DEFAULT_PRESSURE_HPA: f64 = 1013.25;
/// Refraction's default temperature, °C (pvlib's and NREL's examples use 12 or 11).
pub const DEFAULT_TEMPERATURE_C: f64 = 12.0;
/// The sun's apparent radius plus the refraction at the horizon (0.26667° + 0.5667°):
/// below that elevation no refraction is applied (the sun has set).
const SUNSET_ELEVATION_DEG: f64 = -(0.26667 + 0.5667);

/// An instant in Coordinated Universal Time, with its calendar date for reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UtcTime {
    /// Julian day (UT): days since −4712-01-01 12:00, Gregorian calendar.
    pub julian_day: f64,
    /// The UTC calendar year.
    pub year: i32,
    /// The UTC month, 1-12.
    pub month: u32,
}

impl UtcTime {
    /// The instant `year`-`month`-`day` `hour`:`minute`:`second` UTC (proleptic
    /// Gregorian calendar; `second` may reach 60.999 for a leap second).
    pub fn from_utc(
        year: i32,
        month: u32,
        day: u32,
        hour: u32,
        minute: u32,
        second: f64,
    ) -> Result<UtcTime> {
        let date = format!("{year:04}-{month:02}-{day:02}");
        if !(1..=12).contains(&month) || day < 1 || day > days_in_month(year, month) {
            return Err(Error::invalid("date", date, "a valid calendar date"));
        }
        if hour > 23 || minute > 59 || !(0.0..61.0).contains(&second) {
            return Err(Error::invalid(
                "time of day",
                format!("{hour:02}:{minute:02}:{second}"),
                "hh:mm:ss with hh ≤ 23, mm ≤ 59, ss < 61",
            ));
        }
        let days = days_from_civil(year, month, day) as f64;
        let seconds = f64::from(hour * 3600 + minute * 60) + second;
        Ok(UtcTime {
            julian_day: UNIX_EPOCH_JD + days + seconds / 86400.0,
            year,
            month,
        })
    }

    /// The year as a decimal, mid-month (what ΔT's polynomials take).
    pub fn decimal_year(&self) -> f64 {
        f64::from(self.year) + (f64::from(self.month) - 0.5) / 12.0
    }
}

fn is_leap(year: i32) -> bool {
    (year % 4 == 0 && year % 100 != 0) || year % 400 == 0
}

fn days_in_month(year: i32, month: u32) -> u32 {
    match month {
        2 if is_leap(year) => 29,
        2 => 28,
        4 | 6 | 9 | 11 => 30,
        _ => 31,
    }
}

/// Days from 1970-01-01 to the given proleptic Gregorian date (H. Hinnant's algorithm).
fn days_from_civil(year: i32, month: u32, day: u32) -> i64 {
    let y = i64::from(year) - i64::from(month <= 2);
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let m = i64::from(month);
    let doy = (153 * (if m > 2 { m - 3 } else { m + 9 }) + 2) / 5 + i64::from(day) - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// Reads an RFC 3339 date-time, `YYYY-MM-DDTHH:MM:SS[.frac](Z|±HH:MM)` (a space or `t`
/// may stand for `T`, `z` for `Z`), into UTC. The offset is required: a time without
/// one names no instant.
pub fn parse_rfc3339(text: &str) -> Result<UtcTime> {
    let bad = |why: &str| {
        Error::invalid(
            "time",
            text,
            format!(
                "an RFC 3339 time such as 2003-10-17T12:30:30-07:00 or \
                 2024-06-21T12:00:00Z ({why})"
            ),
        )
    };
    let b = text.as_bytes();
    if b.len() < 20 || !b.is_ascii() {
        return Err(bad("too short: date, time and UTC offset are all required"));
    }
    let num = |r: std::ops::Range<usize>| -> Result<u32> {
        let s = &text[r];
        if s.bytes().all(|c| c.is_ascii_digit()) {
            Ok(s.parse().expect("digits"))
        } else {
            Err(bad(&format!("{s:?} is not a number")))
        }
    };
    let sep = |i: usize, want: &[u8]| -> Result<()> {
        if want.contains(&b[i]) {
            Ok(())
        } else {
            Err(bad(&format!(
                "expected {:?} at position {}",
                want[0] as char,
                i + 1
            )))
        }
    };
    sep(4, b"-")?;
    sep(7, b"-")?;
    sep(10, b"Tt ")?;
    sep(13, b":")?;
    sep(16, b":")?;
    let (year, month, day) = (num(0..4)? as i32, num(5..7)?, num(8..10)?);
    let (hour, minute) = (num(11..13)?, num(14..16)?);
    let mut second = f64::from(num(17..19)?);
    let mut i = 19;
    if b[i] == b'.' {
        let start = i + 1;
        i = start;
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
        }
        if i == start {
            return Err(bad("a fraction of a second needs digits"));
        }
        second += format!("0.{}", &text[start..i])
            .parse::<f64>()
            .expect("digits");
    }
    let offset_min = match &b[i..] {
        [b'Z' | b'z'] => 0i64,
        [s @ (b'+' | b'-'), _, _, b':', _, _] => {
            let (h, m) = (num(i + 1..i + 3)?, num(i + 4..i + 6)?);
            if h > 23 || m > 59 {
                return Err(bad("the UTC offset is ±hh:mm with hh ≤ 23, mm ≤ 59"));
            }
            let v = i64::from(h * 60 + m);
            if *s == b'-' {
                -v
            } else {
                v
            }
        }
        _ => return Err(bad("it must end with Z or a UTC offset ±hh:mm")),
    };
    let local = UtcTime::from_utc(year, month, day, hour, minute, second)
        .map_err(|e| bad(&e.to_string()))?;
    let julian_day = local.julian_day - offset_min as f64 / 1440.0;
    // The UTC date's year and month (they differ from the local ones only around
    // midnight at a month's end, which moves ΔT by a millisecond at most).
    let days = (julian_day - UNIX_EPOCH_JD).floor() as i64;
    let (year, month) = civil_year_month(days);
    Ok(UtcTime {
        julian_day,
        year,
        month,
    })
}

/// The year and month of the day `days` after 1970-01-01 (H. Hinnant's algorithm).
fn civil_year_month(days: i64) -> (i32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    (year as i32, month as u32)
}

/// ΔT = TT − UT in seconds for a decimal year, by Espenak & Meeus' polynomials
/// (eclipse.gsfc.nasa.gov/SEcat5/deltatpoly.html) for 1900-2150 and their long-term
/// parabola −20 + 32·u², u = (year − 1820)/100, outside. Observed values: 63.8 s in
/// 2000, 69.4 s in 2020 (the polynomial: 63.9 and 71.6); past today it is an
/// extrapolation (93 s for 2050, 203 s for 2100). A ΔT off by a full minute moves the
/// sun by under 0.001° in zenith angle (tests/sun_position.rs).
pub fn delta_t_estimate(year: f64) -> f64 {
    let y = year;
    if (1900.0..1920.0).contains(&y) {
        let t = y - 1900.0;
        -2.79 + 1.494119 * t - 0.0598939 * t * t + 0.0061966 * t.powi(3) - 0.000197 * t.powi(4)
    } else if (1920.0..1941.0).contains(&y) {
        let t = y - 1920.0;
        21.20 + 0.84493 * t - 0.076100 * t * t + 0.0020936 * t.powi(3)
    } else if (1941.0..1961.0).contains(&y) {
        let t = y - 1950.0;
        29.07 + 0.407 * t - t * t / 233.0 + t.powi(3) / 2547.0
    } else if (1961.0..1986.0).contains(&y) {
        let t = y - 1975.0;
        45.45 + 1.067 * t - t * t / 260.0 - t.powi(3) / 718.0
    } else if (1986.0..2005.0).contains(&y) {
        let t = y - 2000.0;
        63.86 + 0.3345 * t - 0.060374 * t * t
            + 0.0017275 * t.powi(3)
            + 0.000651814 * t.powi(4)
            + 0.00002373599 * t.powi(5)
    } else if (2005.0..2050.0).contains(&y) {
        let t = y - 2000.0;
        62.92 + 0.32217 * t + 0.005589 * t * t
    } else if (2050.0..2150.0).contains(&y) {
        -20.0 + 32.0 * ((y - 1820.0) / 100.0).powi(2) - 0.5628 * (2150.0 - y)
    } else {
        -20.0 + 32.0 * ((y - 1820.0) / 100.0).powi(2)
    }
}

/// Where the sun is seen from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Observer {
    /// Geodetic latitude, degrees, north positive, in [−90, 90].
    pub latitude_deg: f64,
    /// Longitude, degrees, east positive, in [−180, 180].
    pub longitude_deg: f64,
    /// Height above sea level, metres.
    pub altitude_m: f64,
    /// Mean annual local pressure, hPa (mbar), for refraction.
    pub pressure_hpa: f64,
    /// Mean annual local temperature, °C, for refraction.
    pub temperature_c: f64,
}

impl Observer {
    /// An observer at `latitude_deg`, `longitude_deg` (degrees, north and east
    /// positive), sea level, standard pressure, 12 °C.
    pub fn new(latitude_deg: f64, longitude_deg: f64) -> Observer {
        Observer {
            latitude_deg,
            longitude_deg,
            altitude_m: 0.0,
            pressure_hpa: DEFAULT_PRESSURE_HPA,
            temperature_c: DEFAULT_TEMPERATURE_C,
        }
    }

    /// Checks the ranges, naming the field that is out of range.
    pub fn validate(&self) -> Result<()> {
        let checks = [
            (
                "latitude_deg",
                self.latitude_deg,
                (-90.0..=90.0).contains(&self.latitude_deg),
                "a latitude in [-90, 90] degrees, north positive",
            ),
            (
                "longitude_deg",
                self.longitude_deg,
                (-180.0..=180.0).contains(&self.longitude_deg),
                "a longitude in [-180, 180] degrees, east positive",
            ),
            (
                "altitude_m",
                self.altitude_m,
                (-500.0..=20_000.0).contains(&self.altitude_m),
                "an altitude above sea level in [-500, 20000] m",
            ),
            (
                "pressure_hpa",
                self.pressure_hpa,
                (0.0..=1200.0).contains(&self.pressure_hpa),
                "a pressure in [0, 1200] hPa",
            ),
            (
                "temperature_c",
                self.temperature_c,
                (-90.0..=60.0).contains(&self.temperature_c),
                "a temperature in [-90, 60] °C",
            ),
        ];
        for (name, value, ok, expected) in checks {
            if !ok {
                return Err(Error::invalid(name, value, expected));
            }
        }
        Ok(())
    }

    /// The sun this observer sees at `time` (RFC 3339, [`parse_rfc3339`]), with ΔT in
    /// seconds or, when `None`, [`delta_t_estimate`]'s for the year.
    pub fn sun_at(&self, time: &str, delta_t_s: Option<f64>) -> Result<SunPosition> {
        let utc = parse_rfc3339(time)?;
        let delta_t = delta_t_s.unwrap_or_else(|| delta_t_estimate(utc.decimal_year()));
        sun_position(&utc, self, delta_t)
    }
}

/// Where and when a photo or a fisheye sky was taken, and which way the camera looked:
/// what [`Place::sun`] needs to put the sun in the image.
#[derive(Clone, Debug, PartialEq)]
pub struct Place {
    /// Latitude, degrees, north positive.
    pub latitude_deg: f64,
    /// Longitude, degrees, east positive.
    pub longitude_deg: f64,
    /// The instant, RFC 3339 with its UTC offset ([`parse_rfc3339`]).
    pub time: String,
    /// The camera's heading, degrees clockwise from north: for a fisheye sky the compass
    /// direction at the top of the image, for a photo the direction of its centre.
    pub heading_deg: f64,
    /// The observer's height above sea level, metres.
    pub altitude_m: f64,
}

/// The sun found from a [`Place`], in the library's radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacedSun {
    /// The apparent (refracted) zenith angle: what a camera sees, radians.
    pub zenith: f64,
    /// Azimuth clockwise from north, radians.
    pub azimuth: f64,
    /// The camera's heading, radians clockwise from north.
    pub heading: f64,
    /// The heading as given, degrees.
    pub heading_deg: f64,
    /// The full result of the algorithm.
    pub position: SunPosition,
}

impl Place {
    /// The sun at this place and time (standard pressure and temperature for the
    /// refraction, ΔT estimated). Errors name the field: a place or time out of range, a
    /// heading that is not finite, a sun at or below the horizon (no daylight photo
    /// has it there).
    pub fn sun(&self) -> Result<PlacedSun> {
        if !self.heading_deg.is_finite() {
            return Err(Error::invalid(
                "heading_deg",
                self.heading_deg,
                "a compass heading in degrees, clockwise from north",
            ));
        }
        let observer = Observer {
            altitude_m: self.altitude_m,
            ..Observer::new(self.latitude_deg, self.longitude_deg)
        };
        let position = observer.sun_at(&self.time, None)?;
        if position.apparent_zenith_deg >= 90.0 {
            return Err(Error::invalid(
                "time",
                &self.time,
                format!(
                    "a time when the sun is up at {}°, {}° (its apparent zenith angle is \
                     then {:.2}°, at or below the horizon)",
                    self.latitude_deg, self.longitude_deg, position.apparent_zenith_deg
                ),
            ));
        }
        Ok(PlacedSun {
            zenith: position.apparent_zenith_deg.to_radians(),
            azimuth: position.azimuth_deg.to_radians(),
            heading: self.heading_deg.to_radians(),
            heading_deg: self.heading_deg,
            position,
        })
    }
}

/// The sun seen from an [`Observer`] at a [`UtcTime`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct SunPosition {
    /// Topocentric zenith angle without refraction (geometric), degrees.
    pub zenith_deg: f64,
    /// Topocentric zenith angle with the atmosphere's refraction, degrees.
    pub apparent_zenith_deg: f64,
    /// Topocentric azimuth, degrees clockwise from north (east 90°), in [0, 360).
    pub azimuth_deg: f64,
    /// Topocentric right ascension α′, degrees.
    pub right_ascension_deg: f64,
    /// Topocentric declination δ′, degrees.
    pub declination_deg: f64,
    /// Julian day (UT) of the instant.
    pub julian_day: f64,
    /// ΔT used, seconds.
    pub delta_t_s: f64,
}

/// Heliocentric longitude, latitude and radius of the earth, and the nutation: the
/// steps of the algorithm that depend only on the time (sec. 3.2-3.4).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Ecliptic {
    /// Earth heliocentric longitude L and latitude B, degrees; radius R, AU.
    l: f64,
    b: f64,
    r: f64,
    /// Nutation in longitude Δψ and obliquity Δε, degrees.
    delta_psi: f64,
    delta_eps: f64,
    /// True obliquity of the ecliptic ε, degrees.
    epsilon: f64,
}

/// Σ A·cos(B + C·x) over a table's rows.
fn periodic_sum(terms: &[[f64; 3]], x: f64) -> f64 {
    terms.iter().map(|[a, b, c]| a * (b + c * x).cos()).sum()
}

/// Σᵢ Sᵢ·xⁱ / 10⁸ for the tables S₀, S₁, ... (eq. 9-11).
fn series(tables: &[&[[f64; 3]]], jme: f64) -> f64 {
    tables
        .iter()
        .rev()
        .fold(0.0, |acc, t| acc * jme + periodic_sum(t, jme))
        / 1e8
}

fn ecliptic(jce: f64) -> Ecliptic {
    let jme = jce / 10.0;
    let l = series(&[&L0, &L1, &L2, &L3, &L4, &L5], jme)
        .to_degrees()
        .rem_euclid(360.0);
    let b = series(&[&B0, &B1], jme).to_degrees();
    let r = series(&[&R0, &R1, &R2, &R3, &R4], jme);
    let (delta_psi, delta_eps) = nutation(jce);
    let u = jme / 10.0;
    let eps0 = [
        84381.448, -4680.93, -1.55, 1999.25, -51.38, -249.67, -39.05, 7.12, 27.87, 5.79, 2.45,
    ]
    .iter()
    .rev()
    .fold(0.0, |acc, c| acc * u + c);
    Ecliptic {
        l,
        b,
        r,
        delta_psi,
        delta_eps,
        epsilon: eps0 / 3600.0 + delta_eps,
    }
}

/// Nutation in longitude and obliquity, degrees (sec. 3.4).
fn nutation(jce: f64) -> (f64, f64) {
    let cubic = |a: f64, b: f64, c: f64, d: f64| a + jce * (b + jce * (c + jce * d));
    let x = [
        cubic(297.85036, 445_267.111_48, -0.0019142, 1.0 / 189_474.0),
        cubic(357.52772, 35_999.050_34, -0.0001603, -1.0 / 300_000.0),
        cubic(134.96298, 477_198.867_398, 0.0086972, 1.0 / 56_250.0),
        cubic(93.27191, 483_202.017_538, -0.0036825, 1.0 / 327_270.0),
        cubic(125.04452, -1_934.136_261, 0.0020708, 1.0 / 450_000.0),
    ];
    let (mut psi, mut eps) = (0.0, 0.0);
    for (y, [a, b, c, d]) in NUTATION.iter() {
        let arg: f64 = y.iter().zip(&x).map(|(&yi, xi)| f64::from(yi) * xi).sum();
        let arg = arg.to_radians();
        psi += (a + b * jce) * arg.sin();
        eps += (c + d * jce) * arg.cos();
    }
    (psi / 36e6, eps / 36e6)
}

/// The sun's position seen by `observer` at `time`, with ΔT = `delta_t_s` seconds
/// (TT − UT; [`delta_t_estimate`] gives one). Errors: an observer out of range, a
/// year outside [`VALID_YEARS`], a non-finite ΔT.
pub fn sun_position(time: &UtcTime, observer: &Observer, delta_t_s: f64) -> Result<SunPosition> {
    observer.validate()?;
    let (lo, hi) = VALID_YEARS;
    if !(lo..=hi).contains(&time.year) {
        return Err(Error::invalid(
            "time",
            time.year,
            format!("a year in [{lo}, {hi}], where the algorithm holds"),
        ));
    }
    if !(delta_t_s.is_finite() && delta_t_s.abs() < 1e5) {
        return Err(Error::invalid(
            "delta_t_s",
            delta_t_s,
            "ΔT = TT − UT in seconds (about 64 to 200 for 2000-2100)",
        ));
    }
    Ok(position(time.julian_day, observer, delta_t_s))
}

/// The algorithm's steps 3.1-3.15 for a Julian day (UT).
fn position(jd: f64, obs: &Observer, delta_t_s: f64) -> SunPosition {
    let jde = jd + delta_t_s / 86400.0;
    let jc = (jd - J2000) / 36525.0;
    let jce = (jde - J2000) / 36525.0;
    let e = ecliptic(jce);
    // Geocentric longitude and latitude (3.3), aberration (3.6), apparent longitude (3.7).
    let theta = (e.l + 180.0).rem_euclid(360.0);
    let beta = -e.b;
    let aberration = -20.4898 / (3600.0 * e.r);
    let lambda = theta + e.delta_psi + aberration;
    // Apparent sidereal time at Greenwich (3.8).
    let nu0 = (280.460_618_37
        + 360.985_647_366_29 * (jd - J2000)
        + jc * jc * (0.000_387_933 - jc / 38_710_000.0))
        .rem_euclid(360.0);
    let nu = nu0 + e.delta_psi * e.epsilon.to_radians().cos();
    // Geocentric right ascension and declination (3.9, 3.10).
    let (lam, eps, bet) = (
        lambda.to_radians(),
        e.epsilon.to_radians(),
        beta.to_radians(),
    );
    let alpha = (lam.sin() * eps.cos() - bet.tan() * eps.sin())
        .atan2(lam.cos())
        .to_degrees()
        .rem_euclid(360.0);
    let delta = (bet.sin() * eps.cos() + bet.cos() * eps.sin() * lam.sin()).asin();
    // Observer local hour angle (3.11).
    let h = (nu + obs.longitude_deg - alpha)
        .rem_euclid(360.0)
        .to_radians();
    // Topocentric right ascension and declination (3.12).
    let xi = (8.794 / (3600.0 * e.r)).to_radians();
    let phi = obs.latitude_deg.to_radians();
    let u = (0.996_647_19 * phi.tan()).atan();
    let x = u.cos() + obs.altitude_m / 6_378_140.0 * phi.cos();
    let y = 0.996_647_19 * u.sin() + obs.altitude_m / 6_378_140.0 * phi.sin();
    let d_alpha = (-x * xi.sin() * h.sin()).atan2(delta.cos() - x * xi.sin() * h.cos());
    let delta_p =
        ((delta.sin() - y * xi.sin()) * d_alpha.cos()).atan2(delta.cos() - x * xi.sin() * h.cos());
    let h_p = h - d_alpha;
    // Topocentric zenith angle (3.14) and azimuth (3.15).
    let e0 = (phi.sin() * delta_p.sin() + phi.cos() * delta_p.cos() * h_p.cos())
        .asin()
        .to_degrees();
    let refraction = if e0 >= SUNSET_ELEVATION_DEG {
        obs.pressure_hpa / 1010.0 * 283.0 / (273.0 + obs.temperature_c) * 1.02
            / (60.0 * (e0 + 10.3 / (e0 + 5.11)).to_radians().tan())
    } else {
        0.0
    };
    let astronomers = h_p
        .sin()
        .atan2(h_p.cos() * phi.sin() - delta_p.tan() * phi.cos())
        .to_degrees();
    SunPosition {
        zenith_deg: 90.0 - e0,
        apparent_zenith_deg: 90.0 - (e0 + refraction),
        azimuth_deg: (astronomers + 180.0).rem_euclid(360.0),
        right_ascension_deg: (alpha + d_alpha.to_degrees()).rem_euclid(360.0),
        declination_deg: delta_p.to_degrees(),
        julian_day: jd,
        delta_t_s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reda & Andreas' worked example (sec. 4 and Table A5.1): 2003-10-17 12:30:30
    /// local time, UTC−7, Golden, Colorado.
    fn example() -> (UtcTime, Observer) {
        let time = parse_rfc3339("2003-10-17T12:30:30-07:00").unwrap();
        let obs = Observer {
            latitude_deg: 39.742476,
            longitude_deg: -105.1786,
            altitude_m: 1830.14,
            pressure_hpa: 820.0,
            temperature_c: 11.0,
        };
        (time, obs)
    }

    #[test]
    fn the_papers_intermediate_values_are_reproduced() {
        let (time, _) = example();
        assert!((time.julian_day - 2_452_930.312_847).abs() < 1e-6);
        let jce = (time.julian_day + 67.0 / 86400.0 - J2000) / 36525.0;
        let e = ecliptic(jce);
        assert!((e.l - 24.018_261_7).abs() < 1e-6, "L {}", e.l);
        assert!((e.b - -0.000_101_1).abs() < 1e-6, "B {}", e.b);
        assert!((e.r - 0.996_542_297_4).abs() < 1e-9, "R {}", e.r);
        assert!(
            (e.delta_psi - -0.003_998_40).abs() < 1e-7,
            "Δψ {}",
            e.delta_psi
        );
        assert!(
            (e.delta_eps - 0.001_666_57).abs() < 1e-7,
            "Δε {}",
            e.delta_eps
        );
        assert!((e.epsilon - 23.440_465).abs() < 1e-6, "ε {}", e.epsilon);
    }

    #[test]
    fn dates_and_offsets_parse_to_julian_days() {
        let t = parse_rfc3339("2000-01-01T12:00:00Z").unwrap();
        assert_eq!(t.julian_day, J2000);
        let a = parse_rfc3339("2024-03-01T00:30:00.5+01:00").unwrap();
        assert_eq!((a.year, a.month), (2024, 2));
        let b = UtcTime::from_utc(2024, 2, 29, 23, 30, 0.5).unwrap();
        assert!((a.julian_day - b.julian_day).abs() < 1e-9);
        for bad in [
            "2024-02-30T00:00:00Z",
            "2024-01-01T00:00:00",
            "2024-01-01 24:00:00Z",
            "2024-01-01T00:00:00+1:00",
            "24-01-01T00:00:00Z",
            "2024-01-01T00:00:00.Z",
        ] {
            let e = parse_rfc3339(bad).unwrap_err().to_string();
            assert!(e.contains("time") && e.contains("RFC 3339"), "{bad}: {e}");
        }
    }

    #[test]
    fn delta_t_follows_the_observed_values() {
        // Observed ΔT (IERS): 63.83 s at 2000.0, 64.69 at 2005.0, 69.36 at 2020.0.
        assert!((delta_t_estimate(2000.0) - 63.83).abs() < 0.1);
        assert!((delta_t_estimate(2005.0) - 64.69).abs() < 0.5);
        // The 2005-2050 polynomial (2004) overestimates today's ΔT: 71.6 s for 69.4.
        assert!((delta_t_estimate(2020.0) - 69.36).abs() < 2.5);
        // Continuous at the pieces' joins, to a second or so.
        for y in [2005.0, 2050.0, 2150.0] {
            assert!((delta_t_estimate(y - 1e-9) - delta_t_estimate(y)).abs() < 2.0);
        }
    }
}
