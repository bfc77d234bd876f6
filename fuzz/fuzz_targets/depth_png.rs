//! 8- and 16-bit depth PNGs under every dataset rule (Middlebury 2006, KITTI, NYU, TUM,
//! png16, auto): two option bytes (see `brume_fuzz::options`), then the PNG.
#![no_main]

use brume::io::depth::load_range_from_bytes;
use brume_fuzz::{options, OPTION_BYTES};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if data.len() < OPTION_BYTES {
        return;
    }
    let opts = options(data[0], data[1]);
    let png = &data[OPTION_BYTES..];
    let _ = load_range_from_bytes(png, std::path::Path::new("d.png"), &opts, None);
});
