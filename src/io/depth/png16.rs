//! 16-bit PNG depth conventions: KITTI, NYU Depth v2 and TUM RGB-D each fix the metres
//! per unit (their rows in `format.rs`), and `png16` takes it from the `depth_scale`
//! option (`DepthOptions::scale`).

use super::{positive_option, DepthFormat, DepthOptions};
use crate::{Error, Result};

/// Metres per unit of a 16-bit PNG in `format`: the dataset's fixed scale, or
/// `depth_scale` for `png16`.
pub(super) fn scale(
    format: DepthFormat,
    opts: &DepthOptions,
    notes: &mut Vec<String>,
) -> Result<f64> {
    let fixed = format.rule().fixed_scale;
    let scale = match fixed {
        Some(scale) => scale,
        None => given_scale(opts)?,
    };
    if fixed.is_some() && opts.scale.is_some() {
        notes.push(format!("`depth_scale` ignored: {format} has a fixed scale"));
    }
    Ok(scale)
}

/// `depth_scale` (`DepthOptions::scale`), required and positive.
pub(super) fn given_scale(opts: &DepthOptions) -> Result<f64> {
    let scale = opts.scale.ok_or_else(|| {
        Error::invalid(
            "depth_scale",
            "nothing",
            "a positive multiplier for `depth_format` png16 (e.g. 0.001 for millimetres)",
        )
    })?;
    positive_option(scale, "depth_scale", "a positive finite multiplier")
}
