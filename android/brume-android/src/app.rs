//! The NativeActivity's loop: Android's events (a window given or taken, pause, the end),
//! touches to [`Controls`], and one frame drawn and shown per vsync while there is a
//! window.

use crate::camera::Camera;
use crate::controls::{Controls, Gesture, Mode, Touch};
use crate::live::{Live, Target};
use crate::permission;
use crate::window::WindowGl;
use android_activity::input::{InputEvent, MotionAction, MotionEvent};
use android_activity::{AndroidApp, InputStatus, MainEvent, PollEvent};
use glow::HasContext;
use std::time::{Duration, Instant};

/// How often the camera permission is looked at again while the dialog is up.
const PERMISSION_POLL: Duration = Duration::from_secs(1);

/// Runs the app until Android destroys the activity.
pub fn run(app: AndroidApp) {
    android_logger::init_once(
        android_logger::Config::default()
            .with_max_level(log::LevelFilter::Info)
            .with_tag("brume"),
    );
    let mut state = State::default();
    let mut quit = false;
    while !quit {
        // Block while there is nothing to draw; with a window, draw as fast as vsync.
        let timeout = state.window().then_some(Duration::ZERO);
        app.poll_events(timeout, |event| match event {
            PollEvent::Main(MainEvent::InitWindow { .. }) => state.window_ready(&app),
            PollEvent::Main(MainEvent::TerminateWindow { .. }) => state.window_gone(),
            PollEvent::Main(MainEvent::Pause) => state.camera = None,
            PollEvent::Main(MainEvent::Destroy) => quit = true,
            _ => {}
        });
        state.read_input(&app);
        if !quit {
            state.frame(&app);
        }
    }
    log::info!("brume: activity destroyed");
}

/// Whether the camera may be opened.
#[derive(Clone, Copy, Debug, Default)]
enum Permission {
    /// Not looked at yet.
    #[default]
    Unknown,
    /// The dialog was shown; looked at again from time to time.
    Asked(Instant),
    /// Granted.
    Granted,
}

/// Everything the app holds. Field order is drop order: the camera and brume's pipeline
/// (GL objects) go while the context, dropped last, is still current.
#[derive(Default)]
struct State {
    camera: Option<Camera>,
    live: Option<Live>,
    gl: Option<WindowGl>,
    controls: Controls,
    mode: Mode,
    permission: Permission,
    /// What went wrong for good (no GLES 3, no float targets): logged once, shown as a
    /// red screen.
    failed: bool,
}

impl State {
    fn window(&self) -> bool {
        self.gl.as_ref().is_some_and(WindowGl::has_window)
    }

    /// A window arrived: draw into it (the context and the pipeline are made once).
    fn window_ready(&mut self, app: &AndroidApp) {
        let Some(window) = app.native_window() else {
            return;
        };
        if self.gl.is_none() {
            match WindowGl::new() {
                Ok(gl) => self.gl = Some(gl),
                Err(e) => return self.fail(&format!("EGL: {e}")),
            }
        }
        let gl = self.gl.as_mut().expect("made above");
        if let Err(e) = gl.attach(window) {
            return self.fail(&e);
        }
        if self.live.is_none() && !self.failed {
            match Live::new(std::sync::Arc::clone(gl.gl())) {
                Ok(live) => self.live = Some(live),
                Err(e) => self.fail(&format!("brume: {e}")),
            }
        }
    }

    fn window_gone(&mut self) {
        if let Some(gl) = self.gl.as_mut() {
            gl.detach();
        }
    }

    fn fail(&mut self, why: &str) {
        log::error!("{why}");
        self.failed = true;
    }

    /// Feeds the first pointer's touches to the controls.
    fn read_input(&mut self, app: &AndroidApp) {
        let Ok(mut events) = app.input_events_iter() else {
            return;
        };
        let size = self
            .gl
            .as_ref()
            .and_then(WindowGl::size)
            .map_or((1.0, 1.0), |(w, h)| (w as f32, h as f32));
        while events.next(|event| match event {
            InputEvent::MotionEvent(motion) => {
                if let Some(touch) = touch_of(motion) {
                    let gesture = self.controls.touch(touch, size);
                    self.gesture(gesture);
                }
                InputStatus::Handled
            }
            _ => InputStatus::Unhandled,
        }) {}
    }

    fn gesture(&mut self, gesture: Gesture) {
        if gesture == Gesture::SwitchMode {
            self.mode = self.mode.toggled();
            log::info!("mode: {:?}", self.mode);
            if self.mode == Mode::Demo {
                self.camera = None; // free the camera for other apps, and the battery
            }
        }
    }

