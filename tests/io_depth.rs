//! Depth loaders: PFM, calib.txt, Middlebury 2014/2006, 16-bit PNG formats (the datasets',
//! Android DEPTH16, ARCore and Cityscapes with its camera file), float maps; the phone
//! formats and Cityscapes also through the CLI; which loads are metric.

use std::path::{Path, PathBuf};

use brume::io::depth::{
    load_cityscapes, load_cityscapes_from_bytes, load_range, load_range_from_bytes, parse_calib,
    parse_camera_str, parse_pfm, range_from_map, read_pfm, DepthFormat, DepthKind, DepthOptions,
    LoadedDepth, Pfm, StereoView, DEPTH16_DEFAULT_MIN_CONFIDENCE,
};
use brume::io::output::write_scalar;
use brume::raster::{Grid, ScalarMap};
use brume::Error;

use crate::common::{self, npz_bytes};

/// Expects an error without printing a (large) map if there is none.
fn expect_err<T>(r: brume::Result<T>) -> Error {
    match r {
        Ok(_) => panic!("expected an error"),
        Err(e) => e,
    }
}

fn expect_format_error(r: brume::Result<impl Sized>, needle: &str) -> String {
    let err = expect_err(r);
    let msg = err.to_string();
    assert!(
        matches!(err, Error::Format { .. }),
        "not a Format error: {msg}"
    );
    assert!(msg.contains(needle), "`{msg}` should mention `{needle}`");
    msg
}

fn grey(pfm: Pfm) -> ScalarMap {
    match pfm {
        Pfm::Grey(m) => m,
        Pfm::Rgb(_) => panic!("expected a grey PFM"),
    }
}

/// A PFM built by hand; `rows_bottom_up` are the rows in file order.
fn pfm_bytes(
    magic: &str,
    w: usize,
    h: usize,
    scale: &str,
    values: &[f32],
    little: bool,
) -> Vec<u8> {
    let mut b = format!("{magic}\n{w} {h}\n{scale}\n").into_bytes();
    for v in values {
        b.extend_from_slice(&if little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        });
    }
    b
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn opts(format: DepthFormat) -> DepthOptions {
    DepthOptions {
        format,
        ..DepthOptions::default()
    }
}

fn close(a: f32, b: f64) -> bool {
    (f64::from(a) - b).abs() <= 1e-5 * b.abs().max(1.0)
}

// ---------------------------------------------------------------- PFM

#[test]
fn pfm_round_trip_is_bit_identical_with_top_row_first() {
    let dir = tempfile::tempdir().unwrap();
    let map = Grid::from_fn(3, 4, |x, y| {
        if y == 0 {
            100.0 + x as f32
        } else {
            y as f32 * 0.1 + x as f32
        }
    });
    let path = dir.path().join("m.pfm");
    write_scalar(&path, &map).unwrap();
    let back = grey(read_pfm(&path).unwrap());
    assert_eq!(back.width(), 3);
    assert_eq!(back.height(), 4);
    for (a, b) in map.as_slice().iter().zip(back.as_slice()) {
        assert_eq!(a.to_bits(), b.to_bits());
    }
    assert_eq!(*back.get(2, 0), 102.0);
    // The file stores the bottom row first.
    let bytes = std::fs::read(&path).unwrap();
    let header = b"Pf\n3 4\n-1.0\n".len();
    let first = f32::from_le_bytes(bytes[header..header + 4].try_into().unwrap());
    assert_eq!(first, *map.get(0, 3));
}

#[test]
fn pfm_little_and_big_endian_hand_built() {
    // File order: bottom row [1, 2], top row [3, 4].
    let values = [1.0, 2.0, 3.0, 4.0];
    for (scale, little) in [("-1.0", true), ("1.0", false), ("-0.5", true), ("2", false)] {
        let bytes = pfm_bytes("Pf", 2, 2, scale, &values, little);
        let map = grey(parse_pfm(&bytes, Path::new("h.pfm")).unwrap());
        assert_eq!(map.as_slice(), &[3.0, 4.0, 1.0, 2.0], "scale {scale}");
    }
    let crlf = pfm_bytes("Pf\r", 2, 1, "-1.0\r", &[1.0, 2.0], true);
    let map = grey(parse_pfm(&crlf, Path::new("crlf.pfm")).unwrap());
    assert_eq!(map.as_slice(), &[1.0, 2.0]);
    let rgb = pfm_bytes("PF", 1, 2, "-1", &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0], true);
    match parse_pfm(&rgb, Path::new("c.pfm")).unwrap() {
        Pfm::Rgb(img) => assert_eq!(img.as_slice(), &[[4.0, 5.0, 6.0], [1.0, 2.0, 3.0]]),
        Pfm::Grey(_) => panic!("PF is colour"),
    }
}

#[test]
fn pfm_bad_files_are_format_errors() {
    let p = Path::new("bad.pfm");
    let good = pfm_bytes("Pf", 2, 2, "-1.0", &[1.0; 4], true);
    expect_format_error(
        parse_pfm(&good[..good.len() - 3], p),
        "expected 2*2*4 = 16 bytes of data, found 13",
    );
    let mut long = good.clone();
    long.push(0);
    expect_format_error(parse_pfm(&long, p), "found 17");
    expect_format_error(
        parse_pfm(&pfm_bytes("P5", 2, 2, "-1", &[1.0; 4], true), p),
        "must start with `Pf`",
    );
    expect_format_error(parse_pfm(b"Pf\ntwo 2\n-1\n", p), "width");
    expect_format_error(parse_pfm(b"Pf\n2 2\nabc\n", p), "scale");
    expect_format_error(parse_pfm(b"Pf\n2 2\n0\n", p), "scale");
    expect_format_error(parse_pfm(b"Pf\n2", p), "truncated");
    expect_format_error(parse_pfm(b"", p), "truncated");
    expect_format_error(
        parse_pfm(b"Pf\n99999999999 99999999999\n-1\n", p),
        "bad.pfm",
    );
}

#[test]
fn colour_pfm_is_rejected_as_depth() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        dir.path(),
        "c.pfm",
        &pfm_bytes("PF", 1, 1, "-1", &[1.0; 3], true),
    );
    expect_format_error(
        load_range(&path, &DepthOptions::default()),
        "`Pf` (1 channel)",
    );
}

// ---------------------------------------------------------------- Middlebury 2014

const CALIB: &str = "cam0=[4161.221 0 1445.577; 0 4161.221 984.686; 0 0 1]
cam1=[4161.221 0 1654.636; 0 4161.221 984.686; 0 0 1]
doffs=209.059
baseline=176.252
width=2880
height=1988
ndisp=280
isint=0
vmin=27
vmax=260
dyavg=0
dymax=0
";

#[test]
fn calib_parses_a_realistic_file() {
    let dir = tempfile::tempdir().unwrap();
    let c = parse_calib(&write(dir.path(), "calib.txt", CALIB.as_bytes())).unwrap();
    assert_eq!(c.cam0[0], [4161.221, 0.0, 1445.577]);
    assert_eq!(c.cam1[0][2], 1654.636);
    assert_eq!(c.cam0[1][2], 984.686);
    assert_eq!((c.doffs, c.baseline), (209.059, 176.252));
    assert_eq!(
        (c.width, c.height, c.ndisp, c.isint),
        (2880, 1988, 280, false)
    );
    assert_eq!(
        (c.vmin, c.vmax, c.dyavg, c.dymax),
        (27.0, 260.0, Some(0.0), Some(0.0))
    );
    let k = c.intrinsics();
    assert_eq!(
        (k.fx, k.fy, k.cx, k.cy),
        (4161.221, 4161.221, 1445.577, 984.686)
    );
}

#[test]
fn calib_errors_name_the_key_and_file() {
    let dir = tempfile::tempdir().unwrap();
    let bad = CALIB.replace("doffs=209.059", "doffs=twelve");
    let path = write(dir.path(), "calib.txt", bad.as_bytes());
    let msg = expect_format_error(parse_calib(&path), "doffs");
    assert!(msg.contains("calib.txt"), "{msg}");
    let missing = CALIB.replace("baseline=176.252\n", "");
    let path = write(dir.path(), "calib2.txt", missing.as_bytes());
    expect_format_error(parse_calib(&path), "baseline");
    let matrix = CALIB.replace(
        "0 4161.221 984.686; 0 0 1]\ncam1",
        "0 4161.221; 0 0 1]\ncam1",
    );
    let path = write(dir.path(), "calib3.txt", matrix.as_bytes());
    expect_format_error(parse_calib(&path), "cam0");
    let path = write(dir.path(), "calib4.txt", b"just words\n");
    expect_format_error(parse_calib(&path), "key=value");
}

fn middlebury2014_dir(w: usize, h: usize, file_rows_bottom_up: &[f32]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let calib = format!(
        "cam0=[1000 0 1.5; 0 1000 0.5; 0 0 1]\ncam1=[1000 0 11.5; 0 1000 0.5; 0 0 1]\n\
         doffs=10\nbaseline=200\nwidth={w}\nheight={h}\nndisp=100\nisint=0\nvmin=1\nvmax=90\n"
    );
    write(dir.path(), "calib.txt", calib.as_bytes());
    write(
        dir.path(),
        "disp0.pfm",
        &pfm_bytes("Pf", w, h, "-1.0", file_rows_bottom_up, true),
    );
    dir
}

#[test]
fn middlebury2014_end_to_end() {
    // Bottom row: [90, inf, 40, 30]; top row: [10, 20, inf, 0].
    let inf = f32::INFINITY;
    let dir = middlebury2014_dir(4, 2, &[90.0, inf, 40.0, 30.0, 10.0, 20.0, inf, 0.0]);
    let d = load_range(&dir.path().join("disp0.pfm"), &DepthOptions::default()).unwrap();
    assert_eq!(d.format, DepthFormat::Middlebury2014);
    assert_eq!(d.kind, DepthKind::Disparity);
    assert_eq!(d.units, "m");
    assert_eq!(d.unknown_pixels, 2);
    assert!(d.notes.iter().any(|n| n.contains("calib.txt")));
    let k = d.intrinsics.unwrap();
    assert_eq!((k.fx, k.cx, k.cy), (1000.0, 1.5, 0.5));
    // f·B of the left view (disp0), for pre-processing's stereo occlusions.
    assert_eq!(d.stereo_focal_baseline, Some(1000.0 * 200.0 / 1000.0));
    let r = &d.range;
    assert!(r.get(2, 0).is_nan() && r.get(1, 1).is_nan());
    let expect = |x: f64, y: f64, disp: f64| {
        let z_mm = 200.0 * 1000.0 / (disp + 10.0);
        z_mm / 1000.0 * (1.0 + ((x - 1.5).powi(2) + (y - 0.5).powi(2)) / 1000.0f64.powi(2)).sqrt()
    };
    assert!(close(*r.get(0, 0), expect(0.0, 0.0, 10.0)));
    assert!(close(*r.get(3, 0), expect(3.0, 0.0, 0.0)));
    assert!(close(*r.get(0, 1), expect(0.0, 1.0, 90.0)));
    assert!(close(*r.get(3, 1), expect(3.0, 1.0, 30.0)));
    assert!(r.get(0, 0) > r.get(0, 1), "bigger disparity is nearer");
}

/// A right view's map (`disp1.pfm`, or any with `stereo_view` right) is aligned with the
/// right camera: its range is taken from cam1's principal point (10 px right of cam0's in
/// this calib.txt), and notes say so; `disp10.pfm` is no right view, and `stereo_view`
/// left reads `disp1.pfm` as a left one. A map that is no disparity notes the option
/// ignored.
#[test]
fn middlebury2014_right_view_takes_cam1() {
    let dir = middlebury2014_dir(4, 2, &[90.0, 80.0, 40.0, 30.0, 10.0, 20.0, 50.0, 60.0]);
    let left = load_range(&dir.path().join("disp0.pfm"), &DepthOptions::default()).unwrap();
    for name in ["disp1.pfm", "disp10.pfm"] {
        std::fs::copy(dir.path().join("disp0.pfm"), dir.path().join(name)).unwrap();
    }
    let right = load_range(&dir.path().join("disp1.pfm"), &DepthOptions::default()).unwrap();
    let k = right.intrinsics.unwrap();
    assert_eq!((k.fx, k.cx, k.cy), (1000.0, 11.5, 0.5));
    assert!(
        right.notes.iter().any(|n| n.contains("cam1")),
        "{:?}",
        right.notes
    );
    assert!(right
        .notes
        .iter()
        .any(|n| n.contains("right of nearer surfaces")));
    assert_eq!(right.stereo_focal_baseline, left.stereo_focal_baseline);
    assert_eq!(
        (left.stereo_view, right.stereo_view),
        (StereoView::Left, StereoView::Right)
    );
    let opts = |view| DepthOptions {
        stereo_view: Some(view),
        ..DepthOptions::default()
    };
    let as_view = |path: &str, view| load_range(&dir.path().join(path), &opts(view)).unwrap();
    let given = as_view("disp0.pfm", StereoView::Right);
    assert_eq!(
        (given.intrinsics, given.stereo_view),
        (right.intrinsics, StereoView::Right)
    );
    assert_eq!(
        as_view("disp1.pfm", StereoView::Left).intrinsics,
        left.intrinsics
    );
    let depth = dir.path().join("depth.exr");
    write_scalar(&depth, &Grid::from_fn(4, 2, |x, _| 1.0 + x as f32)).unwrap();
    let not_disparity = load_range(&depth, &opts(StereoView::Right)).unwrap();
    assert_eq!(not_disparity.stereo_view, StereoView::Left);
    assert!(
        (not_disparity.notes.iter()).any(|n| n.starts_with("`stereo_view` right ignored")),
        "{:?}",
        not_disparity.notes
    );
    let z = |disp: f64| 200.0 * 1000.0 / (disp + 10.0) / 1000.0;
    let ray = |x: f64, cx: f64| (1.0 + (x - cx).powi(2) / 1000.0f64.powi(2)).sqrt();
    // Top row, column 0: disparity 10, half a pixel above the principal point.
    let expect = |cx: f64| z(10.0) * (ray(0.0, cx).powi(2) + 0.25e-6).sqrt();
    assert!(close(*right.range.get(0, 0), expect(11.5)));
    assert!(close(*left.range.get(0, 0), expect(1.5)));
    assert!(right.range.get(0, 0) > left.range.get(0, 0));
    let other = load_range(&dir.path().join("disp10.pfm"), &DepthOptions::default()).unwrap();
    assert_eq!(other.intrinsics, left.intrinsics);
}

