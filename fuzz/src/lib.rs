//! What the fuzz targets share: how the first bytes of an input choose the depth loader's
//! options, so that one input exercises one combination of dataset rule, kind and knobs
//! and the fuzzer can explore them all. `examples/fuzz_seeds.rs` in the main crate writes
//! seeds in this framing.

use std::path::Path;

use brume::io::depth::{load_range_from_bytes, DepthFormat, DepthKind, DepthOptions};

/// Bytes of options at the front of a `depth_png` or `load_range` input.
pub const OPTION_BYTES: usize = 2;

const KINDS: [Option<DepthKind>; 4] = [
    None,
    Some(DepthKind::Depth),
    Some(DepthKind::Range),
    Some(DepthKind::Disparity),
];
// Each knob takes a usual value, another plausible one, and values the option checks must
// refuse.
const SCALES: [f64; 4] = [1.0 / 256.0, 1e-3, 0.0, -1.0];
const FOCALS: [f64; 4] = [500.0, 3740.0, 0.0, f64::NAN];
const BASELINES: [f64; 4] = [160.0, 1.0, -5.0, f64::INFINITY];
const OFFSETS: [f64; 2] = [270.0, -1000.0];

/// Options from two bytes. `a`: bits 0-2 the format, 3-4 the kind, 5, 6, 7 whether scale,
/// focal and baseline are given. `b`: bit 0 whether a disparity offset is given, bits 1-2
/// the scale, 3-4 the focal, 5-6 the baseline, 7 the offset.
pub fn options(a: u8, b: u8) -> DepthOptions {
    let pick = |on: bool, v: f64| on.then_some(v);
    DepthOptions {
        format: DepthFormat::ALL[usize::from(a & 7)],
        kind: KINDS[usize::from((a >> 3) & 3)],
        calib: None,
        scale: pick(a & 0x20 != 0, SCALES[usize::from((b >> 1) & 3)]),
        focal: pick(a & 0x40 != 0, FOCALS[usize::from((b >> 3) & 3)]),
        baseline: pick(a & 0x80 != 0, BASELINES[usize::from((b >> 5) & 3)]),
        disparity_offset: pick(b & 1 != 0, OFFSETS[usize::from(b >> 7)]),
        ..DepthOptions::default()
    }
}

/// Extensions a `load_range` input may claim, chosen by the low 3 bits of its first byte.
pub const EXTENSIONS: [&str; 8] = ["png", "pfm", "exr", "tif", "tiff", "npy", "jpg", "npz"];

/// Runs the depth loader on a `load_range` input: byte 0 picks the extension (bits 0-2)
/// and whether a calib.txt follows (bit 3); bytes 1-2 are [`options`]; then, with a
/// calib, its length as 2 bytes little-endian and its text; the rest is the file.
pub fn load_range_input(data: &[u8]) {
    let Some((&[head, a, b], rest)) = data.split_first_chunk::<3>() else {
        return;
    };
    let ext = EXTENSIONS[usize::from(head & 7)];
    let opts = options(a, b);
    let (calib, file) = if head & 8 != 0 {
        let Some((len, rest)) = rest.split_first_chunk::<2>() else {
            return;
        };
        let len = usize::from(u16::from_le_bytes(*len)).min(rest.len());
        let (text, file) = rest.split_at(len);
        // A calib.txt is read as UTF-8 text; other bytes never reach its parser.
        let Ok(text) = std::str::from_utf8(text) else {
            return;
        };
        (Some(text), file)
    } else {
        (None, rest)
    };
    let name = format!("scene/d.{ext}");
    let calib_path = Path::new("scene/calib.txt");
    let _ = load_range_from_bytes(
        file,
        Path::new(&name),
        &opts,
        calib.map(|t| (calib_path, t)),
    );
}

/// Runs the depth loader on `file` as if read from a file with extension `ext`, with
/// default options (every format guessed).
pub fn load_as(file: &[u8], ext: &str) {
    let name = format!("d.{ext}");
    let _ = load_range_from_bytes(file, Path::new(&name), &DepthOptions::default(), None);
}
