//! Paper 003's layered fog: a fog whose density δ depends on height only, integrated in
//! closed form along the segment from the camera to each fragment of a rendered frame.
//!
//! **Model** (paper 003, eq. 6-9). The fog factor is f = e^(−F) with F = ∫ δ dt along the
//! camera-to-fragment segment. With δ a function of the height y alone,
//!
//! ```text
//! F = (l / Δy)·∫_{y_cam}^{y_frag} δ(y) dy = l·δ̄,   Δy = y_frag − y_cam,
//! ```
//!
//! with l the Euclidean length of the segment and δ̄ the mean density over the heights it
//! spans. The blend C = f·C_frag + (1 − f)·C_fog is brume's τ·E + (1 − τ)·L∞ with τ = f
//! (grey) and L∞ the fog colour. l is the Euclidean distance, not the eye depth, so turning
//! the camera about its centre leaves the fog on a fixed point unchanged (paper 003,
//! fig. 1).
//!
//! **The fragment's position** comes from the frame's depth buffer: the medium reads the
//! window depth d ∈ [0, 1] (clamped there) and the frame's camera
//! ([`crate::camera::FrameInputs::camera`]: the medium holds none, one value fogs every
//! frame). The
//! shader rebuilds it the fast way, eye + ray·A/(d + B) (paper 003, sec. 2.1); the CPU
//! reference by the inverse matrices (paper 002, eq. 22-23), so that comparing the two
//! also tests the fast path. A sky pixel (the far end of the depth range) lies on the far
//! plane: its fog is that of the segment to the far plane, or, for an engine's infinite
//! projection, to its sky depth ([`crate::camera::MatrixCamera::with_sky_depth`]).
//!
//! **The mean density without cancellation.** The textbook form
//! (Iδ(y1) − Iδ(y0)) / Δy, with Iδ an antiderivative ([`HeightProfile::antiderivative`]),
//! is 0/0 for a horizontal ray and loses all of f32's digits long before: every row near
//! the horizon would be noise. Each profile's mean is written instead as a product of
//! well-conditioned factors, exact for any Δy:
//!
//! - exponential, δ(y) = ρ·e^(−(y − base)/H): δ̄ = δ(ȳ)·sinh(h)/h with ȳ the mid-height and
//!   h = |Δy|/(2H); for h ≥ 1, δ̄ = δ(y_low)·(1 − e^(−2h))/(2h), which cannot overflow;
//! - sine band: the overlap [a, b] of the segment's heights with the band, a fraction
//!   w = (b − a)/|Δy| of the segment, has the mean δ(ā)·sin(h)/h, h = π(b − a)/(2T), where
//!   ā is its mid-height (cos a − cos b written as a product of sines);
//! - linear ramp: δ is piecewise linear, and the mean of a linear piece is its value at
//!   the piece's mid-height: no series at all.
//!
//! sinh(h)/h and sin(h)/h are summed as their Taylor series through h¹² below h = 1
//! (truncation < 1e-12) and by the library functions from h = 1 (a few ulps: at h ≥ 1
//! there is nothing left to cancel), so both branches are accurate to f32's last digits
//! at the switch and the switch leaves no seam. `glsl/medium/layered.glsl` evaluates the
//! same formulas in the same order.
//!
//! **The blur** follows [`blur_from_optical_depth`]: σ = σ0 + λ·r·√Ds with
//! r = l / [`LayeredFog::range_unit`] and the scattering optical depth
//! Ds = albedo·min(δ̄·min(l, range_unit), [`MAX_BLUR_OPTICAL_DEPTH`]). The optical depth is
//! the one the segment gathers over its first `range_unit` of length at its mean density,
//! because the law's r stops at 1 (a homogeneous medium then gets paper 000's eq. 7, like
//! [`crate::medium::Haze`]); and it stops at [`MAX_BLUR_OPTICAL_DEPTH`], where nothing of
//! the scene is left to blur. Both caps make [`Medium::sigma_max`] a true bound without
//! knowing the image: σ ≤ σ0 + λ·√(albedo·min(sup δ·range_unit, MAX_BLUR_OPTICAL_DEPTH)).

