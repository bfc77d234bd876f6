//! The camera through the NDK's Camera2 API (`libcamera2ndk`, no Java): the back camera
//! streams into an `AImageReader` of GPU-sampled `AHardwareBuffer`s (`PRIVATE` format,
//! what a `SurfaceTexture` would get); each new buffer becomes an EGLImage bound to
//! `GL_TEXTURE_EXTERNAL_OES` and is copied by `Pipeline::import_external` with the
//! transform that turns the sensor's image upright ([`Orientation`]). Where the same
//! camera also lists `DEPTH16` outputs (a time-of-flight phone), a second reader
//! streams them and the range texture is made from them: each depth image is turned
//! upright by the same orientation and cropped centrally to the colour's aspect ratio
//! ([`crate::registration`]: an approximation without calibration); when the crop is
//! smaller than the colour by one factor of 1 to 16 it is unpacked at its own size into a
//! small R32F texture and, every colour frame (the guide changes with each), upsampled
//! into the colour-sized range texture by `Pipeline::upsample_range_into` (joint
//! bilateral upsampling guided by the imported colour copy); otherwise (or when the
//! upsampling fails on this GPU) it is resampled nearest to the colour's size on the CPU,
//! and the log says why once. Elsewhere the range is a plane receding to the top of the
//! frame (the floor ahead), so the haze still grows with "distance".
//!
//! **Lifetimes.** A camera buffer must not go back to the camera while the GPU reads it:
//! the last image is held until the next one is acquired, and brume's render returns only
//! after its passes ran (it waits for its timer queries, or `glFinish`es with the wall
//! clock), the import before them included. The EGLImage is destroyed right after the
//! texture is bound to it (the texture keeps the buffer). The app's GL objects (the
//! external texture, the range texture) are made once, the depth's small texture again
//! only when its size changes; EGLImages, which are not GL objects, are made per frame,
//! and the upsampling makes its low grid's texture and two framebuffers per frame.

use crate::depth16::{self, Depth16, Depth16Error, Unpack};
use crate::orientation::Orientation;
use crate::registration::{self, Crop, DepthPath};
use crate::streams;
use brume::gpu::texture::{Filter, TexelFormat, Texture};
use brume::pipeline::{ExternalColour, RefineInput, TEXTURE_EXTERNAL_OES};
use brume::refine::DEFAULT_UPSAMPLE_SIGMA_COLOUR;
use brume::{Encoding, Input, Pipeline};
use glow::HasContext;
use khronos_egl as egl;
use ndk::hardware_buffer::{HardwareBuffer, HardwareBufferUsage};
use ndk::media::image_reader::{AcquireResult, Image, ImageFormat, ImageReader};
use ndk_sys as ffi;
use session::{choose_camera, start, Session};
use std::ffi::c_void;
use std::fmt;
use std::sync::atomic::Ordering;
use std::sync::Arc;

mod session;

// ndk-sys declares the Camera2 functions but links only libandroid; they live in
// libcamera2ndk (API 24+).
#[link(name = "camera2ndk")]
extern "C" {}

/// Buffers in flight per reader: one held for the GPU, one being acquired, one filling.
const MAX_IMAGES: i32 = 3;
/// `EGL_NATIVE_BUFFER_ANDROID`: an EGLImage's source is an Android native buffer.
const EGL_NATIVE_BUFFER_ANDROID: egl::Enum = 0x3140;
/// `EGL_IMAGE_PRESERVED_KHR`.
const EGL_IMAGE_PRESERVED_KHR: egl::Int = 0x30D2;

/// Why the camera could not be used.
#[derive(Debug)]
pub enum CameraError {
    /// A Camera2 call failed with a `camera_status_t`.
    Camera {
        /// The NDK function.
        call: &'static str,
        /// Its status.
        status: i32,
    },
    /// An image-reader call failed.
    Media(ndk::media_error::MediaError),
    /// No camera, or none that streams to the GPU.
    NoCamera(String),
    /// An EGL function or extension the import needs is missing or failed.
    Egl(String),
    /// brume refused the frame (no external-image support, a size, a GL error).
    Brume(brume::Error),
    /// A `DEPTH16` plane that cannot hold its rows.
    Depth(Depth16Error),
    /// The camera service closed the device (another app took it, or an error).
    Lost,
}

