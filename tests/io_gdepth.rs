//! GDepth and Dynamic Depth: the depth map a phone's portrait photo stores with its JPEG,
//! read from files whose XMP ExifTool wrote (`tests/data/gdepth/`,
//! `tools/gdepth_fixtures.py`) and checked against the specification's formulas on the
//! plane each file encodes; the render that reads it from `--image` alone.

use std::path::{Path, PathBuf};

use brume::io::depth::{has_embedded_depth, load_range, load_range_from_bytes};
use brume::io::depth::{DepthFormat, DepthKind, DepthOptions};
use brume::Error;

use crate::common;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/gdepth")
        .join(name)
}

/// The plane of `inv8.jpg` and `lin16.jpg`, metres, on their 32 x 24 grid.
fn small_plane(x: usize, y: usize) -> f64 {
    1.5 + 0.25 * x as f64 + 0.5 * y as f64
}

/// RangeInverse's d_n of depth `d` (the specification's encoding).
fn inverse_d_n(d: f64, near: f64, far: f64) -> f64 {
    far * (d - near) / (d * (far - near))
}

#[test]
fn an_8_bit_range_inverse_map_is_within_half_a_code_of_its_plane() {
    let loaded = load_range(&fixture("inv8.jpg"), &DepthOptions::default()).unwrap();
    assert_eq!(loaded.format, DepthFormat::Gdepth);
    assert_eq!(
        loaded.kind,
        DepthKind::Depth,
        "no MeasureType: the optical axis"
    );
    assert!(loaded.metric, "no Units: metres, the format's default");
    assert!(loaded.notes.iter().any(|n| n.contains("without Units")));
    let range = &loaded.range;
    assert_eq!(
        (range.width(), range.height()),
        (32, 24),
        "the embedded map's own size"
    );
    // The samples the writer rounded to the last code, Far, are where the map stops:
    // unknown (the far corner and the three beside it, 8 bits being coarse there).
    let last_code = |x, y| (inverse_d_n(small_plane(x, y), 1.5, 20.75) * 255.0).round() == 255.0;
    let at_far = (0..24)
        .flat_map(|y| (0..32).map(move |x| (x, y)))
        .filter(|&(x, y)| last_code(x, y))
        .count();
    assert_eq!(at_far, 4);
    assert_eq!(loaded.unknown_pixels, at_far);
    assert!(loaded.notes.iter().any(|n| n.contains("4 samples at Far")));
    for y in 0..24 {
        for x in 0..32 {
            if last_code(x, y) {
                assert!(range.get(x, y).is_nan(), "({x}, {y})");
                continue;
            }
            let (got, want) = (f64::from(*range.get(x, y)), small_plane(x, y));
            let codes = (inverse_d_n(got, 1.5, 20.75) - inverse_d_n(want, 1.5, 20.75)) * 255.0;
            assert!(codes.abs() <= 0.5 + 1e-4, "({x}, {y}): {got} for {want}");
        }
    }
    // The near code is exact.
    assert!((f64::from(*range.get(0, 0)) - 1.5).abs() < 1e-5);
}

/// `far8-jpeg.jpg` is a map clamped at Far (its top 6 rows, the sky) as a JPEG of quality
/// 100, which moved some of those samples to the code below: a lossy image clamped there,
/// whose codes within 3 of Far are read as Far. `inv8-jpeg.jpg` holds `inv8.jpg`'s plane,
/// which only reaches Far (4 samples at it, 45 within 3 codes): its codes are depths.
#[test]
fn a_jpeg_depth_image_clamped_at_far_stops_within_three_codes_of_it() {
    let loaded = load_range(&fixture("far8-jpeg.jpg"), &DepthOptions::default()).unwrap();
    assert_eq!(
        loaded.unknown_pixels,
        6 * 32,
        "the clamped rows, and only they"
    );
    assert!(loaded.notes.iter().any(|n| n.contains("clamped at Far")));
    let plane = |x: usize, y: usize| 1.5 + 0.2 * x as f64 + 0.4 * (y as f64 - 6.0);
    for y in 0..24 {
        for x in 0..32 {
            let got = f64::from(*loaded.range.get(x, y));
            if y < 6 {
                assert!(got.is_nan(), "({x}, {y})");
                continue;
            }
            let codes =
                (inverse_d_n(got, 1.5, 20.75) - inverse_d_n(plane(x, y), 1.5, 20.75)) * 255.0;
            assert!(codes.abs() <= 1.5 + 1e-3, "({x}, {y}): {codes} codes");
        }
    }

    let reaching = load_range(&fixture("inv8-jpeg.jpg"), &DepthOptions::default()).unwrap();
    let code = |x, y| (inverse_d_n(small_plane(x, y), 1.5, 20.75) * 255.0).round();
    let samples = || (0..24).flat_map(|y| (0..32).map(move |x| (x, y)));
    let at_least = |c: f64| samples().filter(|&(x, y)| code(x, y) >= c).count();
    // Only Far itself is unknown, where the JPEG left a sample at it.
    assert!(
        reaching.unknown_pixels <= at_least(254.0),
        "{}",
        reaching.unknown_pixels
    );
    assert!(!reaching.notes.iter().any(|n| n.contains("clamped")));
    for (x, y) in samples().filter(|&(x, y)| code(x, y) <= 253.0) {
        let got = f64::from(*reaching.range.get(x, y));
        let moved = inverse_d_n(got, 1.5, 20.75) * 255.0 - code(x, y);
        assert!(moved.abs() <= 1.0 + 1e-3, "({x}, {y}): {moved} codes");
    }
}

