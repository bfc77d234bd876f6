//! Bad inputs to the pipeline give typed errors that name the problem, never a panic.
use crate::common;

use brume::raster::Grid;
use brume::{Blur, Error, Haze, UniformBlur};
use common::*;

#[test]
fn different_sizes_are_named() {
    let (_lock, mut r) = renderer();
    let image = noise_image(10, 8, 1);
    let range = Grid::filled(9, 8, 0.5f32);
    match r.render(&image, &range, &Haze::default(), &Blur::default()) {
        Err(Error::SizeMismatch { aw: 10, bw: 9, .. }) => {}
        other => panic!("expected a size mismatch, got {other:?}"),
    }
}

#[test]
fn negative_or_non_finite_parameters_are_rejected() {
    let (_lock, mut r) = renderer();
    let image = noise_image(8, 8, 1);
    let range = Grid::filled(8, 8, 0.5f32);
    let bad = [
        Haze {
            ks: -1.0,
            ..Haze::default()
        },
        Haze {
            ka: f64::NAN,
            ..Haze::default()
        },
        Haze {
            lambda: f64::INFINITY,
            ..Haze::default()
        },
        Haze {
            tint: [1.0, 0.0, 1.0],
            ..Haze::default()
        },
        Haze {
            airlight: [0.5, -0.1, 0.5],
            ..Haze::default()
        },
    ];
    for haze in bad {
        let err = r
            .render(&image, &range, &haze, &Blur::default())
            .expect_err("bad parameter accepted");
        assert!(matches!(err, Error::InvalidParameter { .. }), "{err}");
    }
    let zero_sigma0 = Blur {
        sigma0: 0.0,
        ..Blur::default()
    };
    let below_sigma0 = UniformBlur::new(0.5);
    for (medium, blur) in [
        (&Haze::default() as &dyn brume::Medium, &zero_sigma0),
        (&below_sigma0, &Blur::default()),
    ] {
        let err = r.render(&image, &range, medium, blur).unwrap_err();
        assert!(matches!(err, Error::InvalidParameter { .. }), "{err}");
    }
}

#[test]
fn images_above_the_texture_limit_are_refused_before_any_gl_call() {
    let (_lock, mut r) = renderer();
    let max = r.caps().max_texture_size as usize;
    let image = Grid::filled(max + 1, 1, [0.5f32; 3]);
    let range = Grid::filled(max + 1, 1, 0.5f32);
    match r.render(&image, &range, &Haze::default(), &Blur::default()) {
        Err(Error::TooLarge { width, max: m, .. }) => {
            assert_eq!(width as usize, max + 1);
            assert_eq!(m as usize, max);
        }
        other => panic!("expected TooLarge, got {other:?}"),
    }
}

#[test]
fn an_unknown_egl_platform_name_is_an_error() {
    let err = "x11".parse::<brume::egl::Platform>().unwrap_err();
    assert!(err.to_string().contains("surfaceless"), "{err}");
}
