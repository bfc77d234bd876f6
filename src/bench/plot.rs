//! Figures 6 and 7 of paper 000 with `plotters`, as PNG or SVG.
//!
//! Two panels stacked, as in the paper: Euler on top, the invariant family (literal
//! invariant and matched) below; f32 dark, f16 light. Text is drawn with an embedded
//! DejaVu Sans through `ab_glyph`, so no system font library is needed at run time (and
//! the output does not depend on which fonts a machine has). PNGs are encoded by the
//! `image` crate from plotters' raw RGB buffer, and every file is written atomically.

use super::accuracy::{AccuracyReport, AccuracyRow};
use super::speed::{SpeedReport, SpeedRow};
use crate::error::{Error, Result};
use crate::io::output::write_bytes;
use crate::{Precision, Scheme};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::ops::Range;
use std::path::Path;
use std::sync::Once;

/// DejaVu Sans (Bitstream Vera licence, `assets/fonts/DejaVuSans-LICENSE.txt`).
static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
/// The family name plotters looks up for `("sans-serif", size)`.
const FAMILY: &str = "sans-serif";
/// Figure size (px): two panels of 900 x 450.
const SIZE: (u32, u32) = (900, 900);

/// File format of a plot, from the extension of its path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlotFormat {
    /// `.png`: 8-bit RGB raster.
    Png,
    /// `.svg`: vector, text as `<text>` elements.
    Svg,
}

impl PlotFormat {
    /// `.png` or `.svg` (any case); anything else is an error naming `--plot`.
    pub fn from_path(path: &Path) -> Result<Self> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => Ok(PlotFormat::Png),
            Some("svg") => Ok(PlotFormat::Svg),
            _ => Err(Error::invalid(
                "plot",
                path.display(),
                "a path ending in .png or .svg",
            )),
        }
    }
}

/// Draws fig. 6 (RMS error against σref) to `path`.
pub fn plot_accuracy(report: &AccuracyReport, path: &Path) -> Result<()> {
    write_bytes(path, &accuracy_plot_bytes(report, path)?)
}

/// Draws fig. 7 (time against σref, ±1 std) to `path`.
pub fn plot_speed(report: &SpeedReport, path: &Path) -> Result<()> {
    write_bytes(path, &speed_plot_bytes(report, path)?)
}

/// The file [`plot_accuracy`] would write to `path` (format by its extension), without
/// writing it: for a caller that writes all its outputs together
/// ([`crate::io::output::Outputs`]).
pub fn accuracy_plot_bytes(report: &AccuracyReport, path: &Path) -> Result<Vec<u8>> {
    let title = format!(
        "RMS error vs exact Gaussian, {}x{} ({})",
        report.width, report.height, report.renderer
    );
    render_bytes(path, &AccuracyFigure { report, title })
}

/// The file [`plot_speed`] would write to `path`, without writing it.
pub fn speed_plot_bytes(report: &SpeedReport, path: &Path) -> Result<Vec<u8>> {
    let title = format!(
        "Time of N+2 passes, {}x{}, median of {} ({}, {})",
        report.width, report.height, report.runs, report.clock, report.renderer
    );
    render_bytes(path, &SpeedFigure { report, title })
}

type DrawResult = std::result::Result<(), String>;

/// A figure that can be drawn on any plotters backend (a generic method, which a closure
/// cannot have).
trait Figure {
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> DrawResult;
}

struct AccuracyFigure<'a> {
    report: &'a AccuracyReport,
    title: String,
}

impl Figure for AccuracyFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> DrawResult {
        draw_panels(root, &self.report.rows, &self.title, accuracy_panel::<DB>)
    }
}

struct SpeedFigure<'a> {
    report: &'a SpeedReport,
    title: String,
}

impl Figure for SpeedFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> DrawResult {
        draw_panels(root, &self.report.rows, &self.title, speed_panel::<DB>)
    }
}

/// Draws `figure` on the backend that `path`'s extension asks for; returns the file.
fn render_bytes(path: &Path, figure: &impl Figure) -> Result<Vec<u8>> {
    let format = PlotFormat::from_path(path)?;
    register_font()?;
    let failed = |e: String| Error::io(path, std::io::Error::other(format!("plotting: {e}")));
    let bytes = match format {
        PlotFormat::Png => {
            let mut rgb = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
            let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
            figure.draw(root).map_err(failed)?;
            encode_png(&rgb).map_err(failed)?
        }
        PlotFormat::Svg => {
            let mut svg = String::new();
            let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
            figure.draw(root).map_err(failed)?;
            svg.into_bytes()
        }
    };
    Ok(bytes)
}

