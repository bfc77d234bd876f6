//! Where the horizon is, for the scene beyond the sensor's reach ([`super::reach`]): the
//! lowest row the sky comes down to, along the horizon's tilt where the ground at the
//! reach tells it (a camera held with roll).

use glam::{DMat3, DVec3};

/// Half the width of the window in which a column's horizon is looked for when its tilt is
/// not known, as a fraction of the image's width: wide enough that a far city hiding the
/// horizon does not raise it (in a street the sky comes down to the horizon only at the
/// street's end, in the middle of the frame; view 2 of the phone evaluation sees it only at
/// its right edge, and a quarter of the width put the horizon 3 rows of a 1/8 map too high
/// on the left), narrow enough that a horizon tilted by the camera's roll is taken near the
/// column (the window puts it up to half the width times the roll's slope too low: 9 px of
/// a 1024 px frame at 1°). 0.05 of the width left DEPTH16 view 1 a third more wrong.
const HORIZON_WINDOW: f64 = 0.5;

/// Each column's horizon: the boundary row (between pixel rows, so `top - 0.5`) below the
/// lowest point of `skyline` (per column, the first row under the sky that reaches the top
/// row, where there is one) along lines of slope `tilt` (rows per column) across the whole
/// width, or, without a tilt, level within [`HORIZON_WINDOW`] of the column; `None`
/// without a point of the skyline there.
pub(super) fn horizon_rows(skyline: &[Option<usize>], tilt: Option<f64>) -> Vec<Option<f64>> {
    let w = skyline.len();
    let Some(slope) = tilt else {
        let half = super::reach::columns_in(HORIZON_WINDOW, w);
        return (0..w)
            .map(|x| {
                let window = &skyline[x.saturating_sub(half)..(x + half + 1).min(w)];
                window.iter().flatten().max().map(|&t| t as f64 - 0.5)
            })
            .collect();
    };
    // The line of that slope through the lowest point: every point of the skyline is
    // on or above it.
    let offset = (skyline.iter().enumerate())
        .filter_map(|(x, top)| top.map(|t| t as f64 - 0.5 - slope * x as f64))
        .max_by(f64::total_cmp);
    (0..w)
        .map(|x| offset.map(|o| o + slope * x as f64))
        .collect()
}

/// Most the camera's roll is taken to be when it is measured: beyond it, the ground's
/// contour is taken to be something else (a street's walls).
const MAX_ROLL_DEG: f64 = 15.0;

/// Largest distance, in rows of the grid, of a column's contour from the fitted curve for
/// it to count as the ground's: the contour is ragged by a row or so with a phone's noise.
const CONTOUR_FIT_ROWS: f64 = 1.5;

/// The tilt of the horizon (rows per column) from the contour of the ground at the
/// sensor's reach (`(column, row)` of the columns whose pixels beyond the reach meet the
/// ground at the reach, left to right) in a frame `w` wide: the contour is a line of equal
/// depth (ARCore's z: parallel to the horizon) or equal range (a time-of-flight camera's:
/// a curve symmetric about the image's centre column for a level camera) on the ground,
/// so the slope at the centre column of a parabola fitted to it is the horizon's. The fit
/// drops columns off it by more than [`CONTOUR_FIT_ROWS`] and refits; `None` (the tilt
/// is not known) unless most columns are on it and they reach an eighth of the width
/// either side of the centre, or where the slope is steeper than [`MAX_ROLL_DEG`].
pub(super) fn tilt_of_contour(contour: &[(usize, f64)], w: usize) -> Option<f64> {
    let centre = (w as f64 - 1.0) / 2.0;
    let points: Vec<(f64, f64)> = (contour.iter())
        .map(|&(x, row)| ((x as f64 - centre) / w as f64, row))
        .collect();
    let near = |c: DVec3, (x, row): (f64, f64)| (c.x + c.y * x + c.z * x * x - row).abs();
    let on_curve = |c: DVec3| -> Vec<(f64, f64)> {
        (points.iter().copied())
            .filter(|&p| near(c, p) <= CONTOUR_FIT_ROWS)
            .collect()
    };
    let mut curve = fit_parabola(points.iter().copied())?;
    for _ in 0..2 {
        curve = fit_parabola(on_curve(curve).into_iter())?;
    }
    let kept = on_curve(curve);
    let reaches = |side: f64| kept.iter().any(|&(x, _)| x * side >= 1.0 / 8.0);
    let slope = curve.y / w as f64;
    let most = 2 * kept.len() > points.len() && kept.len() >= 8;
    (most && reaches(-1.0) && reaches(1.0) && slope.abs() <= MAX_ROLL_DEG.to_radians().tan())
        .then_some(slope)
}