#[test]
fn bytes_in_memory_load_as_the_files_do() {
    let dir = middlebury2014_dir(2, 1, &[5.0, 7.0]);
    let (pfm, calib) = (dir.path().join("disp0.pfm"), dir.path().join("calib.txt"));
    let from_file = load_range(&pfm, &DepthOptions::default()).unwrap();
    let bytes = std::fs::read(&pfm).unwrap();
    let text = std::fs::read_to_string(&calib).unwrap();
    let from_bytes = load_range_from_bytes(
        &bytes,
        &pfm,
        &DepthOptions::default(),
        Some((&calib, &text)),
    )
    .unwrap();
    assert_eq!(from_bytes, from_file);
    // Without its calib.txt the same disparity is refused as Middlebury 2014, as on disk.
    let alone = load_range_from_bytes(&bytes, &pfm, &opts(DepthFormat::Middlebury2014), None);
    expect_format_error(alone, "calib");
    // An ignored calibration is noted, not parsed.
    let png = save_png8(dir.path(), "d.png", 1, 1, &[9]);
    let with_calib = DepthOptions {
        calib: Some(calib.clone()),
        ..DepthOptions::default()
    };
    let d = load_range_from_bytes(
        &std::fs::read(&png).unwrap(),
        &png,
        &with_calib,
        Some((&calib, "not a calib")),
    )
    .unwrap();
    assert_eq!(d, load_range(&png, &with_calib).unwrap());
    assert!(d
        .notes
        .iter()
        .any(|n| n.contains("`calib`") && n.contains("ignored")));
}

/// A map in memory reads as a float file of it (range, units, kind, intrinsics, notes)
/// for every kind; side files and file layouts are refused, naming the map.
#[test]
fn a_map_in_memory_reads_as_a_float_file_of_it() {
    let dir = tempfile::tempdir().unwrap();
    let map: ScalarMap = Grid::from_fn(6, 4, |x, y| 0.2 + 0.05 * x as f32 + 0.01 * y as f32);
    let path = dir.path().join("map.pfm");
    write_scalar(&path, &map).unwrap();
    let geometry = DepthOptions {
        fov: Some(50.0),
        ..DepthOptions::default()
    };
    let cases = [
        (DepthKind::Depth, geometry.clone()),
        (
            DepthKind::Range,
            DepthOptions {
                scale: Some(2.0),
                ..DepthOptions::default()
            },
        ),
        (
            DepthKind::Disparity,
            DepthOptions {
                focal: Some(40.0),
                baseline: Some(100.0),
                disparity_offset: Some(0.5),
                ..DepthOptions::default()
            },
        ),
        (DepthKind::Inverse, geometry.clone()),
        (
            DepthKind::Affine,
            DepthOptions {
                near: Some(1.5),
                far: Some(40.0),
                ..geometry.clone()
            },
        ),
        (
            DepthKind::ZBuffer,
            DepthOptions {
                near: Some(0.1),
                far: Some(100.0),
                ..geometry
            },
        ),
    ];
    for (kind, opts) in cases {
        let opts = DepthOptions {
            kind: Some(kind),
            ..opts
        };
        let from_map = range_from_map(map.clone(), "depth", &opts).unwrap();
        let from_file = load_range(&path, &opts).unwrap();
        assert_eq!(from_map, from_file, "{kind}");
    }
    for (opts, needle) in [
        (
            DepthOptions {
                camera: Some(dir.path().join("camera.json")),
                ..DepthOptions::default()
            },
            "invalid camera",
        ),
        (
            DepthOptions {
                calib: Some(dir.path().join("calib.txt")),
                ..DepthOptions::default()
            },
            "invalid calib",
        ),
        (
            opts(DepthFormat::Kitti),
            "depth: `depth_format` kitti expects",
        ),
    ] {
        let e = expect_err(range_from_map(map.clone(), "depth", &opts)).to_string();
        assert!(e.contains(needle), "{needle}: {e}");
    }
}

#[test]
fn middlebury2014_size_disagreement_and_missing_calib() {
    let dir = middlebury2014_dir(5, 2, &[1.0; 8]);
    // The PFM is 4x2 but calib says 5x2.
    write(
        dir.path(),
        "disp0.pfm",
        &pfm_bytes("Pf", 4, 2, "-1", &[1.0; 8], true),
    );
    let err = expect_err(load_range(
        &dir.path().join("disp0.pfm"),
        &DepthOptions::default(),
    ));
    assert!(matches!(err, Error::SizeMismatch { .. }), "{err}");
    std::fs::remove_file(dir.path().join("calib.txt")).unwrap();
    expect_format_error(
        load_range(
            &dir.path().join("disp0.pfm"),
            &opts(DepthFormat::Middlebury2014),
        ),
        "give it as `calib`",
    );
    // Without calib, Auto reads a PFM as a float depth map.
    let d = load_range(&dir.path().join("disp0.pfm"), &DepthOptions::default()).unwrap();
    assert_eq!((d.format, d.kind), (DepthFormat::Float, DepthKind::Depth));
    assert!(d
        .notes
        .iter()
        .any(|n| n == "no intrinsics: depth used as range"));
    // The warning's shortfall: the corner pixel's ray at a 45° vertical field of view,
    // from its offsets to the centre over the focal length.
    let (w, h) = (d.range.width() as f64, d.range.height() as f64);
    let focal = (h / 2.0) / 22.5f64.to_radians().tan();
    let ray = (1.0 + ((w / 2.0).powi(2) + (h / 2.0).powi(2)) / focal.powi(2)).sqrt();
    let warning = d.depth_as_range_warning().expect("depth used as range");
    let expected = format!(
        "{:.0} % short in this {w}x{h} frame's corners",
        100.0 * (1.0 - 1.0 / ray)
    );
    assert!(warning.contains(&expected), "{warning} / {expected}");
    let opts = DepthOptions {
        fov: Some(45.0),
        ..DepthOptions::default()
    };
    let d = load_range(&dir.path().join("disp0.pfm"), &opts).unwrap();
    assert_eq!(d.depth_as_range_warning(), None);
}

// ---------------------------------------------------------------- 8- and 16-bit PNG

fn save_png8(dir: &Path, name: &str, w: u32, h: u32, v: &[u8]) -> PathBuf {
    let p = dir.join(name);
    image::save_buffer(&p, v, w, h, image::ExtendedColorType::L8).unwrap();
    p
}

fn save_png16(dir: &Path, name: &str, w: u32, h: u32, v: &[u16]) -> PathBuf {
    let p = dir.join(name);
    let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_ne_bytes()).collect();
    image::save_buffer(&p, &bytes, w, h, image::ExtendedColorType::L16).unwrap();
    p
}

#[test]
fn middlebury2006_png_zero_is_unknown_and_defaults_apply() {
    let dir = tempfile::tempdir().unwrap();
    let p = save_png8(dir.path(), "disp.png", 3, 1, &[0, 100, 200]);
    let d = load_range(&p, &DepthOptions::default()).unwrap();
    assert_eq!(d.format, DepthFormat::Middlebury2006);
    assert_eq!(d.unknown_pixels, 1);
    assert!(d.range.get(0, 0).is_nan());
    assert!(d
        .notes
        .iter()
        .any(|n| n.contains("3740") && n.contains("160") && n.contains("270")));
    assert!(d.notes.iter().any(|n| n.contains("principal point")));
    // Pixel 1 is the centre column: range = depth there.
    assert!(close(
        *d.range.get(1, 0),
        3740.0 * 160.0 / (100.0 + 270.0) / 1000.0
    ));
    let custom = DepthOptions {
        focal: Some(1000.0),
        baseline: Some(100.0),
        disparity_offset: Some(0.0),
        ..DepthOptions::default()
    };
    let d = load_range(&p, &custom).unwrap();
    assert!(close(*d.range.get(1, 0), 1.0));
    assert_eq!(d.stereo_focal_baseline, Some(1000.0 * 100.0 / 1000.0));
    let bad = DepthOptions {
        disparity_offset: Some(-150.0),
        ..DepthOptions::default()
    };
    let err = expect_err(load_range(&p, &bad));
    assert!(err.to_string().contains("-150"), "{err}");
    // The datasets' views are numbered from the left: disp1.png the left one's, disp5.png
    // the right one's.
    for (name, view) in [
        ("disp1.png", StereoView::Left),
        ("disp5.png", StereoView::Right),
        ("disp50.png", StereoView::Left),
    ] {
        let p = save_png8(dir.path(), name, 3, 1, &[0, 100, 200]);
        let d = load_range(&p, &DepthOptions::default()).unwrap();
        assert_eq!(d.stereo_view, view, "{name}");
    }
}

#[test]
fn real_aloe_disparity_loads() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/aloe/disparity.png");
    // The sample is part of the repository: a missing file is a failure, not a skip.
    assert!(
        path.exists(),
        "{} is missing: restore tests/data/aloe/ from the repository",
        path.display()
    );
    let d = load_range(&path, &DepthOptions::default()).unwrap();
    assert_eq!((d.range.width(), d.range.height()), (1282, 1110));
    assert_eq!(d.unknown_pixels, 49_130);
    // Undo the ray stretch: depth must be a strictly decreasing function of disparity.
    let k = d.intrinsics.unwrap();
    let raw = image::open(&path).unwrap().to_luma8();
    let mut depth_of = [f64::NAN; 256];
    for (x, y, p) in raw.enumerate_pixels() {
        let v = usize::from(p.0[0]);
        if v == 0 {
            continue;
        }
        let depth = f64::from(*d.range.get(x as usize, y as usize))
            / k.range_per_depth(x as usize, y as usize);
        if depth_of[v].is_nan() {
            depth_of[v] = depth;
        }
        assert!((depth - depth_of[v]).abs() < 1e-5 * depth, "disparity {v}");
    }
    let known: Vec<(usize, f64)> = (1..256)
        .filter(|&v| !depth_of[v].is_nan())
        .map(|v| (v, depth_of[v]))
        .collect();
    assert!(known.len() > 100);
    for w in known.windows(2) {
        assert!(
            w[0].1 > w[1].1,
            "disparity {} -> {} m but {} -> {} m",
            w[0].0,
            w[0].1,
            w[1].0,
            w[1].1
        );
    }
    for (v, r) in d.range.as_slice().iter().zip(raw.as_raw()) {
        assert_eq!(v.is_nan(), *r == 0);
    }
}

#[test]
fn sixteen_bit_png_scales() {
    let dir = tempfile::tempdir().unwrap();
    let p = save_png16(dir.path(), "d.png", 3, 1, &[0, 5000, 65535]);
    for (format, metres_per_unit) in [
        (DepthFormat::Kitti, 1.0 / 256.0),
        (DepthFormat::Nyu, 1.0 / 1000.0),
        (DepthFormat::Tum, 1.0 / 5000.0),
    ] {
        let d = load_range(&p, &opts(format)).unwrap();
        assert_eq!(
            (d.format, d.kind, d.unknown_pixels),
            (format, DepthKind::Depth, 1)
        );
        assert!(d.range.get(0, 0).is_nan());
        assert!(
            close(*d.range.get(1, 0), 5000.0 * metres_per_unit),
            "{format}"
        );
        assert!(
            close(*d.range.get(2, 0), 65535.0 * metres_per_unit),
            "{format}"
        );
        assert!(d.intrinsics.is_none());
    }
    let scaled = DepthOptions {
        scale: Some(0.01),
        ..DepthOptions::default()
    };
    let d = load_range(&p, &scaled).unwrap();
    assert_eq!(d.format, DepthFormat::Png16);
    assert!(close(*d.range.get(1, 0), 50.0));
    // With a focal, depth is stretched to range off the centre.
    let focal = DepthOptions {
        focal: Some(2.0),
        ..opts(DepthFormat::Tum)
    };
    let d = load_range(&p, &focal).unwrap();
    let expect = 65535.0 / 5000.0 * (1.0f64 + 0.25).sqrt();
    assert!(close(*d.range.get(2, 0), expect));
    assert!(d.notes.iter().any(|n| n.contains("principal point")));
}

#[test]
fn sixteen_bit_png_without_format_or_scale_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let p = save_png16(dir.path(), "d.png", 2, 1, &[1, 2]);
    expect_format_error(
        load_range(&p, &DepthOptions::default()),
        "`depth_format` kitti, nyu or tum",
    );
    // A monocular model's output (Depth Anything's 16-bit PNG) is pointed to its kind,
    // which reads it.
    expect_format_error(
        load_range(&p, &DepthOptions::default()),
        "Depth Anything or MiDaS: `depth_kind` inverse",
    );
    let inverse = DepthOptions {
        kind: Some(DepthKind::Inverse),
        ..DepthOptions::default()
    };
    assert!(load_range(&p, &inverse).is_ok());
    let err = expect_err(load_range(&p, &opts(DepthFormat::Png16)));
    // The library names the parameter; the CLI shows it as --depth-scale.
    assert!(err.to_string().contains("invalid depth_scale"), "{err}");
    expect_format_error(load_range(&p, &opts(DepthFormat::Middlebury2006)), "8-bit");
}

#[test]
fn all_unknown_is_no_valid_depth() {
    let dir = tempfile::tempdir().unwrap();
    let p = save_png16(dir.path(), "zeros.png", 2, 2, &[0; 4]);
    let err = expect_err(load_range(&p, &opts(DepthFormat::Kitti)));
    assert!(matches!(err, Error::NoValidDepth { .. }), "{err}");
}

// ---------------------------------------------------------------- float maps

fn check_float_map(d: &LoadedDepth) {
    // Source values: [1, NaN, inf, -2, 0, 5].
    assert_eq!((d.format, d.kind), (DepthFormat::Float, DepthKind::Depth));
    assert_eq!(d.units, "file units");
    assert_eq!(d.unknown_pixels, 4);
    assert_eq!((d.range.width(), d.range.height()), (3, 2));
    assert_eq!(*d.range.get(0, 0), 1.0);
    assert_eq!(*d.range.get(2, 1), 5.0);
    for (x, y) in [(1, 0), (2, 0), (0, 1), (1, 1)] {
        assert!(d.range.get(x, y).is_nan(), "({x}, {y})");
    }
}

