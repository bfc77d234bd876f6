//! A photo's ICC colour profile, end to end: decoded by its own curves where they are not
//! sRGB's, carried by the PNG and JPEG outputs of `render` and `batch`, a profile that is
//! unreadable or not RGB ignored with a warning. The fixtures (`tests/data/colour/`,
//! `tools/photo_metadata_fixtures.py`) carry profiles packed from the ICC specification
//! and checked by littleCMS; `iphone-x.jpg` carries a real iPhone's Display P3. Expected
//! values come from the specification's formulas (a pure gamma of 563/256, sRGB's curve of
//! IEC 61966-2-1) and the profiles' tags are read back by this file's own reader.

use std::path::{Path, PathBuf};

use brume::io::image::load_upright_rgb;
use image::ImageDecoder;
use serde_json::Value;

use crate::common::{self, brume, stderr};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/colour")
        .join(name)
}

fn profiles() -> Value {
    serde_json::from_slice(&std::fs::read(fixture("profiles.json")).unwrap()).unwrap()
}

/// sRGB's encoding of linear light, IEC 61966-2-1.
fn srgb_encode(v: f64) -> f64 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

fn srgb_decode(c: f64) -> f64 {
    if c <= 0.040_45 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The ICC profile an image file carries, as its decoder reads it (PNG `iCCP`, JPEG APP2).
fn icc_of(path: &Path) -> Option<Vec<u8>> {
    common::image_decoder(path).icc_profile().unwrap()
}

/// A tag's data in an ICC profile, by the tag table (ICC.1 sec. 7.3).
fn tag<'a>(icc: &'a [u8], signature: &[u8; 4]) -> &'a [u8] {
    let be = |at: usize| u32::from_be_bytes(icc[at..at + 4].try_into().unwrap()) as usize;
    (0..be(128))
        .map(|k| 132 + 12 * k)
        .find(|&at| &icc[at..at + 4] == signature)
        .map(|at| &icc[be(at + 4)..be(at + 4) + be(at + 8)])
        .unwrap_or_else(|| panic!("no {:?} tag", String::from_utf8_lossy(signature)))
}

fn s15f16(b: &[u8]) -> f64 {
    f64::from(i32::from_be_bytes(b.try_into().unwrap())) / 65536.0
}

/// A colorant tag (`XYZ ` type): X, Y, Z.
fn colorant(icc: &[u8], signature: &[u8; 4]) -> [f64; 3] {
    let t = tag(icc, signature);
    assert_eq!(&t[..4], b"XYZ ");
    std::array::from_fn(|i| s15f16(&t[8 + 4 * i..12 + 4 * i]))
}

/// A curve tag's linear value at `x` in [0, 1]: a `para` (ICC.1 10.16, functions 0-4)
/// or a `curv` (a gamma, or a table read by linear interpolation).
fn curve_at(icc: &[u8], signature: &[u8; 4], x: f64) -> f64 {
    let t = tag(icc, signature);
    match &t[..4] {
        b"para" => {
            let kind = u16::from_be_bytes([t[8], t[9]]);
            let p: Vec<f64> = (0..[1, 3, 4, 5, 7][usize::from(kind)])
                .map(|i| s15f16(&t[12 + 4 * i..16 + 4 * i]))
                .collect();
            let (g, a, b, c, d) = (p[0], p[1], p[2], p[3], p[4]);
            assert_eq!(kind, 3, "sRGB's curve is function 3");
            if x >= d {
                (a * x + b).powf(g)
            } else {
                c * x
            }
        }
        b"curv" => {
            let n = u32::from_be_bytes(t[8..12].try_into().unwrap()) as usize;
            let entry = |i: usize| f64::from(u16::from_be_bytes([t[12 + 2 * i], t[13 + 2 * i]]));
            match n {
                1 => x.powf(entry(0) / 256.0),
                _ => {
                    let at = x * (n - 1) as f64;
                    let i = (at.floor() as usize).min(n - 2);
                    let f = at - i as f64;
                    (entry(i) * (1.0 - f) + entry(i + 1) * f) / 65535.0
                }
            }
        }
        other => panic!("curve type {other:?}"),
    }
}

