//! Android Camera2 `ImageFormat.DEPTH16` samples, saved as a 16-bit grey PNG.
//!
//! What the Android reference says
//! (<https://developer.android.com/reference/android/graphics/ImageFormat#DEPTH16>):
//! each 16-bit sample is a "depth ranging measurement" made of a confidence value and the
//! range; the confidence is in the 3 most significant bits, code 0 meaning 100 %, code 1
//! meaning 0 %, code 2 meaning 1/7, code 3 2/7 and so on (so code c ≥ 1 is (c − 1)/7);
//! "when produced by a camera, the units for the range are millimeters". The HAL's
//! `HAL_DATASPACE_DEPTH` comment (AOSP's `graphics-base` header) gives the same
//! layout in code: range = sample & 0x1FFF, confidence = (((sample >> 13) − 1) & 7) / 7.
//! Android's own depth-photo writer (AOSP `DepthPhotoProcessor.cpp`) decodes it the same
//! way.
//!
//! Range or depth? Both texts call the value a *range* ("ranging measurement", "units for
//! the range"), but neither says whether it is measured along the ray (range, what haze
//! needs) or along the optical axis (z-depth): the geometry is not documented. (The one
//! hint the other way is weak: the depth-photo writer above stores the map in a Dynamic
//! Depth container without setting its measure type, whose default is "optical axis".)
//! brume follows the documented word and reads DEPTH16 as [`DepthKind::Range`], which needs no
//! field of view; a device known to write z-depth is read with the kind `Depth` and
//! `fov` (or `focal`), like any other depth map.
//!
//! A sample with range 0 is unknown (nothing measured), and so is one whose confidence is
//! below the threshold ([`DEPTH16_DEFAULT_MIN_CONFIDENCE`] unless `min_confidence`
//! says otherwise).
//!
//! [`DepthKind::Range`]: super::DepthKind::Range

use std::path::Path;

use super::{DepthFormat, DepthOptions};
use crate::raster::Grid;
use crate::{Error, Result};

/// Lowest confidence of a DEPTH16 sample kept when `DepthOptions::min_confidence` is
/// `None`: codes 0 (100 %) and 5 to 7 (4/7 to 6/7) are kept, codes 1 to 4 (0 to 3/7) are
/// unknown. Half way: a sample more likely wrong than right is not worth a haze value.
pub const DEPTH16_DEFAULT_MIN_CONFIDENCE: f64 = 0.5;

/// The bits of a sample that hold the range in millimetres (the low 13).
const RANGE_MASK: u16 = 0x1FFF;

/// The range in millimetres and the confidence code (0 to 7) of a DEPTH16 sample.
fn split(sample: u16) -> (u16, u16) {
    (sample & RANGE_MASK, sample >> 13)
}

/// The confidence in [0, 1] of a code: 0 is 100 %, c ≥ 1 is (c − 1)/7.
pub(super) fn confidence(code: u16) -> f64 {
    if code == 0 {
        1.0
    } else {
        f64::from(code - 1) / 7.0
    }
}

/// `DepthOptions::min_confidence`, checked whatever the format (a value outside [0, 1] is
/// a mistake even where it would be ignored); a note when the format has no confidence
/// to test.
pub(super) fn min_confidence(
    format: DepthFormat,
    opts: &DepthOptions,
    notes: &mut Vec<String>,
) -> Result<f64> {
    let Some(value) = opts.min_confidence else {
        return Ok(DEPTH16_DEFAULT_MIN_CONFIDENCE);
    };
    if !(0.0..=1.0).contains(&value) {
        return Err(Error::invalid(
            "min_confidence",
            value,
            "a confidence from 0 to 1 (DEPTH16 levels are 0, 1/7, …, 6/7 and 1)",
        ));
    }
    // A portrait photo's confidence map, where it has one, is read in `interpret`.
    let embedded = matches!(
        format,
        DepthFormat::Gdepth | DepthFormat::DynamicDepth | DepthFormat::AppleDepth
    );
    if format != DepthFormat::AndroidDepth16 && !embedded {
        notes.push(format!(
            "`min_confidence` ignored: {format} carries no confidence"
        ));
    }
    Ok(value)
}

