use super::*;
use crate::camera::Camera;

/// The default camera's eye.
fn eye() -> DVec3 {
    Camera::default().eye()
}

/// The point `l` metres from the default eye along its view axis (−z).
fn ahead(l: f64) -> DVec3 {
    eye() + DVec3::new(0.0, 0.0, -l)
}

/// A frame of the default camera at time 0.
fn frame() -> FrameInputs {
    FrameInputs::new(Camera::default(), 0.0)
}

fn pixel(x: usize, y: usize, depth: f64) -> Pixel {
    Pixel {
        x,
        y,
        width: 64,
        height: 48,
        depth,
        sigma0: 1.0,
    }
}

#[test]
fn defaults_fog_a_metre_scale_scene_visibly_and_gradually() {
    // Camera at 1.7 m, objects 3-900 m away: with any noise value the density lies
    // between ramp·low and ramp·high.
    let fog = DistanceFog::default();
    let bounds = |l: f64| {
        let ramp = fog.distance_ramp(l);
        (ramp * DEFAULT_NOISE_LOW, ramp * DEFAULT_NOISE_HIGH)
    };
    assert!(bounds(3.0).0 > 0.01, "{:?}", bounds(3.0));
    assert!(bounds(300.0).1 < fog.max_density, "{:?}", bounds(300.0));
    assert!(bounds(900.0).0 > 0.35, "{:?}", bounds(900.0));
    let mut last = 0.0;
    for l in [3.0, 10.0, 30.0, 100.0, 300.0, 900.0] {
        let f = fog.at(eye(), ahead(l), 0.0).density;
        let (lo, hi) = bounds(l);
        assert!(
            f >= lo - 1e-12 && f <= hi.min(fog.max_density) + 1e-12,
            "{l} m: {f}"
        );
        assert!(f > last, "{l} m: {f} after {last}");
        last = f;
    }
    // Listing 1's numbers read as metres (they are centimetres) barely fog the same
    // scene: the reason the defaults differ.
    let literal = DistanceFog {
        distance: 1000.0,
        ..DistanceFog::default()
    };
    assert!(literal.distance_ramp(900.0) * DEFAULT_NOISE_HIGH < 0.18);
    assert!(literal.distance_ramp(3.0) * DEFAULT_NOISE_HIGH < 0.01);
}

#[test]
fn no_fog_inside_the_start_distance_and_the_cap_holds() {
    let fog = DistanceFog {
        start_distance: 50.0,
        noise: None,
        ..DistanceFog::default()
    };
    for l in [0.0, 1.0, 49.9] {
        let f = fog.at(eye(), ahead(l), 0.0).density;
        assert_eq!(f, 0.0, "{l} m");
    }
    assert!(fog.at(eye(), ahead(60.0), 0.0).density > 0.0);
    // Without noise the factor is 1 (eq. 3): 100 m past the start, dist = 1, capped.
    assert_eq!(fog.at(eye(), ahead(150.0), 0.0).density, fog.max_density);
    let thin = DistanceFog {
        noise: None,
        distance: 1e6,
        ..DistanceFog::default()
    };
    let l: f64 = 250.0;
    let want = (l / 1e6).powf(DEFAULT_EXPONENT);
    assert!((thin.at(eye(), ahead(l), 0.0).density - want).abs() < 1e-15);
}

#[test]
fn scattering_brightens_the_fog_toward_the_light_beyond_its_start() {
    let fog = DistanceFog {
        light_direction: [0.0, 0.0, -2.0],
        noise: None,
        ..DistanceFog::default()
    };
    let colour = DEFAULT_COLOUR.map(f64::from);
    let glow = |p: FogPoint| -> [f64; 3] { std::array::from_fn(|c| p.colour[c] - colour[c]) };
    // Straight at the light, 1000 m: scatter = 1·(1 − 10/1000).
    let toward = glow(fog.at(eye(), ahead(1000.0), 0.0));
    for c in 0..3 {
        let want = f64::from(DEFAULT_SCATTER_COLOUR[c]) * 0.99;
        assert!((toward[c] - want).abs() < 1e-12, "{toward:?}");
    }
    // Closer than the scatter start: the plain fog colour.
    assert_eq!(glow(fog.at(eye(), ahead(5.0), 0.0)), [0.0; 3]);
    // Behind the camera's light direction: nothing.
    let behind = Camera::default().eye() + DVec3::new(0.0, 0.0, 500.0);
    assert_eq!(glow(fog.at(eye(), behind, 0.0)), [0.0; 3]);
    // 60° off the light: cos⁴ = 1/16 of the colour (times the path fraction).
    let off = Camera::default().eye()
        + 500.0 * DVec3::new(60f64.to_radians().sin(), 0.0, -60f64.to_radians().cos());
    let g = glow(fog.at(eye(), off, 0.0))[0];
    assert!((g - 0.0625 * (1.0 - 10.0 / 500.0)).abs() < 1e-12, "{g}");
}