const FLOATS: [f32; 6] = [1.0, f32::NAN, f32::INFINITY, -2.0, 0.0, 5.0];

#[test]
fn exr_float_map_picks_the_depth_channel() {
    use exr::prelude::*;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("d.exr");
    let channels = AnyChannels::sort(SmallVec::from_vec(vec![
        AnyChannel::new("G", FlatSamples::F32(vec![7.0; 6])),
        AnyChannel::new("Z", FlatSamples::F32(FLOATS.to_vec())),
    ]));
    let layer = Layer::new(
        (3, 2),
        LayerAttributes::default(),
        Encoding::UNCOMPRESSED,
        channels,
    );
    Image::from_layer(layer).write().to_file(&path).unwrap();
    check_float_map(&load_range(&path, &DepthOptions::default()).unwrap());

    let two = AnyChannels::sort(SmallVec::from_vec(vec![
        AnyChannel::new("G", FlatSamples::F32(vec![7.0; 6])),
        AnyChannel::new("B", FlatSamples::F32(vec![7.0; 6])),
    ]));
    let layer = Layer::new(
        (3, 2),
        LayerAttributes::default(),
        Encoding::UNCOMPRESSED,
        two,
    );
    let bad = dir.path().join("gb.exr");
    Image::from_layer(layer).write().to_file(&bad).unwrap();
    expect_format_error(
        load_range(&bad, &DepthOptions::default()),
        "expected a depth channel",
    );
}

/// The channel the depth loader reads from a 3x2 EXR whose channel `i` holds `i + 1`
/// everywhere (parts in order, then channels in the order given), or the error.
fn chosen_channel(parts: Vec<(Option<&str>, Vec<&str>)>) -> brume::Result<f32> {
    let mut value = 0.0;
    let parts = parts
        .into_iter()
        .map(|(name, channels)| {
            let channels = channels
                .into_iter()
                .map(|c| {
                    value += 1.0;
                    (c, common::f32s(&[value; 6]))
                })
                .collect();
            (name, channels)
        })
        .collect();
    let bytes = common::exr_bytes(3, 2, parts);
    let d = load_range_from_bytes(&bytes, Path::new("d.exr"), &opts(DepthFormat::Float), None)?;
    Ok(*d.range.get(2, 1))
}

#[test]
fn exr_depth_channels_as_engines_and_tools_name_them() {
    let flat = |channels: &[&'static str]| vec![(None, channels.to_vec())];
    let blender = [
        "ViewLayer.Combined.R",
        "ViewLayer.Combined.G",
        "ViewLayer.Combined.B",
        "ViewLayer.Combined.A",
        "ViewLayer.Depth.Z",
        "ViewLayer.Mist.Z",
        "ViewLayer.Normal.X",
        "ViewLayer.Normal.Y",
        "ViewLayer.Normal.Z",
    ];
    // (channels, the 1-based index of the one that must be read)
    let cases: [(&[&str], f32); 9] = [
        (&["R", "G", "B", "A", "Z"], 5.0),
        (&blender, 5.0),
        (&["R", "G", "B", "depth.Z"], 4.0), // Nuke
        (&["Depth.Z", "R", "G", "B"], 1.0),
        // A Z in a depth layer before one in another layer, both before a flat Y.
        (&["Y", "camera.Z", "depth.Z"], 3.0),
        (&["Y", "camera.Z"], 2.0),
        // A depth channel before the red of a colour image.
        (&["R", "G", "B", "depth"], 4.0),
        (&["R", "G", "B", "Depth"], 4.0),
        (&["distance"], 1.0),
    ];
    for (channels, want) in cases {
        assert_eq!(
            chosen_channel(flat(channels)).unwrap(),
            want,
            "{channels:?}"
        );
    }
    // Neither a vector's Z or Y (normals, positions) nor Blender's mist factor is depth.
    for channels in [
        &[
            "ViewLayer.Mist.Z",
            "ViewLayer.Normal.X",
            "ViewLayer.Normal.Y",
            "ViewLayer.Normal.Z",
        ][..],
        &["X", "Y", "Z"],
    ] {
        let err = expect_err(chosen_channel(flat(channels)));
        assert!(
            err.to_string().contains("expected a depth channel"),
            "{err}"
        );
    }
    // Multi-part: the part's name is the layer. The decoder alone would read the first
    // part with a `Z`.
    let parts = vec![
        (Some("beauty"), vec!["B", "G", "R", "Z"]),
        (Some("ViewLayer.Depth"), vec!["Z"]),
    ];
    assert_eq!(chosen_channel(parts).unwrap(), 5.0);
}

#[test]
fn one_exr_holds_the_colour_and_the_depth() {
    // What Blender and engine capture tools write: `render --image f.exr --depth f.exr`.
    let dir = tempfile::tempdir().unwrap();
    let z = [2.0f32, 3.0, 4.0, 5.0, 6.0, 1e10];
    let colour = [0.25f32, 2.5, 0.0, 1.0, 0.5, 40.0];
    let files = [
        (
            "flat.exr",
            vec![
                ("R", colour),
                ("G", colour),
                ("B", colour),
                ("A", [1.0; 6]),
                ("Z", z),
            ],
        ),
        (
            "blender.exr",
            vec![
                ("ViewLayer.Combined.R", colour),
                ("ViewLayer.Combined.G", colour),
                ("ViewLayer.Combined.B", colour),
                ("ViewLayer.Combined.A", [1.0; 6]),
                ("ViewLayer.Depth.Z", z),
            ],
        ),
    ];
    for (name, channels) in files {
        let channels = channels
            .into_iter()
            .map(|(c, v)| (c, common::f32s(&v)))
            .collect();
        let path = write(
            dir.path(),
            name,
            &common::exr_bytes(3, 2, vec![(None, channels)]),
        );
        let image = brume::io::image::load_linear_rgb(&path).unwrap();
        let depth = load_range(&path, &DepthOptions::default()).unwrap();
        assert_eq!(
            (depth.format, depth.kind),
            (DepthFormat::Float, DepthKind::Depth)
        );
        // Blender's background (1e10, where nothing was drawn) is a clamp: unknown, the
        // sky; read as it is with `sky_beyond` inf.
        let kept = DepthOptions {
            sky_beyond: Some(f64::INFINITY),
            ..DepthOptions::default()
        };
        let as_written = load_range(&path, &kept).unwrap();
        for i in 0..6 {
            let (x, y) = (i % 3, i / 3);
            assert_eq!(*image.get(x, y), [colour[i]; 3], "{name} {i}");
            let got = *depth.range.get(x, y);
            match z[i] {
                1e10 => assert!(got.is_nan(), "{name} {i}: {got}"),
                z => assert_eq!(got, z, "{name} {i}"),
            }
            assert_eq!(*as_written.range.get(x, y), z[i], "{name} {i}");
        }
        // Planar depth with a field of view becomes range: longer off the axis.
        let with_fov = DepthOptions {
            kind: Some(DepthKind::Depth),
            fov: Some(60.0),
            ..DepthOptions::default()
        };
        let range = load_range(&path, &with_fov).unwrap().range;
        assert!(*range.get(0, 0) > z[0], "{name}");
    }
}

#[test]
fn tiff_float_map() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("d.tif");
    let file = std::fs::File::create(&path).unwrap();
    let mut enc = tiff::encoder::TiffEncoder::new(file).unwrap();
    enc.write_image::<tiff::encoder::colortype::Gray32Float>(3, 2, &FLOATS)
        .unwrap();
    check_float_map(&load_range(&path, &DepthOptions::default()).unwrap());

    // 16-bit integers hold what a 16-bit PNG does; 8-bit ones no depth.
    let ints = dir.path().join("i.tiff");
    let mut enc = tiff::encoder::TiffEncoder::new(std::fs::File::create(&ints).unwrap()).unwrap();
    enc.write_image::<tiff::encoder::colortype::Gray16>(2, 1, &[0, 2560])
        .unwrap();
    let kitti = load_range(&ints, &opts(DepthFormat::Kitti)).unwrap();
    assert!(kitti.range.get(0, 0).is_nan());
    assert_eq!(*kitti.range.get(1, 0), 10.0);
    expect_format_error(
        load_range(&ints, &DepthOptions::default()),
        "16-bit depth (a PNG, a 16-bit TIFF or a uint16 array) has no standard scale",
    );
    let bytes = dir.path().join("b.tiff");
    let mut enc = tiff::encoder::TiffEncoder::new(std::fs::File::create(&bytes).unwrap()).unwrap();
    enc.write_image::<tiff::encoder::colortype::Gray8>(1, 1, &[3])
        .unwrap();
    expect_format_error(
        load_range(&bytes, &DepthOptions::default()),
        "expected 32- or 64-bit floats (or 16-bit integers",
    );
}

#[test]
fn npy_float32_and_float64() {
    let dir = tempfile::tempdir().unwrap();
    let f32s: Vec<u8> = FLOATS.iter().flat_map(|v| v.to_le_bytes()).collect();
    let p = write(
        dir.path(),
        "a.npy",
        &common::npy_bytes("<f4", "(2, 3)", false, &f32s),
    );
    check_float_map(&load_range(&p, &DepthOptions::default()).unwrap());
    let f64s: Vec<u8> = FLOATS
        .iter()
        .flat_map(|v| f64::from(*v).to_le_bytes())
        .collect();
    let p = write(
        dir.path(),
        "b.npy",
        &common::npy_bytes("<f8", "(2, 3)", false, &f64s),
    );
    check_float_map(&load_range(&p, &DepthOptions::default()).unwrap());
    // Fortran order: column-major storage of the same 2x3 array.
    let cols: Vec<u8> = [0, 3, 1, 4, 2, 5]
        .iter()
        .flat_map(|&i| FLOATS[i].to_be_bytes())
        .collect();
    let p = write(
        dir.path(),
        "c.npy",
        &common::npy_bytes(">f4", "(2, 3)", true, &cols),
    );
    check_float_map(&load_range(&p, &DepthOptions::default()).unwrap());

    let p = write(
        dir.path(),
        "i.npy",
        &common::npy_bytes("<i4", "(1, 1)", false, &[0, 0, 0, 1]),
    );
    expect_format_error(
        load_range(&p, &DepthOptions::default()),
        "expected float16, float32 or float64 (or uint16",
    );
    let p = write(
        dir.path(),
        "t.npy",
        &common::npy_bytes("<f4", "(2, 3)", false, &f32s[..10]),
    );
    expect_format_error(load_range(&p, &DepthOptions::default()), "t.npy");
    let p = write(
        dir.path(),
        "s.npy",
        &common::npy_bytes("<f4", "(6,)", false, &f32s),
    );
    expect_format_error(load_range(&p, &DepthOptions::default()), "(height, width)");
}

#[test]
fn npy_float16_uint16_and_npz_archives() {
    let dir = tempfile::tempdir().unwrap();
    // float16, as a model run in half precision saves its depth.
    let f16s: Vec<u8> = FLOATS
        .iter()
        .flat_map(|v| half::f16::from_f32(*v).to_le_bytes())
        .collect();
    let half_npy = common::npy_bytes("<f2", "(2, 3)", false, &f16s);
    let p = write(dir.path(), "h.npy", &half_npy);
    check_float_map(&load_range(&p, &DepthOptions::default()).unwrap());

    // Depth Pro's output: `np.savez_compressed(path, depth=depth)`; a stored archive of one
    // array (`np.savez(path, array)`, named arr_0); the depth picked among several.
    let f32s: Vec<u8> = FLOATS.iter().flat_map(|v| v.to_le_bytes()).collect();
    let npy = common::npy_bytes("<f4", "(2, 3)", false, &f32s);
    let focal = common::npy_bytes("<f4", "(1, 1)", false, &1234f32.to_le_bytes());
    for (name, arrays, deflated) in [
        ("pro.npz", vec![("depth", half_npy.clone())], true),
        ("one.npz", vec![("arr_0", npy.clone())], false),
        (
            "two.npz",
            vec![("f_px", focal.clone()), ("depth", npy.clone())],
            true,
        ),
    ] {
        let p = write(dir.path(), name, &npz_bytes(&arrays, deflated));
        check_float_map(&load_range(&p, &DepthOptions::default()).unwrap());
    }
    let p = write(
        dir.path(),
        "many.npz",
        &npz_bytes(&[("a", npy.clone()), ("b", focal)], false),
    );
    expect_format_error(
        load_range(&p, &DepthOptions::default()),
        "holds 2 arrays (a, b) and none is named 'depth'",
    );
    // Depth Pro's prediction saved whole (`np.savez(path, **prediction)`): its focal length
    // turns the depth into range as `focal` would, unless `focal` or `fov` is given.
    let f_px = common::npy_bytes("<f4", "()", false, &800f32.to_le_bytes());
    let depth = common::npy_bytes(
        "<f4",
        "(2, 3)",
        false,
        &[10f32; 6].map(f32::to_le_bytes).concat(),
    );
    let whole = [("depth", depth.clone()), ("focallength_px", f_px)];
    let p = write(dir.path(), "whole.npz", &npz_bytes(&whole, true));
    let plain = write(dir.path(), "plain.npy", &depth);
    let with_focal = DepthOptions {
        focal: Some(800.0),
        ..DepthOptions::default()
    };
    let from_archive = load_range(&p, &DepthOptions::default()).unwrap();
    let from_option = load_range(&plain, &with_focal).unwrap();
    assert_eq!(from_archive.range.as_slice(), from_option.range.as_slice());
    assert!(*from_archive.range.get(0, 0) > 10.0);
    assert!(from_archive
        .notes
        .iter()
        .any(|n| n.contains("'focallength_px': 800.00 px")));
    let fov = DepthOptions {
        fov: Some(60.0),
        ..DepthOptions::default()
    };
    let overridden = load_range(&p, &fov).unwrap();
    assert!(overridden
        .notes
        .iter()
        .any(|n| n.contains("used instead of the archive's")));
    assert_ne!(overridden.range.as_slice(), from_archive.range.as_slice());
    let two = common::npy_bytes(
        "<f8",
        "(2,)",
        false,
        &[1f64, 2.0].map(f64::to_le_bytes).concat(),
    );
    let p = write(
        dir.path(),
        "two.npz",
        &npz_bytes(&[("depth", depth), ("focallength_px", two)], false),
    );
    expect_format_error(
        load_range(&p, &DepthOptions::default()),
        "array 'focallength_px': shape [2]; expected one focal length in pixels",
    );
    let p = write(dir.path(), "none.npz", &npz_bytes(&[], false));
    expect_format_error(load_range(&p, &DepthOptions::default()), "holds no array");
    let p = write(
        dir.path(),
        "cut.npz",
        &npz_bytes(&[("depth", npy)], true)[..60],
    );
    expect_format_error(load_range(&p, &DepthOptions::default()), "cut.npz");
    let ints = common::npy_bytes("<i4", "(1, 1)", false, &[0, 0, 0, 1]);
    let p = write(dir.path(), "int.npz", &npz_bytes(&[("depth", ints)], true));
    expect_format_error(
        load_range(&p, &DepthOptions::default()),
        "array 'depth': array dtype is '<i4'",
    );

    // uint16 holds what a 16-bit PNG does (RealSense or Kinect millimetres saved with
    // np.save): the same formats read it, and without one it has no scale.
    let mm: Vec<u8> = [0u16, 1000, 2560, 65535, 7, 512]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let p = write(
        dir.path(),
        "mm.npy",
        &common::npy_bytes("<u2", "(2, 3)", false, &mm),
    );
    let kitti = load_range(&p, &opts(DepthFormat::Kitti)).unwrap();
    assert_eq!(kitti.unknown_pixels, 1);
    assert!(kitti.range.get(0, 0).is_nan());
    for (x, y, v) in [
        (1, 0, 1000.0),
        (2, 0, 2560.0),
        (0, 1, 65535.0),
        (2, 1, 512.0),
    ] {
        assert_eq!(*kitti.range.get(x, y), v / 256.0, "({x}, {y})");
    }
    expect_format_error(
        load_range(&p, &DepthOptions::default()),
        "16-bit depth (a PNG, a 16-bit TIFF or a uint16 array) has no standard scale",
    );
    expect_format_error(
        load_range(&p, &opts(DepthFormat::Float)),
        "found 16-bit integers (a PNG, a 16-bit TIFF or a uint16 array)",
    );
}