/// Least squares `row = a + b·x + c·x²` (returned as `(a, b, c)`); `None` for fewer than
/// three distinct columns.
fn fit_parabola(points: impl Iterator<Item = (f64, f64)>) -> Option<DVec3> {
    let (mut s, mut t) = ([0.0f64; 5], DVec3::ZERO);
    for (x, y) in points {
        let powers = [1.0, x, x * x, x * x * x, x * x * x * x];
        s.iter_mut().zip(powers).for_each(|(s, p)| *s += p);
        t += DVec3::new(y, x * y, x * x * y);
    }
    let normal = DMat3::from_cols_array(&[s[0], s[1], s[2], s[1], s[2], s[3], s[2], s[3], s[4]]);
    (normal.determinant().abs() > 1e-12 * s[0].powi(3)).then(|| normal.inverse() * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The contour of a time-of-flight camera's reach on flat ground, 128 columns of a
    /// 1/8 grid: a curve rising toward the centre (range is farthest from the axis at the
    /// edges), turned by `roll_deg`, rounded to rows (the grid's) and ragged by a row here
    /// and there (the noise), with a box just within the reach raising it 8 rows over
    /// columns 40-48.
    fn contour(roll_deg: f64, columns: std::ops::Range<usize>) -> Vec<(usize, f64)> {
        let slope = roll_deg.to_radians().tan();
        columns
            .map(|x| {
                let u = x as f64 - 63.5;
                let row = 47.5 + 0.001 * u * u + slope * u + [0.0, 1.0, 0.0, -1.0][x % 4];
                let boxed = if (40..=48).contains(&x) { 8.0 } else { 0.0 };
                (x, row.round() - 0.5 - boxed)
            })
            .collect()
    }

    #[test]
    fn the_horizon_tilts_as_the_ground_contour_at_the_reach() {
        for roll in [-3.0, 0.0, 1.0, 2.0, 10.0] {
            let tilt = tilt_of_contour(&contour(roll, 0..128), 128).unwrap();
            let got = tilt.atan().to_degrees();
            assert!((got - roll).abs() < 0.15, "roll {roll}: {got}");
        }
        // Steeper than a camera's roll (a street's wall), seen on one side only, or on too
        // few columns: not known.
        assert_eq!(tilt_of_contour(&contour(20.0, 0..128), 128), None);
        assert_eq!(tilt_of_contour(&contour(2.0, 0..60), 128), None);
        assert_eq!(tilt_of_contour(&contour(2.0, 60..66), 128), None);
    }

    #[test]
    fn a_tilted_horizon_is_drawn_across_the_whole_width() {
        // A far city hides the sky below row 10 but at the street's end, column 30, where
        // the sky comes down to row 22 (the horizon, tilted by 0.05 rows a column, is at
        // its boundary above, 21.5): tilted, each column's is on that line; level, each
        // within half the width of column 30 has the street end's.
        let skyline: Vec<Option<usize>> = (0..64)
            .map(|x| Some(if x == 30 { 22 } else { 10 }))
            .collect();
        let tilted = horizon_rows(&skyline, Some(0.05));
        let level = horizon_rows(&skyline, None);
        for x in 0..64 {
            let want = 21.5 + 0.05 * (x as f64 - 30.0);
            let got = tilted[x].unwrap();
            assert!((got - want).abs() < 1e-9, "column {x}: {got} / {want}");
            let want = if x <= 62 { 21.5 } else { 9.5 };
            assert_eq!(level[x], Some(want), "level, column {x}");
        }
        assert_eq!(horizon_rows(&[None, None], Some(0.05)), vec![None, None]);
    }
}
