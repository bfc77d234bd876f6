//! Hostile headers: every reader refuses a size beyond `io::limits` before allocating for
//! it, with an error naming the file, the size claimed and the limit, instead of aborting
//! on a failed allocation or panicking on a size that wrapped around.

use std::path::{Path, PathBuf};

use brume::io::depth::{load_range, DepthFormat, DepthOptions};
use brume::io::image::load_linear_rgb;
use brume::io::limits::{MAX_PIXELS, MAX_SIDE};
use brume::Error;

use crate::common;

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// Asserts a format error that names the file, the claimed size and `limit`.
fn expect_limit_error(r: brume::Result<impl Sized>, file: &str, size: &str, limit: usize) {
    let err = match r {
        Ok(_) => panic!("{file}: expected an error for a {size} image"),
        Err(e) => e,
    };
    let msg = err.to_string();
    assert!(
        matches!(err, Error::Format { .. }),
        "not a Format error: {msg}"
    );
    for needle in [file, size, &limit.to_string()] {
        assert!(msg.contains(needle), "`{msg}` should mention `{needle}`");
    }
}

fn float_opts() -> DepthOptions {
    DepthOptions {
        format: DepthFormat::Float,
        ..DepthOptions::default()
    }
}

/// A 1x1 uncompressed one-channel EXR whose data window is then rewritten to claim
/// `w` x `h` pixels: a few hundred bytes, like a hostile file.
fn exr_claiming(w: i32, h: i32) -> Vec<u8> {
    // Uncompressed scan lines come one per chunk.
    exr_of_claiming(&["Z"], exr::prelude::Encoding::UNCOMPRESSED, w, h, h)
}

/// A 1x1 EXR of float `channels` whose data window is then rewritten to claim `w` x `h`
/// pixels in `chunks` chunks.
fn exr_of_claiming(
    channels: &[&str],
    encoding: exr::prelude::Encoding,
    w: i32,
    h: i32,
    chunks: i32,
) -> Vec<u8> {
    use exr::prelude::*;
    let mut bytes = Vec::new();
    let channels = channels
        .iter()
        .map(|&name| AnyChannel::new(name, FlatSamples::F32(vec![1.0])))
        .collect();
    let layer = Layer::new(
        (1, 1),
        LayerAttributes::default(),
        encoding,
        AnyChannels::sort(channels),
    );
    Image::from_layer(layer)
        .write()
        .to_buffered(std::io::Cursor::new(&mut bytes))
        .unwrap();
    for name in [&b"dataWindow\0box2i\0"[..], &b"displayWindow\0box2i\0"[..]] {
        let at = bytes
            .windows(name.len())
            .position(|win| win == name)
            .expect("the writer names its windows")
            + name.len()
            + 4; // attribute size
        let bounds = [0, 0, w - 1, h - 1];
        for (i, v) in bounds.iter().enumerate() {
            bytes[at + 4 * i..at + 4 * i + 4].copy_from_slice(&v.to_le_bytes());
        }
    }
    // A consistent count gets the header past the decoder's own checks.
    let name = b"chunkCount\0int\0";
    if let Some(at) = bytes.windows(name.len()).position(|win| win == name) {
        let at = at + name.len() + 4;
        bytes[at..at + 4].copy_from_slice(&chunks.to_le_bytes());
    }
    bytes
}

