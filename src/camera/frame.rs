//! What changes from frame to frame: the camera the frame was drawn with and the time.
//! A medium is the fog's description and stays the same value across frames; the
//! pipeline, the [`crate::Renderer`] and the CPU reference take these with each frame.

use super::FrameCamera;
use crate::error::{Error, Result};

/// The per-frame inputs of a medium: the camera of a frame whose depth buffer is read,
/// and the time that moves animated media (the distance fog's noise). An engine keeps one
/// medium value and passes a new `FrameInputs` each frame: nothing is rebuilt or
/// recompiled. The default (no camera, time 0) suits every medium that reads a range map
/// ([`crate::Haze`], [`crate::PhysicalFog`], the photo pipeline).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameInputs {
    /// The camera the frame was rendered with (brume's [`super::Camera`] or an engine's
    /// [`super::MatrixCamera`]); required by the media that read a depth buffer
    /// ([`crate::medium::Medium::needs_camera`]), ignored by the others.
    pub camera: Option<FrameCamera>,
    /// Time, in the unit the medium's speeds use (seconds for brume's media).
    pub time: f64,
}

impl FrameInputs {
    /// A frame drawn with `camera` at `time`.
    pub fn new(camera: impl Into<FrameCamera>, time: f64) -> Self {
        FrameInputs {
            camera: Some(camera.into()),
            time,
        }
    }

    /// No camera, at `time`.
    pub fn at_time(time: f64) -> Self {
        FrameInputs { camera: None, time }
    }

    /// Rejects a time that is not finite or a camera no projection can be built from.
    pub fn validate(&self) -> Result<()> {
        if !self.time.is_finite() {
            return Err(Error::invalid(
                "time",
                self.time,
                "a finite time (in the unit of the medium's speeds)",
            ));
        }
        match &self.camera {
            Some(camera) => camera.validate(),
            None => Ok(()),
        }
    }

    /// The camera, or [`Error::MissingCamera`] naming `medium`, the one that needs it.
    pub fn require_camera(&self, medium: &str) -> Result<FrameCamera> {
        self.camera.ok_or_else(|| Error::MissingCamera {
            medium: medium.to_string(),
        })
    }

    /// The camera, or the default one when there is none: for the per-pixel paths that
    /// cannot fail ([`crate::medium::Medium::sample`]), called only after the entry
    /// points have checked the frame ([`crate::medium::Medium::validate_frame`]).
    pub fn camera_or_default(&self) -> FrameCamera {
        self.camera.unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;

    #[test]
    fn default_has_no_camera_and_time_zero() {
        let f = FrameInputs::default();
        assert_eq!((f.camera, f.time), (None, 0.0));
        assert!(f.validate().is_ok());
    }

    #[test]
    fn rejects_a_non_finite_time_and_a_bad_camera() {
        let e = FrameInputs::at_time(f64::NAN).validate().unwrap_err();
        assert!(e.to_string().contains("time"), "{e}");
        let bad = Camera {
            near: -1.0,
            ..Camera::default()
        };
        let e = FrameInputs::new(bad, 0.0).validate().unwrap_err();
        assert!(e.to_string().contains("near"), "{e}");
    }

    #[test]
    fn missing_camera_names_the_medium_and_what_to_pass() {
        let e = FrameInputs::default()
            .require_camera("layered")
            .unwrap_err();
        assert!(matches!(&e, Error::MissingCamera { medium } if medium == "layered"));
        let text = e.to_string();
        assert!(
            text.contains("layered") && text.contains("camera: Some"),
            "{text}"
        );
    }
}
