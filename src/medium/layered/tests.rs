use super::*;
use crate::camera::Camera;

/// 5-point Gauss-Legendre nodes and weights on [−1, 1].
const GAUSS5: [(f64, f64); 5] = [
    (0.0, 0.568_888_888_888_888_9),
    (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (-0.906_179_845_938_664, 0.236_926_885_056_189_1),
    (0.906_179_845_938_664, 0.236_926_885_056_189_1),
];

/// Pixel (x, y) of a `size` frame at window depth `depth`, with σ0 = 1.
fn pixel((x, y): (usize, usize), size: (usize, usize), depth: f64) -> Pixel {
    Pixel {
        x,
        y,
        width: size.0,
        height: size.1,
        depth,
        sigma0: 1.0,
    }
}

/// The heights where a profile's δ has a kink.
fn kinks(profile: &HeightProfile) -> Vec<f64> {
    match *profile {
        HeightProfile::Exponential { .. } => vec![],
        HeightProfile::SineBand {
            base, thickness, ..
        } => vec![base, base + thickness],
        HeightProfile::LinearRamp { floor, top, .. } => vec![floor, top],
        HeightProfile::Table(ref table) => table.heights().to_vec(),
    }
}

/// F = ∫ δ(y(t)) dt over the segment by composite 5-point Gauss-Legendre (200 panels
/// per smooth piece), split where the segment crosses a kink of δ: the oracle.
fn quadrature(profile: &HeightProfile, from: DVec3, to: DVec3) -> f64 {
    let length = (to - from).length();
    let dy = to.y - from.y;
    let mut cuts = vec![0.0, 1.0];
    if dy != 0.0 {
        for k in kinks(profile) {
            let s = (k - from.y) / dy;
            if s > 0.0 && s < 1.0 {
                cuts.push(s);
            }
        }
    }
    cuts.sort_by(f64::total_cmp);
    let delta = |s: f64| profile.density(from.y + s * dy);
    let panels = 200;
    let mut sum = 0.0;
    for piece in cuts.windows(2) {
        let w = (piece[1] - piece[0]) / panels as f64;
        for i in 0..panels {
            let centre = piece[0] + (i as f64 + 0.5) * w;
            for (x, weight) in GAUSS5 {
                sum += weight * 0.5 * w * delta(centre + 0.5 * w * x);
            }
        }
    }
    sum * length
}

fn profiles() -> [HeightProfile; 3] {
    [
        HeightProfile::EXPONENTIAL,
        HeightProfile::SINE_BAND,
        HeightProfile::LINEAR_RAMP,
    ]
}

/// Eye heights and end heights that start and end below, inside, at the edges of and
/// above each layer (and of the exponential's base), up or down.
fn heights() -> Vec<f64> {
    vec![
        -7.5, -1.0, 0.0, 0.3, 0.5, 1.0, 1.7, 2.5, 4.99, 5.0, 6.0, 20.0, 45.0, 150.0,
    ]
}

/// The profile's `density` parameter: the scale of its δ.
fn peak(profile: &HeightProfile) -> f64 {
    match *profile {
        HeightProfile::Exponential { density, .. }
        | HeightProfile::SineBand { density, .. }
        | HeightProfile::LinearRamp { density, .. } => density,
        HeightProfile::Table(ref table) => table.max_density(),
    }
}

fn relative_error(a: f64, b: f64) -> f64 {
    if a == b {
        0.0
    } else {
        (a - b).abs() / b.abs().max(a.abs())
    }
}

#[test]
fn optical_depth_matches_quadrature_on_many_segments() {
    let mut worst: f64 = 0.0;
    for profile in profiles() {
        for &y0 in &heights() {
            for &y1 in &heights() {
                for run in [0.0, 3.0, 40.0, 700.0] {
                    if run == 0.0 && y0 == y1 {
                        continue;
                    }
                    let from = DVec3::new(1.0, y0, 2.0);
                    let to = DVec3::new(1.0 + 0.6 * run, y1, 2.0 - 0.8 * run);
                    let analytic = profile.optical_depth(from, to);
                    let oracle = quadrature(&profile, from, to);
                    let e = relative_error(analytic, oracle);
                    worst = worst.max(e);
                    assert!(
                        e <= 1e-5 || (analytic - oracle).abs() < 1e-300,
                        "{profile:?} {from} -> {to}: {analytic} vs {oracle}"
                    );
                }
            }
        }
    }
    eprintln!("worst relative error against quadrature: {worst:.2e}");
}

#[test]
fn nearly_horizontal_and_horizontal_segments_match_quadrature() {
    let mut worst: f64 = 0.0;
    for profile in profiles() {
        // Heights on the edges of the layers as well as inside and outside.
        for y0 in [-1.0, 0.0, 0.4, 1.0, 1.7, 2.5, 5.0, 30.0] {
            for length in [3.0f64, 85.0, 900.0] {
                for slope in [0.0, 1e-9, -1e-9, 1e-6, -1e-6, 1e-3, -1e-3] {
                    let dy = slope * length;
                    let run = (length * length - dy * dy).sqrt();
                    let from = DVec3::new(0.0, y0, 0.0);
                    let to = DVec3::new(0.0, y0 + dy, -run);
                    let analytic = profile.optical_depth(from, to);
                    let oracle = quadrature(&profile, from, to);
                    assert!(analytic.is_finite(), "{profile:?} {from} -> {to}");
                    let e = relative_error(analytic, oracle);
                    worst = worst.max(e);
                    assert!(
                        e <= 1e-5,
                        "{profile:?} y0 {y0} slope {slope} l {length}: {analytic} vs {oracle}"
                    );
                }
            }
        }
    }
    eprintln!("worst relative error, near-horizontal: {worst:.2e}");
}

#[test]
fn horizontal_ray_is_the_density_times_the_length() {
    for profile in profiles() {
        for y in heights() {
            let from = DVec3::new(0.0, y, 0.0);
            let to = DVec3::new(30.0, y, -40.0);
            let f = profile.optical_depth(from, to);
            assert_eq!(f, 50.0 * profile.density(y), "{profile:?} at {y}");
        }
    }
}

#[test]
fn mean_density_agrees_with_the_antiderivative_for_distant_limits() {
    for profile in profiles() {
        for &y0 in &heights() {
            for &y1 in &heights() {
                if (y1 - y0).abs() < 0.5 {
                    continue;
                }
                let textbook =
                    (profile.antiderivative(y1) - profile.antiderivative(y0)) / (y1 - y0);
                let mean = profile.mean_density(y0, y1);
                assert!(
                    (mean - textbook).abs() <= 1e-12 * peak(&profile),
                    "{profile:?} {y0}..{y1}: {mean} vs {textbook}"
                );
            }
        }
    }
}

/// The Δy at which a profile's mean switches from the series to the library
/// functions, for a segment starting at `y0`.
fn switch_dy(profile: &HeightProfile) -> f64 {
    match *profile {
        HeightProfile::Exponential { scale_height, .. } => 2.0 * scale_height * SERIES_LIMIT,
        HeightProfile::SineBand { thickness, .. } => thickness / FRAC_PI_2 * SERIES_LIMIT,
        HeightProfile::LinearRamp { .. } | HeightProfile::Table(_) => {
            unreachable!("no switch")
        }
    }
}

#[test]
fn no_seam_at_the_series_switch_in_f64_or_f32() {
    let exponential = HeightProfile::EXPONENTIAL;
    let band = HeightProfile::SINE_BAND;
    // (profile, y0): the band's segment starts at its base so that the whole Δy
    // overlaps the band.
    for (profile, y0) in [
        (exponential.clone(), 1.7),
        (exponential.clone(), -3.0),
        (exponential, 60.0),
        (band.clone(), 0.0),
    ] {
        let s = switch_dy(&profile);
        for sign in [1.0, -1.0] {
            let y = if sign < 0.0 && profile == band {
                y0 + s
            } else {
                y0
            };
            for (below, above) in [(1.0 - 1e-12, 1.0 + 1e-12), (1.0 - 1e-7, 1.0)] {
                let a = mean_density(&profile, y, sign * s * below);
                let b = mean_density(&profile, y, sign * s * above);
                assert!(
                    relative_error(a, b) <= 1e-6,
                    "{profile:?} y0 {y}: {a} | {b}"
                );
            }
            // The f32 twin of the shader on both sides, against f64: both branches
            // keep f32's accuracy at the switch.
            for factor in [0.999, 0.99999, 1.0, 1.00001, 1.001] {
                let dy = sign * s * factor;
                let single = f64::from(mean_density(&profile, y as f32, dy as f32));
                // The f64 mean at the heights f32 actually holds.
                let exact = mean_density(&profile, f64::from(y as f32), f64::from(dy as f32));
                let e = relative_error(single, exact);
                assert!(e <= 1e-6, "{profile:?} y0 {y} dy {dy}: f32 off by {e:.1e}");
            }
        }
    }
}

#[test]
fn f32_twin_is_accurate_near_the_horizon() {
    // What the shader does for rows at the horizon: Δy from 0 to a few ulps of y0.
    for profile in profiles() {
        for y0 in [0.0f32, 0.5, 1.0, 1.7, 5.0] {
            for dy in [0.0f32, 1e-12, -1e-12, 1e-7, -1e-7, 1e-4, -1e-4, 0.05, -0.05] {
                let single = f64::from(mean_density(&profile, y0, dy));
                let exact = mean_density(&profile, f64::from(y0), f64::from(dy));
                let scale = peak(&profile);
                assert!(
                    single.is_finite() && (single - exact).abs() <= 1e-6 * scale,
                    "{profile:?} y0 {y0} dy {dy}: {single} vs {exact}"
                );
            }
        }
    }
}

#[test]
fn cpu_sample_rebuilds_the_pixel_position() {
    let camera = Camera {
        position: [2.0, 1.7, 5.0],
        yaw_deg: 12.0,
        pitch_deg: -4.0,
        near: 1.0,
        ..Camera::default()
    };
    let fog = LayeredFog::for_camera(camera, HeightProfile::SINE_BAND);
    let frame = FrameInputs::new(camera, 0.0);
    let (w, h) = (32, 24);
    for (x, y, z) in [(3, 4, 12.0), (30, 20, 300.0), (16, 11, 999.0)] {
        let d = camera.window_depth(z);
        let p = camera.world_position(x, y, w, h, d);
        let expected = fog.sample_point(camera.eye(), p, 1.0);
        let got = fog.sample(pixel((x, y), (w, h), d), &frame);
        assert!(relative_error(got.transmission[0], expected.transmission[0]) < 1e-9);
        assert!(relative_error(got.sigma, expected.sigma) < 1e-9);
    }
    // A sky pixel is on the far plane.
    let sky = fog.sample(pixel((16, 23), (w, h), 1.0), &frame);
    let far = camera.world_position(16, 23, w, h, 1.0);
    assert!((far - camera.eye()).dot(camera.forward()) - camera.far < 1e-6);
    assert!(relative_error(sky.sigma, fog.sample_point(camera.eye(), far, 1.0).sigma) < 1e-9);
}

#[test]
fn sigma_max_bounds_every_pixel() {
    for profile in profiles() {
        let camera = Camera {
            pitch_deg: -30.0,
            ..Camera::default()
        };
        let frame = FrameInputs::new(camera, 0.0);
        for range_unit in [50.0, 1000.0] {
            let fog = LayeredFog {
                range_unit,
                ..LayeredFog::new(profile.clone())
            };
            let bound = fog.sigma_max(1.0);
            let (w, h) = (24, 16);
            for y in 0..h {
                for x in 0..w {
                    for d in [0.0, 0.9, 0.999, 0.9999, 1.0] {
                        let s = fog.sample(pixel((x, y), (w, h), d), &frame);
                        assert!(s.sigma >= 1.0 && s.sigma <= bound + 1e-12);
                    }
                }
            }
        }
    }
    // Band and ramp: the bound follows the density while it is below the cap.
    let thin = LayeredFog {
        profile: HeightProfile::SineBand {
            density: 1e-3,
            base: 0.0,
            thickness: 5.0,
        },
        range_unit: 100.0,
        ..LayeredFog::default()
    };
    let expected = 1.0 + thin.lambda * (1e-3f64 * 100.0).sqrt();
    assert!((thin.sigma_max(1.0) - expected).abs() < 1e-12);
}

#[test]
fn bad_parameters_are_refused_by_name() {
    let bad = |fog: LayeredFog| fog.validate().unwrap_err().to_string();
    let with = LayeredFog::new;
    assert!(bad(with(HeightProfile::Exponential {
        density: -1.0,
        base: 0.0,
        scale_height: 20.0
    }))
    .contains("density"));
    assert!(bad(with(HeightProfile::Exponential {
        density: 0.01,
        base: f64::NAN,
        scale_height: 20.0
    }))
    .contains("base"));
    assert!(bad(with(HeightProfile::Exponential {
        density: 0.01,
        base: 0.0,
        scale_height: 0.0
    }))
    .contains("scale_height"));
    assert!(bad(with(HeightProfile::SineBand {
        density: 0.01,
        base: 0.0,
        thickness: -1.0
    }))
    .contains("thickness"));
    assert!(bad(with(HeightProfile::LinearRamp {
        density: 1.0,
        floor: 1.0,
        top: 1.0
    }))
    .contains("top"));
    let fog = LayeredFog::default();
    assert!(bad(LayeredFog {
        albedo: 1.5,
        ..fog.clone()
    })
    .contains("albedo"));
    assert!(bad(LayeredFog {
        lambda: -1.0,
        ..fog.clone()
    })
    .contains("lambda"));
    assert!(bad(LayeredFog {
        range_unit: 0.0,
        ..fog.clone()
    })
    .contains("range_unit"));
    assert!(bad(LayeredFog {
        colour: [0.5, f32::NAN, 0.5],
        ..fog.clone()
    })
    .contains("colour"));
    let camera = Camera {
        near: 0.0,
        ..Camera::default()
    };
    let frame_error = |f: FrameInputs| fog.validate_frame(&f).unwrap_err();
    assert!(frame_error(FrameInputs::new(camera, 0.0))
        .to_string()
        .contains("near"));
    assert!(matches!(
        frame_error(FrameInputs::default()),
        Error::MissingCamera { medium } if medium.starts_with("layered")
    ));
    for profile in profiles() {
        assert!(with(profile).validate().is_ok());
    }
}

#[test]
fn defaults_show_fog_at_the_scene_scale() {
    // Eye at 1.7 m, objects from 3 to 900 m: near objects clear, far ones fogged.
    let eye = DVec3::new(0.0, 1.7, 0.0);
    for profile in profiles() {
        let tau = |p: DVec3| (-profile.optical_depth(eye, p)).exp();
        let near_ground = tau(DVec3::new(0.0, 0.0, -3.0));
        let far_ground = tau(DVec3::new(0.0, 0.0, -900.0));
        assert!(near_ground > 0.3, "{profile:?}: {near_ground}");
        assert!(far_ground < 0.05, "{profile:?}: {far_ground}");
    }
}

/// `with` sets the values given on each analytic preset (a ramp's floor from `base`),
/// keeps the others, ignores the ones a profile does not have and leaves a table as it is.
#[test]
fn with_sets_the_given_values_of_a_preset() {
    let given = ProfileValues {
        density: Some(0.5),
        base: Some(2.0),
        scale_height: Some(7.0),
        thickness: Some(3.0),
        top: Some(9.0),
    };
    assert_eq!(
        HeightProfile::EXPONENTIAL.with(&given),
        HeightProfile::Exponential {
            density: 0.5,
            base: 2.0,
            scale_height: 7.0
        }
    );
    assert_eq!(
        HeightProfile::SINE_BAND.with(&given),
        HeightProfile::SineBand {
            density: 0.5,
            base: 2.0,
            thickness: 3.0
        }
    );
    assert_eq!(
        HeightProfile::LINEAR_RAMP.with(&given),
        HeightProfile::LinearRamp {
            density: 0.5,
            floor: 2.0,
            top: 9.0
        }
    );
    let only_top = ProfileValues {
        top: Some(4.0),
        ..ProfileValues::default()
    };
    assert_eq!(
        HeightProfile::EXPONENTIAL.with(&only_top),
        HeightProfile::EXPONENTIAL
    );
    let table = HeightProfile::Table(DensityTable::from_rows(&[(0.0, 0.1), (5.0, 0.0)]).unwrap());
    assert_eq!(table.clone().with(&given), table);
}
