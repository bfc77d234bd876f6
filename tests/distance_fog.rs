//! Paper 001's distance fog on the GPU against the f64 CPU reference, on a frame whose
//! depth buffer is synthesised from an analytic scene: a ground plane (y = 0), three boxes
//! 5 m, 55 m and 650 m away, and the sky (window depth 1) above them.
//!
//! # Tolerance
//!
//! The GPU and the reference do not evaluate the medium at quite the same point: the GPU
//! rebuilds the position in f32 by the fast path (eye + ray·z, paper 003), the reference
//! by the inverse matrices in f64 (the oracle), and the GPU's bilinear filter may round
//! its weights. The tolerance at each pixel is a first-order bound on what these
//! differences do to the output, from the actual values at that pixel, plus the pipeline's
//! f32 rounding budget of `tests/gpu_vs_cpu.rs` (4e-7 per pass over N + 2 passes):
//!
//! - **Distance.** The shader's eye depth is A/((d − 1) + C), C = 1 + B, with A and C
//!   rounded to f32: δz/z ≤ |δC|/|C| + |δA|/|A| + 3·2⁻²⁴ (the exact rounding errors of
//!   this camera's constants; d − 1 is exact or rounds by 2⁻²⁴·|d − 1|, and both terms of
//!   the sum have the same sign). The interpolated ray adds 2⁻²⁰ (relative, direction and
//!   length). So δl ≤ l·(δz/z + 2⁻²⁰), which also bounds the error of the position.
//! - **Distance ramp.** δg ≤ g·(e·δl/(l − s) + 2⁻¹⁸) (GLSL's pow is exp2(y·log2 x); 2⁻¹⁸
//!   covers the spec's ulps of both at these magnitudes).
//! - **Noise.** The texture coordinates move by W·(δl/size + 2⁻²²·(1 + l/size)) texels
//!   (position error, then the f32 arithmetic of the coordinates), and bilinear weights
//!   may be quantised to q = 2⁻⁸ (llvmpipe's and most GPUs' 8-bit sub-texel fraction). The
//!   bilinear interpolant changes by at most Δ per texel of displacement per axis, Δ the
//!   largest difference between neighbouring texels (across the wrap too), so
//!   δN ≤ 2Δ·(texel displacement + q) and δk = (high − low)·δN.
//! - **Density.** F = min(g·k, M) is 1-Lipschitz in g·k: δF ≤ k·δg + g·δk + 2⁻²³.
//! - **Scattering.** The ray's direction error 2⁻¹⁹ moves cosθ by as much; t⁴ by
//!   4·2⁻¹⁹ (+2⁻¹⁸ for pow); the path fraction (l − S)/l by (S/l)·δl/l.
//! - **Output, no blur.** out = τE + (1 − τ)·L with τ = 1 − F:
//!   δout ≤ |E − L|·δF + (F + δF)·δL.
//! - **Output, blurred.** The diffusion is a convex combination at every step (rates
//!   ≤ ¼ on four neighbours, bilinear reads), so it does not grow a max-norm error of its
//!   input: δout ≤ max δF·(1 + max L) + max δL over the frame. The blur scale differs by
//!   δσ ≤ λ·(δr·√Ds + r·δ√Ds) with Ds = −ln(1 − F), δDs ≤ δF/(1 − F − δF) + 2⁻²¹ (GLSL's
//!   log in [½, 2] has an absolute error of 2⁻²¹) and δ√Ds ≤ min(√δDs, δDs/√Ds); a
//!   Gaussian blur of values in [0, 1] changes by at most (4/e)·δσ/σ (∫|∂G/∂σ| over the
//!   plane), which bounds what the scheme, an approximation of it, does too.
use crate::common;

use brume::camera::{Camera, FrameInputs};
use brume::medium::{DistanceFog, FogNoise, Medium};
use brume::raster::{Grid, RgbImage, ScalarMap};
use brume::{reference, Blur, FogBlur, Headless};
use common::ray_enters_box;
use glam::DVec3;

