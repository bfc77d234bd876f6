//! `brume view` in a real window: under Xvfb (installed by `tools/setup.sh`), scripted with
//! `--frames N --screenshot --stats`. The screenshot must show the fogged image, texel for
//! texel the same as `brume render` writes for the same parameters; the run must exit
//! cleanly and create no GL object after its first frame. A missing Xvfb is a failure, as
//! a missing EGL is: these tests prove the window path.

use crate::common;

use common::brume;

use image::RgbImage;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The haze of both the window and the file render (paper 000; σmax ≈ 8).
const HAZE: &[&str] = &["--ka", "0.2", "--ks", "0.5", "--lambda", "7"];

fn xvfb_run() -> PathBuf {
    let found = std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|d| d.join("xvfb-run"))
            .find(|p| p.is_file())
    });
    found.unwrap_or_else(|| {
        panic!(
            "xvfb-run not found: run `bash tools/setup.sh` (it installs Xvfb for the window tests)"
        )
    })
}

/// `brume ARGS` in `dir` on a fresh virtual X display of 1600x1000.
fn brume_in_window(dir: &Path, args: &[&str]) -> Output {
    let _gl = common::gl_lock();
    Command::new(xvfb_run())
        .args(["-a", "-s", "-screen 0 1600x1000x24 -nolisten tcp"])
        .arg(env!("CARGO_BIN_EXE_brume"))
        .args(args)
        .current_dir(dir)
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("xvfb-run runs")
}

fn assert_ok(what: &str, out: &Output) {
    assert!(
        out.status.success(),
        "{what} failed ({:?}):\n{}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{what} panicked:\n{stderr}");
}

fn read_json(path: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).expect("stats written")).expect("stats are JSON")
}

fn load_rgb(path: &Path) -> RgbImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8()
}

/// The part of `shot` at `rect` = [x, y, w, h] (top row first).
fn crop(shot: &RgbImage, rect: &Value) -> RgbImage {
    let r: Vec<u32> = rect
        .as_array()
        .expect("image_rect is an array")
        .iter()
        .map(|v| v.as_u64().expect("whole pixels") as u32)
        .collect();
    assert!(
        r[0] + r[2] <= shot.width() && r[1] + r[3] <= shot.height(),
        "image_rect {r:?} outside the {}x{} screenshot",
        shot.width(),
        shot.height()
    );
    image::imageops::crop_imm(shot, r[0], r[1], r[2], r[3]).to_image()
}

/// Largest and mean absolute difference per channel (8-bit levels).
fn differences(a: &RgbImage, b: &RgbImage) -> (u8, f64) {
    assert_eq!(a.dimensions(), b.dimensions());
    let d: Vec<u8> = a
        .as_raw()
        .iter()
        .zip(b.as_raw())
        .map(|(x, y)| x.abs_diff(*y))
        .collect();
    let max = d.iter().copied().max().unwrap_or(0);
    let mean = d.iter().map(|&v| f64::from(v)).sum::<f64>() / d.len() as f64;
    (max, mean)
}

fn std_dev(img: &RgbImage) -> f64 {
    let v: Vec<f64> = img.as_raw().iter().map(|&x| f64::from(x)).collect();
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / v.len() as f64).sqrt()
}

/// With and without the guided refinement (which the viewer runs at load on its window's
/// context, as `brume render` runs it on its own).
#[test]
fn the_window_shows_what_render_writes_and_allocates_nothing_per_frame() {
    for refine in ["none", "guided"] {
        the_window_shows_what_render_writes(refine);
    }
}

