//! An engine's own camera and media defined at run time.
//!
//! - **Matrices as they are.** Bevy's default projection (reversed-Z, infinite far plane,
//!   wgpu's 0..1 clip depth), an off-centre OpenGL frustum and a left-handed reversed
//!   projection (Unreal's), each with a rolled view, are written out element by element
//!   here, independently of brume's code; known world points go through them, and
//!   brume's [`MatrixCamera`] must give their eye depths and positions back.
//! - **Same world, same fog.** A scene's depth buffer drawn through Bevy's projection and
//!   through an equivalent standard OpenGL one must give the same layered and distance
//!   fog, on the CPU reference and on the GPU.
//! - **Media defined at run time.** Two media of one name with different GLSL get their
//!   own programs, and a medium whose name, GLSL and uniform names are built at run time,
//!   with integer uniforms, renders on the GPU as its CPU `sample` says.
use crate::common;

use brume::camera::{ClipDepth, FrameInputs, MatrixCamera};
use brume::medium::{
    DistanceFog, HeightProfile, LayeredFog, Medium, MediumSample, Pixel, UniformValue,
};
use brume::raster::{Grid, RgbImage, ScalarMap};
use brume::{reference, FogBlur};
use common::*;
use glam::{DMat4, DQuat, DVec3, DVec4};
use std::borrow::Cow;

const W: usize = 64;
const H: usize = 40;
const FOV_Y: f64 = 1.0; // radians
const NEAR: f64 = 0.5;
/// The standard projection's far plane, and the reversed infinite one's sky depth: both
/// send the sky to the same distance.
const FAR: f64 = 400.0;

/// Bevy's `Mat4::perspective_infinite_reverse_rh(fov_y, aspect, near)`, written out:
/// clip = (x·f/aspect, y·f, near, −z), so z_ndc = near/(−z) ∈ (0, 1], 1 at the near plane.
fn bevy_projection(fov_y: f64, aspect: f64, near: f64) -> DMat4 {
    let f = 1.0 / (fov_y / 2.0).tan();
    DMat4::from_cols(
        DVec4::new(f / aspect, 0.0, 0.0, 0.0),
        DVec4::new(0.0, f, 0.0, 0.0),
        DVec4::new(0.0, 0.0, 0.0, -1.0),
        DVec4::new(0.0, 0.0, near, 0.0),
    )
}

/// OpenGL's `glFrustum(l, r, b, t, n, f)` (right-handed, clip z in [−w, w]), written out.
fn gl_frustum(l: f64, r: f64, b: f64, t: f64, n: f64, f: f64) -> DMat4 {
    DMat4::from_cols(
        DVec4::new(2.0 * n / (r - l), 0.0, 0.0, 0.0),
        DVec4::new(0.0, 2.0 * n / (t - b), 0.0, 0.0),
        DVec4::new(
            (r + l) / (r - l),
            (t + b) / (t - b),
            -(f + n) / (f - n),
            -1.0,
        ),
        DVec4::new(0.0, 0.0, -2.0 * f * n / (f - n), 0.0),
    )
}

/// A left-handed reversed-Z infinite projection (Unreal's, and D3D's with reversed depth):
/// clip = (x·f/aspect, y·f, near, z), the eye looking along +z.
fn unreal_projection(fov_y: f64, aspect: f64, near: f64) -> DMat4 {
    let f = 1.0 / (fov_y / 2.0).tan();
    DMat4::from_cols(
        DVec4::new(f / aspect, 0.0, 0.0, 0.0),
        DVec4::new(0.0, f, 0.0, 0.0),
        DVec4::new(0.0, 0.0, 0.0, 1.0),
        DVec4::new(0.0, 0.0, near, 0.0),
    )
}

fn eye() -> DVec3 {
    DVec3::new(2.0, 1.7, 5.0)
}

/// A right-handed view from [`eye`] toward a point down the −z axis, rolled by `roll`
/// radians about the view axis.
fn rolled_view(roll: f64) -> DMat4 {
    let forward = (DVec3::new(-3.0, 0.8, -60.0) - eye()).normalize();
    let up = DQuat::from_axis_angle(forward, roll) * DVec3::Y;
    DMat4::look_to_rh(eye(), forward, up)
}