const W: usize = 64;
const H: usize = 48;
const F32_PER_PASS: f64 = 4e-7;
const EPS: f64 = 1.0 / (1u64 << 24) as f64;
/// Bilinear weight quantum: an 8-bit sub-texel fraction.
const WEIGHT_QUANTUM: f64 = 1.0 / 256.0;

/// An axis-aligned box, eye-relative (metres).
struct Cuboid {
    min: DVec3,
    max: DVec3,
    colour: [f32; 3],
}

fn boxes(ground: f64) -> [Cuboid; 3] {
    [
        Cuboid {
            min: DVec3::new(-3.0, ground, -6.0),
            max: DVec3::new(-1.0, ground + 2.0, -4.0),
            colour: [0.8, 0.25, 0.2],
        },
        Cuboid {
            min: DVec3::new(4.0, ground, -60.0),
            max: DVec3::new(14.0, ground + 12.0, -50.0),
            colour: [0.2, 0.6, 0.3],
        },
        Cuboid {
            min: DVec3::new(-150.0, ground, -700.0),
            max: DVec3::new(-60.0, ground + 80.0, -600.0),
            colour: [0.9, 0.35, 0.1],
        },
    ]
}

/// The colour and window-depth buffers of the scene seen by `camera` (row 0 at the top,
/// as `Renderer::render` takes them: buffer row y is GL row H − 1 − y).
fn scene(camera: &Camera) -> (RgbImage, ScalarMap) {
    let eye = camera.eye();
    let ground = 0.0 - eye.y; // eye-relative height of the ground
    let cuboids = boxes(ground);
    let mut colour = Grid::filled(W, H, [0.0f32; 3]);
    let mut depth = Grid::filled(W, H, 1.0f32);
    for gl_row in 0..H {
        let y = H - 1 - gl_row;
        for x in 0..W {
            // Ray parameter t: the ray has component 1 along the view axis, so t is the
            // eye depth.
            let ray = camera.pixel_ray(x, gl_row, W, H);
            let mut best: Option<(f64, [f32; 3])> = None;
            let mut consider = |t: f64, c: [f32; 3]| {
                if t < camera.far && best.is_none_or(|(b, _)| t < b) {
                    best = Some((t, c));
                }
            };
            if ray.y < 0.0 {
                let t = ground / ray.y;
                let p = eye + ray * t;
                // A checkerboard of 2 m squares: edges for the blur to act on.
                let odd = ((p.x / 2.0).floor() + (p.z / 2.0).floor()) as i64 % 2 != 0;
                consider(
                    t,
                    if odd {
                        [0.35, 0.3, 0.2]
                    } else {
                        [0.15, 0.12, 0.1]
                    },
                );
            }
            for b in &cuboids {
                if let Some(t) = ray_enters_box(DVec3::ZERO, ray, b.min, b.max) {
                    consider(t, b.colour);
                }
            }
            let (d, c) = match best {
                Some((t, c)) => {
                    let (d, _) = camera.project_depth(eye + ray * t).expect("in front");
                    (d, c)
                }
                // The sky: the far plane, a gradient (it is fogged like any other pixel).
                None => (1.0, [0.55, 0.7, 0.9 - 0.2 * (y as f32 / H as f32)]),
            };
            *depth.get_mut(x, y) = d as f32;
            *colour.get_mut(x, y) = c;
        }
    }
    (colour, depth)
}

/// A camera at eye height looking a little down and to the right.
pub(crate) fn camera_at(position: [f64; 3]) -> Camera {
    Camera {
        position,
        yaw_deg: 8.0,
        pitch_deg: -3.0,
        ..Camera::default()
    }
}

/// The fog of these tests; each frame gives it its camera and time.
pub(crate) fn fog(noise: Option<FogNoise>, lambda: f64) -> DistanceFog {
    DistanceFog {
        // Toward the light: in view, right of centre and above the horizon.
        light_direction: [0.35, 0.12, -1.0],
        noise,
        lambda,
        ..DistanceFog::default()
    }
}

/// A generated noise with a tile of 40 m, so that the test frame crosses several tiles.
pub(crate) fn noise() -> FogNoise {
    FogNoise {
        size: 40.0,
        ..FogNoise::generate(128, 2018).unwrap()
    }
}

