//! A headless OpenGL ES context through EGL, loaded at run time (`libEGL.so.1`), so that a
//! machine without Mesa gets a clear error instead of a link failure.
//!
//! The library is `libEGL.so.1` unless `BRUME_EGL_LIBRARY` names another. Display order,
//! unless the caller picks one: `EGL_MESA_platform_surfaceless`, then
//! `EGL_EXT_platform_device` (the headless route on NVIDIA), then
//! `eglGetDisplay(EGL_DEFAULT_DISPLAY)`. The context is OpenGL ES 3.2 (3.0 if the driver
//! has no 3.2) with no surface where `EGL_KHR_surfaceless_context` allows it, else a 1x1
//! pbuffer.
//!
//! **Forked processes.** A display opened before a `fork()` is unusable in the child: the
//! child has a copy of the driver's state but not the driver's threads (llvmpipe's, its
//! shader queue's), so its first draw waits for them forever. Mesa keeps one display per
//! platform and native display, and hands the child that copy again, so a child skips the
//! platforms its parent opened and opens another: after a parent's surfaceless display,
//! the EGL device (`EGL_EXT_platform_device`, which on llvmpipe is
//! `EGL_MESA_device_software`), a display of its own with threads of its own. A PyTorch
//! `DataLoader`'s workers and Python's `multiprocessing` fork this way on Linux.
//!
//! **Several contexts on one thread.** Creating a context makes it current; a context
//! never releases another one: dropping a context that is not current leaves the current
//! one alone, and [`GlContext::make_current`] is how an owner gets its own back (brume's
//! [`crate::Headless`] does that before every call).

use crate::error::{Error, Result};
use khronos_egl as egl;
use std::ffi::c_void;
use std::fmt;
use std::str::FromStr;
use std::sync::{Arc, Mutex};

type EglInstance = egl::DynamicInstance<egl::EGL1_4>;

const PLATFORM_SURFACELESS_MESA: egl::Enum = 0x31DD;
const PLATFORM_DEVICE_EXT: egl::Enum = 0x313F;
const DEBIAN_PACKAGES: &str = "libegl1 libegl-mesa0 libgles2 libgl1-mesa-dri";

/// Memory below which a display that cannot be opened is likely to lack memory rather than
/// a package: llvmpipe's `eglInitialize` failed with 167-208 MB left under `ulimit -v`
/// (2 cores; more threads take more) and worked with 285 MB.
const DRIVER_START_BYTES: u64 = 320_000_000;

/// What to say of the memory `available` when no display could be opened: nothing, unless
/// it is too little for a driver to start.
fn low_memory_hint(available: Option<u64>) -> String {
    match available {
        Some(left) if left < DRIVER_START_BYTES => format!(
            "; only {} of memory can be had, which may be too little for the driver to start \
             (llvmpipe needs about {}): free memory or raise the limit",
            crate::memory::human(left),
            crate::memory::human(DRIVER_START_BYTES)
        ),
        _ => String::new(),
    }
}

/// The platforms whose display this process, or a process it was forked from, opened, with
/// the process that opened each.
static OPENED: Mutex<Vec<(Platform, u32)>> = Mutex::new(Vec::new());

/// The process this one was forked from that opened `platform`'s display, if any: the
/// display is then this process's copy of it, whose driver threads are not here. A forked
/// process also leaves `EGL_DEFAULT_DISPLAY` alone, which may be any platform's display.
fn opened_before_fork(platform: Platform) -> Option<u32> {
    let pid = std::process::id();
    let opened = OPENED.lock().unwrap_or_else(|e| e.into_inner());
    opened
        .iter()
        .find(|&&(p, by)| by != pid && (p == platform || platform == Platform::Default))
        .map(|&(_, by)| by)
}

/// Records that this process opened `platform`'s display.
fn record_opened(platform: Platform) {
    let pid = std::process::id();
    let mut opened = OPENED.lock().unwrap_or_else(|e| e.into_inner());
    if !opened.contains(&(platform, pid)) {
        opened.push((platform, pid));
    }
}