#[test]
fn a_16_bit_linear_map_in_millimetres_of_range() {
    let loaded = load_range(&fixture("lin16.jpg"), &DepthOptions::default()).unwrap();
    assert_eq!(loaded.kind, DepthKind::Range, "MeasureType OpticRay");
    assert!(loaded.metric);
    let half_code_m = (20.75 - 1.5) / 65535.0 / 2.0;
    assert_eq!(loaded.unknown_pixels, 1, "the far corner, at Far");
    for y in 0..24 {
        for x in 0..32 {
            if (x, y) == (31, 23) {
                continue;
            }
            let got = f64::from(*loaded.range.get(x, y));
            let want = small_plane(x, y);
            assert!(
                (got - want).abs() <= half_code_m + 1e-5,
                "({x}, {y}): {got} for {want}"
            );
        }
    }
}

#[test]
fn depth_along_the_axis_becomes_range_with_the_field_of_view() {
    let opts = DepthOptions {
        fov: Some(60.0),
        ..DepthOptions::default()
    };
    let plain = load_range(&fixture("inv8.jpg"), &DepthOptions::default()).unwrap();
    let loaded = load_range(&fixture("inv8.jpg"), &opts).unwrap();
    assert!(loaded.intrinsics.is_some());
    let f = 12.0 / 30f64.to_radians().tan();
    for (x, y) in [(0, 0), (31, 0), (16, 12), (5, 20)] {
        let (dx, dy) = (x as f64 - 15.5, y as f64 - 11.5);
        let ray = (1.0 + (dx * dx + dy * dy) / (f * f)).sqrt();
        let depth = f64::from(*plain.range.get(x, y));
        let range = f64::from(*loaded.range.get(x, y));
        assert!((range - depth * ray).abs() < 1e-4 * range, "({x}, {y})");
    }
    // A user's kind wins over the file's.
    let as_range = DepthOptions {
        kind: Some(DepthKind::Range),
        ..DepthOptions::default()
    };
    let loaded = load_range(&fixture("lin16.jpg"), &as_range).unwrap();
    assert_eq!(loaded.kind, DepthKind::Range);
    let refused = DepthOptions {
        kind: Some(DepthKind::Disparity),
        ..DepthOptions::default()
    };
    assert!(load_range(&fixture("inv8.jpg"), &refused).is_err());
}

#[test]
fn an_extended_xmp_packet_is_put_together_from_its_segments() {
    let loaded = load_range(&fixture("ext16.jpg"), &DepthOptions::default()).unwrap();
    let range = &loaded.range;
    assert_eq!((range.width(), range.height()), (320, 240));
    // The plane plus up to 1 cm of noise, to half a 16-bit code (and f32 rounding: up to
    // 0.01 code near 2 m).
    let code = |d: f64| inverse_d_n(d, 2.0, 42.0) * 65535.0;
    for y in (0..240).step_by(7) {
        for x in (0..320).step_by(5) {
            let got = code(f64::from(*range.get(x, y)));
            let plane = 2.0 + 0.05 * x as f64 + 0.1 * y as f64;
            assert!(
                got >= code(plane) - 0.52 && got <= code(plane + 0.01) + 0.52,
                "({x}, {y}): code {got} for {} to {}",
                code(plane),
                code(plane + 0.01)
            );
        }
    }
}

