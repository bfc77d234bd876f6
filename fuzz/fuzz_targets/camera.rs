//! Cityscapes camera JSON parser (`parse_camera_str`). A camera it accepts must have every
//! value within the ranges the parser documents, so that depth baseline·fx/d and the ray
//! stretch stay finite.
#![no_main]

use std::path::Path;

use brume::io::depth::{
    parse_camera_str, CITYSCAPES_BASELINE_RANGE_M, CITYSCAPES_FOCAL_RANGE_PX,
    CITYSCAPES_HEIGHT_RANGE_M, CITYSCAPES_PRINCIPAL_POINT_RANGE_PX, CITYSCAPES_TILT_RANGE_RAD,
};
use libfuzzer_sys::fuzz_target;

fn within(v: f64, (lo, hi): (f64, f64)) -> bool {
    v.is_finite() && (lo..=hi).contains(&v)
}

fuzz_target!(|data: &[u8]| {
    // The file is read as UTF-8 text before it is parsed.
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = Path::new("scene/x_camera.json");
    match parse_camera_str(text, path) {
        Ok(c) => {
            let k = c.intrinsics;
            assert!(
                c.baseline_m > 0.0 && within(c.baseline_m, CITYSCAPES_BASELINE_RANGE_M),
                "{c:?}"
            );
            assert!(
                k.fx > 0.0 && within(k.fx, CITYSCAPES_FOCAL_RANGE_PX),
                "{c:?}"
            );
            assert!(
                k.fy > 0.0 && within(k.fy, CITYSCAPES_FOCAL_RANGE_PX),
                "{c:?}"
            );
            assert!(within(k.cx, CITYSCAPES_PRINCIPAL_POINT_RANGE_PX), "{c:?}");
            assert!(within(k.cy, CITYSCAPES_PRINCIPAL_POINT_RANGE_PX), "{c:?}");
            // A mount is within its ranges, or left out with a note saying why.
            if let Some(m) = c.mount {
                assert!(within(m.height_m, CITYSCAPES_HEIGHT_RANGE_M), "{c:?}");
                assert!(within(m.pitch, CITYSCAPES_TILT_RANGE_RAD), "{c:?}");
                assert!(within(m.roll, CITYSCAPES_TILT_RANGE_RAD), "{c:?}");
                assert!(c.mount_note.is_none(), "{c:?}");
            }
            // The largest depth a 16-bit disparity can give (d = 1/256 px), and the ray
            // stretch at the far corner of the largest image, stay finite in f32.
            let z = c.depth_m(1.0 / 256.0).expect("d > 0 gives a depth");
            let far = brume::io::limits::MAX_SIDE - 1;
            let r = z * k.range_per_depth(far, far);
            assert!(
                r.is_finite() && r > 0.0 && (r as f32).is_finite(),
                "{c:?}: {r}"
            );
        }
        Err(e) => {
            let msg = e.to_string();
            assert!(msg.starts_with("scene/x_camera.json: "), "{msg}");
        }
    }
});
