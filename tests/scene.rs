//! brume's procedural scene on a headless context: the depth buffer it renders is the
//! camera's standard window depth of the geometry (checked against a CPU ray cast of the
//! same scene), the sky keeps depth 1.0 exactly, the colour is a real, deterministic
//! picture, and nothing leaks.
use crate::common;

use brume::camera::Camera;
use brume::egl::GlContext;
use brume::raster::{RgbImage, ScalarMap};
use brume::scene::{Scene, SceneRenderer, Surface};
use common::gl_lock;
use glow::HasContext;
use std::mem::ManuallyDrop;
use std::sync::Arc;

const W: usize = 96;
const H: usize = 64;

/// Window depth where the CPU and GL agree on the surface. The GL depth has f32 errors
/// (vertex transform, the perspective divide, an ulp of 6e-8 near 1) and the rasteriser's
/// fixed-point vertex snapping, which tilts the interpolated depth plane by a fraction of
/// a pixel's depth gradient. Measured on llvmpipe: 1.4e-7 at worst; the bound leaves 7x.
const DEPTH_TOLERANCE: f64 = 1e-6;

/// The same as a relative error of the eye depth z (a depth error times
/// dz/dd = z²(f − n)/(n·f), largest far away). Measured on llvmpipe: 7.7e-5 at worst.
const EYE_DEPTH_RELATIVE_TOLERANCE: f64 = 5e-4;

/// A context and the renderer on it; the renderer is dropped first.
struct Fixture {
    renderer: ManuallyDrop<SceneRenderer>,
    _ctx: GlContext,
}

impl Fixture {
    fn new() -> Fixture {
        let ctx = GlContext::new(None).unwrap_or_else(|e| panic!("cannot open a GL context: {e}"));
        let renderer = SceneRenderer::new(Arc::clone(ctx.gl())).unwrap();
        Fixture {
            renderer: ManuallyDrop::new(renderer),
            _ctx: ctx,
        }
    }

    fn render(&mut self, camera: &Camera, time: f64) -> (RgbImage, ScalarMap) {
        let frame = self.renderer.render(camera, W, H, time).unwrap();
        assert_eq!((frame.width, frame.height), (W, H));
        (frame.read_colour().unwrap(), frame.read_depth().unwrap())
    }
}

impl Drop for Fixture {
    fn drop(&mut self) {
        // SAFETY: dropped once, with its context current (it was made current by new).
        unsafe { ManuallyDrop::drop(&mut self.renderer) };
    }
}

fn tilted() -> Camera {
    Camera {
        yaw_deg: 30.0,
        pitch_deg: -10.0,
        ..Camera::default()
    }
}

/// What a pixel sees by the CPU ray cast: the plane (ground or water), an object, or the
/// sky (nothing before the far plane).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Seen {
    Sky,
    Plane,
    Object(usize),
}

/// The CPU ray cast of every pixel centre: what it sees and its eye depth (the ray has a
/// component of 1 along the view axis, so the ray parameter is the eye depth).
fn ray_cast(scene: &Scene, camera: &Camera) -> Vec<(Seen, f64)> {
    let mut out = Vec::with_capacity(W * H);
    for y in 0..H {
        for x in 0..W {
            let ray = camera.pixel_ray(x, y, W, H);
            out.push(match scene.ray_cast(camera.eye(), ray) {
                Some(hit) if hit.t < camera.far => {
                    let seen = match hit.surface {
                        Surface::Ground | Surface::Water => Seen::Plane,
                        Surface::Object(i) => Seen::Object(i),
                    };
                    (seen, hit.t)
                }
                _ => (Seen::Sky, f64::INFINITY),
            });
        }
    }
    out
}

/// Pixels whose 3x3 neighbourhood sees the same thing by the ray cast, and whose depth is
/// not within 0.1 % of the far plane: away from silhouettes, where the rasteriser and the
/// ray cast may rightly disagree about a pixel centre on an edge.
fn interior(cast: &[(Seen, f64)], camera: &Camera) -> Vec<(usize, usize)> {
    let mut out = vec![];
    for y in 1..H - 1 {
        for x in 1..W - 1 {
            let (seen, z) = cast[y * W + x];
            let uniform =
                (y - 1..=y + 1).all(|v| (x - 1..=x + 1).all(|u| cast[v * W + u].0 == seen));
            let clear_of_far = seen == Seen::Sky || z < camera.far * 0.999;
            if uniform && clear_of_far {
                out.push((x, y));
            }
        }
    }
    out
}

/// Checks the GL depth of a surface pixel against the window depth of the ray cast.
fn check_depth(camera: &Camera, x: usize, y: usize, d_gl: f64, z: f64, what: &str) {
    let d = camera.window_depth(z);
    assert!(
        (d_gl - d).abs() <= DEPTH_TOLERANCE,
        "{what} pixel ({x}, {y}): GL depth {d_gl} vs {d} (eye depth {z})"
    );
    let z_gl = camera.eye_depth(d_gl);
    assert!(
        (z_gl - z).abs() <= EYE_DEPTH_RELATIVE_TOLERANCE * z,
        "{what} pixel ({x}, {y}): GL eye depth {z_gl} vs {z}"
    );
}