/// The same, left-handed.
fn rolled_view_lh(roll: f64) -> DMat4 {
    let forward = (DVec3::new(-3.0, 0.8, -60.0) - eye()).normalize();
    let up = DQuat::from_axis_angle(forward, roll) * DVec3::Y;
    DMat4::look_to_lh(eye(), forward, up)
}

/// The world point at eye depth `t` behind NDC (x, y) of `projection` · `view`, and the
/// window depth it gets: clip coordinates by the matrices, no brume code.
struct Known {
    world: DVec3,
    window_depth: f64,
}

fn known_point(view: DMat4, projection: DMat4, clip: ClipDepth, ndc: (f64, f64), t: f64) -> Known {
    // Eye-space point on the ray through (x, y) at eye depth t: solve the projection's
    // x and y rows for the eye x and y at that eye z (w = ±z, the depth row is 0 in x, y).
    let handed = projection.row(3).z; // clip w = handed·z_eye
    let z_eye = t / handed; // eye depth t = handed·z_eye for |handed| = 1
    let w = handed * z_eye;
    let (r0, r1) = (projection.row(0), projection.row(1));
    let x_eye = (ndc.0 * w - r0.z * z_eye) / r0.x;
    let y_eye = (ndc.1 * w - r1.z * z_eye) / r1.y;
    let world = view
        .inverse()
        .transform_point3(DVec3::new(x_eye, y_eye, z_eye));
    let c = projection * view * world.extend(1.0);
    let z_ndc = c.z / c.w;
    let window_depth = match clip {
        ClipDepth::MinusOneToOne => (z_ndc + 1.0) / 2.0,
        ClipDepth::ZeroToOne => z_ndc,
    };
    Known {
        world,
        window_depth,
    }
}

/// The centre of pixel (x, y) (row 0 at the bottom) in NDC.
fn ndc(x: usize, y: usize) -> (f64, f64) {
    (
        2.0 * (x as f64 + 0.5) / W as f64 - 1.0,
        2.0 * (y as f64 + 0.5) / H as f64 - 1.0,
    )
}

/// Every pixel position and eye depth path of `camera` against the known points.
fn assert_reconstructs(camera: &MatrixCamera, view: DMat4, projection: DMat4, what: &str) {
    for (x, y) in [
        (0, 0),
        (W - 1, 0),
        (0, H - 1),
        (W - 1, H - 1),
        (17, 23),
        (40, 9),
    ] {
        for t in [0.6, 3.0, 42.0, 390.0, 5_000.0] {
            let k = known_point(view, projection, camera.clip(), ndc(x, y), t);
            let d = k.window_depth;
            let z = camera.eye_depth(d);
            assert!((z - t).abs() <= 1e-9 * t, "{what}: eye depth {z} for {t}");
            let by_inverse = camera.world_position_by_inverse(x, y, W, H, d);
            let fast = camera.world_position(x, y, W, H, d);
            for p in [by_inverse, fast] {
                assert!(
                    (p - k.world).length() <= 1e-9 * t.max(1.0),
                    "{what}: pixel ({x}, {y}) at t {t}: {p} vs {}",
                    k.world
                );
            }
            let (back, distance) = camera.project_depth(k.world).expect("in front");
            assert!(
                (back - d).abs() <= 1e-12,
                "{what}: window depth {back} vs {d}"
            );
            assert!(((k.world - eye()).length() - distance).abs() <= 1e-9 * t);
        }
    }
}

#[test]
fn bevy_reversed_infinite_projection_gives_known_points_back() {
    let aspect = W as f64 / H as f64;
    let (view, projection) = (rolled_view(0.3), bevy_projection(FOV_Y, aspect, NEAR));
    let camera = MatrixCamera::new(view, projection, ClipDepth::ZeroToOne)
        .unwrap()
        .with_sky_depth(1.0e4)
        .unwrap();
    assert!(camera.reversed() && camera.infinite());
    assert!((camera.near() - NEAR).abs() < 1e-15);
    assert!((camera.eye() - eye()).length() < 1e-12);
    // Depth 1 is the near plane, 0 infinity: the sky gets the sky depth.
    assert!((camera.eye_depth(1.0) - NEAR).abs() < 1e-12);
    assert_eq!(camera.eye_depth(0.0), 1.0e4);
    assert_reconstructs(&camera, view, projection, "bevy");
}

