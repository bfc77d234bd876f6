//! The Camera2 side of the camera: choosing one (the back camera with `DEPTH16` if there
//! is one), and the objects of its capture session, freed in reverse order.

use super::CameraError;
use crate::orientation::Orientation;
use crate::streams;
use ndk::native_window::NativeWindow;
use ndk_sys as ffi;
use std::ffi::{c_void, CStr, CString};
use std::sync::atomic::{AtomicBool, Ordering};

fn check(call: &'static str, status: ffi::camera_status_t) -> Result<(), CameraError> {
    if status == ffi::camera_status_t::ACAMERA_OK {
        Ok(())
    } else {
        Err(CameraError::Camera {
            call,
            status: status.0,
        })
    }
}

/// What the app needs to know of one camera.
pub(super) struct Choice {
    pub id: CString,
    pub orientation: Orientation,
    pub colour_sizes: Vec<(usize, usize)>,
    pub depth_sizes: Vec<(usize, usize)>,
}

/// The Camera2 objects of one running capture session, freed in reverse order.
pub(super) struct Session {
    manager: *mut ffi::ACameraManager,
    device: *mut ffi::ACameraDevice,
    container: *mut ffi::ACaptureSessionOutputContainer,
    outputs: Vec<*mut ffi::ACaptureSessionOutput>,
    targets: Vec<*mut ffi::ACameraOutputTarget>,
    request: *mut ffi::ACaptureRequest,
    session: *mut ffi::ACameraCaptureSession,
    /// The readers' windows, held while the session draws into them.
    windows: Vec<NativeWindow>,
    // Boxed: the camera service keeps pointers to them.
    device_callbacks: Box<ffi::ACameraDevice_StateCallbacks>,
    session_callbacks: Box<ffi::ACameraCaptureSession_stateCallbacks>,
    /// Set by the camera service's callbacks when the device is lost.
    pub lost: Box<AtomicBool>,
}

impl Session {
    /// A session of `manager` (which it owns from here) with nothing opened yet.
    pub fn new(manager: *mut ffi::ACameraManager) -> Session {
        let mut session = Session {
            manager,
            device: std::ptr::null_mut(),
            container: std::ptr::null_mut(),
            outputs: Vec::new(),
            targets: Vec::new(),
            request: std::ptr::null_mut(),
            session: std::ptr::null_mut(),
            windows: Vec::new(),
            device_callbacks: Box::new(ffi::ACameraDevice_StateCallbacks {
                context: std::ptr::null_mut(),
                onDisconnected: Some(device_lost),
                onError: Some(device_error),
            }),
            session_callbacks: Box::new(ffi::ACameraCaptureSession_stateCallbacks {
                context: std::ptr::null_mut(),
                onClosed: Some(session_state),
                onReady: Some(session_state),
                onActive: Some(session_state),
            }),
            lost: Box::new(AtomicBool::new(false)),
        };
        session.device_callbacks.context = std::ptr::addr_of!(*session.lost).cast_mut().cast();
        session
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        // SAFETY: every pointer was made by the matching create call and is freed once,
        // session first, as the NDK's samples do; null ones were never made.
        unsafe {
            if !self.session.is_null() {
                ffi::ACameraCaptureSession_stopRepeating(self.session);
                ffi::ACameraCaptureSession_close(self.session);
            }
            if !self.request.is_null() {
                ffi::ACaptureRequest_free(self.request);
            }
            for &target in &self.targets {
                ffi::ACameraOutputTarget_free(target);
            }
            if !self.container.is_null() {
                ffi::ACaptureSessionOutputContainer_free(self.container);
            }
            for &output in &self.outputs {
                ffi::ACaptureSessionOutput_free(output);
            }
            if !self.device.is_null() {
                ffi::ACameraDevice_close(self.device);
            }
            ffi::ACameraManager_delete(self.manager);
        }
        let _ = (&self.device_callbacks, &self.session_callbacks);
    }
}

unsafe extern "C" fn device_lost(context: *mut c_void, _device: *mut ffi::ACameraDevice) {
    log::warn!("camera disconnected");
    // SAFETY: the context is the session's boxed flag, alive while the device is open.
    unsafe { (*context.cast::<AtomicBool>()).store(true, Ordering::Relaxed) };
}

