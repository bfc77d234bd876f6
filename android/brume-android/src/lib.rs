//! brume live on Android: a NativeActivity (no Java or Kotlin) that renders brume's haze
//! every frame into its window, on the built-in demo RGBD image or on the camera, with
//! touch controls and the per-pass GPU times on screen.
//!
//! - A horizontal drag sets the haze's density (κa + κs), a vertical drag its blur (λ),
//!   a double tap switches between the demo and the camera ([`controls`]).
//! - The camera comes through the NDK's Camera2 API into an `AImageReader` whose
//!   `AHardwareBuffer`s are bound, as EGLImages, to `GL_TEXTURE_EXTERNAL_OES` and copied
//!   by `brume::Pipeline::import_external`; a camera that also streams `DEPTH16` gives
//!   the range ([`depth16`], laid over the colour and upsampled guided by it:
//!   [`registration`]), one without gives a plane receding to the top of the frame.
//! - The per-pass GPU times (`GL_TIME_ELAPSED`, `Timing::Deferred`: a frame or more late,
//!   never waited for) are drawn as a bar and digits by `glScissor` + `glClear`
//!   ([`overlay`]) and logged to logcat once a second.
//!
//! The modules without Android in them ([`controls`], [`depth16`], [`orientation`],
//! [`overlay`], [`registration`], [`streams`], [`live`]) build and are tested on any host
//! (`cargo test -p brume-android`, the frame loop on llvmpipe); the rest builds for
//! Android only.

pub mod controls;
pub mod depth16;
pub mod live;
pub mod orientation;
pub mod overlay;
pub mod registration;
pub mod streams;

#[cfg(target_os = "android")]
mod app;
#[cfg(target_os = "android")]
mod camera;
#[cfg(target_os = "android")]
mod permission;
#[cfg(target_os = "android")]
mod window;

/// The entry point NativeActivity's glue calls (through android-activity) on its own
/// thread once the library is loaded.
#[cfg(target_os = "android")]
#[no_mangle]
fn android_main(app: android_activity::AndroidApp) {
    app::run(app);
}
