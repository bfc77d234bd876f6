//! Local outliers, border bands and the ego vehicle on the synthetic street frame, against
//! its true range ([`super::synthetic::StreetScene::truth`]).

use super::synthetic::{street_scene, StreetScene};
use super::*;

const W: usize = 512;
const H: usize = 256;

fn run(s: &StreetScene, opts: &PrepOptions) -> Prepared {
    let guides = Guides {
        image: Some(&s.image),
        ..Guides::default()
    };
    prepare_guided(&s.range, guides, opts).unwrap()
}

/// Mean and largest absolute error against the truth over `pixels`, and how many of them
/// are off by more than a factor 1.5 or called sky.
fn error(s: &StreetScene, p: &Prepared, pixels: &[usize]) -> (f64, f64, usize) {
    let (mut sum, mut max, mut bad) = (0.0f64, 0.0f64, 0usize);
    for &i in pixels {
        let (t, v) = (s.truth.as_slice()[i], p.range.as_slice()[i]);
        let e = f64::from((v - t).abs());
        sum += e;
        max = max.max(e);
        bad += usize::from(p.sky.as_slice()[i] || v > 1.5 * t || v < t / 1.5);
    }
    (sum / pixels.len() as f64, max, bad)
}

fn opts_with(f: impl FnOnce(&mut PrepOptions)) -> PrepOptions {
    let mut o = PrepOptions::default();
    f(&mut o);
    o
}

/// Known pixels that changed, other than the sky's, `except` and the sky noise.
fn changed(s: &StreetScene, p: &Prepared, except: &[usize]) -> Vec<usize> {
    (0..W * H)
        .filter(|&i| {
            let v = s.range.as_slice()[i];
            v.is_finite()
                && !p.sky.as_slice()[i]
                && !except.contains(&i)
                && v.to_bits() != p.range.as_slice()[i].to_bits()
        })
        .collect()
}

#[test]
fn stereo_mismatches_are_refilled_from_their_surface() {
    let mut s = street_scene(W, H, 7);
    // Far above their surroundings but below the far-outlier cut (2 x P99, 181 m here):
    // on a Cityscapes frame, whose P99 is some hundreds of metres, 200-550 m are.
    let planted = s.plant_mismatches(12, 60.0..170.0, 3);
    let off = run(&s, &opts_with(|o| o.local_outlier_factor = 0.0));
    let on = run(&s, &PrepOptions::default());
    let (e_off, m_off, bad_off) = error(&s, &off, &planted);
    let (e_on, m_on, bad_on) = error(&s, &on, &planted);
    let extra = changed(&s, &on, &planted);
    eprintln!(
        "{} mismatch px: mean abs error {e_off:.1} m (max {m_off:.0}, {bad_off} off by 1.5x) \
         without the rule, {e_on:.2} m (max {m_on:.1}, {bad_on}) with it; {} px removed, \
         {} other known px changed (sky noise {}); {:.1} ms vs {:.1} ms",
        planted.len(),
        on.stats.local_outliers,
        extra.len(),
        on.stats.sky_noise,
        on.stats.fill_ms,
        off.stats.fill_ms,
    );
    assert!(planted.len() > 100, "{}", planted.len());
    assert!(e_on * 50.0 < e_off, "{e_on} vs {e_off}");
    assert_eq!(bad_on, 0);
    assert!(planted.iter().all(|&i| on.filled.as_slice()[i]));
    // Everything else known is kept bit for bit, but the sky noise and a few pixels round
    // the blotches (at most a fifth of them).
    assert!(
        extra.len() <= on.stats.sky_noise + planted.len() / 5,
        "{} other pixels changed",
        extra.len()
    );
    assert_eq!(off.stats.local_outliers, 0);
    // The clean frame loses (almost) nothing.
    let clean = street_scene(W, H, 7);
    let p = run(&clean, &PrepOptions::default());
    eprintln!("clean frame: {} local outliers", p.stats.local_outliers);
    assert!(p.stats.local_outliers * 2000 < W * H, "{:?}", p.stats);
}