unsafe extern "C" fn device_error(
    context: *mut c_void,
    _device: *mut ffi::ACameraDevice,
    error: std::os::raw::c_int,
) {
    log::error!("camera device error {error}");
    // SAFETY: as in device_lost.
    unsafe { (*context.cast::<AtomicBool>()).store(true, Ordering::Relaxed) };
}

unsafe extern "C" fn session_state(
    _context: *mut c_void,
    _session: *mut ffi::ACameraCaptureSession,
) {
}

/// The back camera with a `DEPTH16` output if there is one, else the first back camera,
/// else the first camera.
pub(super) fn choose_camera(manager: *mut ffi::ACameraManager) -> Result<Choice, CameraError> {
    let mut list: *mut ffi::ACameraIdList = std::ptr::null_mut();
    // SAFETY: the list is freed below; its ids are copied before.
    let ids: Vec<CString> = unsafe {
        check(
            "ACameraManager_getCameraIdList",
            ffi::ACameraManager_getCameraIdList(manager, &mut list),
        )?;
        let ids = std::slice::from_raw_parts((*list).cameraIds, (*list).numCameras.max(0) as usize)
            .iter()
            .map(|&id| CStr::from_ptr(id).to_owned())
            .collect();
        ffi::ACameraManager_deleteCameraIdList(list);
        ids
    };
    let mut candidates = Vec::new();
    for id in ids {
        match describe(manager, id) {
            Ok(c) => candidates.push(c),
            Err(e) => log::warn!("camera skipped: {e}"),
        }
    }
    let rank = |c: &(Choice, bool)| match (c.1, !c.0.depth_sizes.is_empty()) {
        (true, true) => 0,
        (true, false) => 1,
        _ => 2,
    };
    candidates.sort_by_key(rank);
    candidates
        .into_iter()
        .map(|(choice, _)| choice)
        .find(|c| !c.colour_sizes.is_empty())
        .ok_or_else(|| CameraError::NoCamera("no camera streams PRIVATE buffers".into()))
}

/// A camera's orientation and stream sizes, and whether it faces back.
fn describe(manager: *mut ffi::ACameraManager, id: CString) -> Result<(Choice, bool), CameraError> {
    let mut metadata: *mut ffi::ACameraMetadata = std::ptr::null_mut();
    // SAFETY: the metadata is freed below; entries are copied out before.
    unsafe {
        check(
            "ACameraManager_getCameraCharacteristics",
            ffi::ACameraManager_getCameraCharacteristics(manager, id.as_ptr(), &mut metadata),
        )?;
        let facing = entry_u8(metadata, ffi::acamera_metadata_tag::ACAMERA_LENS_FACING);
        let back = facing.first().map(|&f| u32::from(f))
            == Some(ffi::acamera_metadata_enum_acamera_lens_facing::ACAMERA_LENS_FACING_BACK.0);
        let degrees = entry_i32(
            metadata,
            ffi::acamera_metadata_tag::ACAMERA_SENSOR_ORIENTATION,
        );
        let capabilities = entry_u8(
            metadata,
            ffi::acamera_metadata_tag::ACAMERA_REQUEST_AVAILABLE_CAPABILITIES,
        );
        let depth_output = ffi::acamera_metadata_enum_acamera_request_available_capabilities::ACAMERA_REQUEST_AVAILABLE_CAPABILITIES_DEPTH_OUTPUT.0;
        let has_depth = capabilities.iter().any(|&c| u32::from(c) == depth_output);
        let colour = entry_i32(
            metadata,
            ffi::acamera_metadata_tag::ACAMERA_SCALER_AVAILABLE_STREAM_CONFIGURATIONS,
        );
        let depth = if has_depth {
            entry_i32(
                metadata,
                ffi::acamera_metadata_tag::ACAMERA_DEPTH_AVAILABLE_DEPTH_STREAM_CONFIGURATIONS,
            )
        } else {
            Vec::new()
        };
        ffi::ACameraMetadata_free(metadata);
        Ok((
            Choice {
                orientation: Orientation::from_sensor_degrees(
                    degrees.first().copied().unwrap_or(0),
                ),
                colour_sizes: streams::output_sizes(
                    &colour,
                    ffi::AIMAGE_FORMATS::AIMAGE_FORMAT_PRIVATE.0 as i32,
                ),
                depth_sizes: streams::output_sizes(
                    &depth,
                    ffi::AIMAGE_FORMATS::AIMAGE_FORMAT_DEPTH16.0 as i32,
                ),
                id,
            },
            back,
        ))
    }
}