impl fmt::Display for CameraError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CameraError::Camera { call, status } => write!(f, "{call} failed (status {status})"),
            CameraError::Media(e) => write!(f, "image reader: {e}"),
            CameraError::NoCamera(why) => write!(f, "no usable camera: {why}"),
            CameraError::Egl(why) => write!(f, "EGL: {why}"),
            CameraError::Brume(e) => write!(f, "brume: {e}"),
            CameraError::Depth(e) => write!(f, "{e}"),
            CameraError::Lost => write!(f, "the camera was disconnected or failed"),
        }
    }
}

impl std::error::Error for CameraError {}

impl From<ndk::media_error::MediaError> for CameraError {
    fn from(e: ndk::media_error::MediaError) -> Self {
        CameraError::Media(e)
    }
}

impl From<brume::Error> for CameraError {
    fn from(e: brume::Error) -> Self {
        CameraError::Brume(e)
    }
}

/// Turns a `camera_status_t` into a result naming the call.
/// `eglGetNativeClientBufferANDROID`.
type GetClientBuffer = unsafe extern "C" fn(*const ffi::AHardwareBuffer) -> *mut c_void;
/// `eglCreateImageKHR` (display, context, target, buffer, attributes).
type CreateImage = unsafe extern "C" fn(
    *mut c_void,
    *mut c_void,
    egl::Enum,
    *mut c_void,
    *const egl::Int,
) -> *mut c_void;
/// `eglDestroyImageKHR`.
type DestroyImage = unsafe extern "C" fn(*mut c_void, *mut c_void) -> egl::Boolean;
/// `glEGLImageTargetTexture2DOES`.
type ImageTargetTexture = unsafe extern "C" fn(u32, *mut c_void);

/// The EGL entry points that turn an `AHardwareBuffer` into an external texture.
struct EglImages {
    display: egl::Display,
    get_client_buffer: GetClientBuffer,
    create: CreateImage,
    destroy: DestroyImage,
    target_texture: ImageTargetTexture,
}

impl EglImages {
    fn load(egl: &crate::window::Egl, display: egl::Display) -> Result<Self, CameraError> {
        let find = |name: &str, extension: &str| {
            egl.get_proc_address(name)
                .ok_or_else(|| CameraError::Egl(format!("{name} is missing ({extension})")))
        };
        let get = find(
            "eglGetNativeClientBufferANDROID",
            "EGL_ANDROID_get_native_client_buffer, API 26",
        )?;
        let create = find("eglCreateImageKHR", "EGL_KHR_image_base")?;
        let destroy = find("eglDestroyImageKHR", "EGL_KHR_image_base")?;
        let target = find("glEGLImageTargetTexture2DOES", "GL_OES_EGL_image")?;
        // SAFETY: each pointer is the named function, whose C signature the type spells.
        unsafe {
            Ok(EglImages {
                display,
                get_client_buffer: std::mem::transmute::<extern "system" fn(), GetClientBuffer>(
                    get,
                ),
                create: std::mem::transmute::<extern "system" fn(), CreateImage>(create),
                destroy: std::mem::transmute::<extern "system" fn(), DestroyImage>(destroy),
                target_texture: std::mem::transmute::<extern "system" fn(), ImageTargetTexture>(
                    target,
                ),
            })
        }
    }

    /// Binds `buffer` to `texture` on `GL_TEXTURE_EXTERNAL_OES` through a short-lived
    /// EGLImage (the texture keeps the buffer after the image is destroyed).
    fn bind(
        &self,
        gl: &glow::Context,
        buffer: &HardwareBuffer,
        texture: glow::Texture,
    ) -> Result<(), CameraError> {
        let attributes = [EGL_IMAGE_PRESERVED_KHR, egl::TRUE as egl::Int, egl::NONE];
        // SAFETY: the buffer is alive (its AImage is held); the EGLImage is made, bound to
        // a texture of the current context and destroyed here.
        unsafe {
            let client = (self.get_client_buffer)(buffer.as_ptr());
            if client.is_null() {
                return Err(CameraError::Egl(
                    "eglGetNativeClientBufferANDROID gave no buffer".into(),
                ));
            }
            let image = (self.create)(
                self.display.as_ptr(),
                std::ptr::null_mut(), // EGL_NO_CONTEXT, as native buffers require
                EGL_NATIVE_BUFFER_ANDROID,
                client,
                attributes.as_ptr(),
            );
            if image.is_null() {
                return Err(CameraError::Egl(
                    "eglCreateImageKHR failed for a camera buffer".into(),
                ));
            }
            gl.bind_texture(TEXTURE_EXTERNAL_OES, Some(texture));
            (self.target_texture)(TEXTURE_EXTERNAL_OES, image);
            gl.bind_texture(TEXTURE_EXTERNAL_OES, None);
            (self.destroy)(self.display.as_ptr(), image);
        }
        match unsafe { gl.get_error() } {
            glow::NO_ERROR => Ok(()),
            code => Err(CameraError::Egl(format!(
                "glEGLImageTargetTexture2DOES: GL error 0x{code:04X}"
            ))),
        }
    }
}

