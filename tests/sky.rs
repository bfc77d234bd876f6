//! Preetham skies and the turbidity estimator (paper 002, sec. 3.2 and 3.4), through the
//! library and the `brume sky` / `brume turbidity` / `brume bench turbidity` commands.
//! CPU only: no GL context is opened.

use brume::io::output::write_rgba;
use brume::raster::Grid;
use brume::sky::clouds::{add_clouds, CloudOptions};
use brume::sky::turbidity::{find_sun, SunSource};
use brume::sky::{
    draw_sun_disc, estimate_turbidity, render_sky_image, Fisheye, PreethamSky, TurbidityOptions,
};
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

/// Paper 002's sun for Table 1.
const SUN_DEG: [f64; 2] = [58.4, -179.4];

fn sun() -> [f64; 2] {
    SUN_DEG.map(f64::to_radians)
}

fn brume(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_brume"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run brume")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn json(o: &Output) -> Value {
    assert!(o.status.success(), "{}", stderr(o));
    serde_json::from_slice(&o.stdout).expect("one JSON object on stdout")
}

fn sky_image(t: f64, size: usize) -> brume::raster::RgbImage {
    let [z, a] = sun();
    render_sky_image(
        &PreethamSky::new(t, z, a).unwrap(),
        size,
        &Fisheye::default(),
    )
    .unwrap()
}

/// `brume turbidity NAME --json` in `dir`, the sun given as Table 1's.
fn turbidity_with_table_1s_sun(dir: &Path, name: &str) -> Output {
    let (z, a) = (SUN_DEG[0].to_string(), SUN_DEG[1].to_string());
    let args = [
        "turbidity",
        name,
        "--sun-zenith",
        &z,
        "--sun-azimuth",
        &a,
        "--json",
    ];
    brume(dir, &args)
}

fn options(repeats: usize) -> TurbidityOptions {
    TurbidityOptions {
        sun: Some(sun()),
        repeats,
        ..TurbidityOptions::default()
    }
}

#[test]
fn clear_200px_skies_give_their_turbidity_back() {
    for t in [2.0, 5.0, 9.0] {
        let e = estimate_turbidity(&sky_image(t, 200), "sky", &options(5)).unwrap();
        assert!((e.turbidity - t).abs() <= 0.05, "T = {t}: {e:?}");
        assert!(e.std <= 0.01, "T = {t}: {e:?}");
        assert_eq!(e.repeats, 5);
        assert_eq!(e.samples, 100);
    }
}

#[test]
fn skies_with_20_percent_clouds_give_their_turbidity_back() {
    let f = Fisheye::default();
    for (i, t) in [2.0, 5.0, 9.0].into_iter().enumerate() {
        let mut image = sky_image(t, 200);
        let clouds = CloudOptions {
            coverage: 0.2,
            seed: i as u64 + 11,
            ..CloudOptions::default()
        };
        let report = add_clouds(&mut image, &f, &clouds).unwrap();
        assert!((report.coverage - 0.2).abs() <= 0.005, "{report:?}");
        let e = estimate_turbidity(&image, "cloudy sky", &options(5)).unwrap();
        assert!((e.turbidity - t).abs() <= 0.05, "T = {t}: {e:?}");
        // The cloud samples were rejected: fewer inliers than samples.
        assert!(e.inliers < 95.0, "T = {t}: {e:?}");
    }
}

#[test]
fn the_sun_is_found_from_a_saturated_disc() {
    let f = Fisheye::default();
    for (zenith, azimuth) in [(40.0f64, 120.0f64), (58.4, -179.4), (15.0, -60.0)] {
        let (z, a) = (zenith.to_radians(), azimuth.to_radians());
        let mut image = render_sky_image(&PreethamSky::new(4.0, z, a).unwrap(), 200, &f).unwrap();
        draw_sun_disc(&mut image, &f, z, a, 1.5f64.to_radians()).unwrap();
        let found = find_sun(&image, "sky", &f).unwrap();
        let off = brume::sky::preetham::angle_between(found.zenith, found.azimuth, z, a);
        assert!(
            off < 0.5f64.to_radians(),
            "{zenith}°, {azimuth}°: {found:?}"
        );
        let opts = TurbidityOptions {
            sun: None,
            repeats: 3,
            ..TurbidityOptions::default()
        };
        let e = estimate_turbidity(&image, "sky", &opts).unwrap();
        assert!(matches!(e.sun_source, SunSource::Detected { .. }), "{e:?}");
        assert!(
            (e.turbidity - 4.0).abs() <= 0.05,
            "{zenith}°, {azimuth}°: {e:?}"
        );
    }
}

