//! `brume bench speed` on a tiny image: skipping by `--max-passes`, the report's shape,
//! and the whole `run` entry point with its files. Timed figures are never asserted
//! (benchmarks measure speed, tests do not): only that they exist and are positive.
use crate::common;

use brume::bench::speed::Tau;
use brume::bench::{run_speed, Configs, SpeedOptions};
use brume::{Precision, Scheme};
use common::*;
use std::process::{Command, Output};

/// `brume bench ARGS...`, one at a time with the other GL tests.
fn bench(args: &[&str]) -> Output {
    let _lock = gl_lock();
    Command::new(env!("CARGO_BIN_EXE_brume"))
        .arg("bench")
        .args(args)
        .output()
        .expect("run brume")
}

#[test]
fn max_passes_skips_euler_and_says_so() {
    let opts = SpeedOptions {
        configs: Configs {
            sigmas: vec![3.0],
            schemes: Scheme::ALL.to_vec(),
            precisions: vec![Precision::F32],
            ..Configs::default()
        },
        width: 32,
        height: 24,
        runs: 2,
        // Euler at σ = 3 is 16 + 2 passes, the invariant family 5 + 2.
        max_passes: Some(10),
        tau: Tau::Grey,
        coarse_from: None,
    };
    let (_lock, mut r) = renderer();
    let report = run_speed(r.renderer().unwrap(), &opts, &|_| {}).expect("speed run");
    eprint!("{}", brume::bench::report::speed_table(&report));
    let euler = &report.rows[0];
    assert_eq!(euler.scheme, Scheme::Euler);
    assert!(euler.skipped && euler.median_ms.is_none());
    assert_eq!(euler.reason.as_deref(), Some("18 passes > the limit of 10"));
    for row in &report.rows[1..] {
        assert!(!row.skipped, "{row:?}");
        assert_eq!((row.passes, row.runs, row.samples_ms.len()), (7, 2, 2));
        assert_eq!(row.pass_names.len(), 7);
        assert_eq!(row.pass_median_ms.len(), 7);
        assert!(row.pass_median_ms.iter().all(|&ms| ms > 0.0), "{row:?}");
        assert!(row.median_ms.unwrap() > 0.0 && row.std_ms.is_some());
        assert!(row.clock.is_some());
    }
    assert!(report.ratios.is_empty(), "no Euler figure, no ratio");
    let table = brume::bench::report::speed_table(&report);
    assert!(
        table.contains("skipped: 18 passes > the limit of 10"),
        "{table}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&brume::bench::report::speed_json(&report).unwrap()).unwrap();
    assert_eq!(json["rows"][0]["skipped"], true);
    assert_eq!(json["rows"][0]["reason"], "18 passes > the limit of 10");
    assert_eq!(json["rows"][1]["skipped"], false);
}

/// One run of the matched scheme in f32 at σ `sigma` on a 64x48 image, the coarse stage
/// from `coarse_from` px.
fn matched_f32_64x48(sigma: f64, coarse_from: f64) -> SpeedOptions {
    SpeedOptions {
        configs: Configs {
            sigmas: vec![sigma],
            schemes: vec![Scheme::Matched],
            precisions: vec![Precision::F32],
            ..Configs::default()
        },
        width: 64,
        height: 48,
        runs: 1,
        coarse_from: Some(coarse_from),
        ..SpeedOptions::default()
    }
}

/// With the coarse stage a row counts the passes that ran (N + 1 + 2L, not N + 2) and
/// names each with its median time.
#[test]
fn coarse_rows_count_and_name_their_passes() {
    let opts = matched_f32_64x48(25.0, 2.0);
    let (_lock, mut r) = renderer();
    let report = run_speed(r.renderer().unwrap(), &opts, &|_| {}).expect("speed run");
    let row = &report.rows[0];
    // σ 25: N = 13, two levels from step 3 (σ 2.10 px) and 6.
    assert_eq!((row.steps, row.passes), (13, 13 + 1 + 2 * 2));
    assert_eq!(row.pass_names.len(), row.passes as usize);
    assert_eq!(row.pass_median_ms.len(), row.passes as usize);
    assert_eq!(row.pass_names.first().map(String::as_str), Some("medium"));
    assert_eq!(
        row.pass_names.last().map(String::as_str),
        Some("blend 1/2 + composite")
    );
    let sum: f64 = row.pass_median_ms.iter().sum();
    assert!(sum > 0.0 && row.median_ms.unwrap() > 0.0, "{row:?}");
}

#[test]
fn run_writes_csv_and_plot_and_reports_ratios() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, svg) = (dir.path().join("speed.csv"), dir.path().join("fig7.svg"));
    let out = bench(&[
        "speed",
        "--sigmas",
        "2",
        "--schemes",
        "euler,matched",
        "--precisions",
        "f32",
        "--size",
        "24x16",
        "--runs",
        "2",
        "--csv",
        csv.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count(), 3, "{text}");
    assert!(text.starts_with("sigma_ref,scheme,precision"));
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
}