/// Environment variable naming the EGL library to load instead of `libEGL.so.1` (a
/// vendor's libEGL, or a path, e.g. `/usr/lib/x86_64-linux-gnu/libEGL_mesa.so.0`).
pub const EGL_LIBRARY_ENV: &str = "BRUME_EGL_LIBRARY";

/// Which EGL display to open.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Platform {
    /// `EGL_MESA_platform_surfaceless`: Mesa with no window system (llvmpipe, or a GPU's
    /// render node).
    Surfaceless,
    /// `EGL_EXT_platform_device`: an EGL device enumerated by `eglQueryDevicesEXT`.
    Device,
    /// `eglGetDisplay(EGL_DEFAULT_DISPLAY)`: whatever the EGL vendor picks (needs a display
    /// server unless `EGL_PLATFORM=surfaceless` is set).
    Default,
}

impl Platform {
    /// The order tried when the user does not choose.
    pub const AUTO_ORDER: [Platform; 3] =
        [Platform::Surfaceless, Platform::Device, Platform::Default];

    /// The lowercase name used by `--egl` and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Platform::Surfaceless => "surfaceless",
            Platform::Device => "device",
            Platform::Default => "default",
        }
    }
}

impl fmt::Display for Platform {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Platform {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Platform::AUTO_ORDER
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| Error::invalid("egl", s, "one of surfaceless, device, default"))
    }
}

/// An EGL display plus a current OpenGL ES context on this thread, and the `glow` function
/// table loaded from it. Not `Send`: EGL contexts belong to the thread that made them
/// current.
pub struct GlContext {
    gl: Arc<glow::Context>,
    egl: EglInstance,
    display: egl::Display,
    context: egl::Context,
    pbuffer: Option<egl::Surface>,
    platform: Platform,
    egl_vendor: String,
    egl_version: String,
}

impl fmt::Debug for GlContext {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("GlContext")
            .field("platform", &self.platform)
            .field("egl_vendor", &self.egl_vendor)
            .field("egl_version", &self.egl_version)
            .finish_non_exhaustive()
    }
}

impl GlContext {
    /// Opens a display (the given platform, or the first that works in
    /// [`Platform::AUTO_ORDER`]) and makes a GLES 3.2 context current on this thread.
    pub fn new(platform: Option<Platform>) -> Result<Self> {
        let library = std::env::var_os(EGL_LIBRARY_ENV).unwrap_or_else(|| "libEGL.so.1".into());
        // SAFETY: loading libEGL runs its initialisers; it is the system's EGL loader (or
        // the one the user named).
        let egl = unsafe { EglInstance::load_required_from_filename(&library) }.map_err(|e| {
            Error::Egl(format!(
                "cannot load {} ({e}); install Mesa's EGL and GLES: \
                 apt-get install {DEBIAN_PACKAGES}",
                library.to_string_lossy()
            ))
        })?;
        let order: Vec<Platform> = match platform {
            Some(p) => vec![p],
            None => Platform::AUTO_ORDER.to_vec(),
        };
        let mut tried = Vec::new();
        for p in order {
            if let Some(parent) = opened_before_fork(p) {
                log::debug!("EGL {p}: skipped, opened by process {parent} before a fork");
                tried.push(format!(
                    "{p}: opened by process {parent} before it forked this one, and a \
                     display's driver threads do not survive fork() (open brume's first \
                     context after the fork, or start processes with 'spawn')"
                ));
                continue;
            }
            let opened = open_display(&egl, p).and_then(|display| {
                record_opened(p);
                create_context(&egl, display)
            });
            match opened {
                Ok(parts) => {
                    return Ok(GlContext {
                        gl: Arc::new(parts.gl),
                        egl,
                        display: parts.display,
                        context: parts.context,
                        pbuffer: parts.pbuffer,
                        platform: p,
                        egl_vendor: parts.egl_vendor,
                        egl_version: parts.egl_version,
                    })
                }
                Err(reason) => {
                    log::debug!("EGL {p}: {reason}");
                    tried.push(format!("{p}: {reason}"));
                }
            }
        }
        let default_hint = if platform == Some(Platform::Default) {
            " (EGL_DEFAULT_DISPLAY needs a display server: use --egl surfaceless, or set \
             EGL_PLATFORM=surfaceless)"
        } else {
            ""
        };
        Err(Error::Egl(format!(
            "no usable display (tried {}){default_hint}{}; on Debian/Ubuntu install Mesa's \
             EGL and GLES with: apt-get install {DEBIAN_PACKAGES}",
            tried.join("; "),
            low_memory_hint(crate::memory::available())
        )))
    }

