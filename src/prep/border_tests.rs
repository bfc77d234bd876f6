//! Unit tests of `prep::border`: the bands' continuation, islands and slopes on small
//! lines and images.

use super::*;

#[test]
fn a_left_band_continues_a_plane_and_top_rows_above_sky_are_sky() {
    let (w, h) = (40, 20);
    // A facade whose disparity is affine in x and y, the top 4 rows sky in columns
    // 20.., a band of 6 unknown columns on the left, 2 unknown rows at the top.
    let truth = |x: usize, y: usize| 1.0 / (0.02 + 0.001 * x as f32 + 0.0005 * y as f32);
    let mut work = vec![0.0f32; w * h];
    let mut sky = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            if x < 6 || y < 2 {
                work[i] = f32::NAN;
            } else if y < 6 && x >= 20 {
                sky[i] = true;
                work[i] = f32::INFINITY;
            } else {
                work[i] = truth(x, y);
            }
        }
    }
    let known = work.clone();
    let mut filled = vec![false; w * h];
    let done = fill_borders(
        &mut work,
        &mut sky,
        &mut filled,
        (w, h),
        0.2,
        (0.0, 1e9),
        None,
    );
    assert_eq!(done.sky, 2 * 20, "{done:?}");
    assert_eq!(done.filled, 6 * (h - 2) + 2 * 20, "{done:?}");
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            if known[i].is_finite() {
                assert_eq!(work[i].to_bits(), known[i].to_bits());
            } else if !sky[i] {
                let e = (work[i] - truth(x, y)).abs() / truth(x, y);
                assert!(e < 1e-4, "({x}, {y}): {} vs {}", work[i], truth(x, y));
            }
        }
    }
    assert!((20..w).all(|x| sky[x] && sky[w + x]));
}

/// A road by a stereo pair's left band, measured with a matcher's noise (3 % in
/// disparity): each row's few first pixels (6, then a gap: the road striped with the
/// matcher's gaps) or its noisy run of 32 show no slope, and the band takes their
/// median, within the noise of the row's true range; followed, their slopes made
/// each row a stripe of its own, up to 1.5 times off.
#[test]
fn a_band_by_noisy_pixels_takes_their_median_not_their_slope() {
    let (w, h, band) = (200, 40, 90);
    let truth = |y: usize| 1.0 / (0.1 + 0.002 * y as f32);
    for striped in [true, false] {
        let mut rng = crate::rng::SplitMix64::new(7);
        let mut range = vec![f32::NAN; w * h];
        for y in 0..h {
            for x in band..w {
                if striped && (band + 6..band + 9).contains(&x) {
                    continue;
                }
                let noise = 1.0 + 0.03 * (2.0 * rng.unit() as f32 - 1.0);
                range[y * w + x] = truth(y) / noise;
            }
        }
        let (work, done) = fill_line(&range, (w, h));
        assert_eq!(done.filled, band * h, "{done:?}");
        for y in 0..h {
            for x in 0..band {
                let e = work[y * w + x] / truth(y) - 1.0;
                assert!(e.abs() < 0.035, "striped {striped}, ({x}, {y}): {e}");
            }
        }
    }
}

/// A bottom band below a road measured with a matcher's noise (3 % in disparity) and a
/// pole standing on it: each column's continuation, taken from its own few pixels, made
/// the band a streak per column (Cityscapes' Düsseldorf frame); the median of the
/// columns round it on the same surface leaves it smooth, and the pole, nearer than the
/// road beside it, keeps its own range.
#[test]
fn a_bottom_band_is_smooth_across_a_noisy_road_and_keeps_a_pole() {
    let (w, h, band) = (120, 40, 8);
    let road = |y: usize| 1.0 / (0.05 + 0.002 * y as f32);
    let pole = |x: usize| (50..54).contains(&x);
    let mut rng = crate::rng::SplitMix64::new(11);
    let mut range = vec![f32::NAN; w * h];
    for y in 0..h - band {
        for x in 0..w {
            let noise = 1.0 + 0.03 * (2.0 * rng.unit() as f32 - 1.0);
            range[y * w + x] = if pole(x) { 3.0 } else { road(y) } / noise;
        }
    }
    let mut work = range.clone();
    let (mut sky, mut filled) = (vec![false; w * h], vec![false; w * h]);
    let done = fill_borders(
        &mut work,
        &mut sky,
        &mut filled,
        (w, h),
        0.25,
        (1.0, 1e4),
        None,
    );
    assert_eq!(done.filled, band * w, "{done:?}");
    let mut steps = Vec::new();
    for y in h - band..h {
        for x in 0..w {
            let r = work[y * w + x];
            if pole(x) {
                assert!((r / 3.0 - 1.0).abs() < 0.03, "pole ({x}, {y}): {r}");
            } else {
                let last = road(h - band - 1);
                assert!(r < 1.1 * last && r > 0.8 * last, "road ({x}, {y}): {r}");
            }
            if x > 0 && pole(x) == pole(x - 1) {
                steps.push((work[y * w + x - 1] / r - 1.0).abs());
            }
        }
    }
    let mean = steps.iter().sum::<f32>() / steps.len() as f32;
    assert!(mean < 0.004, "mean step between columns {mean}");
}