/// Pixels of the left band whose truth is the scene (not the sky, not the wire).
fn band_scene(s: &StreetScene) -> Vec<usize> {
    (0..W * H)
        .filter(|&i| i % W < s.band_width && s.truth.as_slice()[i].is_finite())
        .collect()
}

#[test]
fn the_left_band_continues_its_surfaces() {
    let s = street_scene(W, H, 7);
    let band = band_scene(&s);
    let off = run(&s, &opts_with(|o| o.border_band_fraction = 0.0));
    let on = run(&s, &PrepOptions::default());
    let (e_off, m_off, bad_off) = error(&s, &off, &band);
    let (e_on, m_on, bad_on) = error(&s, &on, &band);
    eprintln!(
        "left band, {} scene px: mean abs error {e_off:.2} m (max {m_off:.1} m, {bad_off} off \
         by 1.5x or sky) as holes, {e_on:.2} m (max {m_on:.1} m, {bad_on}) continued; {:?}",
        band.len(),
        on.stats
    );
    assert!(e_on * 3.0 < e_off, "{e_on} vs {e_off}");
    assert!(bad_on * 100 < band.len(), "{bad_on} of {}", band.len());
    // Known pixels: as without the border fill.
    assert!(changed(&s, &on, &[]).len() <= on.stats.sky_noise + on.stats.far_outliers);
}

#[test]
fn rectification_rows_above_the_sky_are_sky() {
    const ROWS: usize = 6;
    let mut s = street_scene(W, H, 7);
    s.blank_top_rows(ROWS);
    let top: Vec<usize> = (0..ROWS * W).collect();
    let under_sky = |i: usize| s.sky.as_slice()[ROWS * W + i % W];
    let score = |p: &Prepared| {
        let sky_ok = top
            .iter()
            .filter(|&&i| under_sky(i) && p.sky.as_slice()[i])
            .count();
        let scene: Vec<usize> = top
            .iter()
            .copied()
            .filter(|&i| !under_sky(i) && s.truth.as_slice()[i].is_finite())
            .collect();
        (sky_ok, error(&s, p, &scene))
    };
    let above_sky = top.iter().filter(|&&i| under_sky(i)).count();
    let off = run(&s, &opts_with(|o| o.border_band_fraction = 0.0));
    let on = run(&s, &PrepOptions::default());
    let (sky_off, e_off) = score(&off);
    let (sky_on, e_on) = score(&on);
    eprintln!(
        "top {ROWS} rows: {sky_off} / {above_sky} px above the sky are sky as holes, \
         {sky_on} continued; above the scene: {e_off:?} vs {e_on:?} (mean, max, bad)"
    );
    assert!(sky_on * 100 >= above_sky * 99, "{sky_on} of {above_sky}");
    assert!(e_on.0 <= e_off.0 && e_on.2 <= e_off.2);
}

#[test]
#[ignore]
fn dump_band_rows() {
    let s = street_scene(W, H, 7);
    let on = run(&s, &PrepOptions::default());
    let off = run(&s, &opts_with(|o| o.border_band_fraction = 0.0));
    let b = s.band_width;
    for y in 0..H {
        let i = y * W;
        let t = |x: usize| s.truth.as_slice()[i + x];
        let r = |x: usize| s.range.as_slice()[i + x];
        eprintln!(
            "y {y:3}: truth {:7.2} {:7.2} {:7.2} | raw {:7.2} {:7.2} | on {:7.2} {:7.2} sky {} | off {:7.2} {:7.2} sky {}",
            t(0), t(b / 2), t(b), r(b), r(b + 8),
            on.range.as_slice()[i], on.range.as_slice()[i + b - 1], on.sky.as_slice()[i] as u8,
            off.range.as_slice()[i], off.range.as_slice()[i + b - 1], off.sky.as_slice()[i] as u8,
        );
    }
}

