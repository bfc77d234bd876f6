//! The built-in demo scene, so that brume can show something without any input file: the
//! Middlebury 2006 Aloe pair at half size (641x555), embedded in the binary and decoded
//! by the same code as files. `examples/make_demo.rs` regenerates the assets.

use std::path::Path;

use crate::io::depth::{range_from_bytes, DepthFormat, DepthOptions, LoadedDepth};
use crate::io::image::decode_linear_rgb;
use crate::raster::RgbImage;
use crate::Result;

/// Credit line for the demo scene.
pub const DEMO_SOURCE: &str = "Aloe, Middlebury 2006 stereo datasets (Scharstein and Pal, CVPR 2007), as shipped in Debian's opencv-doc; downsampled by 2";

const IMAGE_NAME: &str = "<built-in demo>/aloe-left-half.jpg";
const DISPARITY_NAME: &str = "<built-in demo>/aloe-disparity-half.png";
const IMAGE_BYTES: &[u8] = include_bytes!("../../assets/demo/aloe-left-half.jpg");
const DISPARITY_BYTES: &[u8] = include_bytes!("../../assets/demo/aloe-disparity-half.png");

/// The demo's pixels were 2x2 blocks of the full-size pair.
const DOWNSAMPLING: f64 = 2.0;

/// The demo colour image, in linear light.
pub fn demo_image() -> Result<RgbImage> {
    decode_linear_rgb(IMAGE_BYTES, IMAGE_NAME)
}

/// Disparity offset of the demo: 0, not the dataset's ≈270 px.
///
/// With the real offset the whole plant lies between 1.24 and 1.96 m: normalised range
/// spans only [0.63, 1], haze is nearly uniform and the near leaves blur almost as much as
/// the cloth. With offset 0 the range is ∝ 1/d and spans [0.2, 1] (a scene about five
/// times deeper), which shows what the model does with depth. Real data should use its
/// real offset (`DepthOptions::disparity_offset`).
pub const DEMO_DISPARITY_OFFSET_PX: f64 = 0.0;

/// The demo range map (NaN where the disparity is unknown), read as a Middlebury 2006
/// disparity with the default focal and baseline and [`DEMO_DISPARITY_OFFSET_PX`]. Its
/// disparities are in full-size units, so depth uses the full-size focal; the ray
/// directions use half that focal because each demo pixel spans two full-size pixels.
pub fn demo_range() -> Result<LoadedDepth> {
    let opts = DepthOptions {
        format: DepthFormat::Middlebury2006,
        disparity_offset: Some(DEMO_DISPARITY_OFFSET_PX),
        ..DepthOptions::default()
    };
    let mut loaded = range_from_bytes(
        DISPARITY_BYTES,
        Path::new(DISPARITY_NAME),
        "png",
        &opts,
        DOWNSAMPLING,
    )?;
    loaded
        .notes
        .push("demo is half size: disparities in full-size units, ray focal halved".to_string());
    loaded.notes.push(
        "demo uses disparity offset 0 to stretch the depth range (see DEMO_DISPARITY_OFFSET_PX)"
            .to_string(),
    );
    Ok(loaded)
}