#[test]
fn noise_varies_the_density_and_time_moves_it() {
    let fog = DistanceFog::default();
    let points: Vec<DVec3> = (0..40)
        .map(|i| ahead(60.0) + DVec3::new(7.3 * f64::from(i), 0.0, 0.0))
        .collect();
    let densities = |f: &DistanceFog, t: f64| -> Vec<f64> {
        points.iter().map(|&p| f.at(eye(), p, t).density).collect()
    };
    let now = densities(&fog, 0.0);
    let spread =
        now.iter().cloned().fold(f64::MIN, f64::max) - now.iter().cloned().fold(f64::MAX, f64::min);
    let ramp = fog.distance_ramp(60.0);
    assert!(
        spread > 0.01 * ramp,
        "noise barely varies the fog: {spread}"
    );
    // The same time, the same fog; another time, another fog.
    assert_eq!(densities(&fog.clone(), 0.0), now);
    let moved = densities(&fog, 7.0);
    assert!(moved.iter().zip(&now).any(|(a, b)| (a - b).abs() > 1e-3));
    // Eq. 9-10's shift: at time t the fog at P is the fog at time 0 at P + speed·t
    // (horizontally; P's distance to the eye is kept by moving the eye too).
    let noise = fog.noise.as_ref().unwrap();
    for &p in &points {
        let shift = DVec3::new(noise.speed[0] * 7.0, 0.0, noise.speed[2] * 7.0);
        let a = noise.factor(p, 7.0);
        let b = noise.factor(p + shift, 0.0);
        assert!((a - b).abs() < 1e-12);
    }
    // Without noise, time changes nothing.
    let plain = DistanceFog {
        noise: None,
        ..fog.clone()
    };
    assert_eq!(densities(&plain, 0.0), densities(&plain, 7.0));
}

#[test]
fn noise_origin_is_reduced_to_one_tile() {
    // A long time and a far camera: the shader gets the origin modulo one tile.
    let fog = DistanceFog::default();
    let camera = Camera {
        position: [5_000.25, 1.7, -12_000.5],
        ..Camera::default()
    };
    let frame = FrameInputs::new(camera, 123_456.75);
    let noise = fog.noise.as_ref().unwrap();
    let (u, v) = noise.coordinates(camera.eye(), frame.time);
    let origin = fog
        .uniforms(&frame)
        .into_iter()
        .find(|(name, _)| *name == "u_noise_origin")
        .unwrap()
        .1;
    let UniformValue::Vec2([ou, ov]) = origin else {
        panic!("{origin:?}");
    };
    assert!((0.0..1.0).contains(&ou) && (0.0..1.0).contains(&ov));
    assert!((f64::from(ou) - u.rem_euclid(1.0)).abs() < 1e-6);
    assert!((f64::from(ov) - v.rem_euclid(1.0)).abs() < 1e-6);
}

#[test]
fn medium_sample_is_the_paper_blend_and_the_sky_is_the_far_plane() {
    let fog = DistanceFog::default();
    let (x, y) = (40, 30);
    let sky = fog.sample(pixel(x, y, 1.0), &frame());
    let camera = Camera::default();
    let ray = camera.pixel_ray(x, y, 64, 48);
    let far = camera.far * ray.length();
    let world = camera.eye() + ray * camera.far;
    let point = fog.at(eye(), world, 0.0);
    assert!((point.distance - far).abs() < 1e-9 * far);
    assert!((sky.transmission[0] - (1.0 - point.density)).abs() < 1e-9);
    assert_eq!(sky.transmission[0], sky.transmission[2]);
    for c in 0..3 {
        assert!((sky.inscatter[c] - point.colour[c]).abs() < 1e-9);
    }
    // τ·E + (1 − τ)·C_fog' is eq. 4's lerp(E, C_fog', F).
    let e = 0.3;
    let tau = sky.transmission[0];
    let lerp = e + (sky.inscatter[0] - e) * point.density;
    assert!((tau * e + (1.0 - tau) * sky.inscatter[0] - lerp).abs() < 1e-12);
    // Depth beyond [0, 1] is the far plane or the near plane, never a NaN.
    assert_eq!(fog.sample(pixel(x, y, 1.5), &frame()), sky);
    let below = fog.sample(pixel(x, y, -0.5), &frame());
    assert_eq!(below, fog.sample(pixel(x, y, 0.0), &frame()));
}

#[test]
fn sigma_max_bounds_every_pixel() {
    let fog = DistanceFog {
        max_density: 0.8,
        noise: None,
        ..DistanceFog::default()
    };
    let bound = fog.sigma_max(1.0);
    let expected = 1.0 + DEFAULT_LAMBDA * f64::sqrt(-f64::ln(0.2));
    assert!((bound - expected).abs() < 1e-12);
    let mut largest: f64 = 0.0;
    for depth in [0.0, 0.5, 0.99, 0.9999, 1.0] {
        for (x, y) in [(0, 0), (63, 47), (32, 24)] {
            largest = largest.max(fog.sample(pixel(x, y, depth), &frame()).sigma);
        }
    }
    assert!(largest <= bound + 1e-12, "{largest} > {bound}");
    // The sky, beyond range_unit, with the density capped, reaches it.
    assert!(largest > bound - 1e-9, "{largest} vs {bound}");
}

