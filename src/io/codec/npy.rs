//! NumPy `.npy` and `.npz` through the `npyz` and `zip` crates: 2-D float16, float32 or
//! float64 arrays, or uint16 (a depth sensor's integer units, as a 16-bit PNG holds them);
//! read only (no output is written as `.npy`).

use std::io::{Cursor, Read};
use std::path::Path;

use super::{MapSamples, NpzDepth, NPZ_FOCAL_ARRAY};
use crate::io::limits::{check_map_decoding_fits, check_size};
use crate::raster::{Grid, ScalarMap};
use crate::{Error, Result};

/// Reads a 2-D (or `h x w x 1`) float16, float32 or float64 NumPy `.npy` array, C or
/// Fortran order, no larger than `io::limits` allows.
pub fn read_npy_scalar(path: &Path) -> Result<ScalarMap> {
    let bytes = crate::io::limits::read_file(path)?;
    parse_npy(&bytes, path)?.floats(
        path,
        "an array of dtype uint16; expected float16, float32 or float64",
    )
}

/// A float or uint16 array from `.npy` bytes.
pub(crate) fn parse_npy(bytes: &[u8], path: &Path) -> Result<MapSamples> {
    check_header(bytes, path)?;
    let npy = npyz::NpyFile::new(bytes)
        .map_err(|e| Error::format(path, format!("not a valid .npy file: {e}")))?;
    let (w, h) = grid_size(npy.shape(), path)?;
    let dtype = npy.dtype().descr();
    // Before the reader reserves room for every value a shorter file cannot hold.
    if let Some(item) = npy.dtype().num_bytes() {
        if bytes.len() < w * h * item {
            return Err(Error::format(
                path,
                format!(
                    "array shape ({h}, {w}) of {dtype} needs at least {} bytes of data, but the \
                     file has {}; it is truncated",
                    w * h * item,
                    bytes.len()
                ),
            ));
        }
    }
    let fortran = npy.order() == npyz::Order::Fortran;
    let truncated = |e: std::io::Error| {
        Error::format(
            path,
            format!("cannot read {h}*{w} values of {dtype}: {e}; the file may be truncated"),
        )
    };
    let npy = match npy.try_data::<f32>() {
        Ok(reader) => {
            let values = reader.collect::<std::io::Result<_>>().map_err(truncated)?;
            return grid(values, w, h, fortran, path).map(MapSamples::Float);
        }
        Err(npy) => npy,
    };
    let npy = match npy.try_data::<f64>() {
        Ok(reader) => {
            let values = reader
                .map(|v| v.map(|x| x as f32))
                .collect::<std::io::Result<_>>()
                .map_err(truncated)?;
            return grid(values, w, h, fortran, path).map(MapSamples::Float);
        }
        Err(npy) => npy,
    };
    let npy = match npy.try_data::<half::f16>() {
        Ok(reader) => {
            let values = reader
                .map(|v| v.map(half::f16::to_f32))
                .collect::<std::io::Result<_>>()
                .map_err(truncated)?;
            return grid(values, w, h, fortran, path).map(MapSamples::Float);
        }
        Err(npy) => npy,
    };
    match npy.try_data::<u16>() {
        Ok(reader) => {
            let values = reader.collect::<std::io::Result<_>>().map_err(truncated)?;
            grid(values, w, h, fortran, path).map(MapSamples::Uint16)
        }
        Err(_) => Err(Error::format(
            path,
            format!(
                "array dtype is {dtype}; expected float16, float32 or float64 (or uint16, \
                 a depth sensor's integer units)"
            ),
        )),
    }
}

/// The width and height of the `.npy` array `bytes`, from its header alone, if it can be
/// read (else the decoder's error).
pub(crate) fn npy_size(bytes: &[u8], path: &Path) -> Option<(usize, usize)> {
    check_header(bytes, path).ok()?;
    let npy = npyz::NpyFile::new(bytes).ok()?;
    grid_size(npy.shape(), path).ok()
}

