//! The scene beyond the sensor's reach: unknown pixels joined to the sky that the image
//! shows are not sky (see the module docs of [`crate::prep`], step 4).

/// Where one end of a vertical run of pixels beyond the reach leads.
#[derive(Clone, Copy, PartialEq, Debug)]
enum End {
    /// A pixel of the scene: the run starts at the sensor's reach.
    Scene,
    /// The sky or the image's top or bottom border.
    Sky,
}

/// Fills the pixels `beyond` (not sky) of `work`: each vertical run of them recedes, linearly
/// in log range, from `r_max` where it meets the scene to `s_max` where it meets the sky
/// (or the image border): a column of it is what the sensor did not reach, at least as far
/// as the farthest it measured, and nearer the horizon the farther. A run between the scene
/// at both ends is at `r_max`, one between the sky at both ends at `s_max`. Columns
/// are filled on their own: the known range beside them (a near pole) says nothing of the
/// background behind it, and blending it in would draw a clear halo round the pole.
pub(crate) fn recede(
    work: &mut [f32],
    (sky, beyond): (&[bool], &[usize]),
    (w, h): (usize, usize),
    (r_max, s_max): (f32, f32),
) {
    let mut is_beyond = vec![false; w * h];
    beyond.iter().for_each(|&p| is_beyond[p] = true);
    let end = |y: Option<usize>, x: usize| match y {
        Some(y) if !sky[y * w + x] => End::Scene,
        _ => End::Sky,
    };
    let log_of = |e: End| match e {
        End::Scene => f64::from(r_max).ln(),
        End::Sky => f64::from(s_max).ln(),
    };
    for x in 0..w {
        let mut y = 0;
        while y < h {
            if !is_beyond[y * w + x] {
                y += 1;
                continue;
            }
            let top = y;
            while y < h && is_beyond[y * w + x] {
                y += 1;
            }
            let (above, below) = (end(top.checked_sub(1), x), end((y < h).then_some(y), x));
            let (lo, hi) = (log_of(below), log_of(above));
            let n = (y - top) as f64;
            for (k, row) in (top..y).enumerate() {
                // 1 at the upper end's neighbour, 0 at the lower end's.
                let t = (n - k as f64) / (n + 1.0);
                work[row * w + x] = (lo + t * (hi - lo)).exp() as f32;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_column_recedes_from_the_reach_into_the_sky_in_log_range() {
        // One column: sky, three pixels beyond the reach, the scene (a near pole at 2).
        let sky = [true, false, false, false, false];
        let mut work = [f32::INFINITY, f32::NAN, f32::NAN, f32::NAN, 2.0];
        recede(&mut work, (&sky, &[1, 2, 3]), (1, 5), (8.0, 128.0));
        // ln 8 .. ln 128 in four equal steps: 8, 16, 32, 64, 128.
        for (got, want) in work[1..4].iter().zip([64.0, 32.0, 16.0]) {
            assert!((got - want).abs() < 1e-3 * want, "{got} / {want}");
        }
        assert_eq!(work[4], 2.0, "the known pixel is left alone");
    }

    #[test]
    fn each_column_is_filled_on_its_own() {
        // Two columns: the left one's run meets a near pole (range 1) below, the right
        // one's the sky at both ends; neither takes anything from the other.
        let (w, h) = (2, 3);
        let sky = [true, true, false, false, false, true];
        let mut work = [
            f32::INFINITY,
            f32::INFINITY,
            f32::NAN,
            f32::NAN,
            1.0,
            f32::INFINITY,
        ];
        recede(&mut work, (&sky, &[2, 3]), (w, h), (10.0, 15.0));
        let middle = (10.0f64.ln() + 15.0f64.ln()) / 2.0;
        assert!(
            (f64::from(work[2]) - middle.exp()).abs() < 1e-4,
            "{}",
            work[2]
        );
        assert_eq!(work[3], 15.0, "sky above and below: the sky's range");
    }
}