#[test]
fn brume_sky_then_brume_turbidity_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (z, a) = (SUN_DEG[0].to_string(), SUN_DEG[1].to_string());
    for t in ["3", "7.5"] {
        // Linear EXR, sun given.
        let o = brume(
            d,
            &[
                "sky",
                "--turbidity",
                t,
                "--sun-zenith",
                &z,
                "--sun-azimuth",
                &a,
                "--size",
                "200",
                "--out",
                "sky.exr",
                "--json",
            ],
        );
        let sky = json(&o);
        assert_eq!(sky["size"], 200);
        assert!(sky["zenith_luminance_kcd_m2"].as_f64().unwrap() > 0.0);
        let o = brume(
            d,
            &[
                "turbidity",
                "sky.exr",
                "--sun-zenith",
                &z,
                "--sun-azimuth",
                &a,
                "--repeats",
                "4",
                "--json",
            ],
        );
        let e = json(&o);
        let want: f64 = t.parse().unwrap();
        let got = e["turbidity"].as_f64().unwrap();
        assert!((got - want).abs() <= 0.01, "T = {t}: {e}");
        assert!(e["std"].as_f64().unwrap() <= 0.01, "{e}");
        assert_eq!(e["sun_source"], "given");
        assert_eq!(e["estimates"].as_array().unwrap().len(), 4);

        // 8-bit PNG with a sun disc: the sun is found, not given.
        let o = brume(
            d,
            &[
                "sky",
                "--turbidity",
                t,
                "--sun-zenith",
                &z,
                "--sun-azimuth",
                &a,
                "--size",
                "300",
                "--sun-disc",
                "1",
                "--out",
                "sky.png",
            ],
        );
        assert!(o.status.success(), "{}", stderr(&o));
        for extra in [&[][..], &["--fit-level"][..]] {
            let mut args = vec!["turbidity", "sky.png", "--json"];
            args.extend_from_slice(extra);
            let e = json(&brume(d, &args));
            assert_eq!(e["sun_source"], "detected", "{e}");
            assert!(
                (e["sun_zenith_deg"].as_f64().unwrap() - SUN_DEG[0]).abs() < 0.5,
                "{e}"
            );
            let got = e["turbidity"].as_f64().unwrap();
            assert!((got - want).abs() <= 0.05, "T = {t} {extra:?}: {e}");
        }
    }
}

/// A Display P3 sky photo (a Preetham sky taken to P3's primaries by the standards'
/// matrices, IEC 61966-2-1's sRGB to XYZ and SMPTE EG 432-1's XYZ to P3, written as an EXR
/// whose `chromaticities` say P3) gives its turbidity back through `brume turbidity` and
/// the aerial medium's `turbidity_from_sky`: its luminance is weighted by P3's Y row. The
/// same pixels read as sRGB (no `chromaticities`) take the blue zenith for darker than
/// it is, and T 10 for about 10.1.
#[test]
fn a_display_p3_sky_is_read_in_its_own_primaries() {
    const SRGB_TO_XYZ: [[f64; 3]; 3] = [
        [0.4124, 0.3576, 0.1805],
        [0.2126, 0.7152, 0.0722],
        [0.0193, 0.1192, 0.9505],
    ];
    const XYZ_TO_P3: [[f64; 3]; 3] = [
        [2.4935, -0.9314, -0.4027],
        [-0.8295, 1.7627, 0.0236],
        [0.0358, -0.0762, 0.9569],
    ];
    let row = |m: [[f64; 3]; 3], v: [f64; 3]| m.map(|r| r[0] * v[0] + r[1] * v[1] + r[2] * v[2]);
    let (t, sun_deg) = (10.0, [60.0f64, 45.0f64]);
    let [z, a] = sun_deg.map(f64::to_radians);
    let srgb = render_sky_image(
        &PreethamSky::new(t, z, a).unwrap(),
        200,
        &Fisheye::default(),
    )
    .unwrap();
    let p3 = Grid::from_fn(200, 200, |x, y| {
        let xyz = row(SRGB_TO_XYZ, srgb.get(x, y).map(f64::from));
        let [r, g, b] = row(XYZ_TO_P3, xyz).map(|c| c as f32);
        [r, g, b, 1.0]
    });
    let p3_photo = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/colour/p3-flat.png");
    let metadata = brume::io::image::load_upright_rgb(&p3_photo)
        .unwrap()
        .metadata;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    brume::io::output::write_photo(&d.join("p3.exr"), &p3, &metadata).unwrap();
    write_rgba(&d.join("as-srgb.exr"), &p3).unwrap();

    let [zs, as_] = sun_deg.map(|v| v.to_string());
    let estimate = |name: &str| {
        let args = [
            "turbidity",
            name,
            "--sun-zenith",
            &zs,
            "--sun-azimuth",
            &as_,
        ];
        json(&brume(d, &[&args[..], &["--json"]].concat()))
    };
    let e = estimate("p3.exr");
    let got = e["turbidity"].as_f64().unwrap();
    assert!((got - t).abs() <= 0.01, "{e}");
    let weights: Vec<f64> = serde_json::from_value(e["luminance_weights"].clone()).unwrap();
    let p3_y = [0.2290, 0.6917, 0.0793];
    assert!(
        weights.iter().zip(p3_y).all(|(w, y)| (w - y).abs() < 1e-3),
        "{e}"
    );
    assert!(e["colour_profile"].is_string(), "{e}");
    let from_sky = brume::photo::turbidity_from_sky(&d.join("p3.exr"), Some([z, a])).unwrap();
    assert!((from_sky.turbidity - t).abs() <= 0.01, "{from_sky:?}");

    let e = estimate("as-srgb.exr");
    assert!(e["turbidity"].as_f64().unwrap() - t > 0.05, "{e}");
    assert_eq!(
        e["luminance_weights"],
        serde_json::json!([0.2126, 0.7152, 0.0722])
    );
}