/// Width and height of a `(h, w)` or `(h, w, 1)` shape within `io::limits`.
fn grid_size(shape: &[u64], path: &Path) -> Result<(usize, usize)> {
    let (h, w) = match shape[..] {
        [h, w] | [h, w, 1] if h > 0 && w > 0 => (h, w),
        _ => {
            return Err(Error::format(
                path,
                format!("array shape is {shape:?}; expected (height, width)"),
            ))
        }
    };
    // Before anything is sized from the shape: a product of two 2^32 sides wraps to 0.
    check_size(path, "NPY", w, h)?;
    Ok((w as usize, h as usize))
}

/// The grid of `values` read in C (row-major) or Fortran (column-major) order.
fn grid<T: Copy>(
    values: Vec<T>,
    w: usize,
    h: usize,
    fortran: bool,
    path: &Path,
) -> Result<Grid<T>> {
    if values.len() != w * h {
        return Err(Error::format(
            path,
            format!("expected {h}*{w} values, found {}", values.len()),
        ));
    }
    Ok(if fortran {
        Grid::from_fn(w, h, |x, y| values[x * h + y])
    } else {
        Grid::from_vec(w, h, values)
    })
}

/// The name of the array an `.npz` archive holds that brume reads when it holds several:
/// what Apple's Depth Pro writes (`np.savez_compressed(path, depth=depth)`).
const NPZ_DEPTH_ARRAY: &str = "depth";

/// Reads the depth array of a NumPy `.npz` archive (`np.savez`, stored, or
/// `np.savez_compressed`, deflated): its only array, or the one named `depth`; and the
/// focal length in pixels beside it, where it holds one named [`NPZ_FOCAL_ARRAY`].
pub(crate) fn parse_npz(bytes: &[u8], path: &Path) -> Result<NpzDepth> {
    let bad = |e: zip::result::ZipError| {
        Error::format(path, format!("not a valid .npz (zip) archive: {e}"))
    };
    let mut archive = zip::ZipArchive::new(Cursor::new(bytes)).map_err(bad)?;
    let arrays: Vec<String> = archive
        .file_names()
        .filter_map(|n| n.strip_suffix(".npy"))
        .map(str::to_owned)
        .collect();
    let name = match &arrays[..] {
        [only] => only.clone(),
        _ if arrays.iter().any(|a| a == NPZ_DEPTH_ARRAY) => NPZ_DEPTH_ARRAY.to_owned(),
        [] => return Err(Error::format(path, "the .npz archive holds no array")),
        _ => {
            return Err(Error::format(
                path,
                format!(
                    "the .npz archive holds {} arrays ({}) and none is named \
                     '{NPZ_DEPTH_ARRAY}'; save the depth alone (np.save to a .npy, or \
                     np.savez(path, {NPZ_DEPTH_ARRAY}=array))",
                    arrays.len(),
                    arrays.join(", ")
                ),
            ))
        }
    };
    let member = archive.by_name(&format!("{name}.npy")).map_err(bad)?;
    let npy = read_member(member, path, &name)?;
    let samples = parse_npy(&npy, path).map_err(|e| within(&name, e))?;
    let focal_px = if name != NPZ_FOCAL_ARRAY && arrays.iter().any(|a| a == NPZ_FOCAL_ARRAY) {
        let member = archive
            .by_name(&format!("{NPZ_FOCAL_ARRAY}.npy"))
            .map_err(bad)?;
        // One value: a header and at most 8 bytes.
        let mut npy = Vec::new();
        member
            .take(NPY_PREAMBLE + MAX_HEADER as u64 + 8)
            .read_to_end(&mut npy)
            .map_err(|e| Error::io(path, e))?;
        Some(parse_focal(&npy, path).map_err(|e| within(NPZ_FOCAL_ARRAY, e))?)
    } else {
        None
    };
    Ok(NpzDepth { samples, focal_px })
}

/// `e`, a format error of the archive's array `name`, saying which.
fn within(name: &str, e: Error) -> Error {
    match e {
        Error::Format { path, detail } => Error::format(path, format!("array '{name}': {detail}")),
        other => other,
    }
}

