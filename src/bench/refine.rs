//! The speed of image-guided refinement (issue 19's target: ≤ 100 ms at 2048 x 1024 on
//! llvmpipe, GPU timer): the guided filter at the image's size, and joint bilateral
//! upsampling of a range 4 and 8 times smaller, of a sawtooth range under a textured image
//! and of the procedural street's true range under its image (sky, receding ground,
//! boxes: what a phone's depth holds, and where most windows are smooth), each `runs`
//! times after one untimed run (llvmpipe compiles a shader at its first draw). The figure
//! is the median of the runs' summed pass times, with the clock; the wall time includes the
//! upload and the read-back.

use crate::error::Result;
use crate::prep::synthetic::street_scene;
use crate::raster::Grid;
use crate::refine::{Refine, DEFAULT_UPSAMPLE_SIGMA_COLOUR};
use crate::renderer::Renderer;
use std::time::Instant;

/// One configuration's figures.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct RefineBenchRow {
    /// `guided filter`, `upsample 1/k` or `upsample 1/k, street`.
    pub what: String,
    /// The range's size (px).
    pub range_size: [usize; 2],
    /// Median of the runs' pass totals (ms).
    pub median_ms: f64,
    /// Median wall time of the whole call: upload, passes, read-back (ms).
    pub median_wall_ms: f64,
    /// Passes per run.
    pub passes: usize,
    /// The clock of `median_ms`.
    pub clock: &'static str,
}

/// The whole report.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct RefineBenchReport {
    /// `GL_RENDERER`.
    pub renderer: String,
    /// Image size (px).
    pub size: [usize; 2],
    /// Timed runs per configuration.
    pub runs: usize,
    /// One row per configuration.
    pub rows: Vec<RefineBenchRow>,
}

/// The smallest side the benchmark takes: the procedural street's.
pub const MIN_REFINE_BENCH_SIDE: usize = 64;

/// Runs the benchmark at `width` x `height` (both multiples of 8 work best, each at least
/// [`MIN_REFINE_BENCH_SIDE`]), `runs` timed runs per configuration.
pub fn run_refine_bench(
    renderer: &mut Renderer,
    width: usize,
    height: usize,
    runs: usize,
) -> Result<RefineBenchReport> {
    if width.min(height) < MIN_REFINE_BENCH_SIDE {
        return Err(crate::Error::invalid(
            "size",
            format!("{width}x{height}"),
            format!("an image of at least {MIN_REFINE_BENCH_SIDE}x{MIN_REFINE_BENCH_SIDE} px"),
        ));
    }
    // A street-like frame: a bright sky, a dark road, textured façades.
    let image = Grid::from_fn(width, height, |x, y| {
        let t = ((x * 7 + y * 13) % 17) as f32 / 17.0;
        if y < height / 3 {
            [0.7, 0.75, 0.85]
        } else {
            [0.2 + 0.3 * t, 0.2 + 0.2 * t, 0.15]
        }
    });
    let range_at = |w: usize, h: usize| {
        Grid::from_fn(w, h, |x, y| {
            if y < h / 3 {
                600.0
            } else {
                5.0 + 200.0 * (1.0 - y as f32 / h as f32) + (x % 9) as f32
            }
        })
    };
    let mut rows = Vec::new();
    let full = range_at(width, height);
    rows.push(time_runs(runs, "guided filter", &full, || {
        renderer.refine(&image, &full, &Refine::default())
    })?);
    for k in [4usize, 8] {
        let low = range_at(width / k, height / k);
        let what = format!("upsample 1/{k}");
        rows.push(time_runs(runs, &what, &low, || {
            renderer.upsample(&image, &low, DEFAULT_UPSAMPLE_SIGMA_COLOUR)
        })?);
    }
    let street = street_scene(width, height, 1);
    // The sky and the wire, which have no range, as far as pre-processing puts the sky.
    let sky = 3.0 * street.scene_max;
    for k in [4usize, 8] {
        let low = Grid::from_fn(width / k, height / k, |x, y| {
            let v = *street.truth.get(k * x + k / 2, k * y + k / 2);
            if v.is_finite() {
                v
            } else {
                sky
            }
        });
        let what = format!("upsample 1/{k}, street");
        rows.push(time_runs(runs, &what, &low, || {
            renderer.upsample(&street.image, &low, DEFAULT_UPSAMPLE_SIGMA_COLOUR)
        })?);
    }
    Ok(RefineBenchReport {
        renderer: renderer.caps().renderer.clone(),
        size: [width, height],
        runs,
        rows,
    })
}

fn time_runs(
    runs: usize,
    what: &str,
    range: &crate::raster::ScalarMap,
    mut run: impl FnMut() -> Result<(crate::raster::ScalarMap, crate::gpu::timer::PassTimes)>,
) -> Result<RefineBenchRow> {
    run()?; // warm-up: shader compilation
    let (mut gpu, mut wall) = (Vec::new(), Vec::new());
    let (mut passes, mut clock) = (0, "");
    for _ in 0..runs {
        let t = Instant::now();
        let (_, times) = run()?;
        wall.push(t.elapsed().as_secs_f64() * 1e3);
        // A run whose GPU-timer figures were rejected is left out of the median.
        if let Some(ms) = times.total() {
            gpu.push(ms);
            passes = times.pass_ms.len();
            clock = times.clock.name();
        }
    }
    Ok(RefineBenchRow {
        what: what.to_string(),
        range_size: [range.width(), range.height()],
        median_ms: super::speed::median(&gpu).unwrap_or(f64::NAN),
        median_wall_ms: super::speed::median(&wall).unwrap_or(f64::NAN),
        passes,
        clock,
    })
}

/// The report as a text table.
pub fn refine_table(report: &RefineBenchReport) -> String {
    let mut out = format!(
        "refinement at {}x{} on {}, median of {} runs\n{:<22} {:>10} {:>7} {:>12} {:>14}\n",
        report.size[0],
        report.size[1],
        report.renderer,
        report.runs,
        "what",
        "range",
        "passes",
        "passes (ms)",
        "wall (ms)"
    );
    for r in &report.rows {
        out.push_str(&format!(
            "{:<22} {:>10} {:>7} {:>9.1} {:<2} {:>14.1}\n",
            r.what,
            format!("{}x{}", r.range_size[0], r.range_size[1]),
            r.passes,
            r.median_ms,
            if r.clock == "gpu-timer" { "G" } else { "W" },
            r.median_wall_ms
        ));
    }
    out.push_str("(G: GPU timer, W: wall clock around each pass)\n");
    out
}