#[test]
fn float_disparity_needs_focal_and_baseline() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "d.pfm",
        &pfm_bytes("Pf", 3, 1, "-1", &[10.0, -5.0, 0.0], true),
    );
    let disparity = DepthOptions {
        kind: Some(DepthKind::Disparity),
        ..DepthOptions::default()
    };
    let err = expect_err(load_range(&p, &disparity));
    assert!(err.to_string().contains("`focal`"), "{err}");
    let with_focal = DepthOptions {
        focal: Some(100.0),
        ..disparity.clone()
    };
    let err = expect_err(load_range(&p, &with_focal));
    assert!(err.to_string().contains("`baseline`"), "{err}");
    let full = DepthOptions {
        baseline: Some(50.0),
        disparity_offset: Some(6.0),
        ..with_focal
    };
    let d = load_range(&p, &full).unwrap();
    assert_eq!(d.kind, DepthKind::Disparity);
    // -5 + 6 > 0 is known, 0 + 6 too; x = 1 is the centre column.
    assert_eq!(d.unknown_pixels, 0);
    assert!(close(*d.range.get(1, 0), 100.0 * 50.0 / 1.0 / 1000.0));
    assert_eq!(d.stereo_focal_baseline, Some(100.0 * 50.0 / 1000.0));
    let no_offset = DepthOptions {
        disparity_offset: None,
        ..full
    };
    assert_eq!(load_range(&p, &no_offset).unwrap().unknown_pixels, 2);
}

/// A matcher's disparity as a 16-bit PNG (KITTI's stereo layout: d = value / 256) reads with
/// its focal length and baseline, and carries f·B for pre-processing's stereo occlusions.
#[test]
fn png16_disparity_reads_with_focal_and_baseline() {
    let dir = tempfile::tempdir().unwrap();
    let p = save_png16(dir.path(), "disp.png", 3, 1, &[0, 256 * 10, 256 * 20]);
    let opts = DepthOptions {
        format: DepthFormat::Png16,
        kind: Some(DepthKind::Disparity),
        scale: Some(1.0 / 256.0),
        focal: Some(100.0),
        baseline: Some(500.0),
        ..DepthOptions::default()
    };
    let d = load_range(&p, &opts).unwrap();
    assert_eq!(d.unknown_pixels, 1);
    // x = 1 is the centre column: range = depth = f·B/d there.
    assert!(close(*d.range.get(1, 0), 100.0 * 0.5 / 10.0));
    assert_eq!(d.stereo_focal_baseline, Some(100.0 * 500.0 / 1000.0));
}

/// A street's depth (near at the bottom, far toward the horizon) loads without a word; its
/// inverse, a disparity or a monocular model's inverse depth read as depth, is named, with
/// what to give instead. Read as what it is, or with too little known, it is not.
#[test]
fn a_map_whose_values_grow_toward_the_bottom_is_called_inverted() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (40, 60);
    // A level road seen from 1.5 m: depth 1.5·f / (y − horizon) below the horizon at row
    // 20, a far facade (80 m) above it.
    let depth = |y: usize| {
        if y > 22 {
            1.5 * 50.0 / (y - 20) as f32
        } else {
            80.0
        }
    };
    let street: ScalarMap = Grid::from_fn(w, h, |_, y| depth(y));
    let inverse: ScalarMap = Grid::from_fn(w, h, |_, y| 1.0 / depth(y));
    let load = |name: &str, map: &ScalarMap, opts: &DepthOptions| {
        let path = dir.path().join(name);
        write_scalar(&path, map).unwrap();
        load_range(&path, opts).unwrap()
    };
    let plain = DepthOptions::default();
    let d = load("street.pfm", &street, &plain);
    assert_eq!(d.inverted_warning(), None);
    assert!(!d.warnings().iter().any(|w| w.contains("bottom")));
    let d = load("inverse.pfm", &inverse, &plain);
    let warning = d
        .inverted_warning()
        .expect("an inverse depth read as depth is named");
    for said in ["bottom", "`depth_kind` disparity", "`depth_kind` inverse"] {
        assert!(warning.contains(said), "{said}: {warning}");
    }
    assert!(d.warnings().contains(&warning));
    let as_inverse = DepthOptions {
        kind: Some(DepthKind::Inverse),
        fov: Some(50.0),
        ..DepthOptions::default()
    };
    assert_eq!(
        load("inverse.pfm", &inverse, &as_inverse).inverted_warning(),
        None
    );
    // One known value in the bottom tenth: too few to judge.
    let sparse: ScalarMap = Grid::from_fn(w, h, |x, y| {
        if y < 30 || (y == h - 1 && x == 0) {
            1.0 / depth(y)
        } else {
            f32::NAN
        }
    });
    assert_eq!(load("sparse.pfm", &sparse, &plain).inverted_warning(), None);
}

#[test]
fn range_kind_is_not_converted() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "r.pfm",
        &pfm_bytes("Pf", 3, 1, "-1", &[4.0, 5.0, 6.0], true),
    );
    let o = DepthOptions {
        kind: Some(DepthKind::Range),
        focal: Some(1.0),
        ..DepthOptions::default()
    };
    let d = load_range(&p, &o).unwrap();
    assert_eq!(
        d.range.as_slice(),
        &[6.0, 5.0, 4.0][..]
            .iter()
            .rev()
            .copied()
            .collect::<Vec<_>>()[..]
    );
    assert!(d.intrinsics.is_none());
}

#[test]
fn wrong_kind_for_format_and_unknown_extension() {
    let dir = tempfile::tempdir().unwrap();
    let p = save_png8(dir.path(), "d.png", 1, 1, &[5]);
    let o = DepthOptions {
        kind: Some(DepthKind::Depth),
        ..DepthOptions::default()
    };
    let err = expect_err(load_range(&p, &o));
    assert!(matches!(err, Error::InvalidParameter { .. }), "{err}");
    let p = write(dir.path(), "d.bmp", b"BM");
    expect_format_error(load_range(&p, &DepthOptions::default()), ".exr");
    let p = write(dir.path(), "d.png", b"\x89PNG\r\n\x1a\n\0\0");
    expect_format_error(load_range(&p, &DepthOptions::default()), "d.png");
}

#[test]
fn kind_and_format_parse_and_print() {
    for k in [DepthKind::Depth, DepthKind::Range, DepthKind::Disparity] {
        assert_eq!(k.to_string().parse::<DepthKind>().unwrap(), k);
    }
    let names =
        "auto middlebury2014 middlebury2006 kitti nyu tum png16 float android-depth16 arcore";
    for name in names.split(' ') {
        assert_eq!(name.parse::<DepthFormat>().unwrap().to_string(), name);
    }
    assert_eq!("KITTI".parse::<DepthFormat>().unwrap(), DepthFormat::Kitti);
    assert_eq!(
        " Android-Depth16".parse::<DepthFormat>().unwrap(),
        DepthFormat::AndroidDepth16
    );
    let err = "lidar".parse::<DepthFormat>().unwrap_err().to_string();
    assert!(
        err.contains("lidar")
            && err.contains("middlebury2014")
            && err.contains("android-depth16")
            && err.contains("arcore"),
        "{err}"
    );
    let err = "far".parse::<DepthKind>().unwrap_err().to_string();
    assert!(err.contains("far") && err.contains("disparity"), "{err}");
}

/// Range over depth at pixel `(x, y)` of a `w` x `h` map with its principal point at the
/// centre and focal length `focal` px: the length of the ray through it at depth 1.
fn ray_length(x: usize, y: usize, (w, h): (usize, usize), focal: f64) -> f64 {
    let (u, v) = (
        (x as f64 - (w as f64 - 1.0) / 2.0) / focal,
        (y as f64 - (h as f64 - 1.0) / 2.0) / focal,
    );
    (1.0 + u * u + v * v).sqrt()
}

/// A monocular estimator's relative inverse depth (`depth_kind` inverse): depth =
/// S/(d + offset) along the optical axis, then range with `fov`; d + offset ≤ 0 (the
/// sky) unknown; relative units, or metres with `scale`; a 16-bit PNG read as png16
/// without a scale.
#[test]
fn relative_inverse_depth_becomes_range() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h, fov) = (6usize, 4usize, 60.0f64);
    let focal = h as f64 / 2.0 / (fov.to_radians() / 2.0).tan();
    let values = [0.0f32, -0.5, 0.25, 1.0, 7.5, f32::NAN];
    let map = Grid::from_fn(w, h, |x, y| values[(x + y) % values.len()]);
    let pfm = dir.path().join("inverse.pfm");
    write_scalar(&pfm, &map).unwrap();
    let ray = |x: usize, y: usize| ray_length(x, y, (w, h), focal);
    for (scale, offset, units) in [
        (None, None, "relative units"),
        (Some(20.0), Some(0.75), "m"),
    ] {
        let opts = DepthOptions {
            kind: Some(DepthKind::Inverse),
            fov: Some(fov),
            scale,
            disparity_offset: offset,
            ..DepthOptions::default()
        };
        let d = load_range(&pfm, &opts).unwrap();
        assert_eq!((d.units.as_str(), d.metric), (units, scale.is_some()));
        let (s, o) = (scale.unwrap_or(1.0), offset.unwrap_or(0.0));
        for y in 0..h {
            for x in 0..w {
                let v = f64::from(*map.get(x, y)) + o;
                let got = *d.range.get(x, y);
                if v.is_finite() && v > 0.0 {
                    let want = s / v * ray(x, y);
                    assert!(
                        (f64::from(got) - want).abs() <= 1e-6 * want,
                        "{got} vs {want}"
                    );
                } else {
                    assert!(got.is_nan(), "({x}, {y}) {v}: {got}");
                }
            }
        }
    }
    // MiDaS writes 16-bit PNGs of its output: read as png16, no scale needed.
    let png = save_png16(dir.path(), "inverse.png", 3, 1, &[0, 1000, 4000]);
    let opts = DepthOptions {
        kind: Some(DepthKind::Inverse),
        ..DepthOptions::default()
    };
    let d = load_range(&png, &opts).unwrap();
    assert_eq!(d.format, DepthFormat::Png16);
    assert!(d.range.get(0, 0).is_nan());
    assert_eq!(
        (*d.range.get(1, 0), *d.range.get(2, 0)),
        (1.0 / 1000.0, 1.0 / 4000.0)
    );
    // An 8-bit PNG (a monocular model's visualisation) is Middlebury 2006's disparity: the
    // refusal says which files carry inverse depth.
    let png8 = save_png8(dir.path(), "inverse8.png", 3, 1, &[0, 100, 200]);
    let err = load_range(&png8, &opts).unwrap_err().to_string();
    assert!(err.contains("middlebury2006"), "{err}");
    assert!(err.contains("16-bit PNG or a float map"), "{err}");
    assert_eq!(
        "inverse-depth".parse::<DepthKind>().unwrap(),
        DepthKind::Inverse
    );
}

