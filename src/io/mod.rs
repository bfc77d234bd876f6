//! Reading inputs and writing outputs: colour images (sRGB to linear light), depth, range
//! and disparity maps in the formats users bring, and float or 8-bit outputs written
//! atomically (temporary file, then rename).
//!
//! Each file format's reader and writer sit together in [`codec`]; [`depth`] turns depth
//! files into range maps by dataset convention, with the geometry in [`camera`]. Every
//! reader refuses images beyond the size [`limits`] sets, before allocating for them.

pub mod camera;
pub mod codec;
pub mod colour_profile;
pub mod demo;
pub mod depth;
pub(crate) mod heif;
pub mod image;
pub mod limits;
pub mod mask;
pub mod metadata;
pub mod output;
pub(crate) mod png_chunks;
pub mod srgb;

use crate::error::{Error, Result};
use std::fs::{DirEntry, FileType};
use std::path::Path;

/// Calls `visit` with every entry under `dir` and its sub-folders that is not a folder
/// (files, and links, which are not followed), and its type. Errors name the folder or
/// entry that could not be read; the first error of `visit` ends the walk.
pub fn visit_files(
    dir: &Path,
    visit: &mut dyn FnMut(&DirEntry, FileType) -> Result<()>,
) -> Result<()> {
    let entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
    for entry in entries {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let kind = entry.file_type().map_err(|e| Error::io(entry.path(), e))?;
        if kind.is_dir() {
            visit_files(&entry.path(), visit)?;
        } else {
            visit(&entry, kind)?;
        }
    }
    Ok(())
}
