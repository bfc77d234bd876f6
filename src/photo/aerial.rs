//! Paper 002's aerial perspective on a prepared photo: the spectral attenuation of a
//! turbidity along each pixel's ray, the horizon's light from the sky found (per azimuth
//! sector, sec. 4), and retargeting from the turbidity the photo was taken at (sec.
//! 7.2.3, eq. 25-26), as `brume render --medium aerial` and `brume view` run it; and the
//! turbidity of a fisheye sky photo for it ([`turbidity_from_sky`]).
//!
//! Retargeting comes in two forms ([`Retarget`]): the paper's eq. 26 keeps the
//! normalised radiance ρ = I⁰/I∞ (the object term scaled by I∞_t/I∞_s = ζ(T_t)/ζ(T_s)),
//! the other keeps the radiance I⁰ itself.

use super::{Photo, PreparedPhoto};
use crate::atmosphere::{horizon_light, AttenuationTable, Sensitivity};
use crate::blur::Blur;
use crate::camera::Camera;
use crate::camera::FrameInputs;
use crate::error::{Error, Result};
use crate::io::image::UprightPhoto;
use crate::medium::aerial::HorizonSectors;
use crate::medium::haze::{self, at_known_range};
use crate::medium::{AerialPerspective, Medium, Pixel};
use crate::pipeline::FogBlur;
use crate::raster::{Grid, RgbImage, ScalarMap};
use crate::sky::horizon_sectors::{
    horizon_light_by_azimuth, sun_gains, SectorGeometry, DEFAULT_SECTORS, MAX_SECTORS,
};
use crate::sky::image_circle::{find_image_circle, ImageCircle};
use crate::sky::turbidity::{estimate_turbidity, TurbidityEstimate, TurbidityOptions};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The smallest source Γ retargeting divides by: below it the photo holds airlight only.
const MIN_SOURCE_GAMMA: f64 = 1e-3;
/// Where the horizon's light is taken to be by default (zenith angle, degrees) when the
/// sky does not say.
pub const DEFAULT_HORIZON_ZENITH_DEG: f64 = 85.0;
/// Largest camera pitch, degrees: beyond it the image holds no horizon to speak of.
pub const MAX_PITCH_DEG: f64 = 85.0;
/// The turbidities the model is fitted for (Preetham et al.'s range).
pub const TURBIDITY_RANGE: (f64, f64) = (1.0, 20.0);
/// The camera's altitude, metres above sea level: the Dead Sea's shore to above any
/// airliner.
pub const ALTITUDE_RANGE_M: (f64, f64) = (-500.0, 20_000.0);

/// How a photo gets aerial perspective.
#[derive(Clone, Debug, PartialEq)]
pub struct AerialOptions {
    /// The atmosphere's turbidity T, in [1, 20].
    pub turbidity: f64,
    /// The turbidity the photo was taken at: its haze is removed first (retargeting).
    pub from_turbidity: Option<f64>,
    /// The camera's altitude above sea level, metres.
    pub altitude_m: f64,
    /// Metres per unit of the photo's range; `None`: the range is in metres, which the
    /// photo's depth must be known to be ([`metres_per_unit`]).
    pub metres_per_unit: Option<f64>,
    /// The camera whose rays give each pixel's zenith angle (pitch, vertical field of
    /// view).
    pub camera: Camera,
    /// The camera's spectral sensitivity. The default, the CIE observer in sRGB's
    /// primaries ([`Sensitivity::cie_srgb`]), is taken in the photo's own primaries where
    /// its colour profile says others (Display P3, Adobe RGB): see
    /// [`AerialPhoto::sensitivity`]. Other curves (a camera's, measured) are used as given.
    pub sensitivity: Sensitivity,
    /// The blur's strength from the scattering optical depth (0: none).
    pub lambda: f64,
    /// The zenith angle of the horizon's light, degrees, when it is not found in the sky.
    pub horizon_zenith_deg: f64,
    /// The horizon's light (linear RGB); `None` takes the brightest sky of the horizon
    /// region found by pre-processing, else the prepared photo's airlight.
    pub horizon_light: Option<[f32; 3]>,
    /// The diffusion blur's scheme and limits.
    pub blur: Blur,
    /// Azimuth sectors across the image for the horizon's light found in the sky (1: one
    /// value for the whole image), in [1, [`MAX_SECTORS`]].
    pub horizon_sectors: usize,
    /// How a photo taken at [`AerialOptions::from_turbidity`] is carried to the target.
    pub retarget: Retarget,
    /// The sun's zenith angle and its azimuth from the image centre's (radians,
    /// clockwise: the sun's compass azimuth minus the camera's heading). With no sky
    /// found, the horizon's light by azimuth then follows the Preetham sky's
    /// ([`crate::sky::horizon_sectors::sun_gains`]), the light given or estimated being
    /// the image centre's.
    pub sun: Option<[f64; 2]>,
}