/// The camera feeding brume: its session, readers and textures.
pub struct Camera {
    // Field order is drop order: the session stops before its readers go, and the held
    // image goes back before its reader (an image must not outlive its reader).
    session: Session,
    /// The colour image the last import read, held until the next one arrives.
    held: Option<Image>,
    colour: ImageReader,
    depth: Option<ImageReader>,
    images: EglImages,
    gl: Arc<glow::Context>,
    /// The host's (this app's) external texture, bound to each new buffer.
    external: glow::Texture,
    /// The pipeline's copy of the last frame (`None` before the first): `SRGB8_ALPHA8`,
    /// read as linear values.
    copy: Option<glow::Texture>,
    /// The range brume reads, R32F at the colour's upright size.
    range: Texture,
    range_values: Vec<f32>,
    /// The latest depth at its own (cropped, upright) size, R32F, while upsampling.
    low: Option<Texture>,
    /// The upright depth size the plan was made for, and the plan.
    plan: Option<((usize, usize), Crop, DepthPath)>,
    /// The upsampling failed once (a GPU that cannot render to R32F): nearest from then on.
    upsample_failed: bool,
    orientation: Orientation,
    /// The colour stream's size as the sensor gives it.
    buffer_size: (usize, usize),
    unpack: Unpack,
}

impl Camera {
    /// Opens the back camera (one with depth if there is one) with a colour stream whose
    /// upright size fits in `fit` (the window), and starts streaming.
    pub fn open(
        gl: &Arc<glow::Context>,
        egl: (&crate::window::Egl, egl::Display),
        fit: (usize, usize),
    ) -> Result<Camera, CameraError> {
        let images = EglImages::load(egl.0, egl.1)?;
        // SAFETY: creating the manager; owned by the session from here.
        let manager = unsafe { ffi::ACameraManager_create() };
        if manager.is_null() {
            return Err(CameraError::NoCamera("ACameraManager_create failed".into()));
        }
        let mut session = Session::new(manager);
        let choice = choose_camera(manager)?;
        let buffer_size = streams::largest_fitting(&choice.colour_sizes, choice.orientation, fit)
            .ok_or_else(|| {
            CameraError::NoCamera("the camera lists no PRIVATE output".into())
        })?;
        let colour = ImageReader::new_with_usage(
            buffer_size.0 as i32,
            buffer_size.1 as i32,
            ImageFormat::PRIVATE,
            HardwareBufferUsage::GPU_SAMPLED_IMAGE,
            MAX_IMAGES,
        )?;
        let depth = match streams::largest(&choice.depth_sizes) {
            Some((w, h)) => Some(ImageReader::new(
                w as i32,
                h as i32,
                ImageFormat::DEPTH16,
                MAX_IMAGES,
            )?),
            None => None,
        };
        let mut windows = vec![colour.window()?];
        if let Some(reader) = &depth {
            windows.push(reader.window()?);
        }
        start(&mut session, &choice.id, windows)?;
        let upright = choice.orientation.upright_size(buffer_size);
        log::info!(
            "camera {:?}: {}x{} colour (upright {}x{}), {}",
            choice.id,
            buffer_size.0,
            buffer_size.1,
            upright.0,
            upright.1,
            match streams::largest(&choice.depth_sizes) {
                Some((w, h)) => format!("DEPTH16 {w}x{h}"),
                None => "no depth stream: a receding plane as range".into(),
            }
        );
        // SAFETY: one texture of the current context, deleted in Drop.
        let external = unsafe { gl.create_texture() }.map_err(CameraError::Egl)?;
        let range = Texture::new(
            gl,
            upright.0,
            upright.1,
            TexelFormat::R32F,
            Filter::Nearest,
            None,
        )?;
        let mut camera = Camera {
            session,
            colour,
            depth,
            held: None,
            images,
            gl: Arc::clone(gl),
            external,
            copy: None,
            range,
            range_values: Vec::new(),
            low: None,
            plan: None,
            upsample_failed: false,
            orientation: choice.orientation,
            buffer_size,
            unpack: Unpack::default(),
        };
        if camera.depth.is_none() {
            camera.fill_plane();
        }
        Ok(camera)
    }

