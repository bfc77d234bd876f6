//! Reading inputs and writing outputs: colour images (sRGB to linear light), depth, range
//! and disparity maps in the formats users bring, and float or 8-bit outputs written
//! atomically (temporary file, then rename).
//!
//! Each file format's reader and writer sit together in [`codec`]; [`depth`] turns depth
//! files into range maps by dataset convention, with the geometry in [`camera`]. Every
//! reader refuses images beyond the size [`limits`] sets, before allocating for them.

pub mod camera;
pub mod codec;
pub mod demo;
pub mod depth;
pub mod image;
pub mod limits;
pub mod mask;
pub mod output;