use super::{blur_from_optical_depth, Medium, MediumSample, Pixel, UniformValue};
use crate::camera::{FrameCamera, FrameInputs};
use crate::error::{check_non_negative, check_positive, Error, Result};
use glam::DVec3;
use std::f64::consts::{FRAC_PI_2, PI};
use std::ops::{Add, Div, Mul, Neg, Sub};

mod csv;
mod table;
pub use csv::HEADER as DENSITY_CSV_HEADER;
pub use table::DensityTable;

/// Default fog colour (linear RGB): the whitish grey of water-droplet fog.
pub const DEFAULT_COLOUR: [f32; 3] = [0.8, 0.8, 0.8];
/// Default single-scattering albedo: water droplets absorb almost nothing of visible
/// light (their albedo is above 0.99), so the whole extinction scatters.
pub const DEFAULT_ALBEDO: f64 = 1.0;
/// Default blur factor λ (px), paper 000's.
pub const DEFAULT_LAMBDA: f64 = super::haze::DEFAULT_LAMBDA;

/// The largest extinction optical depth the blur law takes: τ = e^(−10) ≈ 4.5e-5 is less
/// than a sixth of the smallest step of an 8-bit sRGB output, so beyond it nothing of the scene
/// is left to blur, while the depth itself may grow without bound (the exponential
/// profile below its base height). Caps σ (see the module docs).
pub const MAX_BLUR_OPTICAL_DEPTH: f64 = 10.0;

/// Below this value of h (the half-width of a height interval in units of the profile's
/// length scale) the means are summed as series; from it, by the library functions.
const SERIES_LIMIT: f64 = 1.0;

/// The largest exponent of the exponential profile: δ ≤ e^80·ρ keeps f32 finite (e^88
/// overflows), and a segment that dense is opaque long before.
const EXPONENT_CAP: f64 = 80.0;

/// Fog density δ(y) (per world unit) as a function of height y (world units, y up).
#[derive(Clone, Debug, PartialEq)]
pub enum HeightProfile {
    /// δ(y) = density·e^(−(y − base)/scale_height): fog thinning with height, as a city's
    /// or a valley's (paper 003, fig. 3). The exponent is capped at 80 so that the
    /// density stays finite far below `base`.
    Exponential {
        /// δ at `base` (per world unit, ≥ 0).
        density: f64,
        /// The height where δ = `density` (world units).
        base: f64,
        /// H: the rise over which δ falls by e (world units, > 0).
        scale_height: f64,
    },
    /// δ(y) = density·sin(π(y − base)/thickness) for base ≤ y ≤ base + thickness, 0
    /// outside: a band of mist just above water (paper 003, fig. 4), densest mid-band.
    SineBand {
        /// δ at the middle of the band (per world unit, ≥ 0).
        density: f64,
        /// The bottom of the band: the water level (world units).
        base: f64,
        /// The band's thickness T (world units, > 0).
        thickness: f64,
    },
    /// δ(y) = density for y ≤ floor, density·(top − y)/(top − floor) between, 0 above
    /// top: dry-ice fog indoors, densest on the floor (paper 003, fig. 5). Below `floor`
    /// it stays at `density` (fog pools in a pit) rather than dropping to 0, so that δ is
    /// continuous and a ray along the floor has one answer.
    LinearRamp {
        /// δ at and below `floor` (per world unit, ≥ 0).
        density: f64,
        /// The height where the ramp starts to thin (world units).
        floor: f64,
        /// The height where δ reaches 0 (world units, > floor).
        top: f64,
    },
    /// Any profile, as a table of heights and extinctions, linear between rows and
    /// constant beyond the ends (paper 003, sec. 3.2; see [`DensityTable`]).
    Table(DensityTable),
}