#[test]
fn off_centre_gl_frustum_with_roll_gives_known_points_back() {
    // A frustum shifted right and down (a tile of a wall of screens, a VR eye).
    let projection = gl_frustum(-0.2, 0.5, -0.3, 0.15, NEAR, 1.0e4);
    let view = rolled_view(-0.5);
    let camera = MatrixCamera::new(view, projection, ClipDepth::MinusOneToOne).unwrap();
    assert!(!camera.reversed() && !camera.infinite());
    assert!((camera.far() - 1.0e4).abs() < 1e-10 * 1.0e4);
    assert_reconstructs(&camera, view, projection, "off-centre");
    // The corner rays are the frustum's corners at eye depth 1, rotated into the world.
    let inverse_view = view.inverse();
    let expect = |x: f64, y: f64| inverse_view.transform_vector3(DVec3::new(x, y, -NEAR) / NEAR);
    let rays = camera.corner_rays();
    for (ray, want) in rays
        .iter()
        .zip([expect(-0.2, -0.3), expect(0.5, -0.3), expect(-0.2, 0.15)])
    {
        assert!((*ray - want).length() < 1e-12, "{ray} vs {want}");
    }
}

#[test]
fn left_handed_reversed_projection_gives_known_points_back() {
    let aspect = W as f64 / H as f64;
    let (view, projection) = (rolled_view_lh(0.2), unreal_projection(FOV_Y, aspect, NEAR));
    let camera = MatrixCamera::new(view, projection, ClipDepth::ZeroToOne)
        .unwrap()
        .with_sky_depth(1.0e4)
        .unwrap();
    assert!(camera.reversed() && camera.infinite());
    assert_reconstructs(&camera, view, projection, "left-handed");
}

#[test]
fn bad_matrices_are_refused_with_what_is_expected() {
    let aspect = 1.5;
    let bevy = bevy_projection(FOV_Y, aspect, NEAR);
    // Bevy's matrix read as OpenGL clip depth puts the near plane behind the eye.
    let wrong_clip = MatrixCamera::new(DMat4::IDENTITY, bevy, ClipDepth::MinusOneToOne);
    let message = wrong_clip.unwrap_err().to_string();
    assert!(message.contains("ZeroToOne"), "{message}");
    let ortho = DMat4::orthographic_rh_gl(-1.0, 1.0, -1.0, 1.0, 0.1, 10.0);
    let message = MatrixCamera::new(DMat4::IDENTITY, ortho, ClipDepth::MinusOneToOne)
        .unwrap_err()
        .to_string();
    assert!(message.contains("perspective"), "{message}");
    let singular = MatrixCamera::new(DMat4::ZERO, bevy, ClipDepth::ZeroToOne);
    assert!(singular.unwrap_err().to_string().contains("view matrix"));
    let camera = MatrixCamera::new(DMat4::IDENTITY, bevy, ClipDepth::ZeroToOne).unwrap();
    assert!(camera.with_sky_depth(0.1).is_err());
    assert!(camera.with_sky_depth(f64::INFINITY).is_err());
}

// ---------------------------------------------------------------------------------------
// The same world through Bevy's projection and a standard one.

/// The Bevy camera and the equivalent standard OpenGL one (same view, same field of view,
/// far plane at the Bevy camera's sky depth).
fn camera_pair() -> (MatrixCamera, MatrixCamera) {
    let aspect = W as f64 / H as f64;
    let view = rolled_view(0.25);
    let bevy = MatrixCamera::new(
        view,
        bevy_projection(FOV_Y, aspect, NEAR),
        ClipDepth::ZeroToOne,
    )
    .unwrap()
    .with_sky_depth(FAR)
    .unwrap();
    let standard = MatrixCamera::new(
        view,
        DMat4::perspective_rh_gl(FOV_Y, aspect, NEAR, FAR),
        ClipDepth::MinusOneToOne,
    )
    .unwrap();
    (bevy, standard)
}

