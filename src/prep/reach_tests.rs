//! Unit tests of `prep::reach`: each rule on small frames, with the image and without.

use super::*;
use crate::raster::RgbImage;
use std::ops::RangeInclusive;

fn close(got: f32, want: f64) -> bool {
    (f64::from(got) - want).abs() < 1e-4 * want
}

/// A `w x h` frame whose last row is the scene at the reach (range 10, the tests'
/// `Rmax`) and whose other pixels are sky where `is_sky`, else beyond the reach: the
/// sky mask, the range, the mask of the pixels beyond.
fn frame(
    w: usize,
    h: usize,
    is_sky: impl Fn(usize, usize) -> bool,
) -> (Vec<bool>, Vec<f32>, Vec<bool>) {
    let mut sky = vec![false; w * h];
    let mut work = vec![10.0f32; w * h];
    let mut beyond = vec![false; w * h];
    for p in 0..w * (h - 1) {
        if is_sky(p % w, p / w) {
            sky[p] = true;
            work[p] = f32::INFINITY;
        } else {
            beyond[p] = true;
            work[p] = f32::NAN;
        }
    }
    (sky, work, beyond)
}

#[test]
fn a_column_recedes_from_the_reach_to_its_horizon_in_log_range() {
    // One column: sky, three pixels beyond the reach, the scene (a near pole at 2).
    let sky = [true, false, false, false, false];
    let mut work = [f32::INFINITY, f32::NAN, f32::NAN, f32::NAN, 2.0];
    let beyond = [false, true, true, true, false];
    recede(&mut work, (&sky, &beyond), (1, 5), (8.0, 128.0), None);
    // The contour at row 3.5, the horizon at 0.5: t = 5/6, 1/2, 1/6 of ln 16 over ln 8.
    for (got, t) in work[1..4].iter().zip([5.0 / 6.0, 0.5, 1.0 / 6.0]) {
        let want = 8.0 * 16f64.powf(t);
        assert!(close(*got, want), "{got} / {want}");
    }
    assert_eq!(work[4], 2.0, "the known pixel is left alone");
}

#[test]
fn the_range_beside_a_run_is_not_used() {
    // Two columns: the left one's run meets a near pole (range 1) below, the right
    // one's the sky at both ends; the pole's range goes nowhere.
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
    let beyond = [false, false, true, true, false, false];
    recede(&mut work, (&sky, &beyond), (w, h), (10.0, 15.0), None);
    assert!(close(work[2], 150f64.sqrt()), "{}", work[2]);
    assert_eq!(work[3], 15.0, "sky above and below: the sky's range");
}

#[test]
fn the_ground_behind_a_box_recedes_as_beside_it() {
    // Three columns: the sky in row 0, beyond the reach rows 1-8 beside and 1-5 in the
    // middle, where a box stands in rows 6-9, near (range 3) or just within the reach
    // (9: its top edge is no contour of the ground at the reach, as it rises 3 rows
    // above the ground's beside); row 9 beside is the ground at the reach (range 10 =
    // Rmax). Above the box the lawn behind it has the range of the lawn beside it, not
    // the reach's; a slate face behind the box (its foot hidden) is farther than the
    // reach at the box's top edge and nearer than the lawn there.
    for box_range in [3.0, 9.0] {
        ground_behind_a_box(box_range);
    }
}

fn ground_behind_a_box(box_range: f32) {
    let (w, h) = (3, 10);
    let box_ = |x: usize, y: usize| x == 1 && y >= 6;
    let ground_behind = |behind: [f32; 3]| {
        let (sky, mut work, mut beyond) = frame(w, h, |_, y| y == 0);
        for p in (0..w * h).filter(|&p| box_(p % w, p / w)) {
            (beyond[p], work[p]) = (false, box_range);
        }
        let image = RgbImage::from_fn(w, h, |x, y| match (x, y) {
            (_, 0) => [0.5, 0.6, 0.9],
            _ if box_(x, y) => [0.6, 0.5, 0.1],
            (1, _) => behind,
            _ => lawn(y),
        });
        guided_and_plain(work, (&sky, &beyond), (w, h), &image)
    };
    let (work, plain) = ground_behind(lawn(5));
    for y in 1..6 {
        let row = &work[y * w..y * w + 3];
        assert!(
            row[1] == row[0] && row[1] == row[2],
            "{box_range}, row {y}: {row:?}"
        );
    }
    assert!(work[5 * w + 1] > plain[5 * w + 1], "{box_range}: {plain:?}");
    let lawn_behind = work[5 * w + 1];
    let (work, plain) = ground_behind([0.2, 0.25, 0.35]);
    let between = plain[5 * w + 1]..lawn_behind;
    assert!(
        between.contains(&work[5 * w + 1]),
        "{box_range}: {work:?} {between:?}"
    );
}

