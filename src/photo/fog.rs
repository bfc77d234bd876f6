//! The fog of a prepared photo: paper 000's haze in normalised range or, from an
//! extinction coefficient or a visibility, in metres, with its diffusion blur.

use super::{Photo, PreparedPhoto};
use crate::blur::Blur;
use crate::error::{Error, Result};
use crate::medium::haze::{self, Haze};
use crate::medium::physical::{self, PhysicalFog, DEFAULT_ALBEDO};
use crate::medium::Medium;
use crate::raster::ScalarMap;
use crate::renderer::{Rendered, Renderer};

/// How dense the haze is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Extinction {
    /// Paper 000's κa and κs per unit of normalised range (the largest range is 1).
    Normalised {
        /// Absorption κa.
        ka: f64,
        /// Scattering κs.
        ks: f64,
    },
    /// An extinction coefficient in 1/m (and its albedo) on range in metres.
    Physical(PhysicalFog),
}

/// The fog a photo gets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FogOptions {
    /// How dense.
    pub extinction: Extinction,
    /// The blur's strength λ (σ grows with the optical depth; 0 for none).
    pub lambda: f64,
    /// Per-channel factors of the extinction (1, 1, 1: grey fog).
    pub tint: [f64; 3],
    /// The diffusion blur's scheme, precision and limits.
    pub blur: Blur,
}

impl Default for FogOptions {
    /// Paper 000's defaults: κa 0.25, κs 0.75 on normalised range, λ 8; the diffusion
    /// blur as `brume render` runs it ([`Blur::photo`]: coarse to fine from 2 px).
    fn default() -> Self {
        FogOptions {
            extinction: Extinction::Normalised {
                ka: haze::DEFAULT_KA,
                ks: haze::DEFAULT_KS,
            },
            lambda: haze::DEFAULT_LAMBDA,
            tint: [1.0; 3],
            blur: Blur::photo(),
        }
    }
}

impl FogOptions {
    /// Fog of extinction `beta` (1/m, albedo 1) on range in metres, the other options
    /// the defaults.
    pub fn beta(beta: f64) -> Result<FogOptions> {
        Ok(FogOptions {
            extinction: Extinction::Physical(PhysicalFog::new(beta, DEFAULT_ALBEDO)?),
            ..FogOptions::default()
        })
    }

    /// Fog of meteorological visibility `visibility_m` (contrast 5 %; albedo 1).
    pub fn visibility(visibility_m: f64) -> Result<FogOptions> {
        Ok(FogOptions {
            extinction: Extinction::Physical(PhysicalFog::from_visibility(
                visibility_m,
                DEFAULT_ALBEDO,
            )?),
            ..FogOptions::default()
        })
    }

    /// Checks every value before any work, naming the field: the haze's (with paper
    /// 000's default airlight) and the blur's ([`Blur::validate`]).
    pub fn validate(&self) -> Result<()> {
        self.haze(haze::DEFAULT_AIRLIGHT)?;
        self.blur.validate()
    }

    /// The haze medium with `airlight`, its values checked.
    pub fn haze(&self, airlight: [f32; 3]) -> Result<Haze> {
        let (ka, ks) = match self.extinction {
            Extinction::Normalised { ka, ks } => (ka, ks),
            Extinction::Physical(_) => (haze::DEFAULT_KA, haze::DEFAULT_KS),
        };
        let haze = Haze {
            ka,
            ks,
            lambda: self.lambda,
            airlight,
            tint: self.tint,
            range_unit: 1.0,
        };
        haze.validate()?;
        Ok(match &self.extinction {
            Extinction::Physical(fog) => fog.haze(&haze),
            Extinction::Normalised { .. } => haze,
        })
    }
}

/// The range texture the haze reads: `range` normalised by its largest value (paper 000),
/// returned with it, or kept in metres for physical fog (returned with 1). Unknown values
/// (NaN, ≤ 0) are taken as the largest.
pub fn medium_range(extinction: &Extinction, range: &ScalarMap) -> Result<(ScalarMap, f64)> {
    match extinction {
        Extinction::Physical(_) => {
            let (metres, _) = physical::metric_range(range)?;
            Ok((metres, 1.0))
        }
        Extinction::Normalised { .. } => {
            let (normalised, r_max) = haze::normalise_range(range)?;
            Ok((normalised, f64::from(r_max)))
        }
    }
}

/// A fogged photo.
#[derive(Debug)]
pub struct FoggedPhoto {
    /// The image, the blur's schedule and the passes' times.
    pub rendered: Rendered,
    /// The medium as rendered (its `range_unit` the visibility for physical fog).
    pub haze: Haze,
    /// The range texture the haze read ([`medium_range`]): normalised by its largest
    /// value, or in metres for physical fog.
    pub range: ScalarMap,
    /// The range that counts as 1 in the medium's units: the largest range (normalised
    /// extinction) or the visibility in metres (physical fog).
    pub range_divisor: f64,
}

impl FoggedPhoto {
    /// The transmittance τ (green channel) at each pixel, as the render applied it: the
    /// dehazing label of I = J·τ + A·(1 − τ) ([`transmittance_map`] of its haze and range).
    pub fn transmittance(&self) -> ScalarMap {
        transmittance_map(&self.haze, &self.range)
    }
}

