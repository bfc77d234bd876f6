//! The real Middlebury Aloe disparity: indoor, no sky, every hole filled.

use crate::common;

use brume::prep::{prepare, PrepOptions};
use common::*;

#[test]
fn aloe_has_no_sky_and_every_hole_is_filled() {
    let map = aloe_range();
    let unknown = map.as_slice().iter().filter(|v| v.is_nan()).count();
    assert_eq!(unknown, 49_130, "the sample's documented unknown count");
    let p = prepare(&map, &PrepOptions::default()).unwrap();
    let s = &p.stats;
    assert_eq!(
        (s.sky_components, s.sky_pixels, s.margin_pixels, s.s_max),
        (0, 0, 0, None),
        "{s:?}"
    );
    // The occlusion band along the left border is continued row by row, the rest filled
    // as holes; no known value is an outlier.
    assert_eq!(s.local_outliers, 0, "{s:?}");
    assert_eq!(s.hole_pixels + s.border_filled, unknown, "{s:?}");
    assert!(s.holes > 1000, "{s:?}");
    assert_all_finite(&p.range);
    assert_known_unchanged(&map, &p.range);
    // Filled values stay within the known range (clamped to each hole's boundary).
    let known = map.as_slice().iter().copied().filter(|v| v.is_finite());
    let (lo, hi) = known.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    assert!(p.range.as_slice().iter().all(|&v| (lo..=hi).contains(&v)));
    if let Ok(dir) = std::env::var("PREP_VIS_DIR") {
        let (w, h, px) = brume::prep::visualize(&map, &p);
        save_png(&format!("{dir}/aloe.png"), w, h, &px);
    }
}
