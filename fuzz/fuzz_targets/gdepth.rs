//! A portrait photo's JPEG through the depth loader: the JPEG's header segments, its
//! standard and extended XMP, the properties, GDepth's base64 data, a Dynamic Depth
//! container's items after the primary image, an iPhone portrait's Multi-Picture index
//! and its auxiliary images' XMP, and the embedded depth image.
#![no_main]

use brume::io::depth::{load_range_from_bytes, DepthOptions};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let name = std::path::Path::new("portrait.jpg");
    let _ = load_range_from_bytes(data, name, &DepthOptions::default(), None);
});