#[test]
fn the_horizon_is_looked_for_half_the_width_either_side() {
    // Ten columns under a far city that hides the sky below row 3, but for the
    // street's end in column 9, where the sky comes down to row 5: columns within
    // half the width of it (5 columns) have their horizon there, the others at the
    // city's skyline.
    let (w, h) = (10, 8);
    let (sky, _, beyond) = frame(w, h, |x, y| y < if x == 9 { 5 } else { 3 });
    let runs = runs_of(&beyond, w, h);
    let skyline = skyline(&runs, |r| r.top > 0 && sky[(r.top - 1) * w + r.x], w);
    let horizon = horizon::horizon_rows(&skyline, None);
    for (x, hz) in horizon.iter().enumerate() {
        assert_eq!(*hz, Some(if x >= 4 { 4.5 } else { 2.5 }), "column {x}");
    }
}

#[test]
fn the_ground_below_a_far_tower_recedes_as_beside_it() {
    // Three columns, the middle one a far tower reaching row 1; the sky comes down to
    // row 1 beside it. Beyond the reach: rows 2-4 beside, 1-4 in the middle; row 5 the
    // scene.
    let (w, h) = (3, 6);
    let (sky, mut work, beyond) = frame(w, h, |x, y| y == 0 || (y == 1 && x != 1));
    recede(&mut work, (&sky, &beyond), (w, h), (10.0, 40.0), None);
    for y in 2..5 {
        let row = &work[y * w..y * w + 3];
        assert!(row[1] == row[0] && row[1] == row[2], "row {y}: {row:?}");
    }
    assert_eq!(
        work[w + 1],
        40.0,
        "the tower above the horizon: the sky's range"
    );
    assert!(work[2 * w] > work[4 * w], "farther up: {work:?}");
}

#[test]
fn sky_in_the_water_is_not_the_horizon() {
    // Three columns: the sky in rows 0-1, beyond the reach rows 2-6, the scene row 7;
    // in the right column row 5 is sky seen in water, not joined to the sky above.
    let (w, h) = (3, 8);
    let (sky, mut work, beyond) = frame(w, h, |x, y| y < 2 || (x, y) == (2, 5));
    recede(&mut work, (&sky, &beyond), (w, h), (10.0, 40.0), None);
    // The horizon at 1.5, the contour at 6.5: row 4 is halfway up (the water's row
    // would have put the horizon at 5.5 and row 4 in the sky's range).
    let want = 10.0 * 4f64.powf(0.5);
    assert!(close(work[4 * w], want), "{} / {want}", work[4 * w]);
}

/// Two tones of one green lawn (the same chromaticity, 1.6 times as bright).
fn lawn(y: usize) -> [f32; 3] {
    if (y / 3).is_multiple_of(2) {
        [0.05, 0.1, 0.02]
    } else {
        [0.08, 0.16, 0.032]
    }
}

/// [`recede`] on a `2 x 40` frame, the sky in rows 0-4 (of the right column, rows
/// `0..right_sky`), the scene in row 39, beyond the reach between, coloured by
/// `colour(x, y)` (the lawn where `None`); with the image as guide and without.
fn recede_with_and_without_the_image(
    right_sky: usize,
    colour: impl Fn(usize, usize) -> Option<[f32; 3]>,
) -> (Vec<f32>, Vec<f32>) {
    let (w, h) = (2, 40);
    let is_sky = |x: usize, y: usize| y < if x == 1 { right_sky } else { 5 };
    let (sky, work, beyond) = frame(w, h, is_sky);
    let image = RgbImage::from_fn(w, h, |x, y| match colour(x, y) {
        _ if is_sky(x, y) => [0.5, 0.6, 0.9],
        Some(c) => c,
        None => lawn(y),
    });
    guided_and_plain(work, (&sky, &beyond), (w, h), &image)
}

