use super::*;
use crate::io::srgb::linear_to_srgb8;
use crate::rng::SplitMix64;

fn grey(v: f32) -> [f32; 3] {
    [v; 3]
}

const DARK: f32 = 0.02;
const LIGHT: f32 = 0.5;

/// A dark pole (x in 20..30, 10 m) before a light wall (30 m), 48 x 24, whose range
/// reaches `fat` px into the wall on its left and `fat_right` on its right.
fn pole(fat: usize, fat_right: usize) -> (RgbImage, ScalarMap) {
    let on_pole = |x: usize| (20..30).contains(&x);
    let image = Grid::from_fn(48, 24, |x, _| grey(if on_pole(x) { DARK } else { LIGHT }));
    let range = Grid::from_fn(48, 24, |x, _| {
        if (20 - fat..30 + fat_right).contains(&x) {
            10.0
        } else {
            30.0
        }
    });
    (image, range)
}

#[test]
fn a_fattened_pole_keeps_its_range_on_its_colour_alone() {
    let (image, range) = pole(4, 4);
    let (out, changed) = median_at_depth_edges(&image, &range, None).expect("sizes agree");
    for y in 0..24 {
        for x in 0..48 {
            let expected = if (20..30).contains(&x) { 10.0 } else { 30.0 };
            assert_eq!(*out.get(x, y), expected, "({x}, {y})");
        }
    }
    assert_eq!(changed, 2 * 4 * 24);
}

#[test]
fn repair_moves_the_edges_and_the_other_modes_do_not() {
    use crate::refine::{refine_range, CpuFilter, RefineMode, RefineOptions};
    let (image, range) = pole(4, 4);
    let refine = |mode| {
        let opts = RefineOptions {
            mode,
            ..RefineOptions::default()
        };
        refine_range(&image, &range, None, &opts, &mut CpuFilter).expect("refined")
    };
    // A fattened pixel 3 px left of the pole: the wall's 30 m after `repair`, the pole's
    // 10 m as measured, a mix of both by the guided filter.
    let at = |map: &ScalarMap| *map.get(17, 12);
    assert_eq!(at(&refine(RefineMode::Repair)), 30.0);
    assert_eq!(at(&refine(RefineMode::None)), 10.0);
    let guided = at(&refine(RefineMode::Guided));
    assert!(guided > 10.5 && guided < 29.5, "{guided}");
}

#[test]
fn a_pole_of_the_walls_colour_is_left_as_measured_where_its_votes_win() {
    // Without a colour edge every vote weighs the same, and the plain median of a 21 px
    // window would take the wall's range for the whole of a 10 px pole: no colour
    // evidence, no move.
    let (_, range) = pole(0, 0);
    let image = Grid::filled(48, 24, grey(LIGHT));
    let (out, _) = median_at_depth_edges(&image, &range, None).expect("sizes agree");
    assert_eq!(out.as_slice(), range.as_slice());
}

#[test]
fn a_range_without_depth_edges_is_kept_to_the_bit() {
    // A textured image over a ground receding 2 % a row, with 3 % noise: no pixel has a
    // range 1.4x its own within reach.
    let mut rng = SplitMix64::new(7);
    let mut random = move || rng.unit() as f32;
    let image = Grid::from_fn(40, 30, |_, _| [random(), random(), random()]);
    let range = Grid::from_fn(40, 30, |_, y| {
        5.0 * 1.02f32.powi(y as i32) * (1.0 + 0.03 * (random() - 0.5))
    });
    let (out, changed) = median_at_depth_edges(&image, &range, None).expect("sizes agree");
    assert_eq!(changed, 0);
    assert_eq!(out.as_slice(), range.as_slice());
}

#[test]
fn kept_out_pixels_neither_vote_nor_change() {
    // Right of the pole the sky (3 km, the wall's colour, kept out) and the ego vehicle's
    // range 0 on the last rows: the pole's range reaching 4 px into the sky has no
    // farther range to be judged against, and the sky does not outvote it.
    let (image, mut range) = pole(4, 4);
    let mut sky = Grid::filled(48, 24, false);
    for y in 0..24 {
        for x in 34..48 {
            *range.get_mut(x, y) = 3000.0;
            *sky.get_mut(x, y) = true;
        }
    }
    for y in 20..24 {
        for x in 0..48 {
            *range.get_mut(x, y) = 0.0;
        }
    }
    let (out, _) = median_at_depth_edges(&image, &range, Some(&sky)).expect("sizes agree");
    for y in 0..24 {
        for x in 30..48 {
            assert_eq!(out.get(x, y), range.get(x, y), "({x}, {y})");
        }
        for x in 0..20 {
            let expected = if y >= 20 { 0.0 } else { 30.0 };
            assert_eq!(*out.get(x, y), expected, "({x}, {y})");
        }
    }
    // A mask or an image of another size is refused, naming it.
    let small = Grid::filled(47, 24, false);
    let err = median_at_depth_edges(&image, &range, Some(&small)).unwrap_err();
    assert!(err.to_string().contains("kept-out mask"), "{err}");
    let err = median_at_depth_edges(&Grid::filled(48, 23, grey(0.5)), &range, None).unwrap_err();
    assert!(err.to_string().contains("image"), "{err}");
    // Without the mask the sky outvotes the fattened pixels' 10 m.
    let (unmasked, _) = median_at_depth_edges(&image, &range, None).expect("sizes agree");
    assert_eq!(*unmasked.get(31, 5), 3000.0);
}

