//! An iPhone's portrait photo saved as JPEG: its depth is an auxiliary JPEG after the photo,
//! listed by a Multi-Picture Format index and described by Apple's XMP. Read from files
//! whose MPF index `tools/apple_depth_fixtures.py` wrote from the specification and
//! ExifTool read back (`tests/data/apple/`), checked against the planes they encode.

use std::path::{Path, PathBuf};

use brume::io::depth::{has_embedded_depth, load_range, load_range_from_bytes};
use brume::io::depth::{DepthFormat, DepthKind, DepthOptions};
use brume::photo::Photo;
use brume::Error;

use crate::common;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/apple")
        .join(name)
}

/// The depth of `portrait.jpg` below its 8 rows of background, metres.
fn portrait_plane(x: usize, y: usize) -> f64 {
    1.0 + 0.05 * x as f64 + 0.1 * (y as f64 - 8.0)
}

/// One code of `portrait.jpg`'s disparity, 1/m: 0.2..1.0 over 0..255.
const DISPARITY_CODE: f64 = 0.8 / 255.0;

/// The message of a refused `bytes` read as `p.jpg`.
fn refusal(bytes: &[u8], opts: &DepthOptions) -> String {
    match load_range_from_bytes(bytes, Path::new("p.jpg"), opts, None) {
        Ok(_) => panic!("expected an error"),
        Err(e) => {
            assert!(matches!(e, Error::Format { .. }), "{e}");
            e.to_string()
        }
    }
}

#[test]
fn an_iphone_portraits_disparity_is_read_as_range_in_metres() {
    let loaded = load_range(&fixture("portrait.jpg"), &DepthOptions::default()).unwrap();
    assert_eq!(loaded.format, DepthFormat::AppleDepth);
    assert_eq!(loaded.kind, DepthKind::Depth);
    assert!(loaded.metric, "Apple's disparity is in 1/m");
    let notes = loaded.notes.join("\n");
    assert!(
        notes.contains("image 3 of the Multi-Picture index"),
        "{notes}"
    );
    assert!(notes.contains("Accuracy is relative"), "{notes}");
    assert!(notes.contains("from the file's IntrinsicMatrix"), "{notes}");
    // The matte before it (image 2) is grey, not depth; the map is the disparity's size.
    let range = &loaded.range;
    assert_eq!((range.width(), range.height()), (32, 24));
    // fx = fy = 60, principal point (30, 26) of a 64 x 48 reference, on the 32 x 24 grid.
    let k = loaded.intrinsics.unwrap();
    assert_eq!((k.fx, k.fy, k.cx, k.cy), (30.0, 30.0, 14.75, 12.75));
    // The top 8 rows are at the farthest code: where the map stops, unknown.
    assert_eq!(loaded.unknown_pixels, 8 * 32);
    for y in 0..24 {
        for x in 0..32 {
            let got = f64::from(*range.get(x, y));
            if y < 8 {
                assert!(got.is_nan(), "({x}, {y}) {got}");
                continue;
            }
            let (dx, dy) = ((x as f64 - k.cx) / k.fx, (y as f64 - k.cy) / k.fy);
            let depth = got / (1.0 + dx * dx + dy * dy).sqrt();
            let codes = (1.0 / depth - 1.0 / portrait_plane(x, y)) / DISPARITY_CODE;
            // Rounding to a code, and the lossy JPEG's one code at most.
            assert!(
                codes.abs() <= 1.5 + 1e-3,
                "({x}, {y}): {depth} m, {codes} codes"
            );
        }
    }
}