/// Asserts that `icc` has the colorants `want` (profiles.json) and sRGB's curve on each
/// channel, within a tenth of an 8-bit code.
fn assert_primaries_with_srgb_curve(icc: &[u8], want: &Value) {
    for (k, signature) in [b"rXYZ", b"gXYZ", b"bXYZ"].into_iter().enumerate() {
        let got = colorant(icc, signature);
        for (i, g) in got.into_iter().enumerate() {
            let w = want[k][i].as_f64().unwrap();
            assert!(
                (g - w).abs() <= 2.0 / 65536.0,
                "{signature:?}[{i}]: {g} for {w}"
            );
        }
    }
    for signature in [b"rTRC", b"gTRC", b"bTRC"] {
        for code in 0..=255 {
            let x = f64::from(code) / 255.0;
            let encoded = srgb_encode(curve_at(icc, signature, x)) * 255.0;
            assert!(
                (encoded - f64::from(code)).abs() < 0.1,
                "{signature:?} at code {code}: {encoded}"
            );
        }
    }
}

/// Each code of the gamma-2.2 ramp decodes to (code/255)^(563/256), the profile's own
/// curve, not sRGB's.
#[test]
fn a_gamma_profile_decodes_each_code_by_its_own_curve() {
    let gamma = profiles()["gamma22"]["gamma"].as_f64().unwrap();
    let photo = load_upright_rgb(&fixture("gamma22-ramp.png")).unwrap();
    let profile = photo.metadata.profile().expect("the ramp's profile");
    assert!(profile.has_own_curves() && !profile.primaries_are_srgb());
    // Own curves, but gamma 2.2, not linear light.
    assert!(!profile.has_linear_curves() && !photo.linear_light);
    assert_eq!(profile.description(), "Adobe RGB (1998) test");
    for (i, px) in photo.image.as_slice().iter().enumerate() {
        let codes = [i, 255 - i, (7 * i) % 256];
        for (c, &v) in codes.into_iter().zip(px) {
            let want = (c as f64 / 255.0).powf(gamma);
            assert!(
                (f64::from(v) - want).abs() < 2e-5,
                "pixel {i}: {v} for {want}"
            );
        }
    }
    // Without a profile, the same code is sRGB's.
    let srgb = load_upright_rgb(&fixture("garbage-icc.png")).unwrap();
    assert!(srgb.metadata.profile().is_none());
    let v = f64::from(srgb.image.as_slice()[0][0]);
    assert!((v - srgb_decode(200.0 / 255.0)).abs() < 1e-6);
}

/// A 32 x 8 range file of 10 m everywhere, for the flat fixtures.
fn flat_range(dir: &Path) {
    common::write_flat_range(dir, 32, 8);
}

/// Renders `image` over 10 m at β = 0.1 with airlight 0.5 into `out`; returns stderr.
fn render_flat(dir: &Path, image: &Path, out: &str) -> String {
    let fog = ["--beta", "0.1", "--airlight", "0.5,0.5,0.5"];
    common::render_over_range(dir, image, out, &fog)
}

/// The output's code of a flat photo whose channels decode to `linear`: τ = exp(−1) of
/// it and 1 − τ of airlight 0.5, encoded by sRGB's curve (a flat image's blur changes
/// nothing).
fn fogged_codes(linear: [f64; 3]) -> [f64; 3] {
    let t = (-1.0f64).exp();
    linear.map(|j| (srgb_encode(t * j + (1.0 - t) * 0.5) * 255.0).round())
}

fn pixel(path: &Path, x: u32, y: u32) -> [f64; 3] {
    let img = image::open(path).unwrap().to_rgb8();
    img.get_pixel(x, y).0.map(f64::from)
}

fn assert_codes(got: [f64; 3], want: [f64; 3], within: f64, what: &str) {
    for (g, w) in got.into_iter().zip(want) {
        assert!((g - w).abs() <= within, "{what}: {got:?} for {want:?}");
    }
}

/// A gamma-2.2 photo fogged: the PNG and the JPEG carry its primaries with sRGB's curve,
/// and their codes are the fog of its own decoding, encoded by sRGB's.
#[test]
fn outputs_of_a_gamma_profile_carry_its_primaries_with_srgb_curves() {
    let dir = tempfile::tempdir().unwrap();
    flat_range(dir.path());
    let p = profiles();
    let gamma = p["gamma22"]["gamma"].as_f64().unwrap();
    let want = fogged_codes([200.0, 120.0, 40.0].map(|c: f64| (c / 255.0).powf(gamma)));
    for (out, within) in [("out.png", 0.0), ("out.jpg", 2.0)] {
        let log = render_flat(dir.path(), &fixture("gamma22-flat.png"), out);
        assert!(log.is_empty(), "no warning: {log}");
        let out = dir.path().join(out);
        assert_codes(pixel(&out, 16, 4), want, within, &out.display().to_string());
        let icc = icc_of(&out).expect("the output carries a profile");
        assert_primaries_with_srgb_curve(&icc, &p["gamma22"]["colorants"]);
        // The photo's profile's creation date, not the moment of writing: one photo gives
        // the same bytes every run.
        let photo_icc = icc_of(&fixture("gamma22-flat.png")).unwrap();
        assert_eq!(icc[24..36], photo_icc[24..36]);
    }
}

