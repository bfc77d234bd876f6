//! Touch controls: a horizontal drag sets the haze's density (its extinction κa + κs,
//! scaled on a log axis), a vertical drag its blur (λ, so σmax = σ0 + λ·√κs), a double tap
//! switches between the demo image and the camera. Pure: events in, settings out.

use brume::medium::haze::{DEFAULT_KA, DEFAULT_KS, DEFAULT_LAMBDA};
use brume::Haze;

/// A drag across the whole width multiplies the density by this.
const DENSITY_PER_WIDTH: f64 = 16.0;
/// Density limits (× the default κa and κs).
const DENSITY_RANGE: (f64, f64) = (0.02, 20.0);
/// A drag up the whole height adds this to λ (px).
const LAMBDA_PER_HEIGHT: f64 = 40.0;
/// λ limits (px): beyond the upper one the diffusion needs many passes on a phone.
const LAMBDA_RANGE: (f64, f64) = (0.0, 48.0);
/// A touch that moves less than this (px) and lifts within [`TAP_MS`] is a tap.
const TAP_SLOP_PX: f32 = 24.0;
const TAP_MS: i64 = 300;
/// Two taps this close in time (from the first's lift to the second's) and space are a
/// double tap.
const DOUBLE_TAP_MS: i64 = 350;
const DOUBLE_TAP_SLOP_PX: f32 = 96.0;

/// What the app shows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Mode {
    /// brume's built-in demo RGBD image.
    #[default]
    Demo,
    /// The camera, with its depth where the device has some.
    Camera,
}

impl Mode {
    /// The other mode.
    pub fn toggled(self) -> Mode {
        match self {
            Mode::Demo => Mode::Camera,
            Mode::Camera => Mode::Demo,
        }
    }
}

/// The haze the controls set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Multiplies brume's default κa and κs.
    pub density: f64,
    /// Blur factor λ (px).
    pub lambda: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            density: 1.0,
            lambda: DEFAULT_LAMBDA,
        }
    }
}

impl Settings {
    /// The haze for a range texture in which `range_unit` is the far end (1 for a
    /// normalised range, metres for a depth sensor's).
    pub fn haze(&self, range_unit: f64) -> Haze {
        Haze {
            ka: DEFAULT_KA * self.density,
            ks: DEFAULT_KS * self.density,
            lambda: self.lambda,
            range_unit,
            ..Haze::default()
        }
    }
}

/// One touch of the first pointer, in screen pixels (y down, as Android gives them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Touch {
    /// The finger lands.
    Down {
        /// Position (px).
        x: f32,
        /// Position (px).
        y: f32,
        /// Event time (ms).
        time_ms: i64,
    },
    /// The finger moves.
    Move {
        /// Position (px).
        x: f32,
        /// Position (px).
        y: f32,
    },
    /// The finger lifts.
    Up {
        /// Position (px).
        x: f32,
        /// Position (px).
        y: f32,
        /// Event time (ms).
        time_ms: i64,
    },
    /// The gesture was taken away (by the system).
    Cancel,
}

/// What a touch did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Gesture {
    /// Nothing visible.
    None,
    /// The settings changed.
    Changed,
    /// A double tap: switch modes.
    SwitchMode,
}

/// A finger down: where and when it landed, and the settings then.
#[derive(Clone, Copy, Debug)]
struct Press {
    x: f32,
    y: f32,
    time_ms: i64,
    start: Settings,
    dragging: bool,
}

/// The gesture recogniser and the settings it drives.
#[derive(Clone, Debug, Default)]
pub struct Controls {
    settings: Settings,
    press: Option<Press>,
    /// Where and when the last tap lifted.
    last_tap: Option<(f32, f32, i64)>,
}

impl Controls {
    /// The current settings.
    pub fn settings(&self) -> Settings {
        self.settings
    }

    /// Feeds one touch on a `width x height` screen.
    pub fn touch(&mut self, touch: Touch, (width, height): (f32, f32)) -> Gesture {
        match touch {
            Touch::Down { x, y, time_ms } => {
                self.press = Some(Press {
                    x,
                    y,
                    time_ms,
                    start: self.settings,
                    dragging: false,
                });
                Gesture::None
            }
            Touch::Move { x, y } => self.drag(x, y, (width, height)),
            Touch::Up { x, y, time_ms } => self.lift(x, y, time_ms),
            Touch::Cancel => {
                self.press = None;
                Gesture::None
            }
        }
    }

    fn drag(&mut self, x: f32, y: f32, (width, height): (f32, f32)) -> Gesture {
        let Some(press) = self.press.as_mut() else {
            return Gesture::None;
        };
        let (dx, dy) = (x - press.x, y - press.y);
        if !press.dragging && dx.hypot(dy) < TAP_SLOP_PX {
            return Gesture::None;
        }
        press.dragging = true;
        let across = f64::from(dx / width.max(1.0));
        let up = f64::from(-dy / height.max(1.0));
        let density = press.start.density * DENSITY_PER_WIDTH.powf(across);
        let lambda = press.start.lambda + LAMBDA_PER_HEIGHT * up;
        self.settings = Settings {
            density: density.clamp(DENSITY_RANGE.0, DENSITY_RANGE.1),
            lambda: lambda.clamp(LAMBDA_RANGE.0, LAMBDA_RANGE.1),
        };
        Gesture::Changed
    }

