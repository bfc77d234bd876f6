//! Capture after the fog (`photo::capture`) and β per frame (`BetaDistribution`), against
//! the models' moments computed here: Poisson-Gaussian means and variances, exposure as a
//! factor of 2^stops, JPEG as a codec round trip, and the distributions' mean, variance
//! and quantiles from their closed forms (normal quantiles from published tables).

use crate::common;

use brume::photo::capture::encode_jpeg;
use brume::photo::{capture, BetaDistribution, CaptureOptions, SensorNoise};
use brume::raster::{Grid, RgbaImage};
use common::{brume, exr_bytes, f32s, stderr};
use std::path::Path;

/// A `w`x`h` image of one grey `value`, alpha 1.
fn flat(w: usize, h: usize, value: f32) -> RgbaImage {
    Grid::filled(w, h, [value, value, value, 1.0])
}

/// Mean and unbiased variance of `samples`.
fn moments(samples: impl Iterator<Item = f64>) -> (f64, f64, usize) {
    let v: Vec<f64> = samples.collect();
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, var, v.len())
}

fn colour_samples(img: &RgbaImage) -> impl Iterator<Item = f64> + '_ {
    img.as_slice()
        .iter()
        .flat_map(|p| [p[0], p[1], p[2]].map(f64::from))
}

/// Checks a sample mean and variance against the model's, within `z` standard errors: of
/// the mean sqrt(σ²/n), of the variance sqrt((μ4 − σ⁴)/n) with the model's fourth central
/// moment μ4.
fn assert_moments(samples: (f64, f64, usize), mean: f64, var: f64, mu4: f64, what: &str) {
    let (m, v, n) = samples;
    let n = n as f64;
    let z = 5.0;
    let se_mean = (var / n).sqrt();
    let se_var = ((mu4 - var * var) / n).sqrt();
    assert!(
        (m - mean).abs() < z * se_mean,
        "{what}: mean {m} vs model {mean} (standard error {se_mean})"
    );
    assert!(
        (v - var).abs() < z * se_var,
        "{what}: variance {v} vs model {var} (standard error {se_var})"
    );
}

fn noise(gain: f64, read_noise: f64, seed: u64) -> CaptureOptions {
    CaptureOptions {
        noise: Some(SensorNoise { gain, read_noise }),
        seed,
        ..CaptureOptions::default()
    }
}

#[test]
fn shot_noise_alone_is_poisson_in_electrons() {
    // K = 0.001, v = 0.005: λ = 5 electrons (the small-λ sampler). v' = K·N, N ~ Poisson(5):
    // mean K·λ, variance K²·λ, fourth central moment K⁴·λ(1 + 3λ).
    let (k, lambda) = (0.001, 5.0);
    let mut img = flat(600, 500, (k * lambda) as f32);
    capture(&mut img, &noise(k, 0.0, 7)).unwrap();
    let s = moments(colour_samples(&img));
    assert_moments(
        s,
        k * lambda,
        k * k * lambda,
        k.powi(4) * lambda * (1.0 + 3.0 * lambda),
        "Poisson λ 5",
    );
    // P(N = 0) = e^−5 = 0.006738: the share of zeros, within 5 binomial standard errors.
    let n = s.2 as f64;
    let zeros = colour_samples(&img).filter(|&x| x == 0.0).count() as f64 / n;
    let p0 = (-lambda).exp();
    assert!(
        (zeros - p0).abs() < 5.0 * (p0 * (1.0 - p0) / n).sqrt(),
        "P(0) {zeros} vs {p0}"
    );
}