/// Values to set on an analytic [`HeightProfile`] ([`HeightProfile::with`]); `None` keeps
/// the profile's own.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ProfileValues {
    /// δ at the base (exponential), mid-band (band) or on the floor (ramp), per world unit.
    pub density: Option<f64>,
    /// The exponential's and the band's `base`, the ramp's `floor` (world units).
    pub base: Option<f64>,
    /// The exponential's scale height (world units).
    pub scale_height: Option<f64>,
    /// The band's thickness (world units).
    pub thickness: Option<f64>,
    /// The ramp's top (world units).
    pub top: Option<f64>,
}

impl HeightProfile {
    /// Default exponential profile: 0.01 /m at the ground (y = 0), scale height 20 m. From
    /// an eye at 1.7 m, τ ≈ 0.4 at 100 m and 2e-4 on the ground 900 m away; a
    /// ray rising 30° to the far plane at 1 km keeps τ ≈ 0.7.
    pub const EXPONENTIAL: HeightProfile = HeightProfile::Exponential {
        density: 0.01,
        base: 0.0,
        scale_height: 20.0,
    };

    /// Default sea mist: a 5 m band above water at y = 0, 0.01 /m mid-band. An eye at
    /// 1.7 m is inside it (δ ≈ 0.0088 /m: τ ≈ 0.4 at 100 m); anything above 5 m stands
    /// out of the mist.
    pub const SINE_BAND: HeightProfile = HeightProfile::SineBand {
        density: 0.01,
        base: 0.0,
        thickness: 5.0,
    };

    /// Default dry-ice fog: 1 /m on the floor (y = 0), thinning to nothing at knee height
    /// (1 m). From an eye at 1.7 m the floor 3 m away keeps τ ≈ 0.36 and the far floor
    /// vanishes, while whatever stands above 1 m stays clear.
    pub const LINEAR_RAMP: HeightProfile = HeightProfile::LinearRamp {
        density: 1.0,
        floor: 0.0,
        top: 1.0,
    };

    /// This profile with the values of `given` where they are set: `density`; `base` (a
    /// ramp's `floor`); `scale_height` (exponential), `thickness` (band) or `top` (ramp).
    /// A value the profile does not have is ignored, and a table is returned as it is:
    /// how `brume scene`'s flags and the Python keywords adjust a preset.
    pub fn with(self, given: &ProfileValues) -> HeightProfile {
        let or = |given: Option<f64>, preset: f64| given.unwrap_or(preset);
        match self {
            HeightProfile::Exponential {
                density,
                base,
                scale_height,
            } => HeightProfile::Exponential {
                density: or(given.density, density),
                base: or(given.base, base),
                scale_height: or(given.scale_height, scale_height),
            },
            HeightProfile::SineBand {
                density,
                base,
                thickness,
            } => HeightProfile::SineBand {
                density: or(given.density, density),
                base: or(given.base, base),
                thickness: or(given.thickness, thickness),
            },
            HeightProfile::LinearRamp {
                density,
                floor,
                top,
            } => HeightProfile::LinearRamp {
                density: or(given.density, density),
                floor: or(given.base, floor),
                top: or(given.top, top),
            },
            table @ HeightProfile::Table(_) => table,
        }
    }