/// Display P3 with sRGB's curve (a 1024-entry table): decoded as sRGB, the profile
/// carried byte for byte.
#[test]
fn a_p3_profile_is_carried_as_it_was() {
    let dir = tempfile::tempdir().unwrap();
    flat_range(dir.path());
    render_flat(dir.path(), &fixture("p3-flat.png"), "out.png");
    let out = dir.path().join("out.png");
    let want = fogged_codes([200.0, 120.0, 40.0].map(|c: f64| srgb_decode(c / 255.0)));
    assert_codes(pixel(&out, 16, 4), want, 0.0, "p3");
    assert_eq!(icc_of(&out), icc_of(&fixture("p3-flat.png")));
}

/// A profile that is not one, or not RGB: a warning naming the file, the photo read as
/// sRGB, no profile written.
#[test]
fn an_unusable_profile_is_ignored_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    flat_range(dir.path());
    let want = fogged_codes([200.0, 120.0, 40.0].map(|c: f64| srgb_decode(c / 255.0)));
    for (name, why) in [
        ("garbage-icc.png", "cannot be read"),
        ("grey-icc.png", "not RGB"),
    ] {
        let log = render_flat(dir.path(), &fixture(name), "out.png");
        assert!(log.contains(name) && log.contains(why), "{log}");
        assert!(log.contains("taken as sRGB"), "{log}");
        let out = dir.path().join("out.png");
        assert_codes(pixel(&out, 16, 4), want, 0.0, name);
        assert_eq!(icc_of(&out), None, "{name}");
    }
}

/// An EXR's `chromaticities` attribute (CIE xy of red, green, blue, white).
fn exr_chromaticities(path: &Path) -> [[f64; 2]; 4] {
    let meta = exr::meta::MetaData::read_from_file(path, false).unwrap();
    let c = meta.headers[0]
        .shared_attributes
        .chromaticities
        .expect("a chromaticities attribute");
    [c.red, c.green, c.blue, c.white].map(|v| [f64::from(v.0), f64::from(v.1)])
}

/// Asserts chromaticities within 0.001 of `want` (the standards' figures).
fn assert_chromaticities(got: [[f64; 2]; 4], want: [[f64; 2]; 4], what: &str) {
    for (g, w) in got.iter().flatten().zip(want.iter().flatten()) {
        assert!((g - w).abs() < 1e-3, "{what}: {got:?} for {want:?}");
    }
}

const D65: [f64; 2] = [0.3127, 0.3290];

/// An EXR of a gamma-2.2 photo says Adobe RGB's primaries (Adobe RGB (1998) sec. 4.3)
/// and D65; a PFM, which cannot, is written with a warning naming them.
#[test]
fn float_outputs_say_the_photos_primaries() {
    let dir = tempfile::tempdir().unwrap();
    flat_range(dir.path());
    render_flat(dir.path(), &fixture("gamma22-flat.png"), "out.exr");
    let adobe = [[0.64, 0.33], [0.21, 0.71], [0.15, 0.06], D65];
    assert_chromaticities(
        exr_chromaticities(&dir.path().join("out.exr")),
        adobe,
        "EXR",
    );
    let log = render_flat(dir.path(), &fixture("gamma22-flat.png"), "out.pfm");
    assert!(
        log.contains("out.pfm") && log.contains("(Adobe RGB (1998) test)"),
        "{log}"
    );
}