#[test]
fn ground_depth_is_the_window_depth_of_the_ray_plane_intersection() {
    let _lock = gl_lock();
    let mut fx = Fixture::new();
    let camera = tilted();
    let (_, depth) = fx.render(&camera, 0.0);
    let cast = ray_cast(fx.renderer.scene(), &camera);
    let mut checked = 0;
    let (mut worst_d, mut worst_z) = (0f64, 0f64);
    for (x, y) in interior(&cast, &camera) {
        if cast[y * W + x].0 != Seen::Plane {
            continue;
        }
        // The analytic intersection of the pixel's ray with y = 0, projected.
        let ray = camera.pixel_ray(x, y, W, H);
        let t = -camera.eye().y / ray.y;
        let point = camera.eye() + ray * t;
        let (d, distance) = camera.project_depth(point).unwrap();
        assert!((distance - (point - camera.eye()).length()).abs() < 1e-9);
        let d_gl = f64::from(*depth.get(x, y));
        check_depth(&camera, x, y, d_gl, t, "ground");
        worst_d = worst_d.max((d_gl - d).abs());
        worst_z = worst_z.max((camera.eye_depth(d_gl) - t).abs() / t);
        checked += 1;
    }
    eprintln!(
        "{checked} ground pixels: window depth within {worst_d:.2e}, eye depth {worst_z:.2e}"
    );
    assert!(checked > W * H / 3, "only {checked} ground pixels");
}

#[test]
fn the_whole_depth_buffer_matches_a_ray_cast_of_the_scene() {
    let _lock = gl_lock();
    let mut fx = Fixture::new();
    for camera in [Camera::default(), tilted()] {
        let (_, depth) = fx.render(&camera, 0.0);
        let cast = ray_cast(fx.renderer.scene(), &camera);
        let pixels = interior(&cast, &camera);
        let mut objects = 0;
        let (mut worst_d, mut worst_z) = (0f64, 0f64);
        for &(x, y) in &pixels {
            let d_gl = f64::from(*depth.get(x, y));
            match cast[y * W + x] {
                (Seen::Sky, _) => assert_eq!(d_gl, 1.0, "sky pixel ({x}, {y})"),
                (seen, z) => {
                    assert!(d_gl < 1.0, "{seen:?} at pixel ({x}, {y}) has depth 1");
                    check_depth(&camera, x, y, d_gl, z, &format!("{seen:?}"));
                    worst_d = worst_d.max((d_gl - camera.window_depth(z)).abs());
                    worst_z = worst_z.max((camera.eye_depth(d_gl) - z).abs() / z);
                    objects += usize::from(matches!(seen, Seen::Object(_)));
                }
            }
        }
        eprintln!(
            "{} pixels ({objects} on objects): window depth within {worst_d:.2e}, eye depth \
             {worst_z:.2e}",
            pixels.len()
        );
        assert!(
            pixels.len() > W * H * 2 / 3,
            "{} pixels checked",
            pixels.len()
        );
        assert!(objects > 100, "only {objects} object pixels");
        // Silhouettes aside, every pixel is sky exactly where the ray cast says so.
        let mismatched = (0..W * H)
            .filter(|&i| (cast[i].0 == Seen::Sky) != (depth.as_slice()[i] == 1.0))
            .count();
        eprintln!("{mismatched} pixels disagree on the sky");
        assert!(
            mismatched < W * H / 200,
            "{mismatched} pixels disagree on the sky"
        );
    }
}

#[test]
fn the_top_of_a_level_view_is_sky_at_depth_one() {
    let _lock = gl_lock();
    let mut fx = Fixture::new();
    let camera = Camera::default();
    let (colour, depth) = fx.render(&camera, 0.0);
    // Nothing rises above 21.8° from the default eye (Scene::generate); the top of the
    // 60° view is 30° up, so rows with NDC y > tan 21.8° / tan 30° = 0.693 are all sky.
    let first_sky_row = ((0.7 + 1.0) / 2.0 * H as f64).ceil() as usize;
    for y in first_sky_row..H {
        for x in 0..W {
            assert_eq!(*depth.get(x, y), 1.0, "pixel ({x}, {y})");
            let [r, _, b] = *colour.get(x, y);
            assert!(
                b > r,
                "sky pixel ({x}, {y}) is not blue: {:?}",
                colour.get(x, y)
            );
        }
    }
    // The bottom row sees the ground or near objects, all nearer than the far plane.
    assert!((0..W).all(|x| *depth.get(x, 0) < 1.0));
}

#[test]
fn world_positions_rebuilt_from_the_depth_lie_on_the_ground() {
    let _lock = gl_lock();
    let mut fx = Fixture::new();
    let camera = tilted();
    let (_, depth) = fx.render(&camera, 0.0);
    let cast = ray_cast(fx.renderer.scene(), &camera);
    let mut checked = 0;
    for (x, y) in interior(&cast, &camera) {
        if cast[y * W + x].0 != Seen::Plane {
            continue;
        }
        let d = f64::from(*depth.get(x, y));
        let p = camera.world_position(x, y, W, H, d);
        let oracle = camera.world_position_by_inverse(x, y, W, H, d);
        let distance = (p - camera.eye()).length();
        // 1.7 m of eye height times the relative eye-depth error.
        assert!(
            p.y.abs() <= 1.7 * EYE_DEPTH_RELATIVE_TOLERANCE,
            "pixel ({x}, {y}) rebuilt at {p} ({distance} m away)"
        );
        assert!((p - oracle).length() <= 1e-6 * distance.max(1.0));
        checked += 1;
    }
    assert!(checked > W * H / 3);
}

