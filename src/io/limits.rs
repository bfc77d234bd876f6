//! The largest image any reader accepts, checked on the size a file's header claims before
//! anything is allocated for its pixels, so that a few hundred hostile bytes cannot make
//! the process ask for gigabytes (and abort when the allocator refuses).

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
}
