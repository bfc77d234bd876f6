//! An engine's camera as it is ([`MatrixCamera`]), the clip depth conventions of depth
//! buffers ([`ClipDepth`]), the depth model every eye-depth path shares ([`DepthModel`]),
//! and the camera a frame gives its medium ([`FrameCamera`]). See the parent module's docs.

use super::{pixel_ndc, Camera};
use crate::error::{Error, Result};
use glam::{DMat4, DVec3, DVec4};

/// How the API that drew a depth buffer maps clip-space depth to the buffer: the
/// window depth d ∈ [0, 1] brume reads is `(z_ndc + 1)/2` or `z_ndc` (with the default
/// depth range 0..1, `glDepthRangef(0, 1)` or a viewport's minDepth 0, maxDepth 1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ClipDepth {
    /// OpenGL's default: clip z in [−w, w], d = (z_ndc + 1)/2. brume's own [`Camera`].
    #[default]
    MinusOneToOne,
    /// Direct3D, Vulkan, Metal, wgpu (so Bevy), Unreal, and OpenGL with
    /// `glClipControl(…, GL_ZERO_TO_ONE)`: clip z in [0, w], d = z_ndc.
    ZeroToOne,
}

impl ClipDepth {
    /// `(s, o)` with z_ndc = s·d + o.
    fn window_to_ndc(self) -> (f64, f64) {
        match self {
            ClipDepth::MinusOneToOne => (2.0, -1.0),
            ClipDepth::ZeroToOne => (1.0, 0.0),
        }
    }
}

/// The largest eye depth a pixel at an infinite far plane gets by default (world units):
/// what the media see for a sky drawn at infinity ([`MatrixCamera::with_sky_depth`]).
pub const DEFAULT_SKY_DEPTH: f64 = 10_000.0;

/// Eye depth from window depth for any perspective projection: `t = a / ((d − k) − c)`,
/// clamped to `max` (module docs of [`MatrixCamera`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthModel {
    /// The numerator a (negative for a standard projection, positive for reversed-Z).
    pub a: f64,
    /// The integer part k ∈ {0, 1} of the window depth at infinite distance, exact in f32.
    pub k: f64,
    /// The rest c of that window depth: n/(f − n) for OpenGL's standard projection, 0 for
    /// an infinite far plane, −n/(f − n) for a reversed finite one.
    pub c: f64,
    /// The largest eye depth returned: the far plane, or the sky depth for an infinite one.
    pub max: f64,
}

impl DepthModel {
    /// The model of a depth buffer written by a perspective projection with planes `near`
    /// and `far` (`f64::INFINITY`: an infinite far plane, eye depth then capped at
    /// [`DEFAULT_SKY_DEPTH`]), standard (window depth 0 at near, 1 at far) or `reversed`
    /// (1 at near, 0 at far), whatever the clip depth convention (the window depth is the
    /// same under both): `a`, `k`, `c` as [`MatrixCamera::new`] reads them off such a
    /// projection's matrix. The standard finite model is [`Camera::depth_model`]'s.
    pub fn of_planes(near: f64, far: f64, reversed: bool) -> DepthModel {
        let (n, f) = (near, far);
        let (a, k, c) = match (reversed, f.is_finite()) {
            (false, true) => (-n * f / (f - n), 1.0, n / (f - n)),
            (false, false) => (-n, 1.0, 0.0),
            (true, true) => (n * f / (f - n), 0.0, -n / (f - n)),
            (true, false) => (n, 0.0, 0.0),
        };
        let max = if f.is_finite() {
            f
        } else {
            DEFAULT_SKY_DEPTH.max(2.0 * n)
        };
        DepthModel { a, k, c, max }
    }

    /// Eye depth of window depth `d` (clamped to [0, 1]), at most [`DepthModel::max`].
    pub fn eye_depth(&self, d: f64) -> f64 {
        let den = (d.clamp(0.0, 1.0) - self.k) - self.c;
        let t = self.a / den;
        if den == 0.0 || t.is_nan() || t <= 0.0 {
            self.max
        } else {
            t.min(self.max)
        }
    }

    /// The window depth of eye depth `t` > 0.
    pub fn window_depth(&self, t: f64) -> f64 {
        self.a / t + self.k + self.c
    }
}

