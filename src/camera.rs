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
//! **Conventions.** World y is up. The camera at yaw 0, pitch 0 looks along −z with +x to
//! its right; yaw turns it to the right (toward +x), pitch up. Pixel `(x, y)` is texel
//! `(x, y)` of the frame, row 0 at the bottom as GL stores it; its centre is at window
//! coordinates `(x + ½, y + ½)`.

use crate::error::{check_positive, Error, Result};
use glam::{DMat4, DVec3, DVec4};

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
                "yaw",
                self.yaw_deg,
                "a finite angle (degrees)",
            ));
        }
        if !(self.pitch_deg.is_finite() && self.pitch_deg.abs() < 90.0) {
            return Err(Error::invalid(
                "pitch",
                self.pitch_deg,
                "an angle strictly between −90 and 90 degrees",
            ));
        }
        if !(self.fov_y_deg.is_finite() && self.fov_y_deg > 0.0 && self.fov_y_deg < 180.0) {
            return Err(Error::invalid(
                "fov",
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
    /// for d ≥ ½ and `c` keeps its own precision. Still one division per fragment.
    pub fn shader_depth_constants(&self) -> [f64; 2] {
        let (n, f) = (self.near, self.far);
        [-n * f / (f - n), n / (f - n)]
    }

    /// Eye depth of window depth `d` by [`Camera::depth_constants`].
    pub fn eye_depth(&self, d: f64) -> f64 {
        let [a, b] = self.depth_constants();
        a / (d + b)
    }

    /// The window depth of a point at eye depth `z` (the inverse of [`Camera::eye_depth`]).
    pub fn window_depth(&self, z: f64) -> f64 {
        let [a, b] = self.depth_constants();
        a / z - b
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
        [
            self.ray_at_ndc(-1.0, -1.0, aspect),
            self.ray_at_ndc(1.0, -1.0, aspect),
            self.ray_at_ndc(-1.0, 1.0, aspect),
        ]
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
        let aspect = width as f64 / height as f64;
        let (ndc_x, ndc_y) = pixel_ndc(x, y, width, height);
        let inverse = (self.projection(aspect) * self.view_matrix()).inverse();
        let p = inverse * DVec4::new(ndc_x, ndc_y, 2.0 * d - 1.0, 1.0);
        p.truncate() / p.w
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
        .contains("fov"));
        assert!(bad(Camera {
            pitch_deg: 90.0,
            ..Camera::default()
        })
        .contains("pitch"));
        assert!(Camera::default().validate().is_ok());
    }
}
