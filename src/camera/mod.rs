//! The camera of a rendered frame: where a fragment of a depth buffer is in the world.
//!
//! An engine fogs the frame it has just drawn from three things: the colour buffer, the
//! non-linear depth buffer and the camera. This module turns the camera into the
//! per-frame constants a post-process needs (paper 003, sec. 2.1), and keeps the slow,
//! obvious way of doing the same as the test oracle (paper 002, eq. 19-23).
//!
//! - **Linear eye depth** from a window depth d ∈ [0, 1] (OpenGL's default depth range,
//!   a standard perspective projection) with one addition and one division:
//!   `z = A / (d + B)`, with `A = −n·f/(f − n)` and `B = −f/(f − n)` computed once on the
//!   CPU ([`Camera::depth_constants`]). The shaders split B as `(d − 1) − c` for f32's sake
//!   ([`Camera::shader_depth_constants`]).
//! - **Eye-to-fragment rays**: the world-space vector from the camera through a pixel,
//!   scaled so that its component along the view axis is 1 ([`Camera::ray_at_ndc`]). Given
//!   at the corners of the full-screen primitive, the hardware interpolates it per
//!   fragment (it is affine in screen space), and `position = eye + ray·z`.
//! - **Distance** is the Euclidean `|ray|·z`, not z: rotating the camera about its centre
//!   does not change the fog on a fixed point (paper 003, fig. 1).
//!
//! - **An engine's camera** ([`MatrixCamera`]): its view and projection matrices as they
//!   are, with the clip depth convention of its depth buffer ([`ClipDepth`]): reversed-Z,
//!   infinite far planes, off-centre frusta and roll. Every path above (eye depth, rays,
//!   positions by the inverse matrices) is computed from the matrices, so brume's own
//!   [`Camera`] goes through the same code ([`Camera::matrices`]); a frame gives either
//!   as a [`FrameCamera`] in its [`FrameInputs`], with the time, to the pipeline.
//!
//! **Depth conventions.** brume reads the *window* depth d ∈ [0, 1] the depth buffer
//! holds, with the default depth range (0..1). How d relates to clip space is the drawing
//! API's: OpenGL's default maps z_ndc ∈ [−1, 1] to (z_ndc + 1)/2
//! ([`ClipDepth::MinusOneToOne`]); Direct3D, Vulkan, Metal, wgpu (Bevy), Unreal and GL
//! with `glClipControl(…, GL_ZERO_TO_ONE)` store z_ndc ∈ [0, 1] itself
//! ([`ClipDepth::ZeroToOne`]). brume assumes no clip control: it is told. Reversed-Z and
//! an infinite far plane are read off the projection matrix.
//!
//! **Conventions.** World y is up. The camera at yaw 0, pitch 0 looks along −z with +x to
//! its right; yaw turns it to the right (toward +x), pitch up. Pixel `(x, y)` is texel
//! `(x, y)` of the frame, row 0 at the bottom as GL stores it; its centre is at window
//! coordinates `(x + ½, y + ½)`.

mod frame;
mod matrix;

pub use frame::FrameInputs;
pub use matrix::{ClipDepth, DepthModel, FrameCamera, MatrixCamera, DEFAULT_SKY_DEPTH};

use crate::error::{check_positive, Error, Result};
use glam::{DMat4, DVec3};

/// A perspective camera of a rendered frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// The eye's position in world units.
    pub position: [f64; 3],
    /// Rotation about +y (degrees): 0 looks along −z, 90 along +x.
    pub yaw_deg: f64,
    /// Elevation of the view axis (degrees, −89..89): positive looks up.
    pub pitch_deg: f64,
    /// Vertical field of view (degrees, in (0, 180)).
    pub fov_y_deg: f64,
    /// Near clipping plane distance (> 0, world units).
    pub near: f64,
    /// Far clipping plane distance (> near, world units).
    pub far: f64,
}

impl Default for Camera {
    /// Eye 1.7 units above the ground, looking level along −z with a 60° vertical field,
    /// near 0.1, far 1000.
    fn default() -> Self {
        Camera {
            position: [0.0, 1.7, 0.0],
            yaw_deg: 0.0,
            pitch_deg: 0.0,
            fov_y_deg: 60.0,
            near: 0.1,
            far: 1000.0,
        }
    }
}

