//! A stand-in for `brume bench` until the CLI lands: the same arguments and the same
//! [`brume::bench::run`], with the Aloe photograph of `/work/shared/data` (or
//! `$BRUME_DEMO_IMAGE`) halved to about 640x555, like the built-in demo, as the demo image.
//!
//! ```text
//! cargo run --release --example bench -- accuracy --plot fig6.png
//! cargo run --release --example bench -- bench speed --size 400x280 --json
//! ```
//!
//! A leading `bench` is accepted so that `tools/peer_compare.py --brume
//! target/release/examples/bench` can call it like the real binary.

use brume::bench::BenchCommand;
use brume::raster::{Grid, RgbImage};
use brume::{Error, Renderer, Result};
use clap::Parser;
use std::path::Path;

/// `brume bench` stand-in.
#[derive(Parser)]
struct Cli {
    #[command(subcommand)]
    bench: BenchCommand,
}

const ALOE_PATH: &str = "/work/shared/data/aloe/left.jpg";

fn main() {
    let args = std::env::args()
        .enumerate()
        .filter(|(i, a)| !(*i == 1 && a == "bench"));
    let cli = Cli::parse_from(args.map(|(_, a)| a));
    let demo = || {
        let path = std::env::var("BRUME_DEMO_IMAGE").unwrap_or_else(|_| ALOE_PATH.into());
        load_srgb(Path::new(&path)).map(|img| halve(&img))
    };
    let outcome = Renderer::new(None)
        .and_then(|mut r| brume::bench::run(&cli.bench, &mut r, &demo, &|p: &Path| load_srgb(p)));
    if let Err(e) = outcome {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

/// Decodes an 8-bit sRGB file to linear RGB (the sRGB transfer curve, IEC 61966-2-1).
fn load_srgb(path: &Path) -> Result<RgbImage> {
    let rgb = image::open(path)
        .map_err(|e| Error::format(path, e.to_string()))?
        .to_rgb8();
    let lut: Vec<f32> = (0..256).map(|v| srgb_to_linear(v as f32 / 255.0)).collect();
    let (w, h) = (rgb.width() as usize, rgb.height() as usize);
    Ok(Grid::from_fn(w, h, |x, y| {
        let p = rgb.get_pixel(x as u32, y as u32).0;
        [lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]]
    }))
}

fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// 2x2 box average in linear light (the demo image is the photograph at half size).
fn halve(img: &RgbImage) -> RgbImage {
    let (w, h) = (img.width() / 2, img.height() / 2);
    Grid::from_fn(w, h, |x, y| {
        let px = |dx, dy| img.get(2 * x + dx, 2 * y + dy);
        std::array::from_fn(|c| 0.25 * (px(0, 0)[c] + px(1, 0)[c] + px(0, 1)[c] + px(1, 1)[c]))
    })
}