/// A display-encoded sky photo (8-bit PNG) is estimated with a warning that a camera's
/// tone curve is not its profile's; linear light (an EXR) without one. The JSON says
/// which it was.
#[test]
fn a_display_encoded_sky_photo_is_warned_of() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sky = sky_image(4.0, 200);
    let rgba = Grid::from_fn(200, 200, |x, y| {
        let [r, g, b] = *sky.get(x, y);
        // Exposed so that the PNG's codes do not clip.
        [r / 20.0, g / 20.0, b / 20.0, 1.0]
    });
    write_rgba(&d.join("sky.png"), &rgba).unwrap();
    write_rgba(&d.join("sky.exr"), &rgba).unwrap();
    for (name, linear) in [("sky.png", false), ("sky.exr", true)] {
        let o = turbidity_with_table_1s_sun(d, name);
        let e = json(&o);
        assert_eq!(e["linear_light"], linear, "{name}: {e}");
        let err = stderr(&o);
        let warning = err
            .lines()
            .find(|l| l.contains("display-encoded sky photo"));
        assert_eq!(warning.is_some(), !linear, "{name}: {err}");
        assert!(warning.is_none_or(|w| !w.contains("  ")), "{err}");
        assert!(
            (e["turbidity"].as_f64().unwrap() - 4.0).abs() < 0.05,
            "{name}: {e}"
        );
    }
}

/// A circular fisheye's frame, wider than tall with black around the sky's disc, is
/// estimated on its image circle: the square found is where the disc was put, and the
/// estimate is the square image's, number for number.
#[test]
fn a_circular_fisheyes_frame_is_estimated_on_its_image_circle() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sky = sky_image(4.0, 200);
    let frame = Grid::from_fn(320, 240, |x, y| {
        let inside = (70..270).contains(&x) && (25..225).contains(&y);
        let [r, g, b] = if inside {
            *sky.get(x - 70, y - 25)
        } else {
            [0.0; 3]
        };
        [r, g, b, 1.0]
    });
    write_rgba(&d.join("frame.exr"), &frame).unwrap();
    write_rgba(&d.join("square.exr"), &sky.opaque()).unwrap();
    let estimate = |name: &str| json(&turbidity_with_table_1s_sun(d, name));
    let (framed, alone) = (estimate("frame.exr"), estimate("square.exr"));
    assert_eq!(
        framed["image_circle"],
        serde_json::json!({"x": 70, "y": 25, "side": 200})
    );
    assert!(alone["image_circle"].is_null(), "{alone}");
    assert_eq!(framed["turbidity"], alone["turbidity"]);
    assert!(
        (framed["turbidity"].as_f64().unwrap() - 4.0).abs() < 0.01,
        "{framed}"
    );
    // A rectangular photo of sky is no fisheye: refused, naming the file and what to do.
    let wide = Grid::from_fn(320, 240, |x, y| {
        let [r, g, b] = *sky.get(x % 200, y % 200);
        [r, g, b, 1.0]
    });
    write_rgba(&d.join("wide.exr"), &wide).unwrap();
    let o = turbidity_with_table_1s_sun(d, "wide.exr");
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(
        err.contains("wide.exr") && err.contains("not a disc"),
        "{err}"
    );
}