/// Retargeting a photo from the turbidity it was taken at, T_s, to T_t (paper 002,
/// sec. 7.2.3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Retarget {
    /// Eq. 25-26 as printed: the normalised radiance ρ = I⁰/I∞ is what stays, so the
    /// object's radiance follows the sky's: I⁰_t = I⁰_s·I∞_t/I∞_s, and
    /// Î_t = I_s·(I∞_t Γ_t)/(I∞_s Γ_s) + I∞_t(1 − Γ_t/Γ_s). With brume's I∞(T, θ) =
    /// I∞(θ′)ζ(T, θ, θ′), I∞_t/I∞_s = ζ(T_t, θ, θ′)/ζ(T_s, θ, θ′).
    #[default]
    Normalised,
    /// The radiance I⁰ stays (the scene's light does not change with the haze):
    /// I⁰ = (I_s − I∞_s(1 − Γ_s))/Γ_s, then eq. 10 at T_t.
    Radiance,
}

impl Retarget {
    /// The name the command line and reports use.
    pub fn name(self) -> &'static str {
        match self {
            Retarget::Normalised => "normalised",
            Retarget::Radiance => "radiance",
        }
    }
}

impl AerialOptions {
    /// Turbidity `turbidity` seen by `camera`, the other options their defaults: sea
    /// level, range in metres, CIE colour matching to linear sRGB, λ 8, the horizon's
    /// light from the sky.
    pub fn new(turbidity: f64, camera: Camera) -> AerialOptions {
        AerialOptions {
            turbidity,
            from_turbidity: None,
            altitude_m: 0.0,
            metres_per_unit: None,
            camera,
            sensitivity: Sensitivity::cie_srgb(),
            lambda: haze::DEFAULT_LAMBDA,
            horizon_zenith_deg: DEFAULT_HORIZON_ZENITH_DEG,
            horizon_light: None,
            blur: Blur::default(),
            horizon_sectors: DEFAULT_SECTORS,
            retarget: Retarget::default(),
            sun: None,
        }
    }

    /// Checks the values, naming the field that is wrong and what it should be: the
    /// turbidities in [`TURBIDITY_RANGE`], the altitude in [`ALTITUDE_RANGE_M`], metres per
    /// unit > 0, λ ≥ 0, the horizon's zenith angle in [0, 90]°, the sectors in [1,
    /// [`MAX_SECTORS`]], the sun's angles, the blur ([`Blur::validate`]), the camera.
    pub fn validate(&self) -> Result<()> {
        let (t_lo, t_hi) = TURBIDITY_RANGE;
        for (name, t) in [
            ("turbidity", Some(self.turbidity)),
            ("from_turbidity", self.from_turbidity),
        ] {
            if let Some(t) = t.filter(|t| !(t_lo..=t_hi).contains(t)) {
                let expected = format!("a turbidity in [{t_lo}, {t_hi}]");
                return Err(Error::invalid(name, t, expected));
            }
        }
        let (a_lo, a_hi) = ALTITUDE_RANGE_M;
        let checks = [
            (
                "altitude_m",
                self.altitude_m,
                (a_lo..=a_hi).contains(&self.altitude_m),
                format!("an altitude above sea level in [{a_lo}, {a_hi}] m"),
            ),
            (
                "metres_per_unit",
                self.metres_per_unit.unwrap_or(1.0),
                self.metres_per_unit
                    .is_none_or(|m| m.is_finite() && m > 0.0),
                "metres per unit of the photo's range, > 0 (1 for a range in metres)".into(),
            ),
            (
                "lambda",
                self.lambda,
                self.lambda.is_finite() && self.lambda >= 0.0,
                "a blur factor ≥ 0 px".into(),
            ),
            (
                "horizon_zenith_deg",
                self.horizon_zenith_deg,
                (0.0..=90.0).contains(&self.horizon_zenith_deg),
                "a zenith angle in [0, 90] degrees (90 is the horizon)".into(),
            ),
        ];
        if let Some((name, value, _, expected)) = checks.into_iter().find(|c| !c.2) {
            return Err(Error::invalid(name, value, expected));
        }
        if !(1..=MAX_SECTORS).contains(&self.horizon_sectors) {
            return Err(Error::invalid(
                "horizon_sectors",
                self.horizon_sectors,
                format!("a number of azimuth sectors in [1, {MAX_SECTORS}]"),
            ));
        }
        if let Some([zenith, azimuth]) = self.sun {
            if !(zenith.is_finite() && (0.0..=PI).contains(&zenith) && azimuth.is_finite()) {
                return Err(Error::invalid(
                    "sun",
                    format!("[{zenith}, {azimuth}]"),
                    "a zenith angle in [0, π] and a finite azimuth, radians",
                ));
            }
        }
        self.blur.validate()?;
        self.camera.validate()
    }
}

