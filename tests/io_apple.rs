//! An iPhone's portrait photo saved as JPEG: its depth is an auxiliary JPEG after the photo,
//! listed by a Multi-Picture Format index and described by Apple's XMP. Read from files
//! whose MPF index `tools/apple_depth_fixtures.py` wrote from the specification and
//! ExifTool read back (`tests/data/apple/`), checked against the planes they encode, and
//! from a real iPhone X portrait, checked against OpenCV's decoding of its disparity.

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
    // A relative map rescaled to a distance known in the scene: the range times S.
    let scaled = DepthOptions {
        scale: Some(3.0),
        ..DepthOptions::default()
    };
    let tripled = load_range(&fixture("portrait.jpg"), &scaled).unwrap();
    for (a, b) in tripled.range.as_slice().iter().zip(range.as_slice()) {
        assert!((a - 3.0 * b).abs() <= 1e-6 * a || (a.is_nan() && b.is_nan()));
    }
    assert!(tripled
        .notes
        .iter()
        .any(|n| n.contains("depth x 3 = metres")));
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

/// The median of `f` over the box `x0..x1` x `y0..y1`, NaN left out.
fn median_over(
    (x0, x1, y0, y1): (usize, usize, usize, usize),
    f: impl Fn(usize, usize) -> f64,
) -> f64 {
    let mut v: Vec<f64> = (y0..y1)
        .flat_map(|y| (x0..x1).map(move |x| (x, y)))
        .map(|(x, y)| f(x, y))
        .filter(|v| !v.is_nan())
        .collect();
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// `iphone-x.jpg`: a real iPhone X portrait (iOS 12; `tests/data/apple/README.md`), its
/// photo at a quarter of its size, its disparity image as the phone wrote it (576 x 768,
/// 0.650879..2.509766 1/m). The expected values were computed apart, with OpenCV's decoder
/// and numpy: the medians of the codes in a box on the vase (220) and on the wall behind it
/// (29); 663 samples at the farthest code, 0, and 6 780 within 3 codes of it: the wall
/// receding to the farthest sample, no clamp, so every sample is a depth (read as
/// stopping there, the wall's brightest strip was taken for sky); the intrinsics are the
/// file's `IntrinsicMatrix` of its 3024 x 4032 reference.
#[test]
fn a_real_iphone_portrait_is_read_and_fogged() {
    let path = fixture("iphone-x.jpg");
    let loaded = load_range(&path, &DepthOptions::default()).unwrap();
    assert_eq!(loaded.format, DepthFormat::AppleDepth);
    assert_eq!((loaded.range.width(), loaded.range.height()), (576, 768));
    assert_eq!(loaded.unknown_pixels, 0);
    let k = loaded.intrinsics.unwrap();
    let (sx, sy) = (576.0 / 3024.0, 768.0 / 4032.0);
    assert!((k.fx - 6112.78125 * sx).abs() < 1e-6 && (k.fy - 6112.78125 * sy).abs() < 1e-6);
    assert!((k.cx - ((1524.835693359375 + 0.5) * sx - 0.5)).abs() < 1e-6);
    assert!((k.cy - ((2027.0889892578125 + 0.5) * sy - 0.5)).abs() < 1e-6);
    let depth = |x: usize, y: usize| {
        let (dx, dy) = ((x as f64 - k.cx) / k.fx, (y as f64 - k.cy) / k.fy);
        f64::from(*loaded.range.get(x, y)) / (1.0 + dx * dx + dy * dy).sqrt()
    };
    let (vase, wall) = ((250, 330, 400, 480), (480, 560, 100, 200));
    let code_of = |z: f64| (1.0 / z - 0.650879) / (2.509766 - 0.650879) * 255.0;
    assert!((code_of(median_over(vase, depth)) - 220.0).abs() <= 1.0 + 1e-3);
    assert!((code_of(median_over(wall, depth)) - 29.0).abs() <= 1.0 + 1e-3);

    // Fogged at β 0.5 m⁻¹ without blur, twice (airlight 0 and 1): out = τ·J + (1 − τ)·A,
    // so τ = 1 − (out(A=1) − out(A=0)); on the photo's grid (1.3125 x the map's), τ is
    // exp(−β R) of the range the loader gave, in the vase's and the wall's boxes.
    let dir = tempfile::tempdir().unwrap();
    let green = |airlight: &str| {
        let out = dir.path().join(format!("out-{airlight}.pfm"));
        let image = path.to_str().unwrap();
        let args = ["render", "--image", image, "--beta", "0.5", "--lambda", "0"];
        let run = common::brume(
            dir.path(),
            &[
                &args[..],
                &["--airlight", airlight, "--out", out.to_str().unwrap()],
            ]
            .concat(),
        );
        assert!(run.status.success(), "{}", common::stderr(&run));
        match brume::io::depth::read_pfm(&out).unwrap() {
            brume::io::depth::Pfm::Rgb(rgb) => rgb,
            brume::io::depth::Pfm::Grey(_) => panic!("a colour PFM"),
        }
    };
    let (dark, bright) = (green("0,0,0"), green("1,1,1"));
    assert_eq!((dark.width(), dark.height()), (756, 1008));
    let tau = |x: usize, y: usize| 1.0 - f64::from(bright.get(x, y)[1] - dark.get(x, y)[1]);
    let on_photo = |(x0, x1, y0, y1): (usize, usize, usize, usize)| {
        let s = 756.0 / 576.0;
        let at = |v: usize| (v as f64 * s).round() as usize;
        (at(x0), at(x1), at(y0), at(y1))
    };
    for region in [vase, wall] {
        let range = median_over(region, |x, y| f64::from(*loaded.range.get(x, y)));
        let got = median_over(on_photo(region), tau);
        let want = (-0.5 * range).exp();
        assert!((got - want).abs() < 0.01, "{region:?}: τ {got} for {want}");
    }
}