/// One row: `cells` from the left border ('.' unknown, a digit d: range 10·d m, 'F' a
/// speck 500 m away, 'p' a pole 3 m away), then a facade 10 m away to the end of the row.
fn row(cells: &str, width: usize) -> Vec<f32> {
    let mut line: Vec<f32> = cells
        .chars()
        .map(|c| match c {
            '.' => f32::NAN,
            'F' => 500.0,
            'p' => 3.0,
            d => 10.0 * d.to_digit(10).expect("a digit") as f32,
        })
        .collect();
    line.resize(width, 10.0);
    line
}

/// `line` filled as one image line (a row: its left band; a column: top then bottom)
/// or as an image of that size, no sky, bands up to half the line.
fn fill_line(line: &[f32], size: (usize, usize)) -> (Vec<f32>, BorderFill) {
    fill_line_seen(line, size, None)
}

/// [`fill_line`] with the line's `image`, when given.
fn fill_line_seen(
    line: &[f32],
    (w, h): (usize, usize),
    image: Option<&crate::raster::RgbImage>,
) -> (Vec<f32>, BorderFill) {
    let guide = image.map(|i| ColourGuide::new(i, 0.08));
    let mut work = line.to_vec();
    let mut sky = vec![false; line.len()];
    let mut filled = vec![false; line.len()];
    let done = fill_borders(
        &mut work,
        &mut sky,
        &mut filled,
        (w, h),
        0.5,
        (1.0, 1e4),
        guide.as_ref(),
    );
    (work, done)
}

/// A speck longer than its distance to the border is taken for a piece of a surface
/// reaching the border, unless the image shows the surface beyond it there: of the
/// facade's chromaticity, a quarter brighter (its shading), it is a speck on the facade
/// (Cityscapes' Düsseldorf glass facade) and dropped, also where it is near enough to
/// the facade to be joined to it; of another colour (far ground), three times as
/// bright, or without the image it is kept; touching the border (no band before it),
/// kept.
#[test]
fn a_speck_the_image_shows_on_the_surface_beyond_is_dropped() {
    let facade = [0.10f32, 0.15, 0.10];
    let seen = |cells: &str, speck: [f32; 3]| {
        let line = row(cells, 160);
        let image =
            crate::raster::Grid::from_fn(
                160,
                1,
                |x, _| {
                    if line[x] == 500.0 {
                        speck
                    } else {
                        facade
                    }
                },
            );
        fill_line_seen(&line, (160, 1), Some(&image))
    };
    let near_border = format!("....{}{}", "F".repeat(10), ".".repeat(20));
    let shaded = facade.map(|c| 1.25 * c);
    let (work, done) = seen(&near_border, shaded);
    assert_eq!(done.islands, 10, "{done:?}");
    assert!(work.iter().all(|&r| (r - 10.0).abs() < 1e-4), "{work:?}");
    let ground = [0.12, 0.10, 0.05];
    assert_eq!(seen(&near_border, ground).1.islands, 0);
    let lit = facade.map(|c| 3.0 * c); // its chromaticity, but no shading of it
    assert_eq!(seen(&near_border, lit).1.islands, 0);
    assert_eq!(fill_line(&row(&near_border, 160), (160, 1)).1.islands, 0);
    let at_border = format!("{}{}", "F".repeat(10), ".".repeat(20));
    assert_eq!(seen(&at_border, shaded).1.islands, 0);
    // 8 px from the facade, a gap the island would be joined across (and the facade
    // then taken for its surface): specks on the facade are not joined to it.
    let by_facade = format!("......{}........", "F".repeat(10));
    let (work, done) = seen(&by_facade, shaded);
    assert_eq!(done.islands, 10, "{done:?}");
    assert!(work.iter().all(|&r| (r - 10.0).abs() < 1e-4), "{work:?}");
    assert_eq!(seen(&by_facade, ground).1.islands, 0);
    // Nearer specks after them are no surface for them to lie on (not wide): joined,
    // all are dropped (a Hamburg frame's road; taken for one, they ended the band).
    let specks = format!("{}{}", "4".repeat(20), ".".repeat(30));
    let by_specks = format!("......{}........{specks}", "F".repeat(10));
    let (work, done) = seen(&by_specks, shaded);
    assert_eq!(done.islands, 30, "{done:?}");
    assert!(work.iter().all(|&r| (r - 10.0).abs() < 1e-4), "{work:?}");
}