/// An engine's camera as it is: its view (world → eye) and projection (eye → clip)
/// matrices and the clip depth convention of its depth buffer. It takes any perspective
/// projection whose clip w is ± the eye z: right- or left-handed, reversed-Z (depth 1 at
/// near, 0 at far), an infinite far plane, off-centre (asymmetric) frusta, and any view
/// (a roll included). Reversed-Z and an infinite far plane are read off the matrix
/// ([`MatrixCamera::reversed`], [`MatrixCamera::infinite`]); the clip depth range cannot
/// be, and is given.
///
/// **Depth.** With z_ndc = s·d + o ([`ClipDepth`]) and the projection's depth row, the
/// eye depth t (distance along the view axis) of a window depth d is
/// `t = a / ((d − k) − c)`, where k + c is the window depth of a point at infinite
/// distance, split into an integer k (0 or 1, exact in f32) and a small rest c, so that
/// the shader keeps c's digits near the far plane ([`MatrixCamera::depth_model`]). An
/// infinite far plane sends d = 0 (reversed) or 1 (standard) to t = ∞: those pixels (the
/// sky) get [`MatrixCamera::sky_depth`] instead, and so does anything beyond it.
///
/// **Positions** are rebuilt by the inverse of projection · view (the test oracle,
/// [`MatrixCamera::world_position_by_inverse`]) or as eye + ray·t, the ray through a
/// pixel having a component 1 along the view axis ([`MatrixCamera::ray_at_ndc`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatrixCamera {
    view: DMat4,
    projection: DMat4,
    clip: ClipDepth,
    inverse_view: DMat4,
    inverse_projection: DMat4,
    /// The sign of the projection's w row: −1 for right-handed (GL, Bevy), +1 for
    /// left-handed (Unreal, D3DX): eye depth = w_sign·z_eye.
    w_sign: f64,
    depth: DepthModel,
    near: f64,
    far: f64,
}

impl MatrixCamera {
    /// The camera of `view` and `projection` whose depth buffer maps clip depth by
    /// `clip`. Refuses matrices that are not finite, a view that cannot be inverted, and a
    /// projection that is not a perspective one with its near plane in front of the eye,
    /// saying which.
    pub fn new(view: DMat4, projection: DMat4, clip: ClipDepth) -> Result<Self> {
        if !view.is_finite() || view.determinant().abs() < 1e-300 {
            return Err(Error::invalid(
                "view matrix",
                format!("{view:?}"),
                "a finite, invertible world-to-eye matrix",
            ));
        }
        if !projection.is_finite() {
            return Err(Error::invalid(
                "projection matrix",
                format!("{projection:?}"),
                "finite elements",
            ));
        }
        // Rows 2 and 3 (z and w) must read z_eye alone: clip w = w_coef·z_eye and clip z
        // = A·z_eye + B. That is every perspective projection, off-centre ones included
        // (their shift is in rows 0 and 1).
        let row = |r: usize| projection.row(r);
        let (z_row, w_row) = (row(2), row(3));
        let perspective = w_row.x == 0.0
            && w_row.y == 0.0
            && w_row.w == 0.0
            && w_row.z != 0.0
            && z_row.x == 0.0
            && z_row.y == 0.0
            && z_row.w != 0.0;
        if !perspective {
            return Err(Error::invalid(
                "projection matrix",
                format!("rows z {z_row:?}, w {w_row:?}"),
                "a perspective projection: clip w = ±z_eye and clip z = A·z_eye + B, B ≠ 0 \
                 (an orthographic projection has no eye depth to rebuild)",
            ));
        }
        let w_sign = w_row.z.signum();
        let scale = w_row.z.abs();
        // z_ndc = α + β/t with t = w_sign·z_eye the eye depth.
        let (alpha, beta) = (z_row.z * w_sign / scale, z_row.w / scale);
        let (s, o) = clip.window_to_ndc();
        let a = beta / s;
        let infinity = (alpha - o) / s;
        let k = infinity.round();
        let c = infinity - k;
        let reversed = a > 0.0;
        let (near_end, far_end) = if reversed { (1.0, 0.0) } else { (0.0, 1.0) };
        let near = a / (near_end - infinity);
        let far = if far_end == infinity {
            f64::INFINITY
        } else {
            a / (far_end - infinity)
        };
        if !(near.is_finite() && near > 0.0 && far > near) {
            return Err(Error::invalid(
                "projection matrix",
                format!("near {near}, far {far} with {clip:?} clip depth"),
                "a projection with 0 < near < far (is the clip depth convention right? \
                 OpenGL's default is MinusOneToOne; Bevy, wgpu, Vulkan, D3D and Unreal \
                 use ZeroToOne)",
            ));
        }
        let max = if far.is_finite() {
            far
        } else {
            DEFAULT_SKY_DEPTH.max(2.0 * near)
        };
        Ok(MatrixCamera {
            view,
            projection,
            clip,
            inverse_view: view.inverse(),
            inverse_projection: projection.inverse(),
            w_sign,
            depth: DepthModel { a, k, c, max },
            near,
            far,
        })
    }

