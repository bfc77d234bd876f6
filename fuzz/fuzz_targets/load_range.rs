//! The whole depth-loading path: extension, options and an optional calib.txt chosen by
//! the input's first bytes (see `brume_fuzz::load_range_input`), then decoding, dataset
//! rules and range conversion.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| brume_fuzz::load_range_input(data));
