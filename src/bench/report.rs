//! Text tables, CSV and JSON for the two benchmarks (`io::output::write_bytes` writes
//! them). A table states what a figure needs to be read (GL_RENDERER, clock, size) and no
//! date, so that two runs can be diffed.

use super::accuracy::{AccuracyReport, AccuracyRow};
use super::speed::{SpeedReport, SpeedRow};
use crate::error::{Error, Result};
use serde::Serialize;
use std::fmt::Write as _;

/// The accuracy report as a readable table (one line per configuration).
pub fn accuracy_table(report: &AccuracyReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "brume bench accuracy: {} | image {}x{} | σ0 = {} px, ρmax = {}",
        report.renderer, report.width, report.height, report.sigma0, report.rho_max
    );
    let _ = writeln!(
        s,
        "error vs exact Gaussian of std √(σref² − σ0²), clamp-to-edge, linear RGB; \
         interior leaves ⌈3σref⌉ px out;\nscale reached = √(var + σ0²) of an impulse \
         response (x, y); ratio = scale / σref"
    );
    let _ = writeln!(
        s,
        "{:>6} {:<9} {:<4} {:>5} {:>10} {:>10} {:>10} {:>15} {:>7}  status",
        "σref", "scheme", "prec", "N", "rms", "rms int", "max|err|", "scale x, y", "ratio"
    );
    for r in &report.rows {
        let _ = writeln!(s, "{}", accuracy_line(r));
    }
    s
}

fn accuracy_line(r: &AccuracyRow) -> String {
    format!(
        "{:>6} {:<9} {:<4} {:>5} {:>10} {:>10} {:>10} {:>15} {:>7.4}  {}",
        r.sigma_ref,
        r.scheme.name(),
        r.precision.name(),
        r.steps,
        sci(Some(r.rms)),
        sci(r.rms_interior),
        sci(Some(r.max_abs)),
        format!("{:.3}, {:.3}", r.scale_x, r.scale_y),
        r.scale_ratio,
        accuracy_status(r),
    )
}

fn accuracy_status(r: &AccuracyRow) -> String {
    match (&r.note, r.diverged) {
        (_, true) => "DIVERGED".into(),
        (Some(note), false) => note.clone(),
        (None, false) => "ok".into(),
    }
}

/// The speed report as a readable table, followed by the scheme ratios.
pub fn speed_table(report: &SpeedReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "brume bench speed: {} | {}x{} | clock {} | median of {} runs after 1 warm-up",
        report.renderer, report.width, report.height, report.clock, report.runs
    );
    let _ = writeln!(
        s,
        "{:>6} {:<9} {:<4} {:>5} {:>6} {:>11} {:>9} {:>9} {:<9}  status",
        "σref", "scheme", "prec", "N", "passes", "median ms", "std ms", "ms/pass", "clock"
    );
    for r in &report.rows {
        let _ = writeln!(s, "{}", speed_line(r));
    }
    for q in &report.ratios {
        let _ = writeln!(
            s,
            "{} / {} at σ = {} ({}): {:.1}x",
            q.slow, q.fast, q.sigma_ref, q.precision, q.ratio
        );
    }
    s
}

fn speed_line(r: &SpeedRow) -> String {
    let fixed = |v: Option<f64>, p: usize| v.map_or("-".into(), |v| format!("{v:.p$}"));
    format!(
        "{:>6} {:<9} {:<4} {:>5} {:>6} {:>11} {:>9} {:>9} {:<9}  {}",
        r.sigma_ref,
        r.scheme.name(),
        r.precision.name(),
        r.steps,
        r.passes,
        fixed(r.median_ms, 2),
        fixed(r.std_ms, 2),
        fixed(r.ms_per_pass, 3),
        r.clock.as_deref().unwrap_or("-"),
        r.reason
            .as_deref()
            .map_or("ok".into(), |why| format!("skipped: {why}")),
    )
}

