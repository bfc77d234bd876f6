//! The largest image any reader accepts, checked on the size a file's header claims before
//! anything is allocated for its pixels, so that a few hundred hostile bytes cannot make
//! the process ask for gigabytes (and abort when the allocator refuses); and the most bytes
//! read from one input file, so that a path that never ends (`/dev/zero`, a pipe) or a
//! file far larger than any image brume takes is refused instead of read until memory
//! runs out.

use std::fs::File;
use std::io::Read;
use std::path::Path;

use crate::{Error, Result};

/// Largest width or height accepted, in pixels: the usual `GL_MAX_TEXTURE_SIZE` of
/// desktop and mobile drivers, beyond which the renderer could not upload the image anyway.
pub const MAX_SIDE: usize = 16384;

/// Largest pixel count accepted (2^26, 8192 x 8192, about 67 million): a 64-megapixel
/// camera frame fits, and decoding the largest accepted photograph (8-bit pixels, then an
/// RGB float copy) stays near 1 GiB.
pub const MAX_PIXELS: usize = 1 << 26;

/// Checks a size claimed by `path`'s header against [`MAX_SIDE`] and [`MAX_PIXELS`]; `what`
/// says which format claims it (`"EXR"`, `"PNG"`). The error names the file, the size and
/// the limit.
pub fn check_size(path: &Path, what: &str, width: u64, height: u64) -> Result<()> {
    let side = MAX_SIDE as u64;
    if width > side || height > side {
        return Err(Error::format(
            path,
            format!(
                "{what} header claims {width}x{height} pixels; at most {MAX_SIDE} per side is accepted"
            ),
        ));
    }
    // Both sides are at most 2^14 here, so the product cannot overflow.
    if width * height > MAX_PIXELS as u64 {
        return Err(Error::format(
            path,
            format!(
                "{what} header claims {width}x{height} = {} pixels; at most {MAX_PIXELS} are accepted",
                width * height
            ),
        ));
    }
    Ok(())
}

/// Most bytes read from one binary input (image, depth, mask, noise): [`MAX_PIXELS`] at
/// 32 bytes each (four 64-bit samples, the widest pixel a reader takes, a float64 RGBA
/// TIFF) and 1 MiB for headers, about 2.1 GB.
pub const MAX_FILE_BYTES: u64 = MAX_PIXELS as u64 * 32 + (1 << 20);

/// Most bytes read from one text input (tables, calibration, camera files, manifests):
/// 256 MiB (268 MB), a manifest of more than a million frames.
pub const MAX_TEXT_BYTES: u64 = 256 << 20;

/// Reads the whole of the input file `path`, at most [`MAX_FILE_BYTES`]. A larger file is
/// refused from its size before anything is read; a path that is not a regular file (a
/// pipe, a device) is read until the limit and refused beyond it.
pub fn read_file(path: &Path) -> Result<Vec<u8>> {
    read_at_most(path, MAX_FILE_BYTES, "an input file")
}

/// Reads the whole of the text file `path` (UTF-8), at most [`MAX_TEXT_BYTES`], as
/// [`read_file`] does.
pub fn read_text(path: &Path) -> Result<String> {
    let bytes = read_at_most(path, MAX_TEXT_BYTES, "a text file")?;
    String::from_utf8(bytes).map_err(|e| {
        Error::format(
            path,
            format!(
                "not UTF-8 text (byte {} is not valid UTF-8); expected a text file",
                e.utf8_error().valid_up_to()
            ),
        )
    })
}

fn read_at_most(path: &Path, limit: u64, what: &str) -> Result<Vec<u8>> {
    let most = format!("{} ({limit} bytes)", crate::memory::human(limit));
    let mut file = File::open(path).map_err(|e| Error::io(path, e))?;
    let meta = file.metadata().map_err(|e| Error::io(path, e))?;
    if meta.is_file() && meta.len() > limit {
        let len = meta.len();
        return Err(Error::format(
            path,
            format!(
                "{} ({len} bytes), larger than any input brume takes; expected {what} of at \
                 most {most}",
                crate::memory::human(len)
            ),
        ));
    }
    // The size a regular file has, so that reading it does not grow the buffer by copies;
    // a size the memory cannot hold is an error, not an abort.
    let mut bytes = Vec::new();
    if meta.is_file() {
        bytes
            .try_reserve_exact(meta.len() as usize)
            .map_err(|_| cannot_hold(path, meta.len()))?;
    }
    (&mut file)
        .take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > limit {
        return Err(Error::format(
            path,
            format!(
                "not a regular file, and it went on past {most}; expected {what} that ends \
                 within that"
            ),
        ));
    }
    Ok(bytes)
}

