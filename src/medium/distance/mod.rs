//! Paper 001's distance fog (Gawron and Boryczka 2018, sec. 3.1-3.3 and Listing 1) as a
//! brume medium: a fog density that grows with the distance from the camera, varied by a
//! tiling noise texture that drifts with time, and a fog colour brightened toward a
//! directional light. The paper's own blur (a fixed 5x5 Gaussian, sec. 3.4) is replaced by
//! brume's diffusion blur, driven by the optical depth of the fog.
//!
//! The medium reads a **depth buffer**: the `depth` of each pixel is the window depth
//! d ∈ [0, 1] of the frame's camera ([`crate::camera::Camera`], OpenGL's standard
//! projection, or an engine's matrices, [`crate::camera::MatrixCamera`]: reversed-Z,
//! infinite far plane), which each frame gives with its time
//! ([`crate::camera::FrameInputs`]: one medium value fogs every frame). The far end of
//! the depth range is the far plane (the sky: nothing was drawn there), whose distance is
//! `far·|ray|` (an infinite projection's sky depth instead). Values outside [0, 1] are
//! clamped. The world position is rebuilt from d and the camera (paper 001 eq. 1; see
//! [`crate::camera`]): on the GPU by the eye-to-fragment ray times the linear eye depth
//! (`brume_eye_depth`, precise to a few f32 ulps at any distance, which the noise needs:
//! see [`crate::camera::Camera::shader_depth_constants`]), on the CPU
//! reference by the inverse matrices.
//!
//! # The model, and where it departs from the paper
//!
//! With `p` the eye-to-point vector and `l = |p|` (eq. 1, Euclidean: fog on a sphere about
//! the camera, the paper's fig. 2):
//!
//! ```text
//! dist     = max((l − start_distance) / distance, 0)^exponent                (eq. 2)
//! noise    = NoiseTex((P.x + speed.x·time) / size, (P.z + speed.z·time) / size)  (Listing 1)
//! factor   = low + (high − low)·noise       (eq. 9; 1 without a noise texture, eq. 3)
//! F        = clamp(dist·factor, 0, max_density)                              (Listing 1)
//! scatter  = saturate(p̂ · L)^scatter_exponent · saturate((l − scatter_start) / l)
//! tint     = 1 + colour_strength·(2·noise − 1)   (sec. 3.3; 1 without a noise texture)
//! C_fog'   = (colour + scatter_colour·scatter)·tint                           (eq. 8)
//! C        = lerp(C_scene, C_fog', F)                                         (eq. 4)
//! ```
//!
//! where P is the world position and L the unit vector toward the light. The equations
//! and the listing disagree in places; this module follows:
//!
//! - **Start distance (eq. 2 vs Listing 1).** Eq. 2 subtracts `StartDistance`, the
//!   listing adds an `Offset`; the equation is followed (a positive start pushes the fog
//!   away). The base is clamped at 0 before the power: inside the start distance there is
//!   no fog, rather than the NaN of a negative number to a fractional power.
//! - **The cap (eq. 3/10 vs Listing 1).** Eq. 3 writes `max(dist, FogDensity)` but calls
//!   FogDensity "the max value of fog density"; with `max` the fog would never be thinner
//!   than it, however close. The listing's `clamp(0, MaxDensity, density)` (HLSL argument
//!   order `clamp(x, min, max)`, so literally `min(max(0, MaxDensity), density)`) is
//!   `min(density, MaxDensity)` for the non-negative values here: the listing is
//!   followed, `F = clamp(dist·factor, 0, max_density)`.
//! - **Noise (eq. 9-10 and Listing 1).** The listing multiplies the density by
//!   `lerp(Low, Max, noise)`, the noise read at `(WorldPos + NoiseSpeed·Time)/NoiseSize`
//!   through `.xy`. Unreal's z is up, so `.xy` is the horizontal plane; brume's world is
//!   y-up, so the noise is read at the (x, z) components, and `speed[1]` (vertical) has
//!   no effect, as the listing's `NoiseSpeed.z` has none. The noise's red channel is used
//!   (`.x`). Without a noise texture the factor is 1 (eq. 3); with one it is about
//!   `(low + high)/2` on average (the generated noise has mean ½), so switching the noise
//!   off thickens the fog by about 1/0.15 ≈ 6.7 at the defaults.
//! - **Scattering start (eq. 5 and Listing 1).** Eq. 5 adds the scalar `ScatterStartDist`
//!   to the vector `WorldPos − CameraPos`; HLSL broadcasts it, adding it to every world
//!   component, which tilts near points' directions toward the world diagonal (1, 1, 1):
//!   a result that depends on the world's axes, not on the view. Pushing the point
//!   `ScatterStartDist` further along its own ray, the other literal reading, leaves its
//!   direction unchanged and the parameter without effect. brume reads it as Unreal's
//!   exponential height fog reads its "directional inscattering start distance", which
//!   the paper's parameters mirror (its fig. 5 compares with that fog): only the part of
//!   the path beyond `scatter_start` scatters toward the light, a fraction
//!   `saturate((l − scatter_start)/l)` of it. Near surfaces keep the plain fog colour,
//!   the sky gets the full glow.
//! - **Direction (eq. 6-7).** `p̂` is the direction of the pixel's ray, `saturate` (the
//!   listing) and `max(0, ·)` (eq. 7) agree for a unit vector.
//!
//! # As a brume medium
//!
//! Per pixel: transmission τ = 1 − F (grey), in-scattered light L∞ = C_fog' (so the
//! composite τ·E + (1 − τ)·L∞ is eq. 4 exactly when nothing is blurred), and the blur
//! scale σ = σ0 + λ·r·√Ds from the optical depth of that transmission, Ds = −ln(1 − F),
//! all of it treated as scattering (the paper has no absorption: its fog only veils), over
//! the normalised distance r = l/range_unit ([`super::blur_from_optical_depth`]). The
//! paper ties its blur to the fog density; this is that tie with brume's blur law.
//!
//! # Units and defaults
//!
//! Listing 1's example values are in Unreal units (centimetres), and its density is
//! multiplied by the noise factor (0.12..0.18). Read as metres, the listing's
//! `Distance = 1000` gives a mean density of 0.006 at 3 m and 0.14 at 900 m: barely any
//! fog in a metre-scale scene. Converted to metres (`Distance = 10 m`) the fog reaches
//! the 0.5 cap by 90 m and everything beyond is one flat veil. brume's defaults are in
//! metres for a camera at eye height looking over 3-900 m: [`DEFAULT_DISTANCE`] = 100 m,
//! so that with the noise's mean factor 0.15 the density grows over the whole range
//! (0.02 at 3 m, 0.15 at 100 m, 0.27 at 300 m) and reaches the cap near the far plane,
//! 1000 m. Lengths of the listing are converted from centimetres (scatter start 10 m,
//! noise tile 100 m, noise speed (2, 0.25) m/s); exponents, densities and colours are the
//! listing's.