    /// The range texture's far end: the depth stream's unknown range (m), or 1 for the
    /// normalised plane.
    pub fn range_unit(&self) -> f64 {
        if self.depth.is_some() {
            f64::from(self.unpack.far_m)
        } else {
            1.0
        }
    }

    /// The input of the latest frame: the newest colour buffer imported (or the last one
    /// again when none arrived), the newest depth unpacked. `None` until the first
    /// colour frame.
    pub fn input(&mut self, pipeline: &mut Pipeline) -> Result<Option<Input>, CameraError> {
        if self.session.lost.load(Ordering::Relaxed) {
            return Err(CameraError::Lost);
        }
        let mut new_colour = false;
        if let AcquireResult::Image(image) = self.colour.acquire_latest_image()? {
            // The previous image's render has finished (module docs): release it.
            self.held = None;
            self.import(&image, pipeline)?;
            self.held = Some(image);
            new_colour = true;
        }
        let new_depth = self.update_depth()?;
        if new_colour || new_depth {
            self.upsample(pipeline);
        }
        let (width, height) = self.orientation.upright_size(self.buffer_size);
        Ok(self.copy.map(|colour| Input {
            colour,
            colour_encoding: Encoding::Linear,
            depth: self.range.raw(),
            width,
            height,
            // The haze reads a range map: no camera; the frame loop sets the time.
            frame: brume::FrameInputs::default(),
        }))
    }

    fn import(&mut self, image: &Image, pipeline: &mut Pipeline) -> Result<(), CameraError> {
        let buffer = image.hardware_buffer()?;
        self.images.bind(&self.gl, &buffer, self.external)?;
        let (width, height) = self.orientation.upright_size(self.buffer_size);
        let copy = pipeline.import_external(&ExternalColour {
            texture: self.external,
            width,
            height,
            transform: self.orientation.transform(),
        })?;
        self.copy = Some(copy);
        Ok(())
    }

    /// Unpacks the newest depth image, if one came: at its cropped size into the small
    /// texture when it is to be upsampled, else resampled nearest into the range texture.
    /// Whether one came.
    fn update_depth(&mut self) -> Result<bool, CameraError> {
        let Some(reader) = &self.depth else {
            return Ok(false);
        };
        let AcquireResult::Image(image) = reader.acquire_latest_image()? else {
            return Ok(false);
        };
        let plane = Depth16 {
            data: image.plane_data(0)?,
            width: image.width()? as usize,
            height: image.height()? as usize,
            row_stride: image.plane_row_stride(0)? as usize,
        };
        let upright = self.orientation.upright_size((plane.width, plane.height));
        let colour = (self.range.width(), self.range.height());
        if self.plan.as_ref().map(|p| p.0) != Some(upright) {
            let (crop, path) = registration::plan(upright, colour);
            log_plan(upright, colour, crop, &path);
            self.plan = Some((upright, crop, path));
        }
        let Some((_, crop, path)) = &self.plan else {
            return Ok(false);
        };
        let crop = *crop;
        let upsampling = matches!(path, DepthPath::Upsample { .. }) && !self.upsample_failed;
        if upsampling {
            let size = depth16::unpack_window(
                &plane,
                self.orientation,
                crop,
                self.unpack,
                &mut self.range_values,
            )
            .map_err(CameraError::Depth)?;
            if self.low.as_ref().map(|t| (t.width(), t.height())) != Some(size) {
                self.low = Some(Texture::new(
                    &self.gl,
                    size.0,
                    size.1,
                    TexelFormat::R32F,
                    Filter::Nearest,
                    None,
                )?);
            }
            if let Some(low) = &self.low {
                upload(&self.gl, low, &self.range_values);
            }
        } else {
            depth16::unpack(
                &plane,
                self.orientation,
                crop,
                colour,
                self.unpack,
                &mut self.range_values,
            )
            .map_err(CameraError::Depth)?;
            upload(&self.gl, &self.range, &self.range_values);
        }
        Ok(true)
    }

