//! Sky on a street frame with the faults of real stereo data (issue #13): the sky's unknown
//! region joined to the left border's unknown band, which reaches the bottom row; matcher
//! noise in the sky; bogus far values in the scene. The range alone finds no sky there;
//! the image and the range together must, and `--sky-mask` must override both.

use crate::common;

use common::brume;

use brume::io::output::{write_rgba, write_scalar};
use brume::prep::synthetic::{street_scene, StreetScene};
use brume::prep::{
    estimate_airlight, prepare, prepare_guided, AirlightSource, Guides, PrepOptions, Prepared,
    SkyMethod,
};
use brume::raster::Grid;
use common::*;
use serde_json::Value;
use std::path::Path;

const W: usize = 512;
const H: usize = 256;

fn frame() -> StreetScene {
    street_scene(W, H, 7)
}

fn guided(s: &StreetScene) -> Prepared {
    let guides = Guides {
        image: Some(&s.image),
        sky_mask: None,
        ego_mask: None,
    };
    prepare_guided(&s.range, guides, &PrepOptions::default()).unwrap()
}

/// Found sky as (fraction of the true sky found, fraction of the rest called sky).
fn coverage(truth: &Grid<bool>, found: &Grid<bool>) -> (f64, f64) {
    let (mut tp, mut sky, mut fp, mut rest) = (0usize, 0usize, 0usize, 0usize);
    for (&t, &f) in truth.as_slice().iter().zip(found.as_slice()) {
        if t {
            sky += 1;
            tp += usize::from(f);
        } else {
            rest += 1;
            fp += usize::from(f);
        }
    }
    (tp as f64 / sky as f64, fp as f64 / rest as f64)
}

/// Median of one channel of the true sky's colours.
fn true_sky_colour(s: &StreetScene) -> [f32; 3] {
    let mut out = [0.0; 3];
    for (c, o) in out.iter_mut().enumerate() {
        let mut v: Vec<f32> = (0..W * H)
            .filter(|&p| s.sky.as_slice()[p])
            .map(|p| s.image.as_slice()[p][c])
            .collect();
        v.sort_by(f32::total_cmp);
        *o = v[v.len() / 2];
    }
    out
}

fn dump(name: &str, s: &StreetScene, p: &Prepared) {
    let Ok(dir) = std::env::var("PREP_VIS_DIR") else {
        return;
    };
    let srgb = |v: f32| (brume::io::image::linear_to_srgb(v.clamp(0.0, 1.0)) * 255.0).round() as u8;
    let px: Vec<[u8; 3]> = (0..W * H)
        .map(|i| {
            let c = s.image.as_slice()[i].map(srgb);
            match (s.sky.as_slice()[i], p.sky.as_slice()[i]) {
                (true, true) | (false, false) => c,
                (true, false) => [255, 0, 255],
                (false, true) => [255, 255, 0],
            }
        })
        .collect();
    save_png(&format!("{dir}/{name}-sky.png"), W, H, &px);
    let (w, h, vis) = brume::prep::visualize(&s.range, p);
    save_png(&format!("{dir}/{name}-range.png"), w, h, &vis);
}

/// The frame reproduces the user's report: the depth rules find no sky, because the
/// sky's unknown region runs down the left band to the bottom row.
#[test]
fn the_range_alone_finds_no_sky() {
    let s = frame();
    let band_bottom = (H - 1) * W;
    assert!(
        s.range.as_slice()[band_bottom].is_nan(),
        "band reaches the bottom"
    );
    assert!(
        s.range.as_slice()[0].is_nan() && s.sky.as_slice()[0],
        "and the sky"
    );
    let p = prepare(&s.range, &PrepOptions::default()).unwrap();
    assert_eq!(p.stats.sky_pixels, 0, "{:?}", p.stats);
    assert_eq!(p.stats.sky_method, SkyMethod::Depth);
}