#[test]
fn shot_and_read_noise_add_their_variances() {
    // K = 0.0005, v = 0.3 (λ = 600, the large-λ sampler), σ = 0.01: variance K·v + σ².
    // Fourth central moment of the sum of independent Poisson (scaled) and Gaussian:
    // μ4 = K⁴λ(1+3λ) + 3σ⁴ + 6·K²λ·σ².
    let (k, v, sigma) = (0.0005, 0.3, 0.01);
    let lambda = v / k;
    let mut img = flat(600, 500, v as f32);
    capture(&mut img, &noise(k, sigma, 11)).unwrap();
    let shot = k * k * lambda;
    let read = sigma * sigma;
    let mu4 = k.powi(4) * lambda * (1.0 + 3.0 * lambda) + 3.0 * read * read + 6.0 * shot * read;
    assert_moments(
        moments(colour_samples(&img)),
        v,
        shot + read,
        mu4,
        "K 0.0005, σ 0.01",
    );
}

#[test]
fn read_noise_alone_is_gaussian() {
    // Signal 0.5 with a huge well (K = 1e-9: shot noise variance 5e-10, negligible):
    // v' ≈ 0.5 + N(0, σ²); the share within ±σ is 0.682689 (normal tables).
    let sigma = 0.02;
    let mut img = flat(500, 400, 0.5);
    capture(&mut img, &noise(1e-9, sigma, 3)).unwrap();
    let s = moments(colour_samples(&img));
    let var = sigma * sigma + 1e-9 * 0.5;
    assert_moments(s, 0.5, var, 3.0 * var * var, "Gaussian σ 0.02");
    let n = s.2 as f64;
    let within = colour_samples(&img)
        .filter(|x| (x - 0.5).abs() < sigma)
        .count() as f64
        / n;
    let p = 0.682_689_492;
    assert!(
        (within - p).abs() < 5.0 * (p * (1.0 - p) / n).sqrt(),
        "share {within}"
    );
}

#[test]
fn noise_is_seeded() {
    let run = |seed| {
        let mut img = flat(64, 48, 0.2);
        capture(&mut img, &noise(0.001, 0.005, seed)).unwrap();
        img
    };
    assert_eq!(run(5).as_slice(), run(5).as_slice());
    assert_ne!(run(5).as_slice(), run(6).as_slice());
}

#[test]
fn exposure_multiplies_by_two_to_the_stops_and_clips_at_full_scale() {
    let mut img = Grid::from_fn(4, 1, |x, _| {
        let v = [0.1f32, 0.2, 0.3, 0.6][x];
        [v, v / 2.0, v / 4.0, 0.5]
    });
    let opts = CaptureOptions {
        exposure_stops: 1.5,
        ..CaptureOptions::default()
    };
    let before = img.clone();
    capture(&mut img, &opts).unwrap();
    let gain = 2f32.powf(1.5);
    for (a, b) in before.as_slice().iter().zip(img.as_slice()) {
        for c in 0..3 {
            let expected = (a[c] * gain).min(1.0);
            assert!((b[c] - expected).abs() < 1e-6, "{} vs {expected}", b[c]);
        }
        assert_eq!(b[3], 0.5, "alpha is kept");
    }
}

#[test]
fn default_capture_leaves_the_image_alone() {
    let mut img = Grid::from_fn(3, 2, |x, y| [x as f32 * 0.7, y as f32 * 1.3, -0.5, 1.0]);
    let before = img.clone();
    assert!(CaptureOptions::default().is_off());
    capture(&mut img, &CaptureOptions::default()).unwrap();
    assert_eq!(img.as_slice(), before.as_slice());
}

/// A smooth image with detail: a gradient with a checker, for the codec.
fn textured(w: usize, h: usize) -> RgbaImage {
    Grid::from_fn(w, h, |x, y| {
        let check = if (x / 4 + y / 4) % 2 == 0 { 0.2 } else { 0.0 };
        [
            x as f32 / w as f32 * 0.6 + check,
            y as f32 / h as f32 * 0.6 + check,
            0.3,
            1.0,
        ]
    })
}

#[test]
fn jpeg_quality_changes_the_bytes_and_decodes_at_the_size() {
    let img = textured(80, 56);
    let low = encode_jpeg(&img, 20).unwrap();
    let high = encode_jpeg(&img, 95).unwrap();
    assert_ne!(low, high);
    assert!(
        low.len() < high.len(),
        "{} vs {} bytes",
        low.len(),
        high.len()
    );
    for bytes in [&low, &high] {
        let decoded = image::load_from_memory(bytes).unwrap();
        assert_eq!((decoded.width(), decoded.height()), (80, 56));
        assert_eq!(
            image::guess_format(bytes).unwrap(),
            image::ImageFormat::Jpeg
        );
    }
    assert!(encode_jpeg(&img, 0).is_err());
    assert!(encode_jpeg(&img, 101).is_err());
}

