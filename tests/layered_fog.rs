//! Paper 003's layered fog on the GPU against the f64 CPU reference, on depth buffers
//! synthesised from an analytic scene (a ground plane, boxes, a far wall and sky).
//!
//! The shader rebuilds each fragment from the interpolated ray and the eye depth
//! A/((d − 1) − c) in f32 (paper 003's A/(d + B), split for f32), the reference by the
//! inverse matrices in f64 (paper 002), so the comparison tests the fast reconstruction
//! too. Its error budget has two parts:
//!
//! - **Eye depth.** d − 1 is exact, c = n/(f − n) is rounded to f32 (2^-24 relative) and
//!   so is the difference, whose size is at least c: the denominator is off by at most
//!   2·2^-24 relative, and the division adds 2^-24, so the eye depth, hence l and F, is
//!   off by a relative ε_z = 3·2^-24 at any distance. τ = e^(−F) then moves by
//!   F·e^(−F)·ε_z ≤ e^(−1)·ε_z. With the f32 exponentials, twice that is the per-pixel
//!   budget of τ, hence of the image (colours and fog colour in [0, 1]) without blur. With
//!   blur, σ − σ0 ∝ r·√Ds is off by 1.5·ε_z relative, the log-law rate by Δσ/σ/N per
//!   step, and N steps move a pixel by at most 4·Δσ/σ ≤ 6·ε_z. Each pass also rounds
//!   its output (tests/gpu_vs_cpu.rs's per-pass budget), and a test that compares with an
//!   exact point rather than the stored depth adds the rounding of d to f32.
//! - **Ray direction.** The interpolated ray's rise is off by about an ulp of the corner
//!   rays (≈ 1), 2^-23, so the fragment's height is off by z·2^-23. A mean over the
//!   segment's heights moves by at most half the steepest slope of δ per unit of rise, so
//!   F by ½·max|δ'|·l·z·2^-23. It is negligible except along a kink of δ at the eye's
//!   height with τ near 1: a horizontal ray along a layer's edge (last test).
use crate::common;

use brume::camera::{Camera, FrameInputs};
use brume::medium::{HeightProfile, LayeredFog, Medium, MediumSample, Pixel};
use brume::raster::{Grid, RgbImage, RgbaImage, ScalarMap};
use brume::{reference, Blur, FogBlur, Precision, Scheme};
use common::*;
use glam::DVec3;

/// The f32 pipeline's own budget per pass (tests/gpu_vs_cpu.rs).
const F32_PER_PASS: f64 = 4e-7;

/// ε_z, the relative error of the shader's eye depth (module docs): 3·2^-24 at any z.
const DEPTH_ERROR: f64 = 3.0 / 16_777_216.0;

/// The budget of τ for the f32 reconstruction of the eye depth (module docs).
fn reconstruction_budget() -> f64 {
    2.0 * (-1f64).exp() * DEPTH_ERROR
}

/// The budget of τ for rounding the window depth of an exact point to f32 (the rotation
/// test compares with the exact point): half an ulp of d < 1, 2^-25, moves the eye depth
/// by a relative 2^-25·(f − n)·z/(n·f) < 2^-25·z/near.
fn stored_depth_budget(camera: &Camera, z: f64) -> f64 {
    (-1f64).exp() * f64::powi(2.0, -25) * z / camera.near
}

/// The budget of a whole frame that is also blurred (module docs).
fn blurred_budget(steps: u32) -> f64 {
    reconstruction_budget() + 6.0 * DEPTH_ERROR + F32_PER_PASS * f64::from(steps + 2)
}

/// The budget of τ for the ray's direction at a pixel whose segment has length `l` and
/// eye depth `z`, with twice the module docs' ulp for the interpolation's rounding.
fn ray_budget(profile: &HeightProfile, tau: f64, l: f64, z: f64) -> f64 {
    // The steepest slope of δ at the heights of the scene (0 to 100 m).
    let slope = match *profile {
        HeightProfile::Exponential {
            density,
            base,
            scale_height,
        } => density / scale_height * (base / scale_height).exp(),
        HeightProfile::SineBand {
            density, thickness, ..
        } => density * std::f64::consts::PI / thickness,
        HeightProfile::LinearRamp {
            density,
            floor,
            top,
        } => density / (top - floor),
        // Its largest slope between rows.
        HeightProfile::Table(ref table) => {
            let (h, k) = (table.heights(), table.extinction());
            (1..h.len())
                .map(|i| (k[i] - k[i - 1]).abs() / (h[i] - h[i - 1]))
                .fold(0.0, f64::max)
        }
    };
    tau * 0.5 * slope * l * z * f64::powi(2.0, -22)
}

