//! Camera geometry: pinhole intrinsics, depth along the optical axis stretched to range
//! along each pixel's ray, and stereo disparity turned into depth. Kept apart from file
//! formats and dataset conventions, which only decide the numbers fed in here.

use crate::raster::{Grid, Orientation, ScalarMap};

/// Pinhole intrinsics in pixels. Pixel `(x, y)` has its centre at integer coordinates
/// `(x, y)`, row 0 at the top, as in Middlebury's `calib.txt`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Intrinsics {
    /// Focal length along x, in pixels.
    pub fx: f64,
    /// Focal length along y, in pixels.
    pub fy: f64,
    /// Principal point x, in pixels.
    pub cx: f64,
    /// Principal point y, in pixels.
    pub cy: f64,
}

impl Intrinsics {
    /// Square pixels of focal `focal` with the principal point at the image centre
    /// `((width - 1) / 2, (height - 1) / 2)`.
    pub fn centred(focal: f64, width: usize, height: usize) -> Self {
        Intrinsics {
            fx: focal,
            fy: focal,
            cx: (width as f64 - 1.0) / 2.0,
            cy: (height as f64 - 1.0) / 2.0,
        }
    }

    /// The square pixels of a `width x height` frame whose 35 mm equivalent focal length
    /// (EXIF `FocalLengthIn35mmFilm`) is `f35` mm, principal point at the centre. The
    /// equivalence is by the diagonal's angle of view, the convention camera makers follow
    /// (CIPA DCG-001): f = f35 · (the frame's diagonal in px) / 43.27 mm, the diagonal of a
    /// 36 x 24 mm film frame. ExifTool's `FOV` matches the long side to 36 mm instead, 4 %
    /// narrower on a 4:3 frame. Assumes the frame is the whole one the camera wrote the
    /// tag for (not a crop of it); any scaling of it keeps the angle.
    pub fn of_35mm_equivalent(f35: f64, width: usize, height: usize) -> Self {
        let diagonal_35mm = 36f64.hypot(24.0);
        let focal = f35 * (width as f64).hypot(height as f64) / diagonal_35mm;
        Intrinsics::centred(focal, width, height)
    }

    /// Range / depth at pixel `(x, y)`: the length of the ray through the pixel per unit
    /// of depth, `sqrt(1 + ((x - cx) / fx)^2 + ((y - cy) / fy)^2)`.
    pub fn range_per_depth(&self, x: usize, y: usize) -> f64 {
        let u = (x as f64 - self.cx) / self.fx;
        let v = (y as f64 - self.cy) / self.fy;
        (1.0 + u * u + v * v).sqrt()
    }

    /// The intrinsics of the same view sampled `scale` times as finely (a map upsampled to
    /// its image's size), pixel centres at integers on both grids.
    pub fn scaled(&self, scale: f64) -> Self {
        let at = |c: f64| (c + 0.5) * scale - 0.5;
        Intrinsics {
            fx: self.fx * scale,
            fy: self.fy * scale,
            cx: at(self.cx),
            cy: at(self.cy),
        }
    }

    /// The intrinsics of a `width x height` grid turned upright by `orientation`
    /// ([`Grid::oriented`]): each upright pixel sees the ray its stored pixel saw.
    pub fn oriented(&self, orientation: Orientation, width: usize, height: usize) -> Self {
        use Orientation as O;
        let (right, bottom) = (width as f64 - 1.0, height as f64 - 1.0);
        let (fx, fy, cx, cy) = (self.fx, self.fy, self.cx, self.cy);
        let (fx, fy, cx, cy) = match orientation {
            O::Upright => (fx, fy, cx, cy),
            O::MirrorLeftRight => (fx, fy, right - cx, cy),
            O::Rotate180 => (fx, fy, right - cx, bottom - cy),
            O::MirrorTopBottom => (fx, fy, cx, bottom - cy),
            O::Rotate90Mirror => (fy, fx, cy, cx),
            O::Rotate90 => (fy, fx, bottom - cy, cx),
            O::Rotate270Mirror => (fy, fx, bottom - cy, right - cx),
            O::Rotate270 => (fy, fx, cy, right - cx),
        };
        Intrinsics { fx, fy, cx, cy }
    }
}