#[test]
fn jpeg_round_trip_is_close_and_worse_at_low_quality() {
    let original = textured(96, 64);
    let error = |q| {
        let mut img = original.clone();
        let opts = CaptureOptions {
            jpeg_quality: Some(q),
            ..CaptureOptions::default()
        };
        capture(&mut img, &opts).unwrap();
        let n = (img.len() * 3) as f64;
        colour_samples(&img)
            .zip(colour_samples(&original))
            .map(|(a, b)| (a - b).abs())
            .sum::<f64>()
            / n
    };
    let (low, high) = (error(10), error(95));
    assert!(high > 0.0 && high < 0.02, "quality 95: mean error {high}");
    assert!(low > 2.0 * high, "quality 10: {low} vs 95: {high}");
}

#[test]
fn bad_capture_options_are_refused_by_name() {
    let mut img = flat(2, 2, 0.5);
    for (opts, name) in [
        (noise(-0.001, 0.01, 0), "shot_noise_gain"),
        (noise(0.001, -1.0, 0), "read_noise"),
        (
            CaptureOptions {
                exposure_stops: f64::NAN,
                ..CaptureOptions::default()
            },
            "exposure_stops",
        ),
        (
            CaptureOptions {
                jpeg_quality: Some(0),
                ..CaptureOptions::default()
            },
            "jpeg_quality",
        ),
    ] {
        let e = capture(&mut img, &opts).unwrap_err().to_string();
        assert!(e.contains(name), "{e}");
    }
}

/// `n` draws of frames 0..n under one seed.
fn draws(d: &BetaDistribution, n: u64) -> Vec<f64> {
    (0..n).map(|i| d.sample(42, i)).collect()
}

/// The sample quantile at `p` of sorted `v`.
fn sample_quantile(sorted: &[f64], p: f64) -> f64 {
    sorted[((sorted.len() as f64 - 1.0) * p).round() as usize]
}

/// Checks the sample quantile at `p` against `expected`, within 5 standard errors of a
/// quantile, sqrt(p(1−p)/n)/f(q) with the density f at the quantile.
fn assert_quantile(sorted: &[f64], p: f64, expected: f64, density: f64) {
    let n = sorted.len() as f64;
    let se = (p * (1.0 - p) / n).sqrt() / density;
    let got = sample_quantile(sorted, p);
    assert!(
        (got - expected).abs() < 5.0 * se,
        "quantile {p}: {got} vs {expected} (se {se})"
    );
}

#[test]
fn uniform_beta_has_the_uniform_moments_and_quantiles() {
    let d: BetaDistribution = "uniform:0.005,0.03".parse().unwrap();
    let (lo, hi) = (0.005, 0.03);
    let mut v = draws(&d, 200_000);
    assert!(v.iter().all(|&b| (lo..hi).contains(&b)));
    let var = (hi - lo) * (hi - lo) / 12.0;
    // Uniform: fourth central moment (b − a)⁴/80.
    let s = moments(v.iter().copied());
    assert_moments(s, (lo + hi) / 2.0, var, (hi - lo).powi(4) / 80.0, "uniform");
    v.sort_by(f64::total_cmp);
    for p in [0.1, 0.5, 0.9] {
        assert_quantile(&v, p, lo + p * (hi - lo), 1.0 / (hi - lo));
    }
}