    /// [`HeightProfile::with`], refusing a value the profile does not have (a band's
    /// `scale_height`, any value with a table) rather than ignoring it: the error names
    /// the value (`density`, `base`, `scale_height`, `thickness`, `top`) and what the
    /// profile has.
    pub fn with_checked(self, given: &ProfileValues) -> Result<HeightProfile> {
        let (kind, has): (&str, &[&str]) = match self {
            HeightProfile::Exponential { .. } => {
                ("exponential", &["density", "base", "scale_height"])
            }
            HeightProfile::SineBand { .. } => ("band", &["density", "base", "thickness"]),
            HeightProfile::LinearRamp { .. } => ("ramp", &["density", "base", "top"]),
            HeightProfile::Table(_) => ("table", &[]),
        };
        let values = [
            ("density", given.density),
            ("base", given.base),
            ("scale_height", given.scale_height),
            ("thickness", given.thickness),
            ("top", given.top),
        ];
        for (name, value) in values {
            if let Some(v) = value.filter(|_| !has.contains(&name)) {
                let what = match has {
                    [] => "nothing to set: its rows give the density at each height".to_string(),
                    _ => has.join(", "),
                };
                return Err(Error::invalid(
                    name,
                    v,
                    format!("no {name} with the {kind} profile (it has {what})"),
                ));
            }
        }
        Ok(self.with(given))
    }

    /// δ(y) (per world unit).
    pub fn density(&self, y: f64) -> f64 {
        mean_density(self, y, 0.0)
    }

    /// An antiderivative Iδ(y) of δ, continuous in y: the textbook F = l·(Iδ(y1) −
    /// Iδ(y0))/Δy. It cancels catastrophically for close limits, which
    /// [`HeightProfile::mean_density`] does not; kept as a cross-check.
    pub fn antiderivative(&self, y: f64) -> f64 {
        match *self {
            HeightProfile::Exponential {
                density,
                base,
                scale_height,
            } => -density * scale_height * (-(y - base) / scale_height).min(EXPONENT_CAP).exp(),
            HeightProfile::SineBand {
                density,
                base,
                thickness,
            } => {
                let u = (y.max(base).min(base + thickness) - base) / thickness;
                density * thickness / PI * (1.0 - (PI * u).cos())
            }
            HeightProfile::LinearRamp {
                density,
                floor,
                top,
            } => {
                let below = y.min(floor) - floor;
                // max/min rather than clamp: no panic on a profile not yet validated.
                let s = y.max(floor).min(top) - floor;
                density * (below + s - s * s / (2.0 * (top - floor)))
            }
            HeightProfile::Table(ref table) => table.integral(y),
        }
    }

    /// The mean of δ over the heights from `y0` to `y1` (either order); δ(y0) when they
    /// are equal. Accurate for any y1 − y0, 0 included (module docs).
    pub fn mean_density(&self, y0: f64, y1: f64) -> f64 {
        mean_density(self, y0, y1 - y0)
    }

    /// The optical depth F = ∫ δ dt along the segment from `from` to `to` (eq. 7-8).
    pub fn optical_depth(&self, from: DVec3, to: DVec3) -> f64 {
        (to - from).length() * mean_density(self, from.y, to.y - from.y)
    }

    /// The supremum of δ over all heights: ∞ for the exponential (it grows without bound
    /// below `base`, up to the exponent cap).
    pub fn max_density(&self) -> f64 {
        match *self {
            HeightProfile::Exponential { .. } => f64::INFINITY,
            HeightProfile::SineBand { density, .. } | HeightProfile::LinearRamp { density, .. } => {
                density
            }
            HeightProfile::Table(ref table) => table.max_density(),
        }
    }

