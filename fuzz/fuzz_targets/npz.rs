//! NumPy .npz (a zip of .npy members), through the depth loader.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| brume_fuzz::load_as(data, "npz"));