    /// The `glow` function table of this context.
    pub fn gl(&self) -> &Arc<glow::Context> {
        &self.gl
    }

    /// Whether this context is the one current on the calling thread.
    pub fn is_current(&self) -> bool {
        self.egl.get_current_context() == Some(self.context)
    }

    /// Makes this context current on the calling thread (nothing to do if it is).
    pub fn make_current(&self) -> Result<()> {
        if self.is_current() {
            return Ok(());
        }
        self.egl
            .make_current(self.display, self.pbuffer, self.pbuffer, Some(self.context))
            .map_err(|e| Error::Egl(format!("eglMakeCurrent failed: {e}")))
    }

    /// Runs `f` with this context current, then makes current again whatever context was
    /// current before (or none): for work that must not disturb another owner's context,
    /// such as deleting this context's objects.
    pub fn with_current<T>(&self, f: impl FnOnce() -> T) -> Result<T> {
        let previous = CurrentContext::save(&self.egl);
        self.make_current()?;
        let value = f();
        previous.restore(&self.egl, self);
        Ok(value)
    }

    /// The platform the display was opened on.
    pub fn platform(&self) -> Platform {
        self.platform
    }

    /// `EGL_VENDOR` of the display.
    pub fn egl_vendor(&self) -> &str {
        &self.egl_vendor
    }

    /// `EGL_VERSION` of the display.
    pub fn egl_version(&self) -> &str {
        &self.egl_version
    }
}

impl Drop for GlContext {
    fn drop(&mut self) {
        // The display is not terminated: EGL displays are process-wide singletons, and
        // terminating one would pull it from under contexts that other threads (other
        // tests, say) still use. Only this context is released, and only if it is the
        // current one: releasing unconditionally would leave another owner's context
        // non-current (the bug of two headless renderers).
        if self.is_current() {
            let _ = self.egl.make_current(self.display, None, None, None);
        }
        let _ = self.egl.destroy_context(self.display, self.context);
        if let Some(surface) = self.pbuffer.take() {
            let _ = self.egl.destroy_surface(self.display, surface);
        }
    }
}

/// The context current on the thread when [`GlContext::with_current`] started.
struct CurrentContext {
    display: Option<egl::Display>,
    draw: Option<egl::Surface>,
    read: Option<egl::Surface>,
    context: Option<egl::Context>,
}

impl CurrentContext {
    fn save(egl: &EglInstance) -> Self {
        CurrentContext {
            display: egl.get_current_display(),
            draw: egl.get_current_surface(egl::DRAW),
            read: egl.get_current_surface(egl::READ),
            context: egl.get_current_context(),
        }
    }

    /// Makes the saved context current again; with none saved, releases `ours`.
    fn restore(self, egl: &EglInstance, ours: &GlContext) {
        match (self.display, self.context) {
            (Some(display), Some(context)) if context != ours.context => {
                if let Err(e) = egl.make_current(display, self.draw, self.read, Some(context)) {
                    log::warn!("could not make the previous EGL context current again: {e}");
                }
            }
            (_, Some(_)) => {}
            (_, None) => {
                let _ = egl.make_current(ours.display, None, None, None);
            }
        }
    }
}

/// What went wrong on one platform, as one line for the error message.
type Reason = String;

