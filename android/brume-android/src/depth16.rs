//! Android's `DEPTH16` samples (Camera2's depth output, `ImageFormat.DEPTH16`), unpacked
//! into the range texture brume's haze reads: one `u16` per pixel, little-endian, the
//! range in millimetres in the low 13 bits (0 = no measurement) and a confidence in the
//! high 3 (0 = 100 %, 1 = 0 %, n = (n − 1)/7 otherwise).
//!
//! The depth stream is resampled (nearest) to the colour's upright size through the
//! same [`Orientation`] as the colour, and written in GL's row order, so that the range
//! texture lines up with the imported colour texel for texel.

use crate::orientation::Orientation;
use std::fmt;

/// The largest range a `DEPTH16` sample can hold (mm).
pub const MAX_RANGE_MM: u16 = 0x1FFF;

/// The range of a sample in millimetres (0: no measurement).
pub fn range_mm(sample: u16) -> u16 {
    sample & MAX_RANGE_MM
}

/// The confidence of a sample, in [0, 1].
pub fn confidence(sample: u16) -> f32 {
    match sample >> 13 {
        0 => 1.0,
        n => f32::from(n - 1) / 7.0,
    }
}

/// One `DEPTH16` plane as the image reader gives it.
#[derive(Clone, Copy, Debug)]
pub struct Depth16<'a> {
    /// The plane's bytes, from its first row.
    pub data: &'a [u8],
    /// Width in samples.
    pub width: usize,
    /// Height in rows.
    pub height: usize,
    /// Bytes from one row to the next (≥ 2 · width; readers pad rows).
    pub row_stride: usize,
}

/// A plane that cannot hold what it claims.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Depth16Error {
    /// Zero width or height.
    Empty,
    /// Rows shorter than their samples.
    RowStride {
        /// The stride given (bytes).
        row_stride: usize,
        /// Two bytes per sample.
        needed: usize,
    },
    /// Fewer bytes than the rows need.
    TooShort {
        /// Bytes given.
        len: usize,
        /// Bytes needed.
        needed: usize,
    },
}

impl fmt::Display for Depth16Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Depth16Error::Empty => write!(f, "DEPTH16 plane: no samples"),
            Depth16Error::RowStride { row_stride, needed } => write!(
                f,
                "DEPTH16 plane: row stride {row_stride} bytes, below the {needed} its samples need"
            ),
            Depth16Error::TooShort { len, needed } => {
                write!(f, "DEPTH16 plane: {len} bytes, its rows need {needed}")
            }
        }
    }
}

impl std::error::Error for Depth16Error {}

impl Depth16<'_> {
    /// Checks that the plane holds its rows.
    pub fn validate(&self) -> Result<(), Depth16Error> {
        if self.width == 0 || self.height == 0 {
            return Err(Depth16Error::Empty);
        }
        if self.row_stride < 2 * self.width {
            return Err(Depth16Error::RowStride {
                row_stride: self.row_stride,
                needed: 2 * self.width,
            });
        }
        // The last row need not be padded.
        let needed = self.row_stride * (self.height - 1) + 2 * self.width;
        if self.data.len() < needed {
            return Err(Depth16Error::TooShort {
                len: self.data.len(),
                needed,
            });
        }
        Ok(())
    }

    /// The sample at column `x` of row `y` (row 0 first in memory). The plane must have
    /// passed [`Depth16::validate`].
    pub fn sample(&self, x: usize, y: usize) -> u16 {
        let i = y * self.row_stride + 2 * x;
        u16::from_le_bytes([self.data[i], self.data[i + 1]])
    }
}

/// What a range value is made of a sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unpack {
    /// Samples below this confidence count as unknown.
    pub min_confidence: f32,
    /// The range (m) given to unknown samples: treated as far, as brume's haze treats
    /// unknown range (no return from a time-of-flight sensor is mostly a far or dark
    /// surface).
    pub far_m: f32,
}

impl Default for Unpack {
    /// Half confidence or better; unknown is 5 m (beyond most phone ToF sensors' reach).
    fn default() -> Self {
        Unpack {
            min_confidence: 0.5,
            far_m: 5.0,
        }
    }
}

impl Unpack {
    /// The range in metres of one sample.
    pub fn range_m(&self, sample: u16) -> f32 {
        let mm = range_mm(sample);
        if mm == 0 || confidence(sample) < self.min_confidence {
            self.far_m
        } else {
            f32::from(mm) / 1000.0
        }
    }
}

