//! Outdoor synthetic scene: sky, holes, horizon margin, airlight, reproducibility.

use crate::common;

use brume::prep::edt::squared_edt;
use brume::prep::{
    estimate_airlight, prepare, prepare_guided, synthetic::outdoor_scene, visualize,
    AirlightSource, Guides, PrepOptions, Prepared, SkyMethod,
};
use brume::raster::{Grid, RgbImage, ScalarMap};
use common::*;

const W: usize = 400;
const H: usize = 280;

/// Paper 000's pre-processing alone (sec. 4.1): the local-outlier rule and the border
/// bands of issue 19 off, so that every known value is kept and every unknown one is sky
/// or a hole.
fn paper_options() -> PrepOptions {
    PrepOptions {
        local_outlier_factor: 0.0,
        border_band_fraction: 0.0,
        ..PrepOptions::default()
    }
}

fn scene() -> (ScalarMap, Prepared) {
    let map = outdoor_scene(W, H, 3);
    let p = prepare(&map, &paper_options()).unwrap();
    (map, p)
}

/// With the default rules, the known values that change are exactly the local outliers
/// the rule counts (4 here), each of them refilled; the border bands fill only unknown
/// pixels.
#[test]
fn default_rules_change_only_the_local_outliers() {
    let map = outdoor_scene(W, H, 3);
    let p = prepare(&map, &PrepOptions::default()).unwrap();
    let changed: Vec<usize> = map
        .as_slice()
        .iter()
        .zip(p.range.as_slice())
        .enumerate()
        .filter(|(_, (b, a))| b.is_finite() && b.to_bits() != a.to_bits())
        .map(|(i, _)| i)
        .collect();
    assert_eq!(changed.len(), p.stats.local_outliers, "{:?}", p.stats);
    assert!(
        changed.len() < map.len() / 10_000,
        "{} changed",
        changed.len()
    );
    let marks: Vec<(bool, bool)> = changed
        .iter()
        .map(|&i| (p.filled.as_slice()[i], p.sky.as_slice()[i]))
        .collect();
    assert!(marks.iter().all(|(f, s)| *f || *s), "{marks:?}");
    let unknown = map.as_slice().iter().filter(|v| v.is_nan()).count();
    assert_eq!(
        p.stats.sky_pixels + p.stats.hole_pixels + p.stats.border_filled,
        unknown + p.stats.local_outliers,
        "{:?}",
        p.stats
    );
}

#[test]
fn sky_found_holes_filled_known_unchanged() {
    let (map, p) = scene();
    let s = &p.stats;
    if let Ok(dir) = std::env::var("PREP_VIS_DIR") {
        let (w, h, px) = visualize(&map, &p);
        save_png(&format!("{dir}/outdoor.png"), w, h, &px);
    }
    assert_eq!(s.sky_components, 1, "{s:?}");
    assert!((0..W).all(|x| *p.sky.get(x, 0)), "the whole top row is sky");
    assert!(s.holes > 100 && s.hole_pixels > W * H / 25, "{s:?}");
    assert_all_finite(&p.range);
    assert_known_unchanged(&map, &p.range);
    assert_eq!(s.s_max, Some(1.5 * s.r_max));
    let max_known = map
        .as_slice()
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(f32::MIN, f32::max);
    assert_eq!(s.r_max, max_known);
    for i in 0..map.len() {
        let unknown = map.as_slice()[i].is_nan();
        let (sky, filled) = (p.sky.as_slice()[i], p.filled.as_slice()[i]);
        assert_eq!(unknown, sky || filled, "pixel {i}");
        assert!(!(sky && filled), "pixel {i}");
    }
    assert_eq!(
        s.sky_pixels + s.hole_pixels,
        map.as_slice().iter().filter(|v| v.is_nan()).count()
    );
}

