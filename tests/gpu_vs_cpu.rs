//! The GPU pipeline against the f64 CPU reference: the same schedule, the same arithmetic.
//!
//! Tolerances are per-pass rounding budgets on values in [0, 1], accumulated linearly
//! over the N + 2 passes (worst case, no cancellation assumed):
//! - f32: 4e-7 per pass (a few f32 ulps at 1.0, 2^-23 ≈ 1.2e-7, for the texture
//!   write, the bilinear lerp and the sum of four fluxes). llvmpipe filters float
//!   textures with full-precision weights; measured errors are 10-40x below the budget.
//! - f16: one half-float ulp at 1.0 (2^-11 ≈ 4.9e-4) per pass: every pass rounds its
//!   output to 11 significant bits, and the rate texture is R16F too. Measured: 2e-3
//!   after 8 steps, 3e-2 after 96 Euler steps (the paper's f16 Euler drift).
use crate::common;

use brume::raster::{Grid, RgbImage, ScalarMap};
use brume::reference;
use brume::{Blur, Haze, Medium, Precision, Scheme, UniformBlur};
use common::*;

const F32_PER_PASS: f64 = 4e-7;
const F16_PER_PASS: f64 = 4.9e-4;

fn tolerance(precision: Precision, steps: u32) -> f64 {
    let per_pass = match precision {
        Precision::F32 => F32_PER_PASS,
        Precision::F16 => F16_PER_PASS,
    };
    per_pass * f64::from(steps + 2)
}

/// Renders on both sides and asserts the largest difference is within the budget.
fn assert_gpu_matches_cpu(image: &RgbImage, range: &ScalarMap, medium: &dyn Medium, blur: &Blur) {
    let (_lock, mut r) = renderer();
    let gpu = r.render(image, range, medium, blur).expect("GPU render");
    let cpu = reference::render(image, range, medium, blur).expect("CPU render");
    let e = reference::rgb_error(&gpu.image, &cpu, 0);
    let tol = tolerance(blur.precision, gpu.schedule.steps);
    eprintln!(
        "{} {} {} N={} rms {:.2e} max {:.2e} (tolerance {:.2e})",
        medium.name(),
        blur.scheme,
        blur.precision,
        gpu.schedule.steps,
        e.rms,
        e.max_abs,
        tol
    );
    assert!(gpu.image.as_slice().iter().flatten().all(|v| v.is_finite()));
    assert!(
        e.max_abs <= tol,
        "{} {}: {e:?} > {tol}",
        blur.scheme,
        blur.precision
    );
}

/// Every scheme with every precision.
fn every_blur() -> impl Iterator<Item = Blur> {
    Precision::ALL
        .into_iter()
        .flat_map(|p| Scheme::ALL.into_iter().map(move |s| Blur::new(s, p)))
}

#[test]
fn haze_matches_reference_for_every_scheme_and_precision() {
    let (w, h) = (48, 40);
    let image = noise_image(w, h, 7);
    let range = ramp_range(w, h);
    let haze = Haze {
        lambda: 6.0,
        ..Haze::default()
    };
    for blur in every_blur() {
        assert_gpu_matches_cpu(&image, &range, &haze, &blur);
    }
}

/// A chromatic medium: each channel's τ is blurred with its colour (the second target of
/// the pipeline), and the composite uses each channel's blurred τ.
#[test]
fn chromatic_haze_matches_reference_for_every_scheme_and_precision() {
    let (w, h) = (48, 40);
    let image = noise_image(w, h, 11);
    let range = ramp_range(w, h);
    let haze = Haze {
        lambda: 6.0,
        ka: 0.5,
        ks: 1.5,
        tint: [0.6, 1.0, 1.8],
        airlight: [0.7, 0.8, 0.95],
        ..Haze::default()
    };
    assert!(haze.chromatic());
    for blur in every_blur() {
        assert_gpu_matches_cpu(&image, &range, &haze, &blur);
    }
}

/// The chromatic path is not a different model: a tint whose channels differ by a hair
/// renders what the grey path renders, up to that hair.
#[test]
fn nearly_grey_tint_renders_like_grey() {
    let (w, h) = (40, 32);
    let image = noise_image(w, h, 5);
    let range = ramp_range(w, h);
    let grey = Haze::default();
    let tinted = Haze {
        tint: [1.0, 1.0, 1.0 + 1e-6],
        ..grey
    };
    assert!(tinted.chromatic() && !grey.chromatic());
    let (_lock, mut r) = renderer();
    let blur = Blur::default();
    let a = r.render(&image, &range, &grey, &blur).unwrap().image;
    let b = r.render(&image, &range, &tinted, &blur).unwrap().image;
    let e = reference::rgb_error(&a, &b, 0);
    assert!(e.max_abs < 1e-5, "{e:?}");
}

#[test]
fn uniform_blur_matches_reference() {
    let (w, h) = (40, 33);
    let image = noise_image(w, h, 3);
    let range = Grid::filled(w, h, 0.0f32);
    for blur in every_blur().filter(|b| b.scheme != Scheme::Euler) {
        assert_gpu_matches_cpu(&image, &range, &UniformBlur::new(6.5), &blur);
    }
}