#[test]
fn exr_claiming_blocks_larger_than_a_gigabyte_is_refused_before_decoding() {
    use exr::prelude::{Blocks, Compression, Encoding, LineOrder};
    let encoding = Encoding {
        compression: Compression::DWAB(None),
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let names: Vec<String> = (0..65).map(|i| format!("c{i:02}")).collect();
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    // One DWAB block of 256 rows of 16384 pixels of 65 floats: 1 090 519 040 bytes, just
    // over the limit; a legal size in pixels, and a file of a few kilobytes.
    let bytes = exr_of_claiming(&names, encoding, 16384, 256, 1);
    assert!(bytes.len() < 4000, "{} bytes", bytes.len());
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "wide.exr", &bytes);
    let err = load_range(&p, &float_opts()).map(|_| ()).unwrap_err();
    let needle = "EXR blocks of 16384x256 pixels of 65 channels (260 bytes a pixel, dwab \
                  compression) decode to 1090519040 bytes each, more than the 1073741824";
    assert!(err.to_string().contains(needle), "`{err}`");
    // One channel fewer fits, and gets as far as the missing pixel data.
    let bytes = exr_of_claiming(&names[1..], encoding, 16384, 256, 1);
    let p = write(dir.path(), "fits.exr", &bytes);
    let err = load_range(&p, &float_opts()).map(|_| ()).unwrap_err();
    assert!(!err.to_string().contains("EXR blocks of"), "`{err}`");
}

#[test]
fn exr_header_claiming_100000_squared_is_refused_before_decoding() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = exr_claiming(100_000, 100_000);
    assert!(bytes.len() < 1000, "{} bytes", bytes.len());
    let p = write(dir.path(), "huge.exr", &bytes);
    expect_limit_error(
        load_range(&p, &float_opts()),
        "huge.exr",
        "100000x100000",
        MAX_SIDE,
    );
    // Within the side limit but beyond the pixel count.
    let p = write(dir.path(), "many.exr", &exr_claiming(16384, 16384));
    expect_limit_error(
        load_range(&p, &float_opts()),
        "many.exr",
        "16384x16384",
        MAX_PIXELS,
    );
    // A plausible size the file is far too short for.
    let p = write(dir.path(), "short.exr", &exr_claiming(8000, 8000));
    let msg = load_range(&p, &float_opts()).unwrap_err().to_string();
    assert!(msg.contains("short.exr"), "{msg}");
}

#[test]
fn colour_exr_and_pfm_headers_beyond_the_limit_are_refused_before_decoding() {
    // Every part's header is checked before the channels are even looked at.
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "huge.exr", &exr_claiming(100_000, 100_000));
    expect_limit_error(load_linear_rgb(&p), "huge.exr", "100000x100000", MAX_SIDE);
    let p = write(dir.path(), "many.exr", &exr_claiming(16384, 16384));
    expect_limit_error(load_linear_rgb(&p), "many.exr", "16384x16384", MAX_PIXELS);
    let msg = load_linear_rgb(&write(dir.path(), "short.exr", &exr_claiming(8000, 8000)))
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("short.exr") && msg.contains("truncated"),
        "{msg}"
    );
    let p = write(dir.path(), "many.pfm", b"PF\n16384 16384\n-1\n");
    expect_limit_error(load_linear_rgb(&p), "many.pfm", "16384x16384", MAX_PIXELS);
}

#[test]
fn npy_shape_whose_product_wraps_is_refused_in_either_order() {
    let dir = tempfile::tempdir().unwrap();
    for fortran in [false, true] {
        let p = write(
            dir.path(),
            "wrap.npy",
            &common::npy_bytes("<f4", "(4294967296, 4294967296)", fortran, &[0; 8]),
        );
        expect_limit_error(
            load_range(&p, &float_opts()),
            "wrap.npy",
            "4294967296x4294967296",
            MAX_SIDE,
        );
    }
    let p = write(
        dir.path(),
        "wide.npy",
        &common::npy_bytes("<f4", "(1, 20000)", false, &[0; 8]),
    );
    expect_limit_error(
        load_range(&p, &float_opts()),
        "wide.npy",
        "20000x1",
        MAX_SIDE,
    );
}

#[test]
fn pfm_header_beyond_the_limit_is_refused_before_its_data_is_checked() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "wide.pfm", b"Pf\n20000 1\n-1\n\0\0\0\0");
    expect_limit_error(
        load_range(&p, &float_opts()),
        "wide.pfm",
        "20000x1",
        MAX_SIDE,
    );
    let p = write(dir.path(), "many.pfm", b"PF\n16384 16384\n-1\n");
    expect_limit_error(
        brume::io::depth::read_pfm(&p),
        "many.pfm",
        "16384x16384",
        MAX_PIXELS,
    );
}