/// The margin is exactly the sky within µ of the scene (checked with a full-image EDT);
/// the sky beyond it is exactly Smax; margin values lie strictly between the scene and Smax.
#[test]
fn margin_is_exact_and_sky_beyond_is_smax() {
    let (_, p) = scene();
    let s_max = p.stats.s_max.unwrap();
    let mu2 = 8.0f64 * 8.0;
    let d2 = squared_edt(&p.sky.map(|s| !s));
    let mut margin = 0;
    for i in 0..p.range.len() {
        if !p.sky.as_slice()[i] {
            continue;
        }
        let v = p.range.as_slice()[i];
        if d2.as_slice()[i] as f64 <= mu2 {
            margin += 1;
            assert!(v < s_max, "margin pixel {i} = {v} not relaxed");
        } else {
            assert_eq!(
                v.to_bits(),
                s_max.to_bits(),
                "sky pixel {i} beyond the margin"
            );
        }
    }
    assert_eq!(margin, p.stats.margin_pixels);
    assert!(
        margin >= W * 8,
        "a margin at least µ deep along the horizon: {margin}"
    );
}

/// No hard transition at the interface. For every scene pixel `a` 4-adjacent to a sky
/// pixel `b`, let `q = (S(b) - R(a)) / (Smax - R(a))` (q = 1 would be the hard step of a
/// sky without margin).
/// - Rigorous: after one Jacobi sweep, `S(b)` is the mean of four values of which one is
///   `R(a)` and none exceeds `Smax` (maximum principle), so `q <= 3/4`.
/// - Straight horizon: after `n = 2µ` sweeps from `Smax`, `q` is the probability that a
///   lazy random walk (step probability 1/2) from `b` has not reached the scene, about
///   `sqrt(2 / (pi n / 2)) = sqrt(2 / (pi µ))`, 0.28 for µ = 8. The median over the
///   ragged horizon must not exceed it (convex foliage tips exceed it, concave bays are
///   below).
///
/// In absolute terms, where the horizon is the far tree line (`R(a)` close to `Rmax`), a
/// typical jump is about `sqrt(2 / (pi µ)) (Smax - Rmax)` instead of `Smax - Rmax`.
#[test]
fn margin_has_no_hard_transition() {
    let (_, p) = scene();
    let s_max = p.stats.s_max.unwrap();
    let mu = 8.0f32;
    let (r, sky) = (p.range.as_slice(), p.sky.as_slice());
    let mut q = Vec::new();
    for y in 0..H {
        for x in 0..W {
            let b = y * W + x;
            if !sky[b] {
                continue;
            }
            let nb = [
                (x > 0).then(|| b - 1),
                (x + 1 < W).then(|| b + 1),
                (y > 0).then(|| b - W),
                (y + 1 < H).then(|| b + W),
            ];
            for a in nb.into_iter().flatten().filter(|&a| !sky[a]) {
                q.push((r[b] - r[a]) / (s_max - r[a]));
            }
        }
    }
    q.sort_by(f32::total_cmp);
    let (median, max) = (q[q.len() / 2], q[q.len() - 1]);
    let straight = (2.0 / (std::f32::consts::PI * mu)).sqrt();
    assert!(max <= 0.75 + 1e-5, "max interface jump ratio {max}");
    assert!(
        median <= straight,
        "median interface jump ratio {median} > {straight}"
    );
    assert!(q.len() > W, "interface pairs: {}", q.len());
}

#[test]
fn same_seed_same_output() {
    let map = outdoor_scene(W, H, 11);
    let opts = PrepOptions {
        seed: 42,
        ..Default::default()
    };
    let a = prepare(&map, &opts).unwrap();
    let b = prepare(&map, &opts).unwrap();
    let bits = |p: &Prepared| {
        p.range
            .as_slice()
            .iter()
            .map(|v| v.to_bits())
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&a), bits(&b));
    assert_eq!(a.sky, b.sky);
    assert_eq!(a.filled, b.filled);
    assert_eq!(outdoor_scene(W, H, 11).as_slice().len(), map.len());
    let again = outdoor_scene(W, H, 11);
    assert!(again
        .as_slice()
        .iter()
        .zip(map.as_slice())
        .all(|(x, y)| x.to_bits() == y.to_bits()));
}

