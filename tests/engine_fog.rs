//! Engine fog (papers 001 and 003) on the GPU against the f64 CPU reference: no blur, the
//! 5 x 5 Gaussian in the fog's pass and in a second pass, the diffusion blur, and paper
//! 003's blended pass over a host framebuffer. The test medium is homogeneous fog seen
//! through a camera: its GLSL rebuilds distance from the depth buffer by the pipeline's
//! rays and depth constants, its CPU side by the inverse matrices.
//!
//! Tolerance: 2e-5 for the one- and two-pass modes. The eye depth is good to 3·2^-24
//! relative (tests/layered_fog.rs derives it), but one f32 ulp of the stored window depth
//! d near the far plane (6e-8, where d + B is a few 1e-3) is a relative 2e-5 of distance,
//! which the CPU sees too but evaluates in f64; τ = e^(−k·l) then moves by at most
//! k·l·2e-5 ≤ 1e-5 here (k·l ≤ 0.5), and the rest is a few f32 ulps.
use crate::common;

use brume::camera::{Camera, FrameInputs};
use brume::medium::{blur_from_optical_depth, Medium, MediumSample, Pixel, UniformValue};
use brume::raster::{Grid, RgbImage, ScalarMap};
use brume::{reference, Blur, FogBlur, GaussBlur, Precision, Scheme};
use common::*;
use std::borrow::Cow;

const ONE_PASS_TOLERANCE: f64 = 2e-5;

/// Homogeneous fog of extinction `k` per unit, seen through the frame's camera; `unit`
/// is the distance that counts as 1 in the blur law, `reach` the farthest distance a
/// pixel sees (for σ's bound).
struct CameraFog {
    unit: f64,
    reach: f64,
    k: f64,
    colour: [f32; 3],
    lambda: f64,
}

impl Medium for CameraFog {
    fn name(&self) -> Cow<'static, str> {
        "test_camera_fog".into()
    }

    fn glsl(&self) -> Cow<'static, str> {
        Cow::Borrowed(
            r"
        uniform float u_k;
        uniform vec3 u_fog_colour;
        uniform float u_lambda;
        uniform float u_unit;
        MediumSample medium_sample(ivec2 pixel, float depth) {
            float l = length(brume_ray) * brume_eye_depth(depth);
            MediumSample m;
            m.transmission = vec3(exp(-u_k * l));
            m.inscatter = u_fog_colour;
            m.sigma = brume_blur_scale(u_lambda, l / u_unit, u_k * l);
            return m;
        }
        ",
        )
    }

    fn uniforms(&self, _frame: &FrameInputs) -> Vec<(Cow<'static, str>, UniformValue)> {
        brume::medium::static_names(vec![
            ("u_k", UniformValue::Float(self.k as f32)),
            ("u_fog_colour", UniformValue::Vec3(self.colour)),
            ("u_lambda", UniformValue::Float(self.lambda as f32)),
            ("u_unit", UniformValue::Float(self.unit as f32)),
        ])
    }

    fn chromatic(&self) -> bool {
        false
    }

    fn sigma_max(&self, sigma0: f64) -> f64 {
        // r ≤ 1 in the law; the optical depth is largest at the far corner.
        blur_from_optical_depth(sigma0, self.lambda, 1.0, self.k * self.reach)
    }

    fn sample(&self, p: Pixel, frame: &FrameInputs) -> MediumSample {
        let c = frame.camera.expect("checked").for_frame(p.width, p.height);
        let pos = c.world_position_by_inverse(p.x, p.y, p.width, p.height, p.depth);
        let l = (pos - c.eye()).length();
        let tau = (-self.k * l).exp();
        MediumSample {
            transmission: [tau; 3],
            inscatter: self.colour.map(f64::from),
            sigma: blur_from_optical_depth(p.sigma0, self.lambda, l / self.unit, self.k * l),
        }
    }

    fn validate(&self) -> brume::Result<()> {
        Ok(())
    }

    fn needs_camera(&self) -> bool {
        true
    }
}

fn scene_camera() -> Camera {
    Camera {
        position: [1.0, 1.7, 0.0],
        yaw_deg: 8.0,
        pitch_deg: -6.0,
        fov_y_deg: 60.0,
        near: 0.5,
        far: 120.0,
    }
}

/// The frame of the scene camera.
fn at() -> FrameInputs {
    FrameInputs::new(scene_camera(), 0.0)
}

fn fog() -> CameraFog {
    let camera = scene_camera();
    CameraFog {
        unit: camera.far,
        reach: camera.far * camera.pixel_ray(0, 0, 4, 3).length(),
        k: 0.004,
        colour: [0.6, 0.65, 0.7],
        lambda: 4.0,
    }
}

fn frame(w: usize, h: usize) -> (RgbImage, ScalarMap) {
    (
        noise_image(w, h, 7),
        synthetic_depth_buffer(&scene_camera(), w, h),
    )
}

fn assert_fog_matches(blur: FogBlur, tolerance: f64) {
    let (image, depth) = frame(64, 48);
    let medium = fog();
    let (_lock, mut r) = renderer();
    let gpu = r
        .render_fog(&image, &depth, &medium, &at(), &blur)
        .expect("GPU fog");
    let cpu = reference::fog(&image, &depth, &medium, &at(), &blur).expect("CPU fog");
    let e = reference::rgb_error(&gpu.image, &cpu, 0);
    eprintln!(
        "{}: max {:.2e} (tolerance {tolerance:.1e})",
        blur.name(),
        e.max_abs
    );
    assert!(e.max_abs <= tolerance, "{}: {e:?}", blur.name());
    assert_eq!(gpu.times.pass_ms.len(), gpu.pass_names().len());
}

