//! The engine fogs' speed (papers 001 and 003): brume's procedural scene rendered once at
//! the benchmark's size into a colour and a depth texture, then each fog configuration
//! rendered into a float texture (no read-back) `runs` times after `warm_up` untimed
//! renders, which absorb the driver's shader compilation (llvmpipe compiles a shader
//! variant at its first draw). The figure is the median of the runs' summed pass times,
//! with the clock that produced them; each pass's median is kept too.
//!
//! Then how soon a host's call returns: with timing off ([`Timing::Off`], a host's
//! default) and blocking, a fence placed right after the call tells whether the GPU was
//! still drawing when it returned, and when it finished (wall clock from the call).
//!
//! Paper 002's aerial perspective is measured the same way on the scene's range in metres
//! (its medium reads range, not a depth buffer); the paper's target is ≤ 30 ms at
//! 1920 x 1080.
//!
//! Paper 001 reports 0.20 ms (fog) and 0.44 ms (fog and 5 x 5 blur in one pass) at
//! 1920 x 1080 on a GTX 970; paper 003 0.4-2.1 ms at 512²-1024² on a GeForce 6800.

use crate::atmosphere::AttenuationTable;
use crate::blur::Blur;
use crate::camera::{Camera, FrameInputs};
use crate::error::{Error, Result};
use crate::gpu::texture::{Filter, TexelFormat, Texture};
use crate::gpu::timer::Timing;
use crate::medium::{AerialPerspective, DistanceFog, LayeredFog, Medium};
use crate::pipeline::{Encoding, FogBlur, GaussBlur, Input, Output};
use crate::raster::{Grid, ScalarMap};
use crate::renderer::Renderer;
use crate::scene::SceneRenderer;
use std::sync::Arc;

/// Timed runs per configuration by default (the "median of 5").
pub const DEFAULT_RUNS: usize = 5;
/// Untimed renders before the timed ones.
pub const DEFAULT_WARM_UP: usize = 2;

/// What to measure.
#[derive(Clone, Debug, PartialEq)]
pub struct FogBenchOptions {
    /// Frame width (px).
    pub width: usize,
    /// Frame height (px).
    pub height: usize,
    /// Timed runs per configuration (≥ 1).
    pub runs: usize,
    /// Untimed renders first.
    pub warm_up: usize,
}

impl Default for FogBenchOptions {
    fn default() -> Self {
        FogBenchOptions {
            width: 1920,
            height: 1080,
            runs: DEFAULT_RUNS,
            warm_up: DEFAULT_WARM_UP,
        }
    }
}

/// One configuration's figures.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FogBenchRow {
    /// The fog and its features, e.g. `distance + noise + scatter`.
    pub fog: &'static str,
    /// `none`, `gauss-single`, `gauss-separate`, `diffusion` or `blend` (paper 003's
    /// fixed-function blending over the host's frame).
    pub blur: &'static str,
    /// Median of the runs' totals (ms).
    pub median_ms: f64,
    /// Every run's total (ms), in order.
    pub runs_ms: Vec<f64>,
    /// Pass names, in order.
    pub passes: Vec<String>,
    /// Median time of each pass (ms).
    pub pass_median_ms: Vec<f64>,
    /// `gpu-timer` or `wall`; `mixed`, or `n/a` when every run's figures were rejected
    /// (those runs are left out of the medians).
    pub clock: &'static str,
}

/// The whole benchmark.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FogBenchReport {
    /// `GL_RENDERER`.
    pub renderer: String,
    /// Frame width (px).
    pub width: usize,
    /// Frame height (px).
    pub height: usize,
    /// Timed runs per configuration.
    pub runs: usize,
    /// Time to render the scene itself once, warm (ms, wall clock with `glFinish`).
    pub scene_ms: f64,
    /// One row per configuration.
    pub rows: Vec<FogBenchRow>,
    /// How soon a call returns, by timing option.
    pub returns: Vec<ReturnRow>,
}

/// How soon a host's call returns with one timing option, and when the GPU is done: a
/// fence placed right after the call, waited for (medians over the runs, wall clock from
/// the call, the GPU idle before it).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ReturnRow {
    /// The configuration.
    pub what: &'static str,
    /// `off` or `blocking`.
    pub timing: &'static str,
    /// Until the call returned (ms).
    pub return_ms: f64,
    /// Until the fence placed at the return signalled (ms).
    pub done_ms: f64,
    /// Runs in which the fence had not signalled when the call returned: the GPU was
    /// still drawing.
    pub pending_at_return: usize,
    /// Runs.
    pub runs: usize,
}

/// How a configuration is drawn.
enum Mode {
    Fog(FogBlur),
    Blend,
}