use std::path::Path;
use std::sync::OnceLock;

use glam::DVec3;

use super::lookup::{Lookup, Wrap};
use super::noise::{self, TilingNoise};
use super::{blur_from_optical_depth, Medium, MediumSample, Pixel, UniformValue};
use crate::camera::FrameInputs;
use crate::error::{check_non_negative, check_positive, Error, Result};

/// The paper's `StartDistance` (Listing 1: 0).
pub const DEFAULT_START_DISTANCE: f64 = 0.0;
/// Blend distance (m). Listing 1 has 1000 Unreal units (10 m); see the module docs.
pub const DEFAULT_DISTANCE: f64 = 100.0;
/// Falloff exponent (Listing 1: 0.55).
pub const DEFAULT_EXPONENT: f64 = 0.55;
/// The density cap (Listing 1's `MaxDensity`: 0.5).
pub const DEFAULT_MAX_DENSITY: f64 = 0.5;
/// Fog colour, linear RGB (Listing 1's `FogColor`).
pub const DEFAULT_COLOUR: [f32; 3] = [0.45, 0.64, 1.0];
/// Toward the light: ahead of the default camera (which looks along −z), a little to its
/// right and above the horizon, so that the default view shows the glow. Listing 1 gives
/// no light.
pub const DEFAULT_LIGHT_DIRECTION: [f64; 3] = [0.3, 0.2, -1.0];
/// Scattering start distance (m). Listing 1: 1000 Unreal units = 10 m.
pub const DEFAULT_SCATTER_START: f64 = 10.0;
/// Scattering falloff exponent (Listing 1: 4).
pub const DEFAULT_SCATTER_EXPONENT: f64 = 4.0;
/// Scattering colour, linear RGB (Listing 1's `ScatterColor`).
pub const DEFAULT_SCATTER_COLOUR: [f32; 3] = [1.0, 0.65, 0.28];
/// Diffusion blur factor λ (px), as [`crate::medium::haze::DEFAULT_LAMBDA`].
pub const DEFAULT_LAMBDA: f64 = 8.0;
/// The distance (m) that counts as 1 in the blur law: the default camera's far plane.
pub const DEFAULT_RANGE_UNIT: f64 = 1000.0;
/// Noise drift (m/s, world x, y, z). Listing 1: (200, 25, 0) Unreal units/s, z up, so
/// (2, 0.25) m/s horizontally: on brume's x and z; y (vertical) has no effect.
pub const DEFAULT_NOISE_SPEED: [f64; 3] = [2.0, 0.0, 0.25];
/// World size of one noise tile (m). Listing 1: 10000 Unreal units = 100 m.
pub const DEFAULT_NOISE_SIZE: f64 = 100.0;
/// Density factor where the noise is 0 (Listing 1's `LowNoiseDensity`).
pub const DEFAULT_NOISE_LOW: f64 = 0.12;
/// Density factor where the noise is 1 (Listing 1's `MaxNoiseDensity`).
pub const DEFAULT_NOISE_HIGH: f64 = 0.18;
/// How much the noise varies the in-scattered colour: none, so that a fog without the
/// option renders as before (see [`FogNoise::colour_factor`]).
pub const DEFAULT_NOISE_COLOUR_STRENGTH: f64 = 0.0;

