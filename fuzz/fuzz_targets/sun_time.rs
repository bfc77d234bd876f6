//! `--time` (`brume sun`, and the sun from place and time of `sky`, `turbidity` and
//! `render --medium aerial`): `parse_rfc3339`, then the sun's position (NREL's SPA) at
//! that instant from a fixed place. An accepted time must give a finite sun, its zenith
//! angle in [0, 180] and its azimuth in [0, 360); every error must name `time`.
#![no_main]

use brume::sky::sun_position::{parse_rfc3339, Observer};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    // A time parse_rfc3339 reads may still be refused by the algorithm (a year beyond
    // where SPA holds), by the same name.
    let sun = parse_rfc3339(text).and_then(|_| Observer::new(47.4, 8.5).sun_at(text, None));
    match sun {
        Ok(sun) => {
            assert!((0.0..=180.0).contains(&sun.zenith_deg), "{sun:?}");
            assert!(sun.apparent_zenith_deg.is_finite(), "{sun:?}");
            assert!((0.0..360.0).contains(&sun.azimuth_deg), "{sun:?}");
        }
        Err(e) => {
            let msg = e.to_string();
            assert!(msg.starts_with("invalid time = "), "{msg}");
        }
    }
});