/// An axis-aligned box.
#[derive(Clone, Copy)]
struct Aabb {
    min: DVec3,
    max: DVec3,
}

/// Boxes standing on the ground at y = 0, from 5 m to a wall 900 m away.
fn scene() -> Vec<Aabb> {
    let b = |min: [f64; 3], max: [f64; 3]| Aabb {
        min: DVec3::from_array(min),
        max: DVec3::from_array(max),
    };
    vec![
        b([-3.0, 0.0, -8.0], [-1.0, 2.5, -5.0]),
        b([4.0, 0.0, -60.0], [12.0, 15.0, -40.0]),
        b([-60.0, 0.0, -300.0], [-45.0, 80.0, -280.0]),
        b([-20.0, 0.0, -130.0], [-5.0, 0.8, -100.0]),
        b([-400.0, 0.0, -905.0], [150.0, 40.0, -900.0]),
    ]
}

/// The smallest t > 0 with `eye + dir·t` on the ground or a box.
fn hit(boxes: &[Aabb], eye: DVec3, dir: DVec3) -> Option<f64> {
    let mut best = (dir.y < 0.0).then(|| -eye.y / dir.y);
    for b in boxes {
        if let Some(t0) = ray_enters_box(eye, dir, b.min, b.max) {
            if !matches!(best, Some(t) if t <= t0) {
                best = Some(t0);
            }
        }
    }
    best
}

/// The window depth buffer of `boxes` seen through `camera`, top row first (buffer row
/// y is GL row h − 1 − y); beyond the far plane is sky, at depth 1. The rays have a
/// component 1 along the view axis, so the hit's t is the eye depth.
fn depth_buffer(camera: &Camera, boxes: &[Aabb], w: usize, h: usize) -> ScalarMap {
    Grid::from_fn(w, h, |x, y| {
        let ray = camera.pixel_ray(x, h - 1 - y, w, h);
        match hit(boxes, camera.eye(), ray) {
            Some(t) if t <= camera.far => camera.window_depth(t) as f32,
            _ => 1.0,
        }
    })
}

/// The test scene's camera: eye at 1.7 m, looking slightly down and to the right.
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