/// How a camera is mounted over level ground (a vehicle's camera, from its calibration):
/// Cityscapes' `extrinsic.z`, `pitch` and `roll`, in the vehicle frame of ISO 8855 (x
/// forward, y left, z up; the camera turned by roll about x, then pitch about y).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Mount {
    /// Height of the optical centre above the ground, in metres.
    pub height_m: f64,
    /// Tilt of the optical axis below the level, in radians (down is positive).
    pub pitch: f64,
    /// Turn about the optical axis, in radians (the left side up is positive).
    pub roll: f64,
}

/// The camera heights over the road a [`Mount`] may have, in metres: 1 cm to 10 km.
pub const MOUNT_HEIGHT_RANGE_M: (f64, f64) = (1e-2, 1e4);

/// The pitches and rolls a [`Mount`] may have, in radians: a quarter turn either way.
pub const MOUNT_TILT_RANGE_RAD: (f64, f64) =
    (-std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_2);

impl Mount {
    /// Parses `HEIGHT,PITCH[,ROLL]`: metres, then degrees (pitch down, roll left side up;
    /// roll 0 when left out), as `brume render --camera-mount` takes it
    /// ([`Mount::from_degrees`]); text that is not two or three numbers is an error naming
    /// it.
    pub fn parse_degrees(text: &str) -> crate::Result<Mount> {
        let values: Vec<f64> = (text.split(',').map(|v| v.trim().parse::<f64>()))
            .collect::<Result<_, _>>()
            .map_err(|_| mount_refused(text))?;
        Mount::from_degrees(&values)
    }

    /// The mount of `[height_m, pitch_deg]` or `[height_m, pitch_deg, roll_deg]` (pitch
    /// down, roll left side up). A height out of [`MOUNT_HEIGHT_RANGE_M`], an angle out of
    /// [`MOUNT_TILT_RANGE_RAD`] or another count of values is an error naming them.
    pub fn from_degrees(values: &[f64]) -> crate::Result<Mount> {
        let (lo, hi) = MOUNT_TILT_RANGE_RAD;
        let angle = |deg: f64| Some(deg.to_radians()).filter(|r| (lo..=hi).contains(r));
        let (height_m, pitch, roll) = match *values {
            [h, pitch] => (h, angle(pitch), Some(0.0)),
            [h, pitch, roll] => (h, angle(pitch), angle(roll)),
            _ => (f64::NAN, None, None),
        };
        let (lo, hi) = MOUNT_HEIGHT_RANGE_M;
        match (pitch, roll) {
            (Some(pitch), Some(roll)) if (lo..=hi).contains(&height_m) => Ok(Mount {
                height_m,
                pitch,
                roll,
            }),
            _ => {
                let text: Vec<String> = values.iter().map(f64::to_string).collect();
                Err(mount_refused(&text.join(",")))
            }
        }
    }

    /// The rays of a camera with intrinsics `k` on this mount, for
    /// [`LevelRays::sine_below_level`] pixel by pixel.
    pub fn rays(&self, k: &Intrinsics) -> LevelRays {
        let (sin_pitch, cos_pitch) = self.pitch.sin_cos();
        let (sin_roll, cos_roll) = self.roll.sin_cos();
        LevelRays {
            k: *k,
            sin_pitch,
            cos_pitch,
            sin_roll,
            cos_roll,
        }
    }
}

/// A mount given as `text` and refused ([`Mount::from_degrees`]).
fn mount_refused(text: &str) -> crate::Error {
    let (lo, hi) = MOUNT_HEIGHT_RANGE_M;
    crate::Error::invalid(
        "camera_mount",
        text,
        format!(
            "HEIGHT,PITCH[,ROLL]: a height over the road from {lo} to {hi} m, then a pitch \
             (down) and a roll (left side up) in degrees within ±90"
        ),
    )
}

/// A mounted camera's rays against the level ([`Mount::rays`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelRays {
    k: Intrinsics,
    sin_pitch: f64,
    cos_pitch: f64,
    sin_roll: f64,
    cos_roll: f64,
}

impl LevelRays {
    /// The sine of the angle by which the ray through pixel `(x, y)` points below the
    /// level: positive below the horizon, 0 on it, negative above. A ray of sine `s > 0`
    /// meets level ground at range `height_m / s`.
    pub fn sine_below_level(&self, x: usize, y: usize) -> f64 {
        self.sine_below_level_at(x as f64, y as f64)
    }