#[test]
fn the_noise_sampler_is_always_listed() {
    let with = DistanceFog::default();
    let without = DistanceFog {
        noise: None,
        ..DistanceFog::default()
    };
    let names = |f: &DistanceFog| f.lookups().into_iter().map(|(n, _)| n).collect::<Vec<_>>();
    assert_eq!(names(&with), vec![NOISE_SAMPLER]);
    assert_eq!(names(&without), vec![NOISE_SAMPLER]);
    let uniform_names = |f: &DistanceFog| {
        f.uniforms(&frame())
            .into_iter()
            .map(|(n, _)| n)
            .collect::<Vec<_>>()
    };
    assert_eq!(uniform_names(&with), uniform_names(&without));
    // The default noise is generated once and shared (one upload).
    assert_eq!(
        with.lookups()[0].1.id(),
        DistanceFog::default().lookups()[0].1.id()
    );
}

#[test]
fn bad_parameters_are_refused_by_name() {
    let bad = |f: DistanceFog| f.validate().unwrap_err().to_string();
    let d = DistanceFog::default;
    assert!(DistanceFog::default().validate().is_ok());
    assert!(bad(DistanceFog {
        distance: 0.0,
        ..d()
    })
    .contains("distance"));
    assert!(bad(DistanceFog {
        exponent: -1.0,
        ..d()
    })
    .contains("exponent"));
    assert!(bad(DistanceFog {
        max_density: 1.0,
        ..d()
    })
    .contains("max_density"));
    assert!(bad(DistanceFog {
        start_distance: f64::NAN,
        ..d()
    })
    .contains("start_distance"));
    assert!(bad(DistanceFog {
        colour: [0.1, -1.0, 0.0],
        ..d()
    })
    .contains("colour"));
    assert!(bad(DistanceFog {
        light_direction: [0.0; 3],
        ..d()
    })
    .contains("light_direction"));
    assert!(bad(DistanceFog {
        scatter_start: -1.0,
        ..d()
    })
    .contains("scatter_start"));
    assert!(bad(DistanceFog {
        scatter_exponent: 0.0,
        ..d()
    })
    .contains("scatter_exponent"));
    assert!(bad(DistanceFog {
        scatter_colour: [f32::NAN; 3],
        ..d()
    })
    .contains("scatter_colour"));
    assert!(bad(DistanceFog {
        lambda: -1.0,
        ..d()
    })
    .contains("lambda"));
    assert!(bad(DistanceFog {
        range_unit: 0.0,
        ..d()
    })
    .contains("range_unit"));
    // The frame's camera and time are checked with the frame, the medium's need of a
    // camera too.
    let frame_error = |f: FrameInputs| d().validate_frame(&f).unwrap_err();
    let camera = Camera {
        near: 0.0,
        ..Camera::default()
    };
    assert!(frame_error(FrameInputs::new(camera, 0.0))
        .to_string()
        .contains("near"));
    assert!(
        frame_error(FrameInputs::new(Camera::default(), f64::INFINITY))
            .to_string()
            .contains("time")
    );
    assert!(matches!(
        frame_error(FrameInputs::default()),
        Error::MissingCamera { medium } if medium == "distance"
    ));
    assert!(d().validate_frame(&frame()).is_ok());
    let noise = |f: fn(&mut FogNoise)| {
        let mut n = FogNoise::default();
        f(&mut n);
        DistanceFog {
            noise: Some(n),
            ..d()
        }
    };
    assert!(bad(noise(|n| n.size = 0.0)).contains("noise size"));
    assert!(bad(noise(|n| n.low = -0.1)).contains("noise low"));
    assert!(bad(noise(|n| n.high = f64::NAN)).contains("noise high"));
    assert!(bad(noise(|n| n.speed[2] = f64::INFINITY)).contains("noise speed"));
    assert!(bad(noise(|n| {
        n.lookup = Lookup::new(1, 1, vec![0.5], Wrap::ClampToEdge).unwrap()
    }))
    .contains("noise lookup"));
}

#[test]
fn png_noise_becomes_a_tiling_lookup() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("noise.png");
    image::GrayImage::from_raw(2, 2, vec![0, 85, 170, 255])
        .unwrap()
        .save(&path)
        .unwrap();
    let noise = FogNoise::from_png(&path).unwrap();
    assert_eq!(noise.lookup.wrap(), Wrap::Repeat);
    assert_eq!(
        noise.lookup.values(),
        &[0.0, 85.0 / 255.0, 170.0 / 255.0, 1.0]
    );
    assert_eq!(noise.size, DEFAULT_NOISE_SIZE);
}
