//! `brume bench speed` on a tiny image: skipping by `--max-passes`, the report's shape,
//! and the whole `run` entry point with its files. Timed figures are never asserted
//! (GUIDE.md): only that they exist and are positive.
mod common;

use brume::bench::args::BenchCommand;
use brume::bench::{run_speed, Configs, SpeedOptions};
use brume::{Precision, Scheme};
use clap::Parser;
use common::*;

#[derive(clap::Parser)]
struct Cli {
    #[command(subcommand)]
    bench: BenchCommand,
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
    };
    let (_lock, mut r) = renderer();
    let report = run_speed(&mut r, &opts, &|_| {}).expect("speed run");
    eprint!("{}", brume::bench::report::speed_table(&report));
    let euler = &report.rows[0];
    assert_eq!(euler.scheme, Scheme::Euler);
    assert!(euler.skipped && euler.median_ms.is_none());
    assert_eq!(euler.reason.as_deref(), Some("18 passes > --max-passes 10"));
    for row in &report.rows[1..] {
        assert!(!row.skipped, "{row:?}");
        assert_eq!((row.passes, row.runs, row.samples_ms.len()), (7, 2, 2));
        assert!(row.median_ms.unwrap() > 0.0 && row.std_ms.is_some());
        assert!(row.clock.is_some());
    }
    assert!(report.ratios.is_empty(), "no Euler figure, no ratio");
    let table = brume::bench::report::speed_table(&report);
    assert!(
        table.contains("skipped: 18 passes > --max-passes 10"),
        "{table}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&brume::bench::report::speed_json(&report).unwrap()).unwrap();
    assert_eq!(json["rows"][0]["skipped"], true);
    assert_eq!(json["rows"][0]["reason"], "18 passes > --max-passes 10");
    assert_eq!(json["rows"][1]["skipped"], false);
}

#[test]
fn run_writes_csv_and_plot_and_reports_ratios() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, svg) = (dir.path().join("speed.csv"), dir.path().join("fig7.svg"));
    let cli = Cli::try_parse_from([
        "bench",
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
    ])
    .unwrap();
    let (_lock, mut r) = renderer();
    let no_image = || -> brume::Result<_> { panic!("speed needs no image") };
    brume::bench::run(&cli.bench, &mut r, &no_image, &|_| no_image()).expect("bench speed");
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count(), 3, "{text}");
    assert!(text.starts_with("sigma_ref,scheme,precision"));
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
}

#[test]
fn bad_options_fail_before_any_work() {
    let (_lock, mut r) = renderer();
    for (args, option) in [
        (vec!["speed", "--sigmas", ""], "--sigmas"),
        (vec!["speed", "--schemes", "euler,fast"], "--schemes"),
        (vec!["speed", "--size", "0x0"], "--size"),
        (vec!["accuracy", "--sigmas", "0.5"], "--sigmas"),
        (vec!["accuracy", "--plot", "/no/such/dir/x.png"], "--plot"),
    ] {
        let cli = Cli::try_parse_from(std::iter::once("bench").chain(args.clone())).unwrap();
        let err = brume::bench::run(&cli.bench, &mut r, &|| panic!("no image needed"), &|_| {
            panic!("no image needed")
        })
        .unwrap_err()
        .to_string();
        assert!(err.contains(option), "{args:?}: {err}");
    }
}
