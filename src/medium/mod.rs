//! Media: what a fog model gives the pipeline, per pixel. A medium is one GLSL file plus
//! its CPU reference, side by side in this folder; the diffusion blur ([`crate::blur`],
//! [`crate::schedule`]) takes the medium's blur scale σ and knows nothing else of it.
//!
//! Per pixel, from the colour and the depth (or range) texture, a medium gives
//!
//! - the **transmission** τ (RGB: paper 002 attenuates each channel differently),
//! - the **in-scattered light** L∞ (RGB: a constant airlight, a sky colour by view
//!   direction, a fog colour brightened toward the sun …),
//! - the **blur scale** σ (px) that the diffusion blur reaches at that pixel.
//!
//! The image is then `F = τ·E` pre-multiplied, diffused to σ(x), and composited as
//! `F + (1 − τ_blurred)·L∞` (paper 000, eq. 2-4), τ blurred with the colour as the paper
//! does (see [`crate::pipeline`] for how an RGB τ travels through the blur, and for the
//! cheaper equivalent it runs when L∞ is the same at every pixel,
//! [`Medium::uniform_inscatter`]).
//!
//! # The blur law of a general medium
//!
//! Paper 000 eq. 6 is the small-angle beam spread of a homogeneous medium: a ray scattered
//! at distance t from the camera lands (R − t)·θ off its target at range R, so the lateral
//! variance is proportional to ∫₀^R κs(t)·(R − t)² dt = κs·R³/3. brume's law for any
//! medium, in the normalised units of paper 000 (R ∈ [0, 1], κs per unit of that range):
//!
//! ```text
//! σ(x) = σ0 + λ·√S(x),   S(x) = 3·∫₀^R(x) κs(t)·(R(x) − t)² dt     (the spread moment)
//! ```
//!
//! For a homogeneous medium S = κs·R³, so σ = σ0 + λ·√κs·R^(3/2) = σ0 + R^(3/2)(σmax − σ0)
//! with σmax = σ0 + λ·√κs: paper 000's eq. 7 exactly. [`blur_scale`] and [`spread_moment`]
//! implement it; the test below checks the reduction by quadrature.
//!
//! # Adding a medium
//!
//! 1. `glsl/medium/NAME.glsl` defines `MediumSample medium_sample(ivec2 pixel, float depth)`
//!    (the struct and the pipeline's uniforms `brume_sigma0` and `brume_size` are declared
//!    before it, see `glsl/medium_api.glsl`), with its own uniforms.
//! 2. `src/medium/NAME.rs` implements [`Medium`]: the same function on the CPU in f64
//!    ([`Medium::sample`]), the uniform values, the largest σ, whether τ is chromatic, and
//!    whether L∞ is the same at every pixel ([`Medium::uniform_inscatter`]: a third less
//!    time per diffusion step on llvmpipe when it is).
//! 3. A test renders it on the GPU and compares with the CPU reference
//!    (`tests/gpu_vs_cpu.rs` shows how).
//!
//! # Per-frame inputs
//!
//! A medium is the fog's description: the same value renders any number of frames. What
//! changes every frame, the camera and the time, comes with the frame as a
//! [`FrameInputs`] (the pipeline's [`crate::Input::frame`], an argument of
//! [`crate::Renderer::render_fog`] and of the CPU reference), and reaches the medium
//! through [`Medium::uniforms`] and [`Medium::sample`]; nothing is rebuilt or recompiled
//! between frames. A medium that reads a rendered frame's depth buffer says so by
//! [`Medium::needs_camera`]: the entry points then refuse a frame without a camera
//! ([`crate::Error::MissingCamera`]), and set its GLSL's `brume_ray` and
//! `brume_eye_depth` from the frame's camera (brume's [`crate::camera::Camera`], or an
//! engine's view and projection matrices as they are: [`crate::camera::MatrixCamera`];
//! see `glsl/medium_api.glsl`); its CPU side rebuilds positions by
//! [`crate::camera::MatrixCamera::world_position_by_inverse`] (`layered/`, `distance/`).
//! A medium whose geometry is its own (the aerial perspective of one photo) returns its
//! camera from [`Medium::frame_camera`] instead. A medium that samples a table (a noise,
//! a precomputed integral) returns it from [`Medium::lookups`].
//!
//! # Media defined at run time
//!
//! Names, GLSL and uniform names are `Cow<'static, str>`: brume's media borrow their
//! files, a user's medium (Python, an engine's material editor) owns text it built. The
//! pipeline keys its programs by the GLSL text itself (a 128-bit hash), so a medium's
//! name is only for messages, and two media of one name never share a program.
//! [`UniformValue`] has floats, vectors, a `mat3` and integers (`int`, `ivec2..4`).
//!
//! The pipeline compiles the medium's GLSL into the first pass (which writes τ·E, τ and the
//! per-pixel diffusion rate) and into the last (which adds (1 − τ_blurred)·L∞), so a medium
//! never writes a texture of its own.