    fn lift(&mut self, x: f32, y: f32, time_ms: i64) -> Gesture {
        let Some(press) = self.press.take() else {
            return Gesture::None;
        };
        let tap = !press.dragging
            && (x - press.x).hypot(y - press.y) < TAP_SLOP_PX
            && time_ms - press.time_ms <= TAP_MS;
        if !tap {
            self.last_tap = None;
            return Gesture::None;
        }
        let double = self.last_tap.is_some_and(|(lx, ly, lt)| {
            time_ms - lt <= DOUBLE_TAP_MS && (x - lx).hypot(y - ly) < DOUBLE_TAP_SLOP_PX
        });
        if double {
            self.last_tap = None;
            Gesture::SwitchMode
        } else {
            self.last_tap = Some((x, y, time_ms));
            Gesture::None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCREEN: (f32, f32) = (1000.0, 2000.0);

    fn tap(c: &mut Controls, x: f32, y: f32, at: i64) -> Gesture {
        c.touch(Touch::Down { x, y, time_ms: at }, SCREEN);
        c.touch(
            Touch::Up {
                x,
                y,
                time_ms: at + 80,
            },
            SCREEN,
        )
    }

    #[test]
    fn a_horizontal_drag_scales_the_density_on_a_log_axis() {
        let mut c = Controls::default();
        c.touch(
            Touch::Down {
                x: 100.0,
                y: 500.0,
                time_ms: 0,
            },
            SCREEN,
        );
        assert_eq!(
            c.touch(Touch::Move { x: 600.0, y: 500.0 }, SCREEN),
            Gesture::Changed
        );
        // Half the width: × √16 = 4.
        assert!((c.settings().density - 4.0).abs() < 1e-9);
        assert_eq!(c.settings().lambda, DEFAULT_LAMBDA);
        c.touch(
            Touch::Move {
                x: -400.0,
                y: 500.0,
            },
            SCREEN,
        );
        assert!((c.settings().density - 0.25).abs() < 1e-9);
        c.touch(
            Touch::Up {
                x: -400.0,
                y: 500.0,
                time_ms: 900,
            },
            SCREEN,
        );
        let haze = c.settings().haze(1.0);
        assert!((haze.ka - DEFAULT_KA * 0.25).abs() < 1e-12);
        assert!((haze.ks - DEFAULT_KS * 0.25).abs() < 1e-12);
    }

    #[test]
    fn a_vertical_drag_up_blurs_more_within_limits() {
        let mut c = Controls::default();
        c.touch(
            Touch::Down {
                x: 500.0,
                y: 1500.0,
                time_ms: 0,
            },
            SCREEN,
        );
        c.touch(
            Touch::Move {
                x: 500.0,
                y: 1000.0,
            },
            SCREEN,
        );
        assert!((c.settings().lambda - (DEFAULT_LAMBDA + 10.0)).abs() < 1e-9);
        c.touch(
            Touch::Move {
                x: 500.0,
                y: 9000.0,
            },
            SCREEN,
        );
        assert_eq!(c.settings().lambda, 0.0);
        c.touch(
            Touch::Move {
                x: 500.0,
                y: -9000.0,
            },
            SCREEN,
        );
        assert_eq!(c.settings().lambda, LAMBDA_RANGE.1);
        assert_eq!(c.settings().haze(3.0).range_unit, 3.0);
    }

    #[test]
    fn a_double_tap_switches_and_single_taps_or_drags_do_not() {
        let mut c = Controls::default();
        assert_eq!(tap(&mut c, 300.0, 300.0, 0), Gesture::None);
        assert_eq!(tap(&mut c, 310.0, 305.0, 250), Gesture::SwitchMode);
        assert_eq!(c.settings(), Settings::default(), "taps change no setting");
        // Too slow.
        tap(&mut c, 300.0, 300.0, 2000);
        assert_eq!(tap(&mut c, 300.0, 300.0, 3000), Gesture::None);
        // Too far apart.
        tap(&mut c, 300.0, 300.0, 5000);
        assert_eq!(tap(&mut c, 800.0, 1300.0, 5200), Gesture::None);
        // A drag between two taps breaks the pair.
        tap(&mut c, 300.0, 300.0, 7000);
        c.touch(
            Touch::Down {
                x: 300.0,
                y: 300.0,
                time_ms: 7100,
            },
            SCREEN,
        );
        c.touch(Touch::Move { x: 500.0, y: 300.0 }, SCREEN);
        assert_eq!(
            c.touch(
                Touch::Up {
                    x: 500.0,
                    y: 300.0,
                    time_ms: 7150
                },
                SCREEN
            ),
            Gesture::None
        );
        assert_eq!(tap(&mut c, 300.0, 300.0, 7200), Gesture::None);
        // A long press is no tap.
        c.touch(
            Touch::Down {
                x: 300.0,
                y: 300.0,
                time_ms: 9000,
            },
            SCREEN,
        );
        assert_eq!(
            c.touch(
                Touch::Up {
                    x: 300.0,
                    y: 300.0,
                    time_ms: 9900
                },
                SCREEN
            ),
            Gesture::None
        );
        assert_eq!(Mode::Demo.toggled(), Mode::Camera);
    }

    #[test]
    fn a_cancelled_touch_is_forgotten() {
        let mut c = Controls::default();
        c.touch(
            Touch::Down {
                x: 0.0,
                y: 0.0,
                time_ms: 0,
            },
            SCREEN,
        );
        c.touch(Touch::Cancel, SCREEN);
        assert_eq!(
            c.touch(Touch::Move { x: 900.0, y: 0.0 }, SCREEN),
            Gesture::None
        );
        assert_eq!(c.settings(), Settings::default());
    }
}