/// The step written out plainly, in f64: every pixel's whole square within the reach
/// for the edge test, every vote of the window with its weight, the median by sorting,
/// the surfaces' colour likeness by their votes. `None` where a comparison is a tie within
/// 1e-5 (f32 may tip it).
fn plain(image: &RgbImage, range: &ScalarMap, x: usize, y: usize) -> Option<f64> {
    let (w, h) = (range.width() as i64, range.height() as i64);
    let code = |x: i64, y: i64| image.get(x as usize, y as usize).map(linear_to_srgb8);
    let r0 = f64::from(*range.get(x, y));
    let (x, y) = (x as i64, y as i64);
    let reach = EDGE_REACH_PX as i64;
    let mut farthest = r0;
    for qy in (y - reach).max(0)..=(y + reach).min(h - 1) {
        for qx in (x - reach).max(0)..=(x + reach).min(w - 1) {
            farthest = farthest.max(f64::from(*range.get(qx as usize, qy as usize)));
        }
    }
    if farthest < f64::from(EDGE_STEP) * r0 {
        return Some(r0);
    }
    let sigma = f64::from(EDGE_SIGMA_COLOUR) * 255.0;
    let mut votes = Vec::new();
    for dy in (-10..=10).step_by(2) {
        for dx in (-10..=10).step_by(2) {
            let (qx, qy) = (x + dx, y + dy);
            if qx < 0 || qy < 0 || qx >= w || qy >= h {
                continue;
            }
            let (a, b) = (code(x, y), code(qx, qy));
            let d2: f64 = (0..3)
                .map(|k| (f64::from(a[k]) - f64::from(b[k])).powi(2))
                .sum();
            let r = f64::from(*range.get(qx as usize, qy as usize));
            votes.push((r, (-d2 / (2.0 * sigma * sigma)).exp()));
        }
    }
    votes.sort_by(|a, b| a.0.total_cmp(&b.0));
    let half = 0.5 * votes.iter().map(|v| v.1).sum::<f64>();
    let mut sum = 0.0;
    let mut median = None;
    for &(r, weight) in &votes {
        sum += weight;
        if (sum - half).abs() < 1e-5 * half {
            return None;
        }
        if sum >= half {
            median = Some(r);
            break;
        }
    }
    let median = median.expect("the weights add up to their sum");
    let same = 0.5 * f64::from(EDGE_STEP).ln();
    let off = (median / r0).ln().abs();
    if (off - same).abs() < 1e-5 {
        return None;
    }
    if off < same {
        return Some(r0);
    }
    let likeness = |centre: f64| {
        let like: Vec<f64> = (votes.iter())
            .filter(|v| (v.0 / centre).ln().abs() < same)
            .map(|v| v.1)
            .collect();
        if like.is_empty() {
            0.0
        } else {
            like.iter().sum::<f64>() / like.len() as f64
        }
    };
    let (win, own) = (
        likeness(median),
        likeness(r0) * f64::from(EDGE_COLOUR_EVIDENCE),
    );
    if (win - own).abs() < 1e-5 * win.max(own) {
        None
    } else if win > own {
        Some(median)
    } else {
        Some(r0)
    }
}

#[test]
fn the_step_is_the_plain_weighted_median_at_depth_edges() {
    // Blobs of four colours and three ranges, with colour noise, none of them kept out.
    let mut rng = SplitMix64::new(11);
    let mut random = move || rng.unit() as f32;
    let (w, h) = (37, 29);
    let label = |x: usize, y: usize| ((x / 7 + y / 5) % 4) as f32;
    let image = Grid::from_fn(w, h, |x, y| grey(0.1 + 0.2 * label(x, y) + 0.05 * random()));
    // The range's blobs are shifted 2 px right of the colour's: a fattened edge each.
    let range = Grid::from_fn(w, h, |x, y| {
        [4.0, 9.0, 20.0, 9.0][label(x.saturating_sub(2), y) as usize] * (1.0 + 0.01 * random())
    });
    let (out, changed) = median_at_depth_edges(&image, &range, None).expect("sizes agree");
    let mut compared = 0;
    for y in 0..h {
        for x in 0..w {
            if let Some(expected) = plain(&image, &range, x, y) {
                assert_eq!(f64::from(*out.get(x, y)), expected, "({x}, {y})");
                compared += 1;
            }
        }
    }
    assert!(
        compared > w * h * 99 / 100,
        "{compared} of {} compared",
        w * h
    );
    assert!(changed > 50, "{changed} changed");
}

#[test]
fn the_running_maximum_is_the_maximum_over_the_square() {
    let (w, h) = (23, 17);
    let values: Vec<f32> = (0..w * h)
        .map(|i| {
            if i % 7 == 3 {
                f32::NAN
            } else {
                ((i * 37) % 101) as f32
            }
        })
        .collect();
    for r in [0, 1, 3, 10, 30] {
        let got = square_max(&values, (w, h), r);
        for y in 0..h {
            for x in 0..w {
                let mut expected = f32::NEG_INFINITY;
                for qy in y.saturating_sub(r)..=(y + r).min(h - 1) {
                    for qx in x.saturating_sub(r)..=(x + r).min(w - 1) {
                        let v = values[qy * w + qx];
                        if !v.is_nan() {
                            expected = expected.max(v);
                        }
                    }
                }
                assert_eq!(got[y * w + x], expected, "r {r} ({x}, {y})");
            }
        }
    }
}