/// The driver's extensions, read here from `GL_EXTENSIONS` one by one (`glGetStringi`),
/// not through brume's `Capabilities`.
fn gl_extensions(h: &brume::Headless) -> Vec<String> {
    use glow::HasContext;
    h.context()
        .make_current()
        .expect("make the context current");
    let gl = h.context().gl();
    // SAFETY: state queries on the context made current just above.
    unsafe {
        let n = gl.get_parameter_i32(glow::NUM_EXTENSIONS).max(0) as u32;
        (0..n)
            .map(|i| gl.get_parameter_indexed_string(glow::EXTENSIONS, i))
            .collect()
    }
}

#[test]
fn pass_count_and_timings_are_reported() {
    use brume::gpu::timer::Clock;
    use std::time::Instant;
    let (w, h) = (32, 24);
    let image = noise_image(w, h, 1);
    let range = ramp_range(w, h);
    let (_lock, mut r) = renderer();
    // llvmpipe offers timer queries; a driver without them is a failure here, not a skip,
    // so that the GPU-timer path is proven wherever this test runs.
    let extensions = gl_extensions(&r);
    assert!(
        extensions
            .iter()
            .any(|e| e == "GL_EXT_disjoint_timer_query"),
        "the driver ({}) lacks GL_EXT_disjoint_timer_query: the GPU-timer path cannot be \
         tested; extensions: {extensions:?}",
        r.caps().renderer
    );
    // The first render on a fresh context is the one whose first TIME_ELAPSED query
    // llvmpipe gets wrong (src/gpu/timer.rs spends one at start-up); the second reuses
    // the pooled queries.
    for render in ["first", "second"] {
        let start = Instant::now();
        let out = r
            .render(&image, &range, &Haze::default(), &Blur::default())
            .unwrap();
        let wall_ms = start.elapsed().as_secs_f64() * 1e3;
        let t = &out.times;
        eprintln!(
            "{render} render: {:?} passes {:?} ms (sum {:.3} ms) inside {wall_ms:.3} ms of \
             wall time",
            t.clock, t.pass_ms, t.total_ms
        );
        // With the extension, figures come from the GPU timer: a batch is timed again by
        // the wall clock only when its figures were rejected (disjoint or implausible),
        // which must not happen on a quiet 32x24 render.
        assert_eq!(t.clock, Clock::GpuTimer, "{render} render: {t:?}");
        assert_eq!(t.pass_ms.len() as u32, out.schedule.steps + 2);
        // Each pass did work (a full-screen triangle over 768 pixels): a positive figure,
        // and one pass cannot take longer than the whole call around it (uploads,
        // compilation, read-back included).
        for (i, ms) in t.pass_ms.iter().enumerate() {
            assert!(
                ms.is_finite() && *ms > 0.0 && *ms < wall_ms,
                "{render} render, pass {i}: {ms} ms (wall time {wall_ms} ms)"
            );
        }
    }
}

#[test]
fn near_pixels_stay_sharp_and_far_pixels_fade_to_airlight() {
    let (w, h) = (40, 30);
    let image = noise_image(w, h, 9);
    // Left half at range 0 (σ = σ0, τ = 1), right half at range 1.
    let range = Grid::from_fn(w, h, |x, _| if x < w / 2 { 0.0 } else { 1.0 });
    // σmax = 3 px: the checked pixels lie > 5σmax from the depth edge, where flux from
    // the other half (eq. 12 averages rates across it) has died out.
    let haze = Haze {
        ka: 3.0,
        ks: 1.0,
        lambda: 2.0,
        ..Haze::default()
    };
    let (_lock, mut r) = renderer();
    let out = r
        .render(&image, &range, &haze, &Blur::default())
        .unwrap()
        .image;
    // Deep inside the near half nothing changes: zero rate and τ = 1.
    let p = out.get(2, 15);
    let q = image.get(2, 15);
    for c in 0..3 {
        assert!(
            (p[c] - q[c]).abs() < 1e-6,
            "near pixel changed: {p:?} vs {q:?}"
        );
    }
    // Deep inside the far half, τ = e^-4 ≈ 0.018: the airlight dominates.
    let far = out.get(w - 3, 15);
    for c in 0..3 {
        assert!(
            (far[c] - haze.airlight[c]).abs() < 0.05,
            "far pixel {far:?}"
        );
    }
}

#[test]
fn real_aloe_crop_matches_reference() {
    use brume::io::{depth, image};
    let full = image::load_linear_rgb(&aloe_path("left.jpg"))
        .expect("Aloe image (tests/data/aloe/left.jpg)");
    let disp = depth::load_range(&aloe_path("disparity.png"), &Default::default())
        .expect("Aloe disparity (tests/data/aloe/disparity.png)");
    // A 96x72 window across leaf edges in front of the cloth, with unknown pixels.
    let (x0, y0, w, h) = (560, 420, 96, 72);
    let image = full.crop(x0, y0, w, h);
    let (range, _) = brume::medium::haze::normalise_range(&disp.range.crop(x0, y0, w, h)).unwrap();
    let haze = Haze {
        ka: 1.0,
        ks: 2.0,
        lambda: 3.0,
        ..Haze::default()
    };
    for blur in every_blur() {
        assert_gpu_matches_cpu(&image, &range, &haze, &blur);
    }
}
