//! Bad inputs to the pipeline give typed errors that name the problem, never a panic.
mod common;

use brume::haze::{Haze, RenderSpec};
use brume::raster::Grid;
use brume::{Error, Precision, Scheme};
use common::*;

#[test]
fn different_sizes_are_named() {
    let (_lock, mut r) = renderer();
    let image = noise_image(10, 8, 1);
    let range = Grid::filled(9, 8, 0.5f32);
    let spec = RenderSpec::haze(&Haze::default(), Scheme::Matched, Precision::F32);
    match r.render(&image, &range, &spec) {
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
            sigma0: 0.0,
            ..Haze::default()
        },
        Haze {
            airlight: [0.5, -0.1, 0.5],
            ..Haze::default()
        },
    ];
    for haze in bad {
        let spec = RenderSpec::haze(&haze, Scheme::Matched, Precision::F32);
        let err = r
            .render(&image, &range, &spec)
            .expect_err("bad parameter accepted");
        assert!(matches!(err, Error::InvalidParameter { .. }), "{err}");
    }
    let uniform = RenderSpec::uniform(0.5, 1.0, Scheme::Matched, Precision::F32);
    assert!(matches!(
        r.render(&image, &range, &uniform),
        Err(Error::InvalidParameter { .. })
    ));
}

#[test]
fn images_above_the_texture_limit_are_refused_before_any_gl_call() {
    let (_lock, mut r) = renderer();
    let max = r.caps().max_texture_size as usize;
    let image = Grid::filled(max + 1, 1, [0.5f32; 3]);
    let range = Grid::filled(max + 1, 1, 0.5f32);
    let spec = RenderSpec::haze(&Haze::default(), Scheme::Matched, Precision::F32);
    match r.render(&image, &range, &spec) {
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
