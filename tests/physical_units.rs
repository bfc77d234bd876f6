//! `brume render --beta/--visibility/--albedo`: fog in physical units on range in metres
//! (here from Cityscapes disparities and camera files the tests write), end to end:
//! τ = exp(−β·R) at pixels of known range, --beta and --visibility render the same bytes,
//! a far outlier no longer changes the fog of the rest, the JSON report, bad values
//! refused with a clear message and nothing written, and a phone's shallow depth under a
//! sky that fog veils.

use brume::io::output::{write_rgba, write_scalar};
use brume::raster::{Grid, RgbImage};
use serde_json::Value;
use std::path::Path;
use std::process::Output;

use crate::common;

use common::{brume, stderr};

/// ln 20: β·V at the visibility.
const LN_20: f64 = 2.995_732_273_553_991;

fn json(o: &Output) -> Value {
    assert!(o.status.success(), "{}", stderr(o));
    serde_json::from_slice(&o.stdout).expect("one JSON object on stdout")
}

fn number(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} is not a number in {v}"))
}

/// A Cityscapes camera: baseline in metres, square pixels of focal `f`, principal point.
struct Camera {
    baseline: f64,
    f: f64,
    u0: f64,
    v0: f64,
}

impl Camera {
    /// Range in metres of stored disparity value `p` at pixel (x, y), by hand:
    /// d = (p − 1)/256, Z = baseline·f/d, R = Z·sqrt(1 + ((x − u0)/f)² + ((y − v0)/f)²).
    fn range(&self, p: u16, x: usize, y: usize) -> f64 {
        let d = (f64::from(p) - 1.0) / 256.0;
        let z = self.baseline * self.f / d;
        let (u, v) = ((x as f64 - self.u0) / self.f, (y as f64 - self.v0) / self.f);
        z * (1.0 + u * u + v * v).sqrt()
    }

    fn json(&self) -> String {
        format!(
            r#"{{"extrinsic": {{"baseline": {}}}, "intrinsic": {{"fx": {f}, "fy": {f}, "u0": {}, "v0": {}}}}}"#,
            self.baseline,
            self.u0,
            self.v0,
            f = self.f
        )
    }
}

/// Writes `scene_disparity.png` (16-bit, `p(x, y)`) and `scene_camera.json` beside it, for
/// `brume` to find; returns the stored values, row 0 first.
fn cityscapes(
    dir: &Path,
    w: usize,
    h: usize,
    camera: &Camera,
    p: impl Fn(usize, usize) -> u16,
) -> Grid<u16> {
    let values = Grid::from_fn(w, h, p);
    let png = image::ImageBuffer::<image::Luma<u16>, _>::from_raw(
        w as u32,
        h as u32,
        values.as_slice().to_vec(),
    )
    .unwrap();
    png.save(dir.join("scene_disparity.png")).unwrap();
    std::fs::write(dir.join("scene_camera.json"), camera.json()).unwrap();
    values
}

/// A colour image with structure for the blur to act on.
fn colour(dir: &Path, name: &str, w: usize, h: usize) {
    let img = Grid::from_fn(w, h, |x, y| {
        let check = ((x / 3 + y / 3) % 2) as f32;
        [
            0.2 + 0.6 * check,
            x as f32 / w as f32,
            y as f32 / h as f32,
            1.0,
        ]
    });
    write_rgba(&dir.join(name), &img).unwrap();
}

/// `brume render` of the test's Cityscapes frame, with the range as the disparity gives it:
/// the image-guided refinement (on by default for Cityscapes) is off, so that τ can be
/// checked against exp(−βR) of the range worked out by hand.
fn render(dir: &Path, image: &str, extra: &[&str]) -> Output {
    let mut args = vec!["render", "--image", image, "--depth", "scene_disparity.png"];
    args.extend_from_slice(&["--refine", "none"]);
    args.extend_from_slice(extra);
    brume(dir, &args)
}

fn load(path: &Path) -> RgbImage {
    brume::io::image::load_linear_rgb(path).unwrap()
}

/// The flags that make the output τ itself on a white image: `--beta 0.02` ([`BETA`]), a
/// black airlight, no blur, `tau.pfm`, and the JSON report.
const TAU_FLAGS: [&str; 9] = [
    "--beta",
    "0.02",
    "--airlight",
    "0,0,0",
    "--lambda",
    "0",
    "--out",
    "tau.pfm",
    "--json",
];
/// The β of [`TAU_FLAGS`].
const BETA: f64 = 0.02;

/// Asserts that every channel of `tau` is exp(−β·R) with β = [`BETA`] and R = `range(x,
/// y)` worked out by hand, within 2e-6 (f32 range and exp on the GPU); returns the least
/// and largest R.
fn assert_tau_is_exp_minus_beta_r(
    tau: &RgbImage,
    range: impl Fn(usize, usize) -> f64,
) -> (f64, f64) {
    let (mut r_min, mut r_max) = (f64::INFINITY, 0f64);
    for y in 0..tau.height() {
        for x in 0..tau.width() {
            let r = range(x, y);
            (r_min, r_max) = (r_min.min(r), r_max.max(r));
            let want = (-BETA * r).exp();
            for got in tau.get(x, y) {
                assert!(
                    (f64::from(*got) - want).abs() < 2e-6,
                    "({x}, {y}): τ = {got}, expected exp(−{BETA}·{r:.3}) = {want}"
                );
            }
        }
    }
    (r_min, r_max)
}

