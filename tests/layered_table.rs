//! Paper 003's tabulated height profiles (sec. 3.2) on the GPU: a table sampled from each
//! analytic profile renders the analytic profile's image to within one step of 8-bit
//! sRGB output; an arbitrary table (an inversion layer) matches the f64 CPU reference
//! pixel by pixel; and the CPU reference's transmission along a segment agrees with an
//! independent composite Simpson quadrature of the linearly interpolated rows along the
//! segment's length (not its height, as the table's code integrates).
//!
//! Depth buffers are synthesised from a ground plane with boxes (as tests/layered_fog.rs).
use crate::common;

use brume::camera::{Camera, FrameInputs};
use brume::io::image::linear_to_srgb8;
use brume::medium::{DensityTable, HeightProfile, LayeredFog, Medium};
use brume::raster::{Grid, RgbaImage, ScalarMap};
use brume::{reference, Blur, Precision, Scheme};
use common::*;
use glam::DVec3;

/// The test scene's camera: eye at 1.7 m, looking slightly down (the top rows reach
/// about 500 m up at the far plane).
fn scene_camera() -> Camera {
    Camera {
        position: [0.0, 1.7, 0.0],
        yaw_deg: -4.0,
        pitch_deg: -2.0,
        fov_y_deg: 60.0,
        near: 1.0,
        far: 1000.0,
    }
}

/// A ground plane at y = 0, a near box, a tall block and a far wall; sky at depth 1.
fn depth_buffer(camera: &Camera, w: usize, h: usize) -> ScalarMap {
    let boxes = [
        ([-3.0, 0.0, -8.0], [-1.0, 2.5, -5.0]),
        ([4.0, 0.0, -60.0], [12.0, 15.0, -40.0]),
        ([-60.0, 0.0, -300.0], [-45.0, 80.0, -280.0]),
        ([-400.0, 0.0, -905.0], [150.0, 40.0, -900.0]),
    ];
    Grid::from_fn(w, h, |x, y| {
        let ray = camera.pixel_ray(x, h - 1 - y, w, h);
        let eye = camera.eye();
        let mut best = (ray.y < 0.0).then(|| -eye.y / ray.y);
        for (min, max) in boxes {
            let (min, max) = (DVec3::from_array(min), DVec3::from_array(max));
            if let Some(t) = ray_enters_box(eye, ray, min, max) {
                if !matches!(best, Some(b) if b <= t) {
                    best = Some(t);
                }
            }
        }
        match best {
            Some(t) if t <= camera.far => camera.window_depth(t) as f32,
            _ => 1.0,
        }
    })
}

/// An 8-bit sRGB encoding of a linear image's colour, as the PNG writer does.
fn srgb8(image: &RgbaImage) -> Vec<u8> {
    image
        .as_slice()
        .iter()
        .flat_map(|p| [p[0], p[1], p[2]].map(linear_to_srgb8))
        .collect()
}

/// The analytic profiles at scales a 1 m table resolves (the module docs of
/// `layered::table` give the error law: c·Δ² relative), and the default 5 m band, which
/// needs Δ = 0.25 m, with their spacings.
fn sampled_cases() -> Vec<(&'static str, HeightProfile, f64)> {
    vec![
        ("exponential", HeightProfile::EXPONENTIAL, 1.0),
        (
            "40 m sine band",
            HeightProfile::SineBand {
                density: 0.01,
                base: 0.0,
                thickness: 40.0,
            },
            1.0,
        ),
        ("5 m sine band", HeightProfile::SINE_BAND, 0.25),
        ("linear ramp", HeightProfile::LINEAR_RAMP, 1.0),
    ]
}

/// The error law seen in 8-bit output: a 1 m table of the default 5 m band is off by up to
/// (π/5)²/6 = 6.6 % in F, which shows, while the 0.25 m table above does not.
#[test]
fn a_band_sampled_too_coarsely_shows_in_8bit_output() {
    let (w, h) = (96, 64);
    let camera = scene_camera();
    let depth = depth_buffer(&camera, w, h);
    let image = noise_image(w, h, 3);
    let (_lock, mut r) = renderer();
    let profile = HeightProfile::SINE_BAND;
    let table = DensityTable::sampled(|y| profile.density(y), 0.0, 1000.0, 1.0).unwrap();
    let fog = |p: HeightProfile| LayeredFog {
        lambda: 0.0,
        colour: [0.75, 0.8, 0.85],
        ..LayeredFog::for_camera(camera, p)
    };
    let blur = brume::FogBlur::Diffusion(Blur::default());
    let at = FrameInputs::new(camera, 0.0);
    let analytic = r
        .render_fog(&image, &depth, &fog(profile), &at, &blur)
        .unwrap();
    let tabled = r
        .render_fog(
            &image,
            &depth,
            &fog(HeightProfile::Table(table)),
            &at,
            &blur,
        )
        .unwrap();
    let (a, b) = (srgb8(&analytic.image), srgb8(&tabled.image));
    let steps = a.iter().zip(&b).map(|(x, y)| x.abs_diff(*y)).max().unwrap();
    let linear = reference::rgb_error(&analytic.image, &tabled.image, 0).max_abs;
    eprintln!("5 m band at Δ = 1 m: {steps} 8-bit steps, linear max {linear:.1e}");
    // τ is off by at most e^(−1)·6.6 % = 0.024 (the colours differ from the fog's by < 1).
    assert!(
        steps > 1 && linear <= 0.025,
        "{steps} steps, linear {linear}"
    );
}

