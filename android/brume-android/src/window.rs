//! The app's EGL: one display, one OpenGL ES context (3.2 where the driver has it, else
//! 3.0) kept for the app's whole life, and a window surface for each `ANativeWindow`
//! Android hands over. Between windows (the app in the background) the context is
//! current on a 1 x 1 pbuffer, so brume's GL objects stay valid and can always be deleted
//! with their context current.

use khronos_egl as egl;
use ndk::native_window::NativeWindow;
use std::ffi::c_void;
use std::sync::Arc;

/// The EGL instance, loaded from the system's `libEGL.so` at run time.
pub type Egl = egl::DynamicInstance<egl::EGL1_4>;

/// The display, the context and the current surface.
pub struct WindowGl {
    egl: Egl,
    display: egl::Display,
    config: egl::Config,
    context: egl::Context,
    /// Current when no window is.
    pbuffer: egl::Surface,
    /// The window's surface and the window it draws into (held so that it lives as long).
    window: Option<(egl::Surface, NativeWindow)>,
    gl: Arc<glow::Context>,
}

impl WindowGl {
    /// Opens the default display and makes a GLES 3.2 (else 3.0) context current on a
    /// pbuffer; loads the GL functions.
    pub fn new() -> Result<WindowGl, String> {
        // SAFETY: loading the system's libEGL, which every Android device has.
        let egl =
            unsafe { Egl::load_required() }.map_err(|e| format!("cannot load libEGL: {e}"))?;
        // SAFETY: EGL_DEFAULT_DISPLAY is the documented null native display.
        let display = unsafe { egl.get_display(egl::DEFAULT_DISPLAY) }
            .ok_or("eglGetDisplay(EGL_DEFAULT_DISPLAY) gave no display")?;
        egl.initialize(display)
            .map_err(|e| format!("eglInitialize: {e}"))?;
        egl.bind_api(egl::OPENGL_ES_API)
            .map_err(|e| format!("eglBindAPI: {e}"))?;
        let config = egl
            .choose_first_config(
                display,
                &[
                    egl::RENDERABLE_TYPE,
                    egl::OPENGL_ES3_BIT,
                    egl::SURFACE_TYPE,
                    egl::WINDOW_BIT | egl::PBUFFER_BIT,
                    egl::RED_SIZE,
                    8,
                    egl::GREEN_SIZE,
                    8,
                    egl::BLUE_SIZE,
                    8,
                    egl::NONE,
                ],
            )
            .map_err(|e| format!("eglChooseConfig: {e}"))?
            .ok_or("no EGL config for OpenGL ES 3 windows (the device has no GLES 3)")?;
        let context = [(3, 2), (3, 0)]
            .into_iter()
            .find_map(|(major, minor)| {
                let attributes = [
                    egl::CONTEXT_MAJOR_VERSION,
                    major,
                    egl::CONTEXT_MINOR_VERSION,
                    minor,
                    egl::NONE,
                ];
                egl.create_context(display, config, None, &attributes).ok()
            })
            .ok_or("eglCreateContext failed for OpenGL ES 3.2 and 3.0")?;
        let pbuffer = egl
            .create_pbuffer_surface(display, config, &[egl::WIDTH, 1, egl::HEIGHT, 1, egl::NONE])
            .map_err(|e| format!("eglCreatePbufferSurface: {e}"))?;
        egl.make_current(display, Some(pbuffer), Some(pbuffer), Some(context))
            .map_err(|e| format!("eglMakeCurrent: {e}"))?;
        // SAFETY: the context is current on this thread; the pointers come from its libEGL.
        let gl = unsafe {
            glow::Context::from_loader_function(|name| {
                egl.get_proc_address(name)
                    .map_or(std::ptr::null(), |f| f as *const c_void)
            })
        };
        Ok(WindowGl {
            egl,
            display,
            config,
            context,
            pbuffer,
            window: None,
            gl: Arc::new(gl),
        })
    }

    /// The GL functions of the context.
    pub fn gl(&self) -> &Arc<glow::Context> {
        &self.gl
    }

    /// The EGL instance and display, for the camera's EGLImages.
    pub fn egl(&self) -> (&Egl, egl::Display) {
        (&self.egl, self.display)
    }

    /// Draws into `window` from now on.
    pub fn attach(&mut self, window: NativeWindow) -> Result<(), String> {
        self.detach();
        // SAFETY: the window is alive (held in `self.window` as long as the surface).
        let surface = unsafe {
            self.egl.create_window_surface(
                self.display,
                self.config,
                window.ptr().as_ptr() as egl::NativeWindowType,
                None,
            )
        }
        .map_err(|e| format!("eglCreateWindowSurface: {e}"))?;
        self.egl
            .make_current(
                self.display,
                Some(surface),
                Some(surface),
                Some(self.context),
            )
            .map_err(|e| format!("eglMakeCurrent on the window: {e}"))?;
        // Vsync: the frame loop runs at the display's rate, not faster.
        let _ = self.egl.swap_interval(self.display, 1);
        self.window = Some((surface, window));
        Ok(())
    }

    /// Stops drawing into the window (Android is taking it away); the context stays
    /// current on the pbuffer.
    pub fn detach(&mut self) {
        if let Some((surface, _window)) = self.window.take() {
            let _ = self.egl.make_current(
                self.display,
                Some(self.pbuffer),
                Some(self.pbuffer),
                Some(self.context),
            );
            let _ = self.egl.destroy_surface(self.display, surface);
        }
    }

    /// Whether a window is attached.
    pub fn has_window(&self) -> bool {
        self.window.is_some()
    }

    /// The window surface's size in pixels.
    pub fn size(&self) -> Option<(i32, i32)> {
        let (surface, _) = self.window.as_ref()?;
        let width = self
            .egl
            .query_surface(self.display, *surface, egl::WIDTH)
            .ok()?;
        let height = self
            .egl
            .query_surface(self.display, *surface, egl::HEIGHT)
            .ok()?;
        Some((width, height))
    }

    /// Shows the frame drawn.
    pub fn swap(&self) -> Result<(), String> {
        let (surface, _) = self.window.as_ref().ok_or("no window to show")?;
        self.egl
            .swap_buffers(self.display, *surface)
            .map_err(|e| format!("eglSwapBuffers: {e}"))
    }
}

impl Drop for WindowGl {
    fn drop(&mut self) {
        self.detach();
        let _ = self.egl.make_current(self.display, None, None, None);
        let _ = self.egl.destroy_surface(self.display, self.pbuffer);
        let _ = self.egl.destroy_context(self.display, self.context);
        let _ = self.egl.terminate(self.display);
    }
}