#[test]
fn the_colour_is_a_deterministic_picture_and_time_moves_only_the_water() {
    let _lock = gl_lock();
    let mut fx = Fixture::new();
    let camera = Camera::default();
    let (colour, depth) = fx.render(&camera, 0.0);
    let pixels = colour.as_slice();
    assert!(pixels.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
    let mean = pixels.iter().flatten().sum::<f32>() / (3 * pixels.len()) as f32;
    assert!(mean > 0.05 && mean < 2.0, "mean {mean}");
    let variance = pixels
        .iter()
        .flatten()
        .map(|v| (v - mean) * (v - mean))
        .sum::<f32>()
        / (3 * pixels.len()) as f32;
    assert!(variance > 1e-3, "variance {variance}");
    let distinct: std::collections::HashSet<[u32; 3]> =
        pixels.iter().map(|p| p.map(f32::to_bits)).collect();
    assert!(
        distinct.len() > W * H / 4,
        "{} distinct colours",
        distinct.len()
    );

    // Another size in between, then the same frame again: bit for bit.
    fx.renderer.render(&camera, 40, 30, 0.0).unwrap();
    let (again, depth_again) = fx.render(&camera, 0.0);
    assert_eq!(colour, again);
    assert_eq!(depth, depth_again);

    // The waves move: the water changes colour, the depth does not change at all.
    let (later, depth_later) = fx.render(&camera, 1.5);
    assert_eq!(depth, depth_later);
    let cast = ray_cast(fx.renderer.scene(), &camera);
    let changed: Vec<usize> = (0..W * H)
        .filter(|&i| pixels[i] != later.as_slice()[i])
        .collect();
    assert!(!changed.is_empty(), "time changed nothing");
    let on_plane = changed
        .iter()
        .filter(|&&i| cast[i].0 == Seen::Plane)
        .count();
    assert!(
        on_plane * 10 >= changed.len() * 9,
        "{on_plane} of {} changes on the plane",
        changed.len()
    );
}

#[test]
fn objects_are_freed_and_the_gl_state_is_left_clean() {
    let _lock = gl_lock();
    let ctx = GlContext::new(None).unwrap();
    let gl = Arc::clone(ctx.gl());
    let before = brume::gpu::live_objects();
    let mut renderer = SceneRenderer::new(Arc::clone(&gl)).unwrap();
    let built = brume::gpu::live_objects();
    assert!(built > before);
    let frame = renderer.render(&Camera::default(), W, H, 0.0).unwrap();
    frame.read_depth().unwrap();
    let rendered = brume::gpu::live_objects();
    // Frames of the same size reuse the targets; another size replaces them.
    renderer.render(&tilted(), W, H, 2.0).unwrap();
    assert_eq!(brume::gpu::live_objects(), rendered);
    renderer.render(&tilted(), W / 2, H / 2, 2.0).unwrap();
    assert_eq!(brume::gpu::live_objects(), rendered);
    // SAFETY: plain state queries on the current context.
    unsafe {
        for (name, parameter) in [
            ("framebuffer", glow::DRAW_FRAMEBUFFER_BINDING),
            ("read framebuffer", glow::READ_FRAMEBUFFER_BINDING),
            ("program", glow::CURRENT_PROGRAM),
            ("vertex array", glow::VERTEX_ARRAY_BINDING),
            ("array buffer", glow::ARRAY_BUFFER_BINDING),
            ("texture on unit 0", glow::TEXTURE_BINDING_2D),
        ] {
            assert_eq!(gl.get_parameter_i32(parameter), 0, "{name} left bound");
        }
        assert_eq!(
            gl.get_parameter_i32(glow::ACTIVE_TEXTURE),
            glow::TEXTURE0 as i32
        );
        assert!(!gl.is_enabled(glow::DEPTH_TEST));
        assert_eq!(gl.get_error(), glow::NO_ERROR);
    }
    drop(renderer);
    assert_eq!(brume::gpu::live_objects(), before);
}

#[test]
fn bad_arguments_are_refused() {
    let _lock = gl_lock();
    let mut fx = Fixture::new();
    let bad_camera = Camera {
        near: 0.0,
        ..Camera::default()
    };
    let refused = fx.renderer.render(&bad_camera, W, H, 0.0).err().unwrap();
    assert!(refused.to_string().contains("near"), "{refused}");
    assert!(fx.renderer.render(&Camera::default(), 0, H, 0.0).is_err());
    assert!(fx
        .renderer
        .render(&Camera::default(), W, H, f64::NAN)
        .is_err());
    // And it still renders after the refusals.
    fx.render(&Camera::default(), 0.0);
}
