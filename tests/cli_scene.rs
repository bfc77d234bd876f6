//! `brume scene` end to end: every fog and blur writes a frame and reports its passes; the
//! fog is visible where the depth buffer is far and not near the eye; the blur softens the
//! far band only; the raw depth buffer round-trips into `brume render`; sequences are
//! numbered and animated; bad input fails with one clear line and writes nothing.
//!
//! Frames are 64x40 (a few tenths of a second each on llvmpipe). Colour and depth are read
//! from PFM, whose floats are the renderer's own (no 8-bit rounding).

use crate::common;

use brume::io::codec::exr::read_exr_scalar;
use brume::io::codec::pfm::{read_pfm, Pfm};
use brume::raster::{RgbImage, ScalarMap};
use common::snapshot;
use serde_json::Value;
use std::fs;
use std::path::Path;
use std::process::{Command, Output};
use std::sync::Mutex;

/// The binary opens a GL context per run; llvmpipe uses every core, so run one at a time.
static SERIAL: Mutex<()> = Mutex::new(());

const SIZE: &str = "64x40";
const W: usize = 64;
const H: usize = 40;
const FOGS: [&str; 2] = ["distance", "layered"];
const BLURS: [&str; 4] = ["none", "gauss-single", "gauss-separate", "diffusion"];