/// Boxes on the ground, the ground, and sky beyond: the eye depth of the hit through the
/// centre of pixel (x, y) (row 0 at the bottom), `None` for the sky.
fn scene_hit(view: DMat4, projection: DMat4, x: usize, y: usize) -> Option<f64> {
    // The ray with eye depth 1 through the pixel, by the projection's own rows.
    let k = known_point(view, projection, ClipDepth::ZeroToOne, ndc(x, y), 1.0);
    let ray = k.world - eye();
    let mut best = (ray.y < 0.0).then(|| -eye().y / ray.y);
    for (min, max) in [
        ([-4.0, 0.0, -12.0], [-1.0, 3.0, -8.0]),
        ([3.0, 0.0, -80.0], [15.0, 25.0, -60.0]),
        ([-60.0, 0.0, -300.0], [-20.0, 60.0, -280.0]),
    ] {
        let hit = ray_enters_box(eye(), ray, DVec3::from(min), DVec3::from(max));
        if let Some(t) = hit {
            best = Some(best.map_or(t, |b: f64| b.min(t)));
        }
    }
    best.filter(|&t| t < FAR)
}

/// The depth buffer of the scene through `camera`, top row first as
/// [`brume::Renderer`] takes it: each hit's window depth by the matrices, the sky at
/// the far end (0 reversed, 1 standard).
fn depth_buffer(camera: &MatrixCamera) -> ScalarMap {
    Grid::from_fn(W, H, |x, row| {
        let y = H - 1 - row;
        match scene_hit(camera.view(), camera.projection(), x, y) {
            Some(t) => {
                known_point(
                    camera.view(),
                    camera.projection(),
                    camera.clip(),
                    ndc(x, y),
                    t,
                )
                .window_depth as f32
            }
            None if camera.reversed() => 0.0,
            None => 1.0,
        }
    })
}

/// The budget between the two projections: the standard one's window depth rounded to
/// f32 (half an ulp, 2^-25 below 1) moves the eye depth by a relative 2^-25·t/near ≤
/// 2^-25·FAR/NEAR; the fog's τ (and density) moves by at most that, times e^-1 for
/// τ = e^(−F) and 0.55 for the distance fog's power law, and the GPU adds a few f32 ulps.
fn projection_budget() -> f64 {
    f64::powi(2.0, -25) * FAR / NEAR + 1e-5
}

/// One medium value through both cameras: each frame gives its own.
fn assert_same_fog(fog: &dyn Medium, what: &str) {
    let (bevy, standard) = camera_pair();
    let image = noise_image(W, H, 11);
    let (depth_bevy, depth_standard) = (depth_buffer(&bevy), depth_buffer(&standard));
    let (at_bevy, at_standard) = (FrameInputs::new(bevy, 0.0), FrameInputs::new(standard, 0.0));
    let cpu_bevy =
        reference::fog(&image, &depth_bevy, fog, &at_bevy, &FogBlur::None).expect("CPU fog, Bevy");
    let cpu_standard = reference::fog(&image, &depth_standard, fog, &at_standard, &FogBlur::None)
        .expect("CPU fog, standard");
    let (_lock, mut r) = renderer();
    let gpu_bevy = r
        .render_fog(&image, &depth_bevy, fog, &at_bevy, &FogBlur::None)
        .expect("GPU fog, Bevy");
    let gpu_standard = r
        .render_fog(&image, &depth_standard, fog, &at_standard, &FogBlur::None)
        .expect("GPU fog, standard");
    let budget = projection_budget();
    let errors = [
        (
            "CPU Bevy vs CPU standard",
            reference::rgb_error(&cpu_bevy, &cpu_standard, 0),
        ),
        (
            "GPU Bevy vs CPU Bevy",
            reference::rgb_error(&gpu_bevy.image, &cpu_bevy, 0),
        ),
        (
            "GPU standard vs CPU standard",
            reference::rgb_error(&gpu_standard.image, &cpu_standard, 0),
        ),
        (
            "GPU Bevy vs GPU standard",
            reference::rgb_error(&gpu_bevy.image, &gpu_standard.image, 0),
        ),
    ];
    for (pair, e) in errors {
        eprintln!(
            "{what}: {pair}: max {:.2e} (budget {budget:.1e})",
            e.max_abs
        );
        assert!(e.max_abs <= budget, "{what}: {pair}: {e:?}");
    }
    // The fog is there: the sky is far from the scene's colour.
    let clear = reference::rgb_error(&cpu_bevy, &image_as_rgba(&image), 0);
    assert!(clear.max_abs > 0.2, "{what}: no fog? {clear:?}");
}