/// What a host knows of a photo's camera: [`PhotoView::camera`] makes of it the camera
/// whose rays give each pixel's zenith angle ([`AerialOptions::camera`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhotoView {
    /// The vertical field of view, degrees; with it [`PhotoView::focal_px`] is not used.
    pub fov_y_deg: Option<f64>,
    /// The focal length in px (a calibration's f_y), for the field of view.
    pub focal_px: Option<f64>,
    /// The pitch, degrees, up positive; 0 (level) when neither it nor the horizon's row is
    /// given.
    pub pitch_deg: Option<f64>,
    /// The image row of the horizon (0 at the top, centres at integers), which gives the
    /// pitch ([`pitch_for_horizon_row`]); not with [`PhotoView::pitch_deg`].
    pub horizon_row: Option<f64>,
}

impl PhotoView {
    /// The camera of an image `height` rows tall. With no field of view to be had it is
    /// an error, not a guess: a guess would tilt every pixel's zenith angle. Errors name
    /// the field (`fov_y_deg`, `focal_px`, `pitch_deg`, `horizon_row`).
    pub fn camera(&self, height: usize) -> Result<Camera> {
        let fov_y_deg = match (self.fov_y_deg, self.focal_px) {
            (Some(fov), _) => fov,
            (None, Some(f)) if f.is_finite() && f > 0.0 => {
                (2.0 * (height as f64 / (2.0 * f)).atan()).to_degrees()
            }
            (None, Some(f)) => {
                return Err(Error::invalid("focal_px", f, "a focal length in px, > 0"))
            }
            (None, None) => {
                return Err(Error::invalid(
                    "fov_y_deg",
                    "(missing)",
                    "the camera's vertical field of view in degrees, or its focal length in \
                     px (or a depth whose calibration gives it): each pixel's zenith angle \
                     depends on it",
                ))
            }
        };
        let pitch_deg = match (self.pitch_deg, self.horizon_row) {
            (Some(_), Some(row)) => {
                let expected = "no pitch_deg with it: the horizon's row gives the pitch";
                return Err(Error::invalid("horizon_row", row, expected));
            }
            (None, Some(row)) => {
                let pitch = pitch_for_horizon_row(row, height, fov_y_deg);
                if !(-MAX_PITCH_DEG..=MAX_PITCH_DEG).contains(&pitch) {
                    return Err(Error::invalid(
                        "horizon_row",
                        row,
                        format!(
                            "a row (0 at the top) that puts the camera's pitch within \
                             ±{MAX_PITCH_DEG}° with this {height}-row image and a \
                             {fov_y_deg:.1}° field of view (it gives {pitch:.5}°; the horizon \
                             may lie a little outside the image)"
                        ),
                    ));
                }
                pitch
            }
            (pitch, None) => pitch.unwrap_or(0.0),
        };
        if !(-MAX_PITCH_DEG..=MAX_PITCH_DEG).contains(&pitch_deg) {
            return Err(Error::invalid(
                "pitch_deg",
                pitch_deg,
                format!("a pitch in [-{MAX_PITCH_DEG}, {MAX_PITCH_DEG}] degrees"),
            ));
        }
        let camera = Camera {
            pitch_deg,
            fov_y_deg,
            ..Camera::default()
        };
        camera.validate().map_err(|e| match e {
            Error::InvalidParameter {
                name,
                value,
                expected,
            } if name == "fov_y_deg" && self.fov_y_deg.is_none() => Error::invalid(
                "focal_px",
                self.focal_px.unwrap_or(f64::NAN),
                format!("a focal length giving a valid field of view: {value} is not {expected}"),
            ),
            e => e,
        })?;
        Ok(camera)
    }
}