    /// Rejects out-of-domain parameters, naming the parameter.
    pub fn validate(&self) -> Result<()> {
        let finite = |name: &str, v: f64| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(Error::invalid(name, v, "a finite height (world units)"))
            }
        };
        match *self {
            HeightProfile::Exponential {
                density,
                base,
                scale_height,
            } => {
                check_non_negative("density", density)?;
                finite("base", base)?;
                check_positive("scale_height", scale_height)
            }
            HeightProfile::SineBand {
                density,
                base,
                thickness,
            } => {
                check_non_negative("density", density)?;
                finite("base", base)?;
                check_positive("thickness", thickness)?;
                finite("top of the band (base + thickness)", base + thickness)
            }
            HeightProfile::LinearRamp {
                density,
                floor,
                top,
            } => {
                check_non_negative("density", density)?;
                finite("floor", floor)?;
                if top.is_finite() && top > floor {
                    Ok(())
                } else {
                    Err(Error::invalid(
                        "top",
                        top,
                        format!("a finite height above floor ({floor})"),
                    ))
                }
            }
            // Checked when it was built.
            HeightProfile::Table(_) => Ok(()),
        }
    }

    /// The shader's `u_profile` selector and `u_layer` parameters.
    fn uniform_values(&self) -> (f32, [f32; 3]) {
        let (selector, params) = match *self {
            HeightProfile::Exponential {
                density,
                base,
                scale_height,
            } => (0.0, [density, base, scale_height]),
            HeightProfile::SineBand {
                density,
                base,
                thickness,
            } => (1.0, [density, base, thickness]),
            HeightProfile::LinearRamp {
                density,
                floor,
                top,
            } => (2.0, [density, floor, top]),
            HeightProfile::Table(_) => (3.0, [0.0; 3]),
        };
        (selector, params.map(|v| v as f32))
    }
}

impl Default for HeightProfile {
    /// [`HeightProfile::EXPONENTIAL`].
    fn default() -> Self {
        HeightProfile::EXPONENTIAL
    }
}

/// The distance (world units) that counts as normalised range 1 in the blur law by
/// default: the default camera's far plane.
pub const DEFAULT_RANGE_UNIT: f64 = 1000.0;

/// Paper 003's layered fog as a medium of a rendered frame (module docs). It reads the
/// depth buffer through the camera each frame gives ([`FrameInputs`]).
#[derive(Clone, Debug, PartialEq)]
pub struct LayeredFog {
    /// The fog density as a function of height.
    pub profile: HeightProfile,
    /// The fog colour C_fog (linear RGB, each ≥ 0): the in-scattered light.
    pub colour: [f32; 3],
    /// The fraction of the extinction that scatters, in [0, 1]: only scattering blurs.
    pub albedo: f64,
    /// Blur factor λ ≥ 0 (px): σ = σ0 + λ·r·√Ds (module docs); 0 turns the blur off.
    pub lambda: f64,
    /// The distance (world units, > 0) that counts as normalised range 1 in the blur law
    /// ([`DEFAULT_RANGE_UNIT`]; [`LayeredFog::for_camera`] takes a camera's far plane).
    pub range_unit: f64,
}

impl LayeredFog {
    /// `profile` with the default colour, albedo, λ and range unit.
    pub fn new(profile: HeightProfile) -> Self {
        LayeredFog {
            profile,
            colour: DEFAULT_COLOUR,
            albedo: DEFAULT_ALBEDO,
            lambda: DEFAULT_LAMBDA,
            range_unit: DEFAULT_RANGE_UNIT,
        }
    }

    /// [`LayeredFog::new`] with the far plane of `camera` (an infinite projection's sky
    /// depth) as the range unit, so that σ reaches its largest value at the far plane.
    /// The camera is not kept: each frame gives its own.
    pub fn for_camera(camera: impl Into<FrameCamera>, profile: HeightProfile) -> Self {
        LayeredFog {
            range_unit: camera.into().max_depth(),
            ..LayeredFog::new(profile)
        }
    }

    /// The medium along the segment from the eye at `eye` to the world point `p`: what a
    /// pixel that sees `p` gets, whatever the camera's orientation.
    pub fn sample_point(&self, eye: DVec3, p: DVec3, sigma0: f64) -> MediumSample {
        let length = (p - eye).length();
        let mean = mean_density(&self.profile, eye.y, p.y - eye.y);
        let optical_depth = length * mean;
        let blur_depth =
            self.albedo * (mean * length.min(self.range_unit)).min(MAX_BLUR_OPTICAL_DEPTH);
        let tau = (-optical_depth).exp();
        MediumSample {
            transmission: [tau; 3],
            inscatter: self.colour.map(f64::from),
            sigma: blur_from_optical_depth(
                sigma0,
                self.lambda,
                length / self.range_unit,
                blur_depth,
            ),
        }
    }
}