fn register_font() -> Result<()> {
    static ONCE: Once = Once::new();
    let mut ok = true;
    ONCE.call_once(|| {
        ok = plotters::style::register_font(FAMILY, FontStyle::Normal, FONT).is_ok();
    });
    if ok {
        Ok(())
    } else {
        Err(Error::invalid(
            "embedded font",
            "DejaVuSans.ttf",
            "a valid TrueType file",
        ))
    }
}

fn encode_png(rgb: &[u8]) -> std::result::Result<Vec<u8>, String> {
    use image::ImageEncoder;
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image(rgb, SIZE.0, SIZE.1, image::ExtendedColorType::Rgb8)
        .map_err(|e| e.to_string())?;
    Ok(out)
}

/// Paper colours: Euler red, invariant blue, matched green; f32 dark, f16 light.
fn colour(scheme: Scheme, precision: Precision) -> RGBColor {
    match (scheme, precision) {
        (Scheme::Euler, Precision::F32) => RGBColor(160, 0, 0),
        (Scheme::Euler, Precision::F16) => RGBColor(245, 130, 120),
        (Scheme::Invariant, Precision::F32) => RGBColor(0, 40, 170),
        (Scheme::Invariant, Precision::F16) => RGBColor(120, 160, 245),
        (Scheme::Matched, Precision::F32) => RGBColor(0, 110, 40),
        (Scheme::Matched, Precision::F16) => RGBColor(120, 205, 120),
    }
}

/// The two panels: Euler on top, the invariant family below.
const PANELS: [(&str, &[Scheme]); 2] = [
    ("Euler (eq. 13)", &[Scheme::Euler]),
    (
        "invariant (eq. 18) and matched",
        &[Scheme::Invariant, Scheme::Matched],
    ),
];

/// A row that lands in one of the two [`PANELS`] at abscissa σref.
trait PanelRow {
    fn sigma_ref(&self) -> f64;
    fn scheme(&self) -> Scheme;
}

impl PanelRow for AccuracyRow {
    fn sigma_ref(&self) -> f64 {
        self.sigma_ref
    }
    fn scheme(&self) -> Scheme {
        self.scheme
    }
}

impl PanelRow for SpeedRow {
    fn sigma_ref(&self) -> f64 {
        self.sigma_ref
    }
    fn scheme(&self) -> Scheme {
        self.scheme
    }
}

/// The panel drawer of one figure: a fn pointer, since the backend type is generic.
type Panel<DB, R> = fn(&DrawingArea<DB, Shift>, &str, &[&R], Range<f64>) -> DrawResult;

/// The layout both figures share (the paper's figs. 6 and 7): a title over two panels,
/// Euler on top and the invariant family below, on one σref axis.
fn draw_panels<DB: DrawingBackend, R: PanelRow>(
    root: DrawingArea<DB, Shift>,
    rows: &[R],
    title: &str,
    panel: Panel<DB, R>,
) -> DrawResult {
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let root = root
        .titled(title, (FAMILY, 18))
        .map_err(|e| e.to_string())?;
    let x_range = sigma_range(rows.iter().map(PanelRow::sigma_ref));
    for (area, (name, schemes)) in root.split_evenly((2, 1)).iter().zip(PANELS) {
        let in_panel: Vec<&R> = rows
            .iter()
            .filter(|r| schemes.contains(&r.scheme()))
            .collect();
        panel(area, name, &in_panel, x_range.clone())?;
    }
    root.present().map_err(|e| e.to_string())
}