/// A colour image for the scene: blue-grey sky with a few bright "sun" pixels, brownish
/// scene getting lighter with range.
fn colours(map: &ScalarMap, p: &Prepared) -> RgbImage {
    const SKY: [f32; 3] = [0.55, 0.62, 0.75];
    Grid::from_fn(W, H, |x, y| {
        let i = y * W + x;
        if p.sky.as_slice()[i] {
            if (x * 7 + y * 13) % 50 == 0 {
                [20.0, 20.0, 18.0]
            } else {
                let n = ((x * 31 + y * 17) % 11) as f32 / 10.0 - 0.5;
                [SKY[0] + 0.02 * n, SKY[1] + 0.02 * n, SKY[2] - 0.02 * n]
            }
        } else {
            let t = (map.as_slice()[i].max(1.0) / 320.0).min(1.0);
            [0.2 + 0.3 * t, 0.15 + 0.3 * t, 0.1 + 0.3 * t]
        }
    })
}

#[test]
fn airlight_from_sky_is_the_sky_colour() {
    let (map, p) = scene();
    let a = estimate_airlight(&colours(&map, &p), &p);
    assert_eq!(a.source, AirlightSource::Sky);
    assert_eq!(a.pixels, p.stats.sky_pixels);
    for (c, want) in a.rgb.iter().zip([0.55, 0.62, 0.75]) {
        assert!((c - want).abs() < 0.012, "{:?}", a.rgb);
    }
}

/// With its colour image, the sky the range rules found stays sky (the image-guided
/// detector only adds), and what it adds are the isolated "leaf" values above the tree
/// line that the sky encloses (their colour is the scene's, but their range is not backed
/// up by any neighbour): nothing of the scene below the horizon.
#[test]
fn the_image_keeps_the_sky_the_range_found() {
    let (map, p) = scene();
    let image = colours(&map, &p);
    let guides = Guides {
        image: Some(&image),
        sky_mask: None,
        ego_mask: None,
    };
    let g = prepare_guided(&map, guides, &PrepOptions::default()).unwrap();
    assert_eq!(g.stats.sky_method, SkyMethod::DepthAndImage);
    let (depth_sky, sky) = (p.sky.as_slice(), g.sky.as_slice());
    assert!(
        (0..W * H).all(|i| !depth_sky[i] || sky[i]),
        "depth sky kept"
    );
    let added: Vec<usize> = (0..W * H).filter(|&i| sky[i] && !depth_sky[i]).collect();
    assert!(added.len() < W * H / 200, "{} added", added.len());
    for &i in &added {
        assert!(map.as_slice()[i].is_finite(), "pixel {i} was a hole");
        let (x, y) = (i % W, i / W);
        let near_sky = (y.saturating_sub(1)..=(y + 1).min(H - 1))
            .flat_map(|v| (x.saturating_sub(1)..=(x + 1).min(W - 1)).map(move |u| v * W + u))
            .any(|j| depth_sky[j]);
        assert!(near_sky, "added pixel ({x}, {y}) away from the sky");
    }
    let a = estimate_airlight(&image, &g);
    for (c, want) in a.rgb.iter().zip([0.55, 0.62, 0.75]) {
        assert!((c - want).abs() < 0.012, "{:?}", a.rgb);
    }
}

