//! The embedded demo scene decodes through the file loaders and matches its source.

use brume::io::demo::{demo_image, demo_range, DEMO_SOURCE};
use brume::io::depth::{DepthFormat, DepthKind};

#[test]
fn demo_image_and_range_have_the_expected_size() {
    let img = demo_image().unwrap();
    assert_eq!((img.width(), img.height()), (641, 555));
    let mean: f32 = img.as_slice().iter().map(|p| p[1]).sum::<f32>() / img.len() as f32;
    assert!(mean > 0.02 && mean < 0.8, "mean green {mean}");
    let d = demo_range().unwrap();
    assert_eq!((d.range.width(), d.range.height()), (641, 555));
    assert_eq!(
        (d.format, d.kind, d.units.as_str()),
        (DepthFormat::Middlebury2006, DepthKind::Disparity, "m")
    );
    // Ray directions use the half-size focal.
    assert_eq!(d.intrinsics.unwrap().fx, 3740.0 / 2.0);
    assert!(DEMO_SOURCE.contains("Middlebury 2006") && DEMO_SOURCE.contains("opencv-doc"));
}

#[test]
fn demo_range_is_nan_exactly_where_disparity_is_zero() {
    let bytes = include_bytes!("../assets/demo/aloe-disparity-half.png");
    let disp = image::load_from_memory(bytes).unwrap().to_luma8();
    let d = demo_range().unwrap();
    let zeros = disp.as_raw().iter().filter(|&&v| v == 0).count();
    assert!(zeros > 0);
    assert_eq!(d.unknown_pixels, zeros);
    for (r, v) in d.range.as_slice().iter().zip(disp.as_raw()) {
        assert_eq!(r.is_nan(), *v == 0);
        if *v != 0 {
            assert!(*r > 0.5 && *r < 20.0, "range {r} m for disparity {v}");
        }
    }
    // Disparities kept in full-size units: same span as the full-size map (43..211).
    let known = disp.as_raw().iter().filter(|&&v| v != 0);
    assert!(*known.clone().min().unwrap() >= 43 && *known.max().unwrap() <= 211);
}

#[test]
fn real_aloe_left_loads() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/aloe/left.jpg");
    // The sample is part of the repository: a missing file is a failure, not a skip.
    assert!(
        path.exists(),
        "{} is missing: restore tests/data/aloe/ from the repository",
        path.display()
    );
    let img = brume::io::image::load_linear_rgb(&path).unwrap();
    assert_eq!((img.width(), img.height()), (1282, 1110));
}
