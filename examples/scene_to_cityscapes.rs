//! Renders brume's procedural street-less outdoor scene ([`brume::scene`]) as Cityscapes
//! frames: `leftImg8bit/{split}/{city}/{name}_leftImg8bit.png` (8-bit sRGB),
//! `disparity/…/{name}_disparity.png` (16-bit, p = 256·d + 1, 0 where there is no depth:
//! the sky, as in Cityscapes) and `camera/…/{name}_camera.json` (Cityscapes' keys), for
//! trying and timing `brume batch` on frames of Cityscapes' size and format.
//!
//! ```sh
//! cargo run --release --example scene_to_cityscapes -- OUT_ROOT [FRAMES [W H]]
//! ```
//!
//! Frame k looks along yaw 25·k degrees. Defaults: 3 frames of 2048 x 1024 (Cityscapes').

use brume::camera::Camera;
use brume::egl::GlContext;
use brume::io::image::linear_to_srgb;
use brume::scene::SceneRenderer;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

/// Cityscapes' stereo rig, roughly: baseline 0.209 m, fx from the field of view.
const BASELINE_M: f64 = 0.209313;

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("scene_to_cityscapes: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let root = PathBuf::from(
        args.first()
            .ok_or("usage: scene_to_cityscapes OUT_ROOT [FRAMES [W H]]")?,
    );
    let number = |i: usize, default: usize| -> Result<usize, Box<dyn std::error::Error>> {
        Ok(args
            .get(i)
            .map(|s| s.parse())
            .transpose()?
            .unwrap_or(default))
    };
    let frames = number(1, 3)?;
    let (width, height) = (number(2, 2048)?, number(3, 1024)?);
    let ctx = GlContext::new(None)?;
    let mut scene = SceneRenderer::new(Arc::clone(ctx.gl()))?;
    for k in 0..frames {
        let camera = Camera {
            yaw_deg: 25.0 * k as f64,
            fov_y_deg: 45.0,
            ..Camera::default()
        };
        let name = format!("brume_{k:06}_000019");
        let frame = scene.render(&camera, width, height, 0.0)?;
        let colour = frame.read_colour()?;
        let depth = frame.read_depth()?;
        let fx = (height as f64 / 2.0) / (camera.fov_y_deg.to_radians() / 2.0).tan();
        // GL rows start at the bottom, PNG rows at the top.
        let mut rgb = image::RgbImage::new(width as u32, height as u32);
        let mut disparity =
            image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::new(width as u32, height as u32);
        for y in 0..height {
            for x in 0..width {
                let gl_row = height - 1 - y;
                let c = colour.get(x, gl_row);
                rgb.put_pixel(
                    x as u32,
                    y as u32,
                    image::Rgb(
                        c.map(|v| (linear_to_srgb(v.clamp(0.0, 1.0)) * 255.0).round() as u8),
                    ),
                );
                let d = f64::from(*depth.get(x, gl_row));
                let p = if d >= 1.0 {
                    0
                } else {
                    let disparity_px = BASELINE_M * fx / camera.eye_depth(d);
                    (256.0 * disparity_px + 1.0).round().clamp(1.0, 65535.0) as u16
                };
                disparity.put_pixel(x as u32, y as u32, image::Luma([p]));
            }
        }
        let folder = |kind: &str| -> std::io::Result<PathBuf> {
            let d = root.join(kind).join("train").join("brume");
            std::fs::create_dir_all(&d)?;
            Ok(d)
        };
        rgb.save(folder("leftImg8bit")?.join(format!("{name}_leftImg8bit.png")))?;
        disparity.save(folder("disparity")?.join(format!("{name}_disparity.png")))?;
        write_camera(
            &folder("camera")?.join(format!("{name}_camera.json")),
            fx,
            width,
            height,
        )?;
        println!("{}: frame {name} ({width}x{height})", root.display());
    }
    Ok(())
}

fn write_camera(path: &Path, fx: f64, width: usize, height: usize) -> std::io::Result<()> {
    let json = serde_json::json!({
        "extrinsic": {"baseline": BASELINE_M, "pitch": 0.0, "roll": 0.0, "x": 1.7, "y": 0.0, "yaw": 0.0, "z": 1.2},
        "intrinsic": {"fx": fx, "fy": fx, "u0": width as f64 / 2.0, "v0": height as f64 / 2.0},
    });
    std::fs::write(path, format!("{json:#}\n"))
}
