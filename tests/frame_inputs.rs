//! One medium value, many frames: the camera and the time come with each frame
//! ([`FrameInputs`]), so an engine keeps its fog and gives it a new camera and time at
//! every frame without rebuilding the medium or compiling anything.
//!
//! - The distance fog (with its drifting noise) through three frames of different cameras
//!   and times equals the CPU reference of each frame within `tests/distance_fog.rs`'s
//!   per-pixel bounds, and the pipeline's program count stays what the first frame made.
//! - The layered fog through three cameras on a host's own textures equals the CPU
//!   reference of each frame within `tests/engine_fog.rs`'s one-pass tolerance (2e-5: one
//!   f32 ulp of the stored window depth near the far plane is a relative 2e-5 of
//!   distance, τ = e^(−F) moves by at most F·2e-5 with F ≤ 0.5 here, plus a few f32 ulps),
//!   and the frames after the first create no GL object and no program.
//! - A medium that reads a depth buffer, given a frame without a camera, is refused with
//!   [`Error::MissingCamera`] by every entry point, before anything is drawn.
//! - A CPU-buffer `Renderer` keeps its uploads' textures: the photos after the first of
//!   one size create no GL object, and each result is bit for bit a fresh renderer's.
use crate::common;
use crate::distance_fog;

use brume::camera::{Camera, FrameInputs};
use brume::gpu::framebuffer::Framebuffer;
use brume::gpu::texture::{Filter, TexelFormat, Texture};
use brume::medium::{HeightProfile, LayeredFog};
use brume::raster::Grid;
use brume::{reference, Blur, Encoding, Error, FogBlur, Haze, Input, Output};
use common::{noise_image, synthetic_depth_buffer};
use std::sync::Arc;

/// engine_fog.rs's tolerance for a one-pass fog (module docs).
const ONE_PASS_TOLERANCE: f64 = 2e-5;

/// Three frames of a moving, turning camera: eye height 1.7 m, near 0.5, far 120, as
/// engine_fog.rs's scene camera, so that the stored depth keeps its precision.
fn moving_cameras() -> [Camera; 3] {
    let at = |position: [f64; 3], yaw_deg: f64, pitch_deg: f64| Camera {
        position,
        yaw_deg,
        pitch_deg,
        fov_y_deg: 60.0,
        near: 0.5,
        far: 120.0,
    };
    [
        at([1.0, 1.7, 0.0], 8.0, -6.0),
        at([-2.0, 2.5, 6.0], -12.0, -3.0),
        at([3.0, 1.2, 12.0], 20.0, 4.0),
    ]
}

#[test]
fn one_distance_fog_renders_frames_of_other_cameras_and_times_as_the_reference() {
    let (_lock, mut r) = common::renderer();
    // One value for every frame: the noise drifts with each frame's time.
    let fog = distance_fog::fog(Some(distance_fog::noise()), 6.0);
    let frames = [
        (distance_fog::camera_at([0.0, 1.7, 0.0]), 0.0),
        (distance_fog::camera_at([14.0, 2.4, -30.0]), 2.5),
        (
            Camera {
                yaw_deg: -15.0,
                pitch_deg: 2.0,
                ..distance_fog::camera_at([-40.0, 1.7, 25.0])
            },
            40.0,
        ),
    ];
    let mut programs = None;
    let mut images = Vec::new();
    for (k, (camera, time)) in frames.iter().enumerate() {
        let what = format!("frame {k}, t = {time} s");
        let (image, _) = distance_fog::check(&mut r, &fog, camera, *time, &what);
        let count = r.renderer().unwrap().pipeline().program_count();
        assert_eq!(
            *programs.get_or_insert(count),
            count,
            "{what}: a new camera and time compiled a program"
        );
        images.push(image);
    }
    // The frames differ: the camera and the time reached the shader.
    assert_ne!(images[0].as_slice(), images[1].as_slice());
    assert_ne!(images[1].as_slice(), images[2].as_slice());
    // The same camera at another time moves the noise: the time alone reaches it.
    let (camera, _) = frames[0];
    let (later, _) = distance_fog::check(&mut r, &fog, &camera, 7.0, "frame 0, t = 7 s");
    let moved = reference::rgb_error(&images[0], &later, 0);
    assert!(
        moved.max_abs > 1e-3,
        "time did not move the noise: {moved:?}"
    );
}

