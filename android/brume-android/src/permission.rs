//! The camera permission, asked at run time as Android 6+ requires. NativeActivity has no
//! Java of its own, so the calls go through JNI to the activity object; its answer
//! (`onRequestPermissionsResult`) is not forwarded to native code, so the app asks
//! [`camera_granted`] again while it waits.

use android_activity::AndroidApp;
use jni::objects::{JObject, JValue};
use jni::JavaVM;

const CAMERA: &str = "android.permission.CAMERA";
/// `PackageManager.PERMISSION_GRANTED`.
const GRANTED: i32 = 0;

/// Whether the app may open the camera.
pub fn camera_granted(app: &AndroidApp) -> Result<bool, jni::errors::Error> {
    with_activity(app, |env, activity| {
        let name = env.new_string(CAMERA)?;
        let status = env
            .call_method(
                activity,
                "checkSelfPermission",
                "(Ljava/lang/String;)I",
                &[JValue::Object(&name)],
            )?
            .i()?;
        Ok(status == GRANTED)
    })
}

/// Shows Android's permission dialog for the camera (returns at once; the answer is read
/// later by [`camera_granted`]).
pub fn request_camera(app: &AndroidApp) -> Result<(), jni::errors::Error> {
    with_activity(app, |env, activity| {
        let name = env.new_string(CAMERA)?;
        let names = env.new_object_array(1, "java/lang/String", &name)?;
        env.call_method(
            activity,
            "requestPermissions",
            "([Ljava/lang/String;I)V",
            &[JValue::Object(&names), JValue::Int(1)],
        )?;
        Ok(())
    })
}

/// Runs `f` with this thread attached to the VM and the activity object; a Java
/// exception is cleared (and returned as the error) so that later JNI calls work.
fn with_activity<T>(
    app: &AndroidApp,
    f: impl FnOnce(&mut jni::JNIEnv, &JObject) -> Result<T, jni::errors::Error>,
) -> Result<T, jni::errors::Error> {
    // SAFETY: android-activity gives the process's JavaVM and a global reference to the
    // activity, both valid while the app runs.
    let vm = unsafe { JavaVM::from_raw(app.vm_as_ptr().cast()) }?;
    let mut env = vm.attach_current_thread()?;
    // SAFETY: as above; the reference is not deleted here (JObject does not own it).
    let activity = unsafe { JObject::from_raw(app.activity_as_ptr().cast()) };
    let result = f(&mut env, &activity);
    if env.exception_check().unwrap_or(false) {
        let _ = env.exception_clear();
    }
    result
}
