//! What a batch tells its host: each event of a run as it happens ([`BatchEvent`]) and
//! the totals at its end ([`BatchReport`]).

use crate::error::{Error, Result};
use crate::io::output::Outputs;
use std::path::{Path, PathBuf};

/// What happens in a run, as it happens.
#[derive(Debug)]
pub enum BatchEvent<'a> {
    /// Temporaries an interrupted run left under the output folder were removed.
    RemovedTemporaries {
        /// How many files.
        count: usize,
        /// The output folder.
        folder: &'a Path,
    },
    /// An output's files are written under temporary names and are about to be renamed
    /// into place.
    Staged {
        /// The staged files.
        outputs: &'a Outputs,
    },
    /// An output is in place and logged.
    Written {
        /// The fogged image's path.
        output: &'a Path,
    },
    /// An output could not be made or written; it is logged as failed.
    OutputFailed {
        /// The fogged image's path.
        output: &'a Path,
        /// Why.
        error: &'a Error,
    },
    /// A frame was loaded with warnings ([`LoadedDepth::warnings`]: its depth taken as
    /// range for want of intrinsics, options given and ignored); it is rendered, and each
    /// of its outputs' log records lists them under `warnings`. Sent before its outputs.
    ///
    /// [`LoadedDepth::warnings`]: crate::io::depth::LoadedDepth::warnings
    FrameWarned {
        /// The frame's colour image.
        image: &'a Path,
        /// What to tell the user, naming the library's options in backticks.
        warnings: &'a [String],
    },
    /// A frame could not be loaded or rendered, and is logged as failed.
    FrameFailed {
        /// The frame's colour image.
        image: &'a Path,
        /// Why.
        error: &'a Error,
        /// How many of its outputs will not be written.
        outputs: usize,
    },
}

/// What a run did and what it cost, totals over its outputs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BatchReport {
    /// Outputs written.
    pub written: usize,
    /// Outputs already complete, skipped.
    pub skipped: usize,
    /// Outputs that failed.
    pub failed_outputs: usize,
    /// Frames that could not be loaded or rendered.
    pub failed_frames: usize,
    /// Frames rendered.
    pub frames: usize,
    /// Frames rendered with warnings ([`BatchEvent::FrameWarned`]).
    pub warned_frames: usize,
    /// Decoding the frames' files, ms (wall, on the loader thread).
    pub decode_ms: f64,
    /// Pre-processing, ms (wall, on the loader thread).
    pub prep_ms: f64,
    /// Refinement and the range in metres, once per frame, ms (wall, on the GPU's thread).
    pub refine_ms: f64,
    /// The GPU's time for the passes, ms (outputs whose timer figures were rejected do
    /// not count).
    pub gpu_ms: f64,
    /// Rendering and reading back, ms (wall, on the GPU's thread).
    pub render_ms: f64,
    /// The capture, encoding and writing, ms (wall, on the writer thread).
    pub encode_ms: f64,
    /// The whole run, s.
    pub wall_s: f64,
    /// The run's log.
    pub log: PathBuf,
}

impl BatchReport {
    /// [`Error::BatchFailures`] if a frame or an output failed.
    pub fn check(&self) -> Result<()> {
        if self.failed_frames == 0 && self.failed_outputs == 0 {
            return Ok(());
        }
        Err(Error::BatchFailures {
            frames: self.failed_frames,
            outputs: self.failed_outputs,
            written: self.written,
            log: self.log.clone(),
        })
    }
}