/// The outdoor scene with sky detection off: every unknown pixel is a filled hole.
fn scene_without_sky() -> (ScalarMap, Prepared) {
    let map = outdoor_scene(W, H, 3);
    let p = prepare(
        &map,
        &PrepOptions {
            detect_sky: false,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(p.stats.sky_pixels, 0);
    assert_eq!(p.stats.s_max, None);
    (map, p)
}

/// Rec. 709 luminance of linear RGB, summed in the estimator's order.
fn luminance(c: [f32; 3]) -> f32 {
    c.iter()
        .zip([0.2126f32, 0.7152, 0.0722])
        .map(|(v, w)| v * w)
        .sum()
}

#[test]
fn airlight_without_sky_is_neutral_at_the_bright_end() {
    const RED_WALL: [f32; 3] = [0.078, 0.014, 0.005];
    const BROWN: [f32; 3] = [0.6, 0.5, 0.3];
    let (map, p) = scene_without_sky();
    let mut far: Vec<f32> = map
        .as_slice()
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .collect();
    far.sort_by(f32::total_cmp);
    let far_from = far[far.len() * 95 / 100];
    // Known pixels: the farthest 5 % a dark red wall, the rest brown, under 1 % lamp
    // highlights (which must not set the brightness) and some NaN colours (skipped).
    // Filled pixels are brighter than everything: they must not count either.
    let (mut nan, mut known) = (0, 0);
    let image = Grid::from_fn(W, H, |x, y| {
        let i = y * W + x;
        if p.filled.as_slice()[i] {
            return [50.0, 50.0, 50.0];
        }
        known += 1;
        if i.is_multiple_of(97) {
            nan += 1;
            [f32::NAN, 0.5, 0.5]
        } else if i % 211 == 5 {
            [20.0, 20.0, 18.0]
        } else if map.as_slice()[i] >= far_from {
            RED_WALL
        } else {
            BROWN
        }
    });
    let a = estimate_airlight(&image, &p);
    assert_eq!(a.source, AirlightSource::Neutral);
    assert_eq!(a.pixels, known - nan);
    assert!(a.rgb[0] == a.rgb[1] && a.rgb[1] == a.rgb[2], "{:?}", a.rgb);
    assert!((a.rgb[0] - luminance(BROWN)).abs() < 1e-6, "{:?}", a.rgb);
}

#[test]
fn neutral_airlight_of_black_overexposed_and_nan_images() {
    let (_, p) = scene_without_sky();
    let flat = |c: [f32; 3]| estimate_airlight(&Grid::from_fn(W, H, |_, _| c), &p);
    assert_eq!(flat([0.0; 3]).rgb, [0.0; 3], "black: haze only absorbs");
    assert_eq!(flat([1.0; 3]).rgb, [1.0; 3], "overexposed: white");
    assert_eq!(flat([-0.2, -0.1, 0.0]).rgb, [0.0; 3], "never negative");
    let none = flat([f32::NAN, 0.0, 0.0]);
    assert_eq!((none.rgb, none.pixels), ([0.0; 3], 0), "no finite colour");
}

#[test]
fn visualize_stacks_before_and_after() {
    let (map, p) = scene();
    let (w, h, px) = visualize(&map, &p);
    assert_eq!((w, h, px.len()), (W, 2 * H, W * 2 * H));
    assert_eq!(px[0], [255, 0, 0], "unknown is red before");
    assert_eq!(px[W * H], [255, 255, 255], "sky is white after");
    let bottom = &px[W * (2 * H - 1)..];
    assert!(
        bottom
            .iter()
            .all(|c| c[0] == c[1] && c[1] == c[2] && c[0] < 128),
        "near is dark"
    );
}

/// An ego-vehicle mask that covers every known pixel (a wrong file: a depth map given as
/// the mask) leaves no range outside the sky; the error counts the sky, the ego vehicle
/// and the unknown pixels, so that the mask shows as the cause.
#[test]
fn no_range_left_says_how_much_the_ego_mask_took() {
    let (map, _) = scene();
    let known = Grid::from_fn(W, H, |x, y| map.get(x, y).is_finite());
    let guides = Guides {
        image: None,
        sky_mask: None,
        ego_mask: Some(&known),
    };
    let e = prepare_guided(&map, guides, &paper_options())
        .unwrap_err()
        .to_string();
    let ego = known.as_slice().iter().filter(|&&k| k).count();
    let said = format!("{ego} the ego vehicle (its mask)");
    assert!(
        e.contains("no valid range value outside the sky") && e.contains(&said),
        "{e}"
    );
    assert!(
        e.contains(&format!("of the {} pixels ({W}x{H})", W * H)),
        "{e}"
    );
}
