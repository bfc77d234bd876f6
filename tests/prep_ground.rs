//! The level road under a Cityscapes camera bounds the range a matcher may measure below
//! the horizon (`src/prep/ground.rs`), end to end from a disparity PNG and its camera file.

use brume::io::depth::DepthOptions;
use brume::photo::{Photo, PrepareOptions};

const W: u32 = 160;
const H: u32 = 96;
/// Focal length (px), baseline (m), the camera's height (m) and pitch (rad, down).
const F: f64 = 200.0;
const B: f64 = 0.2;
const HEIGHT: f64 = 1.2;
const PITCH: f64 = 0.04;
/// The principal point.
const U0: f64 = 80.0;
const V0: f64 = 48.0;
/// Columns the right camera does not see (unknown), as a matcher leaves them.
const BAND: u32 = 24;

/// Depth Z along the optical axis of the level road seen through pixel row `y`, by the
/// camera's own geometry: the ray (u, v, 1) drops Z (v cos p + sin p) over depth Z.
fn road_depth(y: u32) -> Option<f64> {
    let v = (f64::from(y) - V0) / F;
    let drop = v * PITCH.cos() + PITCH.sin();
    (drop > 0.0).then(|| HEIGHT / drop)
}

/// A speck in the band, touching the left border (which the band's island rule keeps):
/// disparity 0.02 px, 2 km away, on rows of the road 4 to 7 m off.
fn speck(x: u32, y: u32) -> bool {
    x < 5 && (70..78).contains(&y)
}

/// The stored Cityscapes value of disparity `d` px (0: unknown).
fn stored(d: f64) -> u16 {
    if d <= 0.0 {
        0
    } else {
        (256.0 * d) as u16 + 1
    }
}

/// A wall 60 m off above the road's far part; the band unknown but for the specks.
fn disparity(x: u32, y: u32) -> f64 {
    if speck(x, y) {
        return 0.02;
    }
    if x < BAND {
        return 0.0;
    }
    let z = road_depth(y).map_or(60.0, |z| z.min(60.0));
    F * B / z
}

/// The camera files of the frames below: with the camera's mount over the road, and
/// without it (baseline and intrinsics only).
fn camera_files() -> [String; 2] {
    let intrinsic = format!(r#""intrinsic": {{"fx": {F}, "fy": {F}, "u0": {U0}, "v0": {V0}}}"#);
    [
        format!(
            r#"{{"extrinsic": {{"baseline": {B}, "z": {HEIGHT}, "pitch": {PITCH}}}, {intrinsic}}}"#
        ),
        format!(r#"{{"extrinsic": {{"baseline": {B}}}, {intrinsic}}}"#),
    ]
}

/// The frame saved in `dir` (`f_disparity.png`, `f_leftImg8bit.png`) prepared with
/// `camera` as its camera file.
fn prepared(dir: &std::path::Path, camera: &str) -> brume::photo::PreparedPhoto {
    let camera_path = dir.join("c_camera.json");
    std::fs::write(&camera_path, camera).unwrap();
    let opts = DepthOptions {
        camera: Some(camera_path),
        ..DepthOptions::default()
    };
    let photo = Photo::load(
        &dir.join("f_leftImg8bit.png"),
        &dir.join("f_disparity.png"),
        &opts,
    )
    .unwrap();
    brume::photo::preprocess(&photo, &PrepareOptions::default()).unwrap()
}

/// The level road's range through pixel (x, y).
fn road_range(x: u32, y: u32) -> f64 {
    let u = (f64::from(x) - U0) / F;
    let v = (f64::from(y) - V0) / F;
    road_depth(y).unwrap() * (1.0 + u * u + v * v).sqrt()
}

#[test]
fn specks_beyond_the_road_are_filled_as_the_road() {
    let dir = tempfile::tempdir().unwrap();
    let disp = image::ImageBuffer::from_fn(W, H, |x, y| image::Luma([stored(disparity(x, y))]));
    disp.save(dir.path().join("f_disparity.png")).unwrap();
    let colour = image::RgbImage::from_fn(W, H, |_, y| match road_depth(y) {
        Some(z) if z < 60.0 => image::Rgb([90, 90, 95]),
        _ => image::Rgb([150, 110, 80]),
    });
    colour.save(dir.path().join("f_leftImg8bit.png")).unwrap();
    let [with_mount, without] = camera_files();
    // The mean |ln(R / R_road)| over the specks' pixels once prepared, and the count of
    // values dropped beyond the road.
    let speck_error = |camera: &str| -> (f64, usize) {
        let p = prepared(dir.path(), camera);
        let (mut sum, mut n) = (0.0, 0);
        for y in 0..H {
            for x in (0..W).filter(|&x| speck(x, y)) {
                let got = f64::from(*p.range.get(x as usize, y as usize));
                sum += (got / road_range(x, y)).ln().abs();
                n += 1;
            }
        }
        let stats = &p.prepared.as_ref().unwrap().stats;
        (sum / f64::from(n), stats.below_ground)
    };
    let (bounded, dropped) = speck_error(&with_mount);
    let (unbounded, none) = speck_error(&without);
    assert_eq!((dropped, none), (40, 0));
    assert!(bounded < 0.05, "mean |ln(R / R_road)| {bounded}");
    assert!(
        unbounded > 1.0,
        "mean |ln(R / R_road)| {unbounded} without the mount"
    );
}

/// Rows at the bottom that the matcher left unknown (a car's hood).
const HOOD: u32 = 10;

/// The bottom band below the road comes out on the level road with the mount: there the
/// road's last measured rows are 1.15 times too far (a matcher's bias on a dark road,
/// within the bound), and the band, which continues them, would carry that on to the
/// border; without the mount it does.
#[test]
fn a_bottom_band_comes_no_farther_than_the_road() {
    let dir = tempfile::tempdir().unwrap();
    let biased = |y: u32| (H - HOOD - 8..H - HOOD).contains(&y);
    let disp = image::ImageBuffer::from_fn(W, H, |_, y| {
        let d = match road_depth(y) {
            _ if y >= H - HOOD => 0.0,
            Some(z) if biased(y) => F * B / (1.15 * z),
            z => F * B / z.map_or(60.0, |z| z.min(60.0)),
        };
        image::Luma([stored(d)])
    });
    disp.save(dir.path().join("f_disparity.png")).unwrap();
    let colour = image::RgbImage::from_fn(W, H, |_, _| image::Rgb([90, 90, 95]));
    colour.save(dir.path().join("f_leftImg8bit.png")).unwrap();
    let [with_mount, without] = camera_files();
    // The largest R / R_road over the band's pixels once prepared, and how many the level
    // road brought nearer.
    let band_over_road = |camera: &str| -> (f64, usize) {
        let p = prepared(dir.path(), camera);
        let mut worst: f64 = 0.0;
        for y in H - HOOD..H {
            for x in 0..W {
                let got = f64::from(*p.range.get(x as usize, y as usize));
                worst = worst.max(got / road_range(x, y));
            }
        }
        (worst, p.prepared.as_ref().unwrap().stats.border_on_road)
    };
    let (bounded, on_road) = band_over_road(&with_mount);
    let (unbounded, none) = band_over_road(&without);
    assert!(
        on_road > 0 && none == 0,
        "{on_road} and {none} px brought onto the road"
    );
    assert!(bounded < 1.01, "R / R_road up to {bounded} with the mount");
    assert!(
        unbounded > 1.1,
        "R / R_road up to {unbounded} without the mount"
    );
}