/// A focal length in pixels: one finite positive float, of any shape holding one value.
fn parse_focal(bytes: &[u8], path: &Path) -> Result<f64> {
    let shape = plain_shape(bytes, path)?.unwrap_or_default();
    if shape.len() > 2 || shape.iter().any(|&d| d != 1) {
        return Err(Error::format(
            path,
            format!(
                "shape {shape:?}; expected one focal length in pixels (leave it out of the \
                 archive, or give `focal`)"
            ),
        ));
    }
    let npy = npyz::NpyFile::new(bytes)
        .map_err(|e| Error::format(path, format!("not a valid .npy array: {e}")))?;
    let value = match npy.try_data::<f32>() {
        Ok(values) => values
            .map(|v| v.map(f64::from))
            .collect::<std::io::Result<Vec<_>>>(),
        Err(npy) => match npy.try_data::<f64>() {
            Ok(values) => values.collect::<std::io::Result<Vec<_>>>(),
            Err(npy) => {
                return Err(Error::format(
                    path,
                    format!(
                        "dtype is {}; expected a float focal length in pixels",
                        npy.dtype().descr()
                    ),
                ))
            }
        },
    };
    match value.ok().as_deref() {
        Some(&[f]) if f.is_finite() && f > 0.0 => Ok(f),
        Some(&[f]) => Err(Error::format(
            path,
            format!("{f}; expected a finite focal length > 0 in pixels (or give `focal`)"),
        )),
        _ => Err(Error::format(
            path,
            "cannot read its value; the archive may be truncated",
        )),
    }
}

/// The bytes of an archive member, no more than the array its header describes needs: a
/// small deflated member may claim, or inflate to, far more than that.
fn read_member(member: impl Read, path: &Path, name: &str) -> Result<Vec<u8>> {
    let inflate = |e: std::io::Error| {
        Error::format(
            path,
            format!("cannot inflate array '{name}' of the .npz: {e}"),
        )
    };
    let mut member = member;
    let mut npy = Vec::new();
    (&mut member)
        .take(NPY_PREAMBLE + MAX_HEADER as u64)
        .read_to_end(&mut npy)
        .map_err(inflate)?;
    if let Some((len, (w, h))) = npy_extent(&npy, path)? {
        // Before the member is inflated: a compressed member of one repeated value is a
        // few hundred kilobytes for gigabytes of array.
        let member_name = format!("{} (its array '{name}')", path.display());
        let _reserved = check_map_decoding_fits(&member_name, w, h, len as u64)?;
        let rest = (len as u64).saturating_sub(npy.len() as u64);
        member.take(rest).read_to_end(&mut npy).map_err(inflate)?;
        npy.truncate(len);
    }
    Ok(npy)
}

/// The length of a whole `.npy` file from its first bytes (header and the data its shape
/// and dtype need) and its grid's size, once its header is known to be plain; `None` for
/// a dtype without a fixed size, which `parse_npy` then names.
fn npy_extent(head: &[u8], path: &Path) -> Result<Option<(usize, (usize, usize))>> {
    check_header(head, path)?;
    let mut data = head;
    let header = npyz::NpyHeader::from_reader(&mut data)
        .map_err(|e| Error::format(path, format!("not a valid .npy array: {e}")))?;
    let header_len = head.len() - data.len();
    let npy = npyz::NpyFile::with_header(header, data);
    let (w, h) = grid_size(npy.shape(), path)?;
    Ok(npy
        .dtype()
        .num_bytes()
        .map(|item| (header_len + w * h * item, (w, h))))
}

/// Bytes before a `.npy` header's text: magic, version and length (4 bytes from version 2).
const NPY_PREAMBLE: u64 = 12;

/// Longest .npy header text accepted: numpy's own `max_header_size` default, for the
/// same reason (parsing a long Python literal is slow).
const MAX_HEADER: usize = 10_000;

