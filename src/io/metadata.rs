//! What an image of a photo carries besides its pixels: the photo's colour profile
//! ([`crate::io::colour_profile`]) and its EXIF (camera, lens, exposure, date, place), so
//! that a fogged photo keeps its colours and its place in a photo library, which sorts by
//! the EXIF date.
//!
//! The EXIF block is copied as the photo had it, with three edits made in place (every
//! other byte, maker notes included, stays where it was, so offsets into it stay right):
//! the orientation becomes 1, as the pixels written are upright; `PixelXDimension` and
//! `PixelYDimension` become the output's size; and the link to the second IFD, the
//! thumbnail's, is cut, since that thumbnail shows the photo without its fog. A block that
//! is not a well-formed TIFF structure is not carried (the photo's EXIF is then left
//! out, as before), and neither is one too large for a JPEG's APP1 segment.

use std::sync::Arc;

use crate::io::colour_profile::ColourProfile;

/// A photo's colour profile and EXIF, for the PNG and JPEG images written of it.
#[derive(Clone, Debug, Default)]
pub struct PhotoMetadata {
    /// Its ICC profile, where it has a usable one.
    pub profile: Option<ColourProfile>,
    /// Its EXIF block (TIFF structure, without JPEG's `Exif\0\0`), as stored.
    pub exif: Option<Arc<Vec<u8>>>,
}

/// The largest EXIF block a JPEG's APP1 segment holds: 65535 bytes of segment less its
/// length field and `Exif\0\0`.
const MAX_JPEG_EXIF_BYTES: usize = 65535 - 2 - 6;

const ORIENTATION: u16 = 0x0112;
const EXIF_IFD: u16 = 0x8769;
const PIXEL_X_DIMENSION: u16 = 0xA002;
const PIXEL_Y_DIMENSION: u16 = 0xA003;
const SHORT: u16 = 3;
const LONG: u16 = 4;

impl PhotoMetadata {
    /// The colour profile, where there is one.
    pub fn profile(&self) -> Option<&ColourProfile> {
        self.profile.as_ref()
    }

    /// The luminance of the photo's linear R, G, B: its profile's
    /// ([`ColourProfile::luminance_weights`]), or Rec. 709's for a photo without one (sRGB).
    pub fn luminance_weights(&self) -> [f64; 3] {
        self.profile().map_or(
            crate::sky::REC709_LUMINANCE,
            ColourProfile::luminance_weights,
        )
    }

    /// The EXIF block for an image `width x height` of the upright photo (see the module
    /// docs), or None where the photo had none or it cannot be carried; `name` is the
    /// output's, for the log.
    pub fn exif_for_output(&self, width: u32, height: u32, name: &str) -> Option<Vec<u8>> {
        let tiff = self.exif.as_ref()?;
        if tiff.len() > MAX_JPEG_EXIF_BYTES {
            log::warn!(
                "{name}: the photo's EXIF ({} bytes) is larger than a JPEG segment holds; \
                 it is not copied",
                tiff.len()
            );
            return None;
        }
        let edited = upright_exif(tiff, width, height);
        if edited.is_none() {
            log::warn!("{name}: the photo's EXIF is not a well-formed TIFF block; not copied");
        }
        edited
    }
}

/// The TIFF block `tiff` with the edits of the module docs, or None where it is not well
/// formed (an offset or an entry out of bounds, an unknown byte order, a tag of an
/// unexpected type).
fn upright_exif(tiff: &[u8], width: u32, height: u32) -> Option<Vec<u8>> {
    let mut out = tiff.to_vec();
    let order = ByteOrder::of(&out)?;
    let ifd0 = order.u32(&out, 4)? as usize;
    let mut exif_ifd = None;
    let next_at = next_ifd_link(&out, order, ifd0)?;
    for at in entries(&out, order, ifd0)? {
        match order.u16(&out, at)? {
            ORIENTATION => set_short(&mut out, order, at, 1)?,
            EXIF_IFD => exif_ifd = Some(order.u32(&out, at + 8)? as usize),
            _ => {}
        }
    }
    order.put_u32(&mut out, next_at, 0)?;
    if let Some(exif_ifd) = exif_ifd {
        for at in entries(&out, order, exif_ifd)? {
            match order.u16(&out, at)? {
                PIXEL_X_DIMENSION => set_dimension(&mut out, order, at, width)?,
                PIXEL_Y_DIMENSION => set_dimension(&mut out, order, at, height)?,
                _ => {}
            }
        }
    }
    Some(out)
}