fn brume(dir: &Path, args: &[&str]) -> Output {
    let _lock = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    Command::new(env!("CARGO_BIN_EXE_brume"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run brume")
}

/// `brume scene --size 64x40 ARGS` in `dir`, which must succeed.
fn scene(dir: &Path, args: &[&str]) -> Output {
    let mut all = vec!["scene", "--size", SIZE];
    all.extend_from_slice(args);
    let o = brume(dir, &all);
    assert!(
        o.status.success(),
        "brume {}: {}",
        all.join(" "),
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// `scene` with `--json`: the one JSON object on stdout.
fn scene_json(dir: &Path, args: &[&str]) -> Value {
    let mut all = args.to_vec();
    all.push("--json");
    let o = scene(dir, &all);
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| {
        panic!(
            "stdout is not one JSON object ({e}): {}",
            String::from_utf8_lossy(&o.stdout)
        )
    })
}

/// A colour PFM, top row first.
fn rgb(path: &Path) -> RgbImage {
    match read_pfm(path).unwrap() {
        Pfm::Rgb(image) => {
            assert_eq!((image.width(), image.height()), (W, H), "{path:?}");
            image
        }
        Pfm::Grey(_) => panic!("{path:?} is a grey PFM"),
    }
}

/// A depth PFM (window depth, 1 = sky), top row first.
fn depth(path: &Path) -> ScalarMap {
    match read_pfm(path).unwrap() {
        Pfm::Grey(map) => {
            assert_eq!((map.width(), map.height()), (W, H), "{path:?}");
            map
        }
        Pfm::Rgb(_) => panic!("{path:?} is a colour PFM"),
    }
}

fn max_diff(a: [f32; 3], b: [f32; 3]) -> f32 {
    (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f32::max)
}

fn dist(a: [f32; 3], b: [f32; 3]) -> f64 {
    (0..3)
        .map(|k| f64::from(a[k] - b[k]).powi(2))
        .sum::<f64>()
        .sqrt()
}

fn lum(p: [f32; 3]) -> f64 {
    f64::from(p[0] + p[1] + p[2]) / 3.0
}

fn mean(v: &[f64]) -> f64 {
    assert!(!v.is_empty());
    v.iter().sum::<f64>() / v.len() as f64
}

/// Sum of |Δ luminance| over horizontal neighbours in `rows` where both pixels pass `keep`.
fn contrast(
    image: &RgbImage,
    rows: std::ops::Range<usize>,
    keep: impl Fn(usize, usize) -> bool,
) -> f64 {
    let mut sum = 0.0;
    for y in rows {
        for x in 0..W - 1 {
            if keep(x, y) && keep(x + 1, y) {
                sum += (lum(*image.get(x + 1, y)) - lum(*image.get(x, y))).abs();
            }
        }
    }
    sum
}

/// The pass names a frame reports (`Frame::pass_names`) in each mode.
fn assert_pass_names(blur: &str, names: &[&str]) {
    match blur {
        "none" => assert_eq!(names, ["fog"]),
        "gauss-single" => assert_eq!(names, ["fog+blur"]),
        "gauss-separate" => assert_eq!(names, ["fog", "blur"]),
        "diffusion" => {
            assert!(names.len() >= 3, "{names:?}");
            assert_eq!(names[0], "medium");
            assert_eq!(names[names.len() - 1], "composite");
            for (k, name) in names[1..names.len() - 1].iter().enumerate() {
                assert_eq!(*name, format!("diffuse {}", k + 1), "{names:?}");
            }
        }
        _ => unreachable!(),
    }
}

fn finite_ms(v: &Value, what: &str) -> f64 {
    let ms = v
        .as_f64()
        .unwrap_or_else(|| panic!("{what} is not a number: {v}"));
    assert!(ms.is_finite() && ms >= 0.0, "{what} = {ms}");
    ms
}

#[test]
fn every_fog_and_blur_writes_a_frame_and_reports_its_passes() {
    let dir = tempfile::tempdir().unwrap();
    for fog in FOGS {
        for blur in BLURS {
            let name = format!("{fog}-{blur}.png");
            let v = scene_json(dir.path(), &["--fog", fog, "--blur", blur, "--out", &name]);
            let what = format!("--fog {fog} --blur {blur}: {v}");
            let png = image::open(dir.path().join(&name)).expect("the frame is a PNG");
            assert_eq!((png.width(), png.height()), (W as u32, H as u32), "{what}");

            assert_eq!(v["fog"], fog, "{what}");
            assert_eq!(v["blur"], blur, "{what}");
            assert_eq!(v["size"], SIZE, "{what}");
            let camera = &v["camera"];
            assert_eq!(
                camera["position"],
                serde_json::json!([0.0, 1.7, 0.0]),
                "{what}"
            );
            for (key, value) in [
                ("yaw", 0.0),
                ("pitch", 0.0),
                ("fov", 60.0),
                ("near", 0.1),
                ("far", 1000.0),
            ] {
                assert_eq!(camera[key].as_f64(), Some(value), "camera.{key}: {what}");
            }
            assert!(
                v["renderer"].as_str().is_some_and(|r| !r.is_empty()),
                "{what}"
            );

            let frames = v["frames"].as_array().expect("frames");
            assert_eq!(frames.len(), 1, "{what}");
            let frame = &frames[0];
            assert_eq!(frame["out"], name.as_str(), "{what}");
            assert_eq!(frame["time"].as_f64(), Some(0.0), "{what}");
            let clock = frame["clock"].as_str().unwrap_or_default();
            assert!(
                clock == "gpu-timer" || clock == "wall",
                "clock {clock}: {what}"
            );
            let passes = frame["passes"].as_array().expect("passes");
            let names: Vec<&str> = passes
                .iter()
                .map(|p| p["pass"].as_str().expect("pass name"))
                .collect();
            assert_pass_names(blur, &names);
            let sum: f64 = passes.iter().map(|p| finite_ms(&p["ms"], &what)).sum();
            let total = finite_ms(&frame["total_ms"], &what);
            assert!(
                (total - sum).abs() <= 1e-6 * sum.max(1.0),
                "total {total} ≠ Σ passes {sum}: {what}"
            );
        }
    }
}

#[test]
fn no_fog_writes_the_clear_frame_without_warnings() {
    let dir = tempfile::tempdir().unwrap();
    let o = scene(
        dir.path(),
        &[
            "--fog",
            "none",
            "--out",
            "o.pfm",
            "--clear-out",
            "c.pfm",
            "--json",
        ],
    );
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["fog"], "none", "{v}");
    assert_eq!(v["blur"], "none", "--fog none blurs nothing: {v}");
    assert_eq!(v["frames"][0]["passes"], serde_json::json!([]), "{v}");
    assert!(
        o.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let (out, clear) = (
        rgb(&dir.path().join("o.pfm")),
        rgb(&dir.path().join("c.pfm")),
    );
    assert_eq!(
        out.as_slice(),
        clear.as_slice(),
        "--fog none changed the frame"
    );

    // An explicit blur with no fog is ignored, and said so.
    let o = scene(
        dir.path(),
        &["--fog", "none", "--blur", "diffusion", "--out", "b.pfm"],
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("--blur ignored"));
    assert_eq!(rgb(&dir.path().join("b.pfm")).as_slice(), clear.as_slice());
}

/// 1 − |out − F| / |clear − F|: how far a pixel moved from the clear frame toward F.
fn toward(out: &RgbImage, clear: &RgbImage, fog: [f32; 3], x: usize, y: usize) -> f64 {
    let (o, c) = (*out.get(x, y), *clear.get(x, y));
    1.0 - dist(o, fog) / dist(c, fog)
}

#[test]
fn fog_moves_far_pixels_toward_its_colour_and_not_near_ones() {
    let dir = tempfile::tempdir().unwrap();
    let magenta = [1.0, 0.0, 1.0]; // far from every colour of the scene
    for fog in FOGS {
        let (out, clear, z) = (
            format!("{fog}.pfm"),
            format!("{fog}-clear.pfm"),
            format!("{fog}-depth.pfm"),
        );
        scene(
            dir.path(),
            &[
                "--fog",
                fog,
                "--blur",
                "none",
                "--fog-colour",
                "1,0,1",
                "--out",
                &out,
                "--clear-out",
                &clear,
                "--depth-out",
                &z,
            ],
        );
        let (out, clear, z) = (
            rgb(&dir.path().join(out)),
            rgb(&dir.path().join(clear)),
            depth(&dir.path().join(z)),
        );
        assert!(z.as_slice().iter().all(|d| (0.0..=1.0).contains(d)));
        // Far: the sky and the geometry near the horizon (window depth ≥ 0.999, i.e.
        // ≥ 100 m at near 0.1); near: the bottom rows, ground about 3 m from the eye.
        let mut far = Vec::new();
        for y in 0..H {
            for x in 0..W {
                if *z.get(x, y) >= 0.999 {
                    far.push(toward(&out, &clear, magenta, x, y));
                }
            }
        }
        let near: Vec<f64> = (H - 4..H)
            .flat_map(|y| (0..W).map(move |x| (x, y)))
            .map(|(x, y)| {
                assert!(
                    *z.get(x, y) < 0.98,
                    "bottom row is not near: {}",
                    z.get(x, y)
                );
                toward(&out, &clear, magenta, x, y)
            })
            .collect();
        assert!(far.len() > W * 8, "{fog}: only {} far pixels", far.len());
        let (far_mean, near_mean) = (mean(&far), mean(&near));
        let far_min = far.iter().copied().fold(f64::MAX, f64::min);
        assert!(
            far_mean > 0.2 && far_min > 0.1,
            "{fog}: far pixels barely fogged (mean {far_mean}, min {far_min})"
        );
        assert!(
            near_mean < 0.1 && far_mean > 4.0 * near_mean,
            "{fog}: near {near_mean} vs far {far_mean}"
        );
    }
}

#[test]
fn blur_softens_the_far_band_and_leaves_the_near_rows() {
    let dir = tempfile::tempdir().unwrap();
    for fog in FOGS {
        let run = |blur: &str| {
            let out = format!("{fog}-{blur}.pfm");
            scene(
                dir.path(),
                &[
                    "--fog",
                    fog,
                    "--blur",
                    blur,
                    "--out",
                    &out,
                    "--depth-out",
                    "z.pfm",
                ],
            );
            rgb(&dir.path().join(out))
        };
        let sharp = run("none");
        let z = depth(&dir.path().join("z.pfm"));
        // Far geometry (not sky: blurring the horizon into the sky adds contrast there).
        let far = |x: usize, y: usize| (0.999..1.0).contains(z.get(x, y));
        let far_pairs = (0..H)
            .flat_map(|y| (0..W - 1).map(move |x| (x, y)))
            .filter(|&(x, y)| far(x, y) && far(x + 1, y))
            .count();
        assert!(far_pairs >= 30, "{fog}: only {far_pairs} far neighbours");
        let sharp_far = contrast(&sharp, 0..H, far);
        let sharp_near = contrast(&sharp, H - 4..H, |_, _| true);
        assert!(
            sharp_far > 1.0,
            "{fog}: no structure in the far band ({sharp_far})"
        );
        for blur in ["gauss-single", "gauss-separate", "diffusion"] {
            let soft = run(blur);
            let (soft_far, soft_near) = (
                contrast(&soft, 0..H, far),
                contrast(&soft, H - 4..H, |_, _| true),
            );
            assert!(
                soft_far < 0.8 * sharp_far,
                "{fog} {blur}: far contrast {soft_far} vs {sharp_far} unblurred"
            );
            assert!(
                (soft_near / sharp_near - 1.0).abs() < 0.05,
                "{fog} {blur}: near contrast {soft_near} vs {sharp_near} unblurred"
            );
            for y in H - 4..H {
                for x in 0..W {
                    let d = max_diff(*soft.get(x, y), *sharp.get(x, y));
                    assert!(d < 0.02, "{fog} {blur}: near pixel ({x}, {y}) moved by {d}");
                }
            }
        }
    }
}

#[test]
fn depth_buffer_round_trips_into_render() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    scene(
        dir.path(),
        &[
            "--fog",
            "none",
            "--out",
            "clear.png",
            "--depth-out",
            "d.pfm",
        ],
    );
    let z = depth(&p("d.pfm"));
    assert!(z.as_slice().iter().all(|d| (0.0..=1.0).contains(d)));
    assert!((0..W).all(|x| *z.get(x, 0) == 1.0), "the top row is sky");
    assert!(
        (0..W).all(|x| *z.get(x, H - 1) < 1.0),
        "the bottom row is ground"
    );
    let sky = z.as_slice().iter().filter(|&&d| d == 1.0).count();

    let o = brume(
        dir.path(),
        &[
            "render",
            "--image",
            "clear.png",
            "--depth",
            "d.pfm",
            "--depth-kind",
            "zbuffer",
            "--near",
            "0.1",
            "--far",
            "1000",
            "--fov",
            "60",
            "--out",
            "fogged.png",
            "--json",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["depth_kind"], "zbuffer", "{v}");
    assert_eq!(
        (v["width"].as_u64(), v["height"].as_u64()),
        (Some(W as u64), Some(H as u64))
    );
    // Every pixel at window depth 1, and only those, is found to be sky.
    assert_eq!(v["prep"]["sky_pixels"].as_u64(), Some(sky as u64), "{v}");
    assert!(sky > 0);
    assert_eq!(v["airlight_source"], "sky", "{v}");
    assert!(image::open(p("fogged.png")).is_ok());

    // The same buffer as EXR.
    scene(
        dir.path(),
        &[
            "--fog",
            "none",
            "--out",
            "clear2.png",
            "--depth-out",
            "d.exr",
        ],
    );
    let exr = read_exr_scalar(&p("d.exr")).unwrap();
    assert_eq!(exr.as_slice(), z.as_slice(), "EXR and PFM depth differ");
}

/// Above the lake: the bottom half of the frame is water, whose waves move with time.
const LAKE: &str = "-20,1.7,-20";

/// Where two frames differ by more than `tolerance`.
fn changed(a: &RgbImage, b: &RgbImage, tolerance: f32) -> Vec<bool> {
    a.as_slice()
        .iter()
        .zip(b.as_slice())
        .map(|(p, q)| max_diff(*p, *q) > tolerance)
        .collect()
}

#[test]
fn sequences_are_numbered_and_the_noise_drifts() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    let with = |extra: &[&'static str]| -> Vec<&'static str> {
        let mut args = vec!["--position", LAKE, "--blur", "none"];
        args.extend_from_slice(extra);
        args
    };
    let v = scene_json(
        dir.path(),
        &with(&[
            "--frames",
            "3",
            "--fps",
            "2",
            "--out",
            "s.pfm",
            "--clear-out",
            "c0.pfm",
        ]),
    );
    let files: Vec<String> = fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();
    assert_eq!(files, ["c0.pfm", "s_0001.pfm", "s_0002.pfm", "s_0003.pfm"]);
    let frames = v["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 3, "{v}");
    for (k, frame) in frames.iter().enumerate() {
        assert_eq!(frame["time"].as_f64(), Some(k as f64 / 2.0), "{v}");
        assert_eq!(frame["out"], format!("s_{:04}.pfm", k + 1), "{v}");
    }

    // Water: where the fog-free frames at t = 0 and t = 0.5 differ.
    scene(
        dir.path(),
        &with(&["--fog", "none", "--time", "0.5", "--out", "c1.pfm"]),
    );
    let water = changed(&rgb(&p("c0.pfm")), &rgb(&p("c1.pfm")), 0.0);
    let wet = water.iter().filter(|&&w| w).count();
    assert!(wet > W * 4 && wet < W * H - W * 4, "{wet} water pixels");

    // The noise drifts: fogged frames differ on dry land and in the air too.
    let s: Vec<RgbImage> = (1..=3).map(|k| rgb(&p(&format!("s_{k:04}.pfm")))).collect();
    for pair in s.windows(2) {
        let moved = changed(&pair[0], &pair[1], 1e-4);
        let dry_moved = moved.iter().zip(&water).filter(|&(&m, &w)| m && !w).count();
        assert!(
            dry_moved > (W * H - wet) / 20,
            "the noise barely moved: {dry_moved} dry pixels changed"
        );
    }
    // Frame k of a sequence is the frame at --time (k − 1)/fps.
    scene(dir.path(), &with(&["--time", "0.5", "--out", "single.pfm"]));
    assert!(!changed(&rgb(&p("single.pfm")), &s[1], 1e-6).contains(&true));

    // With no noise only the water changes.
    scene(
        dir.path(),
        &with(&[
            "--noise", "none", "--frames", "3", "--fps", "2", "--out", "q.pfm",
        ]),
    );
    let q: Vec<RgbImage> = (1..=3).map(|k| rgb(&p(&format!("q_{k:04}.pfm")))).collect();
    for pair in q.windows(2) {
        let moved = changed(&pair[0], &pair[1], 1e-6);
        let dry_moved = moved.iter().zip(&water).filter(|&(&m, &w)| m && !w).count();
        assert_eq!(dry_moved, 0, "--noise none: dry pixels changed with time");
        assert!(moved.contains(&true), "--noise none: the water stood still");
    }
}

/// What every pre-existing output holds before a case runs.
const PRECIOUS: &[u8] = b"precious bytes that no failed command may touch\n";

#[test]
fn bad_input_fails_with_one_line_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("notes.txt"), "not a picture\n").unwrap();
    fs::write(dir.path().join("keep.png"), PRECIOUS).unwrap();
    // Density tables (`--profile table`), each wrong in one way.
    let header = "height_m,extinction_per_m\n";
    for (name, text) in [
        ("noheader.csv", "0,0.01\n1,0.02\n".to_string()),
        ("onerow.csv", format!("{header}0,0.01\n")),
        ("down.csv", format!("{header}0,0.01\n5,0.02\n3,0.01\n")),
        ("negative.csv", format!("{header}0,0.01\n5,-0.02\n")),
        ("word.csv", format!("{header}0,0.01\n5,thick\n")),
        ("good.csv", format!("{header}0,0.01\n5,0.02\n")),
    ] {
        fs::write(dir.path().join(name), text).unwrap();
    }
    // (arguments after `scene`, exit code, words stderr must contain). `--size 16x10` and
    // `--out o.png` are added unless the case gives its own.
    let cases: &[(&str, i32, &str)] = &[
        ("--frames 0", 1, "--frames 0"),
        ("--frames -1", 2, "--frames -1"),
        ("--fps 0", 1, "--fps 0"),
        ("--fps nan", 1, "--fps NaN"),
        ("--time inf", 1, "--time inf"),
        ("--pitch 95", 1, "--pitch 95"),
        ("--yaw nan", 1, "--yaw NaN"),
        ("--fov 0", 1, "--fov 0"),
        ("--fov 180", 1, "--fov 180"),
        ("--near 0", 1, "--near 0"),
        ("--far 0.05", 1, "--far 0.05"),
        ("--size 0x10", 1, "--size 0x10"),
        ("--size -3x4", 1, "--size -3x4"),
        ("--size big", 1, "--size big"),
        ("--blur-max 2", 1, "--blur-max 2"),
        ("--blur gauss-single --blur-max 2", 1, "--blur-max 2"),
        ("--blur-distance 0", 1, "--blur-distance 0"),
        (
            "--blur gauss-separate --blur-falloff -1",
            1,
            "--blur-falloff -1",
        ),
        ("--rho-max 0.3", 1, "--rho-max 0.3"),
        // A blur's options with another blur cannot take effect.
        (
            "--blur none --sigma0 2",
            1,
            "--sigma0 2 --blur diffusion not --blur none",
        ),
        (
            "--blur gauss-single --scheme euler",
            1,
            "--scheme euler --blur diffusion",
        ),
        (
            "--blur-distance 50",
            1,
            "--blur-distance 50 gauss-single not --blur diffusion",
        ),
        (
            "--blur none --precision f16",
            1,
            "--precision f16 --blur none",
        ),
        ("--sigma0 0", 1, "--sigma0 0"),
        ("--lambda -1", 1, "--lambda -1"),
        ("--max-density 1", 1, "--max-density 1"),
        ("--fog-distance 0", 1, "--fog-distance 0"),
        ("--fog-exponent -1", 1, "--fog-exponent -1"),
        ("--fog-start nan", 1, "--fog-start NaN"),
        ("--scatter-exponent 0", 1, "--scatter-exponent 0"),
        ("--light-dir 0,0,0", 1, "--light-dir 0,0,0"),
        ("--noise-size 0", 1, "--noise-size 0"),
        ("--noise-low -1", 1, "--noise-low -1"),
        ("--noise-high -1", 1, "--noise-high -1"),
        ("--noise-seed -1", 2, "--noise-seed -1"),
        ("--noise /nonexistent.png", 1, "--noise /nonexistent.png"),
        ("--noise notes.txt", 1, "notes.txt noise"),
        ("--out keep.png --noise keep.png", 1, "--out keep.png input"),
        ("--out x.txt", 1, "--out x.txt .png"),
        ("--out o", 1, "--out o"),
        ("--out nodir/o.png", 1, "--out nodir"),
        ("--depth-out d.png", 1, "--depth-out d.png .pfm"),
        ("--clear-out c.txt", 1, "--clear-out c.txt"),
        (
            "--out keep.png --clear-out keep.png",
            1,
            "--clear-out keep.png --out",
        ),
        (
            "--out o.pfm --depth-out ./o.pfm",
            1,
            "--depth-out ./o.pfm --out",
        ),
        (
            "--frames 3 --out s.png --clear-out s_0002.png",
            1,
            "--clear-out s_0002.png",
        ),
        ("--fog layered --density -1", 1, "--density -1"),
        (
            "--fog layered --profile table --density-csv noheader.csv",
            1,
            "noheader.csv line 1 height_m,extinction_per_m",
        ),
        (
            "--fog layered --profile table --density-csv onerow.csv",
            1,
            "onerow.csv 1 data row at least 2",
        ),
        (
            "--fog layered --profile table --density-csv down.csv",
            1,
            "down.csv line 4 height_m = 3 increase",
        ),
        (
            "--fog layered --profile table --density-csv negative.csv",
            1,
            "negative.csv line 3 -0.02 negative",
        ),
        (
            "--fog layered --profile table --density-csv word.csv",
            1,
            "word.csv line 3 `thick`",
        ),
        (
            "--fog layered --profile table --density-csv none.csv",
            1,
            "none.csv",
        ),
        (
            "--fog layered --profile table",
            1,
            "--profile table --density-csv",
        ),
        (
            "--fog layered --density-csv down.csv",
            1,
            "--density-csv down.csv --profile table",
        ),
        (
            "--noise-colour-strength 2",
            1,
            "--noise-colour-strength 2 [0, 1]",
        ),
        (
            "--noise-colour-strength -0.5",
            1,
            "--noise-colour-strength -0.5",
        ),
        ("--fog layered --albedo 2", 1, "--albedo 2"),
        ("--fog layered --scale-height 0", 1, "--scale-height 0"),
        (
            "--fog layered --profile band --thickness 0",
            1,
            "--thickness 0",
        ),
        // An option of another fog, or of no noise, is refused, not ignored.
        (
            "--fog layered --fog-start 10",
            1,
            "--fog-start 10 --fog distance",
        ),
        (
            "--fog distance --thickness 4",
            1,
            "--thickness 4 --fog layered",
        ),
        (
            "--fog distance --profile band",
            1,
            "--profile band --fog layered",
        ),
        (
            "--fog layered --noise-size 3",
            1,
            "--noise-size 3 --fog distance",
        ),
        (
            "--noise none --noise-low 0.2",
            1,
            "--noise-low 0.2 --noise none",
        ),
        (
            "--fog none --fog-colour 1,0,0",
            1,
            "--fog-colour --fog none",
        ),
        // A value the profile does not have is refused, not ignored.
        (
            "--fog layered --thickness 5",
            1,
            "--thickness 5 exponential",
        ),
        (
            "--fog layered --profile ramp --scale-height 9",
            1,
            "--scale-height 9 ramp",
        ),
        (
            "--fog layered --profile table --density-csv good.csv --density 2",
            1,
            "--density 2 table",
        ),
        ("--position 0,nan,0", 2, "--position 0,nan,0"),
        ("--position 1,2", 2, "--position 1,2"),
        ("--fog-colour -1,0,0", 2, "--fog-colour -1,0,0"),
        ("--fog fluffy", 2, "--fog fluffy"),
        ("--blur box", 2, "--blur box"),
        ("--frobnicate", 2, "--frobnicate"),
    ];
    let before = snapshot(dir.path());
    let mut failures = Vec::new();
    for &(extra, code, mentions) in cases {
        let mut args: Vec<&str> = vec!["scene"];
        let words: Vec<&str> = extra.split_whitespace().collect();
        if !words.contains(&"--size") {
            args.extend(["--size", "16x10"]);
        }
        if !words.contains(&"--out") {
            args.extend(["--out", "o.png"]);
        }
        args.extend(&words);
        let o = brume(dir.path(), &args);
        let err = String::from_utf8_lossy(&o.stderr);
        let first = err.lines().next().unwrap_or_default();
        let mut wrong = Vec::new();
        if o.status.code() != Some(code) {
            wrong.push(format!("exit {:?}, expected {code}", o.status.code()));
        }
        for m in mentions.split_whitespace() {
            if !first.contains(m) {
                wrong.push(format!("the first line does not name {m:?}"));
            }
        }
        if err.contains("panicked") {
            wrong.push("panicked".into());
        }
        if code == 1 && !(err.starts_with("brume: error: ") && err.lines().count() == 1) {
            wrong.push("stderr is not one `brume: error:` line".into());
        }
        if code == 2 && !first.starts_with("error: ") {
            wrong.push("stderr does not start with clap's `error:`".into());
        }
        let after = snapshot(dir.path());
        if after != before {
            let changed: Vec<&String> = before
                .keys()
                .chain(after.keys())
                .filter(|k| before.get(*k) != after.get(*k))
                .collect();
            wrong.push(format!("directory changed: {changed:?}"));
            for k in after.keys().filter(|k| !before.contains_key(*k)) {
                let path = dir.path().join(k);
                let _ = fs::remove_file(&path).or_else(|_| fs::remove_dir_all(&path));
            }
            fs::write(dir.path().join("keep.png"), PRECIOUS).unwrap();
        }
        if !wrong.is_empty() {
            failures.push(format!(
                "brume {}\n    {}\n    stderr: {}",
                args.join(" "),
                wrong.join("; "),
                err.trim_end()
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

/// `--profile table --density-csv`: a table sampled every metre from the default
/// exponential profile renders the exponential's frame (to the sampling's error, Δ²/(8H²)
/// relative in the optical depth: 3e-4 here), and a table with an inversion layer renders
/// another frame.
#[test]
fn density_table_from_a_csv_renders_the_profile_it_samples() {
    let dir = tempfile::tempdir().unwrap();
    let mut csv =
        String::from("# the default exponential profile, every metre\nheight_m,extinction_per_m\n");
    for h in 0..=1000 {
        csv.push_str(&format!("{h},{}\n", 0.01 * f64::exp(-f64::from(h) / 20.0)));
    }
    fs::write(dir.path().join("exp.csv"), csv).unwrap();
    fs::write(
        dir.path().join("inversion.csv"),
        "height_m,extinction_per_m\n0,0.001\n20,0.002\n25,0.05\n40,0.05\n60,0.001\n",
    )
    .unwrap();
    let v = scene_json(
        dir.path(),
        &[
            "--fog",
            "layered",
            "--profile",
            "table",
            "--density-csv",
            "exp.csv",
            "--out",
            "t.pfm",
        ],
    );
    assert_eq!(v["fog"], "layered", "{v}");
    scene(dir.path(), &["--fog", "layered", "--out", "a.pfm"]);
    scene(
        dir.path(),
        &[
            "--fog",
            "layered",
            "--profile",
            "table",
            "--density-csv",
            "inversion.csv",
            "--out",
            "i.pfm",
        ],
    );
    let (t, a, i) = (
        rgb(&dir.path().join("t.pfm")),
        rgb(&dir.path().join("a.pfm")),
        rgb(&dir.path().join("i.pfm")),
    );
    let largest = |x: &RgbImage, y: &RgbImage| {
        x.as_slice()
            .iter()
            .zip(y.as_slice())
            .flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).abs()))
            .fold(0.0f32, f32::max)
    };
    let (same, other) = (largest(&t, &a), largest(&i, &a));
    assert!(same < 1e-3, "sampled table vs exponential: {same}");
    assert!(
        other > 0.02,
        "the inversion renders the same frame: {other}"
    );
}

/// `--noise-colour-strength`: 0 (the default) renders the frame of no option at all, and
/// a strength changes the colour of the distance fog.
#[test]
fn noise_colour_strength_changes_the_fog_colour_only_when_given() {
    let dir = tempfile::tempdir().unwrap();
    scene(dir.path(), &["--fog", "distance", "--out", "plain.pfm"]);
    scene(
        dir.path(),
        &[
            "--fog",
            "distance",
            "--noise-colour-strength",
            "0",
            "--out",
            "zero.pfm",
        ],
    );
    scene(
        dir.path(),
        &[
            "--fog",
            "distance",
            "--noise-colour-strength",
            "0.8",
            "--out",
            "tint.pfm",
        ],
    );
    let read = |name: &str| fs::read(dir.path().join(name)).unwrap();
    assert_eq!(
        read("plain.pfm"),
        read("zero.pfm"),
        "strength 0 changed the frame"
    );
    assert_ne!(
        read("plain.pfm"),
        read("tint.pfm"),
        "strength 0.8 left the frame alone"
    );
}