/// The noise that varies the fog's density (paper 001, sec. 3.3, eq. 9-10).
#[derive(Clone, Debug)]
pub struct FogNoise {
    /// The noise texture, values in [0, 1]; it must tile ([`Wrap::Repeat`]): the world is
    /// larger than one tile.
    pub lookup: Lookup,
    /// Drift of the noise (world units per unit of [`FrameInputs::time`]); only x and z
    /// count (the texture covers the horizontal plane).
    pub speed: [f64; 3],
    /// World units per noise tile (> 0).
    pub size: f64,
    /// Density factor where the noise is 0 (≥ 0).
    pub low: f64,
    /// Density factor where the noise is 1 (≥ 0).
    pub high: f64,
    /// How strongly the same noise varies the in-scattered colour, s in [0, 1]: the fog
    /// colour C_fog' is multiplied by 1 + s·(2·noise − 1) (paper 001, sec. 3.3: "the
    /// noise ... is used to manipulate the density and color of fog"; the paper gives no
    /// formula, see [`FogNoise::colour_factor`]). 0 leaves the colour alone.
    pub colour_strength: f64,
}

impl Default for FogNoise {
    /// [`TilingNoise::default`] (256 px, seed 0), generated once per process and shared,
    /// so that the GPU uploads it once, with Listing 1's parameters in metres.
    fn default() -> Self {
        static DEFAULT: OnceLock<Lookup> = OnceLock::new();
        let lookup = DEFAULT
            .get_or_init(|| {
                TilingNoise::default()
                    .lookup()
                    .expect("the default noise recipe is valid")
            })
            .clone();
        FogNoise::with_lookup(lookup)
    }
}

impl FogNoise {
    /// `lookup` with the default drift, tile size and density factors.
    pub fn with_lookup(lookup: Lookup) -> Self {
        FogNoise {
            lookup,
            speed: DEFAULT_NOISE_SPEED,
            size: DEFAULT_NOISE_SIZE,
            low: DEFAULT_NOISE_LOW,
            high: DEFAULT_NOISE_HIGH,
            colour_strength: DEFAULT_NOISE_COLOUR_STRENGTH,
        }
    }

    /// A generated tiling noise ([`TilingNoise::new`]: periodic Perlin fBm) of `size_px`
    /// texels per side from `seed`, with the default parameters.
    pub fn generate(size_px: usize, seed: u64) -> Result<Self> {
        Ok(FogNoise::with_lookup(
            TilingNoise::new(size_px, seed).lookup()?,
        ))
    }

    /// A noise texture from a grey or RGB PNG of 8 or 16 bits (see [`noise::load_png`]),
    /// tiling, with the default parameters.
    pub fn from_png(path: &Path) -> Result<Self> {
        let (w, h, values) = noise::load_png(path)?;
        let lookup = Lookup::new(w, h, values, Wrap::Repeat)
            .map_err(|e| Error::format(path, format!("not usable as a noise texture: {e}")))?;
        Ok(FogNoise::with_lookup(lookup))
    }