/// [`recede`] of `work` (`Rmax` 10, `Smax` 40) with `image` as guide, and without.
fn guided_and_plain(
    mut work: Vec<f32>,
    (sky, beyond): (&[bool], &[bool]),
    (w, h): (usize, usize),
    image: &RgbImage,
) -> (Vec<f32>, Vec<f32>) {
    let mut plain = work.clone();
    let guide = ColourGuide::new(image, 0.08);
    recede(&mut work, (sky, beyond), (w, h), (10.0, 40.0), Some(&guide));
    recede(&mut plain, (sky, beyond), (w, h), (10.0, 40.0), None);
    (work, plain)
}

/// Whether `work` is `plain` but in the right column's `rows`, which are `foot`.
fn moved_only(work: &[f32], plain: &[f32], rows: RangeInclusive<usize>, foot: f32) -> bool {
    let standing = |p: usize| p % 2 == 1 && rows.contains(&(p / 2));
    (0..work.len()).all(|p| work[p] == if standing(p) { foot } else { plain[p] })
}

/// Asserts that with the image the right column's `rows` stand at the range of their
/// lowest row, the frame of [`recede_with_and_without_the_image`] otherwise as
/// without it.
fn assert_stands(
    right_sky: usize,
    colour: impl Fn(usize, usize) -> Option<[f32; 3]>,
    rows: RangeInclusive<usize>,
) {
    let (work, plain) = recede_with_and_without_the_image(right_sky, colour);
    let foot = plain[2 * *rows.end() + 1];
    assert!(moved_only(&work, &plain, rows, foot), "{work:?}");
}

#[test]
fn a_box_beyond_the_reach_stands_at_its_foot() {
    // The right column: a slate box in rows 20-30 on the lawn, the lawn seen above it.
    let (work, plain) = recede_with_and_without_the_image(5, |x, y| {
        (x == 1 && (20..=30).contains(&y)).then_some([0.2, 0.25, 0.35])
    });
    assert!(
        plain[2 * 20 + 1] > plain[2 * 30 + 1],
        "without the image it recedes"
    );
    assert!(
        moved_only(&work, &plain, 20..=30, plain[2 * 30 + 1]),
        "{work:?}"
    );
}

#[test]
fn a_tower_over_the_horizon_stands_at_its_foot_and_hides_what_is_behind() {
    // The right column: a brown tower in rows 2-30 rising over the horizon (the sky
    // comes down to row 4 on the left); then one on a slate box (rows 20-30), which
    // neither rises over the horizon nor has the lawn above it: both recede.
    let brown = [0.3, 0.15, 0.05];
    assert_stands(
        2,
        |x, y| (x == 1 && (2..=30).contains(&y)).then_some(brown),
        2..=30,
    );
    let (work, plain) = recede_with_and_without_the_image(2, |x, y| match (x, y) {
        (1, 20..=30) => Some([0.2, 0.25, 0.35]),
        (1, 2..=19) => Some(brown),
        _ => None,
    });
    assert_eq!(work, plain);
}

#[test]
fn a_tower_stands_across_its_columns() {
    // 64 columns (a tower's range is carried 4 columns along its rows): the sky in rows
    // 0-1, the lawn below the horizon (row 4.5, where the sky comes down at column 63),
    // the scene at the reach in row 39. A brown tower in columns 20-29, rows 2-30,
    // rises over the horizon and stands at its foot; in columns 20-22 a slate box
    // (rows 24-33) hides its foot, so their walk stops at the box, but they are the
    // tower's, beside its held columns. A brown patch of the same material 10 columns
    // away (columns 40-41, rows 8-9, not upright) is not held from it, and a low brown
    // wall in row 12 leading away from the tower (columns 30-45) only for 4 columns.
    let (w, h) = (64, 40);
    let is_sky = |x: usize, y: usize| y < 2 || (x == 63 && y < 5);
    let brown = [0.3, 0.15, 0.05];
    let (sky, work, beyond) = frame(w, h, is_sky);
    let image = RgbImage::from_fn(w, h, |x, y| match (x, y) {
        _ if is_sky(x, y) => [0.5, 0.6, 0.9],
        (20..=22, 24..=33) => [0.2, 0.25, 0.35],
        (20..=29, 2..=30) | (40..=41, 8..=9) | (30..=45, 12) => brown,
        _ => lawn(y),
    });
    let (work, plain) = guided_and_plain(work, (&sky, &beyond), (w, h), &image);
    let at = |x: usize, y: usize| y * w + x;
    for y in 2..=23 {
        for x in 20..=22 {
            assert_eq!(work[at(x, y)], work[at(23, y)], "({x}, {y})");
        }
        assert!(work[at(20, y)] < plain[at(20, y)], "row {y} stands nearer");
    }
    assert_eq!(
        work[at(33, 12)],
        work[at(29, 12)],
        "the wall beside the tower"
    );
    for (x, y) in [(40, 8), (41, 9), (34, 12), (35, 20), (15, 10)] {
        assert_eq!(work[at(x, y)], plain[at(x, y)], "({x}, {y}) recedes");
    }
}

