//! The fog of a prepared photo: paper 000's haze in normalised range or, from an
//! extinction coefficient or a visibility, in metres, with its diffusion blur.

use super::{Photo, PreparedPhoto};
use crate::blur::Blur;
use crate::error::{Error, Result};
use crate::medium::haze::{self, Haze};
use crate::medium::physical::{self, PhysicalFog, DEFAULT_ALBEDO};
use crate::medium::Medium;
use crate::raster::{Grid, ScalarMap};
use crate::renderer::{Rendered, Renderer};

/// How dense the haze is.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
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
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
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

/// The range texture the haze reads: `prepared`'s range normalised by its largest value
/// (paper 000), returned with it, or in metres for physical fog, its sky at least
/// [`SKY_RANGE_M`] away ([`PreparedPhoto::metres`]; returned with 1). Unknown values
/// (NaN, ≤ 0) are taken as the largest.
pub fn medium_range(extinction: &Extinction, prepared: &PreparedPhoto) -> Result<(ScalarMap, f64)> {
    match extinction {
        Extinction::Physical(_) => Ok((prepared.metres()?, 1.0)),
        Extinction::Normalised { .. } => {
            let (normalised, r_max) = haze::normalise_range(&prepared.range)?;
            Ok((normalised, f64::from(r_max)))
        }
    }
}

/// The least range, in metres, at which physical fog sees the sky (1 km: a low cloud
/// deck seen across a valley; the clear sky is farther): fog of visibility V veils it to
/// τ = 20^(−1000 m / V), 2e-9 at V = 150 m and 0.37 at V = 3 km.
///
/// Pre-processing puts the sky at Smax = 1.5·Rmax (`PrepOptions::sky_range_factor`),
/// paper 000's sky for normalised range, where only ratios count. In metres that ties the
/// sky to how far the sensor reached: a phone's depth stops at 8.2 m (`DEPTH16`) or
/// 65.5 m (ARCore), which put the sky 12 or 98 m away, and fog of 150 m visibility left it
/// 78 % or 14 % of its own colour.
pub const SKY_RANGE_M: f64 = 1000.0;

impl PreparedPhoto {
    /// The range in metres that physical fog reads ([`physical::metric_range`] of
    /// [`PreparedPhoto::range`]), the sky moved out to at least [`SKY_RANGE_M`]: the range
    /// above Rmax, the farthest scene point, is stretched in log range so that the sky's
    /// Smax lands on [`SKY_RANGE_M`] (r ↦ Rmax·(r/Rmax)^k, k = ln(SKY_RANGE_M/Rmax) /
    /// ln(Smax/Rmax)). The scene beyond the sensor's reach
    /// ([`crate::prep::Prepared::beyond_reach`], filled from Rmax to Smax linearly in log
    /// range, its parameter u in [0, 1]) is the ground receding toward the horizon
    /// instead: 1/R linear in u from 1/Rmax to 1/[`SKY_RANGE_M`], R = Rmax / (1 − (1 −
    /// Rmax/[`SKY_RANGE_M`])·u). The power law would put the ground halfway to the horizon
    /// at √(Rmax·1 km), 90 m for a phone's 8 m, where a plane puts it at 16 m. The scene up
    /// to Rmax keeps its range bit for bit, and the horizon margin's taper from the scene
    /// into the sky and the refinement's blend across the skyline stay continuous; the two
    /// maps agree at Rmax and at the sky, and differ between, so across the edge of the
    /// mask of the scene beyond the reach (brought to the image's size by nearest
    /// neighbour) a range upsampled between them may step.
    /// Without pre-processing, without sky, or with the sky already at [`SKY_RANGE_M`] or
    /// farther, the range is only made metric.
    pub fn metres(&self) -> Result<ScalarMap> {
        let (metres, _) = physical::metric_range(&self.range)?;
        let Some((r_max, s_max)) = self.sky_to_move_out() else {
            return Ok(metres);
        };
        let log_span = (s_max / r_max).ln();
        let k = (SKY_RANGE_M / r_max).ln() / log_span;
        let c = 1.0 - r_max / SKY_RANGE_M;
        let beyond = self.prepared.as_ref().map(|p| &p.beyond_reach);
        let beyond =
            beyond.filter(|b| (b.width(), b.height()) == (metres.width(), metres.height()));
        let w = metres.width();
        Ok(Grid::par_from_fn(w, metres.height(), |x, y| {
            let r = f64::from(*metres.get(x, y));
            if r <= r_max {
                return r as f32;
            }
            if beyond.is_some_and(|b| *b.get(x, y)) {
                // The ground receding toward the horizon: 1/R linear in the fill's
                // parameter, from 1/Rmax at the reach to 1/SKY_RANGE_M at the horizon.
                let u = ((r / r_max).ln() / log_span).min(1.0);
                (r_max / (1.0 - c * u)) as f32
            } else {
                (r_max * (r / r_max).powf(k)) as f32
            }
        }))
    }