impl Default for LayeredFog {
    /// The default exponential fog.
    fn default() -> Self {
        LayeredFog::new(HeightProfile::default())
    }
}

impl Medium for LayeredFog {
    fn name(&self) -> std::borrow::Cow<'static, str> {
        table::medium_name(&self.profile).into()
    }

    fn glsl(&self) -> std::borrow::Cow<'static, str> {
        table::medium_glsl(&self.profile).into()
    }

    fn uniforms(
        &self,
        _frame: &FrameInputs,
    ) -> Vec<(std::borrow::Cow<'static, str>, UniformValue)> {
        let (selector, layer) = self.profile.uniform_values();
        super::static_names(
            vec![
                ("u_profile", UniformValue::Float(selector)),
                ("u_layer", UniformValue::Vec3(layer)),
                ("u_fog_colour", UniformValue::Vec3(self.colour)),
                ("u_albedo", UniformValue::Float(self.albedo as f32)),
                ("u_lambda", UniformValue::Float(self.lambda as f32)),
                ("u_range_unit", UniformValue::Float(self.range_unit as f32)),
            ]
            .into_iter()
            .chain(table::profile_uniforms(&self.profile)),
        )
    }

    // The fog's colour, the same along every ray.
    fn uniform_inscatter(&self) -> bool {
        true
    }

    fn chromatic(&self) -> bool {
        false
    }

    fn sigma_max(&self, sigma0: f64) -> f64 {
        let depth = (self.profile.max_density() * self.range_unit).min(MAX_BLUR_OPTICAL_DEPTH);
        blur_from_optical_depth(sigma0, self.lambda, 1.0, self.albedo * depth)
    }

    fn sample(&self, p: Pixel, frame: &FrameInputs) -> MediumSample {
        let d = p.depth.clamp(0.0, 1.0);
        let camera = frame.camera_or_default().for_frame(p.width, p.height);
        let point = camera.world_position_by_inverse(p.x, p.y, p.width, p.height, d);
        self.sample_point(camera.eye(), point, p.sigma0)
    }

    fn validate(&self) -> Result<()> {
        self.profile.validate()?;
        if !self.colour.iter().all(|c| c.is_finite() && *c >= 0.0) {
            let [r, g, b] = self.colour;
            return Err(Error::invalid(
                "colour",
                format!("{r},{g},{b}"),
                "three finite linear values ≥ 0, e.g. 0.8,0.8,0.8",
            ));
        }
        if !(0.0..=1.0).contains(&self.albedo) {
            return Err(Error::invalid(
                "albedo",
                self.albedo,
                "a fraction in [0, 1]",
            ));
        }
        check_non_negative("lambda", self.lambda)?;
        check_positive("range_unit", self.range_unit)
    }

    fn needs_camera(&self) -> bool {
        true
    }

    fn lookups(&self) -> Vec<(std::borrow::Cow<'static, str>, super::Lookup)> {
        super::static_names(table::profile_lookups(&self.profile))
    }
}

/// The arithmetic of the density formulas, so that one body serves the f64 reference and,
/// in the tests, an f32 twin of the shader.
trait Real:
    Copy
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    fn of(v: f64) -> Self;
    fn to_f64(self) -> f64;
    fn exp(self) -> Self;
    fn sin(self) -> Self;
    fn abs(self) -> Self;
    fn min(self, other: Self) -> Self;
    fn max(self, other: Self) -> Self;
}

macro_rules! real {
    ($t:ty) => {
        impl Real for $t {
            fn of(v: f64) -> Self {
                v as $t
            }
            fn to_f64(self) -> f64 {
                self as f64
            }
            fn exp(self) -> Self {
                <$t>::exp(self)
            }
            fn sin(self) -> Self {
                <$t>::sin(self)
            }
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
            fn min(self, other: Self) -> Self {
                <$t>::min(self, other)
            }
            fn max(self, other: Self) -> Self {
                <$t>::max(self, other)
            }
        }
    };
}