/// Checks a header before `npyz` sees it. `npyz` allocates the header's stated length
/// before reading it, multiplies the shape's dimensions without checking for overflow (a
/// debug build panics, a release build wraps to a small count), and parses the header with
/// a Python-literal parser that takes exponential time on nested or unclosed brackets (16
/// `{` took longer than the fuzzer's 10 s). So the header must be the plain dictionary
/// numpy writes for an array, read here in linear time, and its shape within `io::limits`.
fn check_header(bytes: &[u8], path: &Path) -> Result<()> {
    let Some(shape) = plain_shape(bytes, path)? else {
        return Ok(()); // npyz names what is wrong
    };
    // Any other shape is refused here too: npyz would multiply its dimensions first.
    match shape[..] {
        [h, w] | [h, w, 1] => check_size(path, "NPY", w, h),
        _ => Err(Error::format(
            path,
            format!("array shape is {shape:?}; expected (height, width)"),
        )),
    }
}

/// The shape of a plain `.npy` header ([`check_header`]), read in linear time; `None` for
/// bytes that do not start as one.
fn plain_shape(bytes: &[u8], path: &Path) -> Result<Option<Vec<u64>>> {
    if !bytes.starts_with(b"\x93NUMPY") || bytes.len() < 8 {
        return Ok(None);
    }
    // Version 1 gives the header length in 2 bytes, later versions in 4.
    let (text_at, len): (usize, _) = match bytes[6] {
        1 => (
            10,
            bytes
                .get(8..10)
                .map(|b| usize::from(u16::from_le_bytes([b[0], b[1]]))),
        ),
        _ => (
            12,
            bytes
                .get(8..12)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize),
        ),
    };
    let Some(len) = len else {
        return Ok(None);
    };
    if len > MAX_HEADER {
        return Err(Error::format(
            path,
            format!(
                ".npy header claims {len} bytes; at most {MAX_HEADER} are accepted, as by numpy"
            ),
        ));
    }
    let Some(text) = bytes.get(text_at..text_at + len) else {
        return Err(Error::format(
            path,
            format!(
                ".npy header claims {len} bytes but the file has {} after its preamble; it is truncated",
                bytes.len().saturating_sub(text_at)
            ),
        ));
    };
    let shape = PlainHeader { text, pos: 0 }.shape().ok_or_else(|| {
        Error::format(
            path,
            format!(
                ".npy header `{}` is not the dictionary numpy writes for a plain array; expected \
                 {{'descr': '<f4', 'fortran_order': False, 'shape': (height, width), }}",
                String::from_utf8_lossy(&text[..text.len().min(120)]).trim_end()
            ),
        )
    })?;
    Ok(Some(shape))
}

/// A linear-time reader of the header numpy writes for a plain (not structured) dtype: a
/// dictionary of quoted keys whose values are quoted strings, `True`, `False`, or tuples or
/// lists of integers. Anything else is refused before the slow Python-literal parser sees
/// it; a plain float array never needs more.
struct PlainHeader<'a> {
    text: &'a [u8],
    pos: usize,
}

impl<'a> PlainHeader<'a> {
    /// The last `shape` entry (the one npyz keeps), if the whole header is plain.
    fn shape(mut self) -> Option<Vec<u64>> {
        let mut shape = None;
        self.expect(b'{')?;
        loop {
            if self.eat(b'}') {
                break;
            }
            let key = self.string()?;
            self.expect(b':')?;
            if key == b"shape" {
                shape = Some(self.integers()?);
            } else {
                self.scalar()?;
            }
            if !self.eat(b',') {
                self.expect(b'}')?;
                break;
            }
        }
        self.skip_space();
        (self.pos == self.text.len()).then_some(shape).flatten()
    }

    fn skip_space(&mut self) {
        while self.text.get(self.pos).is_some_and(u8::is_ascii_whitespace) {
            self.pos += 1;
        }
    }

    fn eat(&mut self, c: u8) -> bool {
        self.skip_space();
        let found = self.text.get(self.pos) == Some(&c);
        self.pos += usize::from(found);
        found
    }

    fn expect(&mut self, c: u8) -> Option<()> {
        self.eat(c).then_some(())
    }