/// Where an aerial photo's horizon light came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HorizonFrom {
    /// The brightest sky of the horizon region (paper 002, sec. 4).
    Horizon,
    /// [`AerialOptions::horizon_light`].
    Given,
    /// The prepared photo's airlight (no sky found).
    Airlight,
}

impl HorizonFrom {
    /// The name reports use.
    pub fn name(self) -> &'static str {
        match self {
            HorizonFrom::Horizon => "horizon",
            HorizonFrom::Given => "given",
            HorizonFrom::Airlight => "airlight",
        }
    }
}

/// A photo ready for aerial perspective: what the renderer is given.
#[derive(Clone, Debug)]
pub struct AerialPhoto {
    /// The photo (its haze removed with [`AerialOptions::from_turbidity`]).
    pub image: RgbImage,
    /// The range in the photo's units ([`AerialOptions::metres_per_unit`]), unknown
    /// samples taken as the sky.
    pub range: ScalarMap,
    /// The medium.
    pub medium: AerialPerspective,
    /// The largest known range.
    pub max_range: f32,
    /// Where the horizon's light came from.
    pub horizon_from: HorizonFrom,
    /// The diffusion blur, when the medium blurs.
    pub blur: Blur,
    /// The sensitivity the medium's attenuation was integrated with: the options', or the
    /// CIE observer in the photo's primaries.
    pub sensitivity: Sensitivity,
}

impl AerialPhoto {
    /// The fog's blur: none when λ is 0 (one pass does all).
    pub fn fog_blur(&self) -> FogBlur {
        if self.medium.lambda == 0.0 {
            FogBlur::None
        } else {
            FogBlur::Diffusion(self.blur)
        }
    }
}

/// The aerial medium for `photo` with its `prepared` range (at the image's size; see
/// [`super::prepare()`]), and the retargeted image. Errors: no known range, bad options.
pub fn aerial(
    photo: &Photo,
    prepared: &PreparedPhoto,
    opts: &AerialOptions,
) -> Result<AerialPhoto> {
    let range = &prepared.range;
    let max_range = haze::largest_range(range).map_err(|_| Error::NoValidDepth {
        path: PathBuf::from(&photo.depth_name),
    })?;
    // Unknown range (only without pre-processing) is taken as the sky is by it; 0 (the
    // ego vehicle's) stays at the camera.
    let range = range.map(|&v| {
        if at_known_range(v) {
            v
        } else {
            1.5 * max_range
        }
    });
    opts.validate()?;
    let metres_per_unit = metres_per_unit(photo, opts.metres_per_unit)?;
    // The sky's own turbidity carries a sector's light between zenith angles.
    let sky_turbidity = opts.from_turbidity.unwrap_or(opts.turbidity);
    let found = match (&opts.horizon_light, &prepared.prepared) {
        (None, Some(p)) if opts.horizon_sectors > 1 => horizon_light_by_azimuth(
            &photo.image,
            &p.sky,
            &opts.camera,
            opts.horizon_sectors,
            sky_turbidity,
        )
        .map(|h| {
            let g = h.geometry;
            let sectors = HorizonSectors::new(h.gains, g.centre, g.sector_width);
            (h.overall, Some(sectors))
        }),
        (None, Some(p)) => horizon_light(&photo.image, &p.sky, &opts.camera).map(|h| (h, None)),
        _ => None,
    };
    let (found, sectors) = match found {
        Some((h, s)) => (Some(h), s.transpose()?),
        None => (None, None),
    };
    let (light, zenith, horizon_from) = match (found, opts.horizon_light) {
        (Some(h), _) => (h.rgb, h.zenith, HorizonFrom::Horizon),
        (None, Some(rgb)) => (
            rgb,
            opts.horizon_zenith_deg.to_radians(),
            HorizonFrom::Given,
        ),
        (None, None) => (
            prepared.airlight,
            opts.horizon_zenith_deg.to_radians(),
            HorizonFrom::Airlight,
        ),
    };
    let far = 1.5 * f64::from(max_range);
    let sensitivity = photo_sensitivity(&opts.sensitivity, photo);
    let mut medium = aerial_medium(opts, &sensitivity, metres_per_unit, far, light, zenith)?;
    let sectors = match (sectors, opts.sun) {
        (Some(s), _) => Some(s),
        (None, Some([sun_zenith, sun_azimuth])) if opts.horizon_sectors > 1 => {
            let (w, h) = (photo.image.width(), photo.image.height());
            let g = SectorGeometry::across(&opts.camera, w, h, opts.horizon_sectors);
            let gains = sun_gains(&g, sky_turbidity, sun_zenith, sun_azimuth, zenith)?;
            Some(HorizonSectors::new(gains, g.centre, g.sector_width)?)
        }
        (None, _) => None,
    };
    if let Some(s) = sectors {
        medium.horizon_sectors = s;
    }
    let image = match opts.from_turbidity {
        Some(from) => dehaze(
            &photo.image,
            &range,
            &medium,
            &sensitivity,
            from,
            opts.retarget,
        )?,
        None => photo.image.clone(),
    };
    Ok(AerialPhoto {
        image,
        range,
        medium,
        max_range,
        horizon_from,
        blur: opts.blur,
        sensitivity,
    })
}

