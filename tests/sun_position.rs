//! NREL's Solar Position Algorithm (src/sky/sun_position) against an independent
//! implementation, pvlib's (tests/data/sun/pvlib_spa.csv, written by
//! tools/sun_reference.py), against Reda & Andreas' worked example, and through
//! `brume sun`.

use brume::sky::sun_position::{
    delta_t_estimate, parse_rfc3339, sun_position, Observer, Place, SunPosition,
};
use serde_json::Value;
use std::process::Command;

/// The accuracy asked for 2000-2100, degrees.
const TOLERANCE_DEG: f64 = 0.01;

struct Row {
    time: String,
    observer: Observer,
    delta_t: f64,
    zenith: f64,
    apparent: f64,
    azimuth: f64,
}

fn reference() -> Vec<Row> {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/sun/pvlib_spa.csv"
    ))
    .expect("tests/data/sun/pvlib_spa.csv");
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let n = |i: usize| f[i].parse::<f64>().expect(l);
            Row {
                time: f[0].to_string(),
                observer: Observer {
                    latitude_deg: n(1),
                    longitude_deg: n(2),
                    altitude_m: n(3),
                    pressure_hpa: n(4),
                    temperature_c: n(5),
                },
                delta_t: n(6),
                zenith: n(7),
                apparent: n(8),
                azimuth: n(9),
            }
        })
        .collect()
}

/// Angular difference of azimuths, degrees, in [0, 180].
fn azimuth_diff(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(360.0);
    d.min(360.0 - d)
}

/// The largest (zenith, apparent zenith, azimuth) errors against pvlib, ΔT from
/// `delta_t` for each row. The azimuth is compared where the sun is more than 0.01°
/// from the zenith (it is undefined there).
fn max_errors(delta_t: impl Fn(&Row) -> f64) -> [f64; 3] {
    let rows = reference();
    assert!(rows.len() >= 300, "{} rows", rows.len());
    let mut worst = [0f64; 3];
    for r in &rows {
        let t = parse_rfc3339(&r.time).unwrap();
        let s: SunPosition = sun_position(&t, &r.observer, delta_t(r)).unwrap();
        worst[0] = worst[0].max((s.zenith_deg - r.zenith).abs());
        worst[1] = worst[1].max((s.apparent_zenith_deg - r.apparent).abs());
        if r.zenith > 0.01 {
            worst[2] = worst[2].max(azimuth_diff(s.azimuth_deg, r.azimuth));
        }
    }
    worst
}

#[test]
fn sun_positions_match_pvlib_over_2000_to_2100() {
    let worst = max_errors(|r| r.delta_t);
    eprintln!(
        "max |error| vs pvlib, same ΔT: zenith {:.2e}°, apparent {:.2e}°, azimuth {:.2e}°",
        worst[0], worst[1], worst[2]
    );
    // Same algorithm, same tables: agreement to rounding, far inside 0.01°.
    for w in worst {
        assert!(w < 1e-6, "{worst:?}");
    }
}

#[test]
fn the_default_delta_t_matches_pvlibs_and_keeps_the_accuracy() {
    let rows = reference();
    let worst_dt = rows
        .iter()
        .map(|r| {
            let t = parse_rfc3339(&r.time).unwrap();
            (delta_t_estimate(t.decimal_year()) - r.delta_t).abs()
        })
        .fold(0.0, f64::max);
    assert!(worst_dt < 1e-6, "ΔT differs from pvlib's by {worst_dt} s");
    let worst = max_errors(|r| delta_t_estimate(parse_rfc3339(&r.time).unwrap().decimal_year()));
    for w in worst {
        assert!(w < TOLERANCE_DEG, "{worst:?}");
    }
    // ΔT off by a full minute still keeps 0.01° (the sun moves ~0.04″ per second of ΔT).
    let worst = max_errors(|r| r.delta_t + 60.0);
    eprintln!("ΔT + 60 s: {worst:?}");
    for w in worst {
        assert!(w < TOLERANCE_DEG, "{worst:?}");
    }
}