    /// [`LevelRays::sine_below_level`] at a position in pixels that need not be whole.
    pub fn sine_below_level_at(&self, x: f64, y: f64) -> f64 {
        let (u, v) = self.uv(x, y);
        self.down(u, v) / (1.0 + u * u + v * v).sqrt()
    }

    /// Whether some pixel of row `y` of a `width`-pixel row may point more than `sine`
    /// below the level (`sine` ≥ 0): false lets a caller skip the row.
    pub fn row_may_reach(&self, y: usize, width: usize, sine: f64) -> bool {
        // The down component is linear along a row, so largest at an end, and the ray's
        // length is at least 1.
        let (first, last) = (
            self.uv(0.0, y as f64),
            self.uv(width.saturating_sub(1) as f64, y as f64),
        );
        self.down(first.0, first.1).max(self.down(last.0, last.1)) > sine
    }

    /// The down component of the ray (u, v, 1): (forward 1, left −u, up −v) in the
    /// vehicle frame before the camera's turn, then turned by the roll and the pitch.
    fn down(&self, u: f64, v: f64) -> f64 {
        self.sin_pitch + self.cos_pitch * (v * self.cos_roll + u * self.sin_roll)
    }

    /// Pixel `(x, y)` on the plane at unit depth.
    fn uv(&self, x: f64, y: f64) -> (f64, f64) {
        ((x - self.k.cx) / self.k.fx, (y - self.k.cy) / self.k.fy)
    }
}

/// Stereo geometry for disparity: depth in mm = `focal * baseline / (d + offset)`.
pub(crate) struct Stereo {
    /// Focal length in pixels.
    pub(crate) focal: f64,
    /// Baseline in millimetres.
    pub(crate) baseline_mm: f64,
    /// Added to the disparity before dividing, in pixels.
    pub(crate) offset: f64,
}

impl Stereo {
    /// f·B in px·m: a disparity step between two depths is f·B·(1/Z₁ − 1/Z₂) px, whatever
    /// the offset ([`crate::prep::PrepOptions::stereo_focal_baseline`]).
    pub(crate) fn focal_baseline(&self) -> f64 {
        self.focal * self.baseline_mm / 1000.0
    }

    /// Depth in metres, `None` where the disparity cannot give one.
    pub(crate) fn depth_m(&self, d: f64) -> Option<f64> {
        let denom = d + self.offset;
        (d.is_finite() && denom > 0.0).then(|| self.focal * self.baseline_mm / denom / 1000.0)
    }
}

/// Applies `depth_of` to every raw value, keeps positive finite results, and stretches
/// depth to range along each pixel's ray when intrinsics are known.
pub(crate) fn to_range<T: Copy>(
    raw: &Grid<T>,
    depth_of: impl Fn(T) -> Option<f64>,
    intrinsics: Option<&Intrinsics>,
) -> ScalarMap {
    Grid::from_fn(raw.width(), raw.height(), |x, y| {
        match depth_of(*raw.get(x, y)).filter(|z| z.is_finite() && *z > 0.0) {
            Some(z) => {
                let stretch = intrinsics.map_or(1.0, |k| k.range_per_depth(x, y));
                (z * stretch) as f32
            }
            None => f32::NAN,
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every upright pixel's ray stretch is its stored pixel's, for an off-centre,
    /// non-square camera on a non-square grid, in all eight orientations.
    #[test]
    fn oriented_intrinsics_keep_each_pixels_ray() {
        let (w, h) = (7, 4);
        let k = Intrinsics {
            fx: 5.0,
            fy: 3.5,
            cx: 2.25,
            cy: 1.75,
        };
        let stored = Grid::from_fn(w, h, |x, y| k.range_per_depth(x, y));
        for exif in 1..=8 {
            let o = Orientation::from_exif(exif).unwrap();
            let upright = stored.oriented(o);
            let turned = k.oriented(o, w, h);
            for v in 0..upright.height() {
                for u in 0..upright.width() {
                    let (want, got) = (*upright.get(u, v), turned.range_per_depth(u, v));
                    assert!((want - got).abs() < 1e-12, "EXIF {exif} ({u}, {v})");
                }
            }
        }
    }
}
