//! Android's `DEPTH16` samples (Camera2's depth output, `ImageFormat.DEPTH16`), unpacked
//! into the range texture brume's haze reads: one `u16` per pixel, little-endian, the
//! range in millimetres in the low 13 bits (0 = no measurement) and a confidence in the
//! high 3 (0 = 100 %, 1 = 0 %, n = (n − 1)/7 otherwise).
//!
//! The depth stream is turned upright through the same [`Orientation`] as the colour,
//! cropped to a window of it ([`crate::registration`]: the colour's aspect ratio) and
//! written in GL's row order, either at the window's own size (one texel per sample, for
//! the GPU's upsampling) or resampled nearest to the colour's size, so that the range
//! texture lines up with the imported colour.

use crate::orientation::Orientation;
use crate::registration::Crop;
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
    /// A window that is empty or reaches outside the upright plane.
    Crop {
        /// The window.
        crop: Crop,
        /// The upright plane's size.
        upright: (usize, usize),
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
            Depth16Error::Crop { crop, upright } => write!(
                f,
                "DEPTH16 plane: the window {}x{} at ({}, {}) is empty or outside the upright {}x{}",
                crop.width, crop.height, crop.x, crop.y, upright.0, upright.1
            ),
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

/// Fills `out` with the range (m) at each texel of a `size` image in GL's row order,
/// resampled (nearest) from the window `crop` of `plane` turned upright through
/// `orientation` (`Crop::full(orientation.upright_size(..))` for all of it). `out` is
/// resized, so a buffer kept between frames of the same size is never reallocated.
pub fn unpack(
    plane: &Depth16,
    orientation: Orientation,
    crop: Crop,
    size: (usize, usize),
    options: Unpack,
    out: &mut Vec<f32>,
) -> Result<(), Depth16Error> {
    plane.validate()?;
    let (width, height) = size;
    if width == 0 || height == 0 {
        return Err(Depth16Error::Empty);
    }
    let upright = orientation.upright_size((plane.width, plane.height));
    if crop.width == 0
        || crop.height == 0
        || crop.x + crop.width > upright.0
        || crop.y + crop.height > upright.1
    {
        return Err(Depth16Error::Crop { crop, upright });
    }
    out.resize(width * height, 0.0);
    // Texel centres, in the upright plane's texture coordinates (v = 0 at the bottom): at
    // the window's own size each lands on one sample's centre, which nearest picks.
    let (uw, uh) = (upright.0 as f64, upright.1 as f64);
    for (y, row) in out.chunks_exact_mut(width).enumerate() {
        let from_top =
            crop.y as f64 + ((height - 1 - y) as f64 + 0.5) / height as f64 * crop.height as f64;
        let v = (1.0 - from_top / uh) as f32;
        for (x, value) in row.iter_mut().enumerate() {
            let across = crop.x as f64 + (x as f64 + 0.5) / width as f64 * crop.width as f64;
            let u = (across / uw) as f32;
            let (s, t) = orientation.source(u, v);
            let sx = ((s * plane.width as f32) as usize).min(plane.width - 1);
            let sy = ((t * plane.height as f32) as usize).min(plane.height - 1);
            *value = options.range_m(plane.sample(sx, sy));
        }
    }
    Ok(())
}

/// [`unpack`] at the window's own size: one texel per sample, no resampling. Returns that
/// size.
pub fn unpack_window(
    plane: &Depth16,
    orientation: Orientation,
    crop: Crop,
    options: Unpack,
    out: &mut Vec<f32>,
) -> Result<(usize, usize), Depth16Error> {
    unpack(plane, orientation, crop, crop.size(), options, out)?;
    Ok(crop.size())
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
            Crop::full((w, h)),
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
            Crop::full((w, h)),
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
        unpack(
            &plane,
            o,
            Crop::full(size),
            size,
            Unpack::default(),
            &mut out,
        )
        .unwrap();
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
            Crop::full((2, 1)),
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
                Crop::full((p.width, p.height)),
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
    #[test]
    fn a_window_unpacks_at_its_own_size_one_texel_per_sample() {
        // A 4x3 plane (sample = 1000 mm + 10·row + column), its window of 2x2 from
        // column 1, row 1 (from the top).
        let (w, h) = (4, 3);
        let data = plane_bytes(w, h, 2 * w + 4, |x, y| (1000 + 10 * y + x) as u16);
        let plane = Depth16 {
            data: &data,
            width: w,
            height: h,
            row_stride: 2 * w + 4,
        };
        let crop = Crop {
            x: 1,
            y: 1,
            width: 2,
            height: 2,
        };
        let mut out = Vec::new();
        let size = unpack_window(
            &plane,
            Orientation::UPRIGHT,
            crop,
            Unpack::default(),
            &mut out,
        )
        .unwrap();
        assert_eq!(size, (2, 2));
        // GL's row 0 is the window's last row (plane row 2).
        assert_eq!(out, [1.021, 1.022, 1.011, 1.012]);
    }

    #[test]
    fn every_orientation_unpacks_the_whole_plane_without_resampling() {
        // Every sample distinct: the upright image at the upright size holds each once,
        // where the orientation map puts it.
        let (w, h) = (5, 3);
        let data = plane_bytes(w, h, 2 * w, |x, y| (1 + 10 * y + x) as u16);
        let plane = Depth16 {
            data: &data,
            width: w,
            height: h,
            row_stride: 2 * w,
        };
        for degrees in [0, 90, 180, 270] {
            let o = Orientation::from_sensor_degrees(degrees);
            let upright = o.upright_size((w, h));
            let mut out = Vec::new();
            let size =
                unpack_window(&plane, o, Crop::full(upright), Unpack::default(), &mut out).unwrap();
            assert_eq!(size, upright, "{degrees}°");
            let mut seen: Vec<u32> = out.iter().map(|r| (r * 1000.0).round() as u32).collect();
            seen.sort_unstable();
            let mut all: Vec<u32> = (0..h)
                .flat_map(|y| (0..w).map(move |x| (1 + 10 * y + x) as u32))
                .collect();
            all.sort_unstable();
            assert_eq!(seen, all, "{degrees}°: each sample once");
            // Each texel is the sample the orientation map shows at its centre.
            for (i, r) in out.iter().enumerate() {
                let (x, y) = (i % upright.0, i / upright.0);
                let u = (x as f32 + 0.5) / upright.0 as f32;
                let v = (y as f32 + 0.5) / upright.1 as f32;
                let (s, t) = o.source(u, v);
                let (sx, sy) = ((s * w as f32) as usize, (t * h as f32) as usize);
                assert_eq!(*r, Unpack::default().range_m(plane.sample(sx, sy)));
            }
        }
    }

    #[test]
    fn a_window_is_cut_from_the_upright_image() {
        // A quarter turn: the 4x2 plane is 2x4 upright; the window is its lower half.
        let (w, h) = (4, 2);
        let data = plane_bytes(w, h, 2 * w, |x, y| (100 + 10 * y + x) as u16);
        let plane = Depth16 {
            data: &data,
            width: w,
            height: h,
            row_stride: 2 * w,
        };
        let o = Orientation::from_sensor_degrees(90);
        let crop = Crop {
            x: 0,
            y: 2,
            width: 2,
            height: 2,
        };
        let mut out = Vec::new();
        unpack_window(&plane, o, crop, Unpack::default(), &mut out).unwrap();
        let mut whole = Vec::new();
        unpack_window(&plane, o, Crop::full((2, 4)), Unpack::default(), &mut whole).unwrap();
        // GL's rows 0 and 1 are the upright image's two bottom rows.
        assert_eq!(out, whole[..4]);
        // A window outside the upright image is refused.
        let outside = Crop { y: 3, ..crop };
        let e = unpack_window(&plane, o, outside, Unpack::default(), &mut out).unwrap_err();
        assert_eq!(
            e,
            Depth16Error::Crop {
                crop: outside,
                upright: (2, 4)
            }
        );
        assert!(e.to_string().contains("2x4"), "{e}");
    }

    #[test]
    fn a_cropped_window_resampled_to_the_colour_stretches_only_the_window() {
        // A 4x3 plane under an 8x2 colour (4:1): the crop keeps row 1 only, stretched
        // along its width, not the whole plane squeezed.
        let data = plane_bytes(4, 3, 8, |x, y| (1000 * (y + 1) + x) as u16);
        let plane = Depth16 {
            data: &data,
            width: 4,
            height: 3,
            row_stride: 8,
        };
        let crop = crate::registration::centre_crop((4, 3), (8, 2));
        assert_eq!((crop.y, crop.size()), (1, (4, 1)));
        let mut out = Vec::new();
        unpack(
            &plane,
            Orientation::UPRIGHT,
            crop,
            (8, 2),
            Unpack::default(),
            &mut out,
        )
        .unwrap();
        let row = [2.0, 2.0, 2.001, 2.001, 2.002, 2.002, 2.003, 2.003];
        assert_eq!(out[..8], row);
        assert_eq!(out[8..], row);
    }
}
