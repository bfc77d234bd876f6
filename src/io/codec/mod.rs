//! File formats, one module each, holding a format's reader and writer side by side so
//! that a change to one is made, and seen, next to the other. Codecs turn bytes into
//! grids and back: what the values mean (depth, disparity, colour) is decided by their
//! callers in `io::depth` and `io::image`, and getting the bytes safely onto disk is
//! `io::output`'s job.

#[cfg(feature = "codecs")]
pub mod exr;
pub mod jpeg;
#[cfg(feature = "codecs")]
pub mod npy;
pub mod pfm;
pub mod png;
#[cfg(feature = "codecs")]
pub mod tiff;
#[cfg(not(feature = "codecs"))]
mod without;
#[cfg(not(feature = "codecs"))]
pub use without::{exr, npy, tiff};