/// A monocular estimator's affine-invariant depth (`depth_kind` affine, Marigold): depth =
/// near + d·(far − near) along the optical axis, then range with `fov`; the far plane
/// (d = 1, where the model clamps the sky) and NaN unknown, 0 (the nearest depth) known;
/// a 16-bit PNG holds d·65535 and is read as png16 without a scale; `near` and `far` are
/// required and checked; metres with `scale`.
#[test]
fn affine_invariant_depth_becomes_range() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h, fov, near, far) = (7usize, 5usize, 55.0f64, 2.5f64, 180.0f64);
    let focal = h as f64 / 2.0 / (fov.to_radians() / 2.0).tan();
    let ray = |x: usize, y: usize| ray_length(x, y, (w, h), focal);
    let values = [0.0f32, 0.125, 0.5, 0.9995, 1.0, f32::NAN, 0.75];
    let map = Grid::from_fn(w, h, |x, y| values[(x + 2 * y) % values.len()]);
    let pfm = dir.path().join("marigold.pfm");
    write_scalar(&pfm, &map).unwrap();
    for (scale, units) in [(None, "file units"), (Some(0.5), "m")] {
        let opts = DepthOptions {
            kind: Some(DepthKind::Affine),
            fov: Some(fov),
            near: Some(near),
            far: Some(far),
            scale,
            ..DepthOptions::default()
        };
        let d = load_range(&pfm, &opts).unwrap();
        assert_eq!((d.units.as_str(), d.metric), (units, scale.is_some()));
        let s = scale.unwrap_or(1.0);
        for y in 0..h {
            for x in 0..w {
                let v = *map.get(x, y);
                let got = *d.range.get(x, y);
                if v.is_finite() && v < 1.0 {
                    let want = s * (near + f64::from(v) * (far - near)) * ray(x, y);
                    let err = (f64::from(got) - want).abs();
                    assert!(err <= 1e-6 * want, "({x}, {y}) {v}: {got} vs {want}");
                } else {
                    assert!(got.is_nan(), "({x}, {y}) {v}: {got}");
                }
            }
        }
    }
    // Marigold's 16-bit PNG: d·65535, the last code the far plane.
    let png = save_png16(dir.path(), "marigold.png", 4, 1, &[0, 16384, 65535, 65534]);
    let opts = DepthOptions {
        kind: Some(DepthKind::Affine),
        near: Some(near),
        far: Some(far),
        ..DepthOptions::default()
    };
    let d = load_range(&png, &opts).unwrap();
    assert_eq!(d.format, DepthFormat::Png16);
    let at = |code: f64| (near + code / 65535.0 * (far - near)) as f32;
    assert_eq!(*d.range.get(0, 0), at(0.0));
    assert_eq!(*d.range.get(1, 0), at(16384.0));
    assert!(d.range.get(2, 0).is_nan());
    assert!(
        d.range.get(3, 0).is_nan(),
        "13 codes below the last are the far plane"
    );
    assert!(d.notes.iter().any(|n| n.contains("affine-invariant")));
    // Without the planes the map has no depth: refused, naming the option and a guess.
    for (without, name) in [
        (
            DepthOptions {
                near: None,
                ..opts.clone()
            },
            "invalid near",
        ),
        (
            DepthOptions {
                far: None,
                ..opts.clone()
            },
            "invalid far",
        ),
    ] {
        let e = expect_err(load_range(&png, &without)).to_string();
        assert!(
            e.contains(name) && e.contains("2 and 200 for a street"),
            "{e}"
        );
    }
    for (near, far, name) in [(0.0, 10.0, "invalid near"), (5.0, 5.0, "invalid far")] {
        let bad = DepthOptions {
            near: Some(near),
            far: Some(far),
            ..opts.clone()
        };
        let e = expect_err(load_range(&png, &bad)).to_string();
        assert!(e.contains(name), "{e}");
    }
    let far_inf = DepthOptions {
        far: Some(f64::INFINITY),
        ..opts.clone()
    };
    assert!(expect_err(load_range(&png, &far_inf))
        .to_string()
        .contains("a finite depth greater than near"));
    // Its visualisation (8 bits) has lost the levels: the refusal says what to save.
    let png8 = save_png8(dir.path(), "marigold8.png", 3, 1, &[0, 100, 200]);
    let e = expect_err(load_range(&png8, &opts)).to_string();
    assert!(e.contains("affine depth is read from a 16-bit PNG"), "{e}");
    // A 16-bit map with neither scale nor kind points Marigold's users to this kind.
    let plain = DepthOptions::default();
    expect_format_error(load_range(&png, &plain), "Marigold: `depth_kind` affine");
    assert_eq!(
        "affine-invariant".parse::<DepthKind>().unwrap(),
        DepthKind::Affine
    );
}

/// A model's sky at a depth of its own: a float map's largest value held exactly by at
/// least 1 % of its samples, 10 times the mean of the others or more (Depth Pro clamps the
/// sky at 10 km), is unknown, with a note; a plateau smaller than that, or not far enough
/// beyond the rest, is a surface and kept. `sky_beyond` makes the range at or beyond it
/// unknown instead (the clamp then kept), `inf` keeps every value, 0 or NaN is refused.
#[test]
fn a_clamped_sky_and_sky_beyond_are_unknown() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (20usize, 10usize);
    // The top two rows (20 %) at the clamp; the scene 3 to 25.5 m below.
    let scene = |x: usize, y: usize| 2.0 + x as f32 + 0.5 * y as f32;
    let write = |name: &str, top: f32, rows: usize| {
        let map = Grid::from_fn(w, h, |x, y| if y < rows { top } else { scene(x, y) });
        let path = dir.path().join(name);
        write_scalar(&path, &map).unwrap();
        path
    };
    let range = DepthOptions {
        kind: Some(DepthKind::Range),
        ..DepthOptions::default()
    };
    let clamped = write("clamped.pfm", 10_000.0, 2);
    let d = load_range(&clamped, &range).unwrap();
    assert_eq!(d.unknown_pixels, 2 * w);
    assert!((0..w).all(|x| d.range.get(x, 0).is_nan() && d.range.get(x, 1).is_nan()));
    assert_eq!(*d.range.get(3, 4), scene(3, 4));
    let note = d
        .notes
        .iter()
        .find(|n| n.contains("a clamp"))
        .expect("a note");
    assert!(
        note.contains("40 samples (20.0 %)") && note.contains("10000"),
        "{note}"
    );
    // A single sample at a far value is not a clamp (the far-outlier rule is for it).
    let speck = Grid::from_fn(w, h, |x, y| {
        if (x, y) == (0, 0) {
            10_000.0
        } else {
            scene(x, y)
        }
    });
    let path = dir.path().join("speck.pfm");
    write_scalar(&path, &speck).unwrap();
    assert_eq!(load_range(&path, &range).unwrap().unknown_pixels, 0);
    // A far wall at 3 times the mean, held by 20 % of the samples: a surface.
    let wall = write("wall.pfm", 45.0, 2);
    assert_eq!(load_range(&wall, &range).unwrap().unknown_pixels, 0);
    // `sky_beyond`: the range at or beyond it, whatever the plateau.
    let beyond = |b: f64| DepthOptions {
        sky_beyond: Some(b),
        ..range.clone()
    };
    let d = load_range(&wall, &beyond(30.0)).unwrap();
    let at_or_beyond = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .filter(|&(x, y)| y < 2 || scene(x, y) >= 30.0)
        .count();
    assert_eq!(d.unknown_pixels, at_or_beyond);
    assert!(d.notes.iter().any(|n| n.contains("beyond `sky_beyond` 30")));
    let kept = load_range(&clamped, &beyond(f64::INFINITY)).unwrap();
    assert_eq!(kept.unknown_pixels, 0);
    for bad in [0.0, -1.0, f64::NAN] {
        let e = expect_err(load_range(&clamped, &beyond(bad))).to_string();
        assert!(e.contains("invalid sky_beyond"), "{e}");
    }
}

/// Engines' z-buffers: reversed-Z (window depth 1 at near, 0 at far: Bevy and Unreal's
/// infinite one, D3D's reversed finite one) and OpenGL's with an infinite far plane, each
/// written here from eye depths by its projection's own formula, become the range worked
/// out by hand; the sky (nothing drawn: 0 reversed, 1 standard) is unknown.
#[test]
fn reversed_and_infinite_zbuffers_become_range() {
    let (w, h, fov_deg, n, f) = (24usize, 16usize, 50.0f64, 0.1f64, 500.0f64);
    let focal = h as f64 / 2.0 / (fov_deg.to_radians() / 2.0).tan();
    // Eye depth from 0.75 to 430 across the frame, the top row sky.
    let eye = |x: usize, y: usize| (y > 0).then(|| 0.5 * 1.0178f64.powi((x + w * y) as i32));
    let range = |x: usize, y: usize, z: f64| {
        let (u, v) = (
            (x as f64 - (w as f64 - 1.0) / 2.0) / focal,
            (y as f64 - (h as f64 - 1.0) / 2.0) / focal,
        );
        z * (1.0 + u * u + v * v).sqrt()
    };
    type Window = fn(f64, f64, f64) -> f64;
    let cases: [(&str, bool, f64, Window, f32); 3] = [
        // clip (x, y, near, −z) / −z: z_ndc = n/z in [0, 1].
        (
            "reversed infinite",
            true,
            f64::INFINITY,
            |z, n, _| n / z,
            0.0,
        ),
        // D3D's reversed [0, 1]: z_ndc = n(f − z)/(z(f − n)).
        (
            "reversed finite",
            true,
            f,
            |z, n, f| n * (f - z) / (z * (f - n)),
            0.0,
        ),
        // OpenGL's infinite: z_ndc = 1 − 2n/z in [−1, 1], window (z_ndc + 1)/2.
        (
            "standard infinite",
            false,
            f64::INFINITY,
            |z, n, _| 1.0 - n / z,
            1.0,
        ),
    ];
    let dir = tempfile::tempdir().unwrap();
    for (name, reversed, far, window, sky) in cases {
        let d = Grid::from_fn(w, h, |x, y| match eye(x, y) {
            Some(z) => window(z, n, f) as f32,
            None => sky,
        });
        let path = dir.path().join("z.pfm");
        write_scalar(&path, &d).unwrap();
        let opts = DepthOptions {
            kind: Some(DepthKind::ZBuffer),
            near: Some(n),
            far: Some(far),
            fov: Some(fov_deg),
            reversed_z: reversed,
            ..DepthOptions::default()
        };
        let loaded = load_range(&path, &opts).unwrap();
        assert_eq!(loaded.unknown_pixels, w, "{name}: the sky row");
        for y in 0..h {
            for x in 0..w {
                let got = *loaded.range.get(x, y);
                match eye(x, y) {
                    None => assert!(got.is_nan(), "{name} ({x}, {y}): {got}"),
                    Some(z) => {
                        // f32 window depth: 2.6e-4 relative at 430 units from an infinite
                        // projection's standard buffer (6e-8 of d near 1 is z/n times
                        // that), 6e-8 reversed.
                        let want = range(x, y, z);
                        let tol = if reversed { 1e-5 } else { 5e-4 };
                        assert!(
                            (f64::from(got) - want).abs() <= tol * want,
                            "{name} ({x}, {y}): {got} vs {want}"
                        );
                    }
                }
            }
        }
        assert!(loaded.notes[0].contains(if reversed { "reversed-Z" } else { "standard" }));
    }
    // A far plane before the near one, and --reversed-z where no z-buffer is read.
    let bad_far = DepthOptions {
        kind: Some(DepthKind::ZBuffer),
        near: Some(n),
        far: Some(n / 2.0),
        fov: Some(fov_deg),
        ..DepthOptions::default()
    };
    let err = expect_err(load_range(&dir.path().join("z.pfm"), &bad_far)).to_string();
    assert!(
        err.starts_with("invalid far = 0.05") && err.contains("inf"),
        "{err}"
    );
    let as_depth = DepthOptions {
        kind: Some(DepthKind::Depth),
        reversed_z: true,
        ..DepthOptions::default()
    };
    let d = load_range(&dir.path().join("z.pfm"), &as_depth).unwrap();
    assert!(
        d.notes
            .iter()
            .any(|n| n.starts_with("`reversed_z` ignored")),
        "{:?}",
        d.notes
    );
}

/// A rendered frame's z-buffer (top row first) of the ground plane y = 0 seen by a level
/// camera 2 units up, with the analytic range of every pixel (NaN where the ray misses).
fn ground_zbuffer(camera: &brume::camera::Camera, w: usize, h: usize) -> (ScalarMap, Vec<f64>) {
    let mut ranges = Vec::new();
    let d = Grid::from_fn(w, h, |x, row| {
        let ray = camera.pixel_ray(x, h - 1 - row, w, h);
        let t = -camera.position[1] / ray.y;
        let hit = (t > 0.0)
            .then(|| camera.project_depth(camera.eye() + ray * t))
            .flatten()
            .filter(|(d, _)| *d < 1.0);
        ranges.push(hit.map_or(f64::NAN, |(_, r)| r));
        hit.map_or(1.0, |(d, _)| d as f32)
    });
    (d, ranges)
}

