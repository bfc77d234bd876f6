//! Renders brume's procedural scene ([`brume::scene`]) on a headless context and saves the
//! colour as an sRGB PNG and the depth as a grey PNG (eye depth on a log scale), to look at.
//!
//! ```sh
//! cargo run --example scene_view -- /tmp/scene.png [WIDTH HEIGHT [YAW PITCH [TIME [FRAMES]]]]
//! ```
//!
//! Writes `PATH` and `PATH` with `-depth` before the extension; prints the render times of
//! FRAMES frames (3 by default; the first one compiles the shaders in the driver).

use brume::camera::Camera;
use brume::egl::GlContext;
use brume::io::image::linear_to_srgb;
use brume::io::output::write_png_rgb8;
use brume::scene::SceneRenderer;
use glow::HasContext;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Instant;

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("scene_view: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = PathBuf::from(
        args.first()
            .ok_or("usage: scene_view PATH.png [W H [YAW PITCH [TIME [FRAMES]]]]")?,
    );
    let number = |i: usize, default: f64| -> Result<f64, Box<dyn std::error::Error>> {
        Ok(args
            .get(i)
            .map(|s| s.parse())
            .transpose()?
            .unwrap_or(default))
    };
    let (width, height) = (number(1, 1280.0)? as usize, number(2, 720.0)? as usize);
    let camera = Camera {
        yaw_deg: number(3, 0.0)?,
        pitch_deg: number(4, 0.0)?,
        ..Camera::default()
    };
    let time = number(5, 0.0)?;
    let frames = number(6, 3.0)? as usize;

    let ctx = GlContext::new(None)?;
    let gl = Arc::clone(ctx.gl());
    let mut renderer = SceneRenderer::new(Arc::clone(&gl))?;
    let mut times = vec![];
    for _ in 0..frames {
        let start = Instant::now();
        renderer.render(&camera, width, height, time)?;
        // SAFETY: waits for the frame on the current context.
        unsafe { gl.finish() };
        times.push(start.elapsed().as_secs_f64() * 1e3);
    }
    let best = times.iter().copied().fold(f64::INFINITY, f64::min);
    println!("{width}x{height}: render {times:.1?} ms, best {best:.1} ms");
    let frame = renderer.render(&camera, width, height, time)?;
    let colour = frame.read_colour()?;
    let depth = frame.read_depth()?;

    // GL rows start at the bottom, PNG rows at the top.
    let top_first = |y: usize| height - 1 - y;
    let mut rgb = Vec::with_capacity(width * height);
    let mut grey = Vec::with_capacity(width * height);
    let (near, far) = (camera.near.ln(), camera.far.ln());
    for y in 0..height {
        for x in 0..width {
            let c = colour.get(x, top_first(y));
            rgb.push(c.map(|v| (linear_to_srgb(v.clamp(0.0, 1.0)) * 255.0).round() as u8));
            let d = f64::from(*depth.get(x, top_first(y)));
            let g = if d >= 1.0 {
                255
            } else {
                let z = camera.eye_depth(d).ln();
                ((z - near) / (far - near) * 254.0).clamp(0.0, 254.0) as u8
            };
            grey.push([g; 3]);
        }
    }
    write_png_rgb8(&path, width, height, &rgb)?;
    let stem = path.file_stem().unwrap_or_default().to_string_lossy();
    let depth_path = path.with_file_name(format!("{stem}-depth.png"));
    write_png_rgb8(&depth_path, width, height, &grey)?;
    println!("wrote {} and {}", path.display(), depth_path.display());
    drop(renderer);
    Ok(())
}
