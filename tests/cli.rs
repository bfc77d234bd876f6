//! The `brume` binary end to end: the demo, the JSON schema scripts rely on, `info`, and
//! bad input giving one clear line, a non-zero exit and no output file.

use brume::io::output::{write_rgba, write_scalar};
use brume::raster::Grid;
use serde_json::Value;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::Mutex;

/// The binary opens a GL context per run; llvmpipe uses every core, so run one at a time.
static SERIAL: Mutex<()> = Mutex::new(());

fn brume(dir: &Path, args: &[&str]) -> Output {
    brume_with_env(dir, args, &[], &[])
}

/// Runs brume with extra environment variables set and others removed.
fn brume_with_env(dir: &Path, args: &[&str], set: &[(&str, &str)], remove: &[&str]) -> Output {
    let _lock = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_brume"));
    cmd.args(args).current_dir(dir);
    for (key, value) in set {
        cmd.env(key, value);
    }
    for key in remove {
        cmd.env_remove(key);
    }
    cmd.output().expect("run brume")
}

/// `brume render --image IMAGE --depth DEPTH EXTRA...` in `dir`.
fn render_files(dir: &Path, image: &Path, depth: &Path, extra: &[&str]) -> Output {
    let (image, depth) = (image.to_str().unwrap(), depth.to_str().unwrap());
    let mut args = vec!["render", "--image", image, "--depth", depth];
    args.extend_from_slice(extra);
    brume(dir, &args)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn aloe(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/aloe")
        .join(name)
}

/// A small scene on disk: a 24x16 PNG and a float PFM range map.
fn small_scene(dir: &Path) -> (PathBuf, PathBuf) {
    let image = dir.join("im.png");
    let depth = dir.join("range.pfm");
    write_rgba(
        &image,
        &Grid::from_fn(24, 16, |x, y| [x as f32 / 24.0, y as f32 / 16.0, 0.5, 1.0]),
    )
    .unwrap();
    write_scalar(&depth, &Grid::from_fn(24, 16, |x, _| 1.0 + x as f32)).unwrap();
    (image, depth)
}

/// The `airlight` of a JSON report.
fn airlight(v: &Value) -> Vec<f64> {
    v["airlight"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_f64().unwrap())
        .collect()
}

/// With no sky the JSON report names the `neutral` airlight: three equal values, lit.
fn assert_neutral_airlight(v: &Value) {
    assert_eq!(v["airlight_source"], "neutral", "{v}");
    let b = airlight(v);
    assert_eq!(b.len(), 3, "{b:?}");
    assert!(b[0] == b[1] && b[1] == b[2], "not neutral: {b:?}");
    assert!(
        b[0] > 0.0 && b[0] <= 1.0,
        "an 8-bit image's bright end: {b:?}"
    );
}

fn assert_fails_cleanly(o: &Output, must_mention: &[&str]) {
    assert!(
        !o.status.success(),
        "expected failure, stdout: {}",
        String::from_utf8_lossy(&o.stdout)
    );
    let err = stderr(o);
    assert!(err.starts_with("brume: error: "), "stderr: {err}");
    assert!(!err.contains("panicked"), "panic: {err}");
    for m in must_mention {
        assert!(err.contains(m), "stderr should mention {m:?}: {err}");
    }
}

#[test]
fn render_without_input_writes_the_demo() {
    let dir = tempfile::tempdir().unwrap();
    let o = brume(dir.path(), &["render"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = dir.path().join("brume-demo.png");
    let img = image::open(&out).expect("demo output is a PNG");
    assert!(img.width() > 100 && img.height() > 100);
    assert!(String::from_utf8_lossy(&o.stdout).contains("brume-demo.png"));
}

#[test]
fn json_report_has_the_stable_fields() {
    let dir = tempfile::tempdir().unwrap();
    let (image, depth) = small_scene(dir.path());
    let o = render_files(
        dir.path(),
        &image,
        &depth,
        &[
            "--depth-kind",
            "range",
            "--out",
            "out.exr",
            "--json",
            "--no-prep",
            // The full-resolution pipeline: N + 2 passes (the coarse stage adds two a level).
            "--coarse-from",
            "off",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let v: Value = serde_json::from_slice(&o.stdout).expect("one JSON object on stdout");
    for key in [
        "width",
        "height",
        "scheme",
        "precision",
        "diffusion_passes",
        "renderer",
        "clock",
        "total_ms",
        "pass_ms",
        "out",
    ] {
        assert!(v.get(key).is_some(), "missing {key} in {v}");
    }
    assert_eq!(v["width"], 24);
    assert_eq!(v["height"], 16);
    assert_eq!(v["scheme"], "matched");
    assert_eq!(v["precision"], "f32");
    let n = v["diffusion_passes"].as_u64().unwrap();
    assert_eq!(v["pass_ms"].as_array().unwrap().len() as u64, n + 2);
    assert!(["gpu-timer", "wall"].contains(&v["clock"].as_str().unwrap()));
    assert!(dir.path().join("out.exr").exists());
}

#[test]
fn uniform_sigma_pfm_output_and_timings() {
    let dir = tempfile::tempdir().unwrap();
    let (image, depth) = small_scene(dir.path());
    let o = render_files(
        dir.path(),
        &image,
        &depth,
        &[
            "--depth-kind",
            "range",
            "--uniform-sigma",
            "3",
            "--precision",
            "f16",
            "--scheme",
            "euler",
            "--out",
            "blur.pfm",
            "--timings",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("medium") && text.contains("composite"),
        "{text}"
    );
    let pfm = fs::read(dir.path().join("blur.pfm")).unwrap();
    assert!(pfm.starts_with(b"PF\n"));
}

/// brume's Aloe as a Cityscapes frame under `dir`: its image, disparity and camera file,
/// relative to `dir`.
fn cityscapes_frame_files(dir: &Path) -> [String; 3] {
    crate::batch::cityscapes_frame(dir, "aachen", "aachen_000000_000019");
    let frame =
        |kind: &str, suffix: &str| format!("{kind}/train/aachen/aachen_000000_000019_{suffix}");
    [
        frame("leftImg8bit", "leftImg8bit.png"),
        frame("disparity", "disparity.png"),
        frame("camera", "camera.json"),
    ]
}

/// A uniform blur reads no range, but a Cityscapes disparity (repaired by default, which
/// needs the holes filled) is prepared as for the haze: the render works, the report says
/// the blur has no airlight, and the picture is the one the same blur gives with the
/// depth taken as it is (`--no-prep --refine none`).
#[test]
fn a_uniform_blur_works_on_a_cityscapes_disparity_and_ignores_it() {
    let dir = tempfile::tempdir().unwrap();
    let [image, depth, _] = cityscapes_frame_files(dir.path());
    let render = |out: &str, extra: &[&str]| {
        let mut args = vec!["render", "--image", &image, "--depth", &depth];
        args.extend_from_slice(&["--uniform-sigma", "4", "--out", out, "--json"]);
        args.extend_from_slice(extra);
        let o = brume(dir.path(), &args);
        assert!(
            o.status.success(),
            "{extra:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        serde_json::from_slice::<Value>(&o.stdout).unwrap()
    };
    let prepared = render("prepared.pfm", &[]);
    assert_eq!(prepared["medium"], "uniform_blur", "{prepared}");
    assert_eq!(prepared["sources"], brume::SOURCES, "{prepared}");
    assert_eq!(prepared["airlight_source"], "none", "{prepared}");
    assert_eq!(prepared["airlight"], serde_json::json!([0.0, 0.0, 0.0]));
    assert!(prepared["transmittance_min"].is_null() && prepared["prep"].is_object());
    render("as_read.pfm", &["--no-prep", "--refine", "none"]);
    let read = |name: &str| fs::read(dir.path().join(name)).unwrap();
    assert!(
        read("prepared.pfm") == read("as_read.pfm"),
        "the depth changed a uniform blur"
    );
}

/// `--no-prep` where the refinement needs a range known everywhere is refused, and the
/// error says which refinement needs it (the format's default, or the upsampling of a
/// smaller depth map) and what would do.
#[test]
fn no_prep_where_the_refinement_needs_it_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let [image, depth, camera] = cityscapes_frame_files(dir.path());
    let full = image::open(dir.path().join(&depth)).unwrap().to_luma16();
    let (w, h) = (full.width() / 2, full.height() / 2);
    image::imageops::resize(&full, w, h, image::imageops::FilterType::Nearest)
        .save(dir.path().join("half_disparity.png"))
        .unwrap();
    let refused = |depth: &str, extra: &[&str], says: &[&str]| {
        let mut args = vec!["render", "--image", &image, "--depth", depth, "--no-prep"];
        args.extend_from_slice(&["--camera", &camera, "--depth-format", "cityscapes"]);
        args.extend_from_slice(&["--out", "o.png"]);
        args.extend_from_slice(extra);
        let o = brume(dir.path(), &args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{extra:?}");
        for s in says {
            assert!(err.contains(s), "{extra:?}: {err}");
        }
    };
    refused(
        &depth,
        &[],
        &[
            "--no-prep",
            "with the repair refinement",
            "invalid --no-prep = given",
            "(or --refine none); repair is --refine's default for a cityscapes depth",
        ],
    );
    refused(
        &depth,
        &["--refine", "guided"],
        &["with the guided refinement:"],
    );
    let smaller = format!("with a depth map of {w}x{h}, smaller than the");
    refused("half_disparity.png", &["--refine", "none"], &[&smaller]);
}

#[test]
fn info_reports_the_driver() {
    let dir = tempfile::tempdir().unwrap();
    let o = brume(dir.path(), &["info", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["renderer"].as_str().is_some_and(|s| !s.is_empty()));
    assert!(v["max_texture_size"].as_u64().unwrap() >= 2048);
    assert_eq!(
        (&v["brume"], &v["sources"]),
        (&brume::VERSION.into(), &brume::SOURCES.into())
    );
    let text = brume(dir.path(), &["info"]);
    let first = String::from_utf8_lossy(&text.stdout)
        .lines()
        .next()
        .map(str::to_owned);
    let build = format!("brume {} (sources {})", brume::VERSION, brume::SOURCES);
    assert_eq!(first.as_deref(), Some(build.as_str()));
    for key in [
        "color_buffer_float",
        "color_buffer_half_float",
        "texture_float_linear",
        "disjoint_timer_query",
        "egl_image_external_essl3",
        "egl_image_external",
    ] {
        assert!(v[key].is_boolean(), "{key}");
    }
}

/// `brume completions`: the bash script, sourced by bash, completes a command, a flag and
/// a flag's values; every shell's script names the commands and flags; a script that
/// cannot be written whole (a full device) fails the command rather than pass for done.
#[test]
fn completion_scripts_complete_in_bash() {
    let dir = tempfile::tempdir().unwrap();
    for shell in ["bash", "zsh", "fish", "elvish", "powershell"] {
        let o = brume(dir.path(), &["completions", shell]);
        assert!(o.status.success(), "{shell}: {}", stderr(&o));
        let script = String::from_utf8(o.stdout).unwrap();
        for word in ["render", "batch", "turbidity", "beta", "refine"] {
            assert!(script.contains(word), "{shell}'s script has no {word}");
        }
        if shell == "bash" {
            fs::write(dir.path().join("brume.bash"), script).unwrap();
        }
    }
    // What bash offers after `words`, the last being the one completed.
    let complete = |words: &str| -> String {
        let line = format!(
            "source brume.bash; COMP_WORDS=({words}); COMP_CWORD=$((${{#COMP_WORDS[@]}} - 1)); \
             _brume brume \"${{COMP_WORDS[COMP_CWORD]}}\" \"${{COMP_WORDS[COMP_CWORD-1]}}\"; \
             echo \"${{COMPREPLY[*]}}\""
        );
        let o = Command::new("bash")
            .args(["-c", &line])
            .current_dir(dir.path())
            .output()
            .expect("run bash");
        assert!(o.status.success(), "{words}: {}", stderr(&o));
        String::from_utf8(o.stdout).unwrap().trim().to_string()
    };
    assert_eq!(complete("brume ren"), "render");
    assert_eq!(complete("brume render --bet"), "--beta");
    assert_eq!(
        complete("brume batch --refine ''"),
        "none guided unreliable repair"
    );

    let full = fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_brume"))
        .args(["completions", "bash"])
        .stdout(full)
        .output()
        .unwrap();
    assert!(!o.status.success(), "a script written to /dev/full passed");
    assert!(stderr(&o).contains("standard output"), "{}", stderr(&o));
}

/// A file without its flag (as most image tools take it) is refused by clap with a tip
/// naming the flags that take it, those not given yet; a subcommand's option given to its
/// parent names the subcommand; another tool's name for a flag names brume's instead of
/// clap's nearest spelling (`--input` is not `--tint`); clap's own suggestion of a similar
/// name is left alone otherwise.
#[test]
fn a_file_without_its_flag_gets_a_tip() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&[&str], &[&str], &[&str]); 10] = [
        (
            &["render", "photo.jpg", "depth.png"],
            &[
                "brume render takes its files by flag",
                "'--image photo.jpg'",
                "'--depth photo.jpg'",
            ],
            &[],
        ),
        (
            &["render", "--image", "photo.jpg", "depth.png"],
            &["'--depth depth.png'"],
            &["--image depth.png"],
        ),
        (
            &["view", "photo.jpg"],
            &["brume view render takes its files", "'--image photo.jpg'"],
            &[],
        ),
        (
            &["view", "--image=photo.jpg"],
            &["--image is an option of brume view render"],
            &[],
        ),
        (
            &["photo.jpg"],
            &["brume render takes its files", "'--image photo.jpg'"],
            &[],
        ),
        (
            &["render", "--input", "photo.jpg"],
            &["brume render takes --image for that (the colour image)"],
            &["--tint"],
        ),
        (
            &["render", "--fog=0.02"],
            &["takes --beta for that", "--visibility"],
            &["--fov"],
        ),
        (
            &["render", "--out", "fog.png", "--force"],
            &["brume render replaces the file --out names without asking"],
            &["--focal"],
        ),
        (
            &["batch", "frames", "--out", "foggy", "-y"],
            &["brume batch writes the outputs missing under --out"],
            &[],
        ),
        (
            &["rendr", "photo.jpg"],
            &["a similar subcommand exists: 'render'"],
            &["takes its files"],
        ),
    ];
    for (args, wanted, unwanted) in cases {
        let o = brume(dir.path(), args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        for w in wanted {
            assert!(err.contains(w), "{args:?}: {w:?} not in {err}");
        }
        for u in unwanted {
            assert!(!err.contains(u), "{args:?}: {u:?} in {err}");
        }
    }
}

/// On a terminal (a pseudo-terminal from `script`, bsdutils, which `tools/setup.sh`
/// installs) `render` shows the stage it is at and takes it off before the report; a log
/// line goes above it. Where stderr is not a terminal nothing of it is written.
#[test]
fn render_shows_its_stage_on_a_terminal_only() {
    let dir = tempfile::tempdir().unwrap();
    let (image, depth) = small_scene(dir.path());
    let bin = env!("CARGO_BIN_EXE_brume");
    let command = format!(
        "'{bin}' render --image '{}' --depth '{}' --depth-scale 1 --beta 0.02 --out fog.png",
        image.display(),
        depth.display()
    );
    let _lock = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let o = Command::new("script")
        .args(["-qec", &command, "/dev/null"])
        .current_dir(dir.path())
        .env_remove("RUST_LOG")
        .output()
        .expect("run brume under script (bsdutils: bash tools/setup.sh installs it)");
    drop(_lock);
    let shown = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{shown}");
    let stage = shown.find("reading the photo and its depth").expect(&shown);
    let cleared = shown.rfind("\r\x1b[2K").expect(&shown);
    let report = shown.find("wrote ").expect(&shown);
    assert!(stage < cleared && cleared < report, "{shown:?}");
    // A spinner's line: a stage, then the time so far in brackets.
    let spinner_in = |text: &str| {
        ["the depth (", "rendering (", "writing "]
            .iter()
            .any(|s| text.contains(s))
    };
    assert!(!spinner_in(&shown[report..]), "{shown:?}");
    // The depth along the optical axis without a focal length is warned of: on a line of
    // its own (the spinner taken off first, not written into), with the spinner drawn
    // again after it.
    let warning = shown.find("WARN").expect(&shown);
    let before = &shown[..warning];
    let line_start = before.rfind("\x1b[2K").expect(&shown);
    assert!(!before[line_start..].contains("reading"), "{shown:?}");
    let line_end = warning + shown[warning..].find("\r\n").expect(&shown);
    assert!(spinner_in(&shown[line_end..report]), "{shown:?}");

    let o = render_files(
        dir.path(),
        &image,
        &depth,
        &["--depth-scale", "1", "--beta", "0.02", "--out", "fog2.png"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("reading the photo"), "{}", stderr(&o));
}

#[test]
fn missing_input_file_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let (image, _) = small_scene(dir.path());
    let o = render_files(
        dir.path(),
        &image,
        Path::new("nope.pfm"),
        &["--out", "o.png"],
    );
    assert_fails_cleanly(&o, &["nope.pfm"]);
    assert!(!dir.path().join("o.png").exists());
}

#[test]
fn truncated_pfm_is_a_format_error() {
    let dir = tempfile::tempdir().unwrap();
    let (image, depth) = small_scene(dir.path());
    let bytes = fs::read(&depth).unwrap();
    fs::write(&depth, &bytes[..bytes.len() / 2]).unwrap();
    let o = render_files(dir.path(), &image, &depth, &["--out", "o.png"]);
    assert_fails_cleanly(&o, &["range.pfm"]);
    assert!(!dir.path().join("o.png").exists());
}

#[test]
fn non_numeric_calib_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let (image, depth) = small_scene(dir.path());
    let calib = dir.path().join("calib.txt");
    fs::write(
        &calib,
        "cam0=[3997.684 0 1176.728; 0 3997.684 1011.728; 0 0 1]\ncam1=[3997.684 0 1307.839; 0 3997.684 1011.728; 0 0 1]\n\
         doffs=abc\nbaseline=193.001\nwidth=24\nheight=16\nndisp=290\nisint=0\nvmin=31\nvmax=257\n",
    )
    .unwrap();
    let o = render_files(
        dir.path(),
        &image,
        &depth,
        &["--calib", calib.to_str().unwrap(), "--out", "o.png"],
    );
    assert_fails_cleanly(&o, &["calib.txt", "doffs"]);
}

#[test]
fn image_and_depth_of_different_sizes_name_both() {
    let dir = tempfile::tempdir().unwrap();
    let (image, _) = small_scene(dir.path());
    let other = dir.path().join("other.pfm");
    write_scalar(&other, &Grid::filled(20, 16, 2.0f32)).unwrap();
    let o = render_files(dir.path(), &image, &other, &["--out", "o.png"]);
    assert_fails_cleanly(&o, &["im.png", "other.pfm", "24x16", "20x16"]);
    assert!(!dir.path().join("o.png").exists());
}

#[test]
fn depth_with_no_valid_value_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (image, _) = small_scene(dir.path());
    let empty = dir.path().join("empty.pfm");
    write_scalar(&empty, &Grid::filled(24, 16, f32::NAN)).unwrap();
    let o = render_files(dir.path(), &image, &empty, &["--out", "o.png"]);
    assert_fails_cleanly(&o, &["empty.pfm"]);
}

#[test]
fn bad_parameters_are_named() {
    let dir = tempfile::tempdir().unwrap();
    for (flag, value) in [
        ("--ks", "-1"),
        ("--ka", "nan"),
        ("--lambda", "inf"),
        ("--sigma0", "0"),
        ("--rho-max", "0.5"),
        ("--uniform-sigma", "0.5"),
    ] {
        let o = brume(dir.path(), &["render", flag, value]);
        assert_fails_cleanly(&o, &[flag]);
    }
    assert!(!dir.path().join("brume-demo.png").exists());
    let o = brume(dir.path(), &["render", "--airlight", "1,2"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--airlight"), "{}", stderr(&o));
    for tint in ["1,0,1", "1,1", "a,b,c"] {
        let o = brume(dir.path(), &["render", "--tint", tint]);
        assert!(!o.status.success());
        assert!(stderr(&o).contains("--tint"), "{}", stderr(&o));
    }
}

/// One `--airlight` value is a grey: the render and its report are those of the triple.
#[test]
fn one_airlight_value_is_a_grey() {
    let dir = tempfile::tempdir().unwrap();
    let (image, depth) = small_scene(dir.path());
    let run = |airlight: &str, out: &str| {
        let args = ["--depth-kind", "range", "--airlight", airlight, "--json"];
        let o = render_files(
            dir.path(),
            &image,
            &depth,
            &[&args[..], &["--out", out]].concat(),
        );
        assert!(o.status.success(), "{}", stderr(&o));
        let v: Value = serde_json::from_slice(&o.stdout).unwrap();
        (
            v["airlight"].clone(),
            fs::read(dir.path().join(out)).unwrap(),
        )
    };
    let (grey, grey_pfm) = run("0.6", "grey.pfm");
    let (triple, triple_pfm) = run("0.6,0.6,0.6", "triple.pfm");
    assert_eq!(grey, serde_json::json!([0.6f32, 0.6f32, 0.6f32]));
    assert_eq!(grey, triple);
    assert!(grey_pfm == triple_pfm, "the grey renders another image");
    let o = brume(dir.path(), &["render", "--airlight", "0.6,0.6"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("'0.6,0.6' has 2 values: expected three"),
        "{}",
        stderr(&o)
    );
}

/// A chromatic tint renders through the second target and is reported; blue, the most
/// attenuated channel, takes the most airlight.
#[test]
fn tint_makes_a_chromatic_haze() {
    let dir = tempfile::tempdir().unwrap();
    let (image, depth) = small_scene(dir.path());
    let run = |extra: &[&str], out: &str| {
        // Every step at full resolution in both renders, so that the blur is the same
        // in both whatever the coarse stage does with a tint.
        let mut args = vec![
            "--depth-kind",
            "range",
            "--airlight",
            "0,0,0",
            "--json",
            "--coarse-from",
            "off",
        ];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", out]);
        let o = render_files(dir.path(), &image, &depth, &args);
        assert!(o.status.success(), "{}", stderr(&o));
        let v: Value = serde_json::from_slice(&o.stdout).unwrap();
        (v, fs::read(dir.path().join(out)).unwrap())
    };
    let (grey, grey_pfm) = run(&[], "grey.pfm");
    let (tinted, tinted_pfm) = run(&["--tint", "0.5,1,2"], "tint.pfm");
    assert_eq!(grey["tint"], serde_json::json!([1.0, 1.0, 1.0]));
    assert_eq!(tinted["tint"], serde_json::json!([0.5, 1.0, 2.0]));
    assert_eq!(tinted["medium"], "haze");
    // With a black airlight the output is the attenuated colour. At the far right (R = 1,
    // κ = 1) grey haze keeps e^-1 of every channel; the tint keeps e^-0.5 of red and
    // e^-2 of blue: 1.65x and 0.37x the grey result.
    let last_pixel_of_first_row = |pfm: &[u8]| -> [f32; 3] {
        let data = &pfm[pfm.len() - 24 * 16 * 12..];
        let px = &data[23 * 12..24 * 12];
        [0, 1, 2].map(|c| f32::from_le_bytes(px[4 * c..4 * c + 4].try_into().unwrap()))
    };
    let (g, t) = (
        last_pixel_of_first_row(&grey_pfm),
        last_pixel_of_first_row(&tinted_pfm),
    );
    assert!(
        t[0] / g[0] > 1.5 && t[2] / g[2] < 0.45,
        "grey {g:?}, tinted {t:?}"
    );
    assert!(
        (t[1] / g[1] - 1.0).abs() < 0.01,
        "green untouched: {g:?} vs {t:?}"
    );
}

#[test]
fn output_never_overwrites_an_input() {
    let dir = tempfile::tempdir().unwrap();
    let (image, depth) = small_scene(dir.path());
    let before = fs::read(&image).unwrap();
    let o = render_files(
        dir.path(),
        &image,
        &depth,
        &["--depth-kind", "range", "--out", image.to_str().unwrap()],
    );
    assert_fails_cleanly(&o, &["--out"]);
    assert_eq!(fs::read(&image).unwrap(), before);
}

#[test]
fn unknown_output_extension_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let o = brume(dir.path(), &["render", "--out", "demo.bmp"]);
    assert_fails_cleanly(&o, &["demo.bmp"]);
    assert_eq!(
        fs::read_dir(dir.path()).unwrap().count(),
        0,
        "left a file behind"
    );
}

#[test]
fn real_aloe_renders_with_pre_processing() {
    let dir = tempfile::tempdir().unwrap();
    let o = render_files(
        dir.path(),
        &aloe("left.jpg"),
        &aloe("disparity.png"),
        &["--out", "aloe.png", "--json", "--lambda", "4"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["width"], 1282);
    assert_eq!(v["prep"]["sky_pixels"], 0, "Aloe is indoor: no sky");
    assert!(v["prep"]["hole_pixels"].as_u64().unwrap() > 0);
    assert_neutral_airlight(&v);
}

#[test]
fn a_missing_egl_library_says_what_to_install() {
    let dir = tempfile::tempdir().unwrap();
    let o = brume_with_env(
        dir.path(),
        &["render"],
        &[("BRUME_EGL_LIBRARY", "libEGL-does-not-exist.so.1")],
        &[],
    );
    assert_fails_cleanly(
        &o,
        &[
            "libEGL-does-not-exist.so.1",
            "libegl1 libegl-mesa0 libgles2 libgl1-mesa-dri",
        ],
    );
    assert!(!dir.path().join("brume-demo.png").exists());
}

#[test]
fn no_display_lists_what_was_tried() {
    // eglGetDisplay(EGL_DEFAULT_DISPLAY) needs a display server; with none (and no
    // EGL_PLATFORM override) the error must say what was tried and what to install.
    let dir = tempfile::tempdir().unwrap();
    let o = brume_with_env(
        dir.path(),
        &["info", "--egl", "default"],
        &[],
        &["DISPLAY", "WAYLAND_DISPLAY", "EGL_PLATFORM"],
    );
    if o.status.success() {
        // Some Mesa builds fall back to a surfaceless display by themselves: then the
        // report must say which platform answered.
        let v: String = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(v.contains("EGL platform       default"), "{v}");
    } else {
        assert_fails_cleanly(&o, &["default", "apt-get install"]);
    }
}

#[test]
fn prep_writes_the_range_and_the_picture() {
    let dir = tempfile::tempdir().unwrap();
    let disparity = aloe("disparity.png");
    let o = brume(
        dir.path(),
        &[
            "prep",
            "--depth",
            disparity.to_str().unwrap(),
            "--image",
            aloe("left.jpg").to_str().unwrap(),
            "--out",
            "range.exr",
            "--vis",
            "range.png",
            "--json",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["unknown_pixels"], 49_130);
    // Indoor: every unknown pixel is a hole, or (611 px of the left band) a border band
    // continued from the surfaces to its right; the true disparity has no specks in it.
    assert_eq!(v["border_islands"], 0, "{v}");
    // A left view's disparity: the leaves are only about 1.2 times nearer than the cloth,
    // under the occlusion rule's 1.25, but tens of pixels of disparity nearer, over its
    // 8: the runs beside them are occlusions (4,650 px; 55 by the ratio alone).
    let occluded = v["occluded"].as_u64().unwrap();
    assert!((4_000..5_500).contains(&occluded), "{v}");
    assert_eq!(
        v["hole_pixels"].as_u64().unwrap() + v["border_filled"].as_u64().unwrap(),
        49_130,
        "{v}"
    );
    assert_eq!(v["sky_pixels"], 0);
    assert_neutral_airlight(&v);
    let vis = image::open(dir.path().join("range.png")).unwrap();
    assert_eq!(
        (vis.width(), vis.height()),
        (1282, 2 * 1110),
        "before above after"
    );
    assert!(dir.path().join("range.exr").exists());
}

/// Aloe's disparity mirrored is a right view's: read with `--stereo-view right` its
/// occlusions are found right of the leaves, as many as the left view has left of them;
/// read as a left view's (the default), the runs it takes are others (the projector's
/// shadows right of the leaves, mirrored). The words say which view it was.
#[test]
fn prep_reads_a_right_views_disparity() {
    let dir = tempfile::tempdir().unwrap();
    let disparity = image::open(aloe("disparity.png")).unwrap();
    disparity
        .fliph()
        .save(dir.path().join("right.png"))
        .unwrap();
    let occluded = |depth: &str, view: &[&str]| -> (u64, Value) {
        let mut args = vec!["prep", "--depth", depth, "--out", "range.pfm", "--json"];
        args.extend_from_slice(view);
        let o = brume(dir.path(), &args);
        assert!(o.status.success(), "{}", stderr(&o));
        let v: Value = serde_json::from_slice(&o.stdout).unwrap();
        (v["occluded"].as_u64().unwrap(), v["stereo_view"].clone())
    };
    let left = occluded(aloe("disparity.png").to_str().unwrap(), &[]);
    let right = occluded("right.png", &["--stereo-view", "right"]);
    let as_left = occluded("right.png", &[]);
    assert_eq!(left.1, "left");
    assert_eq!(right.1, "right");
    assert_eq!(right.0, left.0, "the left view's occlusions, mirrored");
    assert!(as_left.0 != left.0, "{} {}", as_left.0, left.0);
    let args = ["prep", "--depth", "right.png", "--stereo-view", "right"];
    let o = brume(dir.path(), &[&args[..], &["--out", "range.pfm"]].concat());
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("px stereo occlusions of a right view"),
        "{text}"
    );
}

#[test]
fn prep_finds_the_sky_of_an_outdoor_scene_and_render_uses_it() {
    let dir = tempfile::tempdir().unwrap();
    let range = brume::prep::synthetic::outdoor_scene(160, 120, 3);
    write_scalar(&dir.path().join("outdoor.pfm"), &range).unwrap();
    // A blue-grey sky where the range is unknown, darker ground below.
    let image = Grid::from_fn(160, 120, |x, y| {
        if range.get(x, y).is_finite() {
            [0.1, 0.2, 0.05, 1.0]
        } else {
            [0.55, 0.6, 0.7, 1.0]
        }
    });
    write_rgba(&dir.path().join("outdoor.exr.png"), &image).unwrap();
    let o = render_files(
        dir.path(),
        Path::new("outdoor.exr.png"),
        Path::new("outdoor.pfm"),
        &["--depth-kind", "range", "--out", "fog.png", "--json"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["prep"]["sky_pixels"].as_u64().unwrap() > 0, "{v}");
    assert_eq!(v["airlight_source"], "sky");
    let b = airlight(&v);
    // The sky colour went through 8-bit sRGB: within a quantisation step in linear light.
    for (got, want) in b.iter().zip([0.55, 0.6, 0.7]) {
        assert!((got - want).abs() < 0.01, "airlight {b:?}");
    }
}

#[test]
fn prep_refuses_a_bad_margin_before_writing() {
    let dir = tempfile::tempdir().unwrap();
    let o = brume(
        dir.path(),
        &[
            "prep",
            "--depth",
            aloe("disparity.png").to_str().unwrap(),
            "--out",
            "r.pfm",
            "--margin",
            "-2",
        ],
    );
    assert_fails_cleanly(&o, &["--margin", "-2"]);
    assert!(!dir.path().join("r.pfm").exists());
}

/// The hidden `.brume-*.tmp` files in `dir`.
fn temporaries(dir: &Path) -> Vec<String> {
    fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|name| name.starts_with(".brume-"))
        .collect()
}

/// Ctrl-C (SIGINT) or SIGTERM while outputs are being written removes the temporaries,
/// leaves the old outputs as they were and exits with 128 + the signal. The test hook
/// `BRUME_TEST_HOLD_OUTPUTS` makes brume wait with both outputs staged, so the signal
/// lands exactly there every time.
#[cfg(unix)]
#[test]
fn a_signal_while_writing_leaves_no_temporary() {
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;
    for (signal, code) in [("INT", 130), ("TERM", 143)] {
        let dir = tempfile::tempdir().unwrap();
        let (_, depth) = small_scene(dir.path());
        let (out, vis) = (dir.path().join("out.pfm"), dir.path().join("vis.png"));
        fs::write(&out, b"old range").unwrap();
        fs::write(&vis, b"old picture").unwrap();
        let _lock = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
        let mut child = Command::new(env!("CARGO_BIN_EXE_brume"))
            .args(["prep", "--depth-kind", "range", "--depth"])
            .arg(&depth)
            .args(["--out", "out.pfm", "--vis", "vis.png"])
            .current_dir(dir.path())
            .env("BRUME_TEST_HOLD_OUTPUTS", "60")
            .stderr(Stdio::piped())
            .stdout(Stdio::null())
            .spawn()
            .expect("run brume");
        let mut stderr = BufReader::new(child.stderr.take().unwrap());
        let mut line = String::new();
        stderr.read_line(&mut line).unwrap();
        assert!(
            line.contains("holding 2 staged outputs"),
            "never reached the writing stage: {line:?}"
        );
        assert_eq!(temporaries(dir.path()).len(), 2, "both outputs staged");
        let kill = Command::new("kill")
            .args(["-s", signal, &child.id().to_string()])
            .status()
            .unwrap();
        assert!(kill.success());
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(code), "SIG{signal}: {status:?}");
        assert_eq!(temporaries(dir.path()), Vec::<String>::new(), "SIG{signal}");
        assert_eq!(fs::read(&out).unwrap(), b"old range");
        assert_eq!(fs::read(&vis).unwrap(), b"old picture");
    }
}

/// An option the depth's format does not read is said on stderr, not only in `--json`:
/// the render goes on.
#[test]
fn ignored_depth_options_are_said_on_stderr() {
    let dir = tempfile::tempdir().unwrap();
    let (image, _) = small_scene(dir.path());
    image::GrayImage::from_fn(24, 16, |x, _| image::Luma([10 + x as u8]))
        .save(dir.path().join("d8.png"))
        .unwrap();
    image::ImageBuffer::<image::Luma<u16>, _>::from_fn(24, 16, |x, _| {
        image::Luma([1000 + x as u16])
    })
    .save(dir.path().join("d16.png"))
    .unwrap();
    fs::write(dir.path().join("cam.json"), r#"{"extrinsic": {"baseline": 0.2}, "intrinsic": {"fx": 2000, "fy": 2000, "u0": 12, "v0": 8}}"#).unwrap();
    fs::write(
        dir.path().join("calib.txt"),
        "cam0=[1000 0 12; 0 1000 8; 0 0 1]\n",
    )
    .unwrap();
    for (depth, extra, said) in [
        ("d8.png", &["--camera", "cam.json"][..], "cam.json ignored"),
        (
            "d16.png",
            &["--depth-format", "kitti", "--camera", "cam.json"][..],
            "cam.json ignored",
        ),
        (
            "d16.png",
            &[
                "--depth-format",
                "cityscapes",
                "--camera",
                "cam.json",
                "--calib",
                "calib.txt",
            ][..],
            "--calib calib.txt ignored",
        ),
        (
            "d16.png",
            &["--depth-format", "arcore", "--depth-scale", "0.01"][..],
            "--depth-scale ignored",
        ),
        (
            "d16.png",
            &["--depth-format", "arcore", "--min-confidence", "0.5"][..],
            "--min-confidence ignored",
        ),
    ] {
        let mut args = vec!["--out", "o.png", "--json"];
        args.extend_from_slice(extra);
        let o = render_files(dir.path(), &image, &dir.path().join(depth), &args);
        let err = stderr(&o);
        assert!(o.status.success(), "{extra:?}: {err}");
        assert!(
            err.contains("WARN") && err.contains(said),
            "{extra:?}: {err}"
        );
        // The report keeps the note as the warning says it, with the flags' names.
        let report: Value = serde_json::from_slice(&o.stdout).unwrap();
        let notes = report["depth_notes"].as_array().unwrap();
        assert!(
            notes.iter().any(|n| n.as_str().unwrap().contains(said)),
            "{extra:?}: {notes:?}"
        );
    }
}

/// A sequence is all or nothing like every other output set: its frames are staged
/// together and an interrupt before they are renamed leaves none of them.
#[cfg(unix)]
#[test]
fn an_interrupted_sequence_leaves_no_frame() {
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;
    let dir = tempfile::tempdir().unwrap();
    let _lock = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let mut child = Command::new(env!("CARGO_BIN_EXE_brume"))
        .args([
            "scene", "--size", "32x24", "--frames", "3", "--out", "f.png",
        ])
        .current_dir(dir.path())
        .env("BRUME_TEST_HOLD_OUTPUTS", "60")
        .stderr(Stdio::piped())
        .stdout(Stdio::null())
        .spawn()
        .expect("run brume");
    let mut stderr = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    stderr.read_line(&mut line).unwrap();
    assert!(line.contains("holding 3 staged outputs"), "{line:?}");
    assert_eq!(temporaries(dir.path()).len(), 3, "every frame staged");
    let kill = Command::new("kill")
        .args(["-s", "TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    assert_eq!(child.wait().unwrap().code(), Some(143));
    let left: Vec<_> = fs::read_dir(dir.path()).unwrap().collect();
    assert!(left.is_empty(), "{left:?}");
}

/// A reader that goes away (`brume … --json | head -c 0`) ends no command with a panic:
/// the work is done, the outputs are written and the exit status is 0.
#[cfg(unix)]
#[test]
fn a_closed_stdout_is_no_crash() {
    use std::process::Stdio;
    let dir = tempfile::tempdir().unwrap();
    let (image, depth) = small_scene(dir.path());
    let (image, depth) = (image.to_str().unwrap(), depth.to_str().unwrap());
    let sky = "sky --turbidity 3 --sun-zenith 40 --sun-azimuth 20 --size 64 --out sky.exr";
    let render = format!("render --image {image} --depth {depth} --depth-kind range --out r.png");
    let cases = [
        (format!("{render} --json"), Some("r.png")),
        (render.clone(), Some("r.png")),
        (format!("{sky} --json"), Some("sky.exr")),
        (
            "turbidity sky.exr --sun-zenith 40 --sun-azimuth 20 --json".into(),
            None,
        ),
        (format!("compare {image} {image}"), None),
        (
            "scene --size 32x24 --frames 2 --out s.png --json".into(),
            Some("s_0002.png"),
        ),
        ("info".into(), None),
    ];
    for (args, output) in cases {
        if let Some(out) = output {
            let _ = fs::remove_file(dir.path().join(out));
        }
        let _lock = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
        let mut child = Command::new(env!("CARGO_BIN_EXE_brume"))
            .args(args.split_whitespace())
            .current_dir(dir.path())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("run brume");
        drop(child.stdout.take());
        let o = child.wait_with_output().unwrap();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(0), "{args}: {err}");
        assert!(!err.contains("panicked"), "{args}: {err}");
        if let Some(out) = output {
            assert!(dir.path().join(out).is_file(), "{args}: no {out}");
        }
    }
}

#[test]
fn compare_reports_ssim_and_histogram_correlation() {
    let dir = tempfile::tempdir().unwrap();
    let (image, _) = small_scene(dir.path());
    let darker = dir.path().join("darker.png");
    write_rgba(
        &darker,
        &Grid::from_fn(24, 16, |x, y| [x as f32 / 48.0, y as f32 / 32.0, 0.25, 1.0]),
    )
    .unwrap();
    let same = brume(dir.path(), &["compare", "im.png", "im.png", "--json"]);
    assert!(same.status.success(), "{}", stderr(&same));
    let v: Value = serde_json::from_slice(&same.stdout).unwrap();
    assert_eq!(v["ssim"].as_f64(), Some(1.0));
    assert_eq!(v["hsv_correlation"].as_f64(), Some(1.0));
    let other = brume(dir.path(), &["compare", "im.png", "darker.png", "--json"]);
    let v: Value = serde_json::from_slice(&other.stdout).unwrap();
    assert!(v["ssim"].as_f64().unwrap() < 0.99, "{v}");
    assert!(v["hsv_correlation"].as_f64().unwrap() < 0.99, "{v}");
    assert!(image.exists());
    let missing = brume(dir.path(), &["compare", "im.png", "nope.png"]);
    assert_fails_cleanly(&missing, &["nope.png"]);
}

/// `brume render --medium aerial` of a Cityscapes disparity: the camera file gives the
/// focal length and, by its mount, the pitch (0.04 rad down: 2.29° in the camera's up
/// positive degrees), unless --pitch or --horizon-row give it; the reports give the mount.
#[test]
fn a_cityscapes_camera_mount_sets_the_aerial_pitch_and_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let disparity = image::ImageBuffer::from_fn(48, 32, |_, _| image::Luma([5u16 * 256 + 1]));
    disparity.save(d.join("f_disparity.png")).unwrap();
    let camera = r#"{"extrinsic": {"baseline": 0.2, "z": 1.2, "pitch": 0.04},
        "intrinsic": {"fx": 40.0, "fy": 40.0, "u0": 23.5, "v0": 15.5}}"#;
    fs::write(d.join("f_camera.json"), camera).unwrap();
    image::RgbImage::from_pixel(48, 32, image::Rgb([90, 95, 100]))
        .save(d.join("f.png"))
        .unwrap();
    let report = |extra: &[&str]| {
        let base = ["render", "--image", "f.png", "--depth", "f_disparity.png"];
        let more = [
            "--medium",
            "aerial",
            "--turbidity",
            "3",
            "--json",
            "--out",
            "o.png",
        ];
        let args: Vec<&str> = base.iter().chain(&more).chain(extra).copied().collect();
        let o = brume(d, &args);
        assert!(o.status.success(), "{extra:?}: {}", stderr(&o));
        let v: Value = serde_json::from_slice(&o.stdout).unwrap();
        fs::remove_file(d.join("o.png")).unwrap();
        v
    };
    let pitch = |extra: &[&str]| report(extra)["pitch"].as_f64().unwrap();
    let mounted = report(&[]);
    let mount = &mounted["camera_mount"];
    assert_eq!(
        (mount["height_m"].as_f64(), mount["pitch"].as_f64()),
        (Some(1.2), Some(0.04))
    );
    assert!((mounted["pitch"].as_f64().unwrap() + 0.04f64.to_degrees()).abs() < 1e-9);
    assert_eq!(pitch(&["--pitch", "1"]), 1.0);
    // Row 15.5 of 32, the principal point's: level.
    assert!(pitch(&["--horizon-row", "15.5"]).abs() < 1e-9);
    // `brume prep` says it in words.
    let prep = brume(
        d,
        &[
            "prep",
            "--image",
            "f.png",
            "--depth",
            "f_disparity.png",
            "--out",
            "p.pfm",
        ],
    );
    assert!(prep.status.success(), "{}", stderr(&prep));
    let words = String::from_utf8_lossy(&prep.stdout);
    assert!(
        words.contains("the camera 1.20 m over the road, 2.29° down, roll 0.00°: 0 px"),
        "{words}"
    );
}

/// `--camera-mount` gives a depth map without a Cityscapes camera file the level road: a
/// road in millimetres (16-bit PNG, 64x48, 40° field of view) seen from 1.2 m up and 3°
/// down, with 6 px of specks 50 times too far on its rows 40-41, loses them with it and
/// keeps them without; a bad value is refused by name, and a map without intrinsics
/// ignores it with a warning.
#[test]
fn a_camera_mount_gives_any_depth_map_the_level_road() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (w, h, fov, pitch) = (64u32, 48u32, 40f64, 3f64.to_radians());
    let f = f64::from(h) / 2.0 / (fov.to_radians() / 2.0).tan();
    let speck = |x: u32, y: u32| (40..42).contains(&y) && (10..13).contains(&x);
    let depth = image::ImageBuffer::from_fn(w, h, |x, y| {
        let v = (f64::from(y) - 23.5) / f;
        let drop = v * pitch.cos() + pitch.sin();
        let z = if drop > 0.0 {
            (1.2 / drop).min(60.0)
        } else {
            60.0
        };
        let mm = if speck(x, y) {
            50.0 * z * 1000.0
        } else {
            z * 1000.0
        };
        image::Luma([mm.min(65535.0) as u16])
    });
    depth.save(d.join("road.png")).unwrap();
    let prep = |extra: &[&str]| {
        let base = ["prep", "--depth", "road.png", "--depth-format", "png16"];
        let more = ["--depth-scale", "0.001", "--out", "p.pfm", "--json"];
        let args: Vec<&str> = base.iter().chain(&more).chain(extra).copied().collect();
        brume(d, &args)
    };
    let dropped = |extra: &[&str]| {
        let o = prep(extra);
        assert!(o.status.success(), "{extra:?}: {}", stderr(&o));
        let v: Value = serde_json::from_slice(&o.stdout).unwrap();
        (v["below_ground"].as_u64().unwrap(), v)
    };
    let (with, v) = dropped(&["--fov", "40", "--camera-mount", "1.2,3"]);
    assert_eq!(with, 6, "{v}");
    assert_eq!(v["camera_mount"]["height_m"].as_f64(), Some(1.2));
    assert_eq!(dropped(&["--fov", "40"]).0, 0);
    let bad = prep(&["--fov", "40", "--camera-mount", "1.2"]);
    let err = stderr(&bad);
    assert!(!bad.status.success() && !err.contains("panicked"), "{err}");
    assert!(
        err.contains("'--camera-mount") && err.contains("HEIGHT,PITCH[,ROLL]"),
        "{err}"
    );
    let (none, v) = dropped(&["--camera-mount", "1.2,3"]);
    assert_eq!(none, 0);
    let notes = v["depth_notes"].to_string();
    assert!(notes.contains("--camera-mount ignored"), "{notes}");
}

/// `brume render --medium aerial`: a rendered frame's z-buffer as range in metres, the
/// turbidity given or estimated from a sky `brume sky` drew, and retargeting.
#[test]
fn aerial_perspective_renders_from_a_turbidity_a_sky_or_a_source_turbidity() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = brume(
        d,
        &[
            "scene",
            "--fog",
            "none",
            "--size",
            "48x32",
            "--out",
            "c.png",
            "--depth-out",
            "z.pfm",
        ],
    );
    assert!(scene.status.success(), "{}", stderr(&scene));
    let sky = brume(
        d,
        &[
            "sky",
            "--turbidity",
            "4",
            "--sun-zenith",
            "40",
            "--sun-azimuth",
            "20",
            "--size",
            "160",
            "--out",
            "sky.exr",
        ],
    );
    assert!(sky.status.success(), "{}", stderr(&sky));
    let base = [
        "render",
        "--image",
        "c.png",
        "--depth",
        "z.pfm",
        "--depth-kind",
        "zbuffer",
        "--near",
        "0.1",
        "--far",
        "1000",
        "--fov",
        "60",
        "--medium",
        "aerial",
        "--metres-per-unit",
        "20",
        "--json",
    ];
    let run = |extra: &[&str]| {
        let args: Vec<&str> = base.iter().chain(extra).copied().collect();
        let o = brume(d, &args);
        assert!(o.status.success(), "{extra:?}: {}", stderr(&o));
        serde_json::from_slice::<Value>(&o.stdout).unwrap()
    };
    let given = run(&["--turbidity", "3", "--out", "t3.png"]);
    assert_eq!(given["turbidity"].as_f64(), Some(3.0));
    assert_eq!(given["turbidity_source"], "given");
    assert_eq!(given["horizon_light_source"], "horizon");
    assert!(given["horizon_zenith"].as_f64().unwrap() > 80.0, "{given}");
    assert!(given["diffusion_passes"].as_u64().unwrap() > 0);
    assert!(
        given["insert"].is_null() && given["capture"].is_null(),
        "{given}"
    );
    let exposed = run(&[
        "--turbidity",
        "3",
        "--exposure-stops",
        "1",
        "--out",
        "t3-exposed.png",
    ]);
    assert_eq!(exposed["capture"]["exposure_stops"].as_f64(), Some(1.0));
    let estimated = run(&["--sky", "sky.exr", "--blur", "none", "--out", "sky.png"]);
    let t = estimated["turbidity"].as_f64().unwrap();
    assert!((t - 4.0).abs() < 0.05, "estimated {t}");
    assert_eq!(estimated["diffusion_passes"].as_u64(), Some(0));
    let retargeted = run(&[
        "--from-turbidity",
        "3",
        "--turbidity",
        "6",
        "--out",
        "t6.png",
    ]);
    assert_eq!(retargeted["from_turbidity"].as_f64(), Some(3.0));
    for out in ["t3.png", "sky.png", "t6.png"] {
        assert!(d.join(out).exists(), "{out}");
    }
    // The horizon on row 10 of 32 with a 60° field, above the centre: the camera looks
    // down, by atan(0.34375·tan 30°) = 11.2°.
    let row = run(&[
        "--turbidity",
        "3",
        "--horizon-row",
        "10",
        "--out",
        "row.png",
    ]);
    let pitch = row["pitch"].as_f64().unwrap();
    assert!((pitch + 11.2253).abs() < 1e-3, "{row}");
    // The sky photo is an input: never overwritten.
    let onto_sky: Vec<&str> = base
        .iter()
        .copied()
        .chain(["--sky", "sky.exr", "--out", "sky.exr"])
        .collect();
    let before = std::fs::read(d.join("sky.exr")).unwrap();
    assert_fails_cleanly(&brume(d, &onto_sky), &["--out", "sky.exr"]);
    assert_eq!(std::fs::read(d.join("sky.exr")).unwrap(), before);
    let missing: Vec<&str> = base.iter().copied().chain(["--out", "x.png"]).collect();
    assert_fails_cleanly(&brume(d, &missing), &["--turbidity"]);
    let both: Vec<&str> = base
        .iter()
        .copied()
        .chain(["--turbidity", "3", "--sky", "sky.exr", "--out", "x.png"])
        .collect();
    assert_fails_cleanly(&brume(d, &both), &["--sky"]);
    let low: Vec<&str> = base
        .iter()
        .copied()
        .chain(["--turbidity", "0.5", "--out", "x.png"])
        .collect();
    assert_fails_cleanly(&brume(d, &low), &["0.5"]);
}

/// `brume prep --image` accepts a depth map 4x smaller than the image: it is
/// pre-processed on its own grid, upsampled to the image's size guided by the image and,
/// with `--refine guided`, filtered by the CPU reference; the GPU's passes (the library's
/// `refine_prepared` through the renderer) give the same range within 1e-4.
#[test]
fn prep_upsamples_and_refines_a_smaller_depth_map_like_the_gpu() {
    let dir = tempfile::tempdir().unwrap();
    let image = brume::io::image::load_linear_rgb(&aloe("left.jpg")).unwrap();
    let (w, h) = (image.width() / 4 * 4, image.height() / 4 * 4);
    let image = brume::raster::Grid::from_fn(w, h, |x, y| *image.get(x, y));
    brume::io::output::write_rgba(&dir.path().join("left.png"), &image.opaque()).unwrap();
    let full = brume::io::depth::load_range(&aloe("disparity.png"), &Default::default())
        .unwrap()
        .range;
    let small = brume::raster::Grid::from_fn(w / 4, h / 4, |x, y| *full.get(4 * x + 1, 4 * y + 1));
    brume::io::output::write_scalar(&dir.path().join("small.pfm"), &small).unwrap();

    let o = brume(
        dir.path(),
        &[
            "prep",
            "--depth",
            "small.pfm",
            "--depth-kind",
            "range",
            "--image",
            "left.png",
            "--refine",
            "guided",
            "--out",
            "r.pfm",
            "--json",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        (v["width"].as_u64(), v["height"].as_u64()),
        (Some(w as u64), Some(h as u64))
    );
    assert_eq!(v["depth_width"].as_u64(), Some((w / 4) as u64));
    assert_eq!(
        (v["upsampled"].as_bool(), v["refine"].as_str()),
        (Some(true), Some("guided"))
    );
    let brume::io::codec::pfm::Pfm::Grey(cli) =
        brume::io::codec::pfm::read_pfm(&dir.path().join("r.pfm")).unwrap()
    else {
        panic!("prep wrote a colour PFM");
    };

    let mut prepared = brume::prep::prepare_guided(
        &small,
        brume::prep::Guides {
            image: Some(&brume::refine::image_at_depth_size(&image, w / 4, h / 4)),
            ..Default::default()
        },
        &brume::prep::PrepOptions::default(),
    )
    .unwrap();
    let opts = brume::refine::RefineOptions {
        mode: brume::refine::RefineMode::Guided,
        ..Default::default()
    };
    let _lock = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let mut headless = brume::Headless::new(None).unwrap();
    brume::refine::refine_prepared(&image, &mut prepared, &opts, headless.renderer().unwrap())
        .unwrap();
    assert_eq!((cli.width(), cli.height()), (w, h));
    let worst = cli
        .as_slice()
        .iter()
        .zip(prepared.range.as_slice())
        .map(|(a, b)| ((a - b) / b).abs())
        .fold(0f32, f32::max);
    assert!(
        worst < 1e-4,
        "CPU (prep) and GPU refinement differ by {worst}"
    );
}

#[test]
fn prep_refuses_refinement_without_an_image() {
    let dir = tempfile::tempdir().unwrap();
    let depth = aloe("disparity.png");
    for flag in [["--refine", "guided"], ["--refine-radius", "5"]] {
        let mut args = vec!["prep", "--depth", depth.to_str().unwrap()];
        args.extend(flag);
        args.extend(["--out", "r.pfm"]);
        let o = brume(dir.path(), &args);
        assert_fails_cleanly(&o, &[flag[0], "--image"]);
        assert!(!dir.path().join("r.pfm").exists());
    }
}

/// A `w` x `h` photo of a blue sky over `sky_rows` rows above a green, striped ground, as
/// `im.png` in `dir`.
fn write_sky_over_ground(dir: &Path, (w, h): (usize, usize), sky_rows: usize) {
    let photo = Grid::from_fn(w, h, |x, y| match y < sky_rows {
        true => [0.35, 0.5, 0.9, 1.0],
        false => [0.2 + 0.02 * (x % 5) as f32, 0.4, 0.15, 1.0],
    });
    write_rgba(&dir.join("im.png"), &photo).unwrap();
}

/// `brume render` of `im.png` in `dir` with the depth file and its `--depth-kind`, a 45°
/// field of view and `extra` flags, into `out`: the output read back as linear RGB.
fn fog_of_kind(
    dir: &Path,
    depth: (&str, &str),
    out: &str,
    extra: &[&str],
) -> brume::raster::RgbImage {
    render_of_kind(dir, depth, out, extra);
    brume::io::image::load_linear_rgb(&dir.join(out)).unwrap()
}

/// [`fog_of_kind`]'s run of `brume render`, asserted to succeed, with its output.
fn render_of_kind(dir: &Path, (depth, kind): (&str, &str), out: &str, extra: &[&str]) -> Output {
    let mut args = vec![
        "render",
        "--image",
        "im.png",
        "--depth",
        depth,
        "--depth-kind",
        kind,
        "--fov",
        "45",
        "--out",
        out,
    ];
    args.extend_from_slice(extra);
    let o = brume(dir, &args);
    assert!(o.status.success(), "{}", stderr(&o));
    o
}

/// The largest difference of two images of one size, over every channel.
fn largest_difference(a: &brume::raster::RgbImage, b: &brume::raster::RgbImage) -> f32 {
    (a.as_slice().iter().zip(b.as_slice()))
        .flat_map(|(a, b)| a.iter().zip(b).map(|(a, b)| (a - b).abs()))
        .fold(0.0f32, f32::max)
}

/// A monocular estimator's relative inverse depth (`--depth-kind inverse`) fogs as the
/// depth it inverts: paper 000's haze reads range over its largest value, so the unknown
/// scale cancels; its sky (0) is found and fogged as the depth map's unknown sky is. So
/// does affine-invariant depth (`--depth-kind affine`, Marigold) with the scene's nearest
/// and farthest depth as `--near` and `--far`, its sky at the far plane (1).
#[test]
fn relative_inverse_and_affine_depth_fog_as_the_depth_they_encode() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (24usize, 16usize);
    write_sky_over_ground(dir.path(), (w, h), 4);
    let z = |x: usize, y: usize| (y >= 4).then(|| 40.0 / (y - 3) as f32 + 0.1 * x as f32);
    let depth = Grid::from_fn(w, h, |x, y| z(x, y).unwrap_or(f32::NAN));
    let inverse = Grid::from_fn(w, h, |x, y| z(x, y).map_or(0.0, |z| 3.0 / z));
    // The farthest surface (42.3) a little short of the far plane, which is the sky's.
    let (near, far) = (4.4f32, 43.0f32);
    let affine = Grid::from_fn(w, h, |x, y| {
        z(x, y).map_or(1.0, |z| (z - near) / (far - near))
    });
    write_scalar(&dir.path().join("depth.pfm"), &depth).unwrap();
    write_scalar(&dir.path().join("inverse.pfm"), &inverse).unwrap();
    write_scalar(&dir.path().join("affine.pfm"), &affine).unwrap();
    let fog = |depth: &str, kind: &str, out: &str, extra: &[&str]| {
        fog_of_kind(dir.path(), (depth, kind), out, extra)
    };
    let from_depth = fog("depth.pfm", "depth", "depth.pfm.out.pfm", &[]);
    let from_inverse = fog("inverse.pfm", "inverse", "inverse.out.pfm", &[]);
    // 3/(3/z) is z to an ulp or two.
    let largest = largest_difference(&from_depth, &from_inverse);
    assert!(largest < 1e-5, "{largest}");
    let planes = ["--near", "4.4", "--far", "43"];
    let from_affine = fog("affine.pfm", "affine", "affine.out.pfm", &planes);
    // near + d·(far − near) is z to a few ulps of 43.
    let largest = largest_difference(&from_depth, &from_affine);
    assert!(largest < 1e-5, "{largest}");
}

/// A monocular model gives the sky a depth, the farthest, where a sensor leaves it
/// unknown: Depth Anything's relative inverse depth a small positive disparity (not 0), a
/// Marigold ensemble's affine depth just under its far plane. Read as inverse or affine
/// depth, the far tail may be sky, and the image finds it: the fog is that of the same
/// depth with the sky unknown.
#[test]
fn a_monocular_maps_sky_in_its_far_tail_is_found() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (24usize, 16usize);
    write_sky_over_ground(dir.path(), (w, h), 5);
    let z = |x: usize, y: usize| (y >= 5).then(|| 30.0 / (y - 4) as f32 + 0.1 * x as f32);
    let map = |surface: &dyn Fn(f32) -> f32, sky: &dyn Fn(usize) -> f32| {
        Grid::from_fn(w, h, |x, y| z(x, y).map_or_else(|| sky(x), surface))
    };
    let (near, far) = (2.0f32, 400.0f32);
    let maps = [
        ("depth.pfm", map(&|z| z, &|_| f32::NAN)),
        (
            "inverse.pfm",
            map(&|z| 3.0 / z, &|x| 0.002 + 0.00002 * x as f32),
        ),
        (
            "affine.pfm",
            map(&|z| (z - near) / (far - near), &|x| 0.97 + 0.001 * x as f32),
        ),
    ];
    for (name, values) in &maps {
        write_scalar(&dir.path().join(name), values).unwrap();
    }
    let fog = |depth: &str, kind: &str, extra: &[&str]| {
        fog_of_kind(
            dir.path(),
            (depth, kind),
            &format!("{depth}.out.pfm"),
            extra,
        )
    };
    let unknown_sky = fog("depth.pfm", "depth", &[]);
    let inverse = fog("inverse.pfm", "inverse", &[]);
    assert!(largest_difference(&unknown_sky, &inverse) < 1e-5);
    let affine = fog("affine.pfm", "affine", &["--near", "2", "--far", "400"]);
    assert!(largest_difference(&unknown_sky, &affine) < 1e-5);
}

/// Depth Pro's sky, clamped at 10 km, fogs as the unknown sky of the same map: found with
/// the image, its colour the airlight. `--sky-beyond` does the same for a sky that is not
/// clamped exactly (Depth Anything's metric models saturate toward their largest depth).
#[test]
fn a_models_clamped_or_saturated_sky_fogs_as_the_unknown_sky() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (24usize, 16usize);
    write_sky_over_ground(dir.path(), (w, h), 5);
    let z = |x: usize, y: usize| (y >= 5).then(|| 30.0 / (y - 4) as f32 + 0.1 * x as f32);
    let map =
        |sky: &dyn Fn(usize) -> f32| Grid::from_fn(w, h, |x, y| z(x, y).unwrap_or_else(|| sky(x)));
    write_scalar(&dir.path().join("nan.pfm"), &map(&|_| f32::NAN)).unwrap();
    write_scalar(&dir.path().join("clamped.pfm"), &map(&|_| 10_000.0)).unwrap();
    write_scalar(
        &dir.path().join("saturated.pfm"),
        &map(&|x| 79.0 + 0.03 * x as f32),
    )
    .unwrap();
    let fog = |depth: &str, extra: &[&str]| {
        let out = format!("{depth}.png");
        let mut args = vec!["--depth-scale", "1", "--beta", "0.02", "--json"];
        args.extend_from_slice(extra);
        let o = render_of_kind(dir.path(), (depth, "depth"), &out, &args);
        let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        (std::fs::read(dir.path().join(&out)).unwrap(), report)
    };
    let (unknown_sky, report) = fog("nan.pfm", &[]);
    assert_eq!(report["airlight_source"], "sky", "{report}");
    let (clamped, report) = fog("clamped.pfm", &[]);
    assert_eq!(clamped, unknown_sky);
    let notes = report["depth_notes"].to_string();
    assert!(
        notes.contains("a clamp") && notes.contains("--sky-beyond"),
        "{notes}"
    );
    let (saturated, _) = fog("saturated.pfm", &["--sky-beyond", "78"]);
    assert_eq!(saturated, unknown_sky);
    // Without it the saturated sky is a far surface, fogged as one: not the same picture.
    assert_ne!(fog("saturated.pfm", &[]).0, unknown_sky);
}

#[test]
fn depth_taken_as_range_for_want_of_intrinsics_warns() {
    let dir = tempfile::tempdir().unwrap();
    let (image, depth) = small_scene(dir.path());
    let o = render_files(
        dir.path(),
        &image,
        &depth,
        &["--depth-kind", "depth", "--out", "o.png"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let warning = "depth along the optical axis used as range for want of --focal or --fov";
    assert!(stderr(&o).contains(warning), "{}", stderr(&o));
    for (geometry, out) in [
        (["--fov", "50"], "fov.png"),
        (["--focal", "30"], "focal.png"),
    ] {
        let mut args = vec!["--depth-kind", "depth", "--out", out];
        args.extend_from_slice(&geometry);
        let o = render_files(dir.path(), &image, &depth, &args);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(!stderr(&o).contains(warning), "{}", stderr(&o));
    }
}