/// Fogs `photo` with its `prepared` range (see [`super::prepare()`]) on `renderer`.
///
/// Errors: [`Error::InvalidParameter`] for bad options, for physical fog on a range not
/// known to be in metres ([`crate::io::depth::LoadedDepth::metric`]), and for a range not
/// yet at the image's size (refine first); the renderer's own.
pub fn fog(
    renderer: &mut Renderer,
    photo: &Photo,
    prepared: &PreparedPhoto,
    opts: &FogOptions,
) -> Result<FoggedPhoto> {
    let haze = checked_haze(photo, prepared, opts)?;
    let (range, r_max) = medium_range(&opts.extinction, &prepared.range)?;
    let rendered = renderer.render(&photo.image, &range, &haze, &opts.blur)?;
    Ok(FoggedPhoto {
        rendered,
        haze,
        range_divisor: range_divisor(opts, &haze, r_max),
        range,
    })
}

/// [`fog`] of `photo` once per entry of `opts` (a dataset's extinctions), each result
/// handed to `each` with its index as soon as it is read back; every option is checked
/// before the first render. When all of `opts` read one range texture with one blur
/// (extinctions of one kind: β or visibilities, or κa and κs), the image and that range
/// are uploaded once for all of them ([`Renderer::render_each`]); otherwise each is
/// rendered on its own. Stops at the first error (of a render or of `each`).
pub fn fog_each(
    renderer: &mut Renderer,
    photo: &Photo,
    prepared: &PreparedPhoto,
    opts: &[FogOptions],
    mut each: impl FnMut(usize, FoggedPhoto) -> Result<()>,
) -> Result<()> {
    let hazes: Vec<Haze> = opts
        .iter()
        .map(|o| checked_haze(photo, prepared, o))
        .collect::<Result<_>>()?;
    let Some(first) = opts.first() else {
        return Ok(());
    };
    let shared = opts.iter().all(|o| {
        o.blur == first.blur
            && std::mem::discriminant(&o.extinction) == std::mem::discriminant(&first.extinction)
    });
    if !shared {
        for (k, o) in opts.iter().enumerate() {
            each(k, fog(renderer, photo, prepared, o)?)?;
        }
        return Ok(());
    }
    let (range, r_max) = medium_range(&first.extinction, &prepared.range)?;
    let media: Vec<&dyn Medium> = hazes.iter().map(|h| h as &dyn Medium).collect();
    renderer.render_each(&photo.image, &range, &media, &first.blur, |k, rendered| {
        let haze = hazes[k];
        each(
            k,
            FoggedPhoto {
                rendered,
                haze,
                range: range.clone(),
                range_divisor: range_divisor(&opts[k], &haze, r_max),
            },
        )
    })
}

/// The haze of `opts` on `prepared`'s airlight, once `photo` and `prepared` are checked
/// to suit it: a range in metres for physical fog, at the image's size.
fn checked_haze(photo: &Photo, prepared: &PreparedPhoto, opts: &FogOptions) -> Result<Haze> {
    if let Extinction::Physical(fog) = &opts.extinction {
        photo.require_metres("beta", fog.beta)?;
    }
    let size = (photo.image.width(), photo.image.height());
    if (prepared.range.width(), prepared.range.height()) != size {
        return Err(Error::invalid(
            "range",
            format!("{}x{}", prepared.range.width(), prepared.range.height()),
            format!(
                "the image's size, {}x{}: refine the prepared photo first (it upsamples)",
                size.0, size.1
            ),
        ));
    }
    opts.haze(prepared.airlight)
}

/// [`FoggedPhoto::range_divisor`] of `haze` made from `opts`, `r_max` the largest range
/// ([`medium_range`]).
fn range_divisor(opts: &FogOptions, haze: &Haze, r_max: f64) -> f64 {
    match opts.extinction {
        Extinction::Physical(_) => haze.range_unit,
        Extinction::Normalised { .. } => r_max,
    }
}

/// The transmittance τ (green channel) of `haze` at each pixel of `medium_range` (as
/// [`medium_range`] makes it), row 0 at the top.
pub fn transmittance_map(haze: &Haze, medium_range: &ScalarMap) -> ScalarMap {
    medium_range.map(|&r| haze.transmission(f64::from(r) / haze.range_unit)[1] as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every value is checked before any work, the field named: the haze's, then the
    /// blur's.
    #[test]
    fn validate_checks_the_haze_and_the_blur() {
        assert!(FogOptions::default().validate().is_ok());
        assert!(FogOptions::beta(0.02).unwrap().validate().is_ok());
        let refused = |change: fn(&mut FogOptions), field: &str| {
            let mut opts = FogOptions::default();
            change(&mut opts);
            match opts.validate() {
                Err(Error::InvalidParameter { name, .. }) => assert_eq!(name, field, "{opts:?}"),
                other => panic!("{opts:?}: {other:?}"),
            }
        };
        refused(|o| o.lambda = -1.0, "lambda");
        refused(|o| o.tint = [1.0, f64::NAN, 1.0], "tint");
        refused(
            |o| o.extinction = Extinction::Normalised { ka: -1.0, ks: 0.5 },
            "ka",
        );
        refused(|o| o.blur.rho_max = 0.5, "rho_max");
    }
}