#[test]
fn tiff_beyond_the_limit_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("wide.tif");
    let mut enc = tiff::encoder::TiffEncoder::new(std::fs::File::create(&p).unwrap()).unwrap();
    enc.write_image::<tiff::encoder::colortype::Gray32Float>(20000, 1, &vec![1.0; 20000])
        .unwrap();
    expect_limit_error(
        load_range(&p, &float_opts()),
        "wide.tif",
        "20000x1",
        MAX_SIDE,
    );
}

#[test]
fn png_depth_and_colour_beyond_the_limit_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("wide.png");
    image::save_buffer(&p, &vec![1; 20000], 20000, 1, image::ExtendedColorType::L8).unwrap();
    expect_limit_error(
        load_range(&p, &DepthOptions::default()),
        "wide.png",
        "20000x1",
        MAX_SIDE,
    );
    let p = dir.path().join("tall.png");
    image::save_buffer(
        &p,
        &vec![1; 3 * 20000],
        1,
        20000,
        image::ExtendedColorType::Rgb8,
    )
    .unwrap();
    expect_limit_error(load_linear_rgb(&p), "tall.png", "1x20000", MAX_SIDE);
}

#[test]
fn images_at_the_side_limit_still_load() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "edge.pfm",
        &[&b"Pf\n16384 1\n-1\n"[..], &vec![0; 4 * 16384]].concat(),
    );
    let mut bytes = std::fs::read(&p).unwrap();
    bytes[15..19].copy_from_slice(&2.0f32.to_le_bytes());
    std::fs::write(&p, bytes).unwrap();
    let d = load_range(&p, &float_opts()).unwrap();
    assert_eq!((d.range.width(), d.range.height()), (MAX_SIDE, 1));
}

// A file far larger than any image brume takes was read whole (40 GB asked of the
// allocator: "out of memory", or the OOM killer), and a stream that never ends
// (`--image /dev/zero`) was read until memory ran out. A regular file is now refused from
// its size, before anything is read; a stream is read only as far as the limit (the
// unit test in `io::limits` covers that with a small limit).
#[test]
fn an_input_larger_than_any_image_is_refused_from_its_size() {
    let dir = tempfile::tempdir().unwrap();
    let depth = dir.path().join("d.png");
    // Sparse: no disk space and no read needed.
    let huge = brume::io::limits::MAX_FILE_BYTES + 1;
    std::fs::File::create(&depth)
        .unwrap()
        .set_len(huge)
        .unwrap();
    let err = brume::io::limits::read_file(&depth)
        .unwrap_err()
        .to_string();
    assert!(err.contains(&format!("({huge} bytes)")), "{err}");

    let limit = brume::io::limits::MAX_FILE_BYTES.to_string();
    let needles = ["d.png", "larger than any input brume takes", &limit];
    common::assert_render_refuses("--depth", &depth, &needles);
}

/// A float64 TIFF over the `tiff` crate's default decoding limit (256 MiB) is read: that
/// limit refused an 8000x6000 float map stored as one strip, as PIL writes it, with "cannot
/// read as TIFF: decoder limits exceeded", where `io::limits` lets 8192x8192 through.
#[test]
fn a_float_tiff_over_the_decoders_default_limit_is_read() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/big/flat-5800x5800-f64.tif");
    let opts = DepthOptions {
        kind: Some(brume::io::depth::DepthKind::Range),
        ..DepthOptions::default()
    };
    let range = load_range(&path, &opts).unwrap().range;
    assert_eq!((range.width(), range.height()), (5800, 5800));
    for (x, y) in [(0, 0), (2900, 2900), (5799, 5799), (5799, 0)] {
        assert_eq!(*range.get(x, y), 10.0, "pixel ({x}, {y})");
    }
}
