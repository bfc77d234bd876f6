//! `brume bench accuracy` on a small image: the figures the paper's fig. 6 rests on, and
//! the report's outputs (JSON, CSV, plots).
use crate::common;

use brume::bench::accuracy::{AccuracyReport, AccuracyRow};
use brume::bench::{plot, report, run_accuracy, AccuracyOptions, Configs};
use brume::{Precision, Scheme};
use common::*;

/// σ 1 and 3, every scheme, f32, on a 64 x 48 noise image (one run shared by the tests
/// below would need a static; the run takes well under a second, so each test makes its
/// own).
fn small_report() -> AccuracyReport {
    let image = noise_image(64, 48, 11);
    let opts = AccuracyOptions {
        configs: Configs {
            sigmas: vec![1.0, 3.0],
            schemes: Scheme::ALL.to_vec(),
            precisions: vec![Precision::F32],
            ..Configs::default()
        },
        coarse_from: None,
    };
    let (_lock, mut r) = renderer();
    let calls = std::cell::Cell::new(0u64);
    let report = run_accuracy(r.renderer().unwrap(), &image, &opts, &|p| {
        assert!(p.done <= p.total, "{} > {}", p.done, p.total);
        calls.set(calls.get() + 1);
    })
    .expect("accuracy run");
    assert_eq!(
        calls.get(),
        12,
        "progress before and after each of 6 configurations"
    );
    report
}

fn row(report: &AccuracyReport, sigma: f64, scheme: Scheme) -> &AccuracyRow {
    report
        .rows
        .iter()
        .find(|r| r.sigma_ref == sigma && r.scheme == scheme)
        .unwrap_or_else(|| panic!("no row for {scheme} σ={sigma}"))
}

#[test]
fn matched_reaches_the_scale_and_the_literal_invariant_does_not() {
    let report = small_report();
    eprint!("{}", report::accuracy_table(&report));
    assert_eq!(report.rows.len(), 6);
    for r in report.rows.iter().filter(|r| r.sigma_ref == 1.0) {
        assert_eq!(r.steps, 0, "{:?}", r.scheme);
        assert!(r.note.as_deref().unwrap().starts_with("N = 0"), "{r:?}");
        assert!((r.scale_ratio - 1.0).abs() < 1e-9 && r.rms < 1e-6, "{r:?}");
    }
    assert!(
        report.rows.iter().all(|r| !r.diverged),
        "f32 never diverges"
    );
    let matched = row(&report, 3.0, Scheme::Matched);
    let invariant = row(&report, 3.0, Scheme::Invariant);
    let euler = row(&report, 3.0, Scheme::Euler);
    // Tolerances: matched's variance is exact by construction (2 % leaves room for
    // f32 rounding of the offsets); the literal scheme misses by about 8 % at σ = 3.
    assert!((matched.scale_ratio - 1.0).abs() < 0.02, "{matched:?}");
    assert!(invariant.scale_ratio < 0.97, "{invariant:?}");
    assert!((euler.scale_ratio - 1.0).abs() < 0.01, "{euler:?}");
    let (m, i) = (
        matched.rms_interior.unwrap(),
        invariant.rms_interior.unwrap(),
    );
    assert!(m < i, "matched interior RMS {m} vs invariant {i}");
    assert_eq!(matched.interior_margin, 9);
}

#[test]
fn json_and_csv_parse() {
    let report = small_report();
    let json: serde_json::Value =
        serde_json::from_str(&report::accuracy_json(&report).unwrap()).expect("valid JSON");
    assert_eq!(json["benchmark"], "accuracy");
    assert_eq!(
        (&json["brume"], &json["sources"]),
        (&brume::VERSION.into(), &brume::SOURCES.into())
    );
    assert_eq!(json["width"], 64);
    assert!(json["renderer"].as_str().is_some_and(|s| !s.is_empty()));
    let rows = json["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 6);
    for key in [
        "sigma_ref",
        "scheme",
        "precision",
        "steps",
        "rms",
        "rms_interior",
    ] {
        assert!(rows[3].get(key).is_some(), "JSON row lacks {key}");
    }
    assert_eq!(rows[0]["scheme"], "euler");
    assert_eq!(rows[0]["precision"], "f32");

    let csv = report::accuracy_csv(&report);
    let lines: Vec<Vec<String>> = csv.lines().map(split_csv).collect();
    assert_eq!(lines.len(), 7, "header + 6 rows");
    assert!(lines.iter().all(|l| l.len() == lines[0].len()), "{csv}");
    let col = |name: &str| lines[0].iter().position(|h| h == name).unwrap();
    let ratio: f64 = lines[6][col("scale_ratio")].parse().unwrap();
    assert_eq!(lines[6][col("scheme")], "matched");
    assert!((ratio - report.rows[5].scale_ratio).abs() < 1e-12);
}

#[test]
fn plots_are_written_whole_or_not_at_all() {
    let report = small_report();
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("fig6.png");
    plot::plot_accuracy(&report, &png).expect("PNG plot");
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let svg = dir.path().join("fig6.svg");
    plot::plot_accuracy(&report, &svg).expect("SVG plot");
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains("<svg") && text.contains("σref"), "SVG text");

    let missing = dir.path().join("no-such-dir").join("fig6.png");
    assert!(plot::plot_accuracy(&report, &missing).is_err());
    let wrong = dir.path().join("fig6.jpg");
    let err = plot::plot_accuracy(&report, &wrong)
        .unwrap_err()
        .to_string();
    assert!(err.contains("invalid plot = "), "{err}");
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(
        names.len(),
        2,
        "only the two plots, no temporary: {names:?}"
    );
}

/// Splits one CSV line, honouring RFC 4180 quotes.
fn split_csv(line: &str) -> Vec<String> {
    let (mut cells, mut cell, mut quoted) = (Vec::new(), String::new(), false);
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cell.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => cells.push(std::mem::take(&mut cell)),
            _ => cell.push(c),
        }
    }
    cells.push(cell);
    cells
}