#[test]
fn zbuffer_becomes_range_with_near_far_and_fov() {
    let camera = brume::camera::Camera {
        position: [0.0, 2.0, 0.0],
        pitch_deg: -8.0,
        fov_y_deg: 50.0,
        near: 0.5,
        far: 300.0,
        ..Default::default()
    };
    let (w, h) = (20, 16);
    let (zbuffer, expected) = ground_zbuffer(&camera, w, h);
    let dir = tempfile::tempdir().unwrap();
    let pfm = dir.path().join("depth.pfm");
    write_scalar(&pfm, &zbuffer).unwrap();
    // Pitched down 8° the camera sees the ground in the lower rows only.
    let with_camera = DepthOptions {
        kind: Some(DepthKind::ZBuffer),
        near: Some(camera.near),
        far: Some(camera.far),
        fov: Some(camera.fov_y_deg),
        ..DepthOptions::default()
    };
    let d = load_range(&pfm, &with_camera).unwrap();
    assert_eq!(d.kind, DepthKind::ZBuffer);
    let mut checked = 0;
    for (got, want) in d.range.as_slice().iter().zip(&expected) {
        if want.is_nan() {
            assert!(got.is_nan());
        } else {
            // f32 window depth: one ulp near d = 1 is a relative 2e-4 at 300 units here.
            assert!(
                (f64::from(*got) - want).abs() <= 1e-3 * want,
                "{got} vs {want}"
            );
            checked += 1;
        }
    }
    assert!(checked > w * h / 4, "{checked} ground pixels");
    assert!(d.unknown_pixels > 0, "the sky is unknown");

    // A 16-bit PNG holds d·65535.
    let raw: Vec<u16> = zbuffer
        .as_slice()
        .iter()
        .map(|d| (f64::from(*d) * 65535.0).round() as u16)
        .collect();
    let png = save_png16(dir.path(), "depth.png", w as u32, h as u32, &raw);
    let d16 = load_range(&png, &with_camera).unwrap();
    let near_pixel = expected.iter().rposition(|r| !r.is_nan()).unwrap();
    let got = f64::from(d16.range.as_slice()[near_pixel]);
    assert!((got - expected[near_pixel]).abs() < 0.01 * expected[near_pixel]);

    // The range is in the planes' units, not known to be metres, until `scale` says how
    // many metres one is: planes given in centimetres with scale 0.01 read as the planes
    // in metres, and count as metric.
    assert_eq!((d.units.as_str(), d.metric), ("file units", false));
    assert_eq!((d16.units.as_str(), d16.metric), ("file units", false));
    let in_cm = DepthOptions {
        near: Some(camera.near * 100.0),
        far: Some(camera.far * 100.0),
        scale: Some(0.01),
        ..with_camera.clone()
    };
    for (path, in_m) in [(&pfm, &d), (&png, &d16)] {
        let cm = load_range(path, &in_cm).unwrap();
        assert_eq!((cm.units.as_str(), cm.metric), ("m", true), "{path:?}");
        assert!(
            cm.notes
                .iter()
                .any(|n| n == "near and far x 0.01 = metres (depth scale)"),
            "{:?}",
            cm.notes
        );
        for (a, b) in cm.range.as_slice().iter().zip(in_m.range.as_slice()) {
            assert!(
                (a.is_nan() && b.is_nan()) || (a - b).abs() <= 1e-6 * b,
                "{path:?}: {a} from centimetres, {b} from metres"
            );
        }
    }
    let bad_scale = DepthOptions {
        scale: Some(-1.0),
        ..with_camera.clone()
    };
    let err = expect_err(load_range(&pfm, &bad_scale)).to_string();
    assert!(err.starts_with("invalid depth_scale = -1"), "{err}");

    let without_far = DepthOptions {
        far: None,
        ..with_camera.clone()
    };
    let err = expect_err(load_range(&pfm, &without_far)).to_string();
    assert!(err.contains("far") && err.contains("zbuffer"), "{err}");
    // Clipping planes are read from a z-buffer only.
    let as_depth = DepthOptions {
        kind: Some(DepthKind::Depth),
        ..with_camera.clone()
    };
    let d = load_range(&pfm, &as_depth).unwrap();
    assert!(
        d.notes
            .iter()
            .any(|n| n.starts_with("`near` and `far` ignored")),
        "{:?}",
        d.notes
    );
    // The camera's field of view is the option `fov` here.
    let bad_fov = DepthOptions {
        fov: Some(0.0),
        ..with_camera.clone()
    };
    let err = expect_err(load_range(&pfm, &bad_fov)).to_string();
    assert!(err.starts_with("invalid fov = 0:"), "{err}");
    let kitti = DepthOptions {
        format: DepthFormat::Kitti,
        ..with_camera
    };
    assert!(expect_err(load_range(&png, &kitti))
        .to_string()
        .contains("zbuffer"));
}

// ---------------------------------------------------------------- phone depth

/// A DEPTH16 sample: `mm` in the low 13 bits, the confidence `code` in the high 3.
fn depth16(mm: u16, code: u16) -> u16 {
    assert!(
        mm <= 0x1FFF && code <= 7,
        "not a DEPTH16 sample: {mm} mm, code {code}"
    );
    code << 13 | mm
}

/// A 4x3 DEPTH16 map with every confidence code, and its range in metres at the default
/// threshold 0.5 (codes 0 and 5 to 7 kept), NaN where unknown.
fn depth16_samples() -> (Vec<u16>, Vec<f64>) {
    let unknown = f64::NAN;
    let cases = [
        (depth16(8191, 0), 8.191),   // the largest range, 100 %
        (depth16(1000, 7), 1.0),     // 6/7
        (depth16(2000, 5), 2.0),     // 4/7: just above 0.5
        (depth16(3000, 4), unknown), // 3/7: just below
        (depth16(1500, 1), unknown), // code 1 is 0 %, not 1/7
        (depth16(0, 0), unknown),    // no range, however confident
        (depth16(0, 7), unknown),
        (depth16(2500, 2), unknown), // 1/7
        (depth16(4000, 0), 4.0),
        (depth16(5000, 6), 5.0),     // 5/7
        (depth16(1234, 3), unknown), // 2/7
        (depth16(7000, 0), 7.0),
    ];
    cases.into_iter().unzip()
}

/// `d` holds `expected` (metres, NaN unknown) pixel by pixel, and counts its unknowns.
fn assert_range(d: &LoadedDepth, expected: &[f64]) {
    assert_eq!(d.range.len(), expected.len());
    for (i, (got, want)) in d.range.as_slice().iter().zip(expected).enumerate() {
        if want.is_nan() {
            assert!(got.is_nan(), "pixel {i}: {got} m, expected unknown");
        } else {
            assert!(close(*got, *want), "pixel {i}: {got} m, expected {want}");
        }
    }
    let unknown = expected.iter().filter(|v| v.is_nan()).count();
    assert_eq!(d.unknown_pixels, unknown);
}

fn depth16_with(min_confidence: f64) -> DepthOptions {
    DepthOptions {
        min_confidence: Some(min_confidence),
        ..opts(DepthFormat::AndroidDepth16)
    }
}

/// Range of depth `z` at pixel (x, y) of a `w` x `h` map with vertical field of view
/// `fov_deg` and the principal point at the centre, computed here from scratch.
fn stretched(z: f64, x: usize, y: usize, w: usize, h: usize, fov_deg: f64) -> f64 {
    let f = h as f64 / 2.0 / (fov_deg.to_radians() / 2.0).tan();
    let u = (x as f64 - (w as f64 - 1.0) / 2.0) / f;
    let v = (y as f64 - (h as f64 - 1.0) / 2.0) / f;
    z * (1.0 + u * u + v * v).sqrt()
}

#[test]
fn android_depth16_splits_range_and_confidence() {
    let dir = tempfile::tempdir().unwrap();
    let (samples, expected) = depth16_samples();
    let p = save_png16(dir.path(), "depth16.png", 4, 3, &samples);
    let d = load_range(&p, &opts(DepthFormat::AndroidDepth16)).unwrap();
    assert_eq!(
        (d.format, d.kind, d.units.as_str()),
        (DepthFormat::AndroidDepth16, DepthKind::Range, "m")
    );
    assert!(d.intrinsics.is_none(), "range needs no field of view");
    assert_range(&d, &expected);
    // 10 samples have a range; codes 1 to 4 (4 of them) are below 0.5.
    assert!(
        d.notes
            .iter()
            .any(|n| n.contains("4 of 10") && n.contains("`min_confidence` 0.5")),
        "{:?}",
        d.notes
    );
    // The default is documented as 0.5, and is what no option gives.
    assert_eq!(DEPTH16_DEFAULT_MIN_CONFIDENCE, 0.5);
    let explicit = load_range(&p, &depth16_with(0.5)).unwrap();
    assert_range(&explicit, &expected);
    assert_eq!(explicit.notes, d.notes);
}

#[test]
fn android_depth16_high_bits_are_confidence_and_arcore_has_none() {
    let dir = tempfile::tempdir().unwrap();
    // 0xFFFF is 8191 mm at code 7; 0x1FFF 8191 mm at code 0; 0xA064 100 mm at code 5.
    let p = save_png16(dir.path(), "bits.png", 3, 1, &[0xFFFF, 0x1FFF, 0xA064]);
    let d = load_range(&p, &opts(DepthFormat::AndroidDepth16)).unwrap();
    assert_range(&d, &[8.191, 8.191, 0.1]);
    // The same file read as ARCore: all 16 bits are millimetres.
    let d = load_range(&p, &opts(DepthFormat::Arcore)).unwrap();
    assert_range(&d, &[65.535, 8.191, 41.06]);
}

#[test]
fn android_depth16_confidence_threshold_edges() {
    let dir = tempfile::tempdir().unwrap();
    let (samples, _) = depth16_samples();
    let p = save_png16(dir.path(), "depth16.png", 4, 3, &samples);
    let at = |c: f64| load_range(&p, &depth16_with(c)).unwrap();
    // 0 keeps every sample with a range, code 1 (0 %) included; only range 0 is unknown.
    let all = at(0.0);
    assert_eq!(all.unknown_pixels, 2);
    assert!(close(*all.range.get(0, 1), 1.5));
    assert!(
        !all.notes.iter().any(|n| n.contains("below")),
        "{:?}",
        all.notes
    );
    // Exactly 4/7 keeps code 5 (4/7); a hair above does not.
    assert!(close(*at(4.0 / 7.0).range.get(2, 0), 2.0));
    assert!(at(4.0 / 7.0 + 1e-9).range.get(2, 0).is_nan());
    // 1/7 keeps code 2 (1/7) but not code 1 (0 %).
    let low = at(1.0 / 7.0);
    assert!(close(*low.range.get(3, 1), 2.5));
    assert!(low.range.get(0, 1).is_nan());
    // 1 keeps code 0 (100 %) only: 8191, 4000 and 7000 mm.
    let mut only_code_0 = vec![f64::NAN; 12];
    (only_code_0[0], only_code_0[8], only_code_0[11]) = (8.191, 4.0, 7.0);
    assert_range(&at(1.0), &only_code_0);
}

#[test]
fn min_confidence_outside_zero_to_one_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (samples, _) = depth16_samples();
    let p = save_png16(dir.path(), "depth16.png", 4, 3, &samples);
    for bad in [-0.1, 1.5, f64::NAN, f64::INFINITY] {
        let err = expect_err(load_range(&p, &depth16_with(bad)));
        let msg = err.to_string();
        assert!(matches!(err, Error::InvalidParameter { .. }), "{msg}");
        assert!(
            msg.contains(&format!("invalid min_confidence = {bad}")) && msg.contains("0 to 1"),
            "{msg}"
        );
    }
    // A format without confidence ignores the option, and says so; a bad value is still
    // refused.
    let kitti = DepthOptions {
        min_confidence: Some(0.9),
        ..opts(DepthFormat::Kitti)
    };
    let d = load_range(&p, &kitti).unwrap();
    assert!(d
        .notes
        .iter()
        .any(|n| n.contains("`min_confidence` ignored") && n.contains("kitti")));
    let kitti = DepthOptions {
        min_confidence: Some(2.0),
        ..kitti
    };
    assert!(expect_err(load_range(&p, &kitti))
        .to_string()
        .contains("min_confidence = 2"));
}

#[test]
fn android_depth16_with_nothing_confident_enough_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let unsure = [depth16(1000, 1), depth16(2000, 3), depth16(3000, 4), 0];
    let p = save_png16(dir.path(), "unsure.png", 2, 2, &unsure);
    let msg = expect_format_error(
        load_range(&p, &opts(DepthFormat::AndroidDepth16)),
        "`min_confidence` 0.5",
    );
    assert!(
        msg.contains("unsure.png") && msg.contains("all 3") && msg.contains("highest is 0.429"),
        "{msg}"
    );
    // Below the best confidence (3/7) the file loads.
    let d = load_range(&p, &depth16_with(0.4)).unwrap();
    assert_range(&d, &[f64::NAN, f64::NAN, 3.0, f64::NAN]);
    // No range anywhere, whatever the confidence bits, is the error every format gives.
    let p = save_png16(dir.path(), "empty.png", 2, 1, &[0, 0xE000]);
    let err = expect_err(load_range(&p, &opts(DepthFormat::AndroidDepth16)));
    assert!(matches!(err, Error::NoValidDepth { .. }), "{err}");
    assert!(err.to_string().contains("empty.png"), "{err}");
    // To ARCore 0xE000 is 57.344 m; only 0 is unknown.
    let d = load_range(&p, &opts(DepthFormat::Arcore)).unwrap();
    assert_range(&d, &[f64::NAN, 57.344]);
    let p = save_png16(dir.path(), "zeros.png", 2, 1, &[0, 0]);
    let err = expect_err(load_range(&p, &opts(DepthFormat::Arcore)));
    assert!(matches!(err, Error::NoValidDepth { .. }), "{err}");
}

#[test]
fn phone_formats_refuse_what_is_not_a_16_bit_grey_png() {
    let dir = tempfile::tempdir().unwrap();
    let png8 = save_png8(dir.path(), "d8.png", 2, 1, &[10, 20]);
    let png16 = save_png16(dir.path(), "d16.png", 2, 1, &[1000, 2000]);
    let rgb16 = dir.path().join("rgb16.png");
    let bytes: Vec<u8> = [1000u16; 6].iter().flat_map(|v| v.to_ne_bytes()).collect();
    image::save_buffer(&rgb16, &bytes, 2, 1, image::ExtendedColorType::Rgb16).unwrap();
    let pfm = write(
        dir.path(),
        "d.pfm",
        &pfm_bytes("Pf", 2, 1, "-1", &[1.0, 2.0], true),
    );
    let jpg = write(dir.path(), "d.jpg", b"\xff\xd8\xff\xe0");
    for format in [DepthFormat::AndroidDepth16, DepthFormat::Arcore] {
        let msg = expect_format_error(load_range(&png8, &opts(format)), "d8.png");
        let expected = format!("`depth_format` {format} expects a 16-bit grey PNG");
        assert!(
            msg.contains(&expected) && msg.contains("found an 8-bit PNG"),
            "{msg}"
        );
        let msg = expect_format_error(load_range(&rgb16, &opts(format)), "rgb16.png");
        assert!(
            msg.contains("Rgb16") && msg.contains("one grey channel"),
            "{msg}"
        );
        let msg = expect_format_error(load_range(&pfm, &opts(format)), "d.pfm");
        assert!(msg.contains("found a float PFM"), "{msg}");
        let msg = expect_format_error(load_range(&jpg, &opts(format)), "d.jpg");
        assert!(
            msg.contains(
                "expects a 16-bit grey PNG (or a 16-bit TIFF or uint16 .npy), found a JPEG"
            ),
            "{msg}"
        );
        // What the values are: depth or range only.
        for kind in [DepthKind::ZBuffer, DepthKind::Disparity] {
            let o = DepthOptions {
                kind: Some(kind),
                ..opts(format)
            };
            let msg = expect_err(load_range(&png16, &o)).to_string();
            assert!(
                msg.contains("depth_kind") && msg.contains(&format!("`depth_format` {format}")),
                "{msg}"
            );
        }
    }
}