/// The hood of the ego vehicle: an ellipse's top along the bottom of the frame, where the
/// matcher gives garbage and the hood reflects the sky.
#[test]
fn the_ego_vehicle_gets_range_zero_and_touches_nothing_else() {
    let mut s = street_scene(W, H, 7);
    let hood = Grid::from_fn(W, H, |x, y| {
        let (dx, dy) = (
            (x as f64 - W as f64 / 2.0) / (0.6 * W as f64),
            (H - y) as f64,
        );
        dy < 0.12 * H as f64 * (1.0 - dx * dx)
    });
    let sky_colour = *s.image.get(W / 2, 2);
    let mut rng = crate::rng::SplitMix64::new(5);
    for i in (0..W * H).filter(|&i| hood.as_slice()[i]) {
        s.image.as_mut_slice()[i] = sky_colour;
        s.range.as_mut_slice()[i] = if rng.unit() < 0.5 {
            f32::NAN
        } else {
            rng.range(0.5, 3000.0) as f32
        };
    }
    let guides = |ego| Guides {
        image: Some(&s.image),
        sky_mask: None,
        ego_mask: ego,
    };
    let opts = PrepOptions::default();
    let with = prepare_guided(&s.range, guides(Some(&hood)), &opts).unwrap();
    let without = prepare_guided(&s.range, guides(None), &opts).unwrap();
    let n = hood.as_slice().iter().filter(|&&e| e).count();
    assert_eq!(with.stats.ego_pixels, n, "{:?}", with.stats);
    for i in 0..W * H {
        if hood.as_slice()[i] {
            assert_eq!(with.range.as_slice()[i], 0.0);
            assert!(!with.sky.as_slice()[i] && !with.filled.as_slice()[i]);
        }
    }
    let (found, false_pos) = {
        let t = s.sky.as_slice();
        let f = with.sky.as_slice();
        let tp = (0..W * H).filter(|&i| t[i] && f[i]).count();
        let fp = (0..W * H).filter(|&i| !t[i] && f[i]).count();
        let sky = t.iter().filter(|&&v| v).count();
        (tp as f64 / sky as f64, fp as f64 / (W * H - sky) as f64)
    };
    assert!(found > 0.95 && false_pos < 0.02, "{found} {false_pos}");
    // The garbage on the hood neither sets the scale nor fills the holes round it.
    assert!(with.stats.r_max <= 1.01 * s.scene_max, "{:?}", with.stats);
    assert!(without.stats.ego_pixels == 0);
    let except: Vec<usize> = (0..W * H).filter(|&i| hood.as_slice()[i]).collect();
    let extra = changed(&s, &with, &except);
    assert!(
        extra.len() <= with.stats.sky_noise + with.stats.far_outliers + with.stats.local_outliers,
        "{} {:?}",
        extra.len(),
        with.stats
    );
}