pub mod aerial;
pub mod distance;
pub mod haze;
pub mod layered;
pub mod lookup;
pub mod noise;
pub mod physical;
pub mod uniform;

pub use aerial::AerialPerspective;
pub use distance::{DistanceFog, FogNoise};
pub use haze::Haze;
pub use layered::{DensityTable, HeightProfile, LayeredFog, ProfileValues};
pub use lookup::{Lookup, Wrap};
pub use physical::PhysicalFog;
pub use uniform::UniformBlur;

use crate::camera::{FrameCamera, FrameInputs};
use crate::error::Result;
use std::borrow::Cow;

/// GLSL declarations every medium's shader sees before its own source: the
/// [`MediumSample`] struct and the pipeline's uniforms.
pub const MEDIUM_API_GLSL: &str = include_str!("../../glsl/medium_api.glsl");

/// What a medium gives at one pixel (f64: the CPU reference).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MediumSample {
    /// Transmission τ per channel, in [0, 1].
    pub transmission: [f64; 3],
    /// In-scattered light L∞ per channel (linear RGB).
    pub inscatter: [f64; 3],
    /// Blur scale σ (px), ≥ σ0.
    pub sigma: f64,
}

/// One pixel as a medium sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pixel {
    /// Column, 0 at the first texel of a row.
    pub x: usize,
    /// Row, 0 at the first row of the texture: the bottom of the image, as GL stores it
    /// ([`crate::Renderer`] uploads buffers stored top row first upside down).
    pub y: usize,
    /// Image width (px).
    pub width: usize,
    /// Image height (px).
    pub height: usize,
    /// The value of the depth or range texture at this pixel (its `.r`).
    pub depth: f64,
    /// The inner scale σ0 of the blur (px).
    pub sigma0: f64,
}

/// A uniform value a shader takes (a medium's, or the pipeline's own).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum UniformValue {
    /// `float`.
    Float(f32),
    /// `vec2`.
    Vec2([f32; 2]),
    /// `vec3`.
    Vec3([f32; 3]),
    /// `vec4`.
    Vec4([f32; 4]),
    /// `int` (or `bool`: GL sets a bool uniform from an int).
    Int(i32),
    /// `ivec2`.
    IVec2([i32; 2]),
    /// `ivec3`.
    IVec3([i32; 3]),
    /// `ivec4`.
    IVec4([i32; 4]),
    /// `mat3`, column-major.
    Mat3([f32; 9]),
}

/// A fog model: per pixel a transmission, an in-scattered light and a blur scale, on the
/// GPU (GLSL) and on the CPU (f64 reference). See the module docs for the contract.
pub trait Medium {
    /// A short name, for messages (shader errors, a misspelled uniform). Not a key: the
    /// program cache is keyed by the GLSL itself, so two media of one name with different
    /// GLSL get their own programs. Need not be static: a medium can be defined at run
    /// time (a Python or engine user's).
    fn name(&self) -> Cow<'static, str>;

    /// The GLSL source defining `MediumSample medium_sample(ivec2 pixel, float depth)`:
    /// a file of brume's (`Cow::Borrowed(include_str!(…))`) or text built at run time.
    fn glsl(&self) -> Cow<'static, str>;

