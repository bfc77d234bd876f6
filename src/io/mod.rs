//! Reading inputs and writing outputs: colour images (sRGB to linear light), depth, range
//! and disparity maps in the formats users bring, and float or 8-bit outputs written
//! atomically (temporary file, then rename).

pub mod camera;
pub mod codec;
pub mod demo;
pub mod depth;
pub mod image;
pub mod output;