fn sci(v: Option<f64>) -> String {
    v.map_or("-".into(), |v| format!("{v:.3e}"))
}

/// CSV of the accuracy rows (header + one line each; empty cell = no value).
pub fn accuracy_csv(report: &AccuracyReport) -> String {
    let mut s = String::from(
        "sigma_ref,scheme,precision,steps,reference_sigma,rms,rms_interior,interior_margin,\
         max_abs,scale_x,scale_y,scale_ratio,diverged,note\n",
    );
    for r in &report.rows {
        let cells = [
            r.sigma_ref.to_string(),
            r.scheme.name().into(),
            r.precision.name().into(),
            r.steps.to_string(),
            r.reference_sigma.to_string(),
            r.rms.to_string(),
            opt(r.rms_interior),
            r.interior_margin.to_string(),
            r.max_abs.to_string(),
            r.scale_x.to_string(),
            r.scale_y.to_string(),
            r.scale_ratio.to_string(),
            r.diverged.to_string(),
            csv_text(r.note.as_deref().unwrap_or("")),
        ];
        s.push_str(&cells.join(","));
        s.push('\n');
    }
    s
}

/// CSV of the speed rows (header + one line each; empty cell = no value).
pub fn speed_csv(report: &SpeedReport) -> String {
    let mut s = String::from(
        "sigma_ref,scheme,precision,steps,passes,skipped,reason,clock,runs,median_ms,std_ms,\
         ms_per_pass,width,height\n",
    );
    for r in &report.rows {
        let cells = [
            r.sigma_ref.to_string(),
            r.scheme.name().into(),
            r.precision.name().into(),
            r.steps.to_string(),
            r.passes.to_string(),
            r.skipped.to_string(),
            csv_text(r.reason.as_deref().unwrap_or("")),
            r.clock.clone().unwrap_or_default(),
            r.runs.to_string(),
            opt(r.median_ms),
            opt(r.std_ms),
            opt(r.ms_per_pass),
            report.width.to_string(),
            report.height.to_string(),
        ];
        s.push_str(&cells.join(","));
        s.push('\n');
    }
    s
}

fn opt(v: Option<f64>) -> String {
    v.map_or(String::new(), |v| v.to_string())
}

/// Quotes a CSV text cell when it holds a comma, quote or newline (RFC 4180).
fn csv_text(t: &str) -> String {
    if t.contains([',', '"', '\n']) {
        format!("\"{}\"", t.replace('"', "\"\""))
    } else {
        t.to_string()
    }
}

/// A report wrapped with the benchmark's name, so that a JSON reader can tell them apart,
/// and the build of brume that measured it ([`crate::VERSION`], [`crate::SOURCES`]):
/// `{"benchmark": "accuracy", "brume": …, "sources": …, "renderer": …, "rows": […]}`.
#[derive(Serialize)]
struct Tagged<'a, T: Serialize> {
    benchmark: &'static str,
    brume: &'static str,
    sources: &'static str,
    #[serde(flatten)]
    report: &'a T,
}

/// The accuracy report as one JSON object (NaN figures become `null`).
pub fn accuracy_json(report: &AccuracyReport) -> Result<String> {
    to_json("accuracy", report)
}

/// The speed report as one JSON object.
pub fn speed_json(report: &SpeedReport) -> Result<String> {
    to_json("speed", report)
}

fn to_json<T: Serialize>(benchmark: &'static str, report: &T) -> Result<String> {
    serde_json::to_string_pretty(&Tagged {
        benchmark,
        brume: crate::VERSION,
        sources: crate::SOURCES,
        report,
    })
    .map_err(|e| {
        Error::invalid(
            "report",
            "(not serialisable)",
            format!("serialisable data: {e}"),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_text_quotes_only_when_needed() {
        assert_eq!(csv_text("plain"), "plain");
        assert_eq!(csv_text("a, b"), "\"a, b\"");
        assert_eq!(csv_text("say \"x\""), "\"say \"\"x\"\"\"");
    }
}