    /// The same camera with the eye depth that pixels at an infinite far plane (or beyond
    /// `sky_depth`) get: a finite distance, beyond the near plane. For a finite far plane,
    /// the far plane stays the cap when it is nearer.
    pub fn with_sky_depth(mut self, sky_depth: f64) -> Result<Self> {
        if !(sky_depth.is_finite() && sky_depth > self.near) {
            return Err(Error::invalid(
                "sky_depth",
                sky_depth,
                format!("a finite eye depth beyond the near plane ({})", self.near),
            ));
        }
        self.depth.max = sky_depth.min(self.far);
        Ok(self)
    }

    /// The world-to-eye matrix as given.
    pub fn view(&self) -> DMat4 {
        self.view
    }

    /// The eye-to-clip matrix as given.
    pub fn projection(&self) -> DMat4 {
        self.projection
    }

    /// The clip depth convention of the depth buffer.
    pub fn clip(&self) -> ClipDepth {
        self.clip
    }

    /// Whether depth falls from 1 at the near plane to 0 at the far one.
    pub fn reversed(&self) -> bool {
        self.depth.a > 0.0
    }

    /// Whether the far plane is at infinity.
    pub fn infinite(&self) -> bool {
        self.far.is_infinite()
    }

    /// The near plane's eye depth.
    pub fn near(&self) -> f64 {
        self.near
    }

    /// The far plane's eye depth (∞ for an infinite projection).
    pub fn far(&self) -> f64 {
        self.far
    }

    /// The largest eye depth a pixel gets: the far plane, or the sky depth of an infinite
    /// projection ([`MatrixCamera::with_sky_depth`]).
    pub fn sky_depth(&self) -> f64 {
        self.depth.max
    }

    /// `t = a / ((d − k) − c)`, capped at the sky depth (type docs).
    pub fn depth_model(&self) -> DepthModel {
        self.depth
    }

    /// `(a, k, c, max)` for the shaders' `brume_depth_constants` (see
    /// `glsl/medium_api.glsl`).
    pub fn shader_depth_constants(&self) -> [f64; 4] {
        let m = self.depth;
        [m.a, m.k, m.c, m.max]
    }

    /// The eye's position (world).
    pub fn eye(&self) -> DVec3 {
        self.inverse_view.transform_point3(DVec3::ZERO)
    }

    /// Unit view direction (world).
    pub fn forward(&self) -> DVec3 {
        self.inverse_view
            .transform_vector3(DVec3::new(0.0, 0.0, self.w_sign))
            .normalize()
    }

    /// Eye depth of window depth `d`, capped at the sky depth.
    pub fn eye_depth(&self, d: f64) -> f64 {
        self.depth.eye_depth(d)
    }

    /// The window depth of a point at eye depth `t` > 0.
    pub fn window_depth(&self, t: f64) -> f64 {
        self.depth.window_depth(t)
    }

    /// The eye-to-fragment vector through normalised device coordinates (x, y), in world
    /// space, with an eye depth of 1 (by the inverse projection: any frustum).
    pub fn ray_at_ndc(&self, x: f64, y: f64) -> DVec3 {
        let (s, o) = self.clip.window_to_ndc();
        let z_ndc = s * self.window_depth(2.0 * self.near) + o;
        let p = self.inverse_projection * DVec4::new(x, y, z_ndc, 1.0);
        let eye_point = p.truncate() / p.w;
        let t = self.w_sign * eye_point.z;
        self.inverse_view.transform_vector3(eye_point / t)
    }

    /// The rays at NDC (−1, −1), (1, −1) and (−1, 1): what the vertex shader interpolates
    /// from (a perspective ray is affine in screen space).
    pub fn corner_rays(&self) -> [DVec3; 3] {
        [
            self.ray_at_ndc(-1.0, -1.0),
            self.ray_at_ndc(1.0, -1.0),
            self.ray_at_ndc(-1.0, 1.0),
        ]
    }

    /// The ray through the centre of pixel `(x, y)` of a `width x height` frame.
    pub fn pixel_ray(&self, x: usize, y: usize, width: usize, height: usize) -> DVec3 {
        let (ndc_x, ndc_y) = pixel_ndc(x, y, width, height);
        self.ray_at_ndc(ndc_x, ndc_y)
    }

