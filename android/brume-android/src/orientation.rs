//! Camera buffers arrive in the sensor's orientation with their first row in memory at
//! the top; brume renders an upright image in GL's row order (row 0 at the bottom). One
//! map between the two serves the colour (as the import's texture transform, applied by
//! the GPU) and the depth (resampled on the CPU), so that the two stay registered.
//!
//! Coordinates: an upright GL texture coordinate (u, v) has v = 0 at the bottom; a buffer
//! coordinate (s, t) has t = 0 at the buffer's first row, which is also what GL's t = 0
//! is for an EGLImage of that buffer (hence the t-flip of Android's transform matrices).

/// How many clockwise quarter turns make the sensor's image upright on the screen in its
/// natural orientation (Android's `SENSOR_ORIENTATION`; the app is locked to portrait).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Orientation {
    quarter_turns: u8,
}

impl Orientation {
    /// The sensor's image is upright as it is.
    pub const UPRIGHT: Orientation = Orientation { quarter_turns: 0 };

    /// From `ACAMERA_SENSOR_ORIENTATION` in degrees (0, 90, 180 or 270; other values are
    /// rounded to the nearest quarter turn).
    pub fn from_sensor_degrees(degrees: i32) -> Self {
        let turns = ((f64::from(degrees) / 90.0).round() as i64).rem_euclid(4);
        Orientation {
            quarter_turns: turns as u8,
        }
    }

    /// The upright size of a `width x height` buffer: a quarter turn swaps the sides.
    pub fn upright_size(self, (width, height): (usize, usize)) -> (usize, usize) {
        if self.quarter_turns % 2 == 1 {
            (height, width)
        } else {
            (width, height)
        }
    }

    /// The buffer coordinate (s, t) shown at the upright texture coordinate (u, v).
    pub fn source(self, u: f32, v: f32) -> (f32, f32) {
        // (a, b): the upright image's coordinate with b growing downwards, as the buffer's.
        let (a, b) = (u, 1.0 - v);
        match self.quarter_turns {
            0 => (a, b),
            // A clockwise quarter turn brings the buffer's top-left corner to the upright
            // image's top-right one.
            1 => (b, 1.0 - a),
            2 => (1.0 - a, 1.0 - b),
            _ => (1.0 - b, a),
        }
    }

    /// [`Orientation::source`] as the column-major 4 x 4 matrix of
    /// `brume::pipeline::ExternalColour::transform` (acting on (u, v, 0, 1)). The map is
    /// affine, so three points define it.
    pub fn transform(self) -> [f32; 16] {
        let (s0, t0) = self.source(0.0, 0.0);
        let (s_u, t_u) = self.source(1.0, 0.0);
        let (s_v, t_v) = self.source(0.0, 1.0);
        [
            s_u - s0,
            t_u - t0,
            0.0,
            0.0, //
            s_v - s0,
            t_v - t0,
            0.0,
            0.0, //
            0.0,
            0.0,
            1.0,
            0.0, //
            s0,
            t0,
            0.0,
            1.0,
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: [i32; 4] = [0, 90, 180, 270];

    fn apply(m: &[f32; 16], u: f32, v: f32) -> (f32, f32) {
        (m[0] * u + m[4] * v + m[12], m[1] * u + m[5] * v + m[13])
    }

    #[test]
    fn an_upright_sensor_gives_androids_usual_flip() {
        let flip = [
            1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 1.0,
        ];
        assert_eq!(Orientation::UPRIGHT.transform(), flip);
        assert_eq!(Orientation::from_sensor_degrees(360), Orientation::UPRIGHT);
        assert_eq!(Orientation::from_sensor_degrees(-90).quarter_turns, 3);
    }

    #[test]
    fn the_matrix_is_the_map() {
        for degrees in ALL {
            let o = Orientation::from_sensor_degrees(degrees);
            let m = o.transform();
            for (u, v) in [(0.1, 0.2), (0.9, 0.3), (0.5, 0.5), (0.25, 0.95)] {
                let (a, b) = (apply(&m, u, v), o.source(u, v));
                assert!(
                    (a.0 - b.0).abs() < 1e-6 && (a.1 - b.1).abs() < 1e-6,
                    "{degrees}°"
                );
            }
        }
    }

    #[test]
    fn a_quarter_turn_puts_the_buffers_first_texel_at_the_top_right() {
        let o = Orientation::from_sensor_degrees(90);
        // The top-right corner of the upright image: u = 1, v = 1 (GL's top).
        let (s, t) = o.source(1.0, 1.0);
        assert!(s.abs() < 1e-6 && t.abs() < 1e-6, "({s}, {t})");
        // The upright image's bottom-left corner shows the buffer's last texel.
        assert_eq!(o.source(0.0, 0.0), (1.0, 1.0));
        assert_eq!(o.upright_size((640, 480)), (480, 640));
        assert_eq!(
            Orientation::from_sensor_degrees(180).upright_size((640, 480)),
            (640, 480)
        );
    }

    #[test]
    fn every_map_is_a_bijection_of_the_corners() {
        let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)];
        for degrees in ALL {
            let o = Orientation::from_sensor_degrees(degrees);
            let mut images: Vec<(f32, f32)> =
                corners.iter().map(|&(u, v)| o.source(u, v)).collect();
            images.sort_by(|a, b| a.partial_cmp(b).unwrap());
            let mut sorted = corners.to_vec();
            sorted.sort_by(|a, b| a.partial_cmp(b).unwrap());
            assert_eq!(images, sorted, "{degrees}°");
        }
    }
}