#[test]
fn lognormal_beta_has_the_lognormal_moments_and_quantiles() {
    let (mu, sigma) = (-4.6f64, 0.5f64);
    let d: BetaDistribution = format!("lognormal:{mu},{sigma}").parse().unwrap();
    let mut v = draws(&d, 200_000);
    // ln β ~ N(mu, sigma²): check ln β's moments (normal: μ4 = 3σ⁴) ...
    let logs = moments(v.iter().map(|b| b.ln()));
    assert_moments(logs, mu, sigma * sigma, 3.0 * sigma.powi(4), "ln β");
    // ... and β's mean e^(μ+σ²/2), within 5 standard errors from the variance
    // (e^σ² − 1)e^(2μ+σ²).
    let mean = (mu + sigma * sigma / 2.0).exp();
    let var = ((sigma * sigma).exp() - 1.0) * (2.0 * mu + sigma * sigma).exp();
    let (m, _, n) = moments(v.iter().copied());
    assert!(
        (m - mean).abs() < 5.0 * (var / n as f64).sqrt(),
        "mean {m} vs {mean}"
    );
    // Quantiles e^(μ + σ·z_p), z_p from the normal table.
    v.sort_by(f64::total_cmp);
    for (p, z) in [
        (0.1, -1.281_551_565_545),
        (0.5, 0.0),
        (0.9, 1.281_551_565_545),
    ] {
        let q = (mu + sigma * z).exp();
        let density = (-(z * z) / 2.0).exp() / (2.0 * std::f64::consts::PI).sqrt() / (sigma * q);
        assert_quantile(&v, p, q, density);
        assert!(
            (d.quantile(p) - q).abs() < 1e-8 * q,
            "closed-form quantile {p}"
        );
    }
}

#[test]
fn beta_draws_depend_on_seed_and_frame_only() {
    let d: BetaDistribution = "uniform:0.01,0.02".parse().unwrap();
    assert_eq!(d.sample(1, 17), d.sample(1, 17));
    assert_ne!(d.sample(1, 17), d.sample(2, 17));
    assert_ne!(d.sample(1, 17), d.sample(1, 18));
    let fixed: BetaDistribution = "0.02".parse().unwrap();
    assert_eq!(fixed.sample(9, 3), 0.02);
}

#[test]
fn bad_beta_distributions_say_what_is_expected() {
    for text in [
        "uniform:0.03,0.005",
        "uniform:0,0.01",
        "uniform:0.01",
        "lognormal:-4.6,-1",
        "lognormal:x,1",
        "gamma:1,2",
        "-0.01",
        "",
    ] {
        let e = text.parse::<BetaDistribution>().unwrap_err().to_string();
        assert!(e.contains("beta_dist"), "{text}: {e}");
        assert!(
            e.contains("uniform:") || e.contains("lognormal:") || e.contains("β"),
            "{e}"
        );
    }
    let d: BetaDistribution = " Uniform: 0.005 , 0.03 ".parse().unwrap();
    assert_eq!(
        d,
        BetaDistribution::Uniform {
            low: 0.005,
            high: 0.03
        }
    );
    assert_eq!(d.to_string().parse::<BetaDistribution>().unwrap(), d);
}

/// A 40x30 photo (linear EXR: a ramp) and its range in metres (EXR, 10-40 m) in `dir`.
fn write_photo(dir: &Path) {
    let (w, h) = (40, 30);
    let ramp: Vec<f32> = (0..w * h)
        .map(|i| 0.1 + 0.5 * (i % w) as f32 / w as f32)
        .collect();
    let range: Vec<f32> = (0..w * h).map(|i| 10.0 + (i / w) as f32).collect();
    let photo = exr_bytes(
        w,
        h,
        vec![(
            None,
            vec![("R", f32s(&ramp)), ("G", f32s(&ramp)), ("B", f32s(&ramp))],
        )],
    );
    std::fs::write(dir.join("photo.exr"), photo).unwrap();
    let depth = exr_bytes(w, h, vec![(None, vec![("Z", f32s(&range))])]);
    std::fs::write(dir.join("range.exr"), depth).unwrap();
}