    /// The range in metres at which physical fog sees the sky ([`PreparedPhoto::metres`]):
    /// [`SKY_RANGE_M`], or pre-processing's Smax where that is farther; `None` without
    /// sky (or without pre-processing).
    pub fn sky_range_m(&self) -> Option<f64> {
        let s_max = self.prepared.as_ref()?.stats.s_max?;
        Some(match self.sky_to_move_out() {
            Some(_) => SKY_RANGE_M,
            None => f64::from(s_max),
        })
    }

    /// Pre-processing's Rmax and Smax where [`PreparedPhoto::metres`] moves the sky out:
    /// there is sky, nearer than [`SKY_RANGE_M`], beyond a scene of range > 0.
    fn sky_to_move_out(&self) -> Option<(f64, f64)> {
        let stats = &self.prepared.as_ref()?.stats;
        let (r_max, s_max) = (f64::from(stats.r_max), f64::from(stats.s_max?));
        (r_max > 0.0 && s_max > r_max && s_max < SKY_RANGE_M).then_some((r_max, s_max))
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
    let (range, r_max) = medium_range(&opts.extinction, prepared)?;
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
    let (range, r_max) = medium_range(&first.extinction, prepared)?;
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
    use crate::raster::{Grid, RgbImage};

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

    /// A phone's street frame: a blue sky the depth does not reach over ground measured
    /// from 2 to `far` metres, its range prepared (sky found, margin tapered).
    fn phone_frame(far: f32) -> PreparedPhoto {
        let (w, h) = (64, 48);
        let image = RgbImage::from_fn(w, h, |x, y| match y < h / 2 {
            true => [0.35, 0.5, 0.9],
            false => [0.1 + 0.01 * (x % 7) as f32, 0.3, 0.1],
        });
        let range = ScalarMap::from_fn(w, h, |_, y| match y < h / 2 {
            true => f32::NAN,
            false => far - (far - 2.0) * (y - h / 2) as f32 / (h / 2 - 1) as f32,
        });
        let photo = Photo::from_range(image, range).unwrap();
        super::super::preprocess(&photo, &super::super::PrepareOptions::default()).unwrap()
    }

    /// Physical fog sees the sky of a shallow depth map 1 km away, not at 1.5 times the
    /// depth's reach; the scene keeps its range to the bit, and the taper into the sky
    /// stays in order (a step would draw the horizon).
    #[test]
    fn physical_fog_puts_a_shallow_sky_a_kilometre_away() {
        let prepared = phone_frame(8.0);
        let p = prepared.prepared.as_ref().unwrap();
        let (r_max, s_max) = (p.stats.r_max, p.stats.s_max.unwrap());
        assert_eq!(r_max, 8.0);
        assert!((s_max - 12.0).abs() < 1e-5, "{s_max}");
        assert!(p.stats.margin_pixels > 0, "{:?}", p.stats);
        let plain = physical::metric_range(&prepared.range).unwrap().0;
        let metres = prepared.metres().unwrap();
        let mut pairs: Vec<(f32, f32)> = plain
            .as_slice()
            .iter()
            .copied()
            .zip(metres.as_slice().iter().copied())
            .collect();
        for &(before, after) in &pairs {
            if before <= r_max {
                assert_eq!(before.to_bits(), after.to_bits());
            } else if before == s_max {
                assert!((f64::from(after) - SKY_RANGE_M).abs() < 1e-3, "{after}");
            } else {
                assert!(
                    after > before && f64::from(after) < SKY_RANGE_M,
                    "{before} -> {after}"
                );
            }
        }
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        assert!(pairs.windows(2).all(|w| w[0].1 <= w[1].1), "not monotone");
        // The fog of 150 m visibility: the sky veiled, the scene as before.
        let fog = FogOptions::visibility(150.0).unwrap();
        let (range, divisor) = medium_range(&fog.extinction, &prepared).unwrap();
        assert_eq!(divisor, 1.0);
        let haze = fog.haze(prepared.airlight).unwrap();
        let tau = transmittance_map(&haze, &range);
        let sky_tau = tau.get(0, 0);
        assert!(*sky_tau < 1e-8, "{sky_tau}");
        assert_eq!(prepared.sky_range_m(), Some(SKY_RANGE_M));
        assert_eq!(tau.get(0, 47), transmittance_map(&haze, &plain).get(0, 47));
    }

    /// The ground a phone's depth did not reach (green below the blue sky, unknown like
    /// the sky) is no sky: physical fog sees it recede as the ground does, 1/R linear in
    /// the fill's parameter from the reach to the sky's 1 km, where the sky's own taper
    /// runs out in log range.
    #[test]
    fn physical_fog_sees_the_ground_beyond_the_reach_recede() {
        let (w, h) = (64, 48);
        let image = RgbImage::from_fn(w, h, |x, y| match y {
            y if y < h / 4 => [0.35, 0.5, 0.9],
            _ => [0.1 + 0.01 * (x % 7) as f32, 0.3, 0.1],
        });
        let range = ScalarMap::from_fn(w, h, |_, y| match y < h / 2 {
            true => f32::NAN,
            false => 8.0 - 6.0 * (y - h / 2) as f32 / (h / 2 - 1) as f32,
        });
        let photo = Photo::from_range(image, range).unwrap();
        let prepared =
            super::super::preprocess(&photo, &super::super::PrepareOptions::default()).unwrap();
        let p = prepared.prepared.as_ref().unwrap();
        let (r_max, s_max) = (f64::from(p.stats.r_max), f64::from(p.stats.s_max.unwrap()));
        assert_eq!(p.stats.beyond_reach, w * h / 4, "{:?}", p.stats);
        let metres = prepared.metres().unwrap();
        let c = 1.0 - r_max / SKY_RANGE_M;
        for y in h / 4..h / 2 {
            let (before, after) = (f64::from(*prepared.range.get(5, y)), *metres.get(5, y));
            assert!(*p.beyond_reach.get(5, y) && !*p.sky.get(5, y));
            let u = (before / r_max).ln() / (s_max / r_max).ln();
            let want = r_max / (1.0 - c * u);
            assert!(
                (f64::from(after) - want).abs() < 1e-4 * want,
                "row {y}: {after} / {want}"
            );
            if y > h / 4 {
                assert!(
                    after < *metres.get(5, y - 1),
                    "row {y} not nearer than above"
                );
            }
        }
        // The contour's row is about the reach; half a row below the horizon (t = 23/24)
        // the ground is 20 times as far.
        assert!(f64::from(*metres.get(5, h / 2 - 1)) < 1.2 * r_max);
        assert!(f64::from(*metres.get(5, h / 4)) > 15.0 * r_max);
    }

    /// A phone's depth 4 times smaller than the image, of flat ground whose 1/R goes to 0
    /// at the horizon (image row 11.5), the sky above it and the sensor's reach (8 m) at
    /// cell row 8: upsampled, the ground beyond the reach recedes as the fill's model puts
    /// it at every pixel, 1/R linear in the image's rows from 1/Rmax at the contour (the
    /// boundary above cell row 8, image row 31.5) toward 1/1 km at the horizon. The joint
    /// bilateral upsampling alone smoothed the kink at the horizon into the ground below
    /// it: 40 % too near at image row 14, 16 % at row 16, and 2 % too far by the contour.
    #[test]
    fn the_ground_beyond_the_reach_is_upsampled_as_it_recedes() {
        let (w, h, f) = (64, 48, 4);
        let image = RgbImage::from_fn(w, h, |x, y| match y {
            y if y < 12 => [0.35, 0.5, 0.9],
            _ => [0.1 + 0.01 * (x % 7) as f32, 0.3, 0.1],
        });
        let range = ScalarMap::from_fn(w / f, h / f, |_, j| match j {
            j if j < 8 => f32::NAN,
            j => 176.0 / (4 * j - 10) as f32,
        });
        let photo = Photo::from_range(image, range).unwrap();
        let opts = super::super::PrepareOptions::default();
        let mut prepared = super::super::preprocess(&photo, &opts).unwrap();
        let stats = prepared.prepared.as_ref().unwrap().stats.clone();
        assert_eq!(
            (stats.r_max, stats.beyond_reach),
            (8.0, 5 * w / f),
            "{stats:?}"
        );
        prepared
            .refine(&photo, &opts.refine, &mut crate::refine::CpuFilter)
            .unwrap();
        let metres = prepared.metres().unwrap();
        let c = 1.0 - 8.0 / SKY_RANGE_M;
        for x in [0, 20, 63] {
            for y in 14..=29 {
                let want = 8.0 / (1.0 - c * (31.5 - y as f64) / 20.0);
                let got = f64::from(*metres.get(x, y));
                assert!(
                    (got - want).abs() < 1e-3 * want,
                    "({x}, {y}): {got} / {want}"
                );
            }
            assert!(*metres.get(x, 13) > *metres.get(x, 14));
        }
    }

    /// An object inserted between the farthest scene point and the sky keeps its range
    /// under physical fog, and the sky round it still goes 1 km out.
    #[test]
    fn an_inserted_object_beyond_the_scene_keeps_its_range() {
        let mut prepared = phone_frame(8.0);
        let (w, h) = (prepared.range.width(), prepared.range.height());
        let mut photo = Photo::from_range(
            RgbImage::filled(w, h, [0.35, 0.5, 0.9]),
            ScalarMap::filled(w, h, 5.0),
        )
        .unwrap();
        let at = |x: usize, y: usize| (20..30).contains(&x) && (4..10).contains(&y);
        let rgba = Grid::from_fn(w, h, |x, y| match at(x, y) {
            true => [0.5, 0.2, 0.1, 1.0],
            false => [0.0; 4],
        });
        let range = ScalarMap::from_fn(w, h, |x, y| if at(x, y) { 10.0 } else { f32::NAN });
        let object = super::super::VirtualObject::from_range(rgba, range, "tower").unwrap();
        let done = super::super::insert(&mut photo, &mut prepared, &object).unwrap();
        assert_eq!(done.in_front, 60, "{done:?}");
        let p = prepared.prepared.as_ref().unwrap();
        assert_eq!(p.stats.r_max, 10.0);
        let metres = prepared.metres().unwrap();
        assert_eq!(*metres.get(25, 6), 10.0);
        assert!((f64::from(*metres.get(2, 0)) - SKY_RANGE_M).abs() < 1e-3);
    }

    /// A sky already a kilometre away or more, normalised κ, and a photo without
    /// pre-processing read the range as they did.
    #[test]
    fn a_deep_sky_and_normalised_range_are_left_alone() {
        let deep = phone_frame(800.0);
        let plain = physical::metric_range(&deep.range).unwrap().0;
        assert_eq!(deep.metres().unwrap().as_slice(), plain.as_slice());
        assert_eq!(deep.sky_range_m(), Some(1200.0));
        let shallow = phone_frame(8.0);
        let kappa = FogOptions::default();
        let (range, r_max) = medium_range(&kappa.extinction, &shallow).unwrap();
        let (normalised, largest) = haze::normalise_range(&shallow.range).unwrap();
        assert_eq!(
            (range.as_slice(), r_max),
            (normalised.as_slice(), f64::from(largest))
        );
        let mut unprepared = shallow.clone();
        unprepared.prepared = None;
        let plain = physical::metric_range(&unprepared.range).unwrap().0;
        assert_eq!(unprepared.metres().unwrap().as_slice(), plain.as_slice());
        assert_eq!(unprepared.sky_range_m(), None);
    }
}