#[test]
fn extended_segments_in_any_order_give_the_same_map() {
    let whole = load_range(&fixture("inv8.jpg"), &DepthOptions::default()).unwrap();
    let split = load_range(&fixture("ext8.jpg"), &DepthOptions::default()).unwrap();
    let bits = |m: &brume::raster::ScalarMap| -> Vec<u32> {
        m.as_slice().iter().map(|v| v.to_bits()).collect()
    };
    assert_eq!(bits(&whole.range), bits(&split.range));
}

#[test]
fn a_dynamic_depth_container_gives_its_depth_item() {
    let gdepth = load_range(&fixture("inv8.jpg"), &DepthOptions::default()).unwrap();
    let loaded = load_range(&fixture("dd8.jpg"), &DepthOptions::default()).unwrap();
    assert_eq!(loaded.format, DepthFormat::DynamicDepth);
    assert_eq!(loaded.kind, DepthKind::Depth);
    assert!(loaded.metric, "Units Meters");
    // The same PNG as inv8.jpg's, found past the confidence item before it, turned into
    // range by the camera's ImagingModel (60 and 62 px of the 64 x 48 photo, principal
    // point 0.45, 0.55 of it) on the 32 x 24 map: no field of view needed.
    let k = loaded.intrinsics.expect("the ImagingModel's intrinsics");
    let (fx, fy, cx, cy) = (30.0, 31.0, 0.45 * 32.0 - 0.5, 0.55 * 24.0 - 0.5);
    assert!(
        (k.fx - fx).abs() < 1e-12 && (k.fy - fy).abs() < 1e-12,
        "{k:?}"
    );
    assert!(
        (k.cx - cx).abs() < 1e-12 && (k.cy - cy).abs() < 1e-12,
        "{k:?}"
    );
    assert_eq!(loaded.unknown_pixels, gdepth.unknown_pixels);
    for y in 0..24 {
        for x in 0..32 {
            let depth = f64::from(*gdepth.range.get(x, y));
            let ray =
                (1.0 + ((x as f64 - cx) / fx).powi(2) + ((y as f64 - cy) / fy).powi(2)).sqrt();
            let range = f64::from(*loaded.range.get(x, y));
            assert!(
                (depth.is_nan() && range.is_nan()) || (range - depth * ray).abs() < 1e-5 * range,
                "({x}, {y}): {range} for {depth} x {ray}"
            );
        }
    }
    assert!(loaded.warnings().is_empty(), "{:?}", loaded.warnings());
    // A field of view given wins over the file's model.
    let with_fov = DepthOptions {
        fov: Some(60.0),
        ..DepthOptions::default()
    };
    let given = load_range(&fixture("dd8.jpg"), &with_fov).unwrap();
    let centred = given.intrinsics.unwrap();
    assert!((centred.cx - 15.5).abs() < 1e-12 && (centred.fx - centred.fy).abs() < 1e-12);
    assert!(has_embedded_depth(&fixture("dd8.jpg")));
    // Read as the other format, it is refused as that layout's mismatch.
    let as_gdepth = DepthOptions {
        format: DepthFormat::Gdepth,
        ..DepthOptions::default()
    };
    let err = match load_range(&fixture("dd8.jpg"), &as_gdepth) {
        Ok(_) => panic!("expected an error"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.contains("expects a JPEG with a GDepth depth map"),
        "{err}"
    );
}

#[test]
fn min_confidence_drops_what_the_confidence_map_doubts() {
    let with = |file: &str, min: Option<f64>| {
        let opts = DepthOptions {
            min_confidence: min,
            ..DepthOptions::default()
        };
        load_range(&fixture(file), &opts).unwrap()
    };
    // Without a threshold the map is read whole: the scales of confidence differ.
    let plain = with("conf8.jpg", None);
    let inv8 = with("inv8.jpg", None);
    assert_eq!(plain.unknown_pixels, inv8.unknown_pixels);
    // Its right half is at 64/255 = 0.251: unknown below 0.5, kept at 0.25.
    let half = with("conf8.jpg", Some(0.5));
    for y in 0..24 {
        for x in 0..32 {
            let (got, whole) = (*half.range.get(x, y), *inv8.range.get(x, y));
            if x >= 16 {
                assert!(got.is_nan(), "({x}, {y})");
            } else {
                assert_eq!(got.to_bits(), whole.to_bits(), "({x}, {y})");
            }
        }
    }
    assert!(half
        .notes
        .iter()
        .any(|n| n.contains("below `min_confidence` 0.5")));
    assert_eq!(
        with("conf8.jpg", Some(0.25)).unknown_pixels,
        inv8.unknown_pixels
    );
    // Dynamic Depth's confidence item (all 1.0) keeps every sample at 1.
    assert_eq!(
        with("dd8.jpg", Some(1.0)).unknown_pixels,
        with("dd8.jpg", None).unknown_pixels
    );
    // A file without a confidence map says the option did nothing.
    let none = with("inv8.jpg", Some(0.5));
    assert!(none
        .warnings()
        .iter()
        .any(|w| w.contains("no confidence map")));
    // A threshold above every sample's confidence (conf-low.jpg's, all 64/255) leaves
    // nothing: refused by name, with the highest confidence there is, rather than the
    // loaders' bare "no valid depth".
    let opts = DepthOptions {
        min_confidence: Some(0.3),
        ..DepthOptions::default()
    };
    let e = load_range(&fixture("conf-low.jpg"), &opts).unwrap_err();
    let message = e.to_string();
    assert!(matches!(e, Error::Format { .. }), "{message}");
    assert!(message.contains("conf-low.jpg"), "{message}");
    assert!(
        message.contains("all 764 depth samples have a confidence below `min_confidence` 0.3")
            && message.contains("the highest is 0.251"),
        "{message}"
    );
    assert_eq!(
        with("conf-low.jpg", Some(0.25)).unknown_pixels,
        inv8.unknown_pixels
    );
}

#[test]
fn broken_gdepth_files_are_refused_by_name() {
    let message = |bytes: &[u8]| match load_range_from_bytes(
        bytes,
        Path::new("p.jpg"),
        &DepthOptions::default(),
        None,
    ) {
        Ok(_) => panic!("expected an error"),
        Err(e) => {
            assert!(matches!(e, Error::Format { .. }), "{e}");
            e.to_string()
        }
    };
    let plain = std::fs::read(fixture("no-depth.jpg")).unwrap();
    assert!(message(&plain).contains("has none"));
    assert!(!has_embedded_depth(&fixture("no-depth.jpg")));
    assert!(has_embedded_depth(&fixture("ext16.jpg")));
    // A device is read no further than the header's bound.
    assert!(!has_embedded_depth(Path::new("/dev/zero")));

    // Cut inside the second extended segment: the header runs past the file.
    let ext = std::fs::read(fixture("ext16.jpg")).unwrap();
    assert!(message(&ext[..60_000]).contains("truncated JPEG"));

    // A format the specification does not have, and a Near that is not a number.
    let inv = std::fs::read(fixture("inv8.jpg")).unwrap();
    let swap = |from: &str, to: &str| {
        assert_eq!(from.len(), to.len(), "the segment keeps its length");
        let at = inv
            .windows(from.len())
            .position(|w| w == from.as_bytes())
            .unwrap();
        let mut bytes = inv.clone();
        bytes[at..at + to.len()].copy_from_slice(to.as_bytes());
        bytes
    };
    let m = message(&swap(">RangeInverse<", ">RangeInvert!<"));
    assert!(
        m.contains("RangeInvert!") && m.contains("RangeLinear"),
        "{m}"
    );
    let m = message(&swap(">1.5<", ">1,5<"));
    assert!(m.contains("Near") && m.contains("1,5"), "{m}");

    // Dynamic Depth: the depth item cut short, and a DepthURI that names no item.
    let dd = std::fs::read(fixture("dd8.jpg")).unwrap();
    let m = message(&dd[..dd.len() - 100]);
    assert!(m.contains("runs past the file"), "{m}");
    let at = dd
        .windows(b">android/depthmap</DepthMap:DepthURI>".len())
        .position(|w| w == b">android/depthmap</DepthMap:DepthURI>")
        .unwrap();
    let mut renamed = dd.clone();
    renamed[at + 16] = b'X';
    let m = message(&renamed);
    assert!(
        m.contains("android/depthmaX") && m.contains("no item"),
        "{m}"
    );
}

#[test]
fn render_reads_a_portrait_photos_depth_from_the_image_alone() {
    let (dir, report) = common::render_photo_alone(&fixture("inv8.jpg"), "0.05");
    assert_eq!(report["depth_format"], "gdepth");
    assert_eq!(report["width"], 64);
    assert!(dir.path().join("out.png").is_file());

    // A JPEG without a depth map still needs --depth, and says so.
    let plain = fixture("no-depth.jpg");
    let run = common::brume(
        dir.path(),
        &[
            "render",
            "--image",
            plain.to_str().unwrap(),
            "--out",
            "o.png",
        ],
    );
    let err = common::stderr(&run);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(err.contains("--depth") && err.contains("GDepth"), "{err}");
    assert!(!dir.path().join("o.png").exists());
}