#[test]
fn one_layered_fog_on_host_textures_makes_no_object_and_no_program_after_the_first_frame() {
    let (w, h) = (48, 32);
    let (_lock, mut headless) = common::renderer();
    let renderer = headless.renderer().unwrap();
    let gl = Arc::clone(renderer.pipeline().gl());
    let cameras = moving_cameras();
    let profile = HeightProfile::Exponential {
        density: 0.003,
        base: 0.0,
        scale_height: 10.0,
    };
    let fog = LayeredFog {
        colour: [0.7, 0.75, 0.8],
        ..LayeredFog::for_camera(cameras[0], profile)
    };
    // The host's frames, uploaded before the loop as an engine's are drawn before it fogs.
    let image = noise_image(w, h, 17);
    let upload = |values: &[f32], format| {
        let t = Texture::new(&gl, w, h, format, Filter::Nearest, None).unwrap();
        t.upload_flipped(values);
        t
    };
    let colour = upload(image.as_slice().as_flattened(), TexelFormat::Rgb32F);
    let depths: Vec<_> = cameras
        .iter()
        .map(|c| synthetic_depth_buffer(c, w, h))
        .collect();
    let depth_textures: Vec<_> = depths
        .iter()
        .map(|d| upload(d.as_slice(), TexelFormat::R32F))
        .collect();
    let target = Texture::new(&gl, w, h, TexelFormat::Rgba32F, Filter::Nearest, None).unwrap();
    let read_back = Framebuffer::over(&gl, &[&target], "the host's target").unwrap();
    let output = Output::Texture {
        texture: target.raw(),
        encoding: Encoding::Linear,
    };
    let pipeline = renderer.pipeline();
    let mut after_first = None;
    for (k, camera) in cameras.iter().enumerate() {
        let frame = FrameInputs::new(*camera, k as f64 / 60.0);
        let input = Input {
            colour: colour.raw(),
            colour_encoding: Encoding::Linear,
            depth: depth_textures[k].raw(),
            width: w,
            height: h,
            frame,
        };
        pipeline
            .fog(&input, &fog, &FogBlur::None, &output)
            .expect("GPU fog");
        let made = (brume::gpu::objects_created(), pipeline.program_count());
        let first = *after_first.get_or_insert(made);
        assert_eq!(made, first, "frame {k}: (GL objects, programs) grew");
        let mut gpu = Grid::from_vec(w, h, read_back.read_rgba().unwrap());
        gpu.flip_rows();
        let cpu = reference::fog(&image, &depths[k], &fog, &frame, &FogBlur::None).unwrap();
        let e = reference::rgb_error(&gpu, &cpu, 0);
        eprintln!(
            "layered fog, frame {k}: max {:.2e} (tolerance {ONE_PASS_TOLERANCE:.0e})",
            e.max_abs
        );
        assert!(e.max_abs <= ONE_PASS_TOLERANCE, "frame {k}: {e:?}");
        // The fog is there, and differs from frame to frame (the camera reached it).
        let clear = Grid::from_fn(w, h, |x, y| {
            let [r, g, b] = *image.get(x, y);
            [r, g, b, 1.0]
        });
        let fogged = reference::rgb_error(&cpu, &clear, 0);
        assert!(fogged.max_abs > 0.05, "frame {k}: no fog? {fogged:?}");
    }
    assert_eq!(after_first.unwrap().1, pipeline.program_count());
}