/// Cityscapes' left band: specks of far disparity among the unknown columns, which the
/// band used to continue (a white blotch by a road 6 m away), are dropped; the band
/// continues the facade beyond them.
#[test]
fn far_specks_in_a_band_are_dropped_and_the_band_continues_its_surface() {
    let line = row("........FF.....F....FFF....................", 100);
    let (work, done) = fill_line(&line, (100, 1));
    assert_eq!(done.islands, 6, "{done:?}");
    assert!(work.iter().all(|&r| (r - 10.0).abs() < 1e-4), "{work:?}");
    // Groups of specks far apart: what lies beyond the first is judged where the
    // facade shows, past the second.
    let apart = format!("........FF{}FF{}", ".".repeat(20), ".".repeat(20));
    let (work, done) = fill_line(&row(&apart, 120), (120, 1));
    assert_eq!(done.islands, 4, "{done:?}");
    assert!(work.iter().all(|&r| (r - 10.0).abs() < 1e-4), "{work:?}");
    // A road striped with the matcher's gaps (half of it known, gaps of 4 px) is a
    // surface all the same (Düsseldorf's road by the left band).
    let striped = format!(
        "............FFFFFF{}{}",
        ".".repeat(20),
        "1111....".repeat(12)
    );
    let (work, done) = fill_line(&row(&striped, 140), (140, 1));
    assert_eq!(done.islands, 6, "{done:?}");
    assert!(
        work[..12].iter().all(|&r| (r - 10.0).abs() < 1e-4),
        "{work:?}"
    );
    // Two pixels of the facade's range 28 px before it do not begin it (Hamburg's van
    // window): the specks before them are judged against the facade, and dropped.
    let piece = format!("........FF{}11{}", ".".repeat(16), ".".repeat(28));
    let (work, done) = fill_line(&row(&piece, 160), (160, 1));
    assert_eq!(done.islands, 2, "{done:?}");
    assert!(
        work[..28].iter().all(|&r| (r - 10.0).abs() < 1e-4),
        "{work:?}"
    );
}

/// What is not a speck stays as it was, and ends the band: a strip less than
/// [`ISLAND_RATIO`] times as far as what is beyond it (a far facade before a car), a
/// piece at or near the border, a pole nearer than the facade, far ground beside a
/// post (brume's synthetic SGBM view 2), a speck hard against a post.
#[test]
fn surfaces_in_a_band_are_kept() {
    let dots = |n: usize| ".".repeat(n);
    // Far ground beside a post: what the band meets is no wide surface.
    let beside_post = format!("{}FF{}{}{}", dots(12), dots(20), "p".repeat(20), dots(30));
    // A speck hard against a post is one island with it, the post's.
    let with_post = format!("........FF......pppppppp{}", dots(10));
    // Each 20 px from the facade (a gap under 16 px would join it to the facade).
    let strip = format!("......22222{}", dots(20));
    let at_border = format!("FF{}", dots(20));
    let near_border = format!(".FFFF{}", dots(20));
    let pole = format!("......pp{}", dots(20));
    for cells in [
        &strip,
        &at_border,
        &near_border,
        &pole,
        &beside_post,
        &with_post,
    ] {
        let line = row(cells, 100);
        let (work, done) = fill_line(&line, (100, 1));
        assert_eq!(done.islands, 0, "{cells}: {done:?}");
        for (k, (a, b)) in line.iter().zip(&work).enumerate() {
            assert!(
                a.is_nan() || a.to_bits() == b.to_bits(),
                "{cells}: step {k}"
            );
        }
    }
    // A sparse map (a lidar's: one known pixel in 8) has too little beyond a speck to
    // judge it.
    let mut sparse: Vec<f32> = (0..80)
        .map(|k| if k % 8 == 0 { 10.0 } else { f32::NAN })
        .collect();
    sparse[0] = f32::NAN;
    sparse[4] = 500.0;
    let (_, done) = fill_line(&sparse, (80, 1));
    assert_eq!(done.islands, 0, "{done:?}");
}