impl Camera {
    /// Rejects a camera no projection can be built from, naming the parameter.
    pub fn validate(&self) -> Result<()> {
        if !self.position.iter().all(|v| v.is_finite()) {
            let [x, y, z] = self.position;
            return Err(Error::invalid(
                "position",
                format!("{x},{y},{z}"),
                "three finite numbers",
            ));
        }
        if !self.yaw_deg.is_finite() {
            return Err(Error::invalid(
                "yaw_deg",
                self.yaw_deg,
                "a finite angle (degrees)",
            ));
        }
        if !(self.pitch_deg.is_finite() && self.pitch_deg.abs() < 90.0) {
            return Err(Error::invalid(
                "pitch_deg",
                self.pitch_deg,
                "an angle strictly between −90 and 90 degrees",
            ));
        }
        if !(self.fov_y_deg.is_finite() && self.fov_y_deg > 0.0 && self.fov_y_deg < 180.0) {
            return Err(Error::invalid(
                "fov_y_deg",
                self.fov_y_deg,
                "a vertical field of view strictly between 0 and 180 degrees",
            ));
        }
        check_positive("near", self.near)?;
        if !(self.far.is_finite() && self.far > self.near) {
            return Err(Error::invalid(
                "far",
                self.far,
                format!("a finite distance greater than near ({})", self.near),
            ));
        }
        Ok(())
    }

    /// The eye's position.
    pub fn eye(&self) -> DVec3 {
        DVec3::from_array(self.position)
    }

    /// Unit view direction.
    pub fn forward(&self) -> DVec3 {
        let (yaw, pitch) = (self.yaw_deg.to_radians(), self.pitch_deg.to_radians());
        DVec3::new(
            yaw.sin() * pitch.cos(),
            pitch.sin(),
            -yaw.cos() * pitch.cos(),
        )
    }

    /// Unit vector to the right of the view (horizontal).
    pub fn right(&self) -> DVec3 {
        let yaw = self.yaw_deg.to_radians();
        DVec3::new(yaw.cos(), 0.0, yaw.sin())
    }

    /// Unit vector up in the image.
    pub fn up(&self) -> DVec3 {
        self.right().cross(self.forward())
    }

    /// The world-to-eye (model-view) matrix.
    pub fn view_matrix(&self) -> DMat4 {
        DMat4::look_to_rh(self.eye(), self.forward(), DVec3::Y)
    }

    /// The OpenGL perspective projection for an image of `aspect` = width / height
    /// (clip z in [−w, w]).
    pub fn projection(&self, aspect: f64) -> DMat4 {
        DMat4::perspective_rh_gl(self.fov_y_deg.to_radians(), aspect, self.near, self.far)
    }

    /// `(A, B)` such that the eye depth (distance along the view axis) of window depth d
    /// is `A / (d + B)`: one addition and one division per fragment.
    pub fn depth_constants(&self) -> [f64; 2] {
        let (n, f) = (self.near, self.far);
        [-n * f / (f - n), -f / (f - n)]
    }

    /// `(A, c)` for the shaders: eye depth = `A / ((d − 1) − c)` with `c = n/(f − n)`.
    /// The same as `A / (d + B)` (B = −1 − c), but in f32 `B` would round away the digits
    /// of `c` that matter near the far plane (d + B is then a few n/f): `d − 1` is exact
    /// for d ≥ ½ and `c` keeps its own precision. Still one division per fragment. The
    /// general form, for any projection, is [`MatrixCamera::depth_model`].
    pub fn shader_depth_constants(&self) -> [f64; 2] {
        let (n, f) = (self.near, self.far);
        [-n * f / (f - n), n / (f - n)]
    }

    /// This camera as view and projection matrices for an image of `aspect` = width /
    /// height, with OpenGL's default clip depth (−1..1): the general camera every
    /// depth-to-position path below goes through.
    pub fn matrices(&self, aspect: f64) -> Result<MatrixCamera> {
        self.validate()?;
        MatrixCamera::new(
            self.view_matrix(),
            self.projection(aspect),
            ClipDepth::MinusOneToOne,
        )
    }