    /// Upsamples the small depth into the range texture guided by the latest colour copy
    /// (joint bilateral upsampling, σ 0.15 in sRGB-encoded values), when both are there.
    /// A failure is logged once and turns the upsampling off: the next depth image is
    /// resampled nearest.
    fn upsample(&mut self, pipeline: &mut Pipeline) {
        if self.upsample_failed {
            return;
        }
        let (Some(colour), Some(low)) = (self.copy, &self.low) else {
            return;
        };
        let input = RefineInput {
            colour,
            // import_external's copy is SRGB8_ALPHA8: GL decodes it, shaders read linear.
            colour_encoding: Encoding::Linear,
            width: self.range.width(),
            height: self.range.height(),
            range: low.raw(),
            range_width: low.width(),
            range_height: low.height(),
        };
        if let Err(e) =
            pipeline.upsample_range_into(&input, DEFAULT_UPSAMPLE_SIGMA_COLOUR, &self.range)
        {
            log::warn!("depth: the guided upsampling failed ({e}); nearest resampling from now on");
            self.upsample_failed = true;
            self.low = None;
        }
    }

    /// Without a depth stream: normalised range from 0.1 at the bottom to 1 at the top,
    /// the floor ahead of a phone held upright.
    fn fill_plane(&mut self) {
        let (width, height) = (self.range.width(), self.range.height());
        self.range_values.clear();
        for y in 0..height {
            let r = 0.1 + 0.9 * (y as f32 + 0.5) / height as f32;
            self.range_values.extend(std::iter::repeat(r).take(width));
        }
        upload(&self.gl, &self.range, &self.range_values);
    }
}

/// Says once per depth size how the depth becomes the range, and why when not upsampled.
fn log_plan(upright: (usize, usize), colour: (usize, usize), crop: Crop, path: &DepthPath) {
    let (w, h) = upright;
    let (cw, ch) = colour;
    let cropped = if crop.size() == upright {
        "not cropped".to_string()
    } else {
        format!(
            "cropped to the centred {}x{} (the colour's aspect ratio, assumed the same field)",
            crop.width, crop.height
        )
    };
    match path {
        DepthPath::Same => log::info!("depth: {w}x{h} upright, {cropped}: the colour's {cw}x{ch}"),
        DepthPath::Upsample { factor } => log::info!(
            "depth: {w}x{h} upright, {cropped}, upsampled {factor:.2}x to {cw}x{ch} guided by the colour"
        ),
        DepthPath::Nearest { why } => log::warn!(
            "depth: {w}x{h} upright, {cropped}, resampled nearest to {cw}x{ch}: no guided upsampling ({why})"
        ),
    }
}

/// Uploads `values` (width x height f32 in GL's row order) into `texture`, R32F.
fn upload(gl: &glow::Context, texture: &Texture, values: &[f32]) {
    assert_eq!(values.len(), texture.width() * texture.height());
    // SAFETY: `values` holds width x height f32, GL's row order (depth16::unpack and
    // fill_plane write exactly that), uploaded into an owned R32F texture.
    unsafe {
        let bytes = std::slice::from_raw_parts(values.as_ptr().cast::<u8>(), values.len() * 4);
        gl.bind_texture(glow::TEXTURE_2D, Some(texture.raw()));
        gl.pixel_store_i32(glow::UNPACK_ALIGNMENT, 4);
        gl.tex_sub_image_2d(
            glow::TEXTURE_2D,
            0,
            0,
            0,
            texture.width() as i32,
            texture.height() as i32,
            glow::RED,
            glow::FLOAT,
            glow::PixelUnpackData::Slice(Some(bytes)),
        );
        gl.bind_texture(glow::TEXTURE_2D, None);
    }
}

impl Drop for Camera {
    fn drop(&mut self) {
        // SAFETY: the app's own texture, on its context (current for the app's life).
        unsafe { self.gl.delete_texture(self.external) };
    }
}