#[test]
fn a_depth_image_in_metres_stops_at_its_farthest_code() {
    let loaded = load_range(&fixture("depth-abs.jpg"), &DepthOptions::default()).unwrap();
    assert_eq!(loaded.format, DepthFormat::AppleDepth);
    let notes = loaded.notes.join("\n");
    assert!(notes.contains("depth (m)"), "{notes}");
    assert!(!notes.contains("relative"), "Accuracy absolute: {notes}");
    // No IntrinsicMatrix: depth along the axis, which wants a field of view.
    assert!(loaded.intrinsics.is_none());
    assert!(loaded.depth_as_range_warning().is_some());
    assert_eq!(
        loaded.unknown_pixels,
        8 * 24,
        "the right 8 columns, at 8.5 m"
    );
    let code = 8.0 / 255.0;
    for y in 0..24 {
        for x in 0..24 {
            let got = f64::from(*loaded.range.get(x, y));
            let want = 0.5 + 0.25 * x as f64;
            assert!(
                (got - want).abs() <= 1.5 * code,
                "({x}, {y}): {got} for {want}"
            );
        }
        assert!(loaded.range.get(24, y).is_nan());
    }
    let with_fov = DepthOptions {
        fov: Some(50.0),
        ..DepthOptions::default()
    };
    let ranged = load_range(&fixture("depth-abs.jpg"), &with_fov).unwrap();
    assert!(ranged.intrinsics.is_some());
    assert!(*ranged.range.get(0, 0) > *loaded.range.get(0, 0));
}

#[test]
fn a_jpeg_without_apples_depth_is_refused_by_name() {
    let opts = DepthOptions::default();
    for name in ["matte-only.jpg", "gain-map.jpg"] {
        let m = refusal(&std::fs::read(fixture(name)).unwrap(), &opts);
        assert!(m.contains("lists no image of Apple's depth"), "{name}: {m}");
        assert!(!has_embedded_depth(&fixture(name)), "{name}");
    }
    assert!(has_embedded_depth(&fixture("portrait.jpg")));
    assert!(has_embedded_depth(&fixture("depth-abs.jpg")));

    let portrait = std::fs::read(fixture("portrait.jpg")).unwrap();
    let m = refusal(&portrait[..portrait.len() - 100], &opts);
    assert!(
        m.contains("image 3 of 3") && m.contains("runs past the file"),
        "{m}"
    );
    let at = portrait
        .windows(b">1.000000<".len())
        .position(|w| w == b">1.000000<")
        .unwrap();
    let mut broken = portrait.clone();
    broken[at + 2] = b',';
    let m = refusal(&broken, &opts);
    assert!(m.contains("FloatMaxValue") && m.contains("1,000000"), "{m}");

    // Each format reads its own layout only.
    let gdepth_only = DepthOptions {
        format: DepthFormat::Gdepth,
        ..DepthOptions::default()
    };
    let m = refusal(&portrait, &gdepth_only);
    assert!(m.contains("GDepth"), "{m}");
    let apple_only = DepthOptions {
        format: DepthFormat::AppleDepth,
        ..DepthOptions::default()
    };
    let gdepth =
        std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gdepth/inv8.jpg"));
    let m = refusal(&gdepth.unwrap(), &apple_only);
    assert!(m.contains("iPhone"), "{m}");
}

/// `portrait-rot6.jpg` is `portrait.jpg` with EXIF Orientation 6 on its photo: the depth,
/// stored as the sensor saw it, turns with the photo, and its intrinsics with it.
#[test]
fn an_upright_iphone_portrait_turns_its_depth() {
    let opts = DepthOptions::default();
    let stored = load_range(&fixture("portrait.jpg"), &opts).unwrap();
    let path = fixture("portrait-rot6.jpg");
    let turned = Photo::load(&path, &path, &opts).unwrap().depth;
    let (range, k) = (&turned.range, turned.intrinsics.unwrap());
    assert_eq!((range.width(), range.height()), (24, 32));
    for v in 0..32 {
        for u in 0..24 {
            let want = *stored.range.get(v, 23 - u);
            let got = *range.get(u, v);
            assert!(got == want || (got.is_nan() && want.is_nan()), "({u}, {v})");
        }
    }
    let s = stored.intrinsics.unwrap();
    assert_eq!((k.fx, k.fy, k.cx, k.cy), (s.fy, s.fx, 23.0 - s.cy, s.cx));
}

#[test]
fn render_reads_an_iphone_portraits_depth_from_the_image_alone() {
    let (dir, report) = common::render_photo_alone(&fixture("portrait-rot6.jpg"), "0.3");
    assert_eq!(report["depth_format"], "apple-depth");
    assert_eq!(
        (report["width"].as_u64(), report["height"].as_u64()),
        (Some(48), Some(64))
    );
    let out = dir.path().join("out.png");
    assert_eq!(image::image_dimensions(out).unwrap(), (48, 64));
}