#[test]
fn android_depth16_of_a_z_depth_device_with_a_field_of_view() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (5, 3);
    let p = save_png16(
        dir.path(),
        "z.png",
        w as u32,
        h as u32,
        &[depth16(2000, 0); 15],
    );
    let o = DepthOptions {
        kind: Some(DepthKind::Depth),
        fov: Some(90.0),
        ..opts(DepthFormat::AndroidDepth16)
    };
    let d = load_range(&p, &o).unwrap();
    assert_eq!(d.kind, DepthKind::Depth);
    assert!(d.intrinsics.is_some());
    for y in 0..h {
        for x in 0..w {
            let want = stretched(2.0, x, y, w, h, 90.0);
            assert!(close(*d.range.get(x, y), want), "({x}, {y})");
        }
    }
    assert!(
        *d.range.get(0, 0) > 2.5,
        "the corner's ray is longer than the depth"
    );
}

#[test]
fn arcore_is_millimetres_along_the_optical_axis() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (5, 3);
    let mut z = vec![2500u16; w * h];
    z[0] = 0; // unknown
    z[1] = 0xE000 | 1000; // 58.344 m: ARCore's top bits are depth, not confidence
    z[w * h - 1] = u16::MAX; // 65.535 m, the farthest ARCore can say
    let p = save_png16(dir.path(), "arcore.png", w as u32, h as u32, &z);
    let metres: Vec<f64> = z
        .iter()
        .map(|&v| {
            if v == 0 {
                f64::NAN
            } else {
                f64::from(v) / 1000.0
            }
        })
        .collect();

    // Without a field of view the depth is used as range, and the notes say so.
    let d = load_range(&p, &opts(DepthFormat::Arcore)).unwrap();
    assert_eq!(
        (d.format, d.kind, d.units.as_str()),
        (DepthFormat::Arcore, DepthKind::Depth, "m")
    );
    assert!(d.intrinsics.is_none());
    assert!(d
        .notes
        .iter()
        .any(|n| n == "no intrinsics: depth used as range"));
    assert_range(&d, &metres);

    // With --fov each pixel's depth is stretched along its ray.
    let with_fov = DepthOptions {
        fov: Some(60.0),
        ..opts(DepthFormat::Arcore)
    };
    let d = load_range(&p, &with_fov).unwrap();
    let k = d.intrinsics.unwrap();
    assert!(close(k.fx as f32, 1.5 / (30.0f64).to_radians().tan()));
    assert_eq!((k.cx, k.cy), (2.0, 1.0));
    let ranges: Vec<f64> = metres
        .iter()
        .enumerate()
        .map(|(i, z)| stretched(*z, i % w, i / w, w, h, 60.0))
        .collect();
    assert_range(&d, &ranges);
    assert!(
        close(*d.range.get(2, 1), 2.5),
        "the centre's range is its depth"
    );

    // A bad field of view is named; --depth-kind range takes the values as they are.
    let bad_fov = DepthOptions {
        fov: Some(180.0),
        ..with_fov.clone()
    };
    let err = expect_err(load_range(&p, &bad_fov)).to_string();
    assert!(err.contains("invalid fov = 180"), "{err}");
    let as_range = DepthOptions {
        kind: Some(DepthKind::Range),
        ..with_fov
    };
    let d = load_range(&p, &as_range).unwrap();
    assert_range(&d, &metres);
    assert!(d.intrinsics.is_none());
}

// ---------------------------------------------------------------- phone depth, CLI

/// Runs the `brume` binary in `dir`.
fn brume(dir: &Path, args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_brume"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run brume")
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn json(o: &std::process::Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", stderr(o));
    serde_json::from_slice(&o.stdout).expect("one JSON object on stdout")
}

fn notes(v: &serde_json::Value) -> Vec<String> {
    v["depth_notes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap().to_string())
        .collect()
}

#[test]
fn android_depth16_through_brume_prep() {
    let dir = tempfile::tempdir().unwrap();
    let (samples, expected) = depth16_samples();
    save_png16(dir.path(), "d16.png", 4, 3, &samples);
    let prep = |extra: &[&str]| {
        let mut args = vec![
            "prep",
            "--depth",
            "d16.png",
            "--depth-format",
            "android-depth16",
        ];
        // A 4 x 3 map of unrelated samples is all "local outliers" to a rule made for
        // real frames: off, so that the decoded values are what is checked.
        args.extend_from_slice(&["--no-sky", "--local-outliers", "0"]);
        args.extend_from_slice(&["--out", "range.pfm", "--json"]);
        args.extend_from_slice(extra);
        json(&brume(dir.path(), &args))
    };
    let v = prep(&[]);
    assert_eq!(v["depth_format"], "android-depth16", "{v}");
    assert_eq!(v["depth_kind"], "range", "{v}");
    assert_eq!(v["unknown_pixels"], 6, "{v}");
    assert!(notes(&v).iter().any(|n| n.contains("4 of 10")), "{v}");
    // The written range map keeps every known value; pre-processing fills the unknown.
    let range = grey(read_pfm(&dir.path().join("range.pfm")).unwrap());
    for (i, (got, want)) in range.as_slice().iter().zip(&expected).enumerate() {
        if want.is_nan() {
            assert!(got.is_finite(), "pixel {i} was not filled: {got}");
        } else {
            assert!(close(*got, *want), "pixel {i}: {got} m, expected {want}");
        }
    }
    // --min-confidence 1 keeps the three 100 % samples only.
    let v = prep(&["--min-confidence", "1"]);
    assert_eq!(v["unknown_pixels"], 9, "{v}");
}

#[test]
fn phone_depth_renders_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (24, 16);
    let image = dir.path().join("im.png");
    let colour = Grid::from_fn(w, h, |x, y| {
        [x as f32 / w as f32, y as f32 / h as f32, 0.5, 1.0]
    });
    brume::io::output::write_rgba(&image, &colour).unwrap();
    // Range grows to the right; the confidence code cycles, so some samples are unknown.
    let samples: Vec<u16> = (0..w * h)
        .map(|i| depth16(1000 + 200 * (i % w) as u16, (i % 8) as u16))
        .collect();
    save_png16(dir.path(), "d16.png", w as u32, h as u32, &samples);
    let arcore: Vec<u16> = (0..w * h).map(|i| 1500 + 300 * (i / w) as u16).collect();
    save_png16(dir.path(), "arcore.png", w as u32, h as u32, &arcore);

    let _gl = common::gl_lock();
    let depth16_args = [
        "--depth-format",
        "android-depth16",
        "--min-confidence",
        "0.3",
    ];
    let mut args = vec!["render", "--image", "im.png", "--depth", "d16.png"];
    args.extend_from_slice(&depth16_args);
    args.extend_from_slice(&["--out", "fog.png", "--json"]);
    let v = json(&brume(dir.path(), &args));
    assert_eq!(v["depth_format"], "android-depth16", "{v}");
    assert_eq!(v["depth_kind"], "range", "{v}");
    // Codes 1 to 3 (0 to 2/7) are below 0.3: 3 of every 8 samples.
    assert!(notes(&v).iter().any(|n| n.contains("144 of 384")), "{v}");
    let fog = image::open(dir.path().join("fog.png")).unwrap();
    assert_eq!((fog.width(), fog.height()), (w as u32, h as u32));

    let args = [
        "render",
        "--image",
        "im.png",
        "--depth",
        "arcore.png",
        "--depth-format",
        "arcore",
        "--fov",
        "60",
        "--out",
        "fog-arcore.png",
        "--json",
    ];
    let v = json(&brume(dir.path(), &args));
    assert_eq!(v["depth_format"], "arcore", "{v}");
    assert_eq!(v["depth_kind"], "depth", "{v}");
    assert!(
        notes(&v).iter().any(|n| n.contains("principal point")),
        "{v}"
    );
    assert!(dir.path().join("fog-arcore.png").is_file());
}

#[test]
fn phone_depth_errors_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let (samples, _) = depth16_samples();
    save_png16(dir.path(), "d16.png", 4, 3, &samples);
    save_png8(dir.path(), "d8.png", 4, 3, &[7; 12]);
    let prep = |depth: &str, extra: &[&str]| {
        let mut args = vec!["prep", "--depth", depth, "--out", "r.pfm"];
        args.extend_from_slice(extra);
        brume(dir.path(), &args)
    };
    for value in ["1.5", "-0.25"] {
        let o = prep(
            "d16.png",
            &[
                "--depth-format",
                "android-depth16",
                "--min-confidence",
                value,
            ],
        );
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(
            err.contains(&format!("invalid --min-confidence = {value}")) && err.contains("0 to 1"),
            "{err}"
        );
    }
    let o = prep("d8.png", &["--depth-format", "android-depth16"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("d8.png")
            && err.contains(
                "expects a 16-bit grey PNG (or a 16-bit TIFF or uint16 .npy), found an 8-bit PNG"
            ),
        "{err}"
    );
    let o = prep("d16.png", &["--depth-format", "depth16"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("android-depth16") && err.contains("arcore"),
        "{err}"
    );
    assert!(
        !dir.path().join("r.pfm").exists(),
        "no output after an error"
    );
}

// ---------------------------------------------------------------- Cityscapes

/// A Cityscapes camera file with the dataset's keys (pitch, roll, … are not used) and a
/// camera chosen so that the rays of a 6x4 map leave the axis noticeably: baseline 0.5 m,
/// fx 20, fy 25, principal point (3.5, 1.25).
fn cityscapes_camera(baseline: &str, fx: &str) -> String {
    format!(
        r#"{{
    "extrinsic": {{"baseline": {baseline}, "pitch": 0.038, "roll": 0.0, "x": 1.7,
                   "y": 0.1, "yaw": -0.0195, "z": 1.18}},
    "intrinsic": {{"fx": {fx}, "fy": 25.0, "u0": 3.5, "v0": 1.25}}
}}"#
    )
}

/// Stored values of a 6x4 Cityscapes disparity: p = 1 + 256·d. Most pixels d = 2 px;
/// (0, 0) d = 1, (2, 1) d = 0.5, (5, 3) d = 4; (1, 0) p = 0 (invalid) and (3, 0) p = 1
/// (d = 0: no depth).
fn cityscapes_disparity() -> Vec<u16> {
    let mut p = vec![513u16; 24];
    p[0] = 257;
    p[1] = 0;
    p[3] = 1;
    p[6 + 2] = 129;
    p[3 * 6 + 5] = 1025;
    p
}

/// Writes `{dir}/{name}_disparity.png` and, if `camera_dir` is given,
/// `{camera_dir}/{name}_camera.json`; returns the disparity's path.
fn cityscapes_files(dir: &Path, name: &str, camera_dir: Option<&Path>) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let disparity = save_png16(
        dir,
        &format!("{name}_disparity.png"),
        6,
        4,
        &cityscapes_disparity(),
    );
    if let Some(c) = camera_dir {
        std::fs::create_dir_all(c).unwrap();
        write(
            c,
            &format!("{name}_camera.json"),
            cityscapes_camera("0.5", "20").as_bytes(),
        );
    }
    disparity
}

/// The known ranges of [`cityscapes_disparity`], worked by hand: Z = baseline·fx/d, then
/// R = Z·sqrt(1 + ((x − u0)/fx)² + ((y − v0)/fy)²).
fn assert_cityscapes_range(d: &LoadedDepth) {
    // (0, 0): Z = 0.5·20/1 = 10 m; u = −3.5/20, v = −1.25/25: R = 10·sqrt(1.033125).
    // (2, 1): Z = 0.5·20/0.5 = 20 m; u = −1.5/20, v = −0.25/25: R = 20·sqrt(1.005725).
    // (5, 3): Z = 0.5·20/4 = 2.5 m; u = 1.5/20, v = 1.75/25: R = 2.5·sqrt(1.010525).
    for (x, y, want) in [
        (0, 0, 10.164_275_675_128_06),
        (2, 1, 20.057_168_294_652_165),
        (5, 3, 2.513_121_813_601_561),
    ] {
        let got = *d.range.get(x, y);
        assert!(close(got, want), "({x}, {y}): {got} m, expected {want}");
    }
    // Every d = 2 px pixel is at Z = 5 m along its own ray.
    let (x, y) = (4, 2);
    let stretch = (1.0f64 + (0.5f64 / 20.0).powi(2) + (0.75f64 / 25.0).powi(2)).sqrt();
    assert!(close(*d.range.get(x, y), 5.0 * stretch));
    assert!(d.range.get(1, 0).is_nan(), "p = 0 is invalid");
    assert!(d.range.get(3, 0).is_nan(), "p = 1 is d = 0: no depth");
    assert_eq!(d.unknown_pixels, 2);
    assert_eq!(
        (d.format, d.kind, d.units.as_str(), d.metric),
        (DepthFormat::Cityscapes, DepthKind::Disparity, "m", true)
    );
    let k = d.intrinsics.unwrap();
    assert_eq!((k.fx, k.fy, k.cx, k.cy), (20.0, 25.0, 3.5, 1.25));
    // fx·baseline, for pre-processing's stereo occlusions.
    assert_eq!(d.stereo_focal_baseline, Some(20.0 * 0.5));
}

/// The same load, NaN for NaN (`==` on the maps would fail on their unknown pixels).
fn assert_same_load(a: &LoadedDepth, b: &LoadedDepth) {
    let bits =
        |d: &LoadedDepth| -> Vec<u32> { d.range.as_slice().iter().map(|v| v.to_bits()).collect() };
    assert_eq!(bits(a), bits(b));
    assert_eq!(
        (a.format, a.kind, a.metric, &a.notes, a.intrinsics),
        (b.format, b.kind, b.metric, &b.notes, b.intrinsics)
    );
    assert_eq!(a.stereo_focal_baseline, b.stereo_focal_baseline);
}

