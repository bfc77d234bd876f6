//! EXR blocks as brume assembles them (`io::codec::exr::decode_pixels`): DWAA and DWAB
//! (lossy DCT for colour channels, lossless for the others) as OpenEXR's own library writes
//! them (`tools/dwa_reference.py`), read as OpenEXR reads them; DWA blocks whose headers
//! claim more than their pixels, refused before exr's DWA decoder allocates what they
//! claim; and tiles, partial at the edges, with mip levels that must not be read.

use std::path::{Path, PathBuf};

use brume::io::depth::{load_range, DepthOptions};
use brume::io::image::decode_linear_rgb;

const FILES: [&str; 2] = ["aloe-dwaa.exr", "aloe-dwab.exr"];
const SIZE: (usize, usize) = (70, 45);

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/exr")
        .join(name)
}

/// A raw little-endian float32 file of `tools/dwa_reference.py`.
fn floats(name: &str) -> Vec<f32> {
    let bytes = std::fs::read(data(name)).unwrap();
    let values = bytes.chunks_exact(4);
    values
        .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
        .collect()
}

#[test]
fn dwa_depth_reads_as_written() {
    let written = floats("aloe.z.f32");
    assert_eq!(written.len(), SIZE.0 * SIZE.1);
    for name in FILES {
        let depth = load_range(&data(name), &DepthOptions::default()).unwrap();
        assert_eq!((depth.range.width(), depth.range.height()), SIZE);
        // Z is zlib-coded in DWA: every value comes back exactly, holes as NaN.
        for (i, (&read, &want)) in depth.range.as_slice().iter().zip(&written).enumerate() {
            let same = read.to_bits() == want.to_bits() || (read.is_nan() && want.is_nan());
            assert!(same, "{name}: pixel {i} read {read}, written {want}");
        }
        assert!(written.iter().any(|v| v.is_nan()), "the sample has holes");
    }
}

#[test]
fn dwa_colour_decodes_as_openexr_does() {
    for name in FILES {
        let bytes = std::fs::read(data(name)).unwrap();
        let image = decode_linear_rgb(&bytes, name).unwrap();
        assert_eq!((image.width(), image.height()), SIZE);
        let reference = floats(&name.replace(".exr", ".rgb.f32"));
        let read: Vec<f32> = image.as_slice().iter().flatten().copied().collect();
        // Bit for bit: exr's DWA decoder is a port of OpenEXR's, and both round the
        // inverse DCT to half floats the same way (the lossy step is the encoder's).
        let differ = read.iter().zip(&reference).filter(|(a, b)| a != b).count();
        assert_eq!(differ, 0, "{name}: {differ} values differ from OpenEXR's");
        assert_eq!(read.len(), reference.len());
    }
}

/// `name`'s bytes with the `index`th of the eleven `u64` counters that open its first DWA
/// block set to `value`.
fn with_claim(name: &str, index: usize, value: u64) -> Vec<u8> {
    use exr::block::chunk::CompressedBlock;
    let mut bytes = std::fs::read(data(name)).unwrap();
    let chunks = exr::block::read(std::io::Cursor::new(&bytes), false).unwrap();
    let first = chunks.all_chunks(false).unwrap().next().unwrap().unwrap();
    let CompressedBlock::ScanLine(block) = first.compressed_block else {
        panic!("a scan-line file");
    };
    let pixels = &block.compressed_pixels_le;
    let at = bytes
        .windows(pixels.len())
        .position(|w| w == pixels)
        .unwrap();
    bytes[at + index * 8..at + index * 8 + 8].copy_from_slice(&value.to_le_bytes());
    bytes
}

#[test]
fn dwa_blocks_claiming_more_than_their_pixels_are_refused() {
    // 70x32 pixels of R, G, B, A (half) and Z (float): 12 bytes a pixel; 9x4 blocks of
    // 8x8 in each of the 5 channels.
    let pixel_bytes = 70 * 32 * 12;
    let blocks = 9 * 4 * 5;
    let claims = [
        (1, pixel_bytes, "bytes of raw channel data"),
        (6, 2 * pixel_bytes, "bytes of run-length tokens"),
        (7, pixel_bytes, "bytes of run-length data"),
        (8, 63 * blocks, "AC coefficients"),
        (9, blocks, "DC coefficients"),
    ];
    for (index, most, what) in claims {
        let bytes = with_claim("aloe-dwaa.exr", index, most + 1);
        let err = decode_linear_rgb(&bytes, "bad.exr")
            .map(|_| ())
            .unwrap_err();
        let needle = format!("claims {} {what}, more than the {most}", most + 1);
        assert!(
            err.to_string().contains(&needle),
            "`{err}` should say `{needle}`"
        );
        assert!(err
            .to_string()
            .contains("EXR block at row 0 (70x32 pixels, dwaa"));
    }
}

/// A `w` x `h` tiled EXR (8x8 tiles, so the last column and row of tiles are partial) of
/// `channels`, each a name and its full-resolution values; with `mip`, also a mip map
/// whose smaller levels are all -1.
fn tiled_exr(w: usize, h: usize, channels: &[(&str, Vec<f32>)], mip: bool) -> Vec<u8> {
    use exr::prelude::*;
    let list = channels
        .iter()
        .map(|(name, full)| {
            let full = FlatSamples::F32(full.clone());
            let levels = if mip {
                let round = exr::math::RoundingMode::Down;
                let sizes = exr::meta::mip_map_levels(round, Vec2(w, h));
                let level = |(i, size): (usize, Vec2<usize>)| match i {
                    0 => full.clone(),
                    _ => FlatSamples::F32(vec![-1.0; size.area()]),
                };
                Levels::Mip {
                    rounding_mode: round,
                    level_data: sizes.map(level).collect(),
                }
            } else {
                Levels::Singular(full)
            };
            AnyChannel::new(*name, levels)
        })
        .collect();
    let encoding = Encoding {
        compression: Compression::PIZ,
        blocks: Blocks::Tiles(Vec2(8, 8)),
        line_order: LineOrder::Increasing,
    };
    let layer = Layer::new(
        (w, h),
        LayerAttributes::default(),
        encoding,
        AnyChannels::sort(list),
    );
    let mut bytes = Vec::new();
    let image = Image::from_layer(layer);
    let cursor = std::io::Cursor::new(&mut bytes);
    image.write().to_buffered(cursor).unwrap();
    bytes
}

#[test]
fn tiled_and_mip_mapped_exr_read_at_full_resolution() {
    let (w, h) = (37, 23);
    let ramp = |k: f32| {
        (0..w * h)
            .map(|i| k + i as f32 * 0.25)
            .collect::<Vec<f32>>()
    };
    let (r, g, b, z) = (ramp(1.0), ramp(2.0), ramp(3.0), ramp(50.0));
    for mip in [false, true] {
        let channels = [("R", r.clone()), ("G", g.clone()), ("B", b.clone())];
        let bytes = tiled_exr(w, h, &channels, mip);
        let image = decode_linear_rgb(&bytes, "tiles.exr").unwrap();
        assert_eq!((image.width(), image.height()), (w, h));
        for (i, p) in image.as_slice().iter().enumerate() {
            assert_eq!(*p, [r[i], g[i], b[i]], "mip {mip}, pixel {i}");
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("z.exr");
        std::fs::write(&path, tiled_exr(w, h, &[("Z", z.clone())], mip)).unwrap();
        let depth = load_range(&path, &DepthOptions::default()).unwrap();
        assert_eq!(depth.range.as_slice(), &z[..], "mip {mip}");
    }
}