/// On a white image with a black airlight and no blur the output is τ itself: every
/// pixel must be exp(−β·R) with R worked out by hand from the disparity and the camera.
/// A normalised κ (τ = exp(−κ·R/Rmax)) or a range left along the optical axis fails.
#[test]
fn tau_is_exp_minus_beta_r_at_every_pixel_of_known_range() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (16, 8);
    // Wide rays: the stretch to range reaches 1.5 % at the corners.
    let camera = Camera {
        baseline: 0.5,
        f: 40.0,
        u0: 7.5,
        v0: 3.5,
    };
    // d = (26 + 13·i)/256 px for pixel i: Z from 197 m down to 3.1 m.
    let p = cityscapes(dir.path(), w, h, &camera, |x, y| {
        1 + 26 + 13 * (x + w * y) as u16
    });
    let white = Grid::filled(w, h, [1.0f32, 1.0, 1.0, 1.0]);
    write_rgba(&dir.path().join("white.pfm"), &white).unwrap();
    let beta = BETA;
    let v = json(&render(dir.path(), "white.pfm", &TAU_FLAGS));
    let out = load(&dir.path().join("tau.pfm"));
    let (r_min, r_max) =
        assert_tau_is_exp_minus_beta_r(&out, |x, y| camera.range(*p.get(x, y), x, y));
    assert!(r_max > 190.0 && r_min < 3.2, "{r_min}..{r_max}");
    // The report: the fog, its visibility, and τ's range over the pixels, 1e-6 (f32).
    assert_eq!(number(&v, "beta"), beta, "{v}");
    assert!(
        (number(&v, "visibility_m") - LN_20 / beta).abs() < 1e-9,
        "{v}"
    );
    assert_eq!(number(&v, "albedo"), 1.0, "{v}");
    assert!(
        (number(&v, "range_divisor") - LN_20 / beta).abs() < 1e-9,
        "{v}"
    );
    let t_min = number(&v, "transmittance_min");
    let t_max = number(&v, "transmittance_max");
    assert!((t_min - (-beta * r_max).exp()).abs() < 1e-6, "{v}");
    assert!((t_max - (-beta * r_min).exp()).abs() < 1e-6, "{v}");
    assert_eq!(v["depth_format"], "cityscapes", "{v}");
    // λ = 0: nothing blurs beyond σ0.
    assert_eq!(number(&v, "sigma_max"), number(&v, "sigma0"), "{v}");
}

/// A renderer's z-buffer whose near and far planes are in metres (`--depth-scale 1`)
/// takes physical fog: τ = exp(−β·R) at every pixel, R worked out by hand from the stored
/// window depth, the planes and the field of view, from OpenGL's standard buffer and from
/// an engine's reversed-Z one with an infinite far plane. Without `--depth-scale` its
/// range is in the planes' unknown unit, and --beta is refused saying what would do.
#[test]
fn a_zbuffer_with_planes_in_metres_takes_physical_fog() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (16, 8);
    let (near, far, fov_deg) = (0.5f64, 400.0f64, 60.0f64);
    // Eye depth z from 2 to 192.5 m; window depth d = f·(1 − n/z)/(f − n).
    let zbuffer = Grid::from_fn(w, h, |x, y| {
        let z = 2.0 + 1.5 * (x + w * y) as f64;
        (far * (1.0 - near / z) / (far - near)) as f32
    });
    write_scalar(&dir.path().join("z.pfm"), &zbuffer).unwrap();
    let white = Grid::filled(w, h, [1.0f32, 1.0, 1.0, 1.0]);
    write_rgba(&dir.path().join("white.pfm"), &white).unwrap();
    let base = [
        &[
            "render",
            "--image",
            "white.pfm",
            "--depth",
            "z.pfm",
            "--depth-kind",
            "zbuffer",
            "--near",
            "0.5",
            "--far",
            "400",
            "--fov",
            "60",
            "--refine",
            "none",
        ][..],
        &TAU_FLAGS,
    ]
    .concat();
    let refused = brume(dir.path(), &base);
    let err = stderr(&refused);
    assert_eq!(refused.status.code(), Some(1), "{err}");
    for said in [
        "invalid --beta = 0.02",
        "z.pfm",
        "zbuffer",
        "file units",
        "--depth-scale",
    ] {
        assert!(err.contains(said), "{said}: {err}");
    }
    assert!(!dir.path().join("tau.pfm").exists());

    let v = json(&brume(
        dir.path(),
        &[&base[..], &["--depth-scale", "1"]].concat(),
    ));
    let notes = v["depth_notes"].to_string();
    assert!(notes.contains("near and far x 1 = metres"), "{v}");
    let out = load(&dir.path().join("tau.pfm"));
    let focal = h as f64 / 2.0 / (fov_deg.to_radians() / 2.0).tan();
    let (cx, cy) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
    let (r_min, r_max) = assert_tau_is_exp_minus_beta_r(&out, |x, y| {
        let d = f64::from(*zbuffer.get(x, y));
        let z = near * far / (far - d * (far - near));
        let (u, v) = ((x as f64 - cx) / focal, (y as f64 - cy) / focal);
        z * (1.0 + u * u + v * v).sqrt()
    });
    // Wide rays: z 2 m at a corner is R 3.1 m, 192.5 m at the other 300 m.
    assert!(r_min < 3.2 && r_max > 290.0, "{r_min}..{r_max}");

    // An engine's reversed-Z buffer with an infinite far plane (Bevy's, Unreal's):
    // d = n/z, the same eye depths.
    let reversed = Grid::from_fn(w, h, |x, y| {
        (near / (2.0 + 1.5 * (x + w * y) as f64)) as f32
    });
    write_scalar(&dir.path().join("rz.pfm"), &reversed).unwrap();
    let args: Vec<&str> = base
        .iter()
        .map(|a| match *a {
            "z.pfm" => "rz.pfm",
            "400" => "inf",
            a => a,
        })
        .chain(["--reversed-z", "--depth-scale", "1"])
        .collect();
    let v = json(&brume(dir.path(), &args));
    assert!(v["depth_notes"].to_string().contains("reversed-Z"), "{v}");
    let out = load(&dir.path().join("tau.pfm"));
    let (r_min, r_max) = assert_tau_is_exp_minus_beta_r(&out, |x, y| {
        let z = near / f64::from(*reversed.get(x, y));
        let (u, v) = ((x as f64 - cx) / focal, (y as f64 - cy) / focal);
        z * (1.0 + u * u + v * v).sqrt()
    });
    assert!(r_min < 3.2 && r_max > 290.0, "{r_min}..{r_max}");
}