fn image_as_rgba(image: &RgbImage) -> brume::raster::RgbaImage {
    Grid::from_fn(image.width(), image.height(), |x, y| {
        let [r, g, b] = *image.get(x, y);
        [r, g, b, 1.0]
    })
}

#[test]
fn layered_fog_is_the_same_through_bevy_and_standard_projections() {
    let profile = HeightProfile::Exponential {
        density: 0.02,
        base: 0.0,
        scale_height: 15.0,
    };
    assert_same_fog(&LayeredFog::new(profile), "layered");
}

#[test]
fn distance_fog_is_the_same_through_bevy_and_standard_projections() {
    let fog = DistanceFog {
        noise: None,
        distance: 150.0,
        ..DistanceFog::default()
    };
    assert_same_fog(&fog, "distance");
}

#[test]
fn fog_reconstructs_the_same_world_point_through_both_projections() {
    // Per pixel, the CPU references of both cameras put the fragment at the scene's hit.
    let (bevy, standard) = camera_pair();
    let (depth_bevy, depth_standard) = (depth_buffer(&bevy), depth_buffer(&standard));
    let fog = LayeredFog::new(HeightProfile::EXPONENTIAL);
    let (at_bevy, at_standard) = (FrameInputs::new(bevy, 0.0), FrameInputs::new(standard, 0.0));
    for (x, row) in [(5, 30), (32, 20), (60, 38), (10, 2)] {
        let y = H - 1 - row;
        let pixel = |depth: &ScalarMap| Pixel {
            x,
            y,
            width: W,
            height: H,
            depth: f64::from(*depth.get(x, row)),
            sigma0: 1.0,
        };
        let a = fog.sample(pixel(&depth_bevy), &at_bevy);
        let b = fog.sample(pixel(&depth_standard), &at_standard);
        let t = scene_hit(bevy.view(), bevy.projection(), x, y).unwrap_or(FAR);
        let point = known_point(
            bevy.view(),
            bevy.projection(),
            ClipDepth::ZeroToOne,
            ndc(x, y),
            t,
        );
        let exact = fog.sample_point(bevy.eye(), point.world, 1.0);
        for s in [a, b] {
            let e = (s.transmission[0] - exact.transmission[0]).abs();
            assert!(e <= projection_budget(), "pixel ({x}, {y}): {e:.2e}");
        }
    }
}

// ---------------------------------------------------------------------------------------
// Media defined at run time.

/// A medium whose every string is built at run time, as a Python or engine user would.
struct RuntimeMedium {
    name: String,
    glsl: String,
    stripe_uniform: String,
    /// Stripe width (px) and number of levels: `ivec2`.
    stripes: [i32; 2],
    /// A level offset: `int`.
    offset: i32,
    colour: [f32; 3],
}

impl RuntimeMedium {
    /// τ in `levels` steps across stripes of `width` pixels: integer arithmetic on both
    /// sides, so the GPU must get the ints exactly.
    fn new(name: &str, floor: f64, stripes: [i32; 2], offset: i32) -> Self {
        let stripe_uniform = format!("u_{}_stripes", name.replace('-', "_"));
        let glsl = format!(
            "uniform ivec2 {stripe_uniform};\n\
             uniform int u_offset;\n\
             uniform vec3 u_user_colour;\n\
             MediumSample medium_sample(ivec2 pixel, float depth) {{\n\
                 int level = (pixel.x / {stripe_uniform}.x + u_offset) % {stripe_uniform}.y;\n\
                 float tau = {floor:.6} + (1.0 - {floor:.6}) * float(level)\n\
                     / float({stripe_uniform}.y - 1);\n\
                 return MediumSample(vec3(tau), u_user_colour, brume_sigma0);\n\
             }}\n"
        );
        RuntimeMedium {
            name: name.to_string(),
            glsl,
            stripe_uniform,
            stripes,
            offset,
            colour: [0.3, 0.5, 0.7],
        }
    }