    /// Draws and shows one frame.
    fn frame(&mut self, app: &AndroidApp) {
        let Some((width, height)) = self.gl.as_ref().and_then(WindowGl::size) else {
            return;
        };
        let target = Target {
            framebuffer: None,
            width,
            height,
        };
        if self.failed || self.live.is_none() {
            self.show_failure(&target);
        } else if self.mode == Mode::Camera && self.camera_frame(app, &target) {
            // drawn from the camera
        } else {
            let settings = self.controls.settings();
            let live = self.live.as_mut().expect("checked above");
            if let Err(e) = live.draw_demo(&settings, &target) {
                self.fail(&format!("brume: {e}"));
            }
        }
        if let Some(Err(e)) = self.gl.as_ref().map(WindowGl::swap) {
            log::warn!("{e}");
        }
    }

    /// Draws the camera's latest frame; false when there is none (yet), or the camera
    /// cannot be used (then the app goes back to the demo).
    fn camera_frame(&mut self, app: &AndroidApp, target: &Target) -> bool {
        if self.camera.is_none() && !self.open_camera(app, target) {
            return false;
        }
        let (camera, live) = match (self.camera.as_mut(), self.live.as_mut()) {
            (Some(c), Some(l)) => (c, l),
            _ => return false,
        };
        let input = match camera.input(live.pipeline()) {
            Ok(Some(input)) => input,
            Ok(None) => return false, // no frame yet: the demo meanwhile
            Err(e) => {
                log::error!("camera: {e}; back to the demo");
                self.camera = None;
                self.mode = Mode::Demo;
                return false;
            }
        };
        let haze = self.controls.settings().haze(camera.range_unit());
        match live.draw(&input, &haze, target) {
            Ok(_) => true,
            Err(e) => {
                log::error!("brume on a camera frame: {e}; back to the demo");
                self.camera = None;
                self.mode = Mode::Demo;
                false
            }
        }
    }

    /// Opens the camera once the permission is granted (asking for it first).
    fn open_camera(&mut self, app: &AndroidApp, target: &Target) -> bool {
        if !self.camera_permitted(app) {
            return false;
        }
        let Some(gl) = self.gl.as_ref() else {
            return false;
        };
        let fit = (target.width.max(1) as usize, target.height.max(1) as usize);
        match Camera::open(gl.gl(), gl.egl(), fit) {
            Ok(camera) => {
                self.camera = Some(camera);
                true
            }
            Err(e) => {
                log::error!("camera: {e}; back to the demo");
                self.mode = Mode::Demo;
                false
            }
        }
    }

    fn camera_permitted(&mut self, app: &AndroidApp) -> bool {
        match self.permission {
            Permission::Granted => return true,
            Permission::Asked(at) if at.elapsed() < PERMISSION_POLL => return false,
            _ => {}
        }
        match permission::camera_granted(app) {
            Ok(true) => {
                self.permission = Permission::Granted;
                true
            }
            Ok(false) => {
                if matches!(self.permission, Permission::Unknown) {
                    if let Err(e) = permission::request_camera(app) {
                        log::error!("cannot ask for the camera permission: {e}");
                    }
                }
                self.permission = Permission::Asked(Instant::now());
                false
            }
            Err(e) => {
                log::error!("cannot read the camera permission: {e}; back to the demo");
                self.mode = Mode::Demo;
                false
            }
        }
    }

    /// A dark red window: something the log names went wrong for good.
    fn show_failure(&self, target: &Target) {
        if let Some(gl) = self.gl.as_ref() {
            let gl = gl.gl();
            // SAFETY: a clear of the window on the current context.
            unsafe {
                gl.bind_framebuffer(glow::FRAMEBUFFER, None);
                gl.viewport(0, 0, target.width, target.height);
                gl.clear_color(0.35, 0.0, 0.0, 1.0);
                gl.clear(glow::COLOR_BUFFER_BIT);
            }
        }
    }
}

/// The first pointer's touch in a motion event (other pointers are ignored).
fn touch_of(motion: &MotionEvent) -> Option<Touch> {
    let pointer = motion.pointer_at_index(0);
    let (x, y) = (pointer.x(), pointer.y());
    let time_ms = motion.event_time() / 1_000_000;
    match motion.action() {
        MotionAction::Down => Some(Touch::Down { x, y, time_ms }),
        MotionAction::Move => Some(Touch::Move { x, y }),
        MotionAction::Up => Some(Touch::Up { x, y, time_ms }),
        MotionAction::Cancel => Some(Touch::Cancel),
        _ => None,
    }
}