/// The range of a sample in metres (`metres_per_mm` is the format's scale), or `None`
/// where it is unknown: range 0, or a confidence below `min_confidence`.
pub(super) fn metres(sample: u16, min_confidence: f64, metres_per_mm: f64) -> Option<f64> {
    let (mm, code) = split(sample);
    (mm != 0 && confidence(code) >= min_confidence).then(|| f64::from(mm) * metres_per_mm)
}

/// Counts the samples the confidence threshold turns unknown, adds a note saying how
/// many, and refuses a file in which the threshold leaves nothing: then the file is not
/// empty, the threshold is too high for it, and the message says so. (A file whose ranges
/// are all 0 is left to the common "no valid depth" error.)
pub(super) fn check_confidence(
    raw: &Grid<u16>,
    min_confidence: f64,
    path: &Path,
    notes: &mut Vec<String>,
) -> Result<()> {
    let mut tally = ConfidenceTally::new(min_confidence);
    for &sample in raw.as_slice() {
        let (mm, code) = split(sample);
        if mm != 0 {
            tally.drops(confidence(code));
        }
    }
    tally.refuse_if_none_left(
        "DEPTH16 samples with a range",
        "",
        ", or check that the file is DEPTH16 (a plain millimetre map is `depth_format` \
         arcore or nyu)",
        path,
    )?;
    let ConfidenceTally {
        measured, dropped, ..
    } = tally;
    if dropped > 0 {
        notes.push(format!(
            "{dropped} of {measured} DEPTH16 samples with a range are below \
             `min_confidence` {min_confidence}: unknown"
        ));
    }
    Ok(())
}

/// The confidences of a map's measured samples as a `min_confidence` threshold meets
/// them: how many were measured, how many it drops, and the highest (DEPTH16's codes, or
/// a portrait photo's confidence map).
pub(super) struct ConfidenceTally {
    threshold: f64,
    /// Samples counted.
    pub measured: usize,
    /// Samples below the threshold.
    pub dropped: usize,
    best: f64,
}

impl ConfidenceTally {
    pub(super) fn new(threshold: f64) -> Self {
        ConfidenceTally {
            threshold,
            measured: 0,
            dropped: 0,
            best: f64::NEG_INFINITY,
        }
    }

    /// Counts a measured sample of confidence `c`; whether the threshold drops it.
    pub(super) fn drops(&mut self, c: f64) -> bool {
        let dropped = c < self.threshold;
        self.measured += 1;
        self.dropped += usize::from(dropped);
        self.best = self.best.max(c);
        dropped
    }

    /// Refuses a threshold that dropped every measured sample: then the file is not
    /// empty, the threshold is too high for it, and the message says so, naming the
    /// `samples` counted, `where_` their confidences are, the highest, and a `hint`.
    pub(super) fn refuse_if_none_left(
        &self,
        samples: &str,
        where_: &str,
        hint: &str,
        path: &Path,
    ) -> Result<()> {
        let ConfidenceTally {
            threshold,
            measured,
            dropped,
            best,
        } = *self;
        if dropped == 0 || dropped < measured {
            return Ok(());
        }
        Err(Error::format(
            path,
            format!(
                "all {measured} {samples} have a confidence below `min_confidence` \
                 {threshold}{where_} (the highest is {best:.3}): expected some at or above \
                 it; lower `min_confidence`{hint}"
            ),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn confidence_codes_follow_the_android_table() {
        assert_eq!(confidence(0), 1.0);
        assert_eq!(confidence(1), 0.0);
        assert_eq!(confidence(2), 1.0 / 7.0);
        assert_eq!(confidence(7), 6.0 / 7.0);
    }

    #[test]
    fn the_high_bits_are_confidence_not_range() {
        // 8191 mm at 100 % confidence: no high bit set.
        assert_eq!(metres(0x1FFF, 0.5, 1e-3), Some(8.191));
        // The same range with code 7 (6/7): kept at 0.5, refused at 0.9.
        assert_eq!(metres(0xFFFF, 0.5, 1e-3), Some(8.191));
        assert_eq!(metres(0xFFFF, 0.9, 1e-3), None);
        // Code 1 (0 %) is kept only at a threshold of 0.
        assert_eq!(metres(0x2000 | 1500, 0.0, 1e-3), Some(1.5));
        assert_eq!(metres(0x2000 | 1500, 0.01, 1e-3), None);
        // Range 0 is unknown at any confidence.
        assert_eq!(metres(0, 0.0, 1e-3), None);
        assert_eq!(metres(0xE000, 0.0, 1e-3), None);
    }
}