fn the_window_shows_what_render_writes(refine: &str) {
    let dir = tempfile::tempdir().unwrap();
    // The demo's half-size Aloe: it fits the virtual screen at zoom 1 beside the panel.
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let image = root.join("assets/demo/aloe-left-half.jpg");
    let depth = root.join("assets/demo/aloe-disparity-half.png");
    let (image, depth) = (image.to_str().unwrap(), depth.to_str().unwrap());
    let mut view = vec![
        "view",
        "--frames",
        "4",
        "--zoom",
        "1",
        "--screenshot",
        "shot.png",
        "--stats",
        "stats.json",
        "render",
        "--image",
        image,
        "--depth",
        depth,
    ];
    view.extend_from_slice(HAZE);
    view.extend_from_slice(&["--refine", refine]);
    let out = brume_in_window(dir.path(), &view);
    assert_ok("brume view", &out);

    let stats = read_json(&dir.path().join("stats.json"));
    assert_eq!(stats["frames"], 4, "{stats:#}");
    assert_eq!(
        stats["gl_objects_created_after_first_frame"], 0,
        "the frame loop must reuse its textures, targets and queries: {stats:#}"
    );
    let last = &stats["last_frame"];
    assert_eq!(last["pass_names"][0], "medium");
    assert!(last["total_ms"].as_f64().unwrap() > 0.0, "{last:#}");

    let mut render = vec![
        "render",
        "--image",
        image,
        "--depth",
        depth,
        "--out",
        "render.png",
    ];
    render.extend_from_slice(HAZE);
    render.extend_from_slice(&["--refine", refine]);
    assert_ok("brume render", &brume(dir.path(), &render));

    let shot = load_rgb(&dir.path().join("shot.png"));
    let shown = crop(&shot, &stats["image_rect"]);
    let written = load_rgb(&dir.path().join("render.png"));
    assert_eq!(
        shown.dimensions(),
        written.dimensions(),
        "zoom 1 shows every texel once"
    );
    // Both are the same f32 render encoded to 8-bit sRGB, once by the GPU into the display
    // texture and once on the CPU: they may differ by one rounding step.
    let (max, mean) = differences(&shown, &written);
    assert!(
        max <= 2 && mean < 0.2,
        "refine {refine}: window vs render.png: max {max}, mean {mean:.3}"
    );

    // Not blank, and fogged: the haze moves the picture away from the photo.
    let contrast = std_dev(&shown);
    assert!(
        contrast > 10.0,
        "the window's image is flat (σ {contrast:.1} levels)"
    );
    let photo = load_rgb(Path::new(image));
    let (_, fog) = differences(&shown, &photo);
    assert!(fog > 10.0, "no visible haze: mean change {fog:.1} levels");
    // The panel is drawn beside the image.
    let panel = image::imageops::crop_imm(&shot, 0, 0, 200, 400).to_image();
    assert!(std_dev(&panel) > 5.0, "no control panel in the screenshot");
}

#[test]
fn the_scene_runs_in_the_window_with_every_blur() {
    let dir = tempfile::tempdir().unwrap();
    for blur in ["diffusion", "gauss-single", "gauss-separate", "none"] {
        let stats = format!("{blur}.json");
        let shot = format!("{blur}.png");
        let out = brume_in_window(
            dir.path(),
            &[
                "view",
                "--frames",
                "3",
                "--screenshot",
                &shot,
                "--stats",
                &stats,
                "scene",
                "--size",
                "320x180",
                "--fog",
                "layered",
                "--blur",
                blur,
            ],
        );
        assert_ok(&format!("brume view scene --blur {blur}"), &out);
        let stats = read_json(&dir.path().join(&stats));
        assert_eq!(
            stats["gl_objects_created_after_first_frame"], 0,
            "{stats:#}"
        );
        let shown = crop(&load_rgb(&dir.path().join(&shot)), &stats["image_rect"]);
        assert!(std_dev(&shown) > 5.0, "--blur {blur}: the scene is flat");
    }
}

#[test]
fn no_display_is_a_clear_error_that_suggests_render() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_brume"))
        .args(["view", "--frames", "1"])
        .current_dir(dir.path())
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("no display") && stderr.contains("brume render"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "wrote nothing"
    );
}

#[test]
fn bad_view_options_are_refused_before_a_window_opens() {
    let dir = tempfile::tempdir().unwrap();
    for (args, expect) in [
        (&["view", "--frames", "0"][..], "--frames"),
        (&["view", "--zoom", "0"][..], "--zoom"),
        (&["view", "--screenshot", "x.png"][..], "--frames"),
        (&["view", "--frames", "1", "render", "--ka", "-1"][..], "ka"),
        (
            &["view", "--frames", "1", "scene", "--size", "0x10"][..],
            "size",
        ),
    ] {
        let out = brume_in_window(dir.path(), args);
        assert!(!out.status.success(), "{args:?} was accepted");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(expect), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "wrote nothing"
    );
}
