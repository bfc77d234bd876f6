//! Hole filling, indoor data (no sky) and bad inputs.

use crate::common;

use brume::io::depth::{DepthFormat, DepthOptions, StereoView};
use brume::photo::{Photo, PrepareOptions};
use brume::prep::{prepare, ImageSkyRules, PrepOptions, SkyRules};
use brume::raster::{Grid, ScalarMap};
use brume::Error;
use common::*;

fn plane(x: usize, y: usize) -> f32 {
    (20.0 + 0.15 * x as f64 - 0.08 * y as f64) as f32
}

/// A tilted plane with a 20x15 hole is filled with the plane's own values: within 1e-4
/// relative (the plane is exact at the boundary, so the RANSAC winner is the plane up to
/// f32 rounding of the samples).
#[test]
fn tilted_plane_hole_is_filled_with_the_plane() {
    let (w, h) = (80, 60);
    let mut map = Grid::from_fn(w, h, plane);
    for y in 20..35 {
        for x in 30..50 {
            *map.get_mut(x, y) = f32::NAN;
        }
    }
    let p = prepare(&map, &PrepOptions::default()).unwrap();
    assert_eq!(
        (p.stats.holes, p.stats.hole_pixels, p.stats.sky_components),
        (1, 300, 0)
    );
    assert_known_unchanged(&map, &p.range);
    for y in 20..35 {
        for x in 30..50 {
            let (got, want) = (*p.range.get(x, y), plane(x, y));
            assert!(
                (got - want).abs() <= 1e-4 * want.abs(),
                "({x},{y}): {got} vs {want}"
            );
            assert!(*p.filled.get(x, y));
        }
    }
}

/// A hole in a flat region whose boundary touches a near object on one side: the robust
/// score follows the majority (the background), and the fill never leaves the boundary's
/// value range.
#[test]
fn fill_is_robust_to_a_minority_on_the_boundary() {
    let (w, h) = (40, 40);
    let mut map = Grid::from_fn(w, h, |x, _| if x < 12 { 3.0 } else { 50.0 });
    for y in 10..30 {
        for x in 12..30 {
            *map.get_mut(x, y) = f32::NAN;
        }
    }
    let p = prepare(&map, &PrepOptions::default()).unwrap();
    for y in 10..30 {
        for x in 12..30 {
            assert_eq!(*p.range.get(x, y), 50.0, "({x},{y})");
        }
    }
}

/// Holes touching the border, single-pixel holes and corner pixels.
#[test]
fn border_and_tiny_holes() {
    let (w, h) = (30, 20);
    let mut map = Grid::from_fn(w, h, plane);
    for &(x, y) in &[(0, 0), (29, 19), (5, 5), (29, 0), (0, 19)] {
        *map.get_mut(x, y) = f32::NAN;
    }
    for y in 8..12 {
        *map.get_mut(0, y) = f32::NAN;
    }
    let p = prepare(&map, &PrepOptions::default()).unwrap();
    assert_all_finite(&p.range);
    assert_known_unchanged(&map, &p.range);
    assert_eq!(p.stats.sky_components, 0);
    // The five pixels on the border and the run of four on the left edge continue the
    // plane along their row (border bands); (5, 5) is a hole.
    assert_eq!(
        (p.stats.holes, p.stats.border_filled),
        (1, 8),
        "{:?}",
        p.stats
    );
    for (i, v) in map.as_slice().iter().enumerate() {
        if v.is_nan() {
            let (x, y) = (i % w, i / w);
            let got = p.range.as_slice()[i];
            // Corner pixels have only 2 boundary edges: a constant (error <= one slope
            // step, 0.15); the others get the plane.
            let corner = (x == 0 || x == w - 1) && (y == 0 || y == h - 1);
            // The left run is continued linearly in disparity with the median slope of
            // the rows round it; this map is linear in range, not in disparity, so each
            // row's slope differs a little from the next: up to 0.107 % off one pixel out
            // with a neighbour's slope (0.092 % with its own).
            let tol = if corner {
                0.16
            } else if x == 0 {
                0.025
            } else {
                1e-3
            };
            assert!(
                (got - plane(x, y)).abs() < tol,
                "({x},{y}) {got} vs {}",
                plane(x, y)
            );
        }
    }
}