/// A time-of-flight sensor that stops at 20 m: the street beyond it is unknown and joined
/// to the sky. The depth rules alone take it for sky (fogged as the sky: a wall of fog at
/// the sensor's reach); the image shows it is not, and it recedes from Rmax into the sky.
#[test]
fn the_street_beyond_the_sensors_reach_is_not_sky() {
    const REACH: f32 = 20.0;
    let s = street_scene(W, H, 7);
    let range = s.truth.map(|&t| if t <= REACH { t } else { f32::NAN });
    let beyond: Vec<usize> = (0..W * H)
        .filter(|&i| s.truth.as_slice()[i] > REACH)
        .collect();
    assert!(
        beyond.len() > W * H / 20,
        "{} px beyond the reach",
        beyond.len()
    );
    let opts = PrepOptions::default();
    let alone = prepare_guided(&range, Guides::default(), &opts).unwrap();
    let with = prepare_guided(
        &range,
        Guides {
            image: Some(&s.image),
            ..Guides::default()
        },
        &opts,
    )
    .unwrap();
    let called_sky = |p: &Prepared| beyond.iter().filter(|&&i| p.sky.as_slice()[i]).count();
    assert!(
        called_sky(&alone) > beyond.len() * 9 / 10,
        "{:?}",
        alone.stats
    );
    assert!(
        called_sky(&with) < beyond.len() / 20,
        "{} of {}: {:?}",
        called_sky(&with),
        beyond.len(),
        with.stats
    );
    assert!(with.stats.beyond_reach > 0, "{:?}", with.stats);
    let (r_max, s_max) = (with.stats.r_max, with.stats.s_max.unwrap());
    for &i in beyond.iter().filter(|&&i| !with.sky.as_slice()[i]) {
        let v = with.range.as_slice()[i];
        assert!(
            v >= 0.999 * r_max && v <= 1.001 * s_max,
            "pixel {i}: {v} outside [{r_max}, {s_max}]"
        );
    }
    // The true sky is still found.
    let sky = s.sky.as_slice();
    let found = (0..W * H)
        .filter(|&i| sky[i] && with.sky.as_slice()[i])
        .count();
    let total = sky.iter().filter(|&&v| v).count();
    assert!(found as f64 > 0.97 * total as f64, "{found} of {total}");
}

/// Prepares a phone's depth of `image`'s frame with `image` as guide: range known from row
/// `known_from` down, 8 m there to 2 m at the bottom row; unknown above (beyond the reach,
/// and the sky).
fn prepare_short_reach(image: &crate::raster::RgbImage, known_from: usize) -> Prepared {
    let (w, h) = (image.width(), image.height());
    let range = ScalarMap::from_fn(w, h, |_, y| match y {
        y if y < known_from => f32::NAN,
        y => 8.0 - 6.0 * (y - known_from) as f32 / (h - known_from - 1) as f32,
    });
    let guides = Guides {
        image: Some(image),
        ..Guides::default()
    };
    prepare_guided(&range, guides, &PrepOptions::default()).unwrap()
}

/// A sunset under a phone's short reach: the blue sky turns orange toward the horizon, in
/// steps too small to see, above a band of green ground the sensor did not reach. The
/// orange is not blue or grey, yet it is sky (reached from the blue, smooth and bright);
/// the ground below it is not.
#[test]
fn a_sunsets_orange_sky_stays_sky() {
    let (w, h) = (64, 96);
    let (blue, orange) = ([0.35f32, 0.5, 0.9], [1.0f32, 0.6, 0.3]);
    let (glow_from, glow_to, ground_from, known_from) = (10, 50, 56, 64);
    let image = crate::raster::RgbImage::from_fn(w, h, |x, y| match y {
        y if y < glow_from => blue,
        y if y < glow_to => {
            let t = (y - glow_from) as f32 / (glow_to - glow_from) as f32;
            [0, 1, 2].map(|c| blue[c] + t * (orange[c] - blue[c]))
        }
        y if y < ground_from => orange,
        _ => [0.1 + 0.03 * ((x + y) % 5) as f32, 0.3, 0.1],
    });
    let p = prepare_short_reach(&image, known_from);
    let sky = |y: usize| (0..w).all(|x| *p.sky.get(x, y));
    assert!((0..ground_from).all(sky), "{:?}", p.stats);
    let beyond = |y: usize| (0..w).all(|x| *p.beyond_reach.get(x, y));
    assert!((ground_from..known_from).all(beyond), "{:?}", p.stats);
}