#[test]
fn cityscapes_disparity_and_camera_give_range_in_metres() {
    let dir = tempfile::tempdir().unwrap();
    let cameras = dir.path().join("elsewhere");
    let p = cityscapes_files(dir.path(), "f", Some(&cameras));
    let camera = cameras.join("f_camera.json");
    let given = DepthOptions {
        camera: Some(camera.clone()),
        ..opts(DepthFormat::Cityscapes)
    };
    let d = load_range(&p, &given).unwrap();
    assert_cityscapes_range(&d);
    assert!(
        d.notes.iter().any(|n| n.contains("stored value 1")),
        "{:?}",
        d.notes
    );
    // `auto` takes a 16-bit PNG with a camera file given for Cityscapes.
    let auto = DepthOptions {
        camera: Some(camera.clone()),
        ..DepthOptions::default()
    };
    assert_same_load(&load_range(&p, &auto).unwrap(), &d);
    // The library's own entry points load the same.
    assert_same_load(&load_cityscapes(&p, Some(&camera)).unwrap(), &d);
    let bytes = std::fs::read(&p).unwrap();
    let text = std::fs::read_to_string(&camera).unwrap();
    let from_bytes = load_cityscapes_from_bytes(&bytes, &p, (&camera, &text)).unwrap();
    assert_same_load(&from_bytes, &d);
    // Without the camera, bytes alone cannot be Cityscapes.
    let err = expect_err(load_range_from_bytes(
        &bytes,
        &p,
        &opts(DepthFormat::Cityscapes),
        None,
    ));
    assert!(err.to_string().contains("`camera`"), "{err}");
}

#[test]
fn cityscapes_camera_is_found_beside_and_in_the_dataset_layout() {
    let dir = tempfile::tempdir().unwrap();
    // Beside the disparity, `auto`: found, used, and said so.
    let beside = dir.path().join("flat");
    let p = cityscapes_files(&beside, "a", Some(&beside));
    let d = load_range(&p, &DepthOptions::default()).unwrap();
    assert_cityscapes_range(&d);
    let camera = beside.join("a_camera.json");
    let note = format!("camera read from {}", camera.display());
    assert!(d.notes.contains(&note), "{:?}", d.notes);
    assert_same_load(&load_cityscapes(&p, None).unwrap(), &d);

    // The dataset's layout: disparity/{split}/{city}/ and camera/{split}/{city}/.
    let root = dir.path().join("cityscapes");
    let p = cityscapes_files(
        &root.join("disparity/train/aachen"),
        "aachen_000000_000019",
        Some(&root.join("camera/train/aachen")),
    );
    let d = load_range(&p, &opts(DepthFormat::Cityscapes)).unwrap();
    assert_cityscapes_range(&d);
    let camera = root.join("camera/train/aachen/aachen_000000_000019_camera.json");
    let note = format!("camera read from {}", camera.display());
    assert!(d.notes.contains(&note), "{:?}", d.notes);

    // Neither: the error names both places and the option.
    let lonely = dir.path().join("disparity/val/bonn");
    let p = cityscapes_files(&lonely, "b", None);
    let msg = expect_format_error(load_range(&p, &opts(DepthFormat::Cityscapes)), "`camera`");
    for tried in [
        lonely.join("b_camera.json"),
        dir.path().join("camera/val/bonn/b_camera.json"),
    ] {
        assert!(msg.contains(&tried.display().to_string()), "{msg}");
    }
    // `auto` with no camera found falls back to the 16-bit PNG message, which names the
    // format.
    expect_format_error(load_range(&p, &DepthOptions::default()), "cityscapes");
}

#[test]
fn cityscapes_camera_errors_name_the_file_the_key_and_the_value() {
    let dir = tempfile::tempdir().unwrap();
    let p = cityscapes_files(dir.path(), "c", None);
    let load = |json: &str| {
        let camera = write(dir.path(), "camera.json", json.as_bytes());
        let o = DepthOptions {
            camera: Some(camera),
            ..opts(DepthFormat::Cityscapes)
        };
        load_range(&p, &o)
    };
    let cases = [
        ("{\"extrinsic\": ", vec!["camera.json", "not JSON", "baseline"]),
        (
            "{\"extrinsic\": {\"baseline\": 0.2}, \"intrinsic\": {\"fx\": 2262.52, \"u0\": 1, \"v0\": 2}}",
            vec!["camera.json", "missing intrinsic.fy"],
        ),
        (
            "{\"extrinsic\": {\"baseline\": \"wide\"}, \"intrinsic\": {}}",
            vec!["extrinsic.baseline = \"wide\"", "a number"],
        ),
        (
            &cityscapes_camera("0", "20"),
            vec!["extrinsic.baseline = 0", "baseline in metres, > 0"],
        ),
        (
            &cityscapes_camera("0.5", "-20"),
            vec!["intrinsic.fx = -20", "focal length in pixels, > 0"],
        ),
    ];
    for (json, needles) in cases {
        let msg = expect_format_error(load(json), needles[0]);
        for n in needles {
            assert!(msg.contains(n), "`{msg}` should mention `{n}`");
        }
    }
    // A camera file that cannot be read names itself.
    let missing = DepthOptions {
        camera: Some(dir.path().join("nope.json")),
        ..opts(DepthFormat::Cityscapes)
    };
    assert!(expect_err(load_range(&p, &missing))
        .to_string()
        .contains("nope.json"));
    // Not a 16-bit grey PNG; not disparity.
    let good = write(
        dir.path(),
        "good.json",
        cityscapes_camera("0.5", "20").as_bytes(),
    );
    let with_camera = DepthOptions {
        camera: Some(good),
        ..opts(DepthFormat::Cityscapes)
    };
    let p8 = save_png8(dir.path(), "d8_disparity.png", 6, 4, &[9; 24]);
    expect_format_error(
        load_range(&p8, &with_camera),
        "`depth_format` cityscapes expects a 16-bit grey PNG (or a 16-bit TIFF or uint16 .npy), found an 8-bit PNG",
    );
    let as_depth = DepthOptions {
        kind: Some(DepthKind::Depth),
        ..with_camera
    };
    let err = expect_err(load_range(&p, &as_depth)).to_string();
    assert!(
        err.contains("invalid depth_kind = depth") && err.contains("cityscapes"),
        "{err}"
    );
}

#[test]
fn a_real_cityscapes_camera_file_parses() {
    let text = r#"{
    "extrinsic": {
        "baseline": 0.209313,
        "pitch": 0.038,
        "roll": 0.0,
        "x": 1.7,
        "y": 0.1,
        "yaw": -0.0195,
        "z": 1.18
    },
    "intrinsic": {
        "fx": 2262.52,
        "fy": 2265.3017905988554,
        "u0": 1096.98,
        "v0": 513.137
    }
}"#;
    let c = parse_camera_str(text, Path::new("aachen_000000_000019_camera.json")).unwrap();
    assert_eq!(c.baseline_m, 0.209313);
    let k = c.intrinsics;
    assert_eq!(
        (k.fx, k.fy, k.cx, k.cy),
        (2262.52, 2265.3017905988554, 1096.98, 513.137)
    );
    // A disparity of 47.36 px is about 10 m.
    assert!((c.depth_m(47.36).unwrap() - 10.0).abs() < 0.01);
    assert_eq!(c.depth_m(0.0), None);
}

#[test]
fn metric_says_whether_the_metres_can_be_trusted() {
    let dir = tempfile::tempdir().unwrap();
    let p16 = save_png16(dir.path(), "k.png", 2, 1, &[2560, 5120]);
    assert!(load_range(&p16, &opts(DepthFormat::Kitti)).unwrap().metric);
    let scaled = DepthOptions {
        scale: Some(0.01),
        ..opts(DepthFormat::Png16)
    };
    assert!(load_range(&p16, &scaled).unwrap().metric);
    let float = dir.path().join("r.pfm");
    write_scalar(&float, &Grid::from_fn(2, 1, |x, _| 1.0 + x as f32)).unwrap();
    let d = load_range(&float, &DepthOptions::default()).unwrap();
    assert_eq!((d.units.as_str(), d.metric), ("file units", false));
    // Middlebury 2006: metres only when its geometry is given in full.
    let p8 = save_png8(dir.path(), "d.png", 2, 1, &[40, 80]);
    let d = load_range(&p8, &DepthOptions::default()).unwrap();
    assert_eq!((d.units.as_str(), d.metric), ("m", false));
    let full = DepthOptions {
        focal: Some(3740.0),
        baseline: Some(160.0),
        disparity_offset: Some(270.0),
        ..DepthOptions::default()
    };
    assert!(load_range(&p8, &full).unwrap().metric);
    assert!(!brume::io::demo::demo_range().unwrap().metric);
}

#[test]
fn cityscapes_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("cs");
    cityscapes_files(
        &root.join("disparity/train/ulm"),
        "ulm_1",
        Some(&root.join("camera/train/ulm")),
    );
    let colour = Grid::from_fn(6, 4, |x, y| [x as f32 / 6.0, y as f32 / 4.0, 0.5, 1.0]);
    brume::io::output::write_rgba(&dir.path().join("im.png"), &colour).unwrap();
    let depth = "cs/disparity/train/ulm/ulm_1_disparity.png";
    let _gl = common::gl_lock();
    let args = [
        "render", "--image", "im.png", "--depth", depth, "--out", "fog.png", "--json",
    ];
    let v = json(&brume(dir.path(), &args));
    assert_eq!(v["depth_format"], "cityscapes", "{v}");
    assert_eq!(v["depth_kind"], "disparity", "{v}");
    assert!(
        notes(&v)
            .iter()
            .any(|n| n.starts_with("camera read from") && n.contains("ulm_1_camera.json")),
        "{v}"
    );
    assert!(dir.path().join("fog.png").is_file());

    // No camera anywhere: both places and --camera named, nothing written.
    std::fs::remove_file(root.join("camera/train/ulm/ulm_1_camera.json")).unwrap();
    let mut args = args.to_vec();
    args[6] = "fog2.png";
    args.extend(["--depth-format", "cityscapes"]);
    let o = brume(dir.path(), &args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.starts_with("brume: error: ")
            && err.contains("disparity/train/ulm/ulm_1_camera.json")
            && err.contains("camera/train/ulm/ulm_1_camera.json")
            && err.contains("--camera"),
        "{err}"
    );
    assert!(!dir.path().join("fog2.png").exists());
}

/// A float map is in file units unless a depth scale says how many metres a unit is: then
/// it is metric (physical fog accepts it) and its values are scaled; without one, `brume
/// render --beta` refuses it. τ of a 40 m range with scale 0.5 at β = 0.05 is
/// exp(−0.05 · 20) = 0.3679.
#[test]
fn a_float_map_with_a_depth_scale_is_metres() {
    let dir = tempfile::tempdir().unwrap();
    let values: Vec<u8> = [40f32; 6].iter().flat_map(|v| v.to_le_bytes()).collect();
    let p = write(
        dir.path(),
        "r.npy",
        &common::npy_bytes("<f4", "(2, 3)", false, &values),
    );
    let plain = load_range(&p, &DepthOptions::default()).unwrap();
    assert!(!plain.metric);
    let scaled = load_range(
        &p,
        &DepthOptions {
            scale: Some(0.5),
            kind: Some(DepthKind::Range),
            ..DepthOptions::default()
        },
    )
    .unwrap();
    assert!(scaled.metric && scaled.units == "m", "{scaled:?}");
    assert!(scaled.range.as_slice().iter().all(|&v| v == 20.0));
    common::save_png(
        dir.path().join("i.png").to_str().unwrap(),
        3,
        2,
        &[[128, 128, 128]; 6],
    );
    let args = [
        "render",
        "--image",
        "i.png",
        "--depth",
        "r.npy",
        "--depth-kind",
        "range",
        "--beta",
        "0.05",
        "--lambda",
        "0",
        "--no-prep",
        "--out",
        "o.png",
        "--json",
    ];
    let refused = common::brume(dir.path(), &args);
    assert!(!refused.status.success());
    assert!(common::stderr(&refused).contains("--depth-scale"));
    let mut with_scale = args.to_vec();
    with_scale.extend(["--depth-scale", "0.5"]);
    let o = common::brume(dir.path(), &with_scale);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let tau = (-0.05f64 * 20.0).exp();
    for key in ["transmittance_min", "transmittance_max"] {
        assert!((v[key].as_f64().unwrap() - tau).abs() < 1e-6, "{key}: {v}");
    }
}

/// No loader leaves a 0 in a range map: every format's "no measurement" becomes NaN, as
/// do a float map's 0 and negative values. The fog relies on it: after the loaders, a 0
/// is pre-processing's ego vehicle, read as at the camera (`medium::haze::at_known_range`),
/// so a 0 that meant "unknown" would come out unfogged.
#[test]
fn no_loader_leaves_a_zero_range() {
    let dir = tempfile::tempdir().unwrap();
    let png16 = save_png16(dir.path(), "d.png", 3, 1, &[0, 5000, 65535]);
    let png8 = save_png8(dir.path(), "m.png", 3, 1, &[0, 100, 200]);
    let floats: Vec<u8> = [0.0f32, -1.0, 5.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let npy = write(
        dir.path(),
        "f.npy",
        &common::npy_bytes("<f4", "(1, 3)", false, &floats),
    );
    let pfm = write(
        dir.path(),
        "f.pfm",
        &pfm_bytes("Pf", 3, 1, "-1.0", &[0.0, -1.0, 5.0], true),
    );
    let scaled = DepthOptions {
        scale: Some(0.01),
        ..DepthOptions::default()
    };
    let mut cases = vec![
        (png16.clone(), scaled),
        (png8, opts(DepthFormat::Middlebury2006)),
        (npy, opts(DepthFormat::Float)),
        (pfm, opts(DepthFormat::Float)),
    ];
    for format in [
        DepthFormat::Kitti,
        DepthFormat::Nyu,
        DepthFormat::Tum,
        DepthFormat::AndroidDepth16,
        DepthFormat::Arcore,
    ] {
        cases.push((png16.clone(), opts(format)));
    }
    let cityscapes = cityscapes_files(&dir.path().join("cs"), "f", Some(&dir.path().join("cs")));
    cases.push((cityscapes, opts(DepthFormat::Cityscapes)));
    for (path, o) in cases {
        let d = load_range(&path, &o).unwrap_or_else(|e| panic!("{:?}: {e}", o.format));
        let zeros = d.range.as_slice().iter().filter(|&&v| v == 0.0).count();
        assert_eq!(
            zeros,
            0,
            "{:?} of {}: {zeros} zero ranges",
            o.format,
            path.display()
        );
        assert!(d.unknown_pixels >= 1, "{:?}: no unknown pixel", o.format);
        assert_eq!(
            d.range.as_slice().iter().filter(|v| v.is_nan()).count(),
            d.unknown_pixels,
            "{:?}",
            o.format
        );
    }
}