    /// A quoted string without escapes.
    fn string(&mut self) -> Option<&'a [u8]> {
        self.skip_space();
        let quote = *self
            .text
            .get(self.pos)
            .filter(|&&q| q == b'\'' || q == b'"')?;
        let start = self.pos + 1;
        let text = self.text;
        let len = text[start..]
            .iter()
            .position(|&c| c == quote || c == b'\\')?;
        if text[start + len] != quote {
            return None;
        }
        self.pos = start + len + 1;
        Some(&text[start..start + len])
    }

    /// A quoted string, `True` or `False`.
    fn scalar(&mut self) -> Option<()> {
        self.skip_space();
        for word in [&b"True"[..], b"False"] {
            if self.text[self.pos..].starts_with(word) {
                self.pos += word.len();
                return Some(());
            }
        }
        self.string().map(|_| ())
    }

    /// `(a, b, ...)` or `[a, b, ...]` of non-negative integers, trailing comma allowed.
    fn integers(&mut self) -> Option<Vec<u64>> {
        let close = if self.eat(b'(') {
            b')'
        } else {
            self.expect(b'[')?;
            b']'
        };
        let mut v = Vec::new();
        loop {
            if self.eat(close) {
                return Some(v);
            }
            self.skip_space();
            let digits = self.text[self.pos..]
                .iter()
                .take_while(|c| c.is_ascii_digit())
                .count();
            // More than 20 digits cannot be a u64; refused without parsing them.
            if digits == 0 || digits > 20 {
                return None;
            }
            let n = std::str::from_utf8(&self.text[self.pos..self.pos + digits])
                .ok()?
                .parse()
                .ok()?;
            v.push(n);
            self.pos += digits;
            if !self.eat(b',') {
                self.expect(close)?;
                return Some(v);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn npy(descr: &str, fortran: bool, shape: &str, data: &[u8]) -> Vec<u8> {
        let order = if fortran { "True" } else { "False" };
        let header =
            format!("{{'descr': '{descr}', 'fortran_order': {order}, 'shape': {shape}, }}\n");
        let mut b = b"\x93NUMPY\x01\x00".to_vec();
        b.extend_from_slice(&(header.len() as u16).to_le_bytes());
        b.extend_from_slice(header.as_bytes());
        b.extend_from_slice(data);
        b
    }

    #[test]
    fn an_archive_member_is_read_no_further_than_its_array() {
        let array = npy("<f4", false, "(2, 3)", &[0; 24]);
        // A deflated member may inflate to far more than its header's array: what follows
        // must stay unread, or a few kB of zip would fill the memory.
        let flood = std::io::repeat(0x55).take(64 << 20);
        let path = Path::new("bomb.npz");
        assert_eq!(read_member(&array[..], path, "depth").unwrap(), array);
        let mut member = array.chain(flood);
        assert_eq!(read_member(&mut member, path, "depth").unwrap(), array);
        let unread = member.into_inner().1.limit();
        assert!(
            unread > (64 << 20) - 2 * MAX_HEADER as u64,
            "{unread} bytes left"
        );
    }

    #[test]
    fn uint16_arrays_keep_their_values_in_either_order() {
        let path = Path::new("u.npy");
        let uint16 = |fortran, values: [u16; 6]| {
            let data: Vec<u8> = values.iter().flat_map(|v| v.to_be_bytes()).collect();
            match parse_npy(&npy(">u2", fortran, "(2, 3)", &data), path) {
                Ok(MapSamples::Uint16(grid)) => grid,
                _ => panic!("not read as uint16"),
            }
        };
        // Rows [1 2 3] and [4 5 65535], stored by rows and by columns.
        let rows = uint16(false, [1, 2, 3, 4, 5, 65535]);
        let columns = uint16(true, [1, 4, 2, 5, 3, 65535]);
        for g in [rows, columns] {
            assert_eq!((g.get(2, 0), g.get(0, 1), g.get(2, 1)), (&3, &4, &65535));
        }
        // A float map's reader (an inserted object's distance) refuses them, saying so.
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("u.npy");
        std::fs::write(&file, npy("<u2", false, "(1, 1)", &[0, 1])).unwrap();
        let message = read_npy_scalar(&file).unwrap_err().to_string();
        assert!(
            message.ends_with(
                "u.npy: an array of dtype uint16; expected float16, float32 or float64 here \
                 (a float map)"
            ),
            "{message}"
        );
    }
}
