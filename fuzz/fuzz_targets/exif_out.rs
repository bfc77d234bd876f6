//! A photo's EXIF block as its outputs carry it (`PhotoMetadata::exif_for_output`, which
//! edits it in place): any block gives an edited copy of the same length, or none; never
//! a panic.
#![no_main]

use std::sync::Arc;

use brume::io::metadata::PhotoMetadata;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // The first 4 bytes are the output's size, the rest the block.
    let Some((size, block)) = data.split_first_chunk::<4>() else {
        return;
    };
    let width = u32::from(u16::from_le_bytes([size[0], size[1]]));
    let height = u32::from(u16::from_le_bytes([size[2], size[3]])) << 4;
    let metadata = PhotoMetadata {
        profile: None,
        exif: Some(Arc::new(block.to_vec())),
    };
    let Some(edited) = metadata.exif_for_output(width, height, "fuzz.jpg") else {
        return;
    };
    assert_eq!(edited.len(), block.len());
});