/// `brume render` of the photo with `extra` options into `out`; its JSON report.
fn render(dir: &Path, out: &str, extra: &[&str]) -> serde_json::Value {
    let mut args = vec![
        "render",
        "--image",
        "photo.exr",
        "--depth",
        "range.exr",
        "--depth-kind",
        "range",
        "--depth-scale",
        "1",
        "--beta",
        "0.02",
        "--no-prep",
        "--airlight",
        "0.8,0.8,0.8",
        "--out",
        out,
        "--json",
    ];
    args.extend(extra);
    let o = brume(dir, &args);
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

fn read_exr(path: &Path) -> Vec<[f32; 3]> {
    brume::io::image::load_linear_rgb(path).unwrap().into_vec()
}

#[test]
fn render_applies_exposure_and_seeded_noise_after_the_fog() {
    let dir = tempfile::tempdir().unwrap();
    write_photo(dir.path());
    let plain = render(dir.path(), "plain.exr", &[]);
    assert!(plain["capture"].is_null());
    let brighter = render(dir.path(), "bright.exr", &["--exposure-stops", "1"]);
    assert_eq!(brighter["capture"]["exposure_stops"], 1.0);
    let (a, b) = (
        read_exr(&dir.path().join("plain.exr")),
        read_exr(&dir.path().join("bright.exr")),
    );
    for (p, q) in a.iter().zip(&b) {
        for k in 0..3 {
            assert!(
                (q[k] - (2.0 * p[k]).min(1.0)).abs() < 1e-5,
                "{} vs 2·{}",
                q[k],
                p[k]
            );
        }
    }
    let noisy = [
        "--shot-noise-gain",
        "0.001",
        "--read-noise",
        "0.01",
        "--seed",
        "3",
    ];
    let report = render(dir.path(), "n1.exr", &noisy);
    assert_eq!(report["capture"]["shot_noise_gain"], 0.001);
    assert_eq!(report["capture"]["seed"], 3);
    render(dir.path(), "n2.exr", &noisy);
    let mut other = noisy.to_vec();
    other[5] = "4";
    render(dir.path(), "n3.exr", &other);
    let [n1, n2, n3] = ["n1.exr", "n2.exr", "n3.exr"].map(|f| read_exr(&dir.path().join(f)));
    assert_eq!(n1, n2, "one seed, one image");
    assert_ne!(n1, n3, "another seed, other noise");
    // The noise is about the fogged image: its mean difference is near 0, its variance
    // K·v + σ² (here v ≤ 1: at most 0.0011).
    let d: Vec<f64> = n1
        .iter()
        .zip(&a)
        .flat_map(|(p, q)| (0..3).map(move |k| f64::from(p[k] - q[k])))
        .collect();
    let mean = d.iter().sum::<f64>() / d.len() as f64;
    let var = d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64;
    assert!(mean.abs() < 0.003, "mean {mean}");
    assert!(var > 0.0001 && var < 0.0011 * 1.2, "variance {var}");
}

#[test]
fn render_refuses_bad_capture_options_by_flag() {
    let dir = tempfile::tempdir().unwrap();
    write_photo(dir.path());
    for (flag, value) in [
        ("--jpeg-quality", "0"),
        ("--jpeg-quality", "101"),
        ("--shot-noise-gain", "-0.1"),
        ("--read-noise", "nan"),
        ("--exposure-stops", "40"),
    ] {
        let o = brume(
            dir.path(),
            &[
                "render",
                "--image",
                "photo.exr",
                "--depth",
                "range.exr",
                "--out",
                "o.png",
                flag,
                value,
            ],
        );
        assert!(!o.status.success(), "{flag} {value}");
        let e = stderr(&o);
        assert!(e.contains(flag), "{flag} {value}: {e}");
        assert!(!dir.path().join("o.png").exists());
    }
}

/// The log records of a batch run into `out`.
fn batch_log(out: &Path) -> Vec<serde_json::Value> {
    let text = std::fs::read_to_string(out.join("brume-batch-1-of-1.jsonl")).unwrap();
    text.lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// β of each frame's record, by image.
fn betas_by_image(records: &[serde_json::Value]) -> std::collections::BTreeMap<String, f64> {
    records
        .iter()
        .map(|r| {
            (
                r["image"].as_str().unwrap().to_string(),
                r["beta"].as_f64().unwrap(),
            )
        })
        .collect()
}

#[test]
fn batch_draws_one_beta_per_frame_from_the_distribution_and_logs_it() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("cityscapes");
    for k in 0..3 {
        crate::batch::cityscapes_frame(&root, "aachen", &format!("aachen_{k:06}_000019"));
    }
    let run = |out: &str, extra: &[&str]| {
        let mut args = vec!["batch", "cityscapes", "--out", out, "--lambda", "0"];
        args.extend(extra);
        let o = brume(dir.path(), &args);
        assert!(o.status.success(), "{}", stderr(&o));
        batch_log(&dir.path().join(out))
    };
    let dist = ["--beta-dist", "uniform:0.005,0.03", "--seed", "7"];
    let first = run("a", &dist);
    assert_eq!(first.len(), 3);
    for r in &first {
        let beta = r["beta"].as_f64().unwrap();
        assert!((0.005..0.03).contains(&beta), "{beta}");
        assert_eq!(r["beta_dist"], "uniform:0.005,0.03");
        let output = r["output"].as_str().unwrap();
        assert!(
            output.ends_with(&format!("_foggy_beta_{beta}.png")),
            "{output} for β {beta}"
        );
        assert!(
            Path::new(output).is_file() || dir.path().join(output).is_file(),
            "{output}"
        );
    }
    let betas = betas_by_image(&first);
    let distinct: std::collections::BTreeSet<u64> = betas.values().map(|b| b.to_bits()).collect();
    assert_eq!(distinct.len(), 3, "one draw per frame: {betas:?}");
    // The same seed draws the same β for each frame, another seed others.
    assert_eq!(betas_by_image(&run("b", &dist)), betas);
    let other = betas_by_image(&run(
        "c",
        &["--beta-dist", "uniform:0.005,0.03", "--seed", "8"],
    ));
    assert_ne!(other, betas);
    // Capture: the log says so, and the image is the plain one with noise and JPEG.
    let fixed = ["--beta-dist", "0.01"];
    let plain = run("p", &fixed);
    let mut captured = fixed.to_vec();
    captured.extend([
        "--read-noise",
        "0.02",
        "--jpeg-quality",
        "40",
        "--seed",
        "1",
    ]);
    let noisy = run("q", &captured);
    assert!(plain[0]["capture"].is_null());
    assert_eq!(noisy[0]["capture"]["jpeg_quality"], 40);
    let load = |r: &serde_json::Value| {
        let p = r["output"].as_str().unwrap();
        let p = if Path::new(p).is_absolute() {
            p.into()
        } else {
            dir.path().join(p)
        };
        image::open(p).unwrap().to_rgb8()
    };
    let (a, b) = (load(&plain[0]), load(&noisy[0]));
    assert_eq!(a.dimensions(), b.dimensions());
    let n = a.as_raw().len() as f64;
    let mad = a
        .as_raw()
        .iter()
        .zip(b.as_raw())
        .map(|(x, y)| (f64::from(*x) - f64::from(*y)).abs())
        .sum::<f64>()
        / n;
    assert!(
        mad > 1.0 && mad < 20.0,
        "mean absolute difference {mad} code values"
    );
}

#[test]
fn batch_refuses_a_bad_beta_distribution() {
    let dir = tempfile::tempdir().unwrap();
    for (dist, says) in [
        ("uniform:0.03", "uniform:LOW,HIGH"),
        ("lognormal:5,1", "per metre"),
    ] {
        let o = brume(
            dir.path(),
            &["batch", "in", "--out", "o", "--beta-dist", dist],
        );
        assert!(!o.status.success());
        let e = stderr(&o);
        assert!(e.contains("beta") && e.contains(says), "{dist}: {e}");
    }
    let o = brume(
        dir.path(),
        &[
            "batch",
            "in",
            "--out",
            "o",
            "--beta",
            "0.01",
            "--beta-dist",
            "0.02",
        ],
    );
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--beta"), "{}", stderr(&o));
}