    /// The texture coordinates of world position `world` at `time` (Listing 1's
    /// `(WorldPosition + NoiseSpeed·Time)/NoiseSize`, horizontal components).
    pub fn coordinates(&self, world: DVec3, time: f64) -> (f64, f64) {
        (
            (world.x + self.speed[0] * time) / self.size,
            (world.z + self.speed[2] * time) / self.size,
        )
    }

    /// The density factor at `world` and `time`: `lerp(low, high, noise)` (eq. 9).
    pub fn factor(&self, world: DVec3, time: f64) -> f64 {
        let (u, v) = self.coordinates(world, time);
        let n = self.lookup.sample(u, v);
        self.low + (self.high - self.low) * n
    }

    /// The factor on the in-scattered colour at `world` and `time`: 1 + s·(2·noise − 1)
    /// with s = [`FogNoise::colour_strength`], the noise read where the density's is. Where
    /// the noise is dense the veil is brighter (more droplets scatter more light), where it
    /// is thin darker, by up to ±s; its mean over a tile is 1 for a noise of mean ½, so
    /// the fog's average colour is kept. In [0, 2] for s in [0, 1].
    pub fn colour_factor(&self, world: DVec3, time: f64) -> f64 {
        let (u, v) = self.coordinates(world, time);
        let n = self.lookup.sample(u, v);
        1.0 + self.colour_strength * (2.0 * n - 1.0)
    }

    fn validate(&self) -> Result<()> {
        if !self.speed.iter().all(|v| v.is_finite()) {
            let [x, y, z] = self.speed;
            return Err(Error::invalid(
                "noise speed",
                format!("{x},{y},{z}"),
                "three finite numbers (world units per unit of time)",
            ));
        }
        check_positive("noise size", self.size)?;
        check_non_negative("noise low", self.low)?;
        check_non_negative("noise high", self.high)?;
        if !(0.0..=1.0).contains(&self.colour_strength) {
            return Err(Error::invalid(
                "noise colour strength",
                self.colour_strength,
                "a strength in [0, 1] (0: the noise leaves the fog colour alone)",
            ));
        }
        if self.lookup.wrap() != Wrap::Repeat {
            return Err(Error::invalid(
                "noise lookup",
                "clamped to its edges",
                "a tiling lookup (Wrap::Repeat)",
            ));
        }
        Ok(())
    }
}

/// Paper 001's distance fog with scattering toward a light and drifting noise (see the
/// module docs for the formulas and the units). It reads the depth buffer through the
/// camera each frame gives, and moves its noise by the frame's time ([`FrameInputs`]).
#[derive(Clone, Debug)]
pub struct DistanceFog {
    /// Distance from the camera where the fog starts (world units).
    pub start_distance: f64,
    /// Blend distance (> 0): the distance beyond the start where `dist` reaches 1.
    pub distance: f64,
    /// Falloff exponent of the distance ramp (> 0).
    pub exponent: f64,
    /// The largest fog density F, in [0, 1) (paper: `FogDensity`, "the max value of fog
    /// density"; Listing 1: `MaxDensity`). 1 would be opaque fog, of infinite optical depth.
    pub max_density: f64,
    /// Fog colour, linear RGB.
    pub colour: [f32; 3],
    /// Toward the light (world; normalised on use, non-zero).
    pub light_direction: [f64; 3],
    /// Distance beyond which the fog scatters the light's colour (world units, ≥ 0).
    pub scatter_start: f64,
    /// Falloff exponent of the scattering lobe (> 0).
    pub scatter_exponent: f64,
    /// Scattering colour, linear RGB, added to the fog colour toward the light.
    pub scatter_colour: [f32; 3],
    /// The density noise, or `None` for a uniform fog (eq. 3).
    pub noise: Option<FogNoise>,
    /// Diffusion blur factor λ ≥ 0 (px): σ = σ0 + λ·r·√(−ln(1 − F)).
    pub lambda: f64,
    /// The distance that counts as 1 in the blur law (> 0, world units).
    pub range_unit: f64,
}

