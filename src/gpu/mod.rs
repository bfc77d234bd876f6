//! GL objects with owners: each wrapper holds an `Arc<glow::Context>` and deletes its object
//! in `Drop`, so nothing leaks when a render fails half-way.

pub mod framebuffer;
pub mod program;
pub(crate) mod state;
pub mod texture;
pub mod timer;

use crate::error::{Error, Result};
use glow::HasContext;
use std::sync::atomic::{AtomicUsize, Ordering};

/// GL objects brume owns now (textures, framebuffers, programs, vertex arrays, queries),
/// over every context of the process: what a leak test watches.
static LIVE_OBJECTS: AtomicUsize = AtomicUsize::new(0);

/// GL objects brume has created since the process started, deleted or not: a frame loop
/// that reuses its textures and targets leaves it unchanged from one frame to the next.
static CREATED_OBJECTS: AtomicUsize = AtomicUsize::new(0);

/// The number of GL objects brume has created and not yet deleted, in this process.
pub fn live_objects() -> usize {
    LIVE_OBJECTS.load(Ordering::Relaxed)
}

/// The number of GL objects brume has created in this process, deleted or not.
pub fn objects_created() -> usize {
    CREATED_OBJECTS.load(Ordering::Relaxed)
}

/// Counts an object an owner has just taken.
pub(crate) fn object_created() {
    LIVE_OBJECTS.fetch_add(1, Ordering::Relaxed);
    CREATED_OBJECTS.fetch_add(1, Ordering::Relaxed);
}

/// Counts an object its owner has just deleted.
pub(crate) fn object_deleted() {
    LIVE_OBJECTS.fetch_sub(1, Ordering::Relaxed);
}

/// Turns a pending `glGetError` into an error naming `what` was being done. Called at the
/// few points where a failure would otherwise surface as garbage pixels.
pub fn check_gl(gl: &glow::Context, what: &str) -> Result<()> {
    // SAFETY: glGetError has no preconditions.
    let code = unsafe { gl.get_error() };
    match code {
        glow::NO_ERROR => Ok(()),
        glow::OUT_OF_MEMORY => Err(Error::OutOfMemory {
            what: what.to_string(),
            detail: "failed: the GL driver has no memory left (GL_OUT_OF_MEMORY)".into(),
            hint: "use a smaller image, or precision f16 (half the texture memory)".into(),
        }),
        _ => Err(Error::Gl(format!(
            "{what}: glGetError = 0x{code:04X} ({})",
            error_name(code)
        ))),
    }
}

/// The name of a `glGetError` code.
fn error_name(code: u32) -> &'static str {
    match code {
        glow::INVALID_ENUM => "GL_INVALID_ENUM",
        glow::INVALID_VALUE => "GL_INVALID_VALUE",
        glow::INVALID_OPERATION => "GL_INVALID_OPERATION",
        glow::INVALID_FRAMEBUFFER_OPERATION => "GL_INVALID_FRAMEBUFFER_OPERATION",
        glow::OUT_OF_MEMORY => "GL_OUT_OF_MEMORY",
        _ => "unknown",
    }
}
