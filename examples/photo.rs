//! Fog a photo with depth in metres through the library alone (`brume::photo`): load,
//! prepare (holes, sky, airlight, refinement), fog at a visibility, write the image and
//! its transmittance map. No command-line code is involved.
//!
//! ```sh
//! cargo run --example photo -- OUT.png                         # Middlebury's Aloe, 6 m visibility
//! cargo run --example photo -- OUT.png IMAGE DEPTH [VISIBILITY_M]
//! ```
//!
//! Without IMAGE and DEPTH it fogs the Middlebury 2006 "Aloe" pair kept in
//! `tests/data/aloe/` with its published geometry (focal length 3740 px, baseline 160 mm,
//! disparity offset 270 px: the plant 1.2-2 m from the camera) at a visibility of 6 m, and
//! checks the result against the physics: the transmittance of every pixel is
//! exp(−βR) of its range, and the fogged image is brighter toward the airlight where τ is
//! lower. Exits 1 if a check fails.

use brume::io::depth::DepthOptions;
use brume::io::output::{write_photo, write_scalar};
use brume::photo::{self, FogOptions, Photo, PrepareOptions};
use brume::Headless;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("photo: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(out) = args.first().map(PathBuf::from) else {
        return Err("usage: photo OUT.png [IMAGE DEPTH [VISIBILITY_M]]".into());
    };
    let aloe = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/aloe");
    let (image, depth, opts, visibility) = match &args[1..] {
        [] => (
            aloe.join("left.jpg"),
            aloe.join("disparity.png"),
            DepthOptions {
                focal: Some(3740.0),
                baseline: Some(160.0),
                disparity_offset: Some(270.0),
                ..DepthOptions::default()
            },
            6.0,
        ),
        [image, depth, rest @ ..] => (
            PathBuf::from(image),
            PathBuf::from(depth),
            DepthOptions::default(),
            match rest.first() {
                Some(v) => v.parse()?,
                None => 200.0,
            },
        ),
        _ => return Err("usage: photo OUT.png [IMAGE DEPTH [VISIBILITY_M]]".into()),
    };

    let mut headless = Headless::new(None)?;
    let photo = Photo::load(&image, &depth, &opts)?;
    let prepared = photo::prepare(
        &photo,
        &PrepareOptions::for_photo(&photo),
        headless.renderer()?,
    )?;
    let fog = FogOptions::visibility(visibility)?;
    let fogged = photo::fog(headless.renderer()?, &photo, &prepared, &fog)?;
    let tau = fogged.transmittance();
    // The photo's colour profile (Display P3 ...) and EXIF go with the fogged image.
    write_photo(&out, &fogged.rendered.image, &photo.metadata)?;
    let tau_path = out.with_extension("transmittance.pfm");
    write_scalar(&tau_path, &tau)?;
    println!(
        "{}: {}x{}, visibility {visibility} m (β {:.4}/m), airlight {:?} ({}), {} diffusion passes; wrote {} and {}",
        photo.image_name,
        photo.image.width(),
        photo.image.height(),
        2.995_732 / visibility,
        prepared.airlight,
        prepared.airlight_from.name(),
        fogged.rendered.schedule.steps,
        out.display(),
        tau_path.display()
    );
    check_physics(
        &photo,
        &prepared.range,
        &tau,
        &fogged.rendered.image,
        visibility,
        prepared.airlight,
    )
}

/// τ = exp(−βR) at every pixel, with β = −ln 0.05 / V computed here, not by brume; and
/// where τ < 0.5 the fogged pixel lies nearer the airlight than the clear one.
fn check_physics(
    photo: &Photo,
    range: &brume::raster::ScalarMap,
    tau: &brume::raster::ScalarMap,
    fogged: &brume::raster::RgbaImage,
    visibility: f64,
    airlight: [f32; 3],
) -> Result<(), Box<dyn std::error::Error>> {
    let beta = -(0.05f64.ln()) / visibility;
    let mut worst: f64 = 0.0;
    for (r, t) in range.as_slice().iter().zip(tau.as_slice()) {
        worst = worst.max(((-beta * f64::from(*r)).exp() - f64::from(*t)).abs());
    }
    if worst > 1e-5 {
        return Err(format!("τ differs from exp(−βR) by {worst}").into());
    }
    let (mut nearer, mut counted) = (0usize, 0usize);
    for ((t, clear), foggy) in tau
        .as_slice()
        .iter()
        .zip(photo.image.as_slice())
        .zip(fogged.as_slice())
    {
        if *t < 0.5 {
            counted += 1;
            let d = |c: [f32; 3]| (0..3).map(|k| (c[k] - airlight[k]).abs()).sum::<f32>();
            if d([foggy[0], foggy[1], foggy[2]]) <= d(*clear) + 1e-3 {
                nearer += 1;
            }
        }
    }
    println!(
        "checked: |τ − exp(−βR)| ≤ {worst:.1e}; {nearer} of {counted} pixels with τ < 0.5 moved toward the airlight"
    );
    if counted > 0 && nearer * 100 < counted * 99 {
        return Err("the fog did not move the far pixels toward the airlight".into());
    }
    Ok(())
}