/// The largest difference between neighbouring texels of the noise, wrap included.
fn largest_texel_step(n: &FogNoise) -> f64 {
    let (w, h) = (n.lookup.width() as i64, n.lookup.height() as i64);
    let mut step: f64 = 0.0;
    for y in 0..h {
        for x in 0..w {
            let v = n.lookup.texel(x, y);
            step = step.max((n.lookup.texel(x + 1, y) - v).abs());
            step = step.max((n.lookup.texel(x, y + 1) - v).abs());
        }
    }
    step
}

/// Per pixel (buffer order): the bound on the unblurred output's error, δF, δL (max over
/// channels) and δσ/σ (see the module docs).
struct PixelBound {
    out: f64,
    density: f64,
    inscatter: f64,
    /// The reference's L∞ (largest channel).
    inscatter_value: f64,
    sigma_rel: f64,
}

#[allow(clippy::too_many_arguments)]
fn pixel_bound(
    fog: &DistanceFog,
    camera: &Camera,
    time: f64,
    x: usize,
    y: usize,
    d: f64,
    e: [f32; 3],
    sigma0: f64,
) -> PixelBound {
    let gl_row = H - 1 - y;
    // The shader's A / ((d − 1) − c) with its f32 constants: d − 1 is exact for d ≥ ½ and
    // rounds by 2⁻²⁴·|d − 1| below; both terms have the same sign.
    let [a, c] = camera.shader_depth_constants();
    let [a32, c32] = [a, c].map(|v| f64::from(v as f32));
    let rel_z = (c32 - c).abs() / c.abs() + (a32 - a).abs() / a.abs() + 3.0 * EPS;
    let world = camera.world_position_by_inverse(x, gl_row, W, H, d);
    let point = fog.at(camera.eye(), world, time);
    let l = point.distance;
    let dl = l * (rel_z + 1.0 / (1u64 << 20) as f64);

    let g = fog.distance_ramp(l);
    let dg = if l > fog.start_distance {
        g * (fog.exponent * dl / (l - fog.start_distance) + 1.0 / (1u64 << 18) as f64)
    } else {
        0.0
    };
    // The density factor k and the colour factor (tint, 1 + s·(2N − 1)), and their errors.
    let (k, dk, tint, dtint) = match &fog.noise {
        Some(n) => {
            let texels = n.lookup.width().max(n.lookup.height()) as f64;
            let shift = texels * (dl / n.size + 4.0 * EPS * (1.0 + l / n.size));
            let dn = 2.0 * largest_texel_step(n) * (shift + WEIGHT_QUANTUM);
            (
                n.factor(world, time),
                (n.high - n.low).abs() * dn + 4.0 * EPS,
                n.colour_factor(world, time),
                2.0 * n.colour_strength * dn + 4.0 * EPS,
            )
        }
        None => (1.0, 0.0, 1.0, 0.0),
    };
    // F = min(g·k, M): where the reference's g·k clears the cap by more than the error
    // of g·k, both sides are capped and agree exactly.
    let product = k * dg + g * dk;
    let f = point.density;
    let density = if g * k - product > fog.max_density {
        0.0
    } else {
        product + 2.0 * EPS
    };

    let dcos = 2.0 / (1u64 << 20) as f64;
    let dpow = fog.scatter_exponent * dcos + 1.0 / (1u64 << 18) as f64;
    let dscatter = dpow + (fog.scatter_start / l) * (dl / l) + 2.0 * EPS;
    // L = (C + Cs·scatter)·tint, scatter ≤ 1: δL ≤ Cs·δscatter·(tint + δtint) + (C + Cs)·δtint.
    let inscatter = (0..3)
        .map(|c| {
            let (base, glow) = (f64::from(fog.colour[c]), f64::from(fog.scatter_colour[c]));
            glow * dscatter * (tint + dtint) + (base + glow) * dtint + 4.0 * EPS
        })
        .fold(0.0, f64::max);
    let out = (0..3)
        .map(|c| (f64::from(e[c]) - point.colour[c]).abs() * density + (f + density) * inscatter)
        .fold(0.0, f64::max);

    let ds = -(-f).ln_1p();
    let dds = density / (1.0 - f - density) + 1.0 / (1u64 << 21) as f64;
    let droot = if ds > 0.0 {
        dds.sqrt().min(dds / ds.sqrt())
    } else {
        dds.sqrt()
    };
    let r = l / fog.range_unit;
    let dr = if r < 1.0 { dl / fog.range_unit } else { 0.0 };
    let sigma = brume::medium::blur_from_optical_depth(sigma0, fog.lambda, r, ds);
    let dsigma = fog.lambda * (dr * ds.sqrt() + r.min(1.0) * droot) + 4.0 * EPS * sigma;
    PixelBound {
        out,
        density,
        inscatter,
        inscatter_value: point.colour.iter().copied().fold(0.0, f64::max),
        sigma_rel: dsigma / sigma,
    }
}