#[test]
fn a_depth_buffer_medium_without_a_camera_is_refused_by_every_entry_point() {
    let (w, h) = (16, 12);
    let camera = moving_cameras()[0];
    let image = noise_image(w, h, 5);
    let depth = synthetic_depth_buffer(&camera, w, h);
    let fog = LayeredFog::for_camera(camera, HeightProfile::EXPONENTIAL);
    let none = FrameInputs::default();
    let is_missing_camera = |e: Error, what: &str| {
        let text = e.to_string();
        assert!(
            matches!(&e, Error::MissingCamera { medium } if medium == "layered"),
            "{what}: {e:?}"
        );
        assert!(
            text.contains("camera: Some") && text.contains("layered"),
            "{what}: {text}"
        );
    };
    is_missing_camera(
        reference::fog(&image, &depth, &fog, &none, &FogBlur::None).unwrap_err(),
        "reference::fog",
    );
    is_missing_camera(
        reference::render(&image, &depth, &fog, &Blur::default()).unwrap_err(),
        "reference::render",
    );
    let (_lock, mut r) = common::renderer();
    is_missing_camera(
        r.render_fog(&image, &depth, &fog, &none, &FogBlur::None)
            .unwrap_err(),
        "Renderer::render_fog, no blur",
    );
    is_missing_camera(
        r.render(&image, &depth, &fog, &Blur::default())
            .unwrap_err(),
        "Renderer::render (a photo's call: no camera)",
    );
    let renderer = r.renderer().unwrap();
    let gl = Arc::clone(renderer.pipeline().gl());
    let texture = |format| Texture::new(&gl, w, h, format, Filter::Nearest, None).unwrap();
    let (colour, depth_texture, target) = (
        texture(TexelFormat::Rgb32F),
        texture(TexelFormat::R32F),
        texture(TexelFormat::Rgba32F),
    );
    let input = Input {
        colour: colour.raw(),
        colour_encoding: Encoding::Linear,
        depth: depth_texture.raw(),
        width: w,
        height: h,
        frame: none,
    };
    let output = Output::Texture {
        texture: target.raw(),
        encoding: Encoding::Linear,
    };
    let pipeline = renderer.pipeline();
    let programs = pipeline.program_count();
    is_missing_camera(
        pipeline
            .fog(&input, &fog, &FogBlur::None, &output)
            .unwrap_err(),
        "Pipeline::fog",
    );
    is_missing_camera(
        pipeline
            .render(&input, &fog, &Blur::default(), &output)
            .unwrap_err(),
        "Pipeline::render",
    );
    is_missing_camera(
        pipeline
            .blend_fog(depth_texture.raw(), w, h, &fog, &none, &output)
            .unwrap_err(),
        "Pipeline::blend_fog",
    );
    assert_eq!(
        pipeline.program_count(),
        programs,
        "refused before compiling"
    );
    // With the camera, the same medium renders; a range-map medium needs none.
    let with = Input {
        frame: FrameInputs::new(camera, 0.0),
        ..input
    };
    pipeline
        .fog(&with, &fog, &FogBlur::None, &output)
        .expect("with its camera");
    pipeline
        .fog(&input, &Haze::default(), &FogBlur::None, &output)
        .expect("Haze needs no camera");
    // A frame's own values are checked too: a time that is not finite.
    let e = reference::fog(
        &image,
        &depth,
        &fog,
        &FrameInputs::new(camera, f64::NAN),
        &FogBlur::None,
    )
    .unwrap_err();
    assert!(e.to_string().contains("time"), "{e}");
}

/// Photos of one size through one `Renderer`: the uploads' textures are kept (no GL object
/// made after the first photo), each result equals a fresh renderer's bit for bit (no
/// stale texel of the photo before), and a photo of another size gets textures of its own.
#[test]
fn renderer_keeps_its_uploads_between_photos() {
    let (_lock, mut kept) = common::renderer();
    let (haze, blur) = (Haze::default(), Blur::default());
    let range = |w: usize, h: usize, seed: u64| {
        let noise = noise_image(w, h, seed);
        Grid::from_fn(w, h, |x, y| 0.05 + 0.9 * noise.get(x, y)[1])
    };
    for (k, (w, h)) in [(24, 16), (24, 16), (24, 16), (20, 14)]
        .into_iter()
        .enumerate()
    {
        let (image, depth) = (noise_image(w, h, 10 + k as u64), range(w, h, 20 + k as u64));
        let before = brume::gpu::objects_created();
        let out = kept.render(&image, &depth, &haze, &blur).unwrap();
        let made = brume::gpu::objects_created() - before;
        match k {
            1 | 2 => assert_eq!(made, 0, "photo {k} of the same size: GL objects made"),
            _ => assert!(made >= 2, "photo {k}: {made} objects, expected its uploads"),
        }
        let fresh = common::headless()
            .render(&image, &depth, &haze, &blur)
            .unwrap();
        assert_eq!(out.image, fresh.image, "photo {k}");
    }
}