/// The real iPhone portrait's Display P3 profile goes into `render`'s PNG and `batch`'s
/// output, and its primaries (SMPTE EG 432-1) into an EXR.
#[test]
fn a_real_iphone_photos_display_p3_reaches_render_and_batch() {
    let dir = tempfile::tempdir().unwrap();
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/apple/iphone-x.jpg");
    std::fs::copy(&src, dir.path().join("p.jpg")).unwrap();
    let icc = icc_of(&src).expect("the iPhone's profile");
    let run = |args: &[&str]| {
        let run = brume(dir.path(), args);
        assert!(run.status.success(), "{}", stderr(&run));
        stderr(&run)
    };
    let render = ["render", "--image", "p.jpg", "--beta", "0.3", "--out"];
    let json = brume(dir.path(), &[&render[..], &["r.png", "--json"]].concat());
    let report: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    assert_eq!(report["colour_profile"], "Display P3");
    assert_eq!(icc_of(&dir.path().join("r.png")).as_ref(), Some(&icc));
    run(&[&render[..], &["r.exr"]].concat());
    let p3 = [[0.680, 0.320], [0.265, 0.690], [0.150, 0.060], D65];
    assert_chromaticities(exr_chromaticities(&dir.path().join("r.exr")), p3, "iPhone");
    std::fs::write(dir.path().join("phone.csv"), "image\np.jpg\n").unwrap();
    run(&[
        "batch",
        "--manifest",
        "phone.csv",
        "--out",
        "o",
        "--beta",
        "0.3",
    ]);
    let log = std::fs::read_to_string(dir.path().join("o/brume-batch-1-of-1.jsonl")).unwrap();
    assert!(log.contains(r#""colour_profile":"Display P3""#), "{log}");
    let batch = dir.path().join("o/p_foggy_beta_0.3.png");
    assert_eq!(icc_of(&batch).as_ref(), Some(&icc));
    assert!(std::fs::read(batch).unwrap() == std::fs::read(dir.path().join("r.png")).unwrap());
}

/// The codes of the 16 x 16 ramp fixtures, pixel by pixel (row-major), over 255.
fn ramp_values() -> impl Iterator<Item = [f64; 3]> {
    (0..256).map(|i| [i, 255 - i, (7 * i) % 256].map(|c| f64::from(c) / 255.0))
}

/// A PNG that states its colour space by chunks instead of an ICC profile: `gAMA` 1 and
/// `cICP` 1/8 (BT.709's primaries, linear) decode each code c to c/255, `cICP` ahead of
/// the `gAMA` 1/2.2 and the gamma-2.2 ICC profile the second file also holds; `gAMA`
/// 1/2.2 with sRGB's `cHRM` is sRGB (no profile, as libpng reads it); Display P3 by `cHRM`
/// or `cICP` 12/13 is sRGB's curve with P3's primaries (SMPTE EG 432-1).
#[test]
fn png_colour_chunks_decode_by_the_specifications_precedence() {
    for name in ["gama-linear-ramp.png", "cicp-linear-ramp.png"] {
        let photo = load_upright_rgb(&fixture(name)).unwrap();
        let profile = photo.metadata.profile().expect(name);
        assert!(
            profile.has_own_curves() && profile.primaries_are_srgb(),
            "{name}"
        );
        assert!(photo.linear_light && profile.has_linear_curves(), "{name}");
        for (i, (px, want)) in photo.image.as_slice().iter().zip(ramp_values()).enumerate() {
            for (&v, w) in px.iter().zip(want) {
                assert!((f64::from(v) - w).abs() < 2e-5, "{name} {i}: {v} for {w}");
            }
        }
    }
    let srgb = load_upright_rgb(&fixture("gama-srgb-flat.png")).unwrap();
    assert!(srgb.metadata.profile().is_none() && !srgb.linear_light);
    let v = f64::from(srgb.image.as_slice()[0][0]);
    assert!((v - srgb_decode(200.0 / 255.0)).abs() < 1e-6);
    let p3 = [[0.68, 0.32], [0.265, 0.69], [0.15, 0.06], D65];
    for name in ["chrm-p3-flat.png", "cicp-p3-flat.png"] {
        let photo = load_upright_rgb(&fixture(name)).unwrap();
        let profile = photo.metadata.profile().expect(name);
        assert!(!profile.has_own_curves() && !profile.primaries_are_srgb());
        assert!(
            !photo.linear_light && !profile.has_linear_curves(),
            "{name}"
        );
        assert_chromaticities(profile.chromaticities(), p3, name);
        let v = f64::from(photo.image.as_slice()[0][0]);
        assert!((v - srgb_decode(200.0 / 255.0)).abs() < 1e-6, "{name}");
    }
}

/// A 16-bit linear PNG (`gAMA` 1, packed by the fixture script and read back by OpenCV):
/// each code c, most of which no 8-bit value gives, decodes to c/65535 through the
/// profile's table of every 16-bit code.
#[test]
fn a_16_bit_linear_png_decodes_each_code() {
    let photo = load_upright_rgb(&fixture("gama-linear-ramp16.png")).unwrap();
    assert!(photo.metadata.profile().expect("gAMA 1").has_own_curves());
    for (i, px) in photo.image.as_slice().iter().enumerate() {
        let codes = [257 * i - i % 7, 65535 - 257 * i, (4099 * i) % 65536];
        for (c, &v) in codes.into_iter().zip(px) {
            let want = c as f64 / 65535.0;
            assert!((f64::from(v) - want).abs() < 1e-6, "{i}: {v} for {want}");
        }
    }
}

/// A linear PNG (`gAMA` 1) fogged by next to nothing comes out as its codes encoded by
/// sRGB's curve, exactly, with a profile of its primaries; Display P3 by `cICP` reaches
/// the output as a profile with P3's colorants; an HDR PNG (`cICP` PQ) is refused, naming
/// the file and what to do.
#[test]
fn png_colour_chunks_reach_the_outputs() {
    let dir = tempfile::tempdir().unwrap();
    common::write_flat_range(dir.path(), 16, 16);
    let fog = ["--beta", "1e-6"];
    common::render_over_range(
        dir.path(),
        &fixture("gama-linear-ramp.png"),
        "lin.png",
        &fog,
    );
    let out = image::open(dir.path().join("lin.png")).unwrap().to_rgb8();
    for (px, want) in out.pixels().zip(ramp_values()) {
        let want = want.map(|v| (srgb_encode(v) * 255.0).round());
        assert_eq!(px.0.map(f64::from), want);
    }
    let icc = icc_of(&dir.path().join("lin.png")).expect("a profile");
    assert_primaries_with_srgb_curve(&icc, &profiles()["srgb"]["colorants"]);
    // A fixed creation date (2025-06-24 00:00:00), so that runs give the same bytes.
    let date: Vec<u16> = (icc[24..36].chunks(2))
        .map(|b| u16::from_be_bytes([b[0], b[1]]))
        .collect();
    assert_eq!(date, [2025, 6, 24, 0, 0, 0]);
    flat_range(dir.path());
    render_flat(dir.path(), &fixture("cicp-p3-flat.png"), "p3.png");
    let icc = icc_of(&dir.path().join("p3.png")).expect("a profile");
    assert_primaries_with_srgb_curve(&icc, &profiles()["p3"]["colorants"]);
    let pq = fixture("cicp-pq-flat.png");
    let args = [
        "render",
        "--image",
        pq.to_str().unwrap(),
        "--depth",
        "r.pfm",
    ];
    let needles = ["cicp-pq-flat.png", "HDR", "PQ", "SDR"];
    common::assert_render_refused(dir.path(), &args, &needles);
}

/// A 32 x 8 EXR of linear (0.5, 0.3, 0.1) whose `chromaticities` are `c` (red, green,
/// blue, white), written by the exr crate.
fn exr_with_chromaticities(path: &Path, c: [[f32; 2]; 4]) {
    use exr::prelude::*;
    let (w, h) = (32, 8);
    let channels = |v: f32| FlatSamples::F32(vec![v; w * h]);
    let list = [("R", 0.5), ("G", 0.3), ("B", 0.1)]
        .map(|(name, v)| AnyChannel::new(name, channels(v)))
        .to_vec();
    let layer = Layer::new(
        (w, h),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list.into()),
    );
    let mut image = Image::from_layer(layer);
    let v = |[x, y]: [f32; 2]| Vec2(x, y);
    image.attributes.chromaticities = Some(attribute::Chromaticities {
        red: v(c[0]),
        green: v(c[1]),
        blue: v(c[2]),
        white: v(c[3]),
    });
    image.write().to_file(path).unwrap();
}

/// An EXR in ACEScg (AP1 primaries, ACES's white near D60, as VFX tools write it): its
/// values are in those primaries, which its EXR output says again and its PNG output's
/// profile holds (colorants by the fixture script's Bradford arithmetic), the codes the
/// fog of its values encoded by sRGB's curve; an EXR saying sRGB's gets no profile.
#[test]
fn an_exrs_chromaticities_reach_its_outputs() {
    let dir = tempfile::tempdir().unwrap();
    flat_range(dir.path());
    let ap1 = [
        [0.713, 0.293],
        [0.165, 0.83],
        [0.128, 0.044],
        [0.32168, 0.33767],
    ];
    let input = dir.path().join("acescg.exr");
    exr_with_chromaticities(&input, ap1);
    render_flat(dir.path(), &input, "out.exr");
    let want = ap1.map(|c| c.map(f64::from));
    assert_chromaticities(exr_chromaticities(&dir.path().join("out.exr")), want, "EXR");
    render_flat(dir.path(), &input, "out.png");
    let out = dir.path().join("out.png");
    assert_codes(
        pixel(&out, 16, 4),
        fogged_codes([0.5, 0.3, 0.1]),
        0.0,
        "ACEScg",
    );
    let icc = icc_of(&out).expect("a profile of AP1's primaries");
    assert_primaries_with_srgb_curve(&icc, &profiles()["acescg"]["colorants"]);
    let srgb = [[0.64, 0.33], [0.3, 0.6], [0.15, 0.06], [0.3127, 0.329]];
    exr_with_chromaticities(&input, srgb);
    render_flat(dir.path(), &input, "srgb.png");
    assert_eq!(icc_of(&dir.path().join("srgb.png")), None);
}

/// XYZ to linear RGB of primaries `rgb` and white `w` (CIE xy), by this test's own
/// arithmetic: the RGB-to-XYZ matrix whose columns, scaled, sum to the white, inverted.
fn xyz_to_rgb(rgb: [[f64; 2]; 3], w: [f64; 2]) -> [[f64; 3]; 3] {
    let xyz = |[x, y]: [f64; 2]| [x / y, 1.0, (1.0 - x - y) / y];
    let m = columns_matrix(rgb.map(xyz));
    let s = solve(m, xyz(w));
    let scaled: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|k| m[i][k] * s[k]));
    invert(scaled)
}