/// Renders `fog` over the scene seen by `camera` at `time` on the GPU and on the CPU, and
/// checks every pixel against its bound. Returns the GPU image and the largest error.
pub(crate) fn check(
    r: &mut Headless,
    fog: &DistanceFog,
    camera: &Camera,
    time: f64,
    what: &str,
) -> (brume::raster::RgbaImage, f64) {
    let (image, depth) = scene(camera);
    let blur = Blur::default();
    let frame = FrameInputs::new(*camera, time);
    let gpu = r
        .render_fog(&image, &depth, fog, &frame, &FogBlur::Diffusion(blur))
        .expect("GPU render");
    let cpu =
        reference::fog(&image, &depth, fog, &frame, &FogBlur::Diffusion(blur)).expect("CPU render");
    let steps = gpu.schedule.steps;
    let budget = F32_PER_PASS * f64::from(steps + 2);
    let bounds = Grid::from_fn(W, H, |x, y| {
        pixel_bound(
            fog,
            camera,
            time,
            x,
            y,
            f64::from(*depth.get(x, y)),
            *image.get(x, y),
            blur.sigma0,
        )
    });
    // How far the diffusion reaches: step k reads (bilinearly) at ±h_k, largest at the
    // largest rate, so an output pixel depends on inputs at most Σ⌈h_k⌉ px away per axis.
    let schedule = &gpu.schedule;
    let top_rate = schedule.rate(schedule.sigma_max);
    let reach: usize = (0..steps)
        .map(|k| schedule.offset(top_rate, k).ceil() as usize)
        .sum();
    let window = |x: usize, y: usize| {
        let xs = x.saturating_sub(reach)..=(x + reach).min(W - 1);
        let ys = y.saturating_sub(reach)..=(y + reach).min(H - 1);
        ys.flat_map(move |j| xs.clone().map(move |i| (i, j)))
    };
    let window_max = |x: usize, y: usize, f: &dyn Fn(&PixelBound) -> f64| {
        window(x, y)
            .map(|(i, j)| f(bounds.get(i, j)))
            .fold(0.0, f64::max)
    };
    // The density error bound, diffused like the image (with the reference's rates).
    let samples = reference::sample(&depth, fog, &frame, blur.sigma0);
    let rates = samples.map(|s| schedule.rate(s.sigma));
    let mut spread = bounds.map(|b| [b.density]);
    reference::diffuse(&mut spread, &rates, schedule);
    // The oscillation of the pre-multiplied field (τ·E and τ) within reach of each pixel.
    let field = reference::premultiply(&image, &samples);
    let oscillation = |x: usize, y: usize| {
        (0..6)
            .map(|c| {
                let values = || window(x, y).map(|(i, j)| field.get(i, j)[c]);
                values().fold(f64::MIN, f64::max) - values().fold(f64::MAX, f64::min)
            })
            .fold(0.0, f64::max)
    };
    let bound_at = |x: usize, y: usize| {
        let b = bounds.get(x, y);
        budget
            + if steps == 0 {
                b.out
            } else {
                let gain = 1.0 + b.inscatter_value;
                spread.get(x, y)[0] * gain
                    + b.inscatter
                    + 4.0 / std::f64::consts::E
                        * window_max(x, y, &|b| b.sigma_rel)
                        * gain
                        * oscillation(x, y)
                        / 2.0
            }
    };
    let (mut largest, mut largest_ratio, mut largest_bound) = (0.0f64, 0.0f64, 0.0f64);
    for y in 0..H {
        for x in 0..W {
            let bound = bound_at(x, y);
            largest_bound = largest_bound.max(bound);
            let (p, q) = (gpu.image.get(x, y), cpu.get(x, y));
            for c in 0..3 {
                let err = (f64::from(p[c]) - f64::from(q[c])).abs();
                assert!(p[c].is_finite(), "{what}: pixel ({x}, {y}) is {p:?}");
                assert!(
                    err <= bound,
                    "{what}: pixel ({x}, {y}) channel {c}: GPU {} vs CPU {}, error {err:.3e} > bound {bound:.3e}",
                    p[c],
                    q[c]
                );
                largest = largest.max(err);
                largest_ratio = largest_ratio.max(err / bound);
            }
        }
    }
    let e = reference::rgb_error(&gpu.image, &cpu, 0);
    let most = |f: &dyn Fn(&PixelBound) -> f64| bounds.as_slice().iter().map(f).fold(0.0, f64::max);
    eprintln!(
        "{what}: N = {steps}, reach {reach} px, max error {largest:.2e} (rms {:.1e}), \
         largest error/bound {largest_ratio:.2}, bounds up to {largest_bound:.2e} \
         (δF ≤ {:.1e}, δL ≤ {:.1e}, δσ/σ ≤ {:.1e})",
        e.rms,
        most(&|b| b.density),
        most(&|b| b.inscatter),
        most(&|b| b.sigma_rel)
    );
    (gpu.image, largest)
}

