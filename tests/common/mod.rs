//! Helpers shared by the `prep_*` integration tests.
#![allow(dead_code)]

use brume::raster::{Grid, ScalarMap};

/// The real Middlebury Aloe ground-truth disparity, as range `1 / (d + 270)`, NaN where
/// `d = 0` (unknown). A stand-in for the real loader, which lives in `io`.
pub const ALOE_DISPARITY: &str = "/work/shared/data/aloe/disparity.png";

/// Loads [`ALOE_DISPARITY`] as a range map; `None` if the file is not there.
pub fn aloe_range() -> Option<ScalarMap> {
    let img = image::open(ALOE_DISPARITY).ok()?.to_luma8();
    let (w, h) = (img.width() as usize, img.height() as usize);
    let data = img
        .pixels()
        .map(|p| {
            if p[0] == 0 {
                f32::NAN
            } else {
                1.0 / (p[0] as f32 + 270.0)
            }
        })
        .collect();
    Some(Grid::from_vec(w, h, data))
}

/// Asserts that every finite pixel of `before` has exactly the same bits in `after`.
pub fn assert_known_unchanged(before: &ScalarMap, after: &ScalarMap) {
    assert_eq!(
        (before.width(), before.height()),
        (after.width(), after.height())
    );
    for (i, (b, a)) in before.as_slice().iter().zip(after.as_slice()).enumerate() {
        if b.is_finite() {
            assert_eq!(
                b.to_bits(),
                a.to_bits(),
                "known pixel {i} changed: {b} -> {a}"
            );
        }
    }
}

/// Asserts that every pixel is finite.
pub fn assert_all_finite(m: &ScalarMap) {
    if let Some(i) = m.as_slice().iter().position(|v| !v.is_finite()) {
        panic!("pixel {i} is {}", m.as_slice()[i]);
    }
}

/// Writes an RGB picture as PNG (for looking at test output by hand).
pub fn save_png(path: &str, w: usize, h: usize, px: &[[u8; 3]]) {
    let buf: Vec<u8> = px.iter().flatten().copied().collect();
    image::save_buffer(path, &buf, w as u32, h as u32, image::ColorType::Rgb8).expect("save png");
}