/// Indoor stereo data: a frame of unknown pixels round the image (touching the whole top
/// row) and a full-height occlusion band are holes, not sky.
#[test]
fn indoor_frame_and_occlusion_band_are_not_sky() {
    let (w, h) = (200, 150);
    let mut map = Grid::from_fn(w, h, |x, y| 2.0 + 0.01 * x as f32 + 0.005 * y as f32);
    for y in 0..h {
        for x in 0..w {
            let frame = x < 3 || y < 3 || x >= w - 3 || y >= h - 3;
            let band = (20..45).contains(&x);
            if frame || band {
                *map.get_mut(x, y) = f32::NAN;
            }
        }
    }
    let p = prepare(&map, &PrepOptions::default()).unwrap();
    assert_eq!(p.stats.sky_components, 0, "{:?}", p.stats);
    assert_eq!(p.stats.s_max, None);
    assert!(p.sky.as_slice().iter().all(|s| !s));
    assert_all_finite(&p.range);
    assert_known_unchanged(&map, &p.range);
    // Without the rules beyond the paper's (area, top), the frame would be sky.
    let loose = PrepOptions {
        sky: SkyRules {
            min_top_fraction: 0.0,
            min_bbox_fill: 0.0,
            reject_bottom: false,
            ..SkyRules::default()
        },
        ..PrepOptions::default()
    };
    assert_eq!(prepare(&map, &loose).unwrap().stats.sky_components, 1);
}

#[test]
fn no_holes_means_unchanged() {
    let map = Grid::from_fn(17, 9, plane);
    let p = prepare(&map, &PrepOptions::default()).unwrap();
    assert_eq!(p.range, map);
    assert_eq!(
        (
            p.stats.holes,
            p.stats.hole_pixels,
            p.stats.sky_pixels,
            p.stats.margin_pixels
        ),
        (0, 0, 0, 0)
    );
    assert!(p.filled.as_slice().iter().all(|f| !f));
}

#[test]
fn one_by_one_maps() {
    let p = prepare(&Grid::filled(1, 1, 4.5f32), &PrepOptions::default()).unwrap();
    assert_eq!(p.range.as_slice(), &[4.5]);
    assert!(matches!(
        prepare(&Grid::filled(1, 1, f32::NAN), &PrepOptions::default()),
        Err(Error::Prep(_))
    ));
    let mut col: ScalarMap = Grid::from_fn(1, 5, |_, y| y as f32 + 1.0);
    *col.get_mut(0, 2) = f32::NAN;
    let p = prepare(&col, &PrepOptions::default()).unwrap();
    assert_all_finite(&p.range);
    assert!((2.0..=4.0).contains(p.range.get(0, 2)));
}

#[test]
fn all_unknown_is_an_error_not_a_panic() {
    for v in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        match prepare(&Grid::filled(32, 24, v), &PrepOptions::default()) {
            Err(Error::Prep(msg)) => assert!(msg.contains("no valid range value"), "{msg}"),
            other => panic!("expected Error::Prep, got {other:?}"),
        }
    }
    assert!(matches!(
        prepare(&Grid::filled(0, 0, 1.0f32), &PrepOptions::default()),
        Err(Error::Prep(_))
    ));
}

#[test]
fn bad_options_are_invalid_parameters() {
    let d = PrepOptions::default;
    let bad = [
        PrepOptions {
            margin_px: -1.0,
            ..d()
        },
        PrepOptions {
            margin_px: f64::NAN,
            ..d()
        },
        PrepOptions {
            margin_px: f64::INFINITY,
            ..d()
        },
        PrepOptions {
            margin_px: 1e9,
            ..d()
        },
        PrepOptions {
            sky_range_factor: 1.0,
            ..d()
        },
        PrepOptions {
            sky_range_factor: 0.5,
            ..d()
        },
        PrepOptions {
            sky_range_factor: f64::NAN,
            ..d()
        },
        PrepOptions {
            sky_range_factor: 1e308,
            ..d()
        },
        PrepOptions {
            ransac_samples: 0,
            ..d()
        },
        PrepOptions {
            sky: SkyRules {
                min_area_fraction: -0.1,
                ..SkyRules::default()
            },
            ..d()
        },
        PrepOptions {
            sky: SkyRules {
                min_bbox_fill: f64::NAN,
                ..SkyRules::default()
            },
            ..d()
        },
        PrepOptions {
            far_outlier_factor: 0.5,
            ..d()
        },
        PrepOptions {
            far_outlier_factor: f64::INFINITY,
            ..d()
        },
        PrepOptions {
            far_patch_fraction: 2.0,
            ..d()
        },
        PrepOptions {
            image_sky: ImageSkyRules {
                max_step: f64::NAN,
                ..ImageSkyRules::default()
            },
            ..d()
        },
        PrepOptions {
            image_sky: ImageSkyRules {
                bridge_px: 1000,
                ..ImageSkyRules::default()
            },
            ..d()
        },
        PrepOptions {
            image_sky: ImageSkyRules {
                seed_rows: -0.1,
                ..ImageSkyRules::default()
            },
            ..d()
        },
    ];
    let map = Grid::filled(4, 4, 1.0f32);
    for o in bad {
        assert!(
            matches!(o.validate(), Err(Error::InvalidParameter { .. })),
            "{o:?}"
        );
        assert!(
            matches!(prepare(&map, &o), Err(Error::InvalidParameter { .. })),
            "{o:?}"
        );
    }
    assert!(d().validate().is_ok());
    assert_eq!(d().jacobi_sweeps(), 16);
    assert_eq!(
        PrepOptions {
            margin_px: 2.5,
            ..d()
        }
        .jacobi_sweeps(),
        5
    );
}

