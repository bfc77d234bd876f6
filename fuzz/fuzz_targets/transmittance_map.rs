//! A transmittance map (`--transmittance-map`, `Photo::load_transmittance`):
//! `compat::decode_optical_depth`. An accepted map must have a size within `io::limits`
//! and a finite, positive optical depth at every pixel; every error must name the file.
#![no_main]

use brume::io::limits::{MAX_PIXELS, MAX_SIDE};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    match brume::compat::decode_optical_depth(data, "t.png") {
        Ok(map) => {
            let (w, h) = (map.width(), map.height());
            assert!(
                w >= 1 && h >= 1 && w <= MAX_SIDE && h <= MAX_SIDE,
                "{w}x{h}"
            );
            assert!(w * h <= MAX_PIXELS, "{w}x{h}");
            for &v in map.as_slice() {
                assert!(v.is_finite() && v > 0.0, "optical depth {v}");
            }
        }
        Err(e) => {
            let msg = e.to_string();
            assert!(msg.starts_with("t.png: "), "{msg}");
        }
    }
});