/// `Place::sun`, what `--latitude/--longitude/--time/--heading` use, against pvlib: the
/// geometric zenith and the azimuth (which the refraction of pvlib's random pressures does
/// not change) within 0.01° with ΔT estimated, the heading in radians as given, and a sun
/// clearly below the horizon refused, naming the time.
#[test]
fn a_place_and_time_put_the_sun_where_pvlib_does() {
    let (mut placed, mut refused) = (0, 0);
    for r in reference() {
        let place = Place {
            latitude_deg: r.observer.latitude_deg,
            longitude_deg: r.observer.longitude_deg,
            time: r.time.clone(),
            heading_deg: 30.0,
            altitude_m: r.observer.altitude_m,
        };
        if r.zenith > 91.0 {
            let e = place.sun().unwrap_err().to_string();
            assert!(e.contains("time") && e.contains("sun is up"), "{e}");
            refused += 1;
        } else if r.apparent < 89.0 {
            let sun = place.sun().unwrap();
            let p = sun.position;
            assert!(
                (p.zenith_deg - r.zenith).abs() < TOLERANCE_DEG,
                "{}: {p:?}",
                r.time
            );
            assert!(
                azimuth_diff(p.azimuth_deg, r.azimuth) < TOLERANCE_DEG,
                "{p:?}"
            );
            assert_eq!(sun.zenith, p.apparent_zenith_deg.to_radians());
            assert_eq!(sun.azimuth, p.azimuth_deg.to_radians());
            assert_eq!((sun.heading, sun.heading_deg), (30f64.to_radians(), 30.0));
            placed += 1;
        }
    }
    assert!(
        placed >= 100 && refused >= 100,
        "{placed} placed, {refused} refused"
    );
    let bad = Place {
        heading_deg: f64::NAN,
        ..Place {
            latitude_deg: 48.0,
            longitude_deg: 2.0,
            time: "2024-06-21T12:00:00Z".into(),
            heading_deg: 0.0,
            altitude_m: 0.0,
        }
    };
    let e = bad.sun().unwrap_err().to_string();
    assert!(e.contains("heading_deg"), "{e}");
}

/// Reda & Andreas' example: 2003-10-17 12:30:30 local (UTC−7), 39.742476° N,
/// 105.1786° W, 1830.14 m, 820 mbar, 11 °C, ΔT 67 s: zenith 50.11162°, azimuth
/// 194.34024° (the zenith includes refraction).
#[test]
fn the_papers_worked_example() {
    let t = parse_rfc3339("2003-10-17T12:30:30-07:00").unwrap();
    let obs = Observer {
        latitude_deg: 39.742476,
        longitude_deg: -105.1786,
        altitude_m: 1830.14,
        pressure_hpa: 820.0,
        temperature_c: 11.0,
    };
    let s = sun_position(&t, &obs, 67.0).unwrap();
    assert!((s.apparent_zenith_deg - 50.11162).abs() < 1e-5, "{s:?}");
    assert!((s.azimuth_deg - 194.34024).abs() < 1e-5, "{s:?}");
    assert!((s.right_ascension_deg - 202.22704).abs() < 1e-5, "{s:?}");
    assert!((s.declination_deg - -9.316179).abs() < 1e-6, "{s:?}");
    // Geometric: without refraction the sun is lower.
    assert!(s.zenith_deg > s.apparent_zenith_deg);
}

fn brume(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_brume"))
        .args(args)
        .output()
        .expect("run brume")
}

#[test]
fn brume_sun_prints_the_worked_example() {
    let o = brume(&[
        "sun",
        "--latitude",
        "39.742476",
        "--longitude",
        "-105.1786",
        "--time",
        "2003-10-17T12:30:30-07:00",
        "--altitude",
        "1830.14",
        "--pressure",
        "820",
        "--temperature",
        "11",
        "--delta-t",
        "67",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let f = |k: &str| v[k].as_f64().unwrap();
    assert!((f("apparent_zenith_deg") - 50.11162).abs() < 1e-5, "{v}");
    assert!((f("azimuth_deg") - 194.34024).abs() < 1e-5, "{v}");
    assert!(f("zenith_deg") > f("apparent_zenith_deg"));
}

#[test]
fn brume_sun_refuses_bad_input_clearly() {
    for (args, want) in [
        (
            vec![
                "--latitude",
                "91",
                "--longitude",
                "0",
                "--time",
                "2024-06-21T12:00:00Z",
            ],
            "--latitude",
        ),
        (
            vec![
                "--latitude",
                "10",
                "--longitude",
                "200",
                "--time",
                "2024-06-21T12:00:00Z",
            ],
            "--longitude",
        ),
        (
            vec![
                "--latitude",
                "10",
                "--longitude",
                "0",
                "--time",
                "2024-06-21 12:00",
            ],
            "RFC 3339",
        ),
        (
            vec![
                "--latitude",
                "10",
                "--longitude",
                "0",
                "--time",
                "2024-06-21T12:00:00",
            ],
            "UTC offset",
        ),
    ] {
        let mut a = vec!["sun"];
        a.extend(args);
        let o = brume(&a);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && e.contains(want), "{a:?}: {e}");
        assert!(!e.contains("panicked"), "{e}");
    }
}