    fn floor(&self) -> f64 {
        // The GLSL carries it with 6 decimals; the CPU reads it back from the same text.
        let start = self.glsl.find("float tau = ").unwrap() + "float tau = ".len();
        let end = self.glsl[start..].find(' ').unwrap() + start;
        self.glsl[start..end].parse().unwrap()
    }
}

impl Medium for RuntimeMedium {
    fn name(&self) -> Cow<'static, str> {
        Cow::Owned(self.name.clone())
    }

    fn glsl(&self) -> Cow<'static, str> {
        Cow::Owned(self.glsl.clone())
    }

    fn uniforms(&self, _frame: &FrameInputs) -> Vec<(Cow<'static, str>, UniformValue)> {
        vec![
            (
                Cow::Owned(self.stripe_uniform.clone()),
                UniformValue::IVec2(self.stripes),
            ),
            ("u_offset".into(), UniformValue::Int(self.offset)),
            ("u_user_colour".into(), UniformValue::Vec3(self.colour)),
        ]
    }

    fn chromatic(&self) -> bool {
        false
    }

    fn sigma_max(&self, sigma0: f64) -> f64 {
        sigma0
    }

    fn sample(&self, p: Pixel, _frame: &FrameInputs) -> MediumSample {
        let [width, levels] = self.stripes;
        let level = (p.x as i32 / width + self.offset) % levels;
        let floor = self.floor();
        let tau = floor + (1.0 - floor) * f64::from(level) / f64::from(levels - 1);
        MediumSample {
            transmission: [tau; 3],
            inscatter: self.colour.map(f64::from),
            sigma: p.sigma0,
        }
    }

    fn validate(&self) -> brume::Result<()> {
        Ok(())
    }
}

fn assert_gpu_matches_sample(r: &mut brume::Headless, medium: &RuntimeMedium) -> RgbImage {
    let image = noise_image(W, H, 3);
    let range = ramp_range(W, H);
    let gpu = r
        .render_fog(
            &image,
            &range,
            medium,
            &FrameInputs::default(),
            &FogBlur::None,
        )
        .expect("GPU render of a run-time medium");
    let cpu = reference::fog(
        &image,
        &range,
        medium,
        &FrameInputs::default(),
        &FogBlur::None,
    )
    .expect("CPU");
    let e = reference::rgb_error(&gpu.image, &cpu, 0);
    eprintln!("{}: max {:.2e}", medium.name(), e.max_abs);
    assert!(e.max_abs < 1e-5, "{}: {e:?}", medium.name());
    Grid::from_fn(W, H, |x, y| {
        let [r, g, b, _] = *gpu.image.get(x, y);
        [r, g, b]
    })
}

#[test]
fn a_medium_defined_at_run_time_with_int_uniforms_matches_its_sample() {
    let (_lock, mut r) = renderer();
    let name = format!("user-fog-{}", W * H);
    let medium = RuntimeMedium::new(&name, 0.2, [5, 4], 1);
    assert_gpu_matches_sample(&mut r, &medium);
    // New int values, same program: the uniforms are set per frame.
    let other = RuntimeMedium {
        stripes: [3, 7],
        offset: 2,
        ..RuntimeMedium::new(&name, 0.2, [5, 4], 1)
    };
    assert_gpu_matches_sample(&mut r, &other);
}

#[test]
fn two_media_of_one_name_with_different_glsl_get_their_own_programs() {
    let (_lock, mut r) = renderer();
    let thin = RuntimeMedium::new("same-name", 0.9, [4, 3], 0);
    let thick = RuntimeMedium::new("same-name", 0.1, [4, 3], 0);
    assert_eq!(thin.name(), thick.name());
    assert_ne!(thin.glsl(), thick.glsl());
    let a = assert_gpu_matches_sample(&mut r, &thin);
    // Keyed by name, this would reuse the first program and render 0.9's floor.
    let b = assert_gpu_matches_sample(&mut r, &thick);
    let differ = (0..W).any(|x| (a.get(x, 0)[0] - b.get(x, 0)[0]).abs() > 0.05);
    assert!(
        differ,
        "the second medium rendered with the first one's GLSL"
    );
    // And the first again, after the second: its own program, still right.
    assert_gpu_matches_sample(&mut r, &thin);
}
