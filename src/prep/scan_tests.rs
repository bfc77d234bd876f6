//! Unit tests of `prep::scan`: the gaps between a scanner's lines, found and filled.

use super::*;
use crate::raster::RgbImage;

const W: usize = 6;
const H: usize = 40;

/// A map known on every 4th row (the scanner's lines), NaN elsewhere, of `range(y)`.
fn scanned(range: impl Fn(usize) -> f32) -> Vec<f32> {
    (0..W * H)
        .map(|p| match p / W {
            y if y % 4 == 0 => range(y),
            _ => f32::NAN,
        })
        .collect()
}

#[test]
fn lines_a_few_rows_apart_are_found_and_blobs_are_not() {
    let map = scanned(|_| 10.0);
    let gaps = find_lines(&map, (W, H)).expect("scanned").gaps;
    // Between rows 0 and 36 every unknown pixel is a gap; below the last line, none.
    assert!((0..W * H).all(|p| gaps[p] == (map[p].is_nan() && p / W < 36)));
    // A map with one hole in a block (a stereo matcher's) is not scanned.
    let blob: Vec<f32> = (0..W * H)
        .map(|p| {
            if (10..30).contains(&(p / W)) {
                f32::NAN
            } else {
                10.0
            }
        })
        .collect();
    assert!(find_lines(&blob, (W, H)).is_none());
}

#[test]
fn dotted_lines_are_found_and_their_gaps_filled() {
    // KITTI's lines are dots two to four pixels apart, each line's dots at other columns
    // (here every third column, shifted by one from line to line): down most columns a
    // line is missing, and the runs between the known pixels are three times as long.
    let w = 30;
    let map: Vec<f32> = (0..w * H)
        .map(|p| {
            let (x, y) = (p % w, p / w);
            match y % 4 == 0 && x % 3 == (y / 4) % 3 {
                true => ground(y),
                false => f32::NAN,
            }
        })
        .collect();
    let mut work = map.clone();
    let gaps = find_lines(&work, (w, H)).expect("scanned").gaps;
    let image = RgbImage::from_fn(w, H, |_, _| [0.1, 0.5, 0.1]);
    let guide = ColourGuide::new(&image, 0.08);
    fill_gaps(&mut work, &gaps, &vec![false; w * H], Some(&guide), (w, H));
    // Every pixel between the first and the last line, but beside the first and the last
    // dot of a row (no dot beyond them to join), is the ground's range.
    for p in (0..w * H).filter(|&p| p / w <= 36 && (3..w - 3).contains(&(p % w))) {
        let want = ground(p / w);
        assert!(
            (work[p] / want - 1.0).abs() < 1e-5,
            "({}, {}): {} for {want}",
            p % w,
            p / w,
            work[p]
        );
    }
}

/// The ground seen by a level camera: 1/R grows linearly down the rows below the horizon
/// (row -2 here), as any plane's inverse depth does.
fn ground(y: usize) -> f32 {
    1.0 / (0.01 * (y as f32 + 2.0))
}

#[test]
fn a_gap_on_one_surface_is_filled_linearly_in_inverse_range() {
    // Near the horizon one line is three times as far as the next: one colour tells the
    // ends are of one surface.
    let image = RgbImage::from_fn(W, H, |_, _| [0.1, 0.5, 0.1]);
    let guide = ColourGuide::new(&image, 0.08);
    let mut map = scanned(ground);
    let gaps = find_lines(&map, (W, H)).unwrap().gaps;
    let filled = fill_gaps(&mut map, &gaps, &vec![false; W * H], Some(&guide), (W, H));
    assert_eq!(filled, gaps.iter().filter(|&&g| g).count());
    for p in (0..W * H).filter(|&p| p / W <= 36) {
        let want = ground(p / W);
        assert!(
            (map[p] / want - 1.0).abs() < 1e-5,
            "row {}: {}",
            p / W,
            map[p]
        );
    }
    // A linear fill in range would be a third off mid-gap near the top (row 2).
    let linear = 0.5 * (ground(0) + ground(4));
    assert!(linear / ground(2) - 1.0 > 0.3);
}

/// A red box 8 m away on rows 0-17, green ground 20 m away below: the gap from row 16 to 20
/// meets the box above and the ground below, whose colour edge lies between rows 17 and 18.
#[test]
fn a_gap_across_a_depth_edge_splits_at_the_colour_edge_or_waits() {
    let range = |y: usize| if y < 18 { 8.0 } else { 20.0 };
    let image = RgbImage::from_fn(W, H, |_, y| {
        if y < 18 {
            [0.6, 0.1, 0.1]
        } else {
            [0.1, 0.5, 0.1]
        }
    });
    let guide = ColourGuide::new(&image, 0.08);
    let mut map = scanned(range);
    let gaps = find_lines(&map, (W, H)).unwrap().gaps;
    fill_gaps(&mut map, &gaps, &vec![false; W * H], Some(&guide), (W, H));
    for (p, &v) in map.iter().enumerate().take(W * 37) {
        assert_eq!(v, range(p / W), "row {}", p / W);
    }
    // Without the image the gap across the edge is left to the hole fill; the others fill.
    let mut blind = scanned(range);
    fill_gaps(&mut blind, &gaps, &vec![false; W * H], None, (W, H));
    for (p, &v) in blind.iter().enumerate().take(W * 36) {
        match p / W {
            17..=19 => assert!(v.is_nan(), "row {}", p / W),
            y => assert_eq!(v, range(y), "row {y}"),
        }
    }
}