/// The sensitivity `given` for `photo`: the default, the CIE observer in sRGB's primaries,
/// in the photo's own where its colour profile says others, so that each channel's
/// attenuation is that of the photo's own red, green and blue (at 5 km and turbidity 2,
/// Display P3's blue keeps 0.389 of its light where sRGB's keeps 0.371).
fn photo_sensitivity(given: &Sensitivity, photo: &Photo) -> Sensitivity {
    match photo.metadata.profile() {
        Some(p) if !p.primaries_are_srgb() && *given == Sensitivity::cie_srgb() => {
            log::info!(
                "{}: aerial perspective integrated for its primaries ({})",
                photo.image_name,
                p.description()
            );
            Sensitivity::cie_in(p.xyz_to_rgb())
        }
        _ => given.clone(),
    }
}

/// Metres per unit of `photo`'s range: `given`, or 1 where its depth is known to be in
/// metres ([`LoadedDepth::metric`](crate::io::depth::LoadedDepth::metric)); an error
/// naming `metres_per_unit` where it is not, since aerial perspective reads metres.
pub fn metres_per_unit(photo: &Photo, given: Option<f64>) -> Result<f64> {
    let depth = &photo.depth;
    match given {
        Some(m) => Ok(m),
        None if depth.metric => Ok(1.0),
        None => Err(Error::invalid(
            "metres_per_unit",
            "(missing)",
            format!(
                "the scale of {}'s range, which aerial perspective reads in metres: it was \
                 read as {} {} in {}, not trustworthy metres (give `metres_per_unit`, or a \
                 metric depth: `calib`, `camera`, a metric `depth_format`)",
                photo.depth_name, depth.format, depth.kind, depth.units
            ),
        )),
    }
}

/// The medium of `opts` with `metres_per_unit` over ranges up to `max_range` (in the
/// photo's units), the horizon's light `light` at zenith angle `zenith` (radians), its
/// attenuation integrated for `sensitivity`.
fn aerial_medium(
    opts: &AerialOptions,
    sensitivity: &Sensitivity,
    metres_per_unit: f64,
    max_range: f64,
    light: [f32; 3],
    zenith: f64,
) -> Result<AerialPerspective> {
    let s_max = (max_range * metres_per_unit).max(1.0);
    let table = AttenuationTable::new(sensitivity, opts.turbidity, opts.altitude_m, s_max)?;
    let medium = AerialPerspective {
        metres_per_unit,
        lambda: opts.lambda,
        reference_zenith: zenith,
        ..AerialPerspective::new(Arc::new(table), opts.camera, light)
    };
    medium.validate()?;
    Ok(medium)
}