/// The matrix whose columns are `columns`.
fn columns_matrix(columns: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    std::array::from_fn(|i| std::array::from_fn(|k| columns[k][i]))
}

fn invert(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    let c = |r: usize, k: usize| {
        let (r1, r2, k1, k2) = ((r + 1) % 3, (r + 2) % 3, (k + 1) % 3, (k + 2) % 3);
        m[r1][k1] * m[r2][k2] - m[r1][k2] * m[r2][k1]
    };
    std::array::from_fn(|i| std::array::from_fn(|k| c(k, i) / det))
}

fn solve(m: [[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    let inv = invert(m);
    std::array::from_fn(|i| (0..3).map(|k| inv[i][k] * v[k]).sum())
}

/// Aerial perspective on a Display P3 photo integrates each channel's attenuation for the
/// CIE observer in P3's primaries (SMPTE EG 432-1, D65; the matrix by this test's own
/// arithmetic), so that it is the attenuation of the photo's own red, green and blue; an
/// sRGB photo keeps the CIE observer in sRGB's, and a camera's own curves are kept.
#[test]
fn aerial_perspective_is_integrated_in_the_photos_primaries() {
    use brume::atmosphere::{Channel, Sensitivity};
    let dir = tempfile::tempdir().unwrap();
    flat_range(dir.path());
    let mut gpu = brume::Headless::new(None).unwrap();
    let mut sensitivity_of = |image: &str, given: Sensitivity| {
        let photo = brume::photo::Photo::load(
            &fixture(image),
            &dir.path().join("r.pfm"),
            &brume::io::depth::DepthOptions::default(),
        )
        .unwrap();
        let opts = brume::photo::PrepareOptions::for_photo(&photo);
        let prepared = brume::photo::prepare(&photo, &opts, gpu.renderer().unwrap()).unwrap();
        let camera = brume::camera::Camera::default();
        let aerial = brume::photo::AerialOptions {
            metres_per_unit: Some(500.0),
            sensitivity: given,
            ..brume::photo::AerialOptions::new(2.0, camera)
        };
        brume::photo::aerial(&photo, &prepared, &aerial)
            .unwrap()
            .sensitivity
    };
    let p3 = xyz_to_rgb([[0.68, 0.32], [0.265, 0.69], [0.15, 0.06]], D65);
    let want = Sensitivity::cie_in(p3);
    let got = sensitivity_of("p3-flat.png", Sensitivity::cie_srgb());
    for c in Channel::ALL {
        let peak = want.curve(c).iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (g, w) in got.curve(c).iter().zip(want.curve(c)) {
            assert!((g - w).abs() < 2e-3 * peak, "{c:?}: {g} for {w}");
        }
    }
    assert!(got != Sensitivity::cie_srgb());
    let srgb = sensitivity_of("garbage-icc.png", Sensitivity::cie_srgb());
    assert!(srgb == Sensitivity::cie_srgb());
    let camera =
        Sensitivity::from_samples(&[(400.0, [0.1, 0.5, 1.0]), (700.0, [1.0, 0.5, 0.0])]).unwrap();
    assert!(sensitivity_of("p3-flat.png", camera.clone()) == camera);
}

/// A lossless WebP (libwebp through Pillow) and an LZW TIFF (Pillow) of the gamma-2.2 ramp
/// with its profile and Orientation 6: turned upright, each code decoded by the profile's
/// own curve as the PNG's is, and the profile carried by the output; as a depth map each
/// is refused (maps are lossless data; a TIFF map is read by the float map reader).
#[test]
fn webp_and_tiff_photos_are_read_with_their_profile_and_orientation() {
    check_turned_ramp_with_profile("gamma22-ramp.webp", "WebP");
    check_turned_ramp_with_profile("gamma22-ramp.tif", "Tiff");
}

fn check_turned_ramp_with_profile(name: &str, kind: &str) {
    let gamma = profiles()["gamma22"]["gamma"].as_f64().unwrap();
    let photo = load_upright_rgb(&fixture(name)).unwrap();
    let profile = photo.metadata.profile().expect("the photo's ICC profile");
    assert_eq!(profile.description(), "Adobe RGB (1998) test");
    assert_eq!(photo.exif.orientation.exif(), 6);
    // Orientation 6 turns the stored image 90° clockwise: the upright pixel (x, y) is
    // the stored pixel (y, 15 − x).
    let (w, h) = (photo.image.width(), photo.image.height());
    assert_eq!((w, h), (16, 16));
    for y in 0..16 {
        for x in 0..16 {
            let i = (15 - x) * 16 + y;
            let codes = [i, 255 - i, (7 * i) % 256];
            let got = photo.image.get(x, y);
            for (c, &v) in codes.into_iter().zip(got) {
                let want = (c as f64 / 255.0).powf(gamma);
                assert!(
                    (f64::from(v) - want).abs() < 2e-5,
                    "({x}, {y}): {v} for {want}"
                );
            }
        }
    }
    let dir = tempfile::tempdir().unwrap();
    common::write_flat_range(dir.path(), 16, 16);
    let fog = ["--beta", "1e-6"];
    common::render_over_range(dir.path(), &fixture(name), "out.png", &fog);
    let icc = icc_of(&dir.path().join("out.png")).expect("the profile carried");
    assert_primaries_with_srgb_curve(&icc, &profiles()["gamma22"]["colorants"]);
    // Named .png, so that the content, not the name, is refused.
    let map = dir.path().join("d.png");
    std::fs::copy(fixture(name), &map).unwrap();
    let e = brume::io::depth::load_range(&map, &brume::io::depth::DepthOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(&format!("d.png: this is a {kind} image, which is not read")),
        "{e}"
    );
}

/// A 16-bit RGB TIFF without a profile (OpenCV) is sRGB, each code decoded by sRGB's curve
/// at 16 bits; a float32 RGB TIFF is linear light, taken as it is (above 1 too).
#[test]
fn a_16_bit_tiff_is_srgb_and_a_float_tiff_linear() {
    let srgb = |c: f64| {
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let codes = |i: usize| [257 * i - i % 7, 65535 - 257 * i, (4099 * i) % 65536];
    let coded = load_upright_rgb(&fixture("ramp16.tif")).unwrap();
    let linear = load_upright_rgb(&fixture("ramp-float.tif")).unwrap();
    assert!(!coded.linear_light && linear.linear_light);
    for i in 0..256 {
        let (x, y) = (i % 16, i / 16);
        for ((c, got), given) in codes(i)
            .into_iter()
            .zip(coded.image.get(x, y))
            .zip(linear.image.get(x, y))
        {
            let want = srgb(c as f64 / 65535.0);
            assert!(
                (f64::from(*got) - want).abs() < 1e-5,
                "({x}, {y}): {got} for {want}"
            );
            assert_eq!(*given, (c as f64 / 65535.0 * 4.0) as f32, "({x}, {y})");
        }
    }
}