impl Default for DistanceFog {
    fn default() -> Self {
        DistanceFog {
            start_distance: DEFAULT_START_DISTANCE,
            distance: DEFAULT_DISTANCE,
            exponent: DEFAULT_EXPONENT,
            max_density: DEFAULT_MAX_DENSITY,
            colour: DEFAULT_COLOUR,
            light_direction: DEFAULT_LIGHT_DIRECTION,
            scatter_start: DEFAULT_SCATTER_START,
            scatter_exponent: DEFAULT_SCATTER_EXPONENT,
            scatter_colour: DEFAULT_SCATTER_COLOUR,
            noise: Some(FogNoise::default()),
            lambda: DEFAULT_LAMBDA,
            range_unit: DEFAULT_RANGE_UNIT,
        }
    }
}

/// The fog at one point, before it meets the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FogPoint {
    /// Density F in [0, max_density] (eq. 10 with Listing 1's cap).
    pub density: f64,
    /// Fog colour brightened toward the light, C_fog' (eq. 8).
    pub colour: [f64; 3],
    /// Distance from the eye (world units).
    pub distance: f64,
}

impl DistanceFog {
    /// The unit vector toward the light.
    pub fn light(&self) -> DVec3 {
        DVec3::from_array(self.light_direction).normalize()
    }

    /// `dist` of eq. 2 at distance `l` from the eye.
    pub fn distance_ramp(&self, l: f64) -> f64 {
        ((l - self.start_distance) / self.distance)
            .max(0.0)
            .powf(self.exponent)
    }

    /// The fog at world position `world` seen from `eye` at `time` (eq. 1-10, module
    /// docs).
    pub fn at(&self, eye: DVec3, world: DVec3, time: f64) -> FogPoint {
        let to = world - eye;
        let l = to.length();
        let factor = self.noise.as_ref().map_or(1.0, |n| n.factor(world, time));
        let density = (self.distance_ramp(l) * factor).clamp(0.0, self.max_density);
        let towards = to.normalize_or_zero().dot(self.light()).clamp(0.0, 1.0);
        let beyond = if l > 0.0 {
            ((l - self.scatter_start) / l).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let scatter = towards.powf(self.scatter_exponent) * beyond;
        let tint = self
            .noise
            .as_ref()
            .map_or(1.0, |n| n.colour_factor(world, time));
        let colour = std::array::from_fn(|c| {
            (f64::from(self.colour[c]) + f64::from(self.scatter_colour[c]) * scatter) * tint
        });
        FogPoint {
            density,
            colour,
            distance: l,
        }
    }

    /// The optical depth of a fog of density `f`: −ln(1 − F).
    fn optical_depth(f: f64) -> f64 {
        -(-f).ln_1p()
    }
}

/// A 1x1 tiling texture bound under the noise sampler when there is no noise: the program
/// is compiled once per GLSL with the sampler's name among its uniforms, so the
/// name must always be there; the shader never reads it (`u_noise_on` = 0).
fn placeholder_noise() -> Lookup {
    static PLACEHOLDER: OnceLock<Lookup> = OnceLock::new();
    PLACEHOLDER
        .get_or_init(|| Lookup::new(1, 1, vec![0.5], Wrap::Repeat).expect("a 1x1 table"))
        .clone()
}

/// The name of the noise sampler in `glsl/medium/distance.glsl`.
const NOISE_SAMPLER: &str = "u_noise";

impl Medium for DistanceFog {
    fn name(&self) -> std::borrow::Cow<'static, str> {
        "distance".into()
    }