#[test]
fn image_and_range_find_the_sky_and_not_the_band() {
    let s = frame();
    let p = guided(&s);
    dump("street", &s, &p);
    let (found, false_pos) = coverage(&s.sky, &p.sky);
    eprintln!(
        "street {W}x{H}: sky found {:.2} %, false positives {:.3} % of the rest; {:?}",
        100.0 * found,
        100.0 * false_pos,
        p.stats
    );
    assert_eq!(p.stats.sky_method, SkyMethod::DepthAndImage);
    assert!(
        found >= 0.95,
        "only {:.2} % of the sky found",
        100.0 * found
    );
    assert!(false_pos < 0.02, "{:.3} % false sky", 100.0 * false_pos);
    // The band below the sky is the scene: filled, not sky.
    let band_scene: Vec<usize> = (0..W * H)
        .filter(|&i| i % W < s.band_width && !s.sky.as_slice()[i])
        .collect();
    let band_sky = band_scene.iter().filter(|&&i| p.sky.as_slice()[i]).count();
    assert!(
        band_sky * 100 < band_scene.len(),
        "{band_sky} of {} band pixels below the sky called sky",
        band_scene.len()
    );
    assert!(band_scene
        .iter()
        .all(|&i| p.sky.as_slice()[i] || p.filled.as_slice()[i]));
    // Matcher noise in the sky was replaced by the sky's range.
    assert!(p.stats.sky_known_pixels > 0, "{:?}", p.stats);
    assert_all_finite(&p.range);
    let s_max = p.stats.s_max.unwrap();
    for i in 0..W * H {
        if p.sky.as_slice()[i] && p.range.as_slice()[i] > s_max {
            panic!("sky pixel {i} above Smax");
        }
    }
}

/// The airlight is the sky's colour, not the neutral grey of the scene's bright end.
#[test]
fn airlight_comes_from_the_sky() {
    let s = frame();
    let p = guided(&s);
    let a = estimate_airlight(&s.image, &p);
    let want = true_sky_colour(&s);
    eprintln!("airlight {:?}, true sky median {want:?}", a.rgb);
    assert_eq!(a.source, AirlightSource::Sky);
    for (got, want) in a.rgb.iter().zip(want) {
        assert!(
            (got - want).abs() < 0.03,
            "airlight {:?} vs sky {want:?}",
            a.rgb
        );
    }
    // Without the image (the user's case) it would have been a grey.
    let depth_only = prepare(&s.range, &PrepOptions::default()).unwrap();
    let grey = estimate_airlight(&s.image, &depth_only);
    assert_eq!(grey.source, AirlightSource::Neutral);
    assert!((grey.rgb[2] - want[2]).abs() > 0.1, "{:?}", grey.rgb);
}

/// Bogus far values in the scene are removed before `Rmax` is taken: the scale is the
/// scene's, and the removed pixels are filled like holes.
#[test]
fn far_outliers_do_not_set_the_scale() {
    let s = frame();
    assert_eq!(s.outliers.len(), 3, "planted");
    let p = guided(&s);
    let st = &p.stats;
    assert!(
        st.r_max <= 1.01 * s.scene_max,
        "Rmax {} but the scene ends at {}",
        st.r_max,
        s.scene_max
    );
    assert!(st.far_outliers >= 3, "{st:?}");
    for &i in &s.outliers {
        assert!(p.filled.as_slice()[i], "outlier {i} filled");
        assert!(p.range.as_slice()[i] <= st.r_max);
    }
    // Known values outside the sky below the cut are untouched, but for the few removed
    // as matcher noise in slivers of sky (then filled).
    let cut = st.far_cut.unwrap();
    let changed: Vec<usize> = (0..W * H)
        .filter(|&i| {
            let v = s.range.as_slice()[i];
            v.is_finite()
                && v <= cut
                && !p.sky.as_slice()[i]
                && v.to_bits() != p.range.as_slice()[i].to_bits()
        })
        .collect();
    assert!(
        changed.len() <= st.sky_noise,
        "{} changed, {st:?}",
        changed.len()
    );
    assert!(changed.iter().all(|&i| p.filled.as_slice()[i]));
    // With the rules off, the 100 km value is the scale (the local-outlier rule alone
    // removes it too: a speck far above its surroundings).
    let off = PrepOptions {
        far_outlier_factor: 0.0,
        local_outlier_factor: 0.0,
        ..PrepOptions::default()
    };
    let guides = Guides {
        image: Some(&s.image),
        sky_mask: None,
        ego_mask: None,
    };
    let p = prepare_guided(&s.range, guides, &off).unwrap();
    assert_eq!(p.stats.r_max, 1.0e5);
    assert_eq!((p.stats.far_outliers, p.stats.far_cut), (0, None));
}

/// A sky mask replaces detection, known range under it included.
#[test]
fn a_sky_mask_is_the_sky() {
    let s = frame();
    let guides = Guides {
        image: Some(&s.image),
        sky_mask: Some(&s.sky),
        ego_mask: None,
    };
    let p = prepare_guided(&s.range, guides, &PrepOptions::default()).unwrap();
    assert_eq!(p.stats.sky_method, SkyMethod::Mask);
    let (found, false_pos) = coverage(&s.sky, &p.sky);
    assert_eq!(found, 1.0);
    // Only unknown pixels with nothing but sky round them may join it (none here but the
    // wire's pixels between two sky pixels).
    assert!(false_pos < 0.002, "{false_pos}");
    let small = Grid::filled(W / 2, H, false);
    let bad = Guides {
        image: None,
        sky_mask: Some(&small),
        ego_mask: None,
    };
    let e = prepare_guided(&s.range, bad, &PrepOptions::default()).unwrap_err();
    assert!(
        e.to_string().contains("256x256") && e.to_string().contains("512x256"),
        "{e}"
    );
}

