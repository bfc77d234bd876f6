//! How a `DEPTH16` stream is laid over the colour stream, without calibration.
//!
//! Both streams come from one camera and are turned upright by the same [`Orientation`]
//! (see [`crate::depth16`]). Their aspect ratios often differ: time-of-flight depth is
//! mostly 4:3 (the sensor's field), previews 16:9. Camera2 makes a stream of another aspect
//! ratio than the sensor's by a centred crop of the field, so the colour then sees the
//! centre of what the depth sees: the app crops the upright depth centrally to the
//! colour's aspect ratio ([`centre_crop`]). That is an approximation: the depth sensor's
//! own field, lens and offset from the colour lens (its extrinsics and intrinsics in the
//! camera's characteristics, which the app does not read) are taken as the colour's.
//!
//! After the crop, a depth map smaller than the colour by one factor (1 to 16 on both
//! sides, `brume::refine::check_depth_size`) is upsampled on the GPU guided by the colour
//! frame; any other size is resampled nearest to the colour's size ([`plan`]).
//!
//! [`Orientation`]: crate::orientation::Orientation

/// A window of an upright image, in its pixels: columns `x .. x + width` and rows
/// `y .. y + height`, rows counted from the top.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Crop {
    /// The first column.
    pub x: usize,
    /// The first row from the top.
    pub y: usize,
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
}

impl Crop {
    /// The whole of a `width x height` image.
    pub fn full((width, height): (usize, usize)) -> Crop {
        Crop {
            x: 0,
            y: 0,
            width,
            height,
        }
    }

    /// The window's size.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }
}

/// The largest centred window of an upright `depth` image with the aspect ratio of the
/// upright `colour` image: the depth's whole height when the depth is the wider (a 4:3
/// map under a 16:9 frame held landscape), its whole width when it is the narrower, the
/// cropped side rounded to the nearest pixel (at least 1), the offset rounded down. The
/// whole image for an empty size.
pub fn centre_crop(depth: (usize, usize), colour: (usize, usize)) -> Crop {
    let (dw, dh) = (depth.0 as u128, depth.1 as u128);
    let (cw, ch) = (colour.0 as u128, colour.1 as u128);
    if dw == 0 || dh == 0 || cw == 0 || ch == 0 {
        return Crop::full(depth);
    }
    let rounded = |num: u128, den: u128| ((2 * num + den) / (2 * den)) as usize;
    let (width, height) = if dw * ch > cw * dh {
        // Wider than the colour: keep the height.
        (rounded(dh * cw, ch).clamp(1, depth.0), depth.1)
    } else {
        (depth.0, rounded(dw * ch, cw).clamp(1, depth.1))
    };
    Crop {
        x: (depth.0 - width) / 2,
        y: (depth.1 - height) / 2,
        width,
        height,
    }
}

/// How the cropped depth becomes the colour-sized range texture.
#[derive(Clone, Debug, PartialEq)]
pub enum DepthPath {
    /// The crop has the colour's size: each sample is one texel.
    Same,
    /// Smaller by one factor (`factor` colour pixels per sample): unpacked at its own size
    /// and upsampled to the colour's by joint bilateral upsampling guided by the colour.
    Upsample {
        /// Colour pixels per depth sample (the horizontal factor).
        factor: f64,
    },
    /// Resampled nearest to the colour's size, because upsampling does not apply.
    Nearest {
        /// Why (brume's size rule, with both sizes).
        why: String,
    },
}

/// What to do with an upright `depth` stream under an upright `colour` stream: the
/// centred crop and the path from it to the colour's size.
pub fn plan(depth: (usize, usize), colour: (usize, usize)) -> (Crop, DepthPath) {
    let crop = centre_crop(depth, colour);
    let path = if crop.size() == colour {
        DepthPath::Same
    } else {
        match brume::refine::check_depth_size(colour, crop.size()) {
            Ok(()) => DepthPath::Upsample {
                factor: colour.0 as f64 / crop.width as f64,
            },
            Err(e) => DepthPath::Nearest { why: e.to_string() },
        }
    };
    (crop, path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_4_3_map_under_a_16_9_frame_loses_its_top_and_bottom() {
        // Landscape: 320x240 ToF under 1920x1080: 320x180, rows 30 .. 210.
        let crop = centre_crop((320, 240), (1920, 1080));
        assert_eq!(
            crop,
            Crop {
                x: 0,
                y: 30,
                width: 320,
                height: 180
            }
        );
        // Portrait (a quarter turn): 240x320 under 1080x1920: columns 30 .. 210.
        let crop = centre_crop((240, 320), (1080, 1920));
        assert_eq!(
            crop,
            Crop {
                x: 30,
                y: 0,
                width: 180,
                height: 320
            }
        );
    }

    #[test]
    fn a_narrower_map_loses_its_sides_and_odd_margins_round_down() {
        // 16:9 depth under a 4:3 frame: the width goes.
        let crop = centre_crop((640, 360), (640, 480));
        assert_eq!(crop.size(), (480, 360));
        assert_eq!((crop.x, crop.y), (80, 0));
        // 224x172 under 1920x1080: 224 * 1080 / 1920 = 126 rows, (172 - 126) / 2 = 23.
        let crop = centre_crop((224, 172), (1920, 1080));
        assert_eq!(crop.size(), (224, 126));
        assert_eq!(crop.y, 23);
        // 5x5 under 2:1: 2.5 rows round to 3, the margin of 2 splits 1 above.
        let crop = centre_crop((5, 5), (2, 1));
        assert_eq!(crop.size(), (5, 3));
        assert_eq!((crop.x, crop.y), (0, 1));
    }

    #[test]
    fn the_same_aspect_and_empty_sizes_keep_the_whole_map() {
        assert_eq!(
            centre_crop((640, 480), (1440, 1080)),
            Crop::full((640, 480))
        );
        assert_eq!(centre_crop((0, 480), (1440, 1080)), Crop::full((0, 480)));
        assert_eq!(centre_crop((640, 480), (0, 0)), Crop::full((640, 480)));
        // A sliver never becomes empty.
        assert_eq!(centre_crop((1, 1000), (1000, 1)).size(), (1, 1));
    }

    #[test]
    fn phone_sizes_are_upsampled_and_the_rest_resampled_nearest() {
        let (crop, path) = plan((240, 320), (1080, 1920));
        assert_eq!(crop.size(), (180, 320));
        assert_eq!(path, DepthPath::Upsample { factor: 6.0 });
        let (_, path) = plan((480, 640), (720, 1280));
        assert_eq!(path, DepthPath::Upsample { factor: 2.0 });
        // The crop's rounding stays within brume's 1 % between the sides.
        let (_, path) = plan((172, 224), (1080, 1920));
        assert!(matches!(path, DepthPath::Upsample { .. }), "{path:?}");
        // The colour's own size.
        assert_eq!(plan((1080, 1920), (1080, 1920)).1, DepthPath::Same);
        // 1080 / 60 = 18 > 16 colour pixels per sample.
        let (_, path) = plan((60, 80), (1080, 1920));
        let DepthPath::Nearest { why } = path else {
            panic!("{path:?}")
        };
        assert!(why.contains("16") && why.contains("1080x1920"), "{why}");
        // Larger than the colour.
        assert!(matches!(
            plan((1440, 1920), (720, 960)).1,
            DepthPath::Nearest { .. }
        ));
    }
}
