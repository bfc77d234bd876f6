//! Middlebury 2014 calib.txt parser.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // The file is read as UTF-8 text before it is parsed.
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = brume::io::depth::parse_calib_str(text, std::path::Path::new("calib.txt"));
    }
});