/// Bytes per pixel that decoding a depth map and reading it as range take at their peak,
/// besides the file's bytes, measured for 8000x6000 maps: 12 resident at most (a float64
/// TIFF, whose samples are decoded whole before they become f32; 8.1 the others), and up
/// to 13.6 of address space, which `ulimit -v` counts with the decoder's threads' arenas
/// (11.2 an `.npy`, 11 an EXR, 9.6 a PFM or a float32 TIFF, 7.6 a 16-bit PNG).
pub(crate) const MAP_DECODING_BYTES_PER_PIXEL: u64 = 14;

/// Refuses to decode `name`, a depth map (or the map a file holds: an archive's member, a
/// phone JPEG's depth image) of `width` x `height` from its header, when its decoding and
/// the `held` bytes it needs first (an archive member inflated) cannot fit in the memory
/// left: before the decoder allocates for it, so that the error names the map and its
/// size where the allocator would abort the process or a cgroup kill it.
pub(crate) fn check_map_decoding_fits(
    name: &str,
    width: usize,
    height: usize,
    held: u64,
) -> Result<crate::memory::Reservation> {
    let pixels = width as u64 * height as u64;
    crate::memory::reserve(
        &format!("reading the depth map {name} ({width}x{height})"),
        held.saturating_add(MAP_DECODING_BYTES_PER_PIXEL.saturating_mul(pixels)),
        &format!(
            "reading a depth map holds about {MAP_DECODING_BYTES_PER_PIXEL} bytes per pixel \
             besides its file: use a smaller depth map"
        ),
    )
}

/// The error for a file of `len` bytes whose buffer could not be allocated: with its size
/// and what could be had, where "out of memory" alone said neither.
fn cannot_hold(path: &Path, len: u64) -> Error {
    let human = crate::memory::human;
    let left = crate::memory::available()
        .map(|b| format!(", and only {} can be had", human(b)))
        .unwrap_or_default();
    Error::OutOfMemory {
        what: format!("reading {}", path.display()),
        detail: format!("needs {} to hold the file{left}", human(len)),
        hint: "it is read whole before it is decoded: free memory, or give a smaller file"
            .to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_are_inclusive_and_name_the_file() {
        let p = Path::new("x.exr");
        assert!(check_size(p, "EXR", MAX_SIDE as u64, (MAX_PIXELS / MAX_SIDE) as u64).is_ok());
        let e = check_size(p, "EXR", MAX_SIDE as u64 + 1, 1)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("x.exr") && e.contains("16385x1") && e.contains("16384"),
            "{e}"
        );
        let e = check_size(p, "EXR", MAX_SIDE as u64, MAX_SIDE as u64)
            .unwrap_err()
            .to_string();
        assert!(e.contains("268435456") && e.contains("67108864"), "{e}");
        assert!(check_size(p, "NPY", u64::MAX, u64::MAX).is_err());
    }

    #[test]
    fn reads_stop_at_the_limit_for_files_and_for_streams() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("d.png");
        std::fs::write(&file, [7u8; 1000]).unwrap();
        assert_eq!(read_at_most(&file, 1000, "a file").unwrap().len(), 1000);
        let e = read_at_most(&file, 999, "a file").unwrap_err().to_string();
        assert!(
            e.contains("d.png") && e.contains("(1000 bytes)") && e.contains("999 bytes"),
            "{e}"
        );
        // A stream has no size to refuse up front: it is read only as far as the limit.
        let zero = Path::new("/dev/zero");
        let e = read_at_most(zero, 4096, "a file").unwrap_err().to_string();
        assert!(
            e.contains("/dev/zero") && e.contains("not a regular file") && e.contains("4096"),
            "{e}"
        );
        std::fs::write(&file, b"ok\n\xff").unwrap();
        let e = read_text(&file).unwrap_err().to_string();
        assert!(e.contains("byte 3") && e.contains("UTF-8"), "{e}");
    }
}
