//! brume: physically based haze and fog for RGBD images and rendered frames, on OpenGL ES
//! 3.2 through EGL or on any host's GLES context.
//!
//! - [`Pipeline`] runs on the host's GL context: the host's colour and depth textures in,
//!   the host's framebuffer or texture out (see [`pipeline`] for the contract).
//! - A [`medium::Medium`] is a fog model: per pixel a transmission τ (RGB), in-scattered
//!   light L∞ and a blur scale σ. [`medium::Haze`] is paper 000's, in normalised range
//!   or, through [`medium::PhysicalFog`], with β in m⁻¹ on range in metres.
//! - The diffusion blur ([`Blur`], [`schedule`]) takes σ from any medium and knows nothing
//!   else of it.
//! - [`Renderer`] wraps the pipeline with CPU buffers, and [`Headless`] adds brume's own
//!   EGL context (no window, no display) for the CLI, benchmarks and tests.
//! - [`reference`](mod@reference) runs the same arithmetic on the CPU in f64.
//! - [`scene::SceneRenderer`] draws a procedural outdoor scene (colour, depth buffer and
//!   [`camera::Camera`]): a real rendered frame for the engine fogs to work on.
//! - [`sky`] renders Preetham clear skies through a fisheye and estimates the turbidity
//!   of a fisheye sky photograph (paper 002), on the CPU.
#![warn(missing_docs)]

pub mod atmosphere;
pub mod bench;
pub mod blur;
pub mod camera;
pub mod caps;
pub mod compat;
pub mod dataset;
pub mod egl;
pub mod error;
pub mod gpu;
pub mod io;
pub mod medium;
pub mod memory;
pub mod metrics;
pub mod parallel;
pub mod photo;
pub mod pipeline;
pub mod prep;
pub mod raster;
pub mod reference;
pub mod refine;
pub mod renderer;
pub(crate) mod rng;
pub mod scene;
pub mod schedule;
pub mod sky;

pub use blur::{Blur, Precision};
pub use camera::FrameInputs;
pub use error::{Error, Result};
pub use gpu::timer::{Clock, PassTimes, Timing};
pub use medium::{Haze, Medium, PhysicalFog, UniformBlur};
pub use pipeline::{Encoding, FogBlur, Frame, GaussBlur, Input, Output, Pipeline};
pub use refine::Refine;
pub use renderer::{Headless, Rendered, Renderer};
pub use schedule::Scheme;

/// A fingerprint of the sources this build was compiled from (`src/` and `glsl/`, 16 hex
/// digits): two builds of one [`VERSION`] whose outputs may differ (a clone's commits
/// between releases) have different fingerprints. A batch's settings record keeps it.
pub const SOURCES: &str = env!("BRUME_SOURCES");

/// brume's version, as its `Cargo.toml` gives it.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");