/// Water beyond a phone's reach reflects the sky: sky-coloured, joined to the depth rules'
/// sky, and reached from the sky through a pale far building that stands in it, across
/// the water's lighter ripples. Under the far city it is not open to the sky above it, so
/// it is the scene beyond the reach (which recedes to the horizon), not sky; taken for
/// sky, it put the horizon at the near shore and fogged all the ground below it as sky.
/// Nor is it under a second pale building, taken for sky (it glows), whose colour steps
/// to the water's; nor is a smooth light grey face in the water, too small to grow a
/// region of its own, which looks like sky.
#[test]
fn water_under_the_far_city_is_not_sky() {
    let (w, h) = (64, 96);
    let (city_from, water_from, ground_from, known_from) = (30, 40, 56, 64);
    let building = |x: usize, y: usize| (28..36).contains(&x) && (city_from..48).contains(&y);
    let image = crate::raster::RgbImage::from_fn(w, h, |x, y| match y {
        _ if building(x, y) => [0.72, 0.78, 0.9],
        y if (8..14).contains(&x) && (city_from..water_from).contains(&y) => [0.74, 0.82, 0.97],
        y if (48..54).contains(&x) && (44..52).contains(&y) => [0.75, 0.75, 0.75],
        y if y < city_from => [0.7, 0.78, 0.92],
        y if y < water_from => [0.2, 0.15, 0.12],
        y if y < ground_from && y % 2 == 0 => [0.68, 0.75, 0.88],
        y if y < ground_from => [0.6, 0.67, 0.8],
        _ => [0.1 + 0.03 * ((x + y) % 5) as f32, 0.3, 0.1],
    });
    let p = prepare_short_reach(&image, known_from);
    let water =
        |x: usize, y: usize| !(27..37).contains(&x) && (water_from..ground_from).contains(&y);
    let water_sky = (0..w * h)
        .filter(|&i| water(i % w, i / w) && p.sky.as_slice()[i])
        .count();
    assert_eq!(water_sky, 0, "{:?}", p.stats);
    assert!(
        (0..city_from).all(|y| (0..w).all(|x| *p.sky.get(x, y))),
        "{:?}",
        p.stats
    );
}

/// A box's face just at a phone's reach (8 m, where its depth stops at 8.19 m), measured
/// in scattered pixels and lost in the others by the noise, is a surface the sensor
/// reached: filled from its own measured pixels, not the scene beyond the reach, which
/// would recede between them and show as blotches. A ground pixel measured above a lost
/// one (the noise crossing the limit at the reach's contour) leaves the ground beyond.
#[test]
fn a_face_at_the_reach_limit_is_filled_from_what_was_reached() {
    let (w, h) = (64, 96);
    let (ground_from, known_from) = (40, 70);
    let face = |x: usize, y: usize| (20..44).contains(&x) && (30..60).contains(&y);
    let image = crate::raster::RgbImage::from_fn(w, h, |x, y| match y {
        _ if face(x, y) => [0.2, 0.25, 0.35],
        y if y < ground_from => [0.35, 0.5, 0.9],
        _ => [0.1 + 0.03 * ((x + y) % 5) as f32, 0.3, 0.1],
    });
    let measured = |x: usize, y: usize| {
        (face(x, y) && x.is_multiple_of(3) && y.is_multiple_of(4))
            || (x, y) == (5, 50)
            || y >= known_from
    };
    let range = ScalarMap::from_fn(w, h, |x, y| match y {
        _ if !measured(x, y) => f32::NAN,
        y if y >= known_from => 8.0 - 6.0 * (y - known_from) as f32 / (h - known_from - 1) as f32,
        _ => 8.0,
    });
    let guides = Guides {
        image: Some(&image),
        ..Guides::default()
    };
    let p = prepare_guided(&range, guides, &PrepOptions::default()).unwrap();
    for (x, y) in (0..w).flat_map(|x| (30..known_from).map(move |y| (x, y))) {
        let (r, beyond) = (*p.range.get(x, y), *p.beyond_reach.get(x, y));
        if face(x, y) {
            assert!(!beyond && (r - 8.0).abs() < 0.05, "face ({x}, {y}): {r}");
        } else if y >= ground_from && !measured(x, y) {
            assert!(beyond && r > 8.0, "ground ({x}, {y}): {r} {:?}", p.stats);
        }
    }
}