#[test]
fn a_box_stands_on_ground_whose_colour_drifts_with_distance() {
    // The lawn turns yellow as it recedes (0.003 of red's share per row, 0.06 over the
    // 20 rows up to the box): the ground below the reach no longer matches it there,
    // the ground just below the box does, and the ground above it.
    let drifted = |y: usize| {
        let [r, g, b] = lawn(y);
        let d = 0.0005 * (39 - y) as f32 * (r + g + b) / 0.17;
        [r + d, g - d, b]
    };
    let slate = [0.2, 0.25, 0.35];
    let box_ = |x: usize, y: usize| x == 1 && (12..=18).contains(&y);
    assert_stands(
        5,
        |x, y| Some(if box_(x, y) { slate } else { drifted(y) }),
        12..=18,
    );
}

#[test]
fn a_box_seen_from_above_stands_with_its_top_face() {
    // The right column: a red box's front in shade (rows 20-30) under its sunlit top
    // face (row 19, 3.7 times as bright), the lawn seen above it.
    let front = [0.2, 0.06, 0.05];
    let colour = |x, y| match (x, y) {
        (1, 19) => Some(front.map(|c| 3.7 * c)),
        (1, 20..=30) => Some(front),
        _ => None,
    };
    assert_stands(5, colour, 19..=30);
}

#[test]
fn a_grey_box_stands_on_its_shadowed_foot_with_its_sunlit_top() {
    // The right column: a grey box's front in the sky's bluish light (rows 20-30), its
    // foot's pixel (row 31) half lawn, half box and darker than either (its shadow), its
    // top face (row 19) in the sun, 3.7 times as bright and warmer by 0.05 in each
    // channel's share; the lawn above it.
    let front = [0.057, 0.067, 0.074];
    let lawn_below = lawn(31);
    let foot: [f32; 3] = std::array::from_fn(|c| 0.6 * 0.5 * (lawn_below[c] + front[c]));
    let colour = |x, y| match (x, y) {
        (1, 19) => Some([0.245, 0.245, 0.235]),
        (1, 20..=30) => Some(front),
        (1, 31) => Some(foot),
        _ => None,
    };
    assert_stands(5, colour, 19..=31);
}

#[test]
fn a_foot_by_the_horizon_is_too_far_to_tell() {
    // The horizon at row 4.5; a brown tower rising over it from a foot 2.5 rows below
    // recedes, from 3.5 rows below it stands.
    let brown = [0.3, 0.15, 0.05];
    let tower = |foot: usize| {
        move |x: usize, y: usize| (x == 1 && (2..=foot).contains(&y)).then_some(brown)
    };
    let (work, plain) = recede_with_and_without_the_image(2, tower(7));
    assert_eq!(work, plain);
    assert_stands(2, tower(8), 2..=8);
}

#[test]
fn water_up_to_the_far_shore_recedes() {
    // The right column: a far city in rows 5-7 above water (rows 8-20) on the lawn:
    // flat, below the horizon, no lawn above it.
    let (work, plain) = recede_with_and_without_the_image(5, |x, y| match (x, y) {
        (1, 5..=7) => Some([0.3, 0.3, 0.3]),
        (1, 8..=20) => Some([0.4, 0.5, 0.7]),
        _ => None,
    });
    assert_eq!(work, plain);
}
