//! Unit tests of `prep::fill`: RANSAC's planes and constants, stereo occlusions and
//! holes by colour, on small maps.

use super::*;
use crate::prep::ground::Ground;
use crate::raster::RgbImage;

#[test]
fn solve3_identity() {
    let x = solve3(
        [[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 4.0]],
        [1.0, 2.0, 4.0],
    )
    .unwrap();
    assert_eq!(x, [1.0, 1.0, 1.0]);
    assert!(solve3(
        [[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        [1.0, 1.0, 1.0]
    )
    .is_none());
}

#[test]
fn constant_hole_in_constant_map() {
    let (w, h) = (5, 5);
    let mut m = vec![3.0f32; w * h];
    m[12] = f32::INFINITY;
    let mut f = HoleFiller::new(100.0, Occlusions::default());
    f.fill(&mut m, w, h, &[12], 8, &mut SplitMix64::new(1))
        .unwrap();
    assert_eq!(m[12], 3.0);
}

/// Row 0: a wall (20 m, 21 m at its end), a run of 4 unknown pixels taken as a stereo
/// occlusion, its occluder (5 m); row 1: unknown pixels of no occlusion.
fn wall_pole_and_run() -> (Vec<f32>, Occlusions, Fit) {
    let n = f32::NAN;
    let work = vec![
        20.0, 21.0, n, n, n, n, 5.0, 5.0, //
        20.0, n, n, n, n, n, 5.0, 5.0,
    ];
    let occlusions = Occlusions {
        occluded: (0..16).map(|p| (2..6).contains(&p)).collect(),
        occluders: (0..16).map(|p| p == 6 || p == 7).collect(),
        background_right: false,
        count: 4,
    };
    // A plane sloped across the run, as one fitted to a whole hole along a pole.
    let sloped = Fit {
        model: Model::Plane {
            a: 20.0,
            b: -3.0,
            c: 0.0,
        },
        origin: (1.0, 0.0),
        lo: 0.0,
        hi: 100.0,
    };
    (work, occlusions, sloped)
}

#[test]
fn an_occlusion_continues_its_rows_background_not_a_plane_across_it() {
    let (mut work, occlusions, sloped) = wall_pole_and_run();
    let run = [2u32, 3, 4, 5];
    let other = [9u32, 10, 11, 12, 13];
    let mut filler = HoleFiller::new(100.0, occlusions);
    filler.begin_hole(&run);
    filler.apply_beside_occlusions(&sloped, &mut work, 8, &[&run[..], &other[..]].concat());
    assert_eq!(&work[2..6], &[21.0; 4]);
    for p in other {
        let expected = sloped.at(f64::from(p % 8), 1.0) as f32;
        assert_eq!(work[p as usize], expected, "pixel {p}");
    }
    // The same pixels in a hole holding no occlusion take the plane.
    let (mut work, occlusions, sloped) = wall_pole_and_run();
    let mut filler = HoleFiller::new(100.0, occlusions);
    filler.begin_hole(&other);
    filler.apply_beside_occlusions(&sloped, &mut work, 8, &run);
    assert_eq!(work[2], sloped.at(2.0, 0.0) as f32);
    assert_eq!(work[5], 8.0);
}

/// A right view's occlusion, the row mirrored: its background is right of the run.
#[test]
fn a_right_views_occlusion_continues_the_background_right_of_it() {
    let (mut work, mut occlusions, sloped) = wall_pole_and_run();
    work[..8].reverse();
    occlusions.occluded[..8].reverse();
    occlusions.occluders[..8].reverse();
    occlusions.background_right = true;
    let run = [2u32, 3, 4, 5];
    let mut filler = HoleFiller::new(100.0, occlusions);
    filler.begin_hole(&run);
    filler.apply_beside_occlusions(&sloped, &mut work, 8, &run);
    assert_eq!(&work[2..6], &[21.0; 4]);
}

/// The range of the ground 1.5 m below a level pinhole camera (focal 500 px, principal
/// point at the centre of a 64 x 48 frame whose horizon is row -10, above it): depth
/// Z = f H / (y - y_h), range Z sqrt(1 + ((x - cx)² + (y - cy)²) / f²).
fn ground(x: usize, y: usize) -> f64 {
    let (f, height, horizon) = (500.0, 1.5, -10.0);
    let (dx, dy) = (x as f64 - 31.5, y as f64 - 23.5);
    let z = f * height / (y as f64 - horizon);
    z * (1.0 + (dx * dx + dy * dy) / (f * f)).sqrt()
}

// A hole in the ground was filled with a plane in range, a ramp that puts its middle
// rows much farther than the ground they show (range grows as 1 / (y - y_h) toward the
// horizon, not linearly). A plane of the scene is affine in inverse depth, and nearly
// so in inverse range: that plane fills it.
#[test]
fn a_hole_in_the_ground_is_filled_with_the_ground() {
    let (w, h) = (64, 48);
    let mut work: Vec<f32> = (0..w * h).map(|p| ground(p % w, p / w) as f32).collect();
    let inside = |x: usize, y: usize| (8..56).contains(&x) && (4..44).contains(&y);
    let hole: Vec<u32> = (0..w * h)
        .filter(|&p| inside(p % w, p / w))
        .map(|p| p as u32)
        .collect();
    hole.iter().for_each(|&p| work[p as usize] = f32::INFINITY);
    HoleFiller::new(100.0, Occlusions::default())
        .fill(&mut work, w, h, &hole, 32, &mut SplitMix64::new(5))
        .unwrap();
    let worst = hole.iter().fold(0.0f64, |m, &p| {
        let (x, y) = (p as usize % w, p as usize / w);
        m.max((f64::from(work[p as usize]) / ground(x, y) - 1.0).abs())
    });
    assert!(worst < 0.01, "worst relative error {worst}");
    // The ramp a plane in range would be: rows 4 and 43 at the centre, linear between.
    let (top, bottom) = (ground(32, 3), ground(32, 44));
    let ramp = top + (bottom - top) * (23.5 - 3.0) / 41.0;
    assert!(
        ramp / ground(32, 23) - 1.0 > 0.4,
        "{ramp} {}",
        ground(32, 23)
    );
}

/// A wide camera (focal 40 px on 64 x 48) 1.5 m over a level road, pitched 10° down, the
/// principal point at the centre: the road's range at pixel `(x, y)`, by similar triangles
/// in the camera's tilted frame (depth t along the axis drops t (v cos p + sin p)).
fn road(x: usize, y: usize) -> f64 {
    let (f, height, pitch) = (40.0, 1.5, 10f64.to_radians());
    let (u, v) = ((x as f64 - 31.5) / f, (y as f64 - 23.5) / f);
    let t = height / (v * pitch.cos() + pitch.sin());
    t * (1.0 + u * u + v * v).sqrt()
}

// Off the principal point of a wide lens the road is not affine in inverse range: a hole
// in a bottom corner, beside a pole 3 m away, took a plane of the scene 4 % off the road
// (measured: the assertion below without the road). With the camera's mount known, the
// road itself is a candidate, and fills the hole to float rounding.
#[test]
fn a_hole_on_the_road_beside_a_pole_is_filled_with_the_road() {
    let (w, h) = (64, 48);
    let pole = |x: usize| (4..7).contains(&x);
    let inside = |x: usize, y: usize| (7..30).contains(&x) && (30..46).contains(&y);
    let start: Vec<f32> = (0..w * h)
        .map(|p| match (p % w, p / w) {
            (x, y) if inside(x, y) => f32::INFINITY,
            (x, y) if pole(x) && y >= 20 => 3.0,
            (x, y) => road(x, y) as f32,
        })
        .collect();
    let hole: Vec<u32> = (0..w * h)
        .filter(|&p| !start[p].is_finite())
        .map(|p| p as u32)
        .collect();
    let ground = Ground {
        mount: crate::io::camera::Mount {
            height_m: 1.5,
            pitch: 10f64.to_radians(),
            roll: 0.0,
        },
        intrinsics: crate::io::camera::Intrinsics::centred(40.0, w, h),
    };
    let worst = |road_known: bool| {
        let mut work = start.clone();
        HoleFiller::new(100.0, Occlusions::default())
            .with_road(road_known.then(|| Road::of(&ground)))
            .fill(&mut work, w, h, &hole, 32, &mut SplitMix64::new(5))
            .unwrap();
        hole.iter().fold(0.0f64, |m, &p| {
            let (x, y) = (p as usize % w, p as usize / w);
            m.max((f64::from(work[p as usize]) / road(x, y) - 1.0).abs())
        })
    };
    let (with, without) = (worst(true), worst(false));
    assert!(with < 1e-5, "worst relative error {with} with the road");
    assert!(without > 0.02, "worst relative error {without} without it");
}

// The ground's unknown far part below the sky (+inf, not a boundary value) continues
// the ground past the boundary's farthest value, up to the filler's far limit.
#[test]
fn the_ground_below_the_sky_recedes_up_to_the_far_limit() {
    let (w, h) = (64, 48);
    // Sky above row 4, a hole from there down to row 20 (left half) or 24 (right half):
    // the step gives the boundary a second row, so planes can be fitted.
    let bottom = |x: usize| if x < 32 { 20 } else { 24 };
    let start: Vec<f32> = (0..w * h)
        .map(|p| match (p % w, p / w) {
            (_, y) if y < 4 => f32::INFINITY,
            (x, y) if y < bottom(x) => f32::NAN,
            (x, y) => ground(x, y) as f32,
        })
        .collect();
    let hole: Vec<u32> = (0..w * h)
        .filter(|&p| start[p].is_nan())
        .map(|p| p as u32)
        .collect();
    let farthest_edge = (0..w).map(|x| ground(x, bottom(x))).fold(0.0, f64::max);
    let top = 4 * w + 20;
    assert!(ground(20, 4) > 2.0 * farthest_edge);
    for far_limit in [100.0, 40.0] {
        let mut work = start.clone();
        HoleFiller::new(far_limit, Occlusions::default())
            .fill(&mut work, w, h, &hole, 32, &mut SplitMix64::new(5))
            .unwrap();
        let want = ground(20, 4).min(far_limit);
        let got = f64::from(work[top]);
        assert!(
            (got / want - 1.0).abs() < 0.01,
            "limit {far_limit}: {got} / {want}"
        );
    }
}

/// A 20 x 10 frame: grey 0.2 left of x = 10, grey 0.8 right of it; range 10 left of
/// x = 5, 50 from x = 15, a hole between (infinite, as `label_unknown` leaves holes).
fn two_faces() -> (RgbImage, Vec<f32>, Vec<u32>) {
    let (w, h) = (20, 10);
    let image = RgbImage::from_fn(w, h, |x, _| if x < 10 { [0.2; 3] } else { [0.8; 3] });
    let work: Vec<f32> = (0..w * h)
        .map(|p| match p % w {
            x if x < 5 => 10.0,
            x if x >= 15 => 50.0,
            _ => f32::INFINITY,
        })
        .collect();
    let hole = (0..w * h)
        .filter(|&p| !work[p].is_finite())
        .map(|p| p as u32)
        .collect();
    (image, work, hole)
}

fn fill_by_colour(image: &RgbImage, work: &mut [f32], hole: &[u32], seed: u64) -> usize {
    let guide = ColourGuide::new(image, 0.08);
    let mut state = vec![Pixel::Other; work.len()];
    HoleFiller::new(100.0, Occlusions::default())
        .fill_by_colour(
            work,
            (image.width(), image.height()),
            hole,
            &guide,
            &mut state,
            8,
            &mut SplitMix64::new(seed),
        )
        .unwrap()
}

#[test]
fn each_colour_continues_its_own_surface() {
    let (image, mut work, hole) = two_faces();
    let mut plain = work.clone();
    HoleFiller::new(100.0, Occlusions::default())
        .fill(&mut plain, 20, 10, &hole, 8, &mut SplitMix64::new(3))
        .unwrap();
    // Without the image the plane through both sides wins: a ramp across the hole.
    assert!(
        (20.0..40.0).contains(&plain[5 * 20 + 9]),
        "{}",
        plain[5 * 20 + 9]
    );

    assert_eq!(fill_by_colour(&image, &mut work, &hole, 3), 2);
    for &p in &hole {
        let expected = if p % 20 < 10 { 10.0 } else { 50.0 };
        assert_eq!(work[p as usize], expected, "pixel {p}");
    }
}

#[test]
fn a_speck_of_another_colour_takes_what_is_round_it() {
    let (mut image, mut work, hole) = two_faces();
    *image.get_mut(7, 5) = [0.5, 0.1, 0.1];
    fill_by_colour(&image, &mut work, &hole, 3);
    assert_eq!(work[5 * 20 + 7], 10.0);
}

#[test]
fn a_colour_whose_known_pixels_disagree_takes_the_whole_holes_surface() {
    // The left face's known pixels say 10 in its top half and 100 in its bottom half
    // (false matches on a face without texture): no fit of them is trusted.
    let (image, mut work, hole) = two_faces();
    (5 * 20..10 * 20)
        .filter(|p| p % 20 < 5)
        .for_each(|p| work[p] = 100.0);
    let mut plain = work.clone();
    HoleFiller::new(100.0, Occlusions::default())
        .fill(&mut plain, 20, 10, &hole, 8, &mut SplitMix64::new(3))
        .unwrap();
    assert_eq!(fill_by_colour(&image, &mut work, &hole, 3), 1);
    for &p in hole.iter().filter(|&&p| p % 20 < 10) {
        assert_eq!(work[p as usize], plain[p as usize], "pixel {p}");
    }
    assert_eq!(work[5 * 20 + 12], 50.0);
}

/// A band along the left border (its edges all on one column) over a surface whose range
/// changes down the column, and one along the top (its edges on one row) over one that
/// changes along the row: the fill follows the surface along the line, level across it.
/// No three edges of a line span a plane, so only a constant could be fitted before, at
/// 14 % off at the left band's first row.
#[test]
fn a_band_with_edges_on_one_line_follows_the_surface_along_it() {
    fill_band_over("left", |_, y| 2.0 + 0.02 * y as f64, |x, _| x < 12);
    fill_band_over("top", |x, _| 3.0 + 0.05 * x as f64, |_, y| y < 9);
}

/// Fills the pixels `band` takes of a 40 x 30 map of `surface` and asserts that they
/// hold the surface (1e-4).
fn fill_band_over(
    name: &str,
    surface: impl Fn(usize, usize) -> f64,
    band: impl Fn(usize, usize) -> bool,
) {
    let (w, h) = (40, 30);
    let mut work: Vec<f32> = (0..w * h).map(|p| surface(p % w, p / w) as f32).collect();
    let hole: Vec<u32> = (0..w * h)
        .filter(|&p| band(p % w, p / w))
        .map(|p| p as u32)
        .collect();
    hole.iter().for_each(|&p| work[p as usize] = f32::NAN);
    HoleFiller::new(100.0, Occlusions::default())
        .fill(&mut work, w, h, &hole, 32, &mut SplitMix64::new(3))
        .unwrap();
    for &p in &hole {
        let (x, y) = (p as usize % w, p as usize / w);
        let (want, got) = (surface(x, y), f64::from(work[p as usize]));
        assert!(
            (got / want - 1.0).abs() < 1e-4,
            "{name} band ({x}, {y}): {got} vs {want}"
        );
    }
}