/// A street pole before a wall, as a stereo matcher leaves it in a Cityscapes disparity:
/// the wall (Z = 10 m, d = fx·B/Z = 5 px) unknown over the 20 px left of the pole (Z = 2 m,
/// d = 25 px) that the right camera cannot see, and the pole's disparity reaching 2 px
/// over the wall on every other row (a matcher's fattened, jagged edge). Loaded as a photo
/// with its camera file, or as a float disparity with its focal length and baseline (a
/// matcher's own output, which used to be filled as any hole), the occlusion is filled with
/// the wall's range, and so is the right view's mirrored one (right of the pole) read as a
/// right view's; filled as any hole (the same map as a 16-bit PNG in millimetres, or the
/// right view's read as a left one) it was not.
#[test]
fn a_cityscapes_pole_leaves_no_halo() {
    const POLE: std::ops::Range<u32> = 60..66;
    const OCCLUDED: std::ops::Range<u32> = 40..60;
    let (w, h) = (96u32, 48u32);
    let fattened = |x: u32, y: u32| y % 2 == 1 && (POLE.start - 2..POLE.start).contains(&x);
    let disparity = |x: u32, y: u32| -> f64 {
        if POLE.contains(&x) || fattened(x, y) {
            25.0
        } else if OCCLUDED.contains(&x) {
            0.0
        } else {
            5.0
        }
    };
    let dir = tempfile::tempdir().unwrap();
    let stored = image::ImageBuffer::from_fn(w, h, |x, y| {
        let d = disparity(x, y);
        image::Luma([if d == 0.0 {
            0u16
        } else {
            (256.0 * d) as u16 + 1
        }])
    });
    stored.save(dir.path().join("f_disparity.png")).unwrap();
    let camera = r#"{"extrinsic": {"baseline": 0.5}, "intrinsic": {"fx": 100.0, "fy": 100.0, "u0": 48.0, "v0": 24.0}}"#;
    std::fs::write(dir.path().join("f_camera.json"), camera).unwrap();
    let millimetres = image::ImageBuffer::from_fn(w, h, |x, y| {
        let d = disparity(x, y);
        image::Luma([if d == 0.0 {
            0u16
        } else {
            (50.0 / d * 1000.0) as u16
        }])
    });
    millimetres.save(dir.path().join("f_depth.png")).unwrap();
    let photo_image = image::RgbImage::from_fn(w, h, |x, y| {
        if POLE.contains(&x) {
            image::Rgb([10, 10, 12])
        } else {
            // Brick: a faint texture of rows.
            let v: u16 = if y % 4 == 0 { 120 } else { 130 };
            image::Rgb([v, v * 3 / 4, v / 2].map(|c| c as u8))
        }
    });
    photo_image
        .save(dir.path().join("f_leftImg8bit.png"))
        .unwrap();
    let load = |depth: &str, format: DepthFormat| {
        let opts = DepthOptions {
            format,
            fov: Some(2.0 * (24.0f64 / 100.0).atan().to_degrees()),
            scale: (format == DepthFormat::Png16).then_some(0.001),
            ..DepthOptions::default()
        };
        Photo::load(
            &dir.path().join("f_leftImg8bit.png"),
            &dir.path().join(depth),
            &opts,
        )
        .unwrap()
    };
    let prepare_options = PrepareOptions::default();
    let stereo = load("f_disparity.png", DepthFormat::Auto);
    assert_eq!(stereo.depth.format, DepthFormat::Cityscapes);
    assert_eq!(stereo.depth.stereo_focal_baseline, Some(50.0));
    let png = load("f_depth.png", DepthFormat::Png16);
    assert_eq!(png.depth.stereo_focal_baseline, None);
    let float_disparity = Grid::from_fn(w as usize, h as usize, |x, y| {
        match disparity(x as u32, y as u32) {
            0.0 => f32::INFINITY,
            d => d as f32,
        }
    });
    let float_path = dir.path().join("f_float.pfm");
    brume::io::output::write_scalar(&float_path, &float_disparity).unwrap();
    let float_opts = DepthOptions {
        format: DepthFormat::Float,
        kind: Some(brume::io::depth::DepthKind::Disparity),
        focal: Some(100.0),
        baseline: Some(500.0),
        ..DepthOptions::default()
    };
    let image_path = dir.path().join("f_leftImg8bit.png");
    let float = Photo::load(&image_path, &float_path, &float_opts).unwrap();
    assert_eq!(float.depth.stereo_focal_baseline, Some(50.0));
    let mirrored = Grid::from_fn(w as usize, h as usize, |x, y| {
        *float_disparity.get(w as usize - 1 - x, y)
    });
    let mirrored_path = dir.path().join("f_right.pfm");
    brume::io::output::write_scalar(&mirrored_path, &mirrored).unwrap();
    let right_image = dir.path().join("f_right.png");
    image::imageops::flip_horizontal(&photo_image)
        .save(&right_image)
        .unwrap();
    let right_opts = DepthOptions {
        stereo_view: Some(StereoView::Right),
        ..float_opts.clone()
    };
    let right = Photo::load(&right_image, &mirrored_path, &right_opts).unwrap();
    assert_eq!(right.depth.stereo_view, StereoView::Right);
    let as_left = Photo::load(&right_image, &mirrored_path, &float_opts).unwrap();
    let wall_error_at = |photo: &Photo, column: &dyn Fn(u32) -> usize| -> (f64, usize) {
        let p = brume::photo::preprocess(photo, &prepare_options).unwrap();
        let stats = p.prepared.as_ref().unwrap().stats.clone();
        let (mut sum, mut n) = (0.0, 0);
        // Every row, row 0 too, whose run is no occlusion (the top band continues row 1's
        // fattened edge over its two pixels beside the pole, and a band's continuation is
        // no occluder): the whole hole's plane there rested on the wall's column of edges
        // and one pole edge, a ramp in the mirrored frame, until a plane sloped across a
        // column had to beat the one level along it by 2δ (`prep::fill`).
        for y in 0..h {
            for x in OCCLUDED.start..POLE.start - 2 {
                let wall = *photo
                    .depth
                    .range
                    .get(column(OCCLUDED.start - 1), y as usize);
                let got = *p.range.get(column(x), y as usize);
                sum += f64::from((got / wall).ln().abs());
                n += 1;
            }
        }
        (sum / n as f64, stats.occluded)
    };
    let wall_error = |photo: &Photo| wall_error_at(photo, &|x| x as usize);
    let (as_occlusion, occluded) = wall_error(&stereo);
    let (as_hole, none) = wall_error(&png);
    assert_eq!(none, 0);
    assert!(occluded >= (OCCLUDED.len() - 2) * h as usize, "{occluded}");
    assert!(as_occlusion < 0.01, "mean |ln(R / R_wall)| {as_occlusion}");
    let (from_float, float_occluded) = wall_error(&float);
    assert_eq!(float_occluded, occluded);
    assert!(
        from_float < 0.01,
        "mean |ln(R / R_wall)| {from_float} from a float map"
    );
    assert!(as_hole > 0.3, "mean |ln(R / R_wall)| {as_hole} as a hole");
    let mirror = |x: u32| (w - 1 - x) as usize;
    let (from_right, right_occluded) = wall_error_at(&right, &mirror);
    assert_eq!(right_occluded, occluded);
    assert!(
        from_right < 0.01,
        "mean |ln(R / R_wall)| {from_right} from a right view"
    );
    let (right_as_left, none) = wall_error_at(&as_left, &mirror);
    assert_eq!(none, 0, "a right view read as a left one");
    assert!(right_as_left > 0.3, "{right_as_left}");
}
