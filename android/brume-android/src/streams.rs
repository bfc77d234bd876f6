//! Which camera streams to ask for, from the camera's characteristics
//! (`ACAMERA_SCALER_AVAILABLE_STREAM_CONFIGURATIONS`, and
//! `ACAMERA_DEPTH_AVAILABLE_DEPTH_STREAM_CONFIGURATIONS` for `DEPTH16`): both are flat
//! `i32` lists of (format, width, height, is-input) quadruples. brume draws its result
//! 1:1 into the window, so the colour stream is the largest whose upright size fits it.

use crate::orientation::Orientation;

/// The output sizes listed for `format`, in the order given.
pub fn output_sizes(entries: &[i32], format: i32) -> Vec<(usize, usize)> {
    entries
        .chunks_exact(4)
        .filter(|q| q[0] == format && q[3] == 0 && q[1] > 0 && q[2] > 0)
        .map(|q| (q[1] as usize, q[2] as usize))
        .collect()
}

/// The largest size (by area) whose upright size fits in `fit`; the smallest size when
/// none fits; `None` when there are none.
pub fn largest_fitting(
    sizes: &[(usize, usize)],
    orientation: Orientation,
    fit: (usize, usize),
) -> Option<(usize, usize)> {
    let area = |&(w, h): &(usize, usize)| w * h;
    sizes
        .iter()
        .filter(|&&size| {
            let (w, h) = orientation.upright_size(size);
            w <= fit.0 && h <= fit.1
        })
        .max_by_key(|s| area(s))
        .or_else(|| sizes.iter().min_by_key(|s| area(s)))
        .copied()
}

/// The largest size by area; `None` when there are none.
pub fn largest(sizes: &[(usize, usize)]) -> Option<(usize, usize)> {
    sizes.iter().max_by_key(|&&(w, h)| w * h).copied()
}

#[cfg(test)]
mod tests {
    use super::*;

    const PRIVATE: i32 = 0x22;
    const DEPTH16: i32 = 0x4436_3159;

    #[test]
    fn outputs_of_one_format_are_picked_from_the_quadruples() {
        let entries = [
            PRIVATE, 1920, 1080, 0, //
            PRIVATE, 640, 480, 0, //
            PRIVATE, 4000, 3000, 1, // an input stream
            DEPTH16, 240, 180, 0, //
            35, 1280, 720, 0,
        ];
        assert_eq!(output_sizes(&entries, PRIVATE), [(1920, 1080), (640, 480)]);
        assert_eq!(output_sizes(&entries, DEPTH16), [(240, 180)]);
        assert!(
            output_sizes(&entries[..3], PRIVATE).is_empty(),
            "a partial quadruple"
        );
    }

    #[test]
    fn the_colour_stream_is_the_largest_that_fits_the_window_upright() {
        let sizes = [(4000, 3000), (1920, 1080), (1280, 720), (640, 480)];
        let portrait = Orientation::from_sensor_degrees(90);
        // A 1080 x 2400 portrait window: 1920 x 1080 turns to 1080 x 1920, which fits.
        assert_eq!(
            largest_fitting(&sizes, portrait, (1080, 2400)),
            Some((1920, 1080))
        );
        // Unturned, 1920 x 1080 is too wide for it.
        assert_eq!(
            largest_fitting(&sizes, Orientation::UPRIGHT, (1080, 2400)),
            Some((640, 480))
        );
        assert_eq!(
            largest_fitting(&sizes, portrait, (100, 100)),
            Some((640, 480))
        );
        assert_eq!(largest_fitting(&[], portrait, (100, 100)), None);
        assert_eq!(largest(&sizes), Some((4000, 3000)));
    }
}