#[test]
fn distance_fog_matches_reference_without_and_with_noise_and_blur() {
    let (_lock, mut r) = common::renderer();
    let camera = camera_at([0.0, 1.7, 0.0]);
    for (noise, label) in [(None, "no noise"), (Some(noise()), "noise")] {
        for lambda in [0.0, 6.0] {
            let fog = fog(noise.clone(), lambda);
            check(
                &mut r,
                &fog,
                &camera,
                0.0,
                &format!("{label}, λ = {lambda}"),
            );
        }
    }
}

#[test]
fn far_camera_and_late_time_match_reference() {
    // Eye 12 km from the origin and an hour of drift: the shader gets the noise origin
    // reduced to one tile, the reference computes it in f64 from the full values.
    let (_lock, mut r) = common::renderer();
    let camera = camera_at([5_000.25, 1.7, -12_000.5]);
    let fog = fog(Some(noise()), 0.0);
    check(&mut r, &fog, &camera, 3_600.0, "far camera, t = 3600 s");
}

#[test]
fn the_scene_is_fogged_as_the_paper_says() {
    let (_lock, mut r) = common::renderer();
    let camera = camera_at([0.0, 1.7, 0.0]);
    let fog = fog(None, 0.0);
    let (image, depth) = scene(&camera);
    let frame = FrameInputs::new(camera, 0.0);
    let out = r
        .render_fog(
            &image,
            &depth,
            &fog,
            &frame,
            &FogBlur::Diffusion(Blur::default()),
        )
        .unwrap()
        .image;
    // The near box (5 m) keeps most of its colour, the far one (650 m) is half fog.
    let near_box = pixel_of(&camera, DVec3::new(-2.0, 1.0 - 1.7, -4.0));
    let far_box = pixel_of(&camera, DVec3::new(-100.0, 40.0 - 1.7, -600.0));
    // The share of fog in the blue channel, where box and fog colours differ most:
    // out = E + F·(L − E).
    let mix = |(x, y): (usize, usize)| {
        let d = f64::from(*depth.get(x, y));
        let world = camera.world_position_by_inverse(x, H - 1 - y, W, H, d);
        let l = fog.at(camera.eye(), world, 0.0).colour[2];
        let (e, o) = (f64::from(image.get(x, y)[2]), f64::from(out.get(x, y)[2]));
        (o - e) / (l - e)
    };
    let (near, far) = (mix(near_box), mix(far_box));
    assert!(near > 0.0 && near < 0.2, "near box fog share {near}");
    assert!(
        far > 0.3 && far <= fog.max_density + 1e-4,
        "far box fog share {far}"
    );
    // Toward the light the sky is warmer than away from it (red over blue).
    let warmth = |x: usize| {
        let p = out.get(x, 2);
        p[0] / p[2]
    };
    let light = fog.light();
    let toward = (0..W)
        .max_by(|&a, &b| {
            let dot = |x: usize| camera.pixel_ray(x, H - 3, W, H).normalize().dot(light);
            dot(a).total_cmp(&dot(b))
        })
        .unwrap();
    let away = if toward < W / 2 { W - 1 } else { 0 };
    assert!(
        warmth(toward) > warmth(away) + 0.05,
        "{} vs {}",
        warmth(toward),
        warmth(away)
    );
}

