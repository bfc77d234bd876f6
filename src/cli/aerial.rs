//! `brume render --medium aerial`: paper 002's aerial perspective on a photo with depth,
//! from a turbidity given or estimated from a fisheye sky photo, and retargeting from the
//! turbidity a photo was taken at (sec. 7.2.3, eq. 25-26).

use super::args::{AerialBlur, RenderArgs};
use brume::atmosphere::{AttenuationTable, Sensitivity};
use brume::camera::Camera;
use brume::io::image::load_linear_rgb;
use brume::medium::{AerialPerspective, Medium, Pixel};
use brume::raster::{Grid, RgbImage, ScalarMap};
use brume::sky::turbidity::{estimate_turbidity, TurbidityOptions};
use brume::{Error, Result};
use std::sync::Arc;

/// The smallest source Γ retargeting divides by: below it the photo holds airlight only.
const MIN_SOURCE_GAMMA: f64 = 1e-3;

/// What the aerial render used, for the report.
pub struct AerialLook {
    pub medium: AerialPerspective,
    pub turbidity_source: &'static str,
    pub from_turbidity: Option<f64>,
}

/// The turbidity: `--turbidity`, or estimated from `--sky`.
fn turbidity(args: &RenderArgs) -> Result<(f64, &'static str)> {
    match (args.turbidity, &args.sky) {
        (Some(t), None) => Ok((t, "given")),
        (None, Some(path)) => {
            let sky = load_linear_rgb(path)?;
            let name = path.display().to_string();
            let estimate = estimate_turbidity(&sky, &name, &TurbidityOptions::default())?;
            log::info!(
                "{name}: turbidity {:.3} ± {:.3}",
                estimate.turbidity,
                estimate.std
            );
            Ok((estimate.turbidity, "sky"))
        }
        (Some(_), Some(_)) => Err(Error::invalid(
            "--sky",
            "given with --turbidity",
            "one of --turbidity T or --sky SKY_IMAGE",
        )),
        (None, None) => Err(Error::invalid(
            "--turbidity",
            "(missing)",
            "a turbidity in [1, 20] (or --sky SKY_IMAGE to estimate it) for --medium aerial",
        )),
    }
}

/// The camera whose rays give each pixel's zenith angle: `--pitch` and `--fov`.
pub fn aerial_camera(args: &RenderArgs) -> Camera {
    Camera {
        pitch_deg: args.pitch,
        fov_y_deg: args.depth.fov.unwrap_or(DEFAULT_FOV_DEG),
        ..Camera::default()
    }
}

/// The aerial medium for a photo whose range (in `--metres-per-unit`) reaches
/// `max_range`, with the horizon's light `horizon` at zenith angle `horizon_zenith`
/// (radians; `None`: `--horizon-zenith`).
pub fn aerial_look(
    args: &RenderArgs,
    max_range: f64,
    horizon: [f32; 3],
    horizon_zenith: Option<f64>,
) -> Result<AerialLook> {
    let (t, source) = turbidity(args)?;
    let sensitivity = match &args.sensitivity {
        Some(path) => Sensitivity::from_csv(path)?,
        None => Sensitivity::cie_srgb(),
    };
    let metres = args.metres_per_unit;
    if !(metres.is_finite() && metres > 0.0) {
        return Err(Error::invalid(
            "--metres-per-unit",
            metres,
            "metres per unit of range, > 0",
        ));
    }
    let s_max = (max_range * metres).max(1.0);
    let table = AttenuationTable::new(&sensitivity, t, args.altitude, s_max)?;
    let camera = aerial_camera(args);
    let medium = AerialPerspective {
        metres_per_unit: metres,
        lambda: match args.blur {
            AerialBlur::None => 0.0,
            AerialBlur::Diffusion => args.lambda,
        },
        reference_zenith: horizon_zenith.unwrap_or(args.horizon_zenith.to_radians()),
        ..AerialPerspective::new(Arc::new(table), camera, horizon)
    };
    medium.validate()?;
    Ok(AerialLook {
        medium,
        turbidity_source: source,
        from_turbidity: args.from_turbidity,
    })
}

/// The vertical field of view assumed when `--fov` is not given (degrees).
pub const DEFAULT_FOV_DEG: f64 = 60.0;

/// Retargeting (eq. 25-26): the haze-free radiance of a photo taken at turbidity
/// `from`, I⁰ = (I − I∞_s(1 − Γ_s))/Γ_s with the source's Γ and airlight, clamped at 0.
/// The target's medium is then applied to it as to any photo.
pub fn dehaze(
    image: &RgbImage,
    range: &ScalarMap,
    target: &AerialPerspective,
    from: f64,
    args: &RenderArgs,
) -> Result<RgbImage> {
    let sensitivity = match &args.sensitivity {
        Some(path) => Sensitivity::from_csv(path)?,
        None => Sensitivity::cie_srgb(),
    };
    let table = AttenuationTable::new(
        &sensitivity,
        from,
        args.altitude,
        target.table.max_distance_m(),
    )?;
    let source = AerialPerspective {
        table: Arc::new(table),
        ..target.clone()
    };
    let (w, h) = (image.width(), image.height());
    Ok(Grid::from_fn(w, h, |x, y| {
        let m = source.sample(Pixel {
            x,
            y: h - 1 - y,
            width: w,
            height: h,
            depth: f64::from(*range.get(x, y)),
            sigma0: 1.0,
        });
        let e = image.get(x, y);
        std::array::from_fn(|c| {
            let g = m.transmission[c].max(MIN_SOURCE_GAMMA);
            ((f64::from(e[c]) - m.inscatter[c] * (1.0 - g)) / g).max(0.0) as f32
        })
    }))
}