#[test]
fn gaps_in_the_sky_and_gaps_to_an_unknown_end_stay() {
    let mut map = scanned(|_| 10.0);
    let gaps = find_lines(&map, (W, H)).unwrap().gaps;
    let sky: Vec<bool> = (0..W * H).map(|p| p / W < 8).collect();
    map[12 * W] = f32::INFINITY;
    fill_gaps(&mut map, &gaps, &sky, None, (W, H));
    assert!((W..8 * W).all(|p| map[p].is_nan() == (p / W != 4)));
    assert!(map[9 * W].is_nan() && map[13 * W].is_nan());
    assert_eq!(map[9 * W + 1], 10.0);
}

/// A grey face 10 m away known on every 4th row, with the background 25 m away on two
/// points of one line (seen past an edge) and a blue tower 25 m away right of the face:
/// the two points go, the tower stays.
#[test]
fn points_unlike_their_colour_round_them_go() {
    let (w, h) = (48, 12);
    let blue = |x: usize| x >= 36;
    let image = RgbImage::from_fn(
        w,
        h,
        |x, _| if blue(x) { [0.1, 0.2, 0.6] } else { [0.4; 3] },
    );
    let guide = ColourGuide::new(&image, 0.08);
    let mut map: Vec<f32> = (0..w * h)
        .map(|p| match (p % w, p / w) {
            (_, y) if y % 4 != 0 => f32::NAN,
            (x, _) if blue(x) => 25.0,
            (20 | 21, 4) => 25.0,
            _ => 10.0,
        })
        .collect();
    let dropped = drop_points_unlike_their_colour(&mut map, &vec![false; w * h], &guide, (w, h));
    assert_eq!(dropped, 2);
    assert!(map[4 * w + 20].is_nan() && map[4 * w + 21].is_nan());
    assert!((0..w * h)
        .filter(|&p| p % w >= 36 && p / w % 4 == 0)
        .all(|p| map[p] == 25.0));
}

/// The scene beyond the reach is kept over the top line only, in columns no line crosses
/// too (the nearest line's), and not below it; the depth rules read every unknown pixel
/// below the line as known.
#[test]
fn beyond_the_reach_is_over_the_top_line() {
    let (w, h) = (20, 20);
    let map: Vec<f32> = (0..w * h)
        .map(|p| match (p % w, p / w) {
            (x, _) if x < 3 || x == 9 => f32::NAN,
            (_, 12 | 14 | 16 | 18) => 10.0,
            _ => f32::NAN,
        })
        .collect();
    let lines = find_lines(&map, (w, h)).expect("scanned");
    let mut beyond: Vec<usize> = (0..w * h).filter(|&p| map[p].is_nan()).collect();
    lines.keep_beyond_reach_over_line(&mut beyond, false);
    assert_eq!(beyond, (0..12 * w).collect::<Vec<_>>());
    let closed = lines.closed(&map);
    assert!((0..w * h).all(|p| closed[p].is_nan() == (p / w < 12)));
}

/// A scan along a street: walls on both sides reach the scanner's top beam, tilted (row 8
/// at the left, 11 at the right); the middle third, open, returns from row 24 down.
fn street(w: usize, h: usize, open: std::ops::Range<usize>) -> Vec<f32> {
    (0..w * h)
        .map(|p| {
            let (x, y) = (p % w, p / w);
            let top = if open.contains(&x) { 24 } else { 8 + x / 32 };
            match y >= top && (y - top).is_multiple_of(4) {
                true => 10.0,
                false => f32::NAN,
            }
        })
        .collect()
}

/// Over the top beam only the open part, which the upper beams swept and met nothing
/// in, is beyond the reach; over the walls, which go on up, lie holes. Without the image's
/// sky (whose pixels would then be among them), or with the beam met in too few columns
/// to tell its row, everything over the line stays beyond the reach.
#[test]
fn over_the_top_beam_only_what_met_nothing_is_beyond_the_reach() {
    let (w, h) = (96, 40);
    let over_line = |lines: &ScanLines| -> Vec<usize> {
        (0..w * h)
            .filter(|&p| p / w < lines.top_line[p % w])
            .collect()
    };
    let map = street(w, h, 32..64);
    let lines = find_lines(&map, (w, h)).expect("scanned");
    let mut beyond = over_line(&lines);
    lines.keep_beyond_reach_over_line(&mut beyond, true);
    // The open part less the line's reach into it (the walls' top line) on each side.
    let want: Vec<usize> = (0..w * h)
        .filter(|&p| (36..60).contains(&(p % w)) && p / w < 24)
        .collect();
    assert_eq!(beyond, want);

    let mut without_sky = over_line(&lines);
    lines.keep_beyond_reach_over_line(&mut without_sky, false);
    assert_eq!(without_sky, over_line(&lines));

    // Walls over a third of the width only: the beam's row is not told.
    let map = street(w, h, 32..96);
    let lines = find_lines(&map, (w, h)).expect("scanned");
    let mut beyond = over_line(&lines);
    lines.keep_beyond_reach_over_line(&mut beyond, true);
    assert_eq!(beyond, over_line(&lines));
}

/// The least-squares quadratic recovers one from exact points, and refuses too few.
#[test]
fn a_quadratic_is_fitted_through_its_points() {
    let q = |x: f64| 145.0 - 0.02 * x + 1e-5 * x * x;
    let points: Vec<(f64, f64)> = (0..24)
        .map(|b| (b as f64 * 50.0, q(b as f64 * 50.0)))
        .collect();
    let fit = quadratic_fit(&points).expect("fitted");
    for x in [0.0, 333.0, 1241.0] {
        assert!((fit(x) - q(x)).abs() < 1e-9, "{x}: {} for {}", fit(x), q(x));
    }
    assert!(quadratic_fit(&points[..2]).is_none());
    assert!(quadratic_fit(&[(5.0, 1.0); 4]).is_none());
}
