//! brume: physically based haze and fog for RGBD images on OpenGL ES 3.2 through EGL.
#![warn(missing_docs)]

pub mod error;
pub mod raster;

pub use error::{Error, Result};
pub mod io;
pub mod prep;