fn every_profile() -> [(&'static str, HeightProfile); 3] {
    [
        ("exponential", HeightProfile::EXPONENTIAL),
        ("sine band", HeightProfile::SINE_BAND),
        ("linear ramp", HeightProfile::LINEAR_RAMP),
    ]
}

/// Renders the frame of `camera` on both sides, checks every value is finite and returns
/// both images.
fn render_both(
    r: &mut brume::Headless,
    image: &RgbImage,
    depth: &ScalarMap,
    fog: &LayeredFog,
    camera: &Camera,
    blur: &Blur,
) -> (brume::Rendered, RgbaImage) {
    let frame = FrameInputs::new(*camera, 0.0);
    let gpu = r
        .render_fog(image, depth, fog, &frame, &FogBlur::Diffusion(*blur))
        .expect("GPU render");
    let cpu =
        reference::fog(image, depth, fog, &frame, &FogBlur::Diffusion(*blur)).expect("CPU render");
    assert!(
        gpu.image.as_slice().iter().flatten().all(|v| v.is_finite()),
        "GPU NaN/inf"
    );
    assert!(
        cpu.as_slice().iter().flatten().all(|v| v.is_finite()),
        "CPU NaN/inf"
    );
    (gpu, cpu)
}

/// The largest GPU-CPU difference of a frame and its number of diffusion steps.
fn gpu_cpu_difference(
    r: &mut brume::Headless,
    image: &RgbImage,
    depth: &ScalarMap,
    fog: &LayeredFog,
    camera: &Camera,
    blur: &Blur,
) -> (f64, u32) {
    let (gpu, cpu) = render_both(r, image, depth, fog, camera, blur);
    let e = reference::rgb_error(&gpu.image, &cpu, 0);
    (e.max_abs, gpu.schedule.steps)
}

/// Without blur each pixel is τ·E + (1 − τ)·C on its own: its budget is the eye depth's
/// and the ray's at that pixel (module docs), plus the two passes'. Returns the largest
/// ratio of difference to budget.
fn assert_unblurred_within_pixel_budgets(
    r: &mut brume::Headless,
    image: &RgbImage,
    depth: &ScalarMap,
    fog: &LayeredFog,
    camera: &Camera,
) -> f64 {
    assert_eq!(fog.lambda, 0.0);
    let (gpu, cpu) = render_both(r, image, depth, fog, camera, &Blur::default());
    let frame = FrameInputs::new(*camera, 0.0);
    let (w, h) = (image.width(), image.height());
    let mut worst: f64 = 0.0;
    for y in 0..h {
        for x in 0..w {
            let d = f64::from(*depth.get(x, y));
            let z = camera.eye_depth(d);
            let l = (camera.world_position(x, h - 1 - y, w, h, d) - camera.eye()).length();
            let pixel = common::pixel_top_first(x, y, w, h, d);
            let tau = fog.sample(pixel, &frame).transmission[0];
            let budget =
                reconstruction_budget() + ray_budget(&fog.profile, tau, l, z) + 2.0 * F32_PER_PASS;
            let (p, q) = (gpu.image.get(x, y), cpu.get(x, y));
            for c in 0..3 {
                let e = (f64::from(p[c]) - f64::from(q[c])).abs();
                assert!(
                    e <= budget,
                    "{:?} pixel ({x}, {y}): {} vs {} (budget {budget:.1e})",
                    fog.profile,
                    p[c],
                    q[c]
                );
                worst = worst.max(e / budget);
            }
        }
    }
    worst
}

#[test]
fn layered_fog_matches_reference_for_every_profile_with_and_without_blur() {
    let (w, h) = (64, 48);
    let camera = scene_camera();
    let depth = depth_buffer(&camera, &scene(), w, h);
    let sky = depth.as_slice().iter().filter(|d| **d == 1.0).count();
    assert!(sky > w && sky < w * h / 2, "{sky} sky pixels");
    let image = noise_image(w, h, 21);
    let (_lock, mut r) = renderer();
    for (name, profile) in every_profile() {
        let fog = LayeredFog {
            lambda: 0.0,
            colour: [0.75, 0.8, 0.85],
            ..LayeredFog::for_camera(camera, profile)
        };
        let worst = assert_unblurred_within_pixel_budgets(&mut r, &image, &depth, &fog, &camera);
        eprintln!("{name} λ = 0: worst difference {worst:.2} of its pixel's budget");
        // With blur, the frame's budget: the diffusion mixes pixels.
        let fog = LayeredFog { lambda: 3.0, ..fog };
        let blur = Blur::new(Scheme::Matched, Precision::F32);
        let (max, steps) = gpu_cpu_difference(&mut r, &image, &depth, &fog, &camera, &blur);
        let tol = blurred_budget(steps);
        eprintln!("{name} λ = 3: N = {steps}, max {max:.2e} (tolerance {tol:.2e})");
        assert!(max <= tol, "{name} λ = 3: {max} > {tol}");
    }
}

/// Turns `camera` about its centre so that the ray through GL pixel (x, y) of a `w x h`
/// frame passes through `p`.
fn aimed(camera: &Camera, p: DVec3, (x, y): (usize, usize), (w, h): (usize, usize)) -> Camera {
    let (ndc_x, ndc_y) = brume::camera::pixel_ndc(x, y, w, h);
    let ty = (camera.fov_y_deg.to_radians() / 2.0).tan();
    let (a, b) = (ndc_x * ty * w as f64 / h as f64, ndc_y * ty);
    let v = p - camera.eye();
    // The ray is a·right + forward + b·up; its height is sin p + b·cos p of its length
    // √(1 + a² + b²), and its horizontal part is (a, −(cos p − b·sin p)) turned by yaw.
    let rise = v.y / v.length() * (1.0 + a * a + b * b).sqrt();
    let pitch = (rise / (1.0 + b * b).sqrt()).asin() - b.atan();
    let across = pitch.cos() - b * pitch.sin();
    let yaw = v.z.atan2(v.x) - (-across).atan2(a);
    let turned = Camera {
        yaw_deg: yaw.to_degrees(),
        pitch_deg: pitch.to_degrees(),
        ..*camera
    };
    let ray = turned.pixel_ray(x, y, w, h);
    assert!(
        ray.normalize().dot(v.normalize()) > 1.0 - 1e-12,
        "aiming failed"
    );
    turned
}

#[test]
fn turning_the_camera_leaves_the_fog_of_a_fixed_point_unchanged() {
    // Paper 003, fig. 1: the eye depth of a fixed point changes as the camera turns about
    // its centre, the fog on it must not. The point is on the face of a wall; each view
    // sees it through another pixel.
    let (w, h) = (64, 48);
    let point = DVec3::new(8.0, 0.6, -60.0);
    let wall = Aabb {
        min: DVec3::new(-100.0, 0.0, -61.0),
        max: DVec3::new(100.0, 10.0, -60.0),
    };
    let pixels = [(10, 30), (32, 24), (55, 8), (40, 44), (3, 2)];
    let base = scene_camera();
    let image = Grid::filled(w, h, [0.0f32; 3]);
    let (_lock, mut r) = renderer();
    let profiles = [
        HeightProfile::EXPONENTIAL,
        HeightProfile::SINE_BAND,
        HeightProfile::LinearRamp {
            density: 0.25,
            floor: 0.0,
            top: 1.0,
        },
    ];
    for profile in profiles {
        // One medium value for every view: each frame gives its camera.
        let fog = LayeredFog {
            colour: [1.0; 3],
            lambda: 0.0,
            ..LayeredFog::for_camera(base, profile.clone())
        };
        let expected = fog.sample_point(base.eye(), point, 1.0).transmission[0];
        assert!(
            expected > 0.2 && expected < 0.8,
            "{profile:?}: τ {expected}"
        );
        let mut eye_depths = vec![];
        for &pixel in &pixels {
            let camera = aimed(&base, point, pixel, (w, h));
            let (d, _) = camera.project_depth(point).unwrap();
            eye_depths.push(camera.eye_depth(d));
            // λ = 0 and fog colour 1 over a black image: the output is 1 − τ.
            let frame = FrameInputs::new(camera, 0.0);
            // The CPU, from the exact depth of the point at that pixel.
            let at_pixel = Pixel {
                x: pixel.0,
                y: pixel.1,
                width: w,
                height: h,
                depth: d,
                sigma0: 1.0,
            };
            let cpu: MediumSample = fog.sample(at_pixel, &frame);
            assert!(
                (cpu.transmission[0] - expected).abs() < 1e-9,
                "{profile:?} pixel {pixel:?}: CPU τ {} vs {expected}",
                cpu.transmission[0]
            );
            // The GPU, from the synthesised depth buffer (f32).
            let depth = depth_buffer(&camera, &[wall], w, h);
            let stored = f64::from(*depth.get(pixel.0, h - 1 - pixel.1));
            assert!(
                (stored - d).abs() < 1e-6,
                "pixel {pixel:?} misses the point"
            );
            let out = r
                .render_fog(
                    &image,
                    &depth,
                    &fog,
                    &frame,
                    &FogBlur::Diffusion(Blur::default()),
                )
                .unwrap();
            let tau = 1.0 - f64::from(out.image.get(pixel.0, h - 1 - pixel.1)[0]);
            // The stored depth is d rounded to f32: one more reconstruction error.
            let z = camera.eye_depth(d);
            let tol = reconstruction_budget()
                + stored_depth_budget(&camera, z)
                + ray_budget(&profile, expected, (point - camera.eye()).length(), z)
                + F32_PER_PASS;
            eprintln!(
                "{profile:?} pixel {pixel:?}: eye depth {:.2}, GPU τ − τ {:.1e} (tolerance {tol:.1e})",
                z,
                tau - expected
            );
            assert!(
                (tau - expected).abs() <= tol,
                "{profile:?} pixel {pixel:?}: GPU τ {tau} vs {expected} (tolerance {tol:.1e})"
            );
        }
        let spread = eye_depths.iter().cloned().fold(f64::MIN, f64::max)
            - eye_depths.iter().cloned().fold(f64::MAX, f64::min);
        assert!(
            spread > 0.05 * eye_depths[0],
            "the views should see the point at different eye depths: {eye_depths:?}"
        );
    }
}

#[test]
fn horizontal_rays_along_a_layer_boundary_have_no_nan() {
    // Pitch 0 and an odd height: the middle row's rays are horizontal (Δy = 0 up to the
    // interpolation's rounding), at the height of a boundary of the layer.
    let (w, h) = (48, 37);
    let camera = Camera {
        pitch_deg: 0.0,
        yaw_deg: 0.0,
        ..scene_camera()
    };
    let eye_y = camera.position[1];
    let depth = depth_buffer(&camera, &scene(), w, h);
    let image = noise_image(w, h, 5);
    let profiles = [
        HeightProfile::Exponential {
            density: 0.01,
            base: eye_y,
            scale_height: 20.0,
        },
        HeightProfile::SineBand {
            density: 0.01,
            base: eye_y,
            thickness: 5.0,
        },
        HeightProfile::SineBand {
            density: 0.01,
            base: eye_y - 5.0,
            thickness: 5.0,
        },
        HeightProfile::LinearRamp {
            density: 0.01,
            floor: eye_y,
            top: eye_y + 3.0,
        },
        HeightProfile::LinearRamp {
            density: 0.01,
            floor: eye_y - 1.0,
            top: eye_y,
        },
    ];
    let (_lock, mut r) = renderer();
    let middle = h / 2;
    let far = camera.far;
    for profile in profiles {
        let fog = LayeredFog {
            lambda: 0.0,
            ..LayeredFog::for_camera(camera, profile.clone())
        };
        let frame = FrameInputs::new(camera, 0.0);
        // τ itself on the horizon row: fog colour 0 over a white image, no blur.
        let white = Grid::filled(w, h, [1.0f32; 3]);
        let readout = LayeredFog {
            colour: [0.0; 3],
            lambda: 0.0,
            ..fog.clone()
        };
        let tau = r
            .render_fog(
                &white,
                &depth,
                &readout,
                &frame,
                &FogBlur::Diffusion(Blur::default()),
            )
            .unwrap();
        for x in 0..w {
            let v = tau.image.get(x, middle)[0];
            assert!(
                v.is_finite() && v > 0.0 && v <= 1.0,
                "{profile:?} x {x}: {v}"
            );
            let d = f64::from(*depth.get(x, middle));
            let at_pixel = common::pixel_top_first(x, middle, w, h, d);
            let cpu = fog.sample(at_pixel, &frame);
            let z = camera.eye_depth(d);
            let p = camera.world_position(x, h - 1 - middle, w, h, d);
            let l = (p - camera.eye()).length();
            let tol = reconstruction_budget()
                + ray_budget(&profile, cpu.transmission[0], l, z)
                + F32_PER_PASS;
            assert!(
                (f64::from(v) - cpu.transmission[0]).abs() <= tol,
                "{profile:?} x {x}: GPU τ {v} vs CPU {}",
                cpu.transmission[0]
            );
        }
        // The whole frame: each pixel within its budget without blur; with blur, the
        // frame's budget plus the worst ray budget there (τ ≤ 1, l ≤ |ray|·far ≤ 1.3·far
        // at this aspect, z ≤ far).
        let worst = assert_unblurred_within_pixel_budgets(&mut r, &image, &depth, &fog, &camera);
        eprintln!("{profile:?} λ = 0: worst difference {worst:.2} of its pixel's budget");
        let fog = LayeredFog { lambda: 3.0, ..fog };
        let (max, steps) =
            gpu_cpu_difference(&mut r, &image, &depth, &fog, &camera, &Blur::default());
        let tol = blurred_budget(steps) + ray_budget(&profile, 1.0, 1.3 * far, far);
        eprintln!("{profile:?} λ = 3: max {max:.2e} (tolerance {tol:.2e})");
        // Where δ vanishes at the eye's height (an edge of the band, the ramp's top), the
        // horizon row's F is exactly 0 on the CPU and ~1e-4 on the GPU, both right to f32
        // (the ray budget), and the blur law's √Ds, of infinite slope at 0, turns that
        // into Δσ ≈ λ·√ΔF ≈ 0.03 px: a difference of the law, not of the medium, whose τ
        // is checked above. Only finiteness is checked there.
        if profile.density(eye_y) > 0.0 {
            assert!(max <= tol, "{profile:?} λ = 3: {max} > {tol}");
        }
    }
}

#[test]
fn layered_fog_is_grey_and_names_itself() {
    let fog = LayeredFog::default();
    assert!(!fog.chromatic());
    assert_eq!(fog.name(), "layered");
    // It reads a depth buffer through the frame's camera, and says so.
    assert!(fog.needs_camera());
    let camera = scene_camera();
    let frame = FrameInputs::new(camera, 0.0);
    assert_eq!(fog.frame_camera(&frame), Some(camera.into()));
    assert_eq!(fog.frame_camera(&FrameInputs::default()), None);
    assert_eq!(
        LayeredFog::for_camera(camera, HeightProfile::EXPONENTIAL).range_unit,
        camera.far
    );
}