/// Retargeting (eq. 25-26): the haze-free image of a photo taken at turbidity `from`,
/// for the `target` medium to be applied to as to any photo. The source's medium is the
/// target's (its horizon light, sectors and geometry) at turbidity `from`: Γ_s and
/// I∞_s = I∞(θ′)ζ(T_s, θ, θ′). [`Retarget::Radiance`] gives I⁰ = (I − I∞_s(1 − Γ_s))/Γ_s;
/// [`Retarget::Normalised`] gives I⁰·I∞_t/I∞_s, so that the target's eq. 10 yields eq.
/// 26. Clamped at 0; Γ_s below 10⁻³ is taken as 10⁻³.
pub fn dehaze(
    image: &RgbImage,
    range: &ScalarMap,
    target: &AerialPerspective,
    sensitivity: &Sensitivity,
    from: f64,
    retarget: Retarget,
) -> Result<RgbImage> {
    let table = AttenuationTable::new(
        sensitivity,
        from,
        target.table.altitude_m(),
        target.table.max_distance_m(),
    )?;
    let source = AerialPerspective {
        table: Arc::new(table),
        ..target.clone()
    };
    let (w, h) = (image.width(), image.height());
    Ok(Grid::from_fn(w, h, |x, y| {
        let pixel = Pixel {
            x,
            y: h - 1 - y,
            width: w,
            height: h,
            depth: f64::from(*range.get(x, y)),
            sigma0: 1.0,
        };
        let m = source.sample(pixel, &FrameInputs::default());
        let scale: [f64; 3] = match retarget {
            Retarget::Radiance => [1.0; 3],
            Retarget::Normalised => {
                let t = target.sample(pixel, &FrameInputs::default());
                std::array::from_fn(|c| {
                    if m.inscatter[c] > 0.0 {
                        t.inscatter[c] / m.inscatter[c]
                    } else {
                        1.0
                    }
                })
            }
        };
        let e = image.get(x, y);
        std::array::from_fn(|c| {
            let g = m.transmission[c].max(MIN_SOURCE_GAMMA);
            (scale[c] * (f64::from(e[c]) - m.inscatter[c] * (1.0 - g)) / g).max(0.0) as f32
        })
    }))
}

/// The turbidity of the fisheye sky photo at `path` (paper 002, sec. 3.4): the sun
/// given as (zenith, azimuth) in radians in the fisheye's convention (azimuth 0 at the
/// image's top, clockwise; a compass azimuth when north is at the top), or found from
/// its saturated disc when `None`; the luminance that of the photo's primaries (its
/// colour profile's), the estimator's other options their defaults.
pub fn turbidity_from_sky(path: &Path, sun: Option<[f64; 2]>) -> Result<TurbidityEstimate> {
    let opts = TurbidityOptions {
        sun,
        ..TurbidityOptions::default()
    };
    let sky = estimate_sky_photo(path, &opts)?;
    log::info!(
        "{}: turbidity {:.3} ± {:.3}",
        path.display(),
        sky.estimate.turbidity,
        sky.estimate.std
    );
    Ok(sky.estimate)
}

/// A sky photo's turbidity ([`estimate_sky_photo`]) and what was read of the photo.
#[derive(Clone, Debug)]
pub struct SkyTurbidity {
    /// The estimate.
    pub estimate: TurbidityEstimate,
    /// The photo's width and height, upright.
    pub size: [usize; 2],
    /// The weights of R, G, B that gave its luminance: its colour profile's Y row.
    pub luminance: [f64; 3],
    /// Its colour profile's description; `None` for sRGB.
    pub colour_profile: Option<String>,
    /// Whether it held linear light ([`UprightPhoto::linear_light`]).
    pub linear_light: bool,
    /// Where its image circle was found, when the frame was not square (a circular
    /// fisheye's): the square estimated.
    pub circle: Option<ImageCircle>,
}