/// The buffer pixel (row 0 at the top) that sees the eye-relative point `p`.
fn pixel_of(camera: &Camera, p: DVec3) -> (usize, usize) {
    let to = p;
    let (f, r, u) = (camera.forward(), camera.right(), camera.up());
    let z = to.dot(f);
    let ty = (camera.fov_y_deg.to_radians() / 2.0).tan();
    let aspect = W as f64 / H as f64;
    let ndc_x = to.dot(r) / z / (ty * aspect);
    let ndc_y = to.dot(u) / z / ty;
    let x = ((ndc_x + 1.0) / 2.0 * W as f64) as usize;
    let gl_row = ((ndc_y + 1.0) / 2.0 * H as f64) as usize;
    (x, H - 1 - gl_row)
}

#[test]
fn time_moves_the_noise_on_the_gpu() {
    let (_lock, mut r) = common::renderer();
    let camera = camera_at([0.0, 1.7, 0.0]);
    let now = fog(Some(noise()), 0.0);
    let (image, depth) = scene(&camera);
    let blur = FogBlur::Diffusion(Blur::default());
    let at = |t: f64| FrameInputs::new(camera, t);
    let a = r
        .render_fog(&image, &depth, &now, &at(0.0), &blur)
        .unwrap()
        .image;
    let b = r
        .render_fog(&image, &depth, &now, &at(0.0), &blur)
        .unwrap()
        .image;
    let c = r
        .render_fog(&image, &depth, &now, &at(5.0), &blur)
        .unwrap()
        .image;
    assert_eq!(
        a.as_slice(),
        b.as_slice(),
        "the same time renders the same frame"
    );
    let moved = reference::rgb_error(&a, &c, 0);
    assert!(
        moved.max_abs > 1e-3,
        "time did not move the noise: {moved:?}"
    );
    // Without noise, time changes nothing.
    let plain = fog(None, 0.0);
    let p = r
        .render_fog(&image, &depth, &plain, &at(0.0), &blur)
        .unwrap()
        .image;
    let q = r
        .render_fog(&image, &depth, &plain, &at(5.0), &blur)
        .unwrap()
        .image;
    assert_eq!(p.as_slice(), q.as_slice());
    // And a fog without noise, after one with it, does not read the noise texture (the
    // same program serves both: the uniform flag decides).
    let p2 = r
        .render_fog(&image, &depth, &plain, &at(0.0), &blur)
        .unwrap()
        .image;
    assert_eq!(p.as_slice(), p2.as_slice());
    assert!(plain.validate().is_ok());
}

/// The noise of `n` at world (x, z) and `time`, by GL's bilinear filter written out here
/// (texel centres at (i + ½)/size, wrapping): independent of `Lookup::sample`.
fn noise_by_hand(n: &FogNoise, world: DVec3, time: f64) -> f64 {
    let (w, h) = (n.lookup.width() as i64, n.lookup.height() as i64);
    let u = (world.x + n.speed[0] * time) / n.size * w as f64 - 0.5;
    let v = (world.z + n.speed[2] * time) / n.size * h as f64 - 0.5;
    let (i, j) = (u.floor() as i64, v.floor() as i64);
    let (fu, fv) = (u - u.floor(), v - v.floor());
    let t = |a: i64, b: i64| n.lookup.values()[(b.rem_euclid(h) * w + a.rem_euclid(w)) as usize];
    let row = |b: i64| f64::from(t(i, b)) * (1.0 - fu) + f64::from(t(i + 1, b)) * fu;
    row(j) * (1.0 - fv) + row(j + 1) * fv
}

