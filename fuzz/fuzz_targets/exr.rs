//! OpenEXR float map, through the depth loader (header check, channel choice, range).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| brume_fuzz::load_as(data, "exr"));
