//! The sun from place and time on the command line: `brume sky`, `brume turbidity` and
//! `brume render --medium aerial` with --latitude/--longitude/--time/--heading, the
//! horizon's light by azimuth and `--retarget` in the render's report, and their errors.

use crate::common;

use common::{brume, stderr};
use serde_json::Value;
use std::path::Path;

/// Vienna, midsummer, late afternoon: the sun about 30° up in the west.
const PLACE: [&str; 6] = [
    "--latitude",
    "48.2082",
    "--longitude",
    "16.3738",
    "--time",
    "2024-06-21T17:00:00+02:00",
];

fn json_of(d: &Path, args: &[&str]) -> Value {
    let o = brume(d, args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    serde_json::from_slice(&o.stdout).expect("one JSON object")
}

fn fails_with(d: &Path, args: &[&str], want: &[&str]) {
    let o = brume(d, args);
    let e = stderr(&o);
    assert!(!o.status.success(), "{args:?} succeeded");
    assert!(!e.contains("panicked"), "{e}");
    for w in want {
        assert!(e.contains(w), "{args:?}: {e:?} lacks {w:?}");
    }
}

fn with<'a>(base: &[&'a str], extra: &[&'a str]) -> Vec<&'a str> {
    base.iter().chain(extra).copied().collect()
}

#[test]
fn sky_and_turbidity_take_the_sun_from_place_and_time() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sun = json_of(d, &with(&["sun", "--json"], &PLACE));
    let (zen, az) = (
        sun["apparent_zenith_deg"].as_f64().unwrap(),
        sun["azimuth_deg"].as_f64().unwrap(),
    );
    assert!(
        (50.0..70.0).contains(&zen) && (260.0..300.0).contains(&az),
        "{sun}"
    );
    let sky = json_of(
        d,
        &with(
            &[
                "sky",
                "--turbidity",
                "4",
                "--size",
                "160",
                "--out",
                "sky.pfm",
                "--json",
            ],
            &PLACE,
        ),
    );
    assert_eq!(sky["sun_zenith_deg"].as_f64(), Some(zen), "{sky}");
    assert_eq!(sky["sun_azimuth_deg"].as_f64(), Some(az), "{sky}");
    // The same sky from the angles is the same image.
    let (zs, azs) = (zen.to_string(), az.to_string());
    let by_angles = json_of(
        d,
        &[
            "sky",
            "--turbidity",
            "4",
            "--size",
            "160",
            "--out",
            "sky2.pfm",
            "--json",
            "--sun-zenith",
            &zs,
            "--sun-azimuth",
            &azs,
        ],
    );
    assert_eq!(
        by_angles["zenith_luminance_kcd_m2"],
        sky["zenith_luminance_kcd_m2"]
    );
    let same =
        std::fs::read(d.join("sky.pfm")).unwrap() == std::fs::read(d.join("sky2.pfm")).unwrap();
    assert!(same, "the skies from place and from angles differ");
    // The estimator gets the sun from the same place and time.
    let t = json_of(d, &with(&["turbidity", "sky.pfm", "--json"], &PLACE));
    assert_eq!(t["sun_source"], "given", "{t}");
    assert!((t["turbidity"].as_f64().unwrap() - 4.0).abs() < 0.05, "{t}");
    // --heading turns the fisheye: the compass direction at its top.
    let turned = json_of(
        d,
        &with(
            &[
                "sky",
                "--turbidity",
                "4",
                "--size",
                "64",
                "--out",
                "s3.png",
                "--json",
                "--heading",
                "90",
            ],
            &PLACE,
        ),
    );
    assert_eq!(
        turned["fisheye"]["azimuth_offset_deg"].as_f64(),
        Some(90.0),
        "{turned}"
    );
}

