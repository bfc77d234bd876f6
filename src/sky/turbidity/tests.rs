use super::*;
use crate::sky::clouds::{add_clouds, CloudOptions};
use crate::sky::{draw_sun_disc, render_sky_image, PreethamSky};

const SUN: [f64; 2] = [0.9, 2.0];

fn image(t: f64, size: usize) -> RgbImage {
    let sky = PreethamSky::new(t, SUN[0], SUN[1]).unwrap();
    render_sky_image(&sky, size, &Fisheye::default()).unwrap()
}

fn opts() -> TurbidityOptions {
    TurbidityOptions {
        sun: Some(SUN),
        repeats: 3,
        ..TurbidityOptions::default()
    }
}

#[test]
fn clear_skies_give_their_turbidity_back() {
    for t in [1.5, 3.0, 7.5, 15.0] {
        let e = estimate_turbidity(&image(t, 96), "sky", &opts()).unwrap();
        assert!((e.turbidity - t).abs() < 1e-3, "T = {t}: {e:?}");
        assert!(e.std < 1e-3, "{e:?}");
        assert!(e.inliers > 90.0, "{e:?}");
        assert_eq!(e.reference_fallbacks, 0);
    }
}

#[test]
fn a_cloud_over_the_reference_is_voted_out() {
    let mut img = image(4.0, 96);
    // A grey cloud twice as bright over the zenith only.
    for y in 40..56 {
        for x in 40..56 {
            let p = img.get_mut(x, y);
            let g = 2.0 * crate::sky::luminance(*p) as f32;
            *p = [g; 3];
        }
    }
    let e = estimate_turbidity(&img, "sky", &opts()).unwrap();
    assert!((e.turbidity - 4.0).abs() < 0.01, "{e:?}");
    assert_eq!(e.reference_fallbacks, 3, "{e:?}");
}

#[test]
fn clouds_are_rejected() {
    let mut img = image(6.0, 128);
    let clouds = CloudOptions {
        coverage: 0.3,
        seed: 3,
        ..CloudOptions::default()
    };
    add_clouds(&mut img, &Fisheye::default(), &clouds).unwrap();
    let e = estimate_turbidity(&img, "sky", &opts()).unwrap();
    assert!((e.turbidity - 6.0).abs() < 0.01, "{e:?}");
    assert!(e.inliers < 90.0, "{e:?}");
}

#[test]
fn the_sun_is_found_from_a_saturated_disc() {
    let f = Fisheye::default();
    for (z, a) in [(30f64, 100f64), (58.4, -179.4), (70.0, -20.0)] {
        let (z, a) = (z.to_radians(), a.to_radians());
        let sky = PreethamSky::new(3.0, z, a).unwrap();
        let mut img = render_sky_image(&sky, 200, &f).unwrap();
        draw_sun_disc(&mut img, &f, z, a, 2f64.to_radians()).unwrap();
        let d = find_sun(&img, "sky", &f).unwrap();
        assert!(
            angle_between(d.zenith, d.azimuth, z, a) < 0.3f64.to_radians(),
            "{d:?}"
        );
        let o = TurbidityOptions {
            sun: None,
            repeats: 2,
            ..TurbidityOptions::default()
        };
        let e = estimate_turbidity(&img, "sky", &o).unwrap();
        assert!(matches!(e.sun_source, SunSource::Detected { .. }));
        assert!((e.turbidity - 3.0).abs() < 0.05, "{e:?}");
    }
}

#[test]
fn bad_images_and_options_are_named() {
    let e = estimate_turbidity(&RgbImage::filled(20, 30, [1.0; 3]), "a.png", &opts())
        .unwrap_err()
        .to_string();
    assert!(e.contains("a.png") && e.contains("square"), "{e}");
    let e = estimate_turbidity(&RgbImage::filled(40, 40, [0.0; 3]), "b.exr", &opts())
        .unwrap_err()
        .to_string();
    assert!(e.contains("b.exr") && e.contains("no sky pixels"), "{e}");
    let o = TurbidityOptions {
        samples: 100_000,
        ..opts()
    };
    let e = estimate_turbidity(&image(3.0, 64), "c.exr", &o)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("invalid samples") && e.contains("usable sky pixels of c.exr"),
        "{e}"
    );
    for (o, name) in [
        (
            TurbidityOptions {
                sun: Some([1.6, 0.0]),
                ..opts()
            },
            "sun_zenith",
        ),
        (
            TurbidityOptions {
                samples: 2,
                ..opts()
            },
            "samples",
        ),
        (
            TurbidityOptions {
                repeats: 0,
                ..opts()
            },
            "repeats",
        ),
        (
            TurbidityOptions {
                threshold: 0.0,
                ..opts()
            },
            "threshold",
        ),
        (
            TurbidityOptions {
                reference: Some([2.0, 0.0]),
                ..opts()
            },
            "reference_zenith",
        ),
    ] {
        let e = o.validate().unwrap_err().to_string();
        assert!(e.contains(name), "{e}");
    }
}

#[test]
fn helpers_behave() {
    let mut rng = SplitMix64::new(1);
    for (len, n) in [(10, 10), (1000, 5), (7, 4)] {
        let d = draw_distinct(&mut rng, len, n);
        let set: HashSet<usize> = d.iter().copied().collect();
        assert_eq!((d.len(), set.len()), (n, n));
        assert!(d.iter().all(|&i| i < len));
    }
    assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
    assert_eq!(median(&mut [4.0, 1.0, 2.0, 3.0]), 2.5);
}
