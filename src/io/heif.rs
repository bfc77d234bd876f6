//! HEIF files (an iPhone's HEIC photos, AVIF) told by their first bytes and refused with
//! what to do instead: brume has no HEVC or AV1 decoder.

use std::path::Path;

use crate::{Error, Result};

/// The major brands of HEIF files (ISO/IEC 23008-12): HEIC (HEVC-coded; an iPhone's
/// default photo format since iOS 11), its image sequences and bursts, AVIF, and the
/// format's own.
const HEIF_BRANDS: [&[u8; 4]; 12] = [
    b"heic", b"heix", b"hevc", b"hevx", b"heim", b"heis", b"hevm", b"hevs", b"mif1", b"msf1",
    b"avif", b"avis",
];

/// The major brand of a HEIF file (its `ftyp` box, first in the file), where the bytes
/// start like one.
pub fn heif_brand(bytes: &[u8]) -> Option<String> {
    let brand = bytes.get(8..12)?;
    (bytes.get(4..8) == Some(b"ftyp") && HEIF_BRANDS.iter().any(|b| b.as_slice() == brand))
        .then(|| String::from_utf8_lossy(brand).into_owned())
}

/// Refuses a HEIF file (an iPhone's HEIC photo) with what to do instead: brume has no
/// HEVC decoder. Ok for any other file, or one that cannot be read (its loader says why).
pub fn refuse_heif(path: &Path) -> Result<()> {
    use std::io::Read;
    let mut head = Vec::new();
    let read = std::fs::File::open(path).and_then(|f| f.take(12).read_to_end(&mut head));
    match read {
        Ok(_) => refuse_heif_bytes(&head, &path.display().to_string()),
        Err(_) => Ok(()),
    }
}

/// [`refuse_heif`] for the bytes (at least the first 12) of the file `name`.
pub(crate) fn refuse_heif_bytes(bytes: &[u8], name: &str) -> Result<()> {
    match heif_brand(bytes) {
        Some(brand) => Err(heif_refusal(name, &brand)),
        None => Ok(()),
    }
}

/// The refusal of the HEIF file `name` of `brand`, with what to do instead.
fn heif_refusal(name: &str, brand: &str) -> Error {
    if brand.starts_with("avi") {
        return Error::format(
            name,
            format!(
                "this is an AVIF image (brand `{brand}`), which brume does not read; convert it \
                 to PNG or JPEG"
            ),
        );
    }
    Error::format(
        name,
        format!(
            "this is a HEIF image (brand `{brand}`; HEIC is an iPhone's default photo \
             format), which brume does not read: save the photo as JPEG (on an iPhone, \
             Settings > Camera > Formats > Most Compatible; a portrait's JPEG keeps its depth \
             map, which brume reads) or convert it (`heif-convert IMG.heic IMG.jpg`, then \
             give its depth map with --depth)"
        ),
    )
}
