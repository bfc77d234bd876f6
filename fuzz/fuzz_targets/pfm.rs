//! PFM parser, both magics and byte orders.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = brume::io::depth::parse_pfm(data, std::path::Path::new("d.pfm"));
});