/// Runs every configuration (module docs). `progress` is told each configuration's name
/// before it runs.
pub fn run_fog_bench(
    renderer: &mut Renderer,
    opts: &FogBenchOptions,
    progress: &dyn Fn(usize, usize, &str),
) -> Result<FogBenchReport> {
    if opts.runs == 0 {
        return Err(Error::invalid("runs", 0, "at least 1 timed run"));
    }
    let (w, h) = (opts.width, opts.height);
    renderer.caps().require_size("frame", w, h)?;
    let renderer_name = renderer.caps().renderer.clone();
    let pipeline = renderer.pipeline();
    let gl = Arc::clone(pipeline.gl());
    let camera = Camera::default();
    let mut scene = SceneRenderer::new(Arc::clone(&gl))?;
    scene.render(&camera, w, h, 0.0)?;
    let started = std::time::Instant::now();
    let frame = scene.render(&camera, w, h, 0.0)?;
    // SAFETY: waiting for the scene's draws on the current context, to time them.
    unsafe { glow::HasContext::finish(&*gl) };
    let scene_ms = started.elapsed().as_secs_f64() * 1e3;
    let input = Input {
        colour: frame.colour,
        colour_encoding: Encoding::Linear,
        depth: frame.depth,
        width: w,
        height: h,
        frame: FrameInputs::new(camera, 0.0),
    };
    let target = Texture::new(&gl, w, h, TexelFormat::Rgba16F, Filter::Nearest, None)?;
    let output = Output::Texture {
        texture: target.raw(),
        encoding: Encoding::Linear,
    };

    let distance = DistanceFog::default();
    let layered = LayeredFog::for_camera(camera, Default::default());
    // Paper 002's medium reads range, not a depth buffer: the scene's, in metres.
    let range = Texture::new(
        &gl,
        w,
        h,
        TexelFormat::R32F,
        Filter::Nearest,
        Some(scene_range(&frame, &camera)?.as_slice()),
    )?;
    let range_input = Input {
        depth: range.raw(),
        ..input
    };
    let aerial = scene_aerial(camera)?;
    let gauss = GaussBlur::default();
    let diffusion = Blur::default();
    let configs: Vec<(&'static str, &dyn Medium, Mode)> = vec![
        (
            "distance + noise + scatter",
            &distance,
            Mode::Fog(FogBlur::None),
        ),
        (
            "distance + noise + scatter",
            &distance,
            Mode::Fog(FogBlur::GaussSingle(gauss)),
        ),
        (
            "distance + noise + scatter",
            &distance,
            Mode::Fog(FogBlur::GaussSeparate(gauss)),
        ),
        (
            "distance + noise + scatter",
            &distance,
            Mode::Fog(FogBlur::Diffusion(diffusion)),
        ),
        ("layered (exponential)", &layered, Mode::Fog(FogBlur::None)),
        ("layered (exponential)", &layered, Mode::Blend),
        (
            "layered (exponential)",
            &layered,
            Mode::Fog(FogBlur::Diffusion(diffusion)),
        ),
        (AERIAL, &aerial, Mode::Fog(FogBlur::None)),
    ];
    let mut rows = Vec::new();
    for (i, (fog, medium, mode)) in configs.iter().enumerate() {
        let blur = match mode {
            Mode::Fog(b) => b.name(),
            Mode::Blend => "blend",
        };
        progress(i, configs.len(), &format!("{fog}, {blur}"));
        let mut times = Vec::new();
        let mut passes = Vec::new();
        let input = if *fog == AERIAL { &range_input } else { &input };
        for run in 0..opts.warm_up + opts.runs {
            let frame = match mode {
                Mode::Fog(b) => {
                    let f = pipeline.fog(input, *medium, b, &output)?;
                    passes = f.pass_names();
                    f
                }
                Mode::Blend => {
                    let f =
                        pipeline.blend_fog(input.depth, w, h, *medium, &input.frame, &output)?;
                    passes = f.pass_names();
                    f
                }
            };
            if run >= opts.warm_up {
                times.push(frame.times);
            }
        }
        rows.push(row(fog, blur, passes, &times));
    }
    let mut returns = Vec::new();
    let before = pipeline.timing();
    for (what, medium, mode) in [
        (
            "distance, diffusion",
            &distance as &dyn Medium,
            Mode::Fog(FogBlur::Diffusion(diffusion)),
        ),
        ("distance, no blur", &distance, Mode::Fog(FogBlur::None)),
        ("layered, blend", &layered, Mode::Blend),
    ] {
        progress(
            configs.len(),
            configs.len(),
            &format!("return time, {what}"),
        );
        for timing in [Timing::Off, Timing::Blocking] {
            pipeline.set_timing(timing);
            let mut call = || -> Result<()> {
                match &mode {
                    Mode::Fog(b) => pipeline.fog(&input, medium, b, &output).map(drop),
                    Mode::Blend => pipeline
                        .blend_fog(input.depth, w, h, medium, &input.frame, &output)
                        .map(drop),
                }
            };
            let (mut returned, mut done, mut pending) = (Vec::new(), Vec::new(), 0);
            for _ in 0..opts.runs {
                // SAFETY: glFinish on the current context: the GPU is idle before the call.
                unsafe { glow::HasContext::finish(&*gl) };
                let start = std::time::Instant::now();
                call()?;
                returned.push(start.elapsed().as_secs_f64() * 1e3);
                // SAFETY: a fence on the current context, waited for and deleted.
                let was_pending = unsafe { wait_for_fence(&gl)? };
                done.push(start.elapsed().as_secs_f64() * 1e3);
                pending += usize::from(was_pending);
            }
            returns.push(ReturnRow {
                what,
                timing: timing.name(),
                return_ms: median(returned),
                done_ms: median(done),
                pending_at_return: pending,
                runs: opts.runs,
            });
        }
    }
    pipeline.set_timing(before);
    Ok(FogBenchReport {
        renderer: renderer_name,
        width: w,
        height: h,
        runs: opts.runs,
        scene_ms,
        rows,
        returns,
    })
}