/// The real Aloe photo with its disparity: indoor, the image must not invent a sky.
#[test]
fn aloe_with_its_image_has_no_sky() {
    let map = aloe_range();
    let image = brume::io::image::load_linear_rgb(&aloe_path("left.jpg")).unwrap();
    let guides = Guides {
        image: Some(&image),
        sky_mask: None,
        ego_mask: None,
    };
    let p = prepare_guided(&map, guides, &PrepOptions::default()).unwrap();
    assert_eq!(
        (p.stats.sky_pixels, p.stats.far_outliers),
        (0, 0),
        "{:?}",
        p.stats
    );
    assert_known_unchanged(&map, &p.range);
}

/// Odd sizes and odd images: results or typed errors, never a panic.
#[test]
fn odd_inputs_never_panic() {
    let opts = PrepOptions::default();
    let run = |range: &brume::raster::ScalarMap, image: &brume::raster::RgbImage| {
        let guides = Guides {
            image: Some(image),
            sky_mask: None,
            ego_mask: None,
        };
        prepare_guided(range, guides, &opts)
    };
    let sky = [0.5f32, 0.6, 0.9];
    for (w, h) in [(1, 1), (1, 7), (7, 1), (2, 2), (16, 9)] {
        let mut range = Grid::from_fn(w, h, |x, y| 5.0 + (x + y) as f32);
        *range.get_mut(0, 0) = f32::NAN;
        for image in [
            Grid::filled(w, h, sky),
            Grid::filled(w, h, [0.0; 3]),
            Grid::filled(w, h, [f32::NAN; 3]),
            Grid::from_fn(
                w,
                h,
                |x, _| if x % 2 == 0 { sky } else { [1e30, 0.0, 1e30] },
            ),
        ] {
            match run(&range, &image) {
                Ok(p) => assert_all_finite(&p.range),
                Err(e) => assert!(matches!(e, brume::Error::Prep(_)), "{w}x{h}: {e}"),
            }
        }
    }
    let unknown = Grid::filled(8, 8, f32::NAN);
    assert!(matches!(
        run(&unknown, &Grid::filled(8, 8, sky)),
        Err(brume::Error::Prep(_))
    ));
    let e = run(&Grid::filled(8, 8, 1.0), &Grid::filled(8, 4, sky)).unwrap_err();
    assert!(matches!(e, brume::Error::SizeMismatch { .. }), "{e}");
}

// --- The command line -------------------------------------------------------------------

/// Writes the frame as `image.png` (8-bit sRGB) and `range.pfm`.
fn write_frame(dir: &Path, s: &StreetScene) {
    let rgba = Grid::from_fn(W, H, |x, y| {
        let c = s.image.get(x, y);
        [c[0], c[1], c[2], 1.0]
    });
    write_rgba(&dir.join("image.png"), &rgba).unwrap();
    write_scalar(&dir.join("range.pfm"), &s.range).unwrap();
}

fn write_labels(path: &Path, w: usize, h: usize, label: impl Fn(usize, usize) -> u8) {
    let px: Vec<u8> = (0..w * h).map(|i| label(i % w, i / w)).collect();
    image::save_buffer(path, &px, w as u32, h as u32, image::ColorType::L8).unwrap();
}

/// `brume prep` on the frame `write_frame` wrote, with `extra` options.
fn prep(dir: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "prep",
        "--depth",
        "range.pfm",
        "--depth-kind",
        "range",
        "--image",
        "image.png",
        "--out",
        "out.pfm",
    ];
    args.extend_from_slice(extra);
    brume(dir, &args)
}

