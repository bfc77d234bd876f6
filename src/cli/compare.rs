//! `brume compare A B`: how alike two images are (SSIM and HSV-histogram correlation, as
//! paper 002 compares a render with a photograph).

use super::args::CompareArgs;
use brume::metrics::compare_files;
use brume::Result;
use serde_json::json;

pub fn run(args: &CompareArgs) -> Result<()> {
    let (s, (width, height)) = compare_files(&args.a, &args.b)?;
    let (a_name, b_name) = (args.a.display().to_string(), args.b.display().to_string());
    if args.json {
        outln!(
            "{}",
            super::stamped(json!({
                "a": a_name,
                "b": b_name,
                "width": width,
                "height": height,
                "ssim": s.ssim,
                "ssim_rgb": s.ssim_rgb,
                "hsv_correlation": s.hsv_correlation,
                "hsv_correlation_hsv": s.hsv_correlation_hsv,
            }))
        );
    } else {
        outln!(
            "SSIM {:.4} (R {:.4}, G {:.4}, B {:.4}); HSV histogram correlation {:.4} \
             (H {:.4}, S {:.4}, V {:.4})",
            s.ssim,
            s.ssim_rgb[0],
            s.ssim_rgb[1],
            s.ssim_rgb[2],
            s.hsv_correlation,
            s.hsv_correlation_hsv[0],
            s.hsv_correlation_hsv[1],
            s.hsv_correlation_hsv[2]
        );
    }
    Ok(())
}
