//! Colour images (PNG, JPEG, WebP, TIFF; OpenEXR and colour PFM, told apart by their magic)
//! decoded to linear light.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = brume::io::image::decode_linear_rgb(data, "c.png");
});