    /// The general camera, or (for a camera [`Camera::validate`] refuses) a camera from
    /// the default's matrices: the depth paths below must not panic on bad input, and
    /// the entry points validate the frame's camera before they render.
    fn general(&self, aspect: f64) -> MatrixCamera {
        self.matrices(aspect).unwrap_or_else(|_| {
            Camera::default()
                .matrices(1.0)
                .expect("the default camera is valid")
        })
    }

    /// The general depth model ([`MatrixCamera::depth_model`]) of this camera's OpenGL
    /// projection, in closed form: a = −nf/(f − n), k = 1, c = n/(f − n), capped at far.
    /// No matrix is inverted, so per-pixel callers (depth files) pay one division.
    pub fn depth_model(&self) -> DepthModel {
        let [a, c] = self.shader_depth_constants();
        DepthModel {
            a,
            k: 1.0,
            c,
            max: self.far,
        }
    }

    /// Eye depth of window depth `d` ∈ [0, 1] (clamped there) by the general depth model.
    pub fn eye_depth(&self, d: f64) -> f64 {
        self.depth_model().eye_depth(d)
    }

    /// The window depth of a point at eye depth `z` (the inverse of [`Camera::eye_depth`]).
    pub fn window_depth(&self, z: f64) -> f64 {
        self.depth_model().window_depth(z)
    }

    /// The eye-to-fragment vector through normalised device coordinates (x, y) ∈ [−1, 1]²,
    /// in world space, with a component of 1 along the view axis.
    pub fn ray_at_ndc(&self, x: f64, y: f64, aspect: f64) -> DVec3 {
        let ty = (self.fov_y_deg.to_radians() / 2.0).tan();
        self.forward() + self.right() * (x * ty * aspect) + self.up() * (y * ty)
    }

    /// The rays at the bottom-left, bottom-right and top-left corners of the image (NDC
    /// (−1, −1), (1, −1), (−1, 1)): what the vertex shader interpolates from.
    pub fn corner_rays(&self, aspect: f64) -> [DVec3; 3] {
        self.general(aspect).corner_rays()
    }

    /// The ray through the centre of pixel `(x, y)` of a `width x height` frame.
    pub fn pixel_ray(&self, x: usize, y: usize, width: usize, height: usize) -> DVec3 {
        let (ndc_x, ndc_y) = pixel_ndc(x, y, width, height);
        self.ray_at_ndc(ndc_x, ndc_y, width as f64 / height as f64)
    }

    /// The world position of pixel `(x, y)` with window depth `d`, by the fast path: eye
    /// plus the pixel's ray times the eye depth.
    pub fn world_position(&self, x: usize, y: usize, width: usize, height: usize, d: f64) -> DVec3 {
        self.eye() + self.pixel_ray(x, y, width, height) * self.eye_depth(d)
    }

    /// The same by the inverse matrices (paper 002, eq. 22-23): window coordinates
    /// remapped to NDC and multiplied by (P·M)⁻¹. Slow and obvious: the test oracle.
    pub fn world_position_by_inverse(
        &self,
        x: usize,
        y: usize,
        width: usize,
        height: usize,
        d: f64,
    ) -> DVec3 {
        self.general(width as f64 / height as f64)
            .world_position_by_inverse(x, y, width, height, d)
    }

    /// Window depth and Euclidean distance of the world point `p` seen through this
    /// camera, or `None` when it is behind the eye.
    pub fn project_depth(&self, p: DVec3) -> Option<(f64, f64)> {
        let z = (p - self.eye()).dot(self.forward());
        (z > 0.0).then(|| (self.window_depth(z), (p - self.eye()).length()))
    }
}

