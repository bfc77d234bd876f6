//! Sky-mask PNG decoder (`decode_sky_mask`): the first byte picks the format (binary,
//! Cityscapes labelIds, trainIds), the rest is the file. An accepted mask has one entry
//! per pixel and a size within `io::limits`.
#![no_main]

use brume::io::limits::{MAX_PIXELS, MAX_SIDE};
use brume::io::mask::{decode_sky_mask, SkyMaskFormat};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&pick, png)) = data.split_first() else {
        return;
    };
    let format = SkyMaskFormat::ALL[usize::from(pick) % SkyMaskFormat::ALL.len()];
    if let Ok(mask) = decode_sky_mask(png, "m.png", format) {
        let (w, h) = (mask.width(), mask.height());
        assert!(
            w <= MAX_SIDE && h <= MAX_SIDE && w * h <= MAX_PIXELS,
            "{w}x{h}"
        );
        assert_eq!(mask.as_slice().len(), w * h);
    }
});