/// --json: σmax follows the law σ0 + λ·√(a·ln 20) whatever β; --albedo moves the blur, not
/// τ; without physical fog the new fields are null.
#[test]
fn json_reports_the_fog_and_the_blur_law() {
    let dir = tempfile::tempdir().unwrap();
    let camera = Camera {
        baseline: 0.209313,
        f: 2262.52,
        u0: 5.5,
        v0: 3.5,
    };
    cityscapes(dir.path(), 12, 8, &camera, |x, _| 1 + 256 * (10 + x as u16));
    colour(dir.path(), "im.png", 12, 8);
    let run = |extra: &[&str]| {
        let mut args = vec!["--out", "fog.png", "--json", "--lambda", "6"];
        args.extend_from_slice(extra);
        json(&render(dir.path(), "im.png", &args))
    };
    for beta in ["0.005", "0.01", "0.02"] {
        let v = run(&["--beta", beta, "--albedo", "0.5"]);
        assert_eq!(number(&v, "albedo"), 0.5, "{v}");
        let want = 1.0 + 6.0 * (0.5 * LN_20).sqrt();
        assert!((number(&v, "sigma_max") - want).abs() < 1e-12, "{v}");
        // τ is exp(−β·R) whatever the albedo: over 10..21 px of disparity, 22.6..47.4 m.
        let b: f64 = beta.parse().unwrap();
        let t_max = number(&v, "transmittance_max");
        let nearest = (0..8)
            .map(|y| camera.range(1 + 256 * 21, 11, y))
            .fold(f64::INFINITY, f64::min);
        assert!((t_max - (-b * nearest).exp()).abs() < 1e-6, "{v}");
    }
    let v = run(&["--visibility", "300"]);
    assert!((number(&v, "beta") - LN_20 / 300.0).abs() < 1e-15, "{v}");
    assert!((number(&v, "visibility_m") - 300.0).abs() < 1e-9, "{v}");
    let v = run(&[]);
    for key in ["beta", "visibility_m", "albedo"] {
        assert!(v[key].is_null(), "{key} in {v}");
    }
    assert!(number(&v, "transmittance_min") < number(&v, "transmittance_max"));
}

