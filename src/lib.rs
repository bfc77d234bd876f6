//! brume: physically based haze and fog for RGBD images on OpenGL ES 3.2 through EGL.
//!
//! The paper-000 pipeline: a range map gives transmission τ = exp(−(κa+κs)R) and a blur
//! scale σ(x); the image is pre-multiplied by τ, diffused in N fragment passes to σ(x),
//! and composited with the airlight. [`pipeline::Renderer`] runs it on the GPU (headless
//! through EGL), [`reference`] runs the same arithmetic on the CPU in f64, and
//! [`schedule`] is the one place where the step count, rates and offsets are decided.
#![warn(missing_docs)]

pub mod bench;
pub mod caps;
pub mod egl;
pub mod error;
pub mod gpu;
pub mod haze;
pub mod io;
pub mod pipeline;
pub mod prep;
pub mod raster;
pub mod reference;
pub mod schedule;

pub use error::{Error, Result};
pub use pipeline::{Precision, Renderer};
pub use schedule::Scheme;