/// Paper 001 sec. 3.3: the noise varies the colour too. On the CPU, the in-scattered
/// colour is (C + Cs·scatter)·(1 + s·(2N − 1)) with N and the scattering computed here
/// by hand; with s = 0 it is eq. 8's colour exactly; and the GPU matches the reference
/// within the per-pixel bounds, which include the colour's share of the noise's error.
#[test]
fn noise_varies_the_fog_colour_as_the_formula_says() {
    let camera = camera_at([0.0, 1.7, 0.0]);
    let strength = 0.6;
    let tinted = fog(
        Some(FogNoise {
            colour_strength: strength,
            ..noise()
        }),
        0.0,
    );
    let plain = fog(Some(noise()), 0.0);
    assert_eq!(
        plain.noise.as_ref().unwrap().colour_strength,
        0.0,
        "default"
    );
    let light = DVec3::from_array(tinted.light_direction).normalize();
    let (mut darkest, mut brightest) = (f64::MAX, f64::MIN);
    for i in 0..400 {
        let p = DVec3::new(
            -200.0 + 1.37 * i as f64,
            0.4 * (i % 7) as f64,
            -30.0 - 2.3 * i as f64,
        );
        let to = p - camera.eye();
        let l = to.length();
        let towards = (to / l).dot(light).clamp(0.0, 1.0);
        let scatter = towards.powf(tinted.scatter_exponent)
            * ((l - tinted.scatter_start) / l).clamp(0.0, 1.0);
        let n = noise_by_hand(tinted.noise.as_ref().unwrap(), p, 0.0);
        let tint = 1.0 + strength * (2.0 * n - 1.0);
        let (a, b) = (
            tinted.at(camera.eye(), p, 0.0),
            plain.at(camera.eye(), p, 0.0),
        );
        for c in 0..3 {
            let eq8 = f64::from(tinted.colour[c]) + f64::from(tinted.scatter_colour[c]) * scatter;
            assert!(
                (b.colour[c] - eq8).abs() <= 1e-12,
                "s = 0 at {p}: {} vs {eq8}",
                b.colour[c]
            );
            assert!(
                (a.colour[c] - eq8 * tint).abs() <= 1e-6 * eq8,
                "s = {strength} at {p}: {} vs {}",
                a.colour[c],
                eq8 * tint
            );
        }
        // The density does not depend on the colour's strength.
        assert_eq!(a.density, b.density);
        darkest = darkest.min(tint);
        brightest = brightest.max(tint);
    }
    // The noise spans enough of [0, 1] that the colour visibly varies both ways.
    assert!(
        darkest < 0.85 && brightest > 1.15,
        "tint {darkest}..{brightest}"
    );
    let (_lock, mut r) = common::renderer();
    let (image, _) = check(
        &mut r,
        &tinted,
        &camera,
        0.0,
        "noise on the colour, s = 0.6",
    );
    let (same, _) = check(&mut r, &plain, &camera, 0.0, "noise on the colour, s = 0");
    assert_ne!(
        image.as_slice(),
        same.as_slice(),
        "the strength changes the frame"
    );
    let blurred = DistanceFog {
        lambda: 6.0,
        ..tinted.clone()
    };
    check(
        &mut r,
        &blurred,
        &camera,
        0.0,
        "noise on the colour, s = 0.6, λ = 6",
    );
}

#[test]
fn bad_noise_colour_strength_is_refused_by_name() {
    for s in [-0.1, 1.5, f64::NAN] {
        let fog = fog(
            Some(FogNoise {
                colour_strength: s,
                ..noise()
            }),
            0.0,
        );
        let e = fog.validate().unwrap_err().to_string();
        assert!(
            e.contains("noise colour strength") && e.contains("[0, 1]"),
            "{s}: {e}"
        );
    }
}