real!(f32);
real!(f64);

/// GLSL's clamp (no panic when the bounds cross).
fn clamp<T: Real>(x: T, low: T, high: T) -> T {
    x.max(low).min(high)
}

/// sinh(h)/h for 0 ≤ h < 1, through h¹²: the next term is below 7.7e-13.
fn sinhc_series<T: Real>(h: T) -> T {
    let t = h * h;
    let one = T::of(1.0);
    let mut s = one + t / T::of(156.0);
    for k in [110.0, 72.0, 42.0, 20.0, 6.0] {
        s = one + t / T::of(k) * s;
    }
    s
}

/// sin(h)/h for 0 ≤ h < 1, through h¹².
fn sinc_series<T: Real>(h: T) -> T {
    let t = h * h;
    let one = T::of(1.0);
    let mut s = one - t / T::of(156.0);
    for k in [110.0, 72.0, 42.0, 20.0, 6.0] {
        s = one - t / T::of(k) * s;
    }
    s
}

/// The mean of δ over the heights from `y0` to `y0 + dy` (δ(y0) for dy = 0), in the
/// arithmetic of `T`: the formulas of the module docs, in the shader's order.
fn mean_density<T: Real>(profile: &HeightProfile, y0: T, dy: T) -> T {
    let (zero, half, one) = (T::of(0.0), T::of(0.5), T::of(1.0));
    let limit = T::of(SERIES_LIMIT);
    match *profile {
        HeightProfile::Exponential {
            density,
            base,
            scale_height,
        } => {
            let (rho, base, scale) = (T::of(density), T::of(base), T::of(scale_height));
            let cap = T::of(EXPONENT_CAP);
            let h = (dy * half).abs() / scale;
            if h < limit {
                let mid = y0 + dy * half;
                rho * (-(mid - base) / scale).min(cap).exp() * sinhc_series(h)
            } else {
                let low = y0 + dy.min(zero);
                let d = h + h;
                rho * (-(low - base) / scale).min(cap).exp() * ((one - (-d).exp()) / d)
            }
        }
        HeightProfile::SineBand {
            density,
            base,
            thickness,
        } => {
            let (rho, base, thickness) = (T::of(density), T::of(base), T::of(thickness));
            let y1 = y0 + dy;
            let (low, high) = (y0.min(y1), y0.max(y1));
            let top = base + thickness;
            let (a, b) = (clamp(low, base, top), clamp(high, base, top));
            // The phase of the overlap's mid-height, folded to [0, 1/2] so that sin is
            // taken near 0 at both edges: δ vanishes there to f32's last digit.
            let u = ((a + b) * half - base) / thickness;
            let u = u.min(one - u);
            let h = T::of(FRAC_PI_2) * (b - a) / thickness;
            let sinc = if h < limit {
                sinc_series(h)
            } else {
                h.sin() / h
            };
            let inside = if high > low {
                (b - a) / (high - low)
            } else if low >= base && low <= top {
                one
            } else {
                zero
            };
            rho * (T::of(PI) * u).sin() * sinc * inside
        }
        HeightProfile::LinearRamp {
            density,
            floor,
            top,
        } => {
            let (rho, floor, top) = (T::of(density), T::of(floor), T::of(top));
            let y1 = y0 + dy;
            let (low, high) = (y0.min(y1), y0.max(y1));
            if high > low {
                let below = high.min(floor) - low.min(floor);
                let (a, b) = (clamp(low, floor, top), clamp(high, floor, top));
                let ramp = (b - a) * ((top - (a + b) * half) / (top - floor));
                rho * ((below + ramp) / (high - low))
            } else {
                rho * clamp((top - low) / (top - floor), zero, one)
            }
        }
        HeightProfile::Table(ref table) => T::of(table.mean_density(y0.to_f64(), dy.to_f64())),
    }
}

#[cfg(test)]
mod tests;