#[test]
fn sun_angles_and_place_do_not_mix() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sky = ["sky", "--turbidity", "4", "--size", "32", "--out", "s.exr"];
    fails_with(
        d,
        &with(
            &with(&sky, &["--sun-zenith", "40", "--sun-azimuth", "10"]),
            &PLACE,
        ),
        &["--sun-azimuth", "not both"],
    );
    fails_with(
        d,
        &with(&sky, &["--latitude", "48"]),
        &["--longitude, --time", "together"],
    );
    fails_with(
        d,
        &with(&sky, &["--heading", "10"]),
        &["--latitude", "together"],
    );
    fails_with(d, &sky, &["--sun-zenith", "--latitude/--longitude/--time"]);
    fails_with(
        d,
        &with(
            &with(&sky, &["--heading", "10", "--azimuth-offset", "5"]),
            &PLACE,
        ),
        &["--heading", "--azimuth-offset"],
    );
    // Night in Vienna.
    fails_with(
        d,
        &with(
            &sky,
            &[
                "--latitude",
                "48.2",
                "--longitude",
                "16.4",
                "--time",
                "2024-06-21T01:00:00+02:00",
            ],
        ),
        &["--time", "sun is up"],
    );
    fails_with(
        d,
        &with(
            &sky,
            &[
                "--latitude",
                "48.2",
                "--longitude",
                "16.4",
                "--time",
                "yesterday",
            ],
        ),
        &["--time", "RFC 3339"],
    );
}

#[test]
fn aerial_renders_take_place_time_heading_sectors_and_retargeting() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = brume(
        d,
        &[
            "scene",
            "--fog",
            "none",
            "--size",
            "64x40",
            "--out",
            "c.png",
            "--depth-out",
            "z.pfm",
        ],
    );
    assert!(scene.status.success(), "{}", stderr(&scene));
    let sky = brume(
        d,
        &with(
            &[
                "sky",
                "--turbidity",
                "4",
                "--size",
                "160",
                "--out",
                "sky.exr",
            ],
            &PLACE,
        ),
    );
    assert!(sky.status.success(), "{}", stderr(&sky));
    let base = [
        "render",
        "--image",
        "c.png",
        "--depth",
        "z.pfm",
        "--depth-kind",
        "zbuffer",
        "--near",
        "0.1",
        "--far",
        "1000",
        "--fov",
        "60",
        "--medium",
        "aerial",
        "--metres-per-unit",
        "20",
        "--json",
    ];
    let r = json_of(
        d,
        &with(
            &with(
                &base,
                &["--sky", "sky.exr", "--heading", "250", "--out", "a.png"],
            ),
            &PLACE,
        ),
    );
    assert!((r["turbidity"].as_f64().unwrap() - 4.0).abs() < 0.05, "{r}");
    assert_eq!(r["sun"]["heading_deg"].as_f64(), Some(250.0), "{r}");
    assert_eq!(r["horizon_sectors"].as_array().unwrap().len(), 8, "{r}");
    let one = json_of(
        d,
        &with(
            &base,
            &[
                "--turbidity",
                "3",
                "--horizon-sectors",
                "1",
                "--out",
                "b.png",
            ],
        ),
    );
    assert_eq!(one["horizon_sectors"].as_array().unwrap().len(), 1, "{one}");
    let norm = json_of(
        d,
        &with(
            &base,
            &[
                "--turbidity",
                "6",
                "--from-turbidity",
                "3",
                "--out",
                "n.png",
            ],
        ),
    );
    assert_eq!(norm["retarget"], "normalised", "{norm}");
    let rad = json_of(
        d,
        &with(
            &base,
            &[
                "--turbidity",
                "6",
                "--from-turbidity",
                "3",
                "--retarget",
                "radiance",
                "--out",
                "r.png",
            ],
        ),
    );
    assert_eq!(rad["retarget"], "radiance", "{rad}");
    assert_ne!(
        std::fs::read(d.join("n.png")).unwrap(),
        std::fs::read(d.join("r.png")).unwrap()
    );
    fails_with(
        d,
        &with(
            &base,
            &[
                "--turbidity",
                "3",
                "--retarget",
                "radiance",
                "--out",
                "x.png",
            ],
        ),
        &["--retarget", "--from-turbidity"],
    );
    fails_with(
        d,
        &with(
            &base,
            &[
                "--turbidity",
                "3",
                "--horizon-sectors",
                "0",
                "--out",
                "x.png",
            ],
        ),
        &["--horizon-sectors", "[1, 64]"],
    );
    fails_with(
        d,
        &with(
            &base,
            &["--turbidity", "3", "--latitude", "10", "--out", "x.png"],
        ),
        &["--longitude", "together"],
    );
    fails_with(
        d,
        &with(
            &[
                "render", "--image", "c.png", "--depth", "z.pfm", "--out", "x.png",
            ],
            &PLACE,
        ),
        &["--latitude", "--medium aerial"],
    );
}
