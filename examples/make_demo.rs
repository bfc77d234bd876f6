//! Regenerates the built-in demo scene in `assets/demo/` from the full-size Middlebury
//! 2006 Aloe sample:
//!
//! ```text
//! cargo run --example make_demo -- [SOURCE_DIR] [OUT_DIR]
//! ```
//!
//! `SOURCE_DIR` defaults to `tests/data/aloe` and `OUT_DIR` to `assets/demo`, both
//! relative to the crate root. Both outputs are half size (1282x1110 -> 641x555):
//!
//! - `aloe-left-half.jpg`: each 2x2 block averaged in linear light, re-encoded as sRGB
//!   JPEG at quality 90.
//! - `aloe-disparity-half.png`: 8-bit, the median of the KNOWN (non-zero) disparities of
//!   each 2x2 block, 0 if none. For an even count the lower middle value is taken, so every
//!   output is a disparity that was measured: no invented in-between depth at object
//!   edges. Values stay in FULL-SIZE disparity units (not halved), so the Middlebury 2006
//!   defaults of `brume::io::depth` (focal, baseline, offset) still give the right depth.

use std::path::{Path, PathBuf};

use brume::io::image::{linear_to_srgb, load_linear_rgb};
use brume::raster::Grid;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut args = std::env::args_os().skip(1).map(PathBuf::from);
    let source = args.next().unwrap_or_else(|| root.join("tests/data/aloe"));
    let out = args.next().unwrap_or_else(|| root.join("assets/demo"));
    std::fs::create_dir_all(&out)?;

    let colour = half_colour(&load_linear_rgb(&source.join("left.jpg"))?);
    let jpg = out.join("aloe-left-half.jpg");
    let file = std::io::BufWriter::new(std::fs::File::create(&jpg)?);
    image::codecs::jpeg::JpegEncoder::new_with_quality(file, 90).encode(
        &colour.data,
        colour.width,
        colour.height,
        image::ExtendedColorType::Rgb8,
    )?;

    let disparity = image::open(source.join("disparity.png"))?.to_luma8();
    let full = Grid::from_vec(
        disparity.width() as usize,
        disparity.height() as usize,
        disparity.into_raw(),
    );
    let half = half_disparity(&full);
    let png = out.join("aloe-disparity-half.png");
    image::save_buffer(
        &png,
        half.as_slice(),
        half.width() as u32,
        half.height() as u32,
        image::ExtendedColorType::L8,
    )?;
    for p in [&jpg, &png] {
        println!("{} ({} bytes)", p.display(), std::fs::metadata(p)?.len());
    }
    Ok(())
}

struct Rgb8 {
    width: u32,
    height: u32,
    data: Vec<u8>,
}

/// Averages 2x2 blocks in linear light (averaging sRGB codes would darken edges).
fn half_colour(img: &Grid<[f32; 3]>) -> Rgb8 {
    let (w, h) = (img.width() / 2, img.height() / 2);
    let mut data = Vec::with_capacity(w * h * 3);
    for y in 0..h {
        for x in 0..w {
            for c in 0..3 {
                let sum: f32 = [(0, 0), (1, 0), (0, 1), (1, 1)]
                    .iter()
                    .map(|&(dx, dy)| img.get(2 * x + dx, 2 * y + dy)[c])
                    .sum();
                let srgb = linear_to_srgb((sum / 4.0).clamp(0.0, 1.0));
                data.push((srgb * 255.0).round() as u8);
            }
        }
    }
    Rgb8 {
        width: w as u32,
        height: h as u32,
        data,
    }
}

/// Lower median of the known values of each 2x2 block; 0 where all four are unknown.
fn half_disparity(full: &Grid<u8>) -> Grid<u8> {
    Grid::from_fn(full.width() / 2, full.height() / 2, |x, y| {
        let mut known: Vec<u8> = [(0, 0), (1, 0), (0, 1), (1, 1)]
            .iter()
            .map(|&(dx, dy)| *full.get(2 * x + dx, 2 * y + dy))
            .filter(|&d| d != 0)
            .collect();
        known.sort_unstable();
        match known.len() {
            0 => 0,
            n => known[(n - 1) / 2],
        }
    })
}