#[test]
fn bad_input_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sky = |extra: &[&str]| {
        let mut args = vec![
            "sky",
            "--turbidity",
            "3",
            "--sun-zenith",
            "30",
            "--sun-azimuth",
            "0",
            "--size",
            "64",
            "--out",
            "bad.exr",
        ];
        args.extend_from_slice(extra);
        brume(d, &args)
    };
    for (extra, named) in [
        (&["--turbidity", "0.5"][..], "--turbidity"),
        (&["--turbidity", "25"][..], "--turbidity"),
        (&["--sun-zenith", "90"][..], "--sun-zenith"),
        (&["--sun-zenith", "-5"][..], "--sun-zenith"),
        (&["--size", "0"][..], "--size"),
        (&["--size", "16385"][..], "--size"),
        (&["--size", "-2"][..], "--size"),
        (&["--clouds", "2"][..], "--clouds"),
        (&["--sun-disc", "-1"][..], "--sun-disc"),
        (&["--cloud-seed", "-1"][..], "--cloud-seed"),
        (
            &["--cloud-seed", "5"][..],
            "--cloud-seed = 5: expected --clouds",
        ),
        (&["--out", "bad.jpg"][..], "--out"),
    ] {
        let o = sky(extra);
        let err = stderr(&o);
        assert!(
            !o.status.success() && err.contains(named),
            "{extra:?}: {err}"
        );
        assert!(!d.join("bad.exr").exists(), "{extra:?} left an output");
    }

    // Inputs for `brume turbidity`.
    write_rgba(
        &d.join("wide.exr"),
        &Grid::filled(40, 30, [1.0, 1.0, 1.0, 1.0]),
    )
    .unwrap();
    write_rgba(
        &d.join("black.exr"),
        &Grid::filled(40, 40, [0.0, 0.0, 0.0, 1.0]),
    )
    .unwrap();
    let o = sky(&[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let turbidity = |args: &[&str]| {
        let mut all = vec!["turbidity"];
        all.extend_from_slice(args);
        brume(d, &all)
    };
    for (args, named) in [
        (&["wide.exr"][..], "wide.exr"),
        (&["black.exr"][..], "black.exr"),
        (&["missing.png"][..], "missing.png"),
        (
            &["bad.exr", "--sun-zenith", "95", "--sun-azimuth", "0"][..],
            "--sun-zenith",
        ),
        (&["bad.exr", "--samples", "2"][..], "--samples"),
        (&["bad.exr", "--repeats", "0"][..], "--repeats"),
        (&["bad.exr", "--seed", "-1"][..], "--seed"),
        (&["bad.exr", "--threshold", "1.5"][..], "--threshold"),
        (
            &["bad.exr", "--horizon-margin", "95"][..],
            "--horizon-margin",
        ),
        (
            &["bad.exr", "--reference-zenith", "100"][..],
            "--reference-zenith",
        ),
        (&["bad.exr", "--sun-zenith", "30"][..], "--sun-azimuth"),
        (&["bad.exr", "--samples", "100000"][..], "--samples"),
    ] {
        let o = turbidity(args);
        let err = stderr(&o);
        assert!(
            !o.status.success() && err.contains(named),
            "{args:?}: {err}"
        );
    }
    let err = stderr(&turbidity(&["wide.exr"]));
    assert!(err.contains("square"), "{err}");
    let err = stderr(&turbidity(&["black.exr"]));
    assert!(err.contains("no sky pixels"), "{err}");
}

#[test]
fn bench_turbidity_reports_the_table_and_json() {
    let dir = tempfile::tempdir().unwrap();
    let o = brume(
        dir.path(),
        &[
            "bench",
            "turbidity",
            "--size",
            "120",
            "--turbidities",
            "2,9",
            "--estimations",
            "3",
            "--json",
        ],
    );
    let report = json(&o);
    assert_eq!(report["rows"].as_array().unwrap().len(), 4, "{report}");
    assert_eq!(report["pass"], true, "{report}");
    assert!(
        stderr(&o).contains("2.011791"),
        "the table with the paper's values"
    );
    let o = brume(dir.path(), &["bench", "turbidity", "--clouds", "1.5"]);
    assert!(
        !o.status.success() && stderr(&o).contains("--clouds"),
        "{}",
        stderr(&o)
    );
}

// ---------------------------------------------------------------------------------------
// The model against the published paper, not against itself.
//
// Everything below is written from Preetham, Shirley and Smits, "A Practical Analytic
// Model for Daylight", SIGGRAPH 1999, appendix A.2 (the Perez coefficients, linear in T)
// and A.3 (the zenith luminance and chromaticity), copied here as literals and evaluated
// in plain f64 by the test's own code: none of it calls brume's model, so a wrong digit or
// a wrong formula in src/sky/preetham.rs no longer cancels out.
// ---------------------------------------------------------------------------------------

/// Appendix A.2, luminance Y: A..E = slope·T + intercept, as `[slope, intercept]`.
const PAPER_PEREZ_Y: [[f64; 2]; 5] = [
    [0.1787, -1.4630],
    [-0.3554, 0.4275],
    [-0.0227, 5.3251],
    [0.1206, -2.5771],
    [-0.0670, 0.3703],
];
/// Appendix A.2, chromaticity x.
const PAPER_PEREZ_X: [[f64; 2]; 5] = [
    [-0.0193, -0.2592],
    [-0.0665, 0.0008],
    [-0.0004, 0.2125],
    [-0.0641, -0.8989],
    [-0.0033, 0.0452],
];
/// Appendix A.2, chromaticity y.
const PAPER_PEREZ_CY: [[f64; 2]; 5] = [
    [-0.0167, -0.2608],
    [-0.0950, 0.0092],
    [-0.0079, 0.2102],
    [-0.0441, -1.6537],
    [-0.0109, 0.0529],
];
/// Appendix A.3: x_z = [T² T 1] · M · [θs³ θs² θs 1]ᵀ.
const PAPER_ZENITH_X: [[f64; 4]; 3] = [
    [0.00166, -0.00375, 0.00209, 0.0],
    [-0.02903, 0.06377, -0.03202, 0.00394],
    [0.11693, -0.21196, 0.06052, 0.25886],
];
/// Appendix A.3: y_z, as x_z.
const PAPER_ZENITH_Y: [[f64; 4]; 3] = [
    [0.00275, -0.00610, 0.00317, 0.0],
    [-0.04214, 0.08970, -0.04153, 0.00516],
    [0.15346, -0.26756, 0.06670, 0.26688],
];

/// An independent implementation's coefficients: Mitsuba 0.x, `SkyLuminaire::configure`
/// in mitsuba-renderer/mitsuba `src/luminaires/sky.cpp` (ported from the authors' own
/// code), which carries five decimals where the paper prints four: Y, x, y in turn.
const MITSUBA_PEREZ: [[[f64; 2]; 5]; 3] = [
    [
        [0.17872, -1.46303],
        [-0.35540, 0.42749],
        [-0.02266, 5.32505],
        [0.12064, -2.57705],
        [-0.06696, 0.37027],
    ],
    [
        [-0.01925, -0.25922],
        [-0.06651, 0.00081],
        [-0.00041, 0.21247],
        [-0.06409, -0.89887],
        [-0.00325, 0.04517],
    ],
    [
        [-0.01669, -0.26078],
        [-0.09495, 0.00921],
        [-0.00792, 0.21023],
        [-0.04405, -1.65369],
        [-0.01092, 0.05291],
    ],
];
/// Mitsuba's zenith chromaticity matrices (same file): they differ from the paper's by one
/// unit of the fifth decimal in a few entries (0.00165 for 0.00166, …).
const MITSUBA_ZENITH: [[[f64; 4]; 3]; 2] = [
    [
        [0.00165, -0.00374, 0.00208, 0.0],
        [-0.02902, 0.06377, -0.03202, 0.00394],
        [0.11693, -0.21196, 0.06052, 0.25885],
    ],
    [
        [0.00275, -0.00610, 0.00316, 0.0],
        [-0.04214, 0.08970, -0.04153, 0.00515],
        [0.15346, -0.26756, 0.06669, 0.26688],
    ],
];

/// A..E of a table at turbidity `t`.
fn paper_coefficients(table: &[[f64; 2]; 5], t: f64) -> [f64; 5] {
    table.map(|[slope, intercept]| slope * t + intercept)
}

/// The Perez function F(θ, γ) = (1 + A·e^(B/cos θ))·(1 + C·e^(D·γ) + E·cos²γ).
fn paper_f([a, b, c, d, e]: [f64; 5], theta: f64, gamma: f64) -> f64 {
    (1.0 + a * (b / theta.cos()).exp()) * (1.0 + c * (d * gamma).exp() + e * gamma.cos().powi(2))
}

/// Y_z = (4.0453T − 4.9710)·tan χ − 0.2155T + 2.4192, χ = (4/9 − T/120)(π − 2θs), kcd/m².
fn paper_zenith_luminance(t: f64, sun_zenith: f64) -> f64 {
    let chi = (4.0 / 9.0 - t / 120.0) * (std::f64::consts::PI - 2.0 * sun_zenith);
    (4.0453 * t - 4.9710) * chi.tan() - 0.2155 * t + 2.4192
}

/// [T² T 1] · M · [θs³ θs² θs 1]ᵀ.
fn paper_zenith_chromaticity(m: &[[f64; 4]; 3], t: f64, sun_zenith: f64) -> f64 {
    let s = sun_zenith;
    let thetas = [s * s * s, s * s, s, 1.0];
    let ts = [t * t, t, 1.0];
    let mut sum = 0.0;
    for i in 0..3 {
        for j in 0..4 {
            sum += ts[i] * m[i][j] * thetas[j];
        }
    }
    sum
}

/// The angle between directions (θ1, φ1) and (θ2, φ2), by the spherical law of cosines.
fn paper_gamma(theta1: f64, phi1: f64, theta2: f64, phi2: f64) -> f64 {
    let c = theta1.cos() * theta2.cos() + theta1.sin() * theta2.sin() * (phi1 - phi2).cos();
    c.clamp(-1.0, 1.0).acos()
}

fn relative_error(got: f64, want: f64) -> f64 {
    (got - want).abs() / want.abs()
}

fn perez_fields(p: brume::sky::preetham::Perez) -> [f64; 5] {
    [p.a, p.b, p.c, p.d, p.e]
}

const TURBIDITIES: [f64; 8] = [1.0, 2.0, 3.0, 4.5, 6.0, 9.0, 15.0, 20.0];

#[test]
fn perez_coefficients_are_the_published_linear_functions_of_t() {
    use brume::sky::preetham::Perez;
    let names = ["Y", "x", "y"];
    let paper = [PAPER_PEREZ_Y, PAPER_PEREZ_X, PAPER_PEREZ_CY];
    let mut worst_mitsuba: f64 = 0.0;
    for t in TURBIDITIES {
        let brume = [Perez::luminance(t), Perez::x(t), Perez::y(t)].map(perez_fields);
        let sky = PreethamSky::new(t, 0.7, 0.3).unwrap().coefficients();
        for q in 0..3 {
            let want = paper_coefficients(&paper[q], t);
            let mitsuba = paper_coefficients(&MITSUBA_PEREZ[q], t);
            for c in 0..5 {
                let name = format!("{}{} at T = {t}", ["A", "B", "C", "D", "E"][c], names[q]);
                // The same two operations on the same two literals: only rounding.
                assert!(
                    (brume[q][c] - want[c]).abs() <= 1e-12,
                    "{name}: brume {} vs the paper's {}",
                    brume[q][c],
                    want[c]
                );
                assert_eq!(perez_fields(sky[q])[c], brume[q][c], "{name}");
                // Against Mitsuba's five decimals: the paper's four are their rounding, so
                // slope and intercept each differ by at most half a unit of the fourth
                // decimal, 5e-5 (several entries sit exactly at 5e-5: 5.32505 → 5.3251).
                let bound = 5e-5 * (t + 1.0) + 1e-12;
                let off = (brume[q][c] - mitsuba[c]).abs();
                worst_mitsuba = worst_mitsuba.max(off / (t + 1.0));
                assert!(
                    off <= bound,
                    "{name}: brume {} vs Mitsuba's {} (bound {bound:.1e})",
                    brume[q][c],
                    mitsuba[c]
                );
            }
        }
    }
    eprintln!("largest |brume − Mitsuba|/(T + 1) over A..E: {worst_mitsuba:.2e} (bound 5e-5)");
}

#[test]
fn zenith_values_are_the_published_formulas() {
    use brume::sky::preetham::{zenith_chromaticity, zenith_luminance};
    for t in TURBIDITIES {
        for deg in [0.0f64, 10.0, 30.0, 45.0, 60.0, 75.0] {
            let s = deg.to_radians();
            let case = format!("T = {t}, θs = {deg}°");
            let yz = paper_zenith_luminance(t, s);
            let xz = paper_zenith_chromaticity(&PAPER_ZENITH_X, t, s);
            let cyz = paper_zenith_chromaticity(&PAPER_ZENITH_Y, t, s);
            assert!(
                relative_error(zenith_luminance(t, s), yz) <= 1e-12,
                "Y_z at {case}: brume {} vs {yz}",
                zenith_luminance(t, s)
            );
            let (bx, by) = zenith_chromaticity(t, s);
            assert!(
                relative_error(bx, xz) <= 1e-12,
                "x_z at {case}: {bx} vs {xz}"
            );
            assert!(
                relative_error(by, cyz) <= 1e-12,
                "y_z at {case}: {by} vs {cyz}"
            );
            // The sky object reports the same values.
            if let Ok(sky) = PreethamSky::new(t, s, 0.0) {
                assert_eq!(sky.zenith_luminance(), zenith_luminance(t, s), "{case}");
                assert_eq!(sky.zenith_chromaticity(), (bx, by), "{case}");
            } else {
                assert!(yz <= 0.0, "{case}: refused with Y_z = {yz} > 0");
            }
            // Against Mitsuba's matrices: each entry differs by at most one unit of the
            // fifth decimal, so x_z and y_z by at most 1e-5 · Σ |T^i θs^j| over the entries
            // that differ, which the test sums.
            for (which, (paper, mitsuba, got)) in [
                (&PAPER_ZENITH_X, &MITSUBA_ZENITH[0], bx),
                (&PAPER_ZENITH_Y, &MITSUBA_ZENITH[1], by),
            ]
            .into_iter()
            .enumerate()
            {
                let (ts, thetas) = ([t * t, t, 1.0], [s * s * s, s * s, s, 1.0]);
                let mut bound = 1e-12;
                for i in 0..3 {
                    for j in 0..4 {
                        let step = (paper[i][j] - mitsuba[i][j]).abs();
                        assert!(step <= 1e-5 + 1e-12, "matrix entry ({i}, {j})");
                        if step > 0.0 {
                            bound += 1e-5 * ts[i] * thetas[j];
                        }
                    }
                }
                let theirs = paper_zenith_chromaticity(mitsuba, t, s);
                assert!(
                    (got - theirs).abs() <= bound,
                    "{} at {case}: brume {got} vs Mitsuba {theirs} (bound {bound:.1e})",
                    ["x_z", "y_z"][which]
                );
            }
        }
    }
}

/// Worked values, computed by hand (Python, plain floats) from the appendix's literals as
/// above: T, θs (degrees), then Y_z (kcd/m²), x_z, y_z.
const WORKED_ZENITH: [(f64, f64, [f64; 3]); 3] = [
    (
        2.0,
        30.0,
        [5.886743249308, 0.2514214623701, 0.2559238381535],
    ),
    (
        2.0,
        60.0,
        [3.487327439551, 0.2380126204684, 0.2419876185696],
    ),
    (
        6.0,
        45.0,
        [14.89332684487, 0.2614478677334, 0.2754501198218],
    ),
];

/// A direction (θ, φ − φs) in degrees and the sky's [Y/Y_z, x, y] there.
type WorkedDirection = ((f64, f64), [f64; 3]);

/// Worked values of the same skies (same order) in directions (θ, φ − φs) in degrees:
/// Y/Y_z = F_Y(θ, γ)/F_Y(0, θs) (eq. 6), then x and y.
const WORKED_SKY: [[WorkedDirection; 4]; 3] = [
    [
        (
            (30.0, 10.0),
            [2.462424659517, 0.2706364896887, 0.2808355628952],
        ),
        (
            (45.0, 90.0),
            [0.9750312659963, 0.2439001590657, 0.2500342429458],
        ),
        (
            (70.0, 180.0),
            [1.242123810921, 0.2440029798947, 0.2571806184159],
        ),
        (
            (80.0, 45.0),
            [2.599518552599, 0.2748497667989, 0.2867590001377],
        ),
    ],
    [
        (
            (60.0, 10.0),
            [7.262572861566, 0.2799064181819, 0.2895337108925],
        ),
        (
            (45.0, 90.0),
            [1.373823477668, 0.2389244382538, 0.2449031134009],
        ),
        (
            (70.0, 180.0),
            [2.292848368158, 0.2461201268898, 0.2593684151805],
        ),
        (
            (80.0, 45.0),
            [5.903382338433, 0.2846012232841, 0.2938246505131],
        ),
    ],
    [
        (
            (45.0, 10.0),
            [2.41289811488, 0.3038370003672, 0.3146068026989],
        ),
        (
            (45.0, 90.0),
            [0.8222436779934, 0.2677062968892, 0.2871325598103],
        ),
        (
            (70.0, 180.0),
            [0.5479954586996, 0.2890399492681, 0.3136686718634],
        ),
        (
            (80.0, 45.0),
            [0.957520218167, 0.3318153381547, 0.3399661156261],
        ),
    ],
];

/// The literals above carry 13 significant digits: they are checked to 1e-11 relative.
const WORKED_TOLERANCE: f64 = 1e-11;

#[test]
fn worked_values_of_the_published_model() {
    use brume::sky::preetham::{zenith_chromaticity, zenith_luminance};
    let sun_azimuth = 0.4f64;
    for ((t, deg, [yz, xz, cyz]), directions) in WORKED_ZENITH.into_iter().zip(WORKED_SKY) {
        let s = deg.to_radians();
        let case = format!("T = {t}, θs = {deg}°");
        // The test's own formulas give the worked values (they are what was worked).
        assert!(relative_error(paper_zenith_luminance(t, s), yz) <= WORKED_TOLERANCE);
        assert!(
            relative_error(paper_zenith_chromaticity(&PAPER_ZENITH_X, t, s), xz)
                <= WORKED_TOLERANCE
        );
        // brume's.
        let (bx, by) = zenith_chromaticity(t, s);
        for (what, got, want) in [
            ("Y_z", zenith_luminance(t, s), yz),
            ("x_z", bx, xz),
            ("y_z", by, cyz),
        ] {
            assert!(
                relative_error(got, want) <= WORKED_TOLERANCE,
                "{what} at {case}: brume {got} vs worked {want}"
            );
        }
        let sky = PreethamSky::new(t, s, sun_azimuth).unwrap();
        for ((theta_deg, dphi_deg), [ratio, x, y]) in directions {
            let (theta, phi) = (theta_deg.to_radians(), sun_azimuth + dphi_deg.to_radians());
            let at = format!("{case}, θ = {theta_deg}°, φ − φs = {dphi_deg}°");
            let gamma = paper_gamma(theta, phi, s, sun_azimuth);
            let f_y = paper_coefficients(&PAPER_PEREZ_Y, t);
            let own = paper_f(f_y, theta, gamma) / paper_f(f_y, 0.0, s);
            assert!(
                relative_error(own, ratio) <= WORKED_TOLERANCE,
                "{at}: {own}"
            );
            let got = sky.relative_luminance(theta, phi);
            assert!(
                relative_error(got, ratio) <= WORKED_TOLERANCE,
                "Y/Y_z at {at}: brume {got} vs worked {ratio}"
            );
            let [gx, gy, big_y] = sky.xyy(theta, phi);
            for (what, got, want) in [("x", gx, x), ("y", gy, y), ("Y", big_y, ratio * yz)] {
                assert!(
                    relative_error(got, want) <= WORKED_TOLERANCE,
                    "{what} at {at}: brume {got} vs worked {want}"
                );
            }
            // The luminance ratio of eq. 8 between two directions: Y_z cancels.
            let got = sky.luminance_ratio(theta, phi, 0.0, 0.0);
            assert!(
                relative_error(got, ratio) <= WORKED_TOLERANCE,
                "{at}: {got}"
            );
        }
    }
}

#[test]
fn relative_luminance_is_eq_6_over_the_sky() {
    use brume::sky::preetham::Perez;
    let mut worst: f64 = 0.0;
    for t in [1.5, 2.0, 3.3, 5.0, 7.5, 10.0] {
        for sun_deg in [5.0f64, 25.0, 50.0, 70.0] {
            let (s, sun_azimuth) = (sun_deg.to_radians(), -2.0);
            let sky = PreethamSky::new(t, s, sun_azimuth).unwrap();
            let coefficients = [PAPER_PEREZ_Y, PAPER_PEREZ_X, PAPER_PEREZ_CY]
                .map(|table| paper_coefficients(&table, t));
            let zenith = [
                paper_zenith_luminance(t, s),
                paper_zenith_chromaticity(&PAPER_ZENITH_X, t, s),
                paper_zenith_chromaticity(&PAPER_ZENITH_Y, t, s),
            ];
            for theta_deg in (0..=85).step_by(5) {
                for dphi_deg in (0..360).step_by(15) {
                    let theta = f64::from(theta_deg).to_radians();
                    let phi = sun_azimuth + f64::from(dphi_deg).to_radians();
                    let gamma = paper_gamma(theta, phi, s, sun_azimuth);
                    let at =
                        format!("T = {t}, θs = {sun_deg}°, θ = {theta_deg}°, Δφ = {dphi_deg}°");
                    let want: Vec<f64> = (0..3)
                        .map(|q| {
                            zenith[q] * paper_f(coefficients[q], theta, gamma)
                                / paper_f(coefficients[q], 0.0, s)
                        })
                        .collect();
                    let [x, y, big_y] = sky.xyy(theta, phi);
                    // Perez F itself, at the same (θ, γ).
                    let f = Perez::luminance(t).eval(theta, gamma);
                    let own_f = paper_f(coefficients[0], theta, gamma);
                    for (what, got, want) in [
                        ("Y", big_y, want[0]),
                        ("x", x, want[1]),
                        ("y", y, want[2]),
                        ("F_Y", f, own_f),
                    ] {
                        let e = relative_error(got, want);
                        worst = worst.max(e);
                        // f64 rounding through exp, cos and acos: a few 1e-16 relative,
                        // amplified by the ill-conditioned acos near γ = 0; 1e-12 is far
                        // below any wrong digit of the model (≥ 1e-5 relative).
                        assert!(e <= 1e-12, "{what} at {at}: brume {got} vs {want}");
                    }
                }
            }
        }
    }
    eprintln!("largest relative difference from eq. 6 written here: {worst:.2e}");
}

/// A square fisheye sky image drawn by the test's own code: the default convention of
/// brume's fisheye module as documented there (equidistant lens, zenith at the centre,
/// horizon on the inscribed circle, azimuth 0 at the top and clockwise, pixel centres at
/// +0.5), luminance from the paper's formulas above (eq. 6 with A.2 and A.3), grey pixels
/// (R = G = B = Y, whose Rec. 709 luminance is Y: the estimator reads luminance only).
fn paper_sky_image(t: f64, sun: [f64; 2], size: usize) -> brume::raster::RgbImage {
    let coefficients = paper_coefficients(&PAPER_PEREZ_Y, t);
    let yz = paper_zenith_luminance(t, sun[0]);
    let norm = paper_f(coefficients, 0.0, sun[0]);
    let half = size as f64 / 2.0;
    Grid::from_fn(size, size, |x, y| {
        let (dx, dy) = (x as f64 + 0.5 - half, y as f64 + 0.5 - half);
        let r = (dx * dx + dy * dy).sqrt() / half;
        if r > 1.0 {
            return [0.0; 3];
        }
        let theta = r * std::f64::consts::FRAC_PI_2;
        let phi = dx.atan2(-dy);
        let gamma = paper_gamma(theta, phi, sun[0], sun[1]);
        let lum = (yz * paper_f(coefficients, theta, gamma) / norm) as f32;
        [lum; 3]
    })
}

/// The estimator on skies it did not draw: brume's estimator against the paper's model as
/// written in this test, so that an error in brume's Perez function would show as a wrong
/// T instead of cancelling between the renderer and the estimator.
#[test]
fn skies_drawn_from_the_published_model_give_their_turbidity_back() {
    // Pixels are f32 (6e-8 relative): the luminance ratios are exact to about 1e-7, which
    // moves T by about 1e-6 at most (measured: 1.2e-7). One unit of the fourth decimal of
    // one coefficient moves it by far more: drawing the skies with A_Y's slope 0.1788,
    // D_Y's intercept −2.5772 or E_Y's slope −0.0671 gave errors of 4.8e-4, 1.4e-4 and
    // 2.2e-4 (the first failing case of each).
    const TOLERANCE: f64 = 1e-5;
    let mut worst: f64 = 0.0;
    for (sun_deg, t) in [
        ([58.4, -179.4], 2.0),
        ([58.4, -179.4], 5.0),
        ([58.4, -179.4], 9.0),
        ([30.0, 45.0], 2.5),
        ([30.0, 45.0], 7.0),
        ([70.0, -100.0], 4.0),
    ] {
        let sun = sun_deg.map(f64::to_radians);
        let image = paper_sky_image(t, sun, 200);
        let opts = TurbidityOptions {
            sun: Some(sun),
            repeats: 3,
            ..TurbidityOptions::default()
        };
        let e = estimate_turbidity(&image, "paper sky", &opts).unwrap();
        let error = (e.turbidity - t).abs();
        worst = worst.max(error);
        eprintln!(
            "T = {t}, sun {sun_deg:?}°: estimated {:.7} (error {error:.2e}, inliers {:.1})",
            e.turbidity, e.inliers
        );
        assert!(error <= TOLERANCE, "T = {t}, sun {sun_deg:?}: {e:?}");
        // A sky that is exactly the model has no outliers: every sample is kept.
        assert_eq!(e.inliers, 100.0, "T = {t}, sun {sun_deg:?}: {e:?}");
        assert!(e
            .estimates
            .iter()
            .all(|s| (s.turbidity - t).abs() <= TOLERANCE));
    }
    eprintln!("largest turbidity error: {worst:.2e} (tolerance {TOLERANCE:.0e})");
}
