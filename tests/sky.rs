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
        (&["--clouds", "2"][..], "--clouds"),
        (&["--sun-disc", "-1"][..], "--sun-disc"),
        (&["--cloud-seed", "-1"][..], "--cloud-seed"),
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