/// A hood at the bottom reflecting the street: rows of 1.3 times the road's range among
/// its unknown rows are dropped (along the bottom the ground comes nearer), and the
/// band below the road continues it, never farther.
#[test]
fn a_hoods_reflection_in_the_bottom_band_is_dropped() {
    let h = 80;
    // Top to bottom: 50 rows of road receding upward, then the hood: unknown rows with
    // 3 rows of reflection 1.3 times as far as the road's last row, 18 rows below it.
    let road = |y: usize| 1.0 / (0.05 + 0.0005 * y as f32);
    let mut column: Vec<f32> = (0..h)
        .map(|y| if y < 50 { road(y) } else { f32::NAN })
        .collect();
    column[68..71].fill(1.3 * road(49));
    let (work, done) = fill_line(&column, (1, h));
    assert_eq!(done.islands, 3, "{done:?}");
    for (y, &r) in work.iter().enumerate().skip(50) {
        assert!(r <= road(49) * 1.0001, "row {y}: {r} vs {}", road(49));
        assert!(
            (r - road(y)).abs() / road(y) < 1e-3,
            "row {y}: the road's plane"
        );
    }
    // The same reflection in a side band is a surface of its own (under 3 times).
    let line: Vec<f32> = column.iter().rev().copied().collect();
    let (_, done) = fill_line(&line, (h, 1));
    assert_eq!(done.islands, 0, "{done:?}");
}

/// Toward the bottom border a slope that recedes (a hood reflecting the street, whose
/// disparity falls toward the border) is not followed: the first half's median holds.
#[test]
fn the_bottom_band_never_continues_farther() {
    // Steps 8..24 from the border, disparity rising away from it.
    let s: Vec<(usize, f32)> = (8..24)
        .map(|k| (k, 1.0 / (0.05 + 0.001 * k as f32)))
        .collect();
    let free = LineFit::of(&s, false);
    let held = LineFit::of(&s, true);
    assert!(free.range_at(0) > s[0].1, "{} {}", free.range_at(0), s[0].1);
    let first_half = 1.0 / (0.05 + 0.001 * 11.5);
    assert!(
        (held.range_at(0) - first_half).abs() < 1e-3,
        "{} {first_half}",
        held.range_at(0)
    );
    // A slope toward nearer is followed alike.
    let rising: Vec<(usize, f32)> = s.iter().map(|&(k, r)| (32 - k, r)).rev().collect();
    assert_eq!(
        LineFit::of(&rising, true).range_at(0),
        LineFit::of(&rising, false).range_at(0)
    );
}

/// Each of the three conditions on following a slope, alone: a clean slope of 16
/// samples is followed; of 6, not (too few); with a 2 % scatter about it, not; a slope
/// of 0.24 % between the halves within a 0.3 % scatter, not (no more than its noise),
/// of 2 %, followed.
#[test]
fn a_slope_is_followed_only_where_the_samples_show_it() {
    // Steps 10.., disparity 0.1 (1 + slope (k - 10)), times 1 ± noise alternately.
    let line = |n: usize, slope: f32, noise: f32| -> Vec<(usize, f32)> {
        (10..10 + n)
            .map(|k| {
                let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                let d = 0.1 * (1.0 + slope * (k - 10) as f32) * (1.0 + sign * noise);
                (k, 1.0 / d)
            })
            .collect()
    };
    let followed = |s: &[(usize, f32)]| {
        let f = LineFit::of(s, false);
        f.range_at(0) != f.range_at(100)
    };
    assert!(followed(&line(16, 0.02, 0.0)));
    assert!(!followed(&line(6, 0.02, 0.0)));
    assert!(!followed(&line(16, 0.02, 0.02)));
    assert!(!followed(&line(16, 0.0003, 0.003)));
    assert!(followed(&line(16, 0.0025, 0.003)));
}