/// Fills `out` with the range (m) at each texel of an upright `size` image in GL's row
/// order, resampled (nearest) from `plane` through `orientation`. `out` is resized, so a
/// buffer kept between frames of the same size is never reallocated.
pub fn unpack(
    plane: &Depth16,
    orientation: Orientation,
    size: (usize, usize),
    options: Unpack,
    out: &mut Vec<f32>,
) -> Result<(), Depth16Error> {
    plane.validate()?;
    let (width, height) = size;
    if width == 0 || height == 0 {
        return Err(Depth16Error::Empty);
    }
    out.resize(width * height, 0.0);
    for (y, row) in out.chunks_exact_mut(width).enumerate() {
        let v = (y as f32 + 0.5) / height as f32;
        for (x, value) in row.iter_mut().enumerate() {
            let u = (x as f32 + 0.5) / width as f32;
            let (s, t) = orientation.source(u, v);
            let sx = ((s * plane.width as f32) as usize).min(plane.width - 1);
            let sy = ((t * plane.height as f32) as usize).min(plane.height - 1);
            *value = options.range_m(plane.sample(sx, sy));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plane of `width x height` samples from `f(x, y)`, rows padded to `row_stride`.
    fn plane_bytes(
        width: usize,
        height: usize,
        row_stride: usize,
        f: impl Fn(usize, usize) -> u16,
    ) -> Vec<u8> {
        let mut data = vec![0xEEu8; row_stride * height];
        for y in 0..height {
            for x in 0..width {
                let i = y * row_stride + 2 * x;
                data[i..i + 2].copy_from_slice(&f(x, y).to_le_bytes());
            }
        }
        data
    }

    #[test]
    fn samples_split_into_range_and_confidence() {
        assert_eq!(range_mm(0x1FFF), 8191);
        assert_eq!(range_mm(0xE000 | 1234), 1234);
        assert_eq!(confidence(1234), 1.0);
        assert_eq!(confidence(0x2000 | 1234), 0.0);
        assert_eq!(confidence(0x4000), 1.0 / 7.0);
        assert_eq!(confidence(0xE000), 6.0 / 7.0);
        let unpack = Unpack::default();
        assert_eq!(unpack.range_m(1500), 1.5);
        assert_eq!(unpack.range_m(0), 5.0, "no measurement is far");
        assert_eq!(unpack.range_m(0x2000 | 1500), 5.0, "0 % confidence is far");
        assert_eq!(unpack.range_m(0x8000 | 1500), 5.0, "3/7 is below one half");
        assert_eq!(unpack.range_m(0xA000 | 1500), 1.5, "4/7 is above");
    }

    #[test]
    fn an_upright_plane_is_flipped_into_gls_row_order() {
        let (w, h, stride) = (4, 3, 12);
        let data = plane_bytes(w, h, stride, |x, y| (1000 * (y + 1) + x) as u16);
        let plane = Depth16 {
            data: &data,
            width: w,
            height: h,
            row_stride: stride,
        };
        let mut out = Vec::new();
        unpack(
            &plane,
            Orientation::UPRIGHT,
            (w, h),
            Unpack::default(),
            &mut out,
        )
        .unwrap();
        // GL's row 0 is the plane's last row (y = 2: 3000 mm + x).
        assert_eq!(&out[..4], &[3.0, 3.001, 3.002, 3.003]);
        assert_eq!(&out[8..], &[1.0, 1.001, 1.002, 1.003]);
        let capacity = out.capacity();
        unpack(
            &plane,
            Orientation::UPRIGHT,
            (w, h),
            Unpack::default(),
            &mut out,
        )
        .unwrap();
        assert_eq!(
            out.capacity(),
            capacity,
            "no reallocation for the same size"
        );
    }

    #[test]
    fn a_rotated_plane_follows_the_colours_orientation() {
        let (w, h) = (4, 2);
        let data = plane_bytes(w, h, 2 * w, |x, y| (100 + 10 * y + x) as u16);
        let plane = Depth16 {
            data: &data,
            width: w,
            height: h,
            row_stride: 2 * w,
        };
        let o = Orientation::from_sensor_degrees(90);
        let size = o.upright_size((w, h));
        assert_eq!(size, (2, 4));
        let mut out = Vec::new();
        unpack(&plane, o, size, Unpack::default(), &mut out).unwrap();
        // Upright top-right (GL: last row, last column) is the plane's first sample.
        assert_eq!(out[size.0 * (size.1 - 1) + size.0 - 1], 0.100);
        // Upright bottom-left (GL: texel 0) is the plane's last sample.
        assert_eq!(out[0], 0.113);
    }

    #[test]
    fn resampling_to_a_larger_colour_picks_the_nearest_sample() {
        let data = plane_bytes(2, 1, 4, |x, _| (1000 + 1000 * x) as u16);
        let plane = Depth16 {
            data: &data,
            width: 2,
            height: 1,
            row_stride: 4,
        };
        let mut out = Vec::new();
        unpack(
            &plane,
            Orientation::UPRIGHT,
            (4, 2),
            Unpack::default(),
            &mut out,
        )
        .unwrap();
        assert_eq!(out, [1.0, 1.0, 2.0, 2.0, 1.0, 1.0, 2.0, 2.0]);
    }

    #[test]
    fn short_planes_are_refused() {
        let data = [0u8; 10];
        let plane = |width, height, row_stride| Depth16 {
            data: &data,
            width,
            height,
            row_stride,
        };
        let mut out = Vec::new();
        let mut run = |p: Depth16| {
            unpack(
                &p,
                Orientation::UPRIGHT,
                (2, 2),
                Unpack::default(),
                &mut out,
            )
        };
        assert_eq!(run(plane(0, 2, 4)), Err(Depth16Error::Empty));
        assert_eq!(
            run(plane(3, 2, 4)),
            Err(Depth16Error::RowStride {
                row_stride: 4,
                needed: 6
            })
        );
        assert_eq!(
            run(plane(2, 3, 4)),
            Err(Depth16Error::TooShort {
                len: 10,
                needed: 12
            })
        );
        // The last row needs no padding: 2 rows of stride 6 with 2 samples fit in 10.
        assert!(run(plane(2, 2, 6)).is_ok());
        assert!(Depth16Error::TooShort { len: 1, needed: 2 }
            .to_string()
            .contains("DEPTH16"));
    }
}