fn client_extensions(egl: &EglInstance) -> String {
    egl.query_string(None, egl::EXTENSIONS)
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

fn has_extension(list: &str, name: &str) -> bool {
    list.split_ascii_whitespace().any(|e| e == name)
}

fn open_display(
    egl: &EglInstance,
    platform: Platform,
) -> std::result::Result<egl::Display, Reason> {
    let display = match platform {
        Platform::Surfaceless => {
            require_client_extension(egl, "EGL_MESA_platform_surfaceless")?;
            platform_display(egl, PLATFORM_SURFACELESS_MESA, std::ptr::null_mut())?
        }
        Platform::Device => device_display(egl)?,
        Platform::Default => {
            // SAFETY: EGL_DEFAULT_DISPLAY is the documented null native display.
            unsafe { egl.get_display(egl::DEFAULT_DISPLAY) }.ok_or_else(|| {
                "eglGetDisplay(EGL_DEFAULT_DISPLAY) returned no display".to_string()
            })?
        }
    };
    egl.initialize(display)
        .map_err(|e| format!("eglInitialize failed: {e}"))?;
    Ok(display)
}

fn require_client_extension(egl: &EglInstance, name: &str) -> std::result::Result<(), Reason> {
    if has_extension(&client_extensions(egl), name) {
        Ok(())
    } else {
        Err(format!("{name} is not offered by this libEGL"))
    }
}

type GetPlatformDisplayExt =
    unsafe extern "system" fn(egl::Enum, *mut c_void, *const egl::Int) -> egl::EGLDisplay;
type QueryDevicesExt =
    unsafe extern "system" fn(egl::Int, *mut *mut c_void, *mut egl::Int) -> egl::Boolean;

/// eglGetPlatformDisplay of EGL 1.5, or the EXT entry point on a 1.4 libEGL.
fn platform_display(
    egl: &EglInstance,
    platform: egl::Enum,
    native: *mut c_void,
) -> std::result::Result<egl::Display, Reason> {
    if let Some(egl15) = egl.upcast::<egl::EGL1_5>() {
        // SAFETY: `native` is null or an EGLDeviceEXT handle returned by the driver.
        return unsafe { egl15.get_platform_display(platform, native, &[egl::ATTRIB_NONE]) }
            .map_err(|e| format!("eglGetPlatformDisplay failed: {e}"));
    }
    let f = egl
        .get_proc_address("eglGetPlatformDisplayEXT")
        .ok_or("libEGL has neither EGL 1.5 nor eglGetPlatformDisplayEXT")?;
    // SAFETY: the EXT_platform_base signature; the attribute list is EGL_NONE-terminated.
    let raw = unsafe {
        let f: GetPlatformDisplayExt = std::mem::transmute(f);
        f(platform, native, [egl::NONE].as_ptr())
    };
    if raw.is_null() {
        Err("eglGetPlatformDisplayEXT returned no display".into())
    } else {
        // SAFETY: a non-null display handle from the driver.
        Ok(unsafe { egl::Display::from_ptr(raw) })
    }
}

/// The first EGL device whose display initialises.
fn device_display(egl: &EglInstance) -> std::result::Result<egl::Display, Reason> {
    require_client_extension(egl, "EGL_EXT_platform_device")?;
    let query = egl
        .get_proc_address("eglQueryDevicesEXT")
        .ok_or("eglQueryDevicesEXT is missing")?;
    let mut devices = [std::ptr::null_mut(); 16];
    let mut count: egl::Int = 0;
    // SAFETY: EGL_EXT_device_enumeration's signature; the array holds 16 handles.
    let ok = unsafe {
        let query: QueryDevicesExt = std::mem::transmute(query);
        query(devices.len() as egl::Int, devices.as_mut_ptr(), &mut count)
    };
    if ok != egl::TRUE || count <= 0 {
        return Err("eglQueryDevicesEXT found no device".into());
    }
    let mut errors = Vec::new();
    for (i, &device) in devices.iter().take(count as usize).enumerate() {
        match platform_display(egl, PLATFORM_DEVICE_EXT, device) {
            Ok(display) => match egl.initialize(display) {
                Ok(_) => return Ok(display),
                Err(e) => errors.push(format!("device {i}: eglInitialize: {e}")),
            },
            Err(e) => errors.push(format!("device {i}: {e}")),
        }
    }
    Err(errors.join(", "))
}

fn choose_config(
    egl: &EglInstance,
    display: egl::Display,
) -> std::result::Result<egl::Config, Reason> {
    // A surfaceless display offers pbuffer-capable configs only; asking for the default
    // EGL_WINDOW_BIT finds none. SURFACE_TYPE 0 means "any" as the last resort.
    for surface_type in [egl::PBUFFER_BIT, 0] {
        let attribs = [
            egl::RENDERABLE_TYPE,
            egl::OPENGL_ES3_BIT,
            egl::SURFACE_TYPE,
            surface_type,
            egl::NONE,
        ];
        if let Ok(Some(config)) = egl.choose_first_config(display, &attribs) {
            return Ok(config);
        }
    }
    Err("no EGLConfig with EGL_OPENGL_ES3_BIT".into())
}

/// A current context before it is wrapped in a [`GlContext`].
struct ContextParts {
    gl: glow::Context,
    display: egl::Display,
    context: egl::Context,
    pbuffer: Option<egl::Surface>,
    egl_vendor: String,
    egl_version: String,
}

fn create_context(
    egl: &EglInstance,
    display: egl::Display,
) -> std::result::Result<ContextParts, Reason> {
    egl.bind_api(egl::OPENGL_ES_API)
        .map_err(|e| format!("eglBindAPI(OPENGL_ES) failed: {e}"))?;
    let config = choose_config(egl, display)?;
    let context = [(3, 2), (3, 0)]
        .into_iter()
        .find_map(|(major, minor)| {
            let attribs = [
                egl::CONTEXT_MAJOR_VERSION,
                major,
                egl::CONTEXT_MINOR_VERSION,
                minor,
                egl::NONE,
            ];
            egl.create_context(display, config, None, &attribs).ok()
        })
        .ok_or("eglCreateContext failed for OpenGL ES 3.2 and 3.0")?;
    let display_exts = egl
        .query_string(Some(display), egl::EXTENSIONS)
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let pbuffer = if has_extension(&display_exts, "EGL_KHR_surfaceless_context") {
        None
    } else {
        let attribs = [egl::WIDTH, 1, egl::HEIGHT, 1, egl::NONE];
        Some(
            egl.create_pbuffer_surface(display, config, &attribs)
                .map_err(|e| {
                    format!("no surfaceless contexts and eglCreatePbufferSurface failed: {e}")
                })?,
        )
    };
    egl.make_current(display, pbuffer, pbuffer, Some(context))
        .map_err(|e| format!("eglMakeCurrent failed: {e}"))?;
    let query = |name| {
        egl.query_string(Some(display), name)
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    let egl_vendor = query(egl::VENDOR);
    let egl_version = query(egl::VERSION);
    // SAFETY: the context is current on this thread (glow panics otherwise), and every
    // pointer comes from eglGetProcAddress of the same libEGL.
    let gl = unsafe {
        glow::Context::from_loader_function(|name| {
            egl.get_proc_address(name)
                .map_or(std::ptr::null(), |f| f as *const c_void)
        })
    };
    Ok(ContextParts {
        gl,
        display,
        context,
        pbuffer,
        egl_vendor,
        egl_version,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A display that cannot be opened with little memory left says so, beside the
    /// packages to install; with memory to spare, or none known, it says nothing of it.
    #[test]
    fn too_little_memory_is_named_when_no_display_opens() {
        let hint = low_memory_hint(Some(167_000_000));
        assert!(
            hint.contains("only 167 MB") && hint.contains("320 MB"),
            "{hint}"
        );
        assert_eq!(low_memory_hint(Some(4_000_000_000)), "");
        assert_eq!(low_memory_hint(None), "");
    }
}
