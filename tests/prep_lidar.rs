//! A LiDAR's scan lines as KITTI stores them (`src/prep/scan.rs`), end to end from a 16-bit
//! PNG: a box 10 m away on a level road under the sky, known on every 4th row from below
//! the box's top down, with the road's points past the box's left edge on its face; in
//! full lines, and in dots as a real scanner's lines are.

use brume::io::depth::{DepthFormat, DepthOptions};
use brume::photo::{Photo, PrepareOptions};

const W: u32 = 160;
const H: u32 = 96;
/// Focal length (px), principal point, the camera's height over the road (m).
const F: f64 = 100.0;
const CX: f64 = 79.5;
const CY: f64 = 47.5;
const HEIGHT: f64 = 1.5;
/// The box: its columns, its top row and its depth (m); its foot is on the road.
const BOX_X: std::ops::Range<u32> = 60..100;
const BOX_TOP: u32 = 20;
const BOX_Z: f64 = 10.0;
/// The scanner's top line (below the box's top), its lines' spacing and reach (m).
const TOP_LINE: u32 = 36;
const LINES: u32 = 4;
const MAX_RANGE: f64 = 60.0;
/// The first line on the road (row 48, 300 m off, is beyond the reach) and the last line:
/// the road between them is filled from lines on both sides. Above the first (the road
/// up to the horizon) it recedes as the scene beyond the reach; below the last, the
/// bottom band continues it.
const FIRST_ROAD_LINE: u32 = 52;
const LAST_LINE: u32 = 92;

/// The road's depth through row `y` (none at and above the horizon).
fn road(y: u32) -> Option<f64> {
    let below = f64::from(y) - CY;
    (below > 0.0).then(|| F * HEIGHT / below)
}

/// The box's rows: from its top to its foot on the road.
fn on_box(x: u32, y: u32) -> bool {
    BOX_X.contains(&x) && y >= BOX_TOP && road(y).is_none_or(|z| z > BOX_Z)
}

/// The true depth through (x, y): the box, the road, or none (the sky).
fn depth(x: u32, y: u32) -> Option<f64> {
    if on_box(x, y) {
        Some(BOX_Z)
    } else {
        road(y)
    }
}

/// Depth to range along the pixel's ray.
fn range(x: u32, y: u32, z: f64) -> f64 {
    let (u, v) = ((f64::from(x) - CX) / F, (f64::from(y) - CY) / F);
    z * (1.0 + u * u + v * v).sqrt()
}

/// What the scanner stored: its lines, one return in ten dropped, nothing beyond its
/// reach; on the box's two left columns below the horizon, the road behind the box.
/// `dotted`: a real scanner's lines, a return in every third column only, each line's at
/// other columns than the line above's (KITTI's are 2 to 4 px apart).
fn scanned(x: u32, y: u32, dotted: bool) -> u16 {
    if y < TOP_LINE || !(y - TOP_LINE).is_multiple_of(LINES) || (x * 7 + y * 13).is_multiple_of(10)
    {
        return 0;
    }
    if dotted && x % 3 != ((y - TOP_LINE) / LINES) % 3 {
        return 0;
    }
    let past_edge = on_box(x, y) && x < BOX_X.start + 2;
    let z = match (past_edge, road(y)) {
        (true, Some(behind)) => Some(behind),
        _ => depth(x, y),
    };
    z.filter(|&z| z < MAX_RANGE)
        .map_or(0, |z| (256.0 * z).round() as u16)
}

#[test]
fn scan_lines_are_filled_between_and_the_box_goes_on_above_the_top_line() {
    prepare_and_check(false);
}

/// The same scene scanned in dots, as a real scanner's lines are: down most columns a line
/// is missing, and the map must still be read as scan lines.
#[test]
fn dotted_scan_lines_are_filled_as_well() {
    prepare_and_check(true);
}

/// Writes the scan (`dotted` or not) and the image, prepares them, and checks the box and
/// the road against the truth.
fn prepare_and_check(dotted: bool) {
    let dir = tempfile::tempdir().unwrap();
    let png = image::ImageBuffer::from_fn(W, H, |x, y| image::Luma([scanned(x, y, dotted)]));
    png.save(dir.path().join("lidar.png")).unwrap();
    let colour = image::RgbImage::from_fn(W, H, |x, y| match depth(x, y) {
        _ if on_box(x, y) => image::Rgb([170, 40, 30]),
        Some(_) => image::Rgb([60, 120, 50]),
        None => image::Rgb([150, 180, 230]),
    });
    colour.save(dir.path().join("image.png")).unwrap();
    let opts = DepthOptions {
        format: DepthFormat::Kitti,
        focal: Some(F),
        ..DepthOptions::default()
    };
    let photo = Photo::load(
        &dir.path().join("image.png"),
        &dir.path().join("lidar.png"),
        &opts,
    )
    .unwrap();
    let p = brume::photo::preprocess(&photo, &PrepareOptions::default()).unwrap();
    let prepared = p.prepared.as_ref().unwrap();
    let stats = &prepared.stats;
    // In dots the background's points on the box have too few of the box's points round
    // them at this image's size (±4 px along the row) to be judged, and stay: a few of
    // the pixels the bound below allows.
    assert!(
        stats.scan_gaps > 0 && (dotted || stats.scan_unlike > 0),
        "{stats:?}"
    );
    // |ln(R / R_true)| over the box (its top above the top line included) and the road
    // within the scanner's reach; the sky stays sky.
    let mut errors = Vec::new();
    for y in 0..H {
        for x in 0..W {
            let sky = *prepared.sky.get(x as usize, y as usize);
            match depth(x, y) {
                None => assert!(sky, "({x}, {y}) is sky"),
                Some(z) if on_box(x, y) || (FIRST_ROAD_LINE..=LAST_LINE).contains(&y) => {
                    let got = f64::from(*p.range.get(x as usize, y as usize));
                    errors.push((got / range(x, y, z)).ln().abs());
                }
                Some(_) => {}
            }
        }
    }
    let n = errors.len() as f64;
    let mean = errors.iter().sum::<f64>() / n;
    let off = errors.iter().filter(|&&e| e > 0.05).count() as f64 / n;
    assert!(mean < 0.01, "mean |ln(R / R_true)| {mean}");
    assert!(
        off < 0.01,
        "{:.1} % of the pixels more than 5 % off",
        100.0 * off
    );
}
