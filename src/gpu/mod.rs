//! GL objects with owners: each wrapper holds an `Arc<glow::Context>` and deletes its object
//! in `Drop`, so nothing leaks when a render fails half-way.

pub mod framebuffer;
pub mod program;
pub mod texture;
pub mod timer;

use crate::error::{Error, Result};
use glow::HasContext;

/// Turns a pending `glGetError` into an error naming `what` was being done. Called at the
/// few points where a failure would otherwise surface as garbage pixels.
pub fn check_gl(gl: &glow::Context, what: &str) -> Result<()> {
    // SAFETY: glGetError has no preconditions.
    let code = unsafe { gl.get_error() };
    if code == glow::NO_ERROR {
        Ok(())
    } else {
        Err(Error::Gl(format!("{what}: glGetError = 0x{code:04X}")))
    }
}