/// The turbidity of the fisheye sky photo at `path` by `opts`, whose `luminance` is
/// replaced by the photo's primaries' ([`load_sky_photo`]). A frame that is not square
/// is taken as a circular fisheye's and estimated on its image circle
/// ([`find_image_circle`]).
pub fn estimate_sky_photo(path: &Path, opts: &TurbidityOptions) -> Result<SkyTurbidity> {
    // The options are checked before the photo is read.
    opts.validate()?;
    let photo = load_sky_photo(path)?;
    let name = path.display().to_string();
    let opts = TurbidityOptions {
        luminance: photo.metadata.luminance_weights(),
        ..opts.clone()
    };
    let (w, h) = (photo.image.width(), photo.image.height());
    let circle = (w != h)
        .then(|| find_image_circle(&photo.image, &name))
        .transpose()?;
    let sky = match circle {
        Some(c) => {
            log::info!(
                "{name}: the image circle, {} px wide at ({}, {}), estimated",
                c.side,
                c.x,
                c.y
            );
            std::borrow::Cow::Owned(c.crop(&photo.image))
        }
        None => std::borrow::Cow::Borrowed(&photo.image),
    };
    let estimate = estimate_turbidity(&sky, &name, &opts)?;
    Ok(SkyTurbidity {
        estimate,
        size: [w, h],
        luminance: opts.luminance,
        colour_profile: photo.metadata.profile().map(|p| p.description().to_owned()),
        linear_light: photo.linear_light,
        circle,
    })
}

/// Bytes per pixel of a sky photo that the turbidity estimator holds besides the file's:
/// the decoded image and its luminance, the usable pixels' directions and ratios. From
/// `brume turbidity`'s peak RSS on 2048 x 2048 and 4096 x 4096 EXR skies: 53-55 bytes per
/// pixel in all, 11 of them the file's; rounded up.
const SKY_PHOTO_BYTES_PER_PIXEL: u64 = 48;

/// The fisheye sky photo at `path` for the turbidity estimator, upright and in linear
/// light, with a warning where its codes are display-encoded
/// ([`UprightPhoto::linear_light`]): the estimator takes them for its profile's curve of
/// linear light, and a camera's tone curve bends them (a mild contrast curve over a T 6
/// sky gave 6.46, a stronger one 4.79).
pub fn load_sky_photo(path: &Path) -> Result<UprightPhoto> {
    let photo = super::load_checked(path, |bytes, name| {
        super::check_decoding_fits(
            &[(bytes, name)],
            "estimating the turbidity of",
            SKY_PHOTO_BYTES_PER_PIXEL,
            "the estimator holds about {} bytes per pixel of the sky photo in memory: use \
             a smaller image",
        )
    })?;
    if !photo.linear_light {
        log::warn!("{}", display_encoded_sky(path));
    }
    Ok(photo)
}

/// What [`load_sky_photo`] warns of a display-encoded sky photo at `path`.
pub fn display_encoded_sky(path: &Path) -> String {
    format!(
        "{}: a display-encoded sky photo: the turbidity takes its codes for its colour \
         profile's curve (sRGB's without one) of linear light, which a camera's tone curve \
         is not; for a trustworthy T give linear light (an EXR, or the RAW developed to a \
         linear TIFF or PNG)",
        path.display()
    )
}

/// The pitch (degrees) that puts the horizon on row `row` (0 at the top, centres at
/// integers) of a `height`-row image with vertical field of view `fov_y_deg`: the ray
/// through the row, fwd + ndc·tan(fov/2)·up, is level when tan(pitch) = −ndc·tan(fov/2).
pub fn pitch_for_horizon_row(row: f64, height: usize, fov_y_deg: f64) -> f64 {
    let ndc = 1.0 - 2.0 * (row + 0.5) / height as f64;
    (-ndc * (fov_y_deg.to_radians() / 2.0).tan())
        .atan()
        .to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_horizon_row_gives_the_pitch_that_levels_its_ray() {
        let (h, fov) = (480, 50.0);
        for row in [0.0, 100.0, 239.5, 400.0, 479.0] {
            let pitch = pitch_for_horizon_row(row, h, fov);
            let camera = Camera {
                pitch_deg: pitch,
                fov_y_deg: fov,
                ..Camera::default()
            };
            // The ray through the row's centre (GL row h − 1 − row) is level.
            let ndc = 1.0 - 2.0 * (row + 0.5) / h as f64;
            let ray = camera.ray_at_ndc(0.0, ndc, 1.0);
            assert!(ray.y.abs() < 1e-12, "row {row}: {ray}");
        }
        assert_eq!(pitch_for_horizon_row(239.5, 480, 50.0), 0.0);
    }
}