fn accuracy_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    name: &str,
    rows: &[&AccuracyRow],
    x_range: Range<f64>,
) -> DrawResult {
    let plottable = |v: f64| v.is_finite() && v > 0.0;
    let values = rows
        .iter()
        .flat_map(|r| [Some(r.rms), r.rms_interior])
        .flatten()
        .filter(|v| plottable(*v));
    let y_range = log_range(values);
    let diverged = rows.iter().filter(|r| r.diverged).count();
    let caption = match diverged {
        0 => format!("{name}: solid = whole image, dashed = interior"),
        n => format!("{name}: solid = whole, dashed = interior ({n} diverged rows)"),
    };
    let mut chart = ChartBuilder::on(area)
        .caption(caption, (FAMILY, 16))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(70)
        .build_cartesian_2d(x_range, y_range.log_scale())
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc("σref (px)")
        .y_desc("RMS error (linear RGB)")
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style((FAMILY, 13))
        .draw()
        .map_err(|e| e.to_string())?;
    for scheme in Scheme::ALL {
        for precision in Precision::ALL {
            let mine: Vec<&&AccuracyRow> = rows
                .iter()
                .filter(|r| r.scheme == scheme && r.precision == precision)
                .collect();
            if mine.is_empty() {
                continue;
            }
            let c = colour(scheme, precision);
            let whole: Vec<(f64, f64)> = mine
                .iter()
                .filter(|r| plottable(r.rms))
                .map(|r| (r.sigma_ref, r.rms))
                .collect();
            let inner: Vec<(f64, f64)> = mine
                .iter()
                .filter_map(|r| Some((r.sigma_ref, r.rms_interior?)))
                .filter(|(_, v)| plottable(*v))
                .collect();
            chart
                .draw_series(LineSeries::new(whole.clone(), c.stroke_width(2)))
                .map_err(|e| e.to_string())?
                .label(format!("{scheme} {precision}"))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                });
            chart
                .draw_series(whole.iter().map(|&p| Circle::new(p, 3, c.filled())))
                .map_err(|e| e.to_string())?;
            chart
                .draw_series(DashedLineSeries::new(inner, 6, 4, c.stroke_width(1)))
                .map_err(|e| e.to_string())?;
        }
    }
    legend(&mut chart)
}

fn speed_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    name: &str,
    rows: &[&SpeedRow],
    x_range: Range<f64>,
) -> DrawResult {
    let top = rows
        .iter()
        .filter_map(|r| Some(r.median_ms? + r.std_ms.unwrap_or(0.0)))
        .fold(0.0, f64::max);
    let skipped = rows.iter().filter(|r| r.skipped).count();
    let caption = match skipped {
        0 => format!("{name}: median ± 1 std"),
        n => format!("{name}: median ± 1 std ({n} over the pass limit, skipped)"),
    };
    let mut chart = ChartBuilder::on(area)
        .caption(caption, (FAMILY, 16))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(70)
        .build_cartesian_2d(x_range, 0.0..(top * 1.1).max(1e-3))
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc("σref (px)")
        .y_desc("time (ms)")
        .label_style((FAMILY, 13))
        .draw()
        .map_err(|e| e.to_string())?;
    for scheme in Scheme::ALL {
        for precision in Precision::ALL {
            let pts: Vec<(f64, f64, f64)> = rows
                .iter()
                .filter(|r| r.scheme == scheme && r.precision == precision)
                .filter_map(|r| Some((r.sigma_ref, r.median_ms?, r.std_ms.unwrap_or(0.0))))
                .collect();
            if pts.is_empty() {
                continue;
            }
            let c = colour(scheme, precision);
            let line = pts.iter().map(|&(x, m, _)| (x, m));
            chart
                .draw_series(LineSeries::new(line, c.stroke_width(2)))
                .map_err(|e| e.to_string())?
                .label(format!("{scheme} {precision}"))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                });
            chart
                .draw_series(pts.iter().map(|&(x, m, s)| {
                    ErrorBar::new_vertical(x, m - s, m, m + s, c.stroke_width(1), 8)
                }))
                .map_err(|e| e.to_string())?;
        }
    }
    legend(&mut chart)
}

fn legend<'a, DB: DrawingBackend + 'a, X: Ranged, Y: Ranged>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
) -> DrawResult {
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FAMILY, 13))
        .draw()
        .map_err(|e| e.to_string())
}

/// 0 … (largest σ + 5 %), so that the last point is not on the frame.
fn sigma_range(sigmas: impl Iterator<Item = f64>) -> Range<f64> {
    let hi = sigmas.fold(1.0, f64::max);
    0.0..hi * 1.05
}

/// A log axis that spans the values with some room, or a default decade span when
/// there is nothing to draw (e.g. every row has N = 0).
fn log_range(values: impl Iterator<Item = f64>) -> Range<f64> {
    let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    if lo.is_finite() && hi > 0.0 {
        lo / 2.0..hi * 2.0
    } else {
        1e-6..1.0
    }
}