#[test]
fn a_depth_edge_in_the_samples_gives_a_constant() {
    let mut s: Vec<(usize, f32)> = (5..13).map(|k| (k, 10.0)).collect();
    s.extend((13..21).map(|k| (k, 40.0)));
    let f = LineFit::of(&s, false);
    assert_eq!(f.range_at(0), 10.0);
    assert_eq!(LineFit::of(&[(3, 7.0)], false).range_at(0), 7.0);
    assert_eq!(LineFit::of(&[(3, 0.0), (4, 1.0)], false).range_at(0), 0.0);
}

/// A slope that one line's pixels show and its neighbours' (of one surface) do not is not
/// followed: the line takes the median of theirs; where every line shows it (a facade),
/// every line follows it; a surface's lines are not outvoted by another surface's next to
/// them (a sloped facade over a road).
#[test]
fn a_slope_one_line_alone_shows_is_not_followed() {
    let (w, h, band) = (100, 17, 40);
    // Rows of one disparity each (a road's: 0.1 + 0.001 y), or of a facade 5 times as far;
    // the sloped rows' disparity rises 0.1 % a pixel.
    let image = |facade: &dyn Fn(usize) -> bool, sloped: &dyn Fn(usize) -> bool| {
        let mut range = vec![f32::NAN; w * h];
        for y in 0..h {
            let d = if facade(y) {
                0.02
            } else {
                0.1 + 0.001 * y as f32
            };
            for x in band..w {
                let rise = if sloped(y) {
                    0.001 * (x - band) as f32
                } else {
                    0.0
                };
                range[y * w + x] = 1.0 / (d * (1.0 + rise));
            }
        }
        fill_line(&range, (w, h)).0
    };
    let flat = |work: &[f32], y: usize| work[y * w] == work[y * w + band - 1];
    let one = image(&|_| false, &|y| y == 8);
    assert!((0..h).all(|y| flat(&one, y)));
    let every = image(&|_| false, &|_| true);
    assert!((0..h).all(|y| !flat(&every, y)));
    let over_road = image(&|y| y < 10, &|y| y < 10);
    assert!((0..h).all(|y| flat(&over_road, y) == (y >= 10)));
}

/// An image of `rows` (each as [`row`], `w` wide), its left band filled; returns the
/// range and what was done.
fn fill_rows(rows: &[String], w: usize) -> (Vec<f32>, BorderFill) {
    let line: Vec<f32> = rows.iter().flat_map(|r| row(r, w)).collect();
    fill_line(&line, (w, rows.len()))
}

/// A far speck under [`ISLAND_RATIO`] times the facade beyond it, on one row of the left
/// band or on a few, has no counterpart on the rows beside it: the band continues the
/// facade there as on those rows (Cityscapes' Aachen and Hamburg frames). A strip of
/// that range on most of the rows round it, or 8 px long, is a surface and is kept, and
/// so is a nearer speck (a pole's edge).
#[test]
fn a_lone_speck_in_a_band_is_dropped_and_a_strip_is_kept() {
    let w = 60;
    let band = ".".repeat(14);
    let speck = format!("{}22{}", ".".repeat(8), ".".repeat(4));
    let rows = |strip: std::ops::Range<usize>, cells: &str| -> Vec<String> {
        (0..17)
            .map(|y| {
                if strip.contains(&y) {
                    cells.to_string()
                } else {
                    band.clone()
                }
            })
            .collect()
    };
    for lone in [8..9, 7..10] {
        let (work, done) = fill_rows(&rows(lone.clone(), &speck), w);
        assert_eq!(done.islands, 2 * lone.len(), "{lone:?}: {done:?}");
        assert!(work.iter().all(|&r| (r - 10.0).abs() < 1e-4), "{lone:?}");
    }
    let long = format!("{}22222222{}", ".".repeat(4), ".".repeat(2));
    let near = format!("{}pp{}", ".".repeat(8), ".".repeat(4));
    let kept = [
        (4..14, &speck, 20.0),
        (8..9, &long, 20.0),
        (8..9, &near, 3.0),
    ];
    for (strip, cells, range) in kept {
        let (work, done) = fill_rows(&rows(strip.clone(), cells), w);
        assert_eq!(done.islands, 0, "{strip:?}: {done:?}");
        for y in strip {
            assert!(work[y * w..y * w + 8]
                .iter()
                .all(|&r| (r - range).abs() < 1e-4));
        }
    }
}
