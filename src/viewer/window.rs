//! The viewer's window and its GL context: winit for the window, glutin for EGL on it.
//! A GLES 3.2 context where the driver has one, GLES 3.0 next, desktop GL last (brume's
//! shaders run there through `ARB_ES3_compatibility`).

use brume::{Error, Result};
use glutin::config::{Api, Config, ConfigTemplateBuilder, GlConfig};
use glutin::context::{
    ContextApi, ContextAttributesBuilder, NotCurrentContext, NotCurrentGlContext,
    PossiblyCurrentContext, Version,
};
use glutin::display::{Display, DisplayApiPreference, GlDisplay};
use glutin::surface::{GlSurface, Surface, SurfaceAttributesBuilder, SwapInterval, WindowSurface};
use glutin_winit::GlWindow;
use std::ffi::CString;
use std::num::NonZeroU32;
use std::sync::Arc;
use winit::dpi::LogicalSize;
use winit::event_loop::ActiveEventLoop;
use winit::raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::Window;

/// A window with a current GL context on its surface. Field order is drop order: the
/// surface and context go before the window they draw to.
pub struct ViewerWindow {
    pub gl: Arc<glow::Context>,
    surface: Surface<WindowSurface>,
    context: PossiblyCurrentContext,
    pub window: Window,
}

/// The error of a failed window step, with what to do instead.
fn window_error(what: &str, detail: impl std::fmt::Display) -> Error {
    Error::Window {
        what: what.into(),
        detail: detail.to_string(),
        hint: "check that the display works (e.g. `glxinfo -B` or `eglinfo`), or use \
               `brume render` to render to a file without a window"
            .into(),
    }
}

impl ViewerWindow {
    /// Opens a window of `size` (logical px) titled `title`, with a GL context current on
    /// it and swaps that wait for the display's refresh unless `vsync` is false.
    pub fn open(
        event_loop: &ActiveEventLoop,
        title: &str,
        size: LogicalSize<f64>,
        vsync: bool,
    ) -> Result<Self> {
        let display = open_display(event_loop)?;
        let config = pick_config(&display)?;
        let attributes = Window::default_attributes()
            .with_title(title)
            .with_inner_size(size);
        let window = glutin_winit::finalize_window(event_loop, attributes, &config)
            .map_err(|e| window_error("creating the window", e))?;
        let context = create_context(&display, &config, &window)?;
        let size = window.inner_size();
        let (w, h) = match (NonZeroU32::new(size.width), NonZeroU32::new(size.height)) {
            (Some(w), Some(h)) => (w, h),
            _ => return Err(window_error("creating the window", "it has no area")),
        };
        let handle = window
            .window_handle()
            .map_err(|e| window_error("the window's handle", e))?
            .as_raw();
        let surface_attributes =
            SurfaceAttributesBuilder::<WindowSurface>::new().build(handle, w, h);
        // SAFETY: the window outlives the surface (field order above).
        let surface = unsafe { display.create_window_surface(&config, &surface_attributes) }
            .map_err(|e| window_error("creating the window's GL surface", e))?;
        let context = context
            .make_current(&surface)
            .map_err(|e| window_error("making the GL context current", e))?;
        let interval = if vsync {
            SwapInterval::Wait(NonZeroU32::MIN)
        } else {
            SwapInterval::DontWait
        };
        if let Err(e) = surface.set_swap_interval(&context, interval) {
            log::debug!("swap interval not set: {e}");
        }
        // SAFETY: the loader returns the display's entry points for the current context.
        let gl = unsafe {
            glow::Context::from_loader_function(|name| {
                let name = CString::new(name).expect("GL function names have no NUL");
                display.get_proc_address(&name)
            })
        };
        Ok(ViewerWindow {
            gl: Arc::new(gl),
            surface,
            context,
            window,
        })
    }

    /// Follows the window's size after a resize.
    pub fn resize(&self) {
        self.window.resize_surface(&self.surface, &self.context);
    }

    /// Shows what was drawn.
    pub fn swap(&self) -> Result<()> {
        self.surface
            .swap_buffers(&self.context)
            .map_err(|e| window_error("presenting the frame", e))
    }
}

/// EGL on the event loop's display (X11 or Wayland). EGL only: Mesa, NVIDIA and AMD all
/// have it, and it gives GLES contexts as phones do.
fn open_display(event_loop: &ActiveEventLoop) -> Result<Display> {
    let handle = event_loop
        .display_handle()
        .map_err(|e| window_error("the display's handle", e))?
        .as_raw();
    // SAFETY: the handle is the event loop's, which outlives the viewer.
    unsafe { Display::new(handle, DisplayApiPreference::Egl) }
        .map_err(|e| window_error("opening EGL on the display", e))
}

/// An RGBA8 window config that can make a GLES 3 (or desktop GL) context, without
/// multisampling: the frame is brume's image, drawn texel for texel.
fn pick_config(display: &Display) -> Result<Config> {
    let template = ConfigTemplateBuilder::new()
        .with_alpha_size(8)
        .with_api(Api::GLES3 | Api::OPENGL)
        .build();
    // SAFETY: the template has no native window to outlive.
    let configs = unsafe { display.find_configs(template) }
        .map_err(|e| window_error("finding an RGBA8 GLES 3 window config", e))?;
    configs
        .filter(|c| c.api().intersects(Api::GLES3 | Api::OPENGL))
        .min_by_key(|c| (c.num_samples(), !c.api().contains(Api::GLES3)))
        .ok_or_else(|| {
            window_error(
                "finding an RGBA8 GLES 3 window config",
                "the display offers none",
            )
        })
}

/// GLES 3.2, else 3.0, else desktop GL 3.3 core.
fn create_context(
    display: &Display,
    config: &Config,
    window: &Window,
) -> Result<NotCurrentContext> {
    let handle = window
        .window_handle()
        .map_err(|e| window_error("the window's handle", e))?
        .as_raw();
    let apis = [
        ContextApi::Gles(Some(Version::new(3, 2))),
        ContextApi::Gles(Some(Version::new(3, 0))),
        ContextApi::OpenGl(Some(Version::new(3, 3))),
    ];
    let mut last = None;
    for api in apis {
        let attributes = ContextAttributesBuilder::new()
            .with_context_api(api)
            .build(Some(handle));
        // SAFETY: the config belongs to this display.
        match unsafe { display.create_context(config, &attributes) } {
            Ok(context) => {
                log::info!("viewer context: {api:?}");
                return Ok(context);
            }
            Err(e) => last = Some(e),
        }
    }
    Err(window_error(
        "creating a GLES 3 or GL 3.3 context",
        last.map_or_else(String::new, |e| e.to_string()),
    ))
}

/// Whether a display server is named in the environment at all.
pub fn display_named() -> bool {
    ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|s| !s.is_empty()))
}