/// The offsets of the 12-byte entries of the IFD at `ifd`, all within the block.
fn entries(tiff: &[u8], order: ByteOrder, ifd: usize) -> Option<Vec<usize>> {
    let count = usize::from(order.u16(tiff, ifd)?);
    let first = ifd.checked_add(2)?;
    (first.checked_add(12 * count)? <= tiff.len())
        .then(|| (0..count).map(|k| first + 12 * k).collect())
}

/// The offset of the IFD at `ifd`'s link to the next IFD, within the block.
fn next_ifd_link(tiff: &[u8], order: ByteOrder, ifd: usize) -> Option<usize> {
    let count = usize::from(order.u16(tiff, ifd)?);
    let at = ifd.checked_add(2 + 12 * count)?;
    (at.checked_add(4)? <= tiff.len()).then_some(at)
}

/// Sets a SHORT entry of count 1 to `value`.
fn set_short(tiff: &mut [u8], order: ByteOrder, at: usize, value: u16) -> Option<()> {
    if order.u16(tiff, at + 2)? != SHORT || order.u32(tiff, at + 4)? != 1 {
        return None;
    }
    order.put_u16(tiff, at + 8, value)
}

/// Sets a size entry (SHORT or LONG, count 1) to `value`, as a LONG where a SHORT cannot
/// hold it.
fn set_dimension(tiff: &mut [u8], order: ByteOrder, at: usize, value: u32) -> Option<()> {
    if order.u32(tiff, at + 4)? != 1 {
        return None;
    }
    match (order.u16(tiff, at + 2)?, u16::try_from(value)) {
        (SHORT, Ok(short)) => {
            order.put_u16(tiff, at + 8, short)?;
            order.put_u16(tiff, at + 10, 0)
        }
        (SHORT | LONG, _) => {
            order.put_u16(tiff, at + 2, LONG)?;
            order.put_u32(tiff, at + 8, value)
        }
        _ => None,
    }
}

/// A TIFF block's byte order, from its first two bytes.
#[derive(Clone, Copy)]
enum ByteOrder {
    Little,
    Big,
}

impl ByteOrder {
    fn of(tiff: &[u8]) -> Option<ByteOrder> {
        match tiff.get(..4)? {
            [b'I', b'I', 42, 0] => Some(ByteOrder::Little),
            [b'M', b'M', 0, 42] => Some(ByteOrder::Big),
            _ => None,
        }
    }

    fn u16(self, b: &[u8], at: usize) -> Option<u16> {
        let bytes: [u8; 2] = b.get(at..at.checked_add(2)?)?.try_into().ok()?;
        Some(match self {
            ByteOrder::Little => u16::from_le_bytes(bytes),
            ByteOrder::Big => u16::from_be_bytes(bytes),
        })
    }

    fn u32(self, b: &[u8], at: usize) -> Option<u32> {
        let bytes: [u8; 4] = b.get(at..at.checked_add(4)?)?.try_into().ok()?;
        Some(match self {
            ByteOrder::Little => u32::from_le_bytes(bytes),
            ByteOrder::Big => u32::from_be_bytes(bytes),
        })
    }

    fn put_u16(self, b: &mut [u8], at: usize, v: u16) -> Option<()> {
        let bytes = match self {
            ByteOrder::Little => v.to_le_bytes(),
            ByteOrder::Big => v.to_be_bytes(),
        };
        b.get_mut(at..at.checked_add(2)?)?.copy_from_slice(&bytes);
        Some(())
    }