/// The name of paper 002's row.
const AERIAL: &str = "aerial perspective (T 3)";

/// The scene's range in metres, row 0 at the bottom as GL stores it: each pixel's ray
/// (of unit length along the view axis) times the eye depth of its window depth.
fn scene_range(frame: &crate::scene::SceneFrame, camera: &Camera) -> Result<ScalarMap> {
    let depth = frame.read_depth()?;
    let (w, h) = (depth.width(), depth.height());
    Ok(Grid::from_fn(w, h, |x, y| {
        let ray = camera.pixel_ray(x, y, w, h).length();
        (ray * camera.eye_depth(f64::from(*depth.get(x, y)))) as f32
    }))
}

/// Paper 002's aerial perspective at turbidity 3 through `camera`, its table over the
/// scene's far plane, a pale horizon, no blur: what `brume render --medium aerial` draws.
fn scene_aerial(camera: Camera) -> Result<AerialPerspective> {
    let sensitivity = crate::atmosphere::Sensitivity::cie_srgb();
    let table = AttenuationTable::new(&sensitivity, 3.0, 0.0, camera.far)?;
    Ok(AerialPerspective::new(
        Arc::new(table),
        camera,
        [0.8, 0.85, 0.9],
    ))
}

/// Places a fence after the commands issued so far and waits for it; returns whether it
/// had not signalled yet when placed (the GPU was still working).
///
/// # Safety
/// A context is current on this thread.
unsafe fn wait_for_fence(gl: &glow::Context) -> Result<bool> {
    use glow::HasContext;
    let fence = gl
        .fence_sync(glow::SYNC_GPU_COMMANDS_COMPLETE, 0)
        .map_err(Error::Gl)?;
    let pending = gl.client_wait_sync(fence, 0, 0) == glow::TIMEOUT_EXPIRED;
    loop {
        match gl.client_wait_sync(fence, glow::SYNC_FLUSH_COMMANDS_BIT, 100_000_000) {
            glow::TIMEOUT_EXPIRED => continue,
            glow::WAIT_FAILED => {
                gl.delete_sync(fence);
                return Err(Error::Gl("waiting for a fence: GL_WAIT_FAILED".into()));
            }
            _ => break,
        }
    }
    gl.delete_sync(fence);
    Ok(pending)
}

fn row(
    fog: &'static str,
    blur: &'static str,
    passes: Vec<String>,
    times: &[crate::gpu::timer::PassTimes],
) -> FogBenchRow {
    // Runs whose GPU-timer figures were rejected are left out (never run again).
    let times: Vec<&crate::gpu::timer::PassTimes> =
        times.iter().filter(|t| t.is_available()).collect();
    let runs_ms: Vec<f64> = times.iter().map(|t| t.total_ms).collect();
    let pass_median_ms = (0..passes.len())
        .map(|p| {
            median(
                times
                    .iter()
                    .filter_map(|t| t.pass_ms.get(p).copied())
                    .collect(),
            )
        })
        .collect();
    let clock = match times.first() {
        Some(first) if times.iter().all(|t| t.clock == first.clock) => first.clock.name(),
        Some(_) => "mixed",
        None => "n/a",
    };
    FogBenchRow {
        fog,
        blur,
        median_ms: median(runs_ms.clone()),
        runs_ms,
        passes,
        pass_median_ms,
        clock,
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    }
}

/// The report as a text table.
pub fn fog_table(report: &FogBenchReport) -> String {
    let mut out = format!(
        "engine fog at {}x{} on {}, median of {} runs (scene itself: {:.1} ms)\n",
        report.width, report.height, report.renderer, report.runs, report.scene_ms
    );
    out.push_str(&format!(
        "{:<28} {:<15} {:>10} {:>7}  {}\n",
        "fog", "blur", "median ms", "passes", "clock"
    ));
    for r in &report.rows {
        out.push_str(&format!(
            "{:<28} {:<15} {:>10.2} {:>7}  {}\n",
            r.fog,
            r.blur,
            r.median_ms,
            r.passes.len(),
            r.clock
        ));
    }
    out.push_str(&format!(
        "\nhow soon a call returns (fence after it; median ms from the call)\n{:<22} {:<9} {:>10} {:>12} {:>18}\n",
        "fog", "timing", "returned", "GPU done", "GPU busy at return"
    ));
    for r in &report.returns {
        out.push_str(&format!(
            "{:<22} {:<9} {:>10.2} {:>12.2} {:>12}/{} runs\n",
            r.what, r.timing, r.return_ms, r.done_ms, r.pending_at_return, r.runs
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
        assert!(median(vec![]).is_nan());
    }
}