fn prep_json(dir: &Path, extra: &[&str]) -> Value {
    let o = prep(dir, &[extra, &["--json"]].concat());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn cli_finds_the_sky_and_reports_the_outliers() {
    let dir = tempfile::tempdir().unwrap();
    let s = frame();
    write_frame(dir.path(), &s);
    let v = prep_json(dir.path(), &[]);
    assert_eq!(v["sky_method"], "depth-and-image", "{v}");
    assert_eq!(v["airlight_source"], "sky", "{v}");
    assert!(v["far_outliers"].as_u64().unwrap() >= 3, "{v}");
    assert!(
        v["far_cut"].as_f64().unwrap() > f64::from(s.scene_max),
        "{v}"
    );
    let truth = s.sky.as_slice().iter().filter(|&&t| t).count() as u64;
    let sky = v["sky_pixels"].as_u64().unwrap();
    assert!(
        sky >= truth * 95 / 100 && sky <= truth * 105 / 100,
        "{sky} vs {truth}"
    );
    assert!(
        v["r_max"].as_f64().unwrap() <= 1.01 * f64::from(s.scene_max),
        "{v}"
    );
}

#[test]
fn cli_sky_mask_binary_and_cityscapes_labels() {
    let dir = tempfile::tempdir().unwrap();
    let s = frame();
    write_frame(dir.path(), &s);
    let truth = s.sky.as_slice().iter().filter(|&&t| t).count() as u64;
    let sky_at = |x: usize, y: usize| *s.sky.get(x, y);
    // Binary: 255 = sky.
    write_labels(&dir.path().join("m.png"), W, H, |x, y| {
        if sky_at(x, y) {
            255
        } else {
            0
        }
    });
    // Cityscapes labelIds: 23 sky, 11 building, 7 road; told by the name.
    let labels = "f_000019_gtFine_labelIds.png";
    write_labels(&dir.path().join(labels), W, H, |x, y| {
        if sky_at(x, y) {
            23
        } else if y > H / 2 {
            7
        } else {
            11
        }
    });
    for (mask, format) in [
        ("m.png", None),
        (labels, None),
        (labels, Some("cityscapes-labelids")),
    ] {
        let mut extra = vec!["--sky-mask", mask];
        if let Some(f) = format {
            extra.extend(["--sky-mask-format", f]);
        }
        let v = prep_json(dir.path(), &extra);
        assert_eq!(v["sky_method"], "mask", "{v}");
        let want = if mask == labels {
            "cityscapes-labelids"
        } else {
            "binary"
        };
        assert_eq!(v["sky_mask_format"], want, "{v}");
        let sky = v["sky_pixels"].as_u64().unwrap();
        assert!(
            sky >= truth && sky <= truth + W as u64,
            "{mask}: {sky} vs {truth}"
        );
        assert!(
            v["sky_known_pixels"].as_u64().unwrap() > 0,
            "noise under the mask"
        );
    }
    // The label file read as binary is all sky (every label is non-zero), which is said,
    // not a panic.
    let o = brume(
        dir.path(),
        &[
            "prep",
            "--depth",
            "range.pfm",
            "--depth-kind",
            "range",
            "--out",
            "out.pfm",
            "--sky-mask",
            labels,
            "--sky-mask-format",
            "binary",
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("every pixel is sky"),
        "{err}"
    );
}

#[test]
fn cli_sky_mask_errors_name_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    let s = frame();
    write_frame(dir.path(), &s);
    write_labels(&dir.path().join("small.png"), 100, 50, |_, _| 255);
    let run = |extra: &[&str]| prep(dir.path(), extra);
    let o = run(&["--sky-mask", "small.png"]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(!o.status.success());
    assert!(
        err.contains("small.png") && err.contains("100x50") && err.contains("512x256"),
        "{err}"
    );
    assert!(!dir.path().join("out.pfm").exists(), "nothing written");
    // A colour PNG is not a label image.
    let rgb = vec![0u8; 3 * W * H];
    image::save_buffer(
        dir.path().join("c.png"),
        &rgb,
        W as u32,
        H as u32,
        image::ColorType::Rgb8,
    )
    .unwrap();
    let o = run(&[
        "--sky-mask",
        "c.png",
        "--sky-mask-format",
        "cityscapes-labelids",
    ]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(
        !o.status.success() && err.contains("c.png") && err.contains("grey"),
        "{err}"
    );
    let o = run(&["--sky-mask", "c.png", "--sky-mask-format", "labels"]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(
        !o.status.success() && err.contains("cityscapes-labelids"),
        "{err}"
    );
    let o = run(&["--sky-mask", "c.png", "--no-sky"]);
    assert!(!o.status.success());
    let o = run(&["--far-outlier-factor", "0.5"]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(
        !o.status.success() && err.contains("--far-outlier-factor"),
        "{err}"
    );
}

/// `--local-outliers`: stereo mismatches far above their surroundings but below the far
/// cut are removed and refilled (on by default), the rule can be off, and a bad factor is
/// refused by its flag's name.
#[test]
fn cli_local_outliers() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = frame();
    let planted = s.plant_mismatches(12, 60.0..170.0, 3);
    write_frame(dir.path(), &s);
    let v = prep_json(dir.path(), &[]);
    assert_eq!(
        v["local_outliers"].as_u64().unwrap(),
        planted.len() as u64,
        "{v}"
    );
    let v = prep_json(dir.path(), &["--local-outliers", "0"]);
    assert_eq!(v["local_outliers"], 0, "{v}");
    let o = prep(dir.path(), &["--local-outliers", "0.5"]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(
        !o.status.success() && err.contains("--local-outliers"),
        "{err}"
    );
}

/// `--ego-mask`: a Cityscapes labelIds file (label 1 = ego vehicle, 23 = sky) gives the
/// hood range 0; train ids are refused.
#[test]
fn cli_ego_mask_from_cityscapes_labels() {
    let dir = tempfile::tempdir().unwrap();
    let s = frame();
    write_frame(dir.path(), &s);
    let hood = |x: usize, y: usize| y >= H - 20 && (W / 4..3 * W / 4).contains(&x);
    let labels = "f_000019_gtFine_labelIds.png";
    write_labels(&dir.path().join(labels), W, H, |x, y| {
        if hood(x, y) {
            1
        } else if *s.sky.get(x, y) {
            23
        } else {
            7
        }
    });
    let v = prep_json(dir.path(), &["--ego-mask", labels]);
    let n = (0..W * H).filter(|&i| hood(i % W, i / W)).count();
    assert_eq!(v["ego_pixels"].as_u64().unwrap(), n as u64, "{v}");
    assert_eq!(v["sky_method"], "depth-and-image", "{v}");
    let out = match brume::io::codec::pfm::read_pfm(&dir.path().join("out.pfm")).unwrap() {
        brume::io::codec::pfm::Pfm::Grey(m) => m,
        other => panic!("{other:?}"),
    };
    for y in 0..H {
        for x in 0..W {
            let r = *out.get(x, y);
            assert_eq!(r == 0.0, hood(x, y), "({x}, {y}): {r}");
        }
    }
    // The same file as the sky mask and the ego mask at once.
    let v = prep_json(dir.path(), &["--ego-mask", labels, "--sky-mask", labels]);
    assert_eq!(
        (v["sky_method"].as_str(), v["ego_pixels"].as_u64()),
        (Some("mask"), Some(n as u64)),
        "{v}"
    );
    let trainids = "f_000019_gtFine_labelTrainIds.png";
    write_labels(&dir.path().join(trainids), W, H, |_, _| 0);
    let o = prep(dir.path(), &["--ego-mask", trainids]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(
        !o.status.success() && err.contains(trainids) && err.contains("labelIds"),
        "{err}"
    );
}

/// The ego vehicle is never fogged, end to end: pre-processing gives the hood range 0,
/// and the fog reads 0 as at the camera (τ = 1), in normalised and in physical units, so
/// the rendered hood is the input (no blur here: with it, its border takes the
/// diffusion's flux from its neighbours). Before, the fog took 0 as unknown and so as
/// the farthest range: the hood came out as fogged as the sky.
#[test]
fn ego_vehicle_is_never_fogged() {
    use brume::photo::{self, FogOptions, Photo, PrepareOptions};
    use brume::refine::RefineMode;
    let s = frame();
    let hood = |x: usize, y: usize| y >= H - 20 && (W / 4..3 * W / 4).contains(&x);
    let photo = Photo::from_range(s.image.clone(), s.range.clone()).unwrap();
    let mut opts = PrepareOptions {
        ego_mask: Some(Grid::from_fn(W, H, hood)),
        ..PrepareOptions::default()
    };
    opts.refine.mode = RefineMode::None;
    let (_lock, mut headless) = common::renderer();
    let renderer = headless.renderer().unwrap();
    let prepared = photo::prepare(&photo, &opts, renderer).unwrap();
    for fog in [FogOptions::default(), FogOptions::beta(0.02).unwrap()] {
        let fog = FogOptions { lambda: 0.0, ..fog };
        let fogged = photo::fog(renderer, &photo, &prepared, &fog).unwrap();
        let (mut hood_error, mut rest_change) = (0f32, 0f32);
        for y in 0..H {
            for x in 0..W {
                let (out, input) = (fogged.rendered.image.get(x, y), s.image.get(x, y));
                let d = (0..3)
                    .map(|c| (out[c] - input[c]).abs())
                    .fold(0f32, f32::max);
                if hood(x, y) {
                    hood_error = hood_error.max(d);
                } else {
                    rest_change = rest_change.max(d);
                }
            }
        }
        assert!(
            hood_error < 1e-6,
            "{:?}: hood changed by {hood_error}",
            fog.extinction
        );
        assert!(rest_change > 0.1, "{:?}: no fog at all", fog.extinction);
    }
}