    fn glsl(&self) -> std::borrow::Cow<'static, str> {
        include_str!("../../../glsl/medium/distance.glsl").into()
    }

    fn uniforms(&self, frame: &FrameInputs) -> Vec<(std::borrow::Cow<'static, str>, UniformValue)> {
        let f = |v: f64| v as f32;
        // The noise's origin, eye and drift together, is reduced to one tile in f64 here:
        // the shader adds only the eye-to-point offset, so that neither a far-off camera
        // nor a long time costs f32 precision in the texture coordinates.
        let (noise_on, origin, scale, range, colour_strength) = match &self.noise {
            Some(n) => {
                let (u, v) = n.coordinates(frame.camera_or_default().eye(), frame.time);
                (
                    1.0,
                    [f(u.rem_euclid(1.0)), f(v.rem_euclid(1.0))],
                    f(1.0 / n.size),
                    [f(n.low), f(n.high)],
                    f(n.colour_strength),
                )
            }
            None => (0.0, [0.0; 2], 0.0, [1.0; 2], 0.0),
        };
        super::static_names(vec![
            (
                "u_fog_shape",
                UniformValue::Vec3([
                    f(self.start_distance),
                    f(1.0 / self.distance),
                    f(self.exponent),
                ]),
            ),
            ("u_max_density", UniformValue::Float(f(self.max_density))),
            ("u_fog_colour", UniformValue::Vec3(self.colour)),
            (
                "u_light",
                UniformValue::Vec3(self.light().as_vec3().to_array()),
            ),
            (
                "u_scatter",
                UniformValue::Vec2([f(self.scatter_start), f(self.scatter_exponent)]),
            ),
            ("u_scatter_colour", UniformValue::Vec3(self.scatter_colour)),
            ("u_noise_on", UniformValue::Float(noise_on)),
            ("u_noise_origin", UniformValue::Vec2(origin)),
            ("u_noise_scale", UniformValue::Float(scale)),
            ("u_noise_range", UniformValue::Vec2(range)),
            ("u_noise_colour", UniformValue::Float(colour_strength)),
            (
                "u_blur",
                UniformValue::Vec2([f(self.lambda), f(1.0 / self.range_unit)]),
            ),
        ])
    }

    fn chromatic(&self) -> bool {
        false
    }

    fn sigma_max(&self, sigma0: f64) -> f64 {
        blur_from_optical_depth(
            sigma0,
            self.lambda,
            1.0,
            Self::optical_depth(self.max_density),
        )
    }

    fn sample(&self, p: Pixel, frame: &FrameInputs) -> MediumSample {
        let d = p.depth.clamp(0.0, 1.0);
        let camera = frame.camera_or_default().for_frame(p.width, p.height);
        let world = camera.world_position_by_inverse(p.x, p.y, p.width, p.height, d);
        let fog = self.at(camera.eye(), world, frame.time);
        let tau = 1.0 - fog.density;
        MediumSample {
            transmission: [tau; 3],
            inscatter: fog.colour,
            sigma: blur_from_optical_depth(
                p.sigma0,
                self.lambda,
                fog.distance / self.range_unit,
                Self::optical_depth(fog.density),
            ),
        }
    }

    fn validate(&self) -> Result<()> {
        if !self.start_distance.is_finite() {
            return Err(Error::invalid(
                "start_distance",
                self.start_distance,
                "a finite distance",
            ));
        }
        check_positive("distance", self.distance)?;
        check_positive("exponent", self.exponent)?;
        if !(self.max_density.is_finite() && (0.0..1.0).contains(&self.max_density)) {
            return Err(Error::invalid(
                "max_density",
                self.max_density,
                "a density in [0, 1) (1 is opaque fog: infinite optical depth and blur)",
            ));
        }
        check_colour("colour", self.colour)?;
        let light = DVec3::from_array(self.light_direction);
        if !(light.is_finite() && light.length() > 0.0) {
            let [x, y, z] = self.light_direction;
            return Err(Error::invalid(
                "light_direction",
                format!("{x},{y},{z}"),
                "a finite, non-zero vector toward the light",
            ));
        }
        check_non_negative("scatter_start", self.scatter_start)?;
        check_positive("scatter_exponent", self.scatter_exponent)?;
        check_colour("scatter_colour", self.scatter_colour)?;
        if let Some(n) = &self.noise {
            n.validate()?;
        }
        check_non_negative("lambda", self.lambda)?;
        check_positive("range_unit", self.range_unit)
    }

    fn needs_camera(&self) -> bool {
        true
    }

    fn lookups(&self) -> Vec<(std::borrow::Cow<'static, str>, super::Lookup)> {
        let lookup = match &self.noise {
            Some(n) => n.lookup.clone(),
            None => placeholder_noise(),
        };
        super::static_names(vec![(NOISE_SAMPLER, lookup)])
    }
}

fn check_colour(name: &str, c: [f32; 3]) -> Result<()> {
    if c.iter().all(|v| v.is_finite() && *v >= 0.0) {
        Ok(())
    } else {
        Err(Error::invalid(
            name,
            format!("{},{},{}", c[0], c[1], c[2]),
            "three finite linear values ≥ 0",
        ))
    }
}

#[cfg(test)]
mod tests;