#[test]
fn chromatic_tau_is_timed_and_reported() {
    let out = bench(&[
        "speed",
        "--sigmas",
        "3",
        "--schemes",
        "matched",
        "--precisions",
        "f32,f16",
        "--size",
        "24x16",
        "--runs",
        "1",
        "--tau",
        "rgb",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["tau"], "rgb");
    for row in json["rows"].as_array().unwrap() {
        assert!(row["median_ms"].as_f64().unwrap() > 0.0, "{row}");
    }
}

#[test]
fn bad_options_fail_before_any_work() {
    for (args, option) in [
        (vec!["speed", "--sigmas", ""], "--sigmas"),
        (vec!["speed", "--schemes", "euler,fast"], "--schemes"),
        (vec!["speed", "--size", "0x0"], "--size"),
        (vec!["speed", "--tau", "blue"], "--tau"),
        (vec!["accuracy", "--sigmas", "0.5"], "--sigmas"),
        (vec!["accuracy", "--plot", "/no/such/dir/x.png"], "--plot"),
    ] {
        let out = bench(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(err.contains(option), "{args:?}: {err}");
    }
}

/// `coarse_from` below 2 px (or not finite) is refused before any work, naming the field
/// (the program's `--coarse-from`: `tests/cli_bad_input.rs`); a valid one runs the
/// configuration with the coarse stage.
#[test]
fn coarse_from_is_checked_and_runs() {
    for bad in [1.0, 0.0, -2.0, f64::NAN] {
        let opts = SpeedOptions {
            coarse_from: Some(bad),
            ..SpeedOptions::default()
        };
        let err = opts.validate().expect_err("refused").to_string();
        assert!(err.contains("invalid coarse_from"), "{bad}: {err}");
    }
    let opts = matched_f32_64x48(12.0, 3.0);
    let (_lock, mut r) = renderer();
    let report = run_speed(r.renderer().unwrap(), &opts, &|_| {}).expect("speed run");
    assert_eq!(report.rows.len(), 1);
    assert!(report.rows[0].median_ms.is_some_and(|ms| ms > 0.0));
}

/// `brume bench refine`: the guided filter, then the upsampling of the sawtooth range and
/// of the procedural street's, each from 1/4 and 1/8 size, with figures; an image too small
/// for the street is refused by its option.
#[test]
fn refine_bench_times_the_filter_and_both_upsamplings() {
    let o = bench(&["refine", "--size", "128x64", "--runs", "1", "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let rows = v["rows"].as_array().unwrap();
    let got: Vec<(&str, u64, u64)> = rows
        .iter()
        .map(|r| {
            let size = r["range_size"].as_array().unwrap();
            (
                r["what"].as_str().unwrap(),
                size[0].as_u64().unwrap(),
                r["passes"].as_u64().unwrap(),
            )
        })
        .collect();
    assert_eq!(
        got,
        [
            ("guided filter", 128, 6),
            ("upsample 1/4", 32, 3),
            ("upsample 1/8", 16, 3),
            ("upsample 1/4, street", 32, 3),
            ("upsample 1/8, street", 16, 3),
        ]
    );
    for r in rows {
        assert!(r["median_ms"].as_f64().unwrap() > 0.0, "{r}");
    }
    let o = bench(&["refine", "--size", "40x40", "--runs", "1"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("invalid --size = 40x40: expected an image of at least 64x64 px"),
        "{err}"
    );
}