/// An `i32` entry of a camera's characteristics (empty when absent).
unsafe fn entry_i32(
    metadata: *const ffi::ACameraMetadata,
    tag: ffi::acamera_metadata_tag,
) -> Vec<i32> {
    let mut entry = std::mem::zeroed::<ffi::ACameraMetadata_const_entry>();
    if ffi::ACameraMetadata_getConstEntry(metadata, tag.0, &mut entry)
        != ffi::camera_status_t::ACAMERA_OK
    {
        return Vec::new();
    }
    std::slice::from_raw_parts(entry.data.i32_, entry.count as usize).to_vec()
}

/// A `u8` (enum) entry of a camera's characteristics (empty when absent).
unsafe fn entry_u8(
    metadata: *const ffi::ACameraMetadata,
    tag: ffi::acamera_metadata_tag,
) -> Vec<u8> {
    let mut entry = std::mem::zeroed::<ffi::ACameraMetadata_const_entry>();
    if ffi::ACameraMetadata_getConstEntry(metadata, tag.0, &mut entry)
        != ffi::camera_status_t::ACAMERA_OK
    {
        return Vec::new();
    }
    std::slice::from_raw_parts(entry.data.u8_, entry.count as usize).to_vec()
}

/// Opens camera `id` and starts a repeating preview request into `windows` (the
/// readers'), filling `session` as it goes so that a failure frees what was made.
pub(super) fn start(
    session: &mut Session,
    id: &CStr,
    windows: Vec<NativeWindow>,
) -> Result<(), CameraError> {
    // SAFETY: Camera2 calls in their documented order; every object made is recorded in
    // `session` at once, whose Drop frees it; the windows are held by the session.
    unsafe {
        check(
            "ACameraManager_openCamera",
            ffi::ACameraManager_openCamera(
                session.manager,
                id.as_ptr(),
                &mut *session.device_callbacks,
                &mut session.device,
            ),
        )?;
        check(
            "ACaptureSessionOutputContainer_create",
            ffi::ACaptureSessionOutputContainer_create(&mut session.container),
        )?;
        check(
            "ACameraDevice_createCaptureRequest",
            ffi::ACameraDevice_createCaptureRequest(
                session.device,
                ffi::ACameraDevice_request_template::TEMPLATE_PREVIEW,
                &mut session.request,
            ),
        )?;
        session.windows = windows;
        for window in &session.windows {
            let mut output = std::ptr::null_mut();
            check(
                "ACaptureSessionOutput_create",
                ffi::ACaptureSessionOutput_create(window.ptr().as_ptr(), &mut output),
            )?;
            session.outputs.push(output);
            check(
                "ACaptureSessionOutputContainer_add",
                ffi::ACaptureSessionOutputContainer_add(session.container, output),
            )?;
            let mut target = std::ptr::null_mut();
            check(
                "ACameraOutputTarget_create",
                ffi::ACameraOutputTarget_create(window.ptr().as_ptr(), &mut target),
            )?;
            session.targets.push(target);
            check(
                "ACaptureRequest_addTarget",
                ffi::ACaptureRequest_addTarget(session.request, target),
            )?;
        }
        check(
            "ACameraDevice_createCaptureSession",
            ffi::ACameraDevice_createCaptureSession(
                session.device,
                session.container,
                &*session.session_callbacks,
                &mut session.session,
            ),
        )?;
        check(
            "ACameraCaptureSession_setRepeatingRequest",
            ffi::ACameraCaptureSession_setRepeatingRequest(
                session.session,
                std::ptr::null_mut(),
                1,
                &mut session.request,
                std::ptr::null_mut(),
            ),
        )
    }
}
