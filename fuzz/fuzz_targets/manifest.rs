//! `brume batch`'s CSV manifest reader (`parse_manifest`). Every item it returns must
//! have a non-empty image and depth path, and every error must name the manifest.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // The file is read as UTF-8 text before it is parsed.
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = Path::new("data/frames.csv");
    match brume::dataset::parse_manifest(text, path) {
        Ok(items) => {
            assert!(!items.is_empty(), "a manifest with no rows is refused");
            for it in &items {
                assert!(!it.image.as_os_str().is_empty(), "{it:?}");
                assert!(!it.depth.as_os_str().is_empty(), "{it:?}");
                for p in [&it.camera, &it.calib, &it.sky_mask].into_iter().flatten() {
                    assert!(!p.as_os_str().is_empty(), "{it:?}");
                }
                let _ = it.key();
            }
        }
        Err(e) => {
            let msg = e.to_string();
            assert!(msg.starts_with("data/frames.csv: "), "{msg}");
        }
    }
});