    fn put_u32(self, b: &mut [u8], at: usize, v: u32) -> Option<()> {
        let bytes = match self {
            ByteOrder::Little => v.to_le_bytes(),
            ByteOrder::Big => v.to_be_bytes(),
        };
        b.get_mut(at..at.checked_add(4)?)?.copy_from_slice(&bytes);
        Some(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A TIFF block in `order`: IFD0 with Make (ASCII, out of line), Orientation 6 and the
    /// Exif IFD pointer, linking to an IFD1; the Exif IFD with PixelXDimension (SHORT)
    /// and PixelYDimension (LONG).
    fn block(order: ByteOrder) -> Vec<u8> {
        let mut b = match order {
            ByteOrder::Little => b"II*\0".to_vec(),
            ByteOrder::Big => b"MM\0*".to_vec(),
        };
        b.resize(8 + 2 + 3 * 12 + 4 + 2 + 2 * 12 + 4 + 2 + 4 + 8, 0);
        let (ifd0, exif, ifd1, make) = (8, 8 + 42, 8 + 42 + 30, 8 + 42 + 30 + 6);
        let entry = |b: &mut Vec<u8>, at: usize, tag: u16, kind: u16, count: u32| {
            order.put_u16(b, at, tag).unwrap();
            order.put_u16(b, at + 2, kind).unwrap();
            order.put_u32(b, at + 4, count).unwrap();
        };
        order.put_u32(&mut b, 4, ifd0 as u32).unwrap();
        order.put_u16(&mut b, ifd0, 3).unwrap();
        entry(&mut b, ifd0 + 2, 0x010F, 2, 7);
        order.put_u32(&mut b, ifd0 + 10, make as u32).unwrap();
        entry(&mut b, ifd0 + 14, ORIENTATION, SHORT, 1);
        order.put_u16(&mut b, ifd0 + 22, 6).unwrap();
        entry(&mut b, ifd0 + 26, EXIF_IFD, LONG, 1);
        order.put_u32(&mut b, ifd0 + 34, exif as u32).unwrap();
        order.put_u32(&mut b, ifd0 + 38, ifd1 as u32).unwrap();
        order.put_u16(&mut b, exif, 2).unwrap();
        entry(&mut b, exif + 2, PIXEL_X_DIMENSION, SHORT, 1);
        order.put_u16(&mut b, exif + 10, 4032).unwrap();
        entry(&mut b, exif + 14, PIXEL_Y_DIMENSION, LONG, 1);
        order.put_u32(&mut b, exif + 22, 3024).unwrap();
        b[make..make + 8].copy_from_slice(b"camera\0\0");
        b
    }

    fn read(b: &[u8]) -> exif::Exif {
        exif::Reader::new().read_raw(b.to_vec()).unwrap()
    }

    fn uint(e: &exif::Exif, tag: exif::Tag) -> Option<u32> {
        e.get_field(tag, exif::In::PRIMARY)?.value.get_uint(0)
    }

    #[test]
    fn orientation_size_and_thumbnail_link_are_edited_in_either_order() {
        for order in [ByteOrder::Little, ByteOrder::Big] {
            let source = block(order);
            assert_eq!(uint(&read(&source), exif::Tag::Orientation), Some(6));
            let out = upright_exif(&source, 3024, 70_000).unwrap();
            assert_eq!(out.len(), source.len());
            let e = read(&out);
            assert_eq!(uint(&e, exif::Tag::Orientation), Some(1));
            assert_eq!(uint(&e, exif::Tag::PixelXDimension), Some(3024));
            // A SHORT cannot hold 70 000: the entry becomes a LONG.
            assert_eq!(uint(&e, exif::Tag::PixelYDimension), Some(70_000));
            let make = e.get_field(exif::Tag::Make, exif::In::PRIMARY).unwrap();
            assert_eq!(make.display_value().to_string(), "\"camera\"");
            assert_eq!(order.u32(&out, 8 + 38), Some(0), "IFD1 unlinked");
        }
    }

    /// Every cut of the block and every byte set to 0xFF in turn gives an edited block or
    /// None, never a panic.
    #[test]
    fn broken_blocks_give_none_not_a_panic() {
        let source = block(ByteOrder::Little);
        for len in 0..source.len() {
            let _ = upright_exif(&source[..len], 10, 10);
        }
        assert!(upright_exif(&source[..8 + 2 + 12], 10, 10).is_none());
        for at in 0..source.len() {
            let mut b = source.clone();
            b[at] = 0xFF;
            let _ = upright_exif(&b, 10, 10);
        }
        assert!(upright_exif(b"MM\0+\0\0\0\x08", 1, 1).is_none());
    }

    #[test]
    fn a_block_too_large_for_a_jpeg_segment_is_not_carried() {
        let mut large = block(ByteOrder::Little);
        large.resize(MAX_JPEG_EXIF_BYTES + 1, 0);
        let metadata = PhotoMetadata {
            profile: None,
            exif: Some(Arc::new(large)),
        };
        assert!(metadata.exif_for_output(1, 1, "out.jpg").is_none());
    }
}