    /// The world position of pixel `(x, y)` with window depth `d`: eye + ray·t.
    pub fn world_position(&self, x: usize, y: usize, width: usize, height: usize, d: f64) -> DVec3 {
        self.eye() + self.pixel_ray(x, y, width, height) * self.eye_depth(d)
    }

    /// The same by (P·V)⁻¹ applied to (x_ndc, y_ndc, z_ndc, 1) (paper 002, eq. 22-23),
    /// `d` clamped to [0, 1] and, past the sky depth, moved to it.
    pub fn world_position_by_inverse(
        &self,
        x: usize,
        y: usize,
        width: usize,
        height: usize,
        d: f64,
    ) -> DVec3 {
        let mut d = d.clamp(0.0, 1.0);
        if self.eye_depth(d) >= self.depth.max {
            d = self.window_depth(self.depth.max);
        }
        let (ndc_x, ndc_y) = pixel_ndc(x, y, width, height);
        let (s, o) = self.clip.window_to_ndc();
        let inverse = self.inverse_view * self.inverse_projection;
        let p = inverse * DVec4::new(ndc_x, ndc_y, s * d + o, 1.0);
        p.truncate() / p.w
    }

    /// Window depth and Euclidean distance of the world point `p`, or `None` when it is
    /// not in front of the eye.
    pub fn project_depth(&self, p: DVec3) -> Option<(f64, f64)> {
        let eye_point = self.view.transform_point3(p);
        let t = self.w_sign * eye_point.z;
        (t > 0.0).then(|| (self.window_depth(t), (p - self.eye()).length()))
    }
}

/// The camera a depth buffer was drawn with, as a frame gives it ([`super::FrameInputs`]): brume's own
/// (position, yaw, pitch, field of view: its projection follows the image's aspect) or an
/// engine's matrices as they are.
// One per frame: staying `Copy` (a frame's inputs are copied per frame) is worth more
// than the 500 bytes a box would save on brume's own camera.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FrameCamera {
    /// brume's camera; OpenGL clip depth.
    Look(Camera),
    /// An engine's view and projection.
    Matrices(MatrixCamera),
}

impl Default for FrameCamera {
    fn default() -> Self {
        FrameCamera::Look(Camera::default())
    }
}

impl From<Camera> for FrameCamera {
    fn from(camera: Camera) -> Self {
        FrameCamera::Look(camera)
    }
}

impl From<MatrixCamera> for FrameCamera {
    fn from(camera: MatrixCamera) -> Self {
        FrameCamera::Matrices(camera)
    }
}

impl FrameCamera {
    /// The general camera for an image of `aspect` = width / height (a matrix camera has
    /// its own aspect and ignores it).
    pub fn resolve(&self, aspect: f64) -> Result<MatrixCamera> {
        match self {
            FrameCamera::Look(camera) => camera.matrices(aspect),
            FrameCamera::Matrices(camera) => Ok(*camera),
        }
    }

    /// The general camera of a `width x height` frame, or the default camera's for one
    /// [`FrameCamera::validate`] refuses (the media validate before rendering).
    pub fn for_frame(&self, width: usize, height: usize) -> MatrixCamera {
        self.resolve(width as f64 / height.max(1) as f64)
            .or_else(|_| Camera::default().matrices(1.0))
            .expect("the default camera is valid")
    }

    /// Rejects a camera no projection can be built from, naming the parameter.
    pub fn validate(&self) -> Result<()> {
        match self {
            FrameCamera::Look(camera) => camera.validate(),
            FrameCamera::Matrices(_) => Ok(()),
        }
    }

    /// brume's own camera, if this is one.
    pub fn look(&self) -> Option<&Camera> {
        match self {
            FrameCamera::Look(camera) => Some(camera),
            FrameCamera::Matrices(_) => None,
        }
    }

    /// The eye's position (world).
    pub fn eye(&self) -> DVec3 {
        match self {
            FrameCamera::Look(camera) => camera.eye(),
            FrameCamera::Matrices(camera) => camera.eye(),
        }
    }

    /// The largest eye depth a pixel gets: the far plane, or the sky depth of an infinite
    /// projection.
    pub fn max_depth(&self) -> f64 {
        match self {
            FrameCamera::Look(camera) => camera.far,
            FrameCamera::Matrices(camera) => camera.sky_depth(),
        }
    }
}