/// The same fog named two ways renders the same bytes.
#[test]
fn beta_and_visibility_render_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let camera = Camera {
        baseline: 0.209313,
        f: 2262.52,
        u0: 15.5,
        v0: 11.5,
    };
    cityscapes(dir.path(), 32, 24, &camera, |x, y| {
        1 + 256 * (4 + ((x + 2 * y) % 16) as u16)
    });
    colour(dir.path(), "im.png", 32, 24);
    let visibility = format!("{}", LN_20 / 0.01);
    for (out, flags) in [
        ("beta.png", ["--beta", "0.01"]),
        ("visibility.png", ["--visibility", visibility.as_str()]),
    ] {
        let o = render(
            dir.path(),
            "im.png",
            &[&flags[..], &["--out", out]].concat(),
        );
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let a = std::fs::read(dir.path().join("beta.png")).unwrap();
    let b = std::fs::read(dir.path().join("visibility.png")).unwrap();
    assert!(a == b, "--beta 0.01 and --visibility {visibility} differ");
    // And it is fog: a denser one renders something else.
    let o = render(
        dir.path(),
        "im.png",
        &["--beta", "0.04", "--out", "dense.png"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(std::fs::read(dir.path().join("dense.png")).unwrap() != a);
}

/// The point of physical units: one bogus far pixel (Cityscapes' disparity 1/256 px,
/// 121 km) leaves the fog of every other pixel as it was under --beta, where with
/// normalised κ it thins the fog of the whole frame.
#[test]
fn a_far_outlier_does_not_change_the_fog_of_the_rest() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (40, 30);
    let camera = Camera {
        baseline: 0.209313,
        f: 2262.52,
        u0: 19.5,
        v0: 14.5,
    };
    let outlier = (20, 15);
    // d from 6 to 42 px: 79 m down to 11 m.
    let scene = |x: usize, y: usize| 1 + 256 * (6 + 4 * ((x + y) % 10) as u16);
    colour(dir.path(), "im.png", w, h);
    let mut renders = Vec::new();
    for with_outlier in [false, true] {
        cityscapes(dir.path(), w, h, &camera, |x, y| {
            if with_outlier && (x, y) == outlier {
                2
            } else {
                scene(x, y)
            }
        });
        let fogs = [
            // The outlier rules off (far, and the local one that catches it too) ...
            (
                "beta",
                &[
                    "--beta",
                    "0.02",
                    "--far-outlier-factor",
                    "0",
                    "--local-outliers",
                    "0",
                ][..],
            ),
            (
                "kappa",
                &["--far-outlier-factor", "0", "--local-outliers", "0"][..],
            ),
            // ... and on, the defaults.
            ("kappa-cut", &[][..]),
        ];
        for (name, fog) in fogs {
            let out = format!("{name}-{with_outlier}.pfm");
            let mut args = fog.to_vec();
            args.extend(["--airlight", "0.7,0.75,0.8", "--out", out.as_str()]);
            // Full resolution, whose locality the bounds below measure: the coarse stage
            // (the default) spreads an increment over its levels' texels (2.6e-5 at 10 px).
            args.extend(["--coarse-from", "off"]);
            let o = render(dir.path(), "im.png", &args);
            assert!(o.status.success(), "{}", stderr(&o));
            renders.push(load(&dir.path().join(out)));
        }
    }
    let [beta, kappa, kappa_cut, beta_out, kappa_out, kappa_cut_out] = &renders[..] else {
        unreachable!("six renders");
    };
    // Largest change of a pixel at least `gap` px (Chebyshev) from the outlier.
    let change = |a: &RgbImage, b: &RgbImage, gap: usize| {
        let mut worst = 0f32;
        for y in 0..h {
            for x in 0..w {
                if x.abs_diff(outlier.0).max(y.abs_diff(outlier.1)) < gap {
                    continue;
                }
                for c in 0..3 {
                    worst = worst.max((a.get(x, y)[c] - b.get(x, y)[c]).abs());
                }
            }
        }
        worst
    };
    // Under --beta only the blur carries the outlier's colour to its neighbours, about as
    // far as its σmax (1 + 8·√ln 20 = 14.8 px, the scale at which the outlier itself is
    // blurred, falling off fast in the neighbours' smaller σ): measured 0.047 at 1 px,
    // 2e-4 at 8 px, 3.5e-6 from 10 px on (f32 noise of the diffusion).
    let physical = change(beta, beta_out, 10);
    assert!(
        physical < 1e-5,
        "--beta: the outlier moved far pixels by {physical}"
    );
    assert!(change(beta, beta_out, 1) < 0.1);
    // With normalised κ and pre-processing's far-outlier rule off, the same outlier sets
    // the frame's scale and thins the fog everywhere (measured 0.44) ...
    let normalised = change(kappa, kappa_out, 10);
    assert!(
        normalised > 0.2,
        "normalised κ moved far pixels by only {normalised}"
    );
    // ... and with the rule on (the default), the outlier is taken as unknown first.
    let cut = change(kappa_cut, kappa_cut_out, 10);
    assert!(cut < 1e-5, "the far-outlier rule left a change of {cut}");
}

/// Bad values, and physical fog on a range that is not in metres: one clear line, the
/// right exit code, nothing written.
#[test]
fn bad_physical_values_are_refused_before_writing() {
    let dir = tempfile::tempdir().unwrap();
    let camera = Camera {
        baseline: 0.209313,
        f: 2262.52,
        u0: 3.5,
        v0: 2.5,
    };
    cityscapes(dir.path(), 8, 6, &camera, |x, _| 1 + 256 * (10 + x as u16));
    colour(dir.path(), "im.png", 8, 6);
    write_scalar(&dir.path().join("range.pfm"), &Grid::filled(8, 6, 5.0)).unwrap();
    let fails = |args: &[&str], code: i32, needles: &[&str]| {
        let o = brume(dir.path(), args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(code), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
        for n in needles {
            assert!(
                err.contains(n),
                "{args:?}: stderr should mention {n:?}: {err}"
            );
        }
        assert!(!dir.path().join("o.png").exists(), "{args:?} wrote");
        assert!(
            !dir.path().join("brume-demo.png").exists(),
            "{args:?} wrote"
        );
    };
    let cs = [
        "render",
        "--image",
        "im.png",
        "--depth",
        "scene_disparity.png",
        "--out",
        "o.png",
    ];
    let with = |extra: &[&'static str]| [&cs[..], extra].concat();
    fails(
        &with(&["--beta", "-0.01"]),
        1,
        &["brume: error: invalid --beta = -0.01", "> 0 in m⁻¹"],
    );
    fails(&with(&["--beta", "0"]), 1, &["invalid --beta = 0"]);
    fails(
        &with(&["--visibility", "-300"]),
        1,
        &["invalid --visibility = -300", "metres"],
    );
    fails(
        &with(&["--beta", "0.01", "--albedo", "1.5"]),
        1,
        &["invalid --albedo = 1.5", "from 0"],
    );
    fails(
        &with(&["--albedo", "0.5"]),
        1,
        &["invalid --albedo = 0.5", "--beta or --visibility"],
    );
    fails(
        &with(&["--beta", "0.01", "--medium", "aerial", "--fov", "40"]),
        1,
        &["invalid --beta = 0.01", "--medium haze"],
    );
    fails(
        &with(&["--beta", "0.01", "--uniform-sigma", "3"]),
        1,
        &["invalid --beta", "--uniform-sigma"],
    );
    // Two ways of giving the extinction at once: clap's usage error, exit 2.
    fails(
        &with(&["--beta", "0.01", "--visibility", "300"]),
        2,
        &["--beta", "--visibility", "cannot be used with"],
    );
    fails(
        &with(&["--visibility", "300", "--ks", "1"]),
        2,
        &["--visibility", "--ks"],
    );
    fails(
        &with(&["--ka", "0.1", "--beta", "0.01"]),
        2,
        &["--ka", "--beta"],
    );
    // A range in file units, and the demo's approximate geometry, are not metres.
    fails(
        &[
            "render",
            "--image",
            "im.png",
            "--depth",
            "range.pfm",
            "--depth-kind",
            "range",
            "--beta",
            "0.01",
            "--out",
            "o.png",
        ],
        1,
        &[
            "invalid --beta = 0.01",
            "range.pfm",
            "float",
            "file units",
            "--camera",
            "--calib",
        ],
    );
    // Middlebury 2006 is metres only with its geometry given in full.
    image::GrayImage::from_pixel(8, 6, image::Luma([60u8]))
        .save(dir.path().join("disp.png"))
        .unwrap();
    let mb = [
        "render", "--image", "im.png", "--depth", "disp.png", "--beta", "0.01", "--out",
    ];
    fails(
        &[&mb[..], &["o.png"]].concat(),
        1,
        &["disp.png", "middlebury2006", "approximate", "--focal"],
    );
    let geometry = [
        "--focal",
        "3740",
        "--baseline",
        "160",
        "--disparity-offset",
        "270",
    ];
    let o = brume(dir.path(), &[&mb[..], &["mb.png"], &geometry[..]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    fails(
        &["render", "--visibility", "300"],
        1,
        &[
            "invalid --visibility = 300",
            "built-in demo",
            "middlebury2006",
            "--depth",
        ],
    );
}

/// The library refuses physical fog on a range not in metres in its own words: the
/// options it names are fields in backticks, which the command line shows as flags.
#[test]
fn the_library_says_what_would_make_a_range_metric() {
    let dir = tempfile::tempdir().unwrap();
    colour(dir.path(), "im.png", 8, 6);
    write_scalar(&dir.path().join("range.pfm"), &Grid::filled(8, 6, 5.0f32)).unwrap();
    let photo = brume::photo::Photo::load(
        &dir.path().join("im.png"),
        &dir.path().join("range.pfm"),
        &brume::io::depth::DepthOptions::default(),
    )
    .unwrap();
    let e = photo.require_metres("beta", 0.01).unwrap_err().to_string();
    for said in [
        "invalid beta = 0.01",
        "range.pfm was read as float depth in file units",
        "`calib` calib.txt, `camera` NAME_camera.json",
        "a metric `depth_format`",
        "`depth_scale` in metres per unit",
        "`ka`/`ks`",
    ] {
        assert!(e.contains(said), "{said}: {e}");
    }
    let options = brume::photo::FogOptions::beta(0.01).unwrap();
    let mut gpu = brume::Headless::new(None).unwrap();
    let prepared = brume::photo::prepare(
        &photo,
        &brume::photo::PrepareOptions::for_photo(&photo),
        gpu.renderer().unwrap(),
    )
    .unwrap();
    let fogged = brume::photo::fog(gpu.renderer().unwrap(), &photo, &prepared, &options);
    assert_eq!(fogged.unwrap_err().to_string(), e);

    // Aerial perspective reads metres too: without `metres_per_unit` it is refused on
    // this range, and given, the medium takes it.
    let camera = brume::camera::Camera::default();
    let mut aerial = brume::photo::AerialOptions::new(3.0, camera);
    let e = brume::photo::aerial(&photo, &prepared, &aerial).unwrap_err();
    let e = e.to_string();
    assert!(
        e.starts_with("invalid metres_per_unit = (missing)")
            && e.contains("range.pfm's range")
            && e.contains("give `metres_per_unit`, or a metric depth"),
        "{e}"
    );
    aerial.metres_per_unit = Some(2.0);
    let fogged = brume::photo::aerial(&photo, &prepared, &aerial).unwrap();
    assert_eq!(fogged.medium.metres_per_unit, 2.0);
}

/// `--compat foggy-cityscapes`: every output code value is Foggy Cityscapes' blend of the
/// input's code values, R·t + L·(1 − t) with t = exp(−βR) and R worked out by hand from
/// the disparity and the camera, within 1 of 255 (the output's rounding).
#[test]
fn foggy_cityscapes_blends_code_values() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (12, 8);
    let camera = Camera {
        baseline: 0.209313,
        f: 2262.52,
        u0: 5.5,
        v0: 3.5,
    };
    let p = cityscapes(dir.path(), w, h, &camera, |x, y| {
        1 + 256 * (10 + (x + y) as u16)
    });
    colour(dir.path(), "im.png", w, h);
    let o = render(
        dir.path(),
        "im.png",
        &[
            "--beta",
            "0.02",
            "--compat",
            "foggy-cityscapes",
            "--airlight",
            "1,0.5,0.25",
            "--out",
            "fc.png",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let input = image::open(dir.path().join("im.png")).unwrap().to_rgb8();
    let output = image::open(dir.path().join("fc.png")).unwrap().to_rgb8();
    let airlight = [1.0f32, 0.5, 0.25].map(brume::io::image::linear_to_srgb);
    let mut worst = 0i32;
    for y in 0..h {
        for x in 0..w {
            let t = (-0.02 * camera.range(*p.get(x, y), x, y)).exp() as f32;
            for (c, l) in airlight.iter().enumerate() {
                let r = f32::from(input.get_pixel(x as u32, y as u32)[c]) / 255.0;
                let want = (255.0 * (r * t + l * (1.0 - t))).round() as i32;
                let got = i32::from(output.get_pixel(x as u32, y as u32)[c]);
                worst = worst.max((got - want).abs());
            }
        }
    }
    assert!(worst <= 1, "off by {worst} code values");
}

/// `--transmittance-map`: a white image under black air with no blur comes out as the
/// map's τ itself, code / 255 (a 0 as half a step), at every pixel.
#[test]
fn a_transmittance_map_is_applied_as_given() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (16, 8);
    let white = Grid::filled(w, h, [1.0f32, 1.0, 1.0, 1.0]);
    write_rgba(&dir.path().join("white.pfm"), &white).unwrap();
    // The top rows, which a sky mask covers below, far denser than the rest (a sky's τ
    // near 0 in a map).
    let codes = |x: usize, y: usize| match y < 3 {
        true => (2 + x % 3) as u8,
        false => (40 + (x * 17 + y * 31) % 216) as u8,
    };
    image::GrayImage::from_fn(w as u32, h as u32, |x, y| {
        image::Luma([codes(x as usize, y as usize)])
    })
    .save(dir.path().join("tau.png"))
    .unwrap();
    let args = [
        "render",
        "--image",
        "white.pfm",
        "--transmittance-map",
        "tau.png",
        "--airlight",
        "0,0,0",
        "--lambda",
        "0",
        "--out",
        "out.pfm",
    ];
    let o = brume(dir.path(), &args);
    assert!(o.status.success(), "{}", stderr(&o));
    // With a sky mask too, whose sky physical fog would otherwise see 1 km away: the
    // map's τ there as given as well.
    image::GrayImage::from_fn(w as u32, h as u32, |_, y| {
        image::Luma([255 * u8::from(y < 3)])
    })
    .save(dir.path().join("sky.png"))
    .unwrap();
    let mut masked = args.to_vec();
    masked.extend(["--sky-mask", "sky.png", "--json"]);
    let out_at = masked.iter().position(|a| *a == "out.pfm").unwrap();
    masked[out_at] = "masked.pfm";
    let report = json(&brume(dir.path(), &masked));
    assert_eq!(report["prep"]["sky_pixels"], 3 * w, "{report}");
    assert!(report["prep"]["s_max"].is_null(), "{report}");
    for out in ["out.pfm", "masked.pfm"] {
        let out = load(&dir.path().join(out));
        for y in 0..h {
            for x in 0..w {
                let want = (f32::from(codes(x, y)) / 255.0).max(0.5 / 255.0);
                for got in out.get(x, y) {
                    // exp(ln τ) in f32 on the GPU: a few ulps.
                    assert!((got - want).abs() < 2e-6, "({x}, {y}): {got} vs {want}");
                }
            }
        }
    }
    // A map with --depth, or with --beta, is a malformed command line.
    for extra in [["--depth", "tau.png"], ["--beta", "0.01"]] {
        let mut args = vec![
            "render",
            "--image",
            "white.pfm",
            "--transmittance-map",
            "tau.png",
        ];
        args.extend_from_slice(&extra);
        args.extend_from_slice(&["--out", "x.png"]);
        let o = brume(dir.path(), &args);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {}", stderr(&o));
    }
}

/// `--right`: a disparity whose match in the right image has another colour fails Foggy
/// Cityscapes' left-right check (12/255) and is taken as unknown; true matches pass. A
/// right view's disparity (`--stereo-view right`) is checked against the left image. And
/// `--refine unreliable` keeps every measured range that pre-processing did not fill: τ
/// there is exp(−βR) of the disparity, to f32.
#[test]
fn left_right_check_and_refining_only_the_unreliable() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (40, 12);
    let camera = Camera {
        baseline: 0.209313,
        f: 2262.52,
        u0: 19.5,
        v0: 5.5,
    };
    let texture = |u: f32, y: usize| {
        let v = 0.5 + 0.4 * (u * 0.9 + y as f32).sin();
        [v, 0.8 * v, 0.3, 1.0]
    };
    let left = Grid::from_fn(w, h, |x, y| texture(x as f32, y));
    let right = Grid::from_fn(w, h, |x, y| texture(x as f32 + 4.0, y));
    write_rgba(&dir.path().join("left.png"), &left).unwrap();
    write_rgba(&dir.path().join("right.png"), &right).unwrap();
    let bad = (30, 6);
    let p = cityscapes(dir.path(), w, h, &camera, |x, y| {
        if (x, y) == bad {
            1 + 256 * 9
        } else {
            1 + 256 * 4
        }
    });
    let run = |extra: &[&str]| {
        let mut args = vec!["--beta", "0.01", "--out", "o.pfm", "--json"];
        args.extend_from_slice(extra);
        json(&render(dir.path(), "left.png", &args))
    };
    let v = run(&["--right", "right.png"]);
    let notes = v["depth_notes"].to_string();
    assert!(
        notes.contains("1 px failed the left-right check"),
        "{notes}"
    );
    // The same map as the right view's disparity, the left image the other one: right(x)
    // matches left(x + 4), and the pixel of 9 px does not.
    let failed = |extra: &[&str]| {
        let mut args = vec!["--beta", "0.01", "--out", "o.pfm", "--json"];
        args.extend_from_slice(&["--right", "left.png"]);
        args.extend_from_slice(extra);
        json(&render(dir.path(), "right.png", &args))["depth_notes"].to_string()
    };
    let as_right = failed(&["--stereo-view", "right"]);
    assert!(
        as_right.contains("1 px failed the left-right check"),
        "{as_right}"
    );
    let as_left = failed(&[]);
    assert!(!as_left.contains("1 px failed"), "{as_left}");

    // --refine unreliable (run directly: the helper above gives --refine none).
    let white = Grid::filled(w, h, [1.0f32, 1.0, 1.0, 1.0]);
    write_rgba(&dir.path().join("white.pfm"), &white).unwrap();
    let o = brume(
        dir.path(),
        &[
            "render",
            "--image",
            "white.pfm",
            "--depth",
            "scene_disparity.png",
            "--beta",
            "0.01",
            "--airlight",
            "0,0,0",
            "--lambda",
            "0",
            "--refine",
            "unreliable",
            "--out",
            "t.pfm",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let out = load(&dir.path().join("t.pfm"));
    for y in 0..h {
        for x in 0..w {
            if (x, y) == bad {
                continue; // a local outlier: filled, then refined
            }
            let want = (-0.01 * camera.range(*p.get(x, y), x, y)).exp();
            let got = f64::from(out.get(x, y)[1]);
            assert!((got - want).abs() < 2e-6, "({x}, {y}): τ {got} vs {want}");
        }
    }
}

/// `photo::fog_each` gives, for each option, what `photo::fog` gives with it alone: the
/// same bytes, haze, range and divisor, whether the options share one upload (β and
/// visibilities, one blur) or not (normalised κ beside β, another blur). An option that
/// cannot take effect is refused before any render.
#[test]
fn fog_each_gives_what_fog_gives_with_each_option() {
    use brume::photo::{self, Extinction, FogOptions, Photo, PrepareOptions};
    let (w, h) = (48, 32);
    let range = Grid::from_fn(w, h, |x, y| {
        if y < 8 {
            f32::NAN // sky
        } else {
            10.0 + 4.0 * x as f32 + y as f32
        }
    });
    let photo = Photo::from_range(common::noise_image(w, h, 9), range).unwrap();
    let (_lock, mut gpu) = common::renderer();
    let prepared = photo::prepare(
        &photo,
        &PrepareOptions::for_photo(&photo),
        gpu.renderer().unwrap(),
    )
    .unwrap();
    let mut thin = FogOptions::beta(0.004).unwrap();
    thin.lambda = 3.0;
    let shared = vec![
        FogOptions::beta(0.02).unwrap(),
        FogOptions::visibility(150.0).unwrap(),
        thin,
    ];
    let mut sharper = FogOptions::beta(0.01).unwrap();
    sharper.blur.coarse_from = None;
    let mixed = vec![
        FogOptions::beta(0.01).unwrap(),
        FogOptions {
            extinction: Extinction::Normalised { ka: 0.5, ks: 1.0 },
            ..FogOptions::default()
        },
        sharper,
    ];
    for opts in [&shared, &mixed] {
        let mut each = Vec::new();
        photo::fog_each(gpu.renderer().unwrap(), &photo, &prepared, opts, |k, f| {
            assert_eq!(k, each.len(), "in order");
            each.push(f);
            Ok(())
        })
        .unwrap();
        assert_eq!(each.len(), opts.len());
        for (o, e) in opts.iter().zip(&each) {
            let alone = photo::fog(gpu.renderer().unwrap(), &photo, &prepared, o).unwrap();
            assert!(e.rendered.image.as_slice() == alone.rendered.image.as_slice());
            assert_eq!(e.haze, alone.haze);
            assert!(e.range.as_slice() == alone.range.as_slice());
            assert_eq!(e.range_divisor, alone.range_divisor);
            assert_eq!(e.rendered.schedule.steps, alone.rendered.schedule.steps);
        }
    }
    let none: &[FogOptions] = &[];
    photo::fog_each(gpu.renderer().unwrap(), &photo, &prepared, none, |_, _| {
        panic!("no options, no render")
    })
    .unwrap();

    // A bad option anywhere in the list stops the call before the first render.
    let mut bad = shared.clone();
    bad[2].lambda = -1.0;
    let mut renders = 0;
    let e = photo::fog_each(gpu.renderer().unwrap(), &photo, &prepared, &bad, |_, _| {
        renders += 1;
        Ok(())
    })
    .unwrap_err();
    assert_eq!(renders, 0);
    assert!(e.to_string().contains("lambda"), "{e}");
}

/// A range with no pixel known (NaN, infinite, zero or negative everywhere) is refused
/// when the photo is made, by the argument's name, as the loaders refuse such a file.
#[test]
fn a_range_with_no_known_pixel_is_refused_by_name() {
    for unknown in [f32::NAN, f32::INFINITY, 0.0, -3.0] {
        let e = brume::photo::Photo::from_range(
            common::noise_image(6, 4, 1),
            Grid::filled(6, 4, unknown),
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "range_m: no valid depth value (every pixel unknown: NaN, infinite, zero or negative)"
        );
    }
    let mut one = Grid::filled(6, 4, f32::NAN);
    *one.get_mut(2, 1) = 4.0;
    assert!(brume::photo::Photo::from_range(common::noise_image(6, 4, 1), one).is_ok());
}

/// A phone's street frame through the CLI: ARCore's depth (millimetres of z-depth, 0
/// unknown) 4 times smaller than the image, reaching 20 m, the sky unknown above. Under
/// fog of 150 m visibility the sky is veiled (it is seen 1 km away, not at 1.5 times the
/// depth's reach), and so is the sky from 8 px above the horizon, the horizon margin
/// being 8 of the image's pixels (2 cells of the depth map), not 8 cells
/// (32 px: the whole sky, tapered from the ground's range). Before both, τ was 0.52 to
/// 0.61 over the whole sky. The ground keeps τ = exp(−β·R) of its range.
#[test]
fn a_phone_frame_has_its_sky_veiled_beyond_the_horizon_margin() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h, factor) = (64, 48, 4);
    let horizon = h / 2;
    let image = Grid::from_fn(w, h, |x, y| match y < horizon {
        true => [0.35f32, 0.5, 0.9, 1.0],
        false => [0.1 + 0.02 * ((x / 3 + y / 3) % 2) as f32, 0.3, 0.1, 1.0],
    });
    write_rgba(&dir.path().join("frame.png"), &image).unwrap();
    // z from 20 m on the first ground cell row down to 3 m on the last.
    let (dw, dh) = (w / factor, h / factor);
    let z_mm = |cy: usize| 20_000 - (17_000 * (cy - dh / 2) / (dh / 2 - 1)) as u16;
    let depth: Vec<u16> = (0..dw * dh)
        .map(|i| if i / dw < dh / 2 { 0 } else { z_mm(i / dw) })
        .collect();
    image::ImageBuffer::<image::Luma<u16>, _>::from_raw(dw as u32, dh as u32, depth)
        .unwrap()
        .save(dir.path().join("arcore.png"))
        .unwrap();
    let tau = |refine: &str| {
        let out: Vec<RgbImage> = ["0,0,0", "1,1,1"]
            .iter()
            .map(|a| {
                let name = format!("a{}.pfm", &a[..1]);
                let o = brume(
                    dir.path(),
                    &[
                        "render",
                        "--image",
                        "frame.png",
                        "--depth",
                        "arcore.png",
                        "--depth-format",
                        "arcore",
                        "--fov",
                        "45",
                        "--visibility",
                        "150",
                        "--lambda",
                        "0",
                        "--airlight",
                        a,
                        "--refine",
                        refine,
                        "--out",
                        &name,
                        "--json",
                    ],
                );
                let report = json(&o);
                assert_eq!(report["sky_range_m"], 1000.0, "{report}");
                assert!(number(&report["prep"], "s_max") < 40.0, "{report}");
                load(&dir.path().join(name))
            })
            .collect();
        Grid::from_fn(w, h, |x, y| {
            1.0 - (out[1].get(x, y)[1] - out[0].get(x, y)[1])
        })
    };
    for refine in ["none", "guided"] {
        let t = tau(refine);
        for x in 0..w {
            for y in 0..horizon - 8 {
                let v = *t.get(x, y);
                assert!(v < 1e-4, "--refine {refine}: sky ({x}, {y}): τ = {v}");
            }
        }
        // The ground 12 px below the horizon: cell row 9 of z = 9.8 m, between its
        // neighbours' 13.2 and 6.4 m (the ray is 1.01 times as long there).
        let beta = LN_20 / 150.0;
        let (x, y) = (w / 2, horizon + 12);
        let v = f64::from(*t.get(x, y));
        let (lo, hi) = ((-beta * 13.2 * 1.01).exp(), (-beta * 6.4).exp());
        assert!(
            v > lo && v < hi,
            "--refine {refine}: ground τ = {v}, not in {lo}..{hi}"
        );
    }
}