    /// The values of the uniforms the GLSL declares for `frame`, set before each pass
    /// that uses it. The names must not depend on the frame (the pipeline lists them
    /// once, when it compiles the program); a medium that needs a camera and is asked
    /// with none uses the default camera's values (the entry points refuse such a frame
    /// before they draw, [`Medium::validate_frame`]).
    fn uniforms(&self, frame: &FrameInputs) -> Vec<(Cow<'static, str>, UniformValue)>;

    /// Whether τ can differ between channels. A grey medium's τ travels in the alpha of
    /// the pre-multiplied colour; a chromatic one adds a second target (see
    /// [`crate::pipeline`]), unless its in-scattered light is uniform
    /// ([`Medium::uniform_inscatter`]).
    fn chromatic(&self) -> bool;

    /// Whether the in-scattered light L∞ is the same at every pixel of a frame (it may
    /// change from frame to frame). The pipeline then diffuses τ·(E − L∞) with ρ in its
    /// alpha, one RGBA target, and composites L∞ + the result: the same image as
    /// F = (τ·E, τ) diffused and composited as `F + (1 − τ_blurred)·L∞` (the diffusion is
    /// linear and L∞ a constant), with half the texture fetches per step and no second
    /// target for a chromatic τ (see [`crate::pipeline`]). A medium that says so while its
    /// L∞ varies renders wrong wherever the blur mixes pixels of different L∞. The
    /// default, no, is always right.
    fn uniform_inscatter(&self) -> bool {
        false
    }

    /// The largest σ any pixel can ask for (px), given the inner scale σ0: it sets the
    /// number of diffusion steps.
    fn sigma_max(&self, sigma0: f64) -> f64;

    /// A lower bound on the σ every pixel asks for (px), given the inner scale σ0. The
    /// coarse stage ([`crate::Blur::coarse_from`]) starts at step 0 when it is at least
    /// [`crate::schedule::STEP0_COARSE_SIGMA`], as for a uniform blur
    /// ([`crate::schedule::Schedule::coarse_start_above`]). The default, σ0, promises
    /// nothing: a medium whose σ follows the range has pixels at σ0 wherever the range is
    /// 0. A bound above what some pixel asks for loses that pixel's detail to the half
    /// resolution.
    fn sigma_min(&self, sigma0: f64) -> f64 {
        sigma0
    }

    /// The same as the GLSL, on the CPU in f64, for one pixel of `frame` (which has
    /// passed [`Medium::validate_frame`]; without a camera a medium that needs one uses
    /// the default camera, as [`Medium::uniforms`] does).
    fn sample(&self, pixel: Pixel, frame: &FrameInputs) -> MediumSample;

    /// Rejects out-of-domain parameters, naming the parameter (`ka`, `airlight` …).
    fn validate(&self) -> Result<()>;

    /// Whether the medium reads a depth buffer (window depth in [0, 1]) through the
    /// camera of the frame, rather than a range map: the frame must then give its camera
    /// ([`FrameInputs::camera`]). The default is no.
    fn needs_camera(&self) -> bool {
        false
    }

    /// The camera the pipeline sets the shader's `brume_ray`, `brume_depth_constants` and
    /// `brume_eye` from for `frame` (see [`crate::camera`]), and the Gaussian engine
    /// blurs measure distance with: the frame's camera for a medium that
    /// [`Medium::needs_camera`], none (the uniforms stay zero) for the others. A medium
    /// whose geometry is its own returns it here
    /// ([`AerialPerspective`]: the photo's camera).
    fn frame_camera(&self, frame: &FrameInputs) -> Option<FrameCamera> {
        if self.needs_camera() {
            frame.camera
        } else {
            None
        }
    }

    /// Rejects a frame this medium cannot render: a non-finite time, a camera no
    /// projection can be built from, or no camera for a medium that
    /// [`Medium::needs_camera`] ([`crate::Error::MissingCamera`]). The pipeline, the
    /// [`crate::Renderer`] and the CPU reference call it before they draw.
    fn validate_frame(&self, frame: &FrameInputs) -> Result<()> {
        frame.validate()?;
        if self.needs_camera() {
            frame.require_camera(&self.name())?;
        }
        Ok(())
    }

    /// Lookup textures the GLSL samples, by their `sampler2D` uniform's name (at most
    /// [`MAX_LOOKUPS`]). The default is none.
    fn lookups(&self) -> Vec<(Cow<'static, str>, Lookup)> {
        Vec::new()
    }
}

/// `(name, value)` pairs with static names as the [`Medium`] methods return them.
pub fn static_names<T>(
    pairs: impl IntoIterator<Item = (&'static str, T)>,
) -> Vec<(Cow<'static, str>, T)> {
    pairs
        .into_iter()
        .map(|(name, value)| (Cow::Borrowed(name), value))
        .collect()
}

/// The most lookup textures one medium may use.
pub const MAX_LOOKUPS: usize = 4;

/// σ = σ0 + λ·r·√Ds: the blur scale of a medium known by its **scattering optical depth**
/// `ds` = ∫κs dt along the ray rather than by κs(t), over a distance `r` in the medium's
/// normalised unit (clamped to [0, 1]). It is the general law of the module docs with the
/// scattering spread evenly along the ray (S = Ds·r²), so a homogeneous medium
/// (Ds = κs·r) gets paper 000's eq. 7 back: σ = σ0 + λ·√κs·r^(3/2). The GLSL twin is
/// `brume_blur_scale` in `glsl/medium_api.glsl`.
pub fn blur_from_optical_depth(sigma0: f64, lambda: f64, r: f64, ds: f64) -> f64 {
    sigma0 + lambda * r.clamp(0.0, 1.0) * ds.max(0.0).sqrt()
}

/// σ = σ0 + λ·√S: the blur scale for a spread moment `spread` (see the module docs).
pub fn blur_scale(sigma0: f64, lambda: f64, spread: f64) -> f64 {
    sigma0 + lambda * spread.max(0.0).sqrt()
}

/// S = 3·∫₀^R κs(t)·(R − t)² dt by the composite Simpson rule on `intervals` (even)
/// sub-intervals: the spread moment of a medium whose scattering coefficient varies along
/// the ray (normalised units). Media with a closed form use that instead; this is their
/// test oracle.
pub fn spread_moment(range: f64, intervals: usize, ks: impl Fn(f64) -> f64) -> f64 {
    let n = intervals.max(2) + intervals % 2;
    let h = range / n as f64;
    let f = |t: f64| ks(t) * (range - t).powi(2);
    let inner: f64 = (1..n)
        .map(|i| {
            let weight = if i % 2 == 1 { 4.0 } else { 2.0 };
            weight * f(i as f64 * h)
        })
        .sum();
    3.0 * h / 3.0 * (f(0.0) + inner + f(range))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn general_law_reduces_to_eq7_for_a_homogeneous_medium() {
        let (sigma0, lambda, ks) = (1.0, 8.0, 0.75);
        let sigma_max = sigma0 + lambda * f64::sqrt(ks);
        for r in [0.0, 0.1, 0.37, 0.8, 1.0] {
            let s = spread_moment(r, 64, |_| ks);
            let general = blur_scale(sigma0, lambda, s);
            let eq7 = sigma0 + f64::powf(r, 1.5) * (sigma_max - sigma0);
            assert!((general - eq7).abs() < 1e-12, "R = {r}: {general} vs {eq7}");
        }
    }

    #[test]
    fn optical_depth_law_is_eq7_for_a_homogeneous_medium() {
        let (sigma0, lambda, ks) = (1.0, 8.0, 0.75);
        for r in [0.0, 0.2, 0.5, 1.0] {
            let law = blur_from_optical_depth(sigma0, lambda, r, ks * r);
            let eq7 = blur_scale(sigma0, lambda, spread_moment(r, 64, |_| ks));
            assert!((law - eq7).abs() < 1e-12, "r = {r}: {law} vs {eq7}");
        }
    }

    #[test]
    fn spread_moment_weights_scattering_near_the_camera_most() {
        // The same optical depth near the camera blurs more than near the target: a ray
        // bent early travels farther off course.
        let near = spread_moment(1.0, 200, |t| if t < 0.5 { 2.0 } else { 0.0 });
        let far = spread_moment(1.0, 200, |t| if t >= 0.5 { 2.0 } else { 0.0 });
        assert!(near > 6.0 * far, "near {near}, far {far}");
    }
}