/// Normalised device coordinates of the centre of pixel `(x, y)` (row 0 at the bottom).
pub fn pixel_ndc(x: usize, y: usize, width: usize, height: usize) -> (f64, f64) {
    (
        2.0 * (x as f64 + 0.5) / width as f64 - 1.0,
        2.0 * (y as f64 + 0.5) / height as f64 - 1.0,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec4;

    fn tilted() -> Camera {
        Camera {
            position: [3.0, 2.5, -4.0],
            yaw_deg: 37.0,
            pitch_deg: -12.0,
            fov_y_deg: 55.0,
            near: 0.25,
            far: 400.0,
        }
    }

    /// The depth model of a projection's planes is the one read off the projection's
    /// matrix (glam's, for the four kinds: standard or reversed, finite or infinite), and
    /// the standard finite one is the camera's own to the bit.
    #[test]
    fn the_planes_model_is_the_matrix_model() {
        use super::matrix::{ClipDepth, DepthModel, MatrixCamera};
        let (n, f, fov) = (0.25, 400.0, 1.0);
        let gl = ClipDepth::MinusOneToOne;
        let zo = ClipDepth::ZeroToOne;
        let cases = [
            (false, f, DMat4::perspective_rh_gl(fov, 1.5, n, f), gl),
            (
                false,
                f64::INFINITY,
                DMat4::perspective_infinite_rh(fov, 1.5, n),
                zo,
            ),
            (true, f, DMat4::perspective_rh(fov, 1.5, f, n), zo),
            (
                true,
                f64::INFINITY,
                DMat4::perspective_infinite_reverse_rh(fov, 1.5, n),
                zo,
            ),
        ];
        for (reversed, far, projection, clip) in cases {
            let from_matrix = MatrixCamera::new(DMat4::IDENTITY, projection, clip)
                .unwrap()
                .depth_model();
            let model = DepthModel::of_planes(n, far, reversed);
            assert_eq!(model.k, from_matrix.k);
            let pairs = [
                (model.a, from_matrix.a),
                (model.c, from_matrix.c),
                (model.max, from_matrix.max),
            ];
            for (got, want) in pairs {
                assert!(
                    (got - want).abs() <= 1e-12 * want.abs().max(1e-3),
                    "{got} {want}"
                );
            }
            for z in [0.3, 1.0, 17.0, 399.0] {
                let d = model.window_depth(z);
                let t = model.eye_depth(d);
                assert!(
                    (t - z).abs() < 1e-9 * z,
                    "{reversed} {far}: {z} -> {d} -> {t}"
                );
                let d_matrix = from_matrix.window_depth(z);
                assert!((d - d_matrix).abs() < 1e-12, "{d} {d_matrix}");
            }
        }
        let camera = Camera {
            near: n,
            far: f,
            ..Camera::default()
        };
        assert_eq!(DepthModel::of_planes(n, f, false), camera.depth_model());
    }

    #[test]
    fn fast_reconstruction_matches_the_inverse_matrices() {
        let camera = tilted();
        let (w, h) = (64, 40);
        for &(x, y) in &[(0, 0), (63, 0), (0, 39), (63, 39), (17, 23)] {
            for d in [0.0, 0.3, 0.9, 0.99, 0.9999] {
                let fast = camera.world_position(x, y, w, h, d);
                let oracle = camera.world_position_by_inverse(x, y, w, h, d);
                let scale = (oracle - camera.eye()).length();
                assert!(
                    (fast - oracle).length() <= 1e-9 * scale.max(1.0),
                    "pixel ({x}, {y}), d {d}: {fast} vs {oracle}"
                );
            }
        }
    }

    #[test]
    fn depth_constants_invert_the_projection() {
        let camera = tilted();
        assert!((camera.eye_depth(0.0) - camera.near).abs() < 1e-12);
        assert!((camera.eye_depth(1.0) - camera.far).abs() < 1e-9);
        let [a, c] = camera.shader_depth_constants();
        for d in [0.0, 0.5, 0.99, 0.999_99] {
            let split = a / ((d - 1.0) - c);
            assert!((split - camera.eye_depth(d)).abs() < 1e-9 * split);
        }
        for z in [0.3, 1.0, 25.0, 399.0] {
            assert!((camera.eye_depth(camera.window_depth(z)) - z).abs() < 1e-9 * z);
        }
    }

    #[test]
    fn distance_to_a_fixed_point_does_not_change_when_the_camera_turns() {
        // Paper 003, fig. 1: the eye depth of a fixed point changes as the camera turns
        // about its centre; the distance rebuilt from depth and ray must not.
        let point = DVec3::new(10.0, 0.5, -30.0);
        let mut camera = Camera::default();
        let (mut depths, mut distances) = (vec![], vec![]);
        for yaw in [-10.0, 0.0, 15.0, 25.0] {
            camera.yaw_deg = yaw;
            let (d, distance) = camera.project_depth(point).unwrap();
            let to_point = point - camera.eye();
            let ray = to_point / to_point.dot(camera.forward());
            let rebuilt = (ray * camera.eye_depth(d)).length();
            assert!((rebuilt - distance).abs() < 1e-9 * distance);
            depths.push(camera.eye_depth(d));
            distances.push(rebuilt);
        }
        let spread = |v: &[f64]| {
            v.iter().cloned().fold(f64::MIN, f64::max) - v.iter().cloned().fold(f64::MAX, f64::min)
        };
        assert!(spread(&depths) > 1.0, "z should change: {depths:?}");
        assert!(spread(&distances) < 1e-9, "{distances:?}");
    }

    #[test]
    fn the_general_camera_of_a_standard_one_has_its_split_constants() {
        // brume's camera through the matrix path: not reversed, finite, k = 1 and c =
        // n/(f − n) as the closed form has them, and the rays of the closed form.
        let camera = tilted();
        let general = camera.matrices(1.6).unwrap();
        assert!(!general.reversed() && !general.infinite());
        let [a, c] = camera.shader_depth_constants();
        let [ga, gk, gc, max] = general.shader_depth_constants();
        assert!((ga - a).abs() <= 1e-12 * a.abs(), "{ga} vs {a}");
        assert_eq!(gk, 1.0);
        assert!((gc - c).abs() <= 1e-9 * c, "{gc} vs {c}");
        assert!((max - camera.far).abs() <= 1e-9 * camera.far);
        assert!((general.near() - camera.near).abs() < 1e-12);
        for (x, y) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (0.3, -0.7)] {
            let (fast, inverse) = (camera.ray_at_ndc(x, y, 1.6), general.ray_at_ndc(x, y));
            assert!((fast - inverse).length() < 1e-12, "{fast} vs {inverse}");
        }
        assert!((general.eye() - camera.eye()).length() < 1e-12);
        assert!((general.forward() - camera.forward()).length() < 1e-12);
    }

    #[test]
    fn depth_beyond_the_sky_depth_is_capped_and_never_negative() {
        // An infinite standard (GL) projection: d = 1 is infinitely far.
        let (n, f) = (0.5, 1.0 / (2.0f64).tan());
        let projection = DMat4::from_cols(
            DVec4::new(f, 0.0, 0.0, 0.0),
            DVec4::new(0.0, f, 0.0, 0.0),
            DVec4::new(0.0, 0.0, -1.0, -1.0),
            DVec4::new(0.0, 0.0, -2.0 * n, 0.0),
        );
        let camera = MatrixCamera::new(DMat4::IDENTITY, projection, ClipDepth::MinusOneToOne)
            .unwrap()
            .with_sky_depth(300.0)
            .unwrap();
        assert!(camera.infinite() && !camera.reversed());
        assert_eq!(camera.eye_depth(1.0), 300.0);
        assert_eq!(camera.eye_depth(2.0), 300.0, "clamped to [0, 1] first");
        assert!((camera.eye_depth(0.0) - n).abs() < 1e-12);
        assert!((camera.eye_depth(0.9) - n / 0.1).abs() < 1e-9);
        let p = camera.world_position_by_inverse(3, 2, 8, 4, 1.0);
        let t = -p.z;
        assert!((t - 300.0).abs() < 1e-6, "the sky at the sky depth: {p}");
    }

    #[test]
    fn bad_cameras_are_refused_by_name() {
        let bad = |c: Camera| c.validate().unwrap_err().to_string();
        assert!(bad(Camera {
            near: 0.0,
            ..Camera::default()
        })
        .contains("near"));
        assert!(bad(Camera {
            far: 0.05,
            ..Camera::default()
        })
        .contains("far"));
        assert!(bad(Camera {
            fov_y_deg: 180.0,
            ..Camera::default()
        })
        .contains("invalid fov_y_deg"));
        assert!(bad(Camera {
            pitch_deg: 90.0,
            ..Camera::default()
        })
        .contains("invalid pitch_deg"));
        assert!(Camera::default().validate().is_ok());
    }
}