#[test]
fn fog_without_blur_matches_the_reference() {
    assert_fog_matches(FogBlur::None, ONE_PASS_TOLERANCE);
}

#[test]
fn gaussian_blur_in_the_fog_pass_matches_the_reference() {
    let gauss = GaussBlur {
        distance: 30.0,
        ..GaussBlur::default()
    };
    assert_fog_matches(FogBlur::GaussSingle(gauss), ONE_PASS_TOLERANCE);
}

#[test]
fn gaussian_blur_in_a_second_pass_matches_the_reference() {
    let gauss = GaussBlur {
        distance: 30.0,
        falloff: 1.5,
        maximum: 0.8,
        ..GaussBlur::default()
    };
    assert_fog_matches(FogBlur::GaussSeparate(gauss), 2.0 * ONE_PASS_TOLERANCE);
}

#[test]
fn diffusion_blur_driven_by_the_fog_matches_the_reference() {
    // Per-pass budget of tests/gpu_vs_cpu.rs on top of the fog's own.
    let blur = Blur::new(Scheme::Matched, Precision::F32);
    let (image, depth) = frame(64, 48);
    let (_lock, mut r) = renderer();
    let gpu = r
        .render_fog(&image, &depth, &fog(), &at(), &FogBlur::Diffusion(blur))
        .unwrap();
    assert!(gpu.schedule.steps > 0, "the fog must ask for blur");
    drop((_lock, r));
    let tolerance = ONE_PASS_TOLERANCE + 4e-7 * f64::from(gpu.schedule.steps + 2);
    assert_fog_matches(FogBlur::Diffusion(blur), tolerance);
}

#[test]
fn the_blur_weight_grows_with_distance_and_fog() {
    let g = GaussBlur::default();
    assert_eq!(g.weight(0.5, 0.0), 0.0);
    assert!(g.weight(0.5, 50.0) < g.weight(0.5, 100.0));
    assert!(g.weight(0.2, 100.0) < g.weight(0.4, 100.0));
    assert_eq!(g.weight(0.9, 1e6), g.maximum);
}

#[test]
fn the_gaussian_modes_blur_only_where_there_is_fog() {
    // With no fog (k = 0) the Gaussian modes must give the input back exactly.
    let (image, depth) = frame(32, 24);
    let medium = CameraFog { k: 0.0, ..fog() };
    let (_lock, mut r) = renderer();
    for blur in [
        FogBlur::GaussSingle(GaussBlur::default()),
        FogBlur::GaussSeparate(GaussBlur::default()),
    ] {
        let out = r.render_fog(&image, &depth, &medium, &at(), &blur).unwrap();
        let sharp = Grid::from_fn(32, 24, |x, y| {
            let c = image.get(x, y);
            [c[0], c[1], c[2], 1.0]
        });
        let e = reference::rgb_error(&out.image, &sharp, 0);
        assert!(e.max_abs < 1e-6, "{}: {e:?}", blur.name());
    }
}

#[test]
fn a_gaussian_blur_needs_a_camera() {
    let (image, _) = frame(16, 12);
    let range = ramp_range(16, 12);
    let (_lock, mut r) = renderer();
    let err = r
        .render_fog(
            &image,
            &range,
            &brume::Haze::default(),
            &at(),
            &FogBlur::GaussSingle(GaussBlur::default()),
        )
        .unwrap_err()
        .to_string();
    assert!(err.contains("blur") && err.contains("camera"), "{err}");
}

#[test]
fn blended_fog_over_a_host_framebuffer_matches_the_one_pass_fog() {
    use brume::gpu::texture::{Filter, TexelFormat, Texture};
    use brume::Output;
    let (w, h) = (48, 32);
    let (image, depth) = frame(w, h);
    let medium = fog();
    let (_lock, mut r) = renderer();
    let renderer = r.renderer().unwrap();
    let gl = std::sync::Arc::clone(renderer.pipeline().gl());
    // The host's frame: its colour already in the target, its depth in a texture (GL
    // rows bottom first, as a host renders them).
    let mut rgba: Vec<f32> = Vec::new();
    let mut depth_rows: Vec<f32> = Vec::new();
    for row in (0..h).rev() {
        for x in 0..w {
            let c = image.get(x, row);
            rgba.extend_from_slice(&[c[0], c[1], c[2], 1.0]);
            depth_rows.push(*depth.get(x, row));
        }
    }
    let target = Texture::new(
        &gl,
        w,
        h,
        TexelFormat::Rgba32F,
        Filter::Nearest,
        Some(&rgba),
    )
    .unwrap();
    let depth_texture = Texture::new(
        &gl,
        w,
        h,
        TexelFormat::R32F,
        Filter::Nearest,
        Some(&depth_rows),
    )
    .unwrap();
    let output = Output::Texture {
        texture: target.raw(),
        encoding: brume::Encoding::Linear,
    };
    renderer
        .pipeline()
        .blend_fog(depth_texture.raw(), w, h, &medium, &at(), &output)
        .expect("blended fog");
    let fb = brume::gpu::framebuffer::Framebuffer::over(&gl, &[&target], "read-back").unwrap();
    let mut blended = Grid::from_vec(w, h, fb.read_rgba().unwrap());
    blended.flip_rows();
    let cpu = reference::fog(&image, &depth, &medium, &at(), &FogBlur::None).unwrap();
    let e = reference::rgb_error(&blended, &cpu, 0);
    assert!(e.max_abs <= ONE_PASS_TOLERANCE, "{e:?}");
}