#[test]
fn tables_sampled_from_analytic_profiles_render_their_images_to_one_8bit_step() {
    let (w, h) = (96, 64);
    let camera = scene_camera();
    let depth = depth_buffer(&camera, w, h);
    let image = noise_image(w, h, 3);
    let (_lock, mut r) = renderer();
    for (name, profile, spacing) in sampled_cases() {
        let table = DensityTable::sampled(|y| profile.density(y), 0.0, 1000.0, spacing).unwrap();
        assert!(table.on_grid(), "{name}");
        for (lambda, blur) in [
            (0.0, Blur::default()),
            (3.0, Blur::new(Scheme::Matched, Precision::F32)),
        ] {
            let fog = |p: HeightProfile| LayeredFog {
                lambda,
                colour: [0.75, 0.8, 0.85],
                ..LayeredFog::for_camera(camera, p)
            };
            let (at, blur) = (
                FrameInputs::new(camera, 0.0),
                brume::FogBlur::Diffusion(blur),
            );
            let analytic = r
                .render_fog(&image, &depth, &fog(profile.clone()), &at, &blur)
                .unwrap();
            let tabled = r
                .render_fog(
                    &image,
                    &depth,
                    &fog(HeightProfile::Table(table.clone())),
                    &at,
                    &blur,
                )
                .unwrap();
            let (a, b) = (srgb8(&analytic.image), srgb8(&tabled.image));
            let steps = a.iter().zip(&b).map(|(x, y)| x.abs_diff(*y)).max().unwrap();
            let linear = reference::rgb_error(&analytic.image, &tabled.image, 0).max_abs;
            eprintln!(
                "{name} at Δ = {spacing} m, λ = {lambda}: {steps} 8-bit step(s), linear max {linear:.1e}"
            );
            assert!(steps <= 1, "{name} λ = {lambda}: {steps} steps");
            // The table differs: the comparison is not of a frame with itself.
            if profile != HeightProfile::LINEAR_RAMP {
                assert!(linear > 0.0, "{name}: identical frames");
            }
        }
    }
}

/// An inversion: clear air at the ground, a dense layer from 20 to 40 m, thinner above.
fn inversion() -> DensityTable {
    DensityTable::from_rows(&[
        (0.0, 0.002),
        (10.0, 0.003),
        (20.0, 0.03),
        (22.5, 0.05),
        (30.0, 0.045),
        (40.0, 0.01),
        (80.0, 0.001),
        (200.0, 0.0),
    ])
    .unwrap()
}

#[test]
fn table_fog_matches_the_cpu_reference_per_pixel() {
    let (w, h) = (64, 48);
    let camera = scene_camera();
    let depth = depth_buffer(&camera, w, h);
    let image = noise_image(w, h, 21);
    let (_lock, mut r) = renderer();
    // On its lattice, and off it (the grid then smooths the rows over their cells).
    let off_grid =
        DensityTable::from_rows(&[(0.0, 0.04), (0.7, 0.02), (3.0, 0.01), (7.3, 0.0)]).unwrap();
    assert!(!off_grid.on_grid());
    for table in [inversion(), off_grid] {
        let k_max = table.integral(table.heights()[table.heights().len() - 1]);
        let slope = {
            let (hs, ks) = (table.heights(), table.extinction());
            (1..hs.len())
                .map(|i| (ks[i] - ks[i - 1]).abs() / (hs[i] - hs[i - 1]))
                .fold(0.0, f64::max)
        };
        let fog = LayeredFog {
            lambda: 0.0,
            colour: [0.75, 0.8, 0.85],
            ..LayeredFog::for_camera(camera, HeightProfile::Table(table.clone()))
        };
        assert_eq!(fog.name(), "layered_table");
        let at = FrameInputs::new(camera, 0.0);
        let blur = Blur::default();
        let gpu = r
            .render_fog(&image, &depth, &fog, &at, &brume::FogBlur::Diffusion(blur))
            .unwrap();
        let cpu =
            reference::fog(&image, &depth, &fog, &at, &brume::FogBlur::Diffusion(blur)).unwrap();
        let mut worst: f64 = 0.0;
        for y in 0..h {
            for x in 0..w {
                let d = f64::from(*depth.get(x, y));
                let p = camera.world_position(x, h - 1 - y, w, h, d);
                let l = (p - camera.eye()).length();
                let z = camera.eye_depth(d);
                let pixel = common::pixel_top_first(x, y, w, h, d);
                let tau = fog.sample(pixel, &at).transmission[0];
                // f32 budgets of τ (F moves τ by τ·ΔF): the eye depth, 3·2^-24 relative
                // in l; the ray's rise, off by z·2^-22, moves the mean by ½·slope per unit
                // of rise; the difference of two f32 K values, 2^-23·K_max over a rise of
                // a cell at least; and the exponential and the two passes.
                let eps = f64::powi(2.0, -24);
                let mean = -tau.ln() / l.max(1e-9);
                let dy = (p.y - camera.eye().y).abs().max(table.grid_spacing());
                let budget = tau
                    * (l * mean * 3.0 * eps
                        + 0.5 * slope * l * z * 4.0 * eps
                        + l * 4.0 * eps * k_max / dy
                        + l * mean * 8.0 * eps)
                    + 8e-7;
                let (g, c) = (gpu.image.get(x, y), cpu.get(x, y));
                for k in 0..3 {
                    let e = (f64::from(g[k]) - f64::from(c[k])).abs();
                    assert!(
                        e <= budget,
                        "pixel ({x}, {y}): GPU {} vs CPU {} (budget {budget:.1e})",
                        g[k],
                        c[k]
                    );
                    worst = worst.max(e / budget);
                }
            }
        }
        eprintln!(
            "{} rows (on grid {}): worst GPU-CPU difference {worst:.2} of its pixel's budget",
            table.heights().len(),
            table.on_grid()
        );
    }
}

/// κ of `rows` at `y`: linear between rows, constant beyond (the definition, by a scan).
fn interpolate(rows: &[(f64, f64)], y: f64) -> f64 {
    let (first, last) = (rows[0], rows[rows.len() - 1]);
    if y <= first.0 {
        return first.1;
    }
    if y >= last.0 {
        return last.1;
    }
    let w = rows.windows(2).find(|w| y <= w[1].0).unwrap();
    w[0].1 + (y - w[0].0) / (w[1].0 - w[0].0) * (w[1].1 - w[0].1)
}

/// ∫ κ(y(t)) dt along the segment by composite Simpson in t, split where it crosses a row.
fn simpson_along(rows: &[(f64, f64)], from: DVec3, to: DVec3) -> f64 {
    let length = (to - from).length();
    let dy = to.y - from.y;
    let mut cuts = vec![0.0, 1.0];
    if dy != 0.0 {
        cuts.extend(
            rows.iter()
                .map(|r| (r.0 - from.y) / dy)
                .filter(|s| *s > 0.0 && *s < 1.0),
        );
    }
    cuts.sort_by(f64::total_cmp);
    let n = 16;
    let kappa = |s: f64| interpolate(rows, from.y + s * dy);
    let mut sum = 0.0;
    for c in cuts.windows(2) {
        let step = (c[1] - c[0]) / (2 * n) as f64;
        let mut part = kappa(c[0]) + kappa(c[1]);
        for i in 1..2 * n {
            part += kappa(c[0] + i as f64 * step) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        sum += part * step / 3.0;
    }
    sum * length
}

#[test]
fn cpu_reference_matches_simpson_along_segments() {
    let table = inversion();
    let rows: Vec<(f64, f64)> = table
        .heights()
        .iter()
        .copied()
        .zip(table.extinction().iter().copied())
        .collect();
    let camera = scene_camera();
    let fog = LayeredFog::for_camera(camera, HeightProfile::Table(table));
    let eye = camera.eye();
    for p in [
        DVec3::new(30.0, 0.0, -400.0),
        DVec3::new(-50.0, 25.0, -300.0),
        DVec3::new(0.0, 1.7, -900.0),
        DVec3::new(10.0, 300.0, -500.0),
        DVec3::new(2.0, 1.7 + 1e-7, -100.0),
        DVec3::new(0.0, -20.0, -60.0),
    ] {
        let tau = fog.sample_point(eye, p, 1.0).transmission[0];
        let want = (-simpson_along(&rows, eye, p)).exp();
        assert!(
            (tau - want).abs() <= 1e-12,
            "{p}: CPU τ {tau} vs Simpson {want}"
        );
    }
}

/// The engine's passes (paper 001's Gaussian modes) compile and bind the table's textures
/// too: the fog without blur and with the one-pass Gaussian match the f64 reference.
#[test]
fn engine_passes_render_a_table_fog() {
    let (w, h) = (64, 48);
    let camera = scene_camera();
    let depth = depth_buffer(&camera, w, h);
    let image = noise_image(w, h, 9);
    let fog = LayeredFog {
        lambda: 0.0,
        ..LayeredFog::for_camera(camera, HeightProfile::Table(inversion()))
    };
    let (_lock, mut r) = renderer();
    for blur in [
        brume::FogBlur::None,
        brume::FogBlur::GaussSingle(brume::GaussBlur::default()),
    ] {
        let at = FrameInputs::new(camera, 0.0);
        let gpu = r
            .render_fog(&image, &depth, &fog, &at, &blur)
            .expect("GPU fog");
        let cpu = reference::fog(&image, &depth, &fog, &at, &blur).expect("CPU fog");
        let e = reference::rgb_error(&gpu.image, &cpu, 0);
        eprintln!("engine {}: max {:.1e}", blur.name(), e.max_abs);
        // The f32 budget of the per-pixel test above, at its largest here (≤ 1e-5), and
        // the Gaussian's weights in f32.
        assert!(e.max_abs <= 2e-5, "{}: {e:?}", blur.name());
    }
}
