//! `brume batch` end to end on datasets the tests write: outputs named as Foggy
//! Cityscapes names them, the same pixels as `brume render` with the same options, runs
//! that resume, shards that split the work with no overlap, and a bad frame that is
//! reported and skipped while the others are written.

use crate::common;

use common::{brume, stderr};

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Cityscapes' camera file of the test frames: metric range of 95-465 m from the demo's
/// disparities (43-211 px).
const CAMERA_JSON: &str = r#"{"extrinsic": {"baseline": 0.2, "pitch": 0.0, "roll": 0.0, "x": 1.7, "y": 0.0, "yaw": 0.0, "z": 1.2},
 "intrinsic": {"fx": 100000.0, "fy": 100000.0, "u0": 320.5, "v0": 277.5}}"#;

/// Writes the demo's Aloe as a Cityscapes frame `name` of `city` under `root`, in
/// Cityscapes' layout: leftImg8bit/, disparity/ (16-bit, p = 256·d + 1) and camera/
/// (also the frames of `capture.rs`).
pub(crate) fn cityscapes_frame(root: &Path, city: &str, name: &str) {
    let demo = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/demo");
    let folder = |kind: &str| {
        let d = root.join(kind).join("train").join(city);
        std::fs::create_dir_all(&d).unwrap();
        d
    };
    image::open(demo.join("aloe-left-half.jpg"))
        .unwrap()
        .to_rgb8()
        .save(folder("leftImg8bit").join(format!("{name}_leftImg8bit.png")))
        .unwrap();
    let disparity = image::open(demo.join("aloe-disparity-half.png"))
        .unwrap()
        .to_luma8();
    let packed = image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_fn(
        disparity.width(),
        disparity.height(),
        |x, y| {
            let d = disparity.get_pixel(x, y)[0];
            image::Luma([if d == 0 { 0 } else { 256 * u16::from(d) + 1 }])
        },
    );
    packed
        .save(folder("disparity").join(format!("{name}_disparity.png")))
        .unwrap();
    std::fs::write(
        folder("camera").join(format!("{name}_camera.json")),
        CAMERA_JSON,
    )
    .unwrap();
}

/// A Cityscapes dataset of `n` frames in two cities under `dir/cityscapes`.
fn cityscapes_dataset(dir: &Path, n: usize) -> PathBuf {
    let root = dir.join("cityscapes");
    for k in 0..n {
        let city = if k % 2 == 0 { "aachen" } else { "bremen" };
        cityscapes_frame(&root, city, &format!("{city}_{k:06}_000019"));
    }
    root
}

/// A manifest over the frames of a Cityscapes dataset (`image,depth,camera`).
fn manifest_of(root: &Path) -> PathBuf {
    let mut csv = String::from("image,depth,camera\n");
    for city in ["aachen", "bremen"] {
        let Ok(entries) = std::fs::read_dir(root.join("leftImg8bit/train").join(city)) else {
            continue;
        };
        let mut names: Vec<String> = entries
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        for f in names {
            let name = f.trim_end_matches("_leftImg8bit.png");
            csv.push_str(&format!(
                "leftImg8bit/train/{city}/{f},disparity/train/{city}/{name}_disparity.png,camera/train/{city}/{name}_camera.json\n"
            ));
        }
    }
    let path = root.join("frames.csv");
    std::fs::write(&path, csv).unwrap();
    path
}

/// The images under `dir` (relative path → bytes).
fn outputs(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    common::snapshot(dir)
        .into_iter()
        .filter(|(k, _)| k.ends_with(".png"))
        .collect()
}

#[test]
fn a_run_writes_every_frame_and_beta_and_the_next_run_resumes() {
    let dir = tempfile::tempdir().unwrap();
    cityscapes_dataset(dir.path(), 2);
    let run = |extra: &[&str]| {
        let mut args = vec!["batch", "cityscapes", "--out", "out", "--beta", "0.01,0.02"];
        args.extend_from_slice(extra);
        brume(dir.path(), &args)
    };
    let first = run(&["--transmittance"]);
    assert!(first.status.success(), "{}", stderr(&first));
    let written = outputs(&dir.path().join("out"));
    let names: Vec<&str> = written.keys().map(String::as_str).collect();
    assert_eq!(
        names,
        [
            "leftImg8bit/train/aachen/aachen_000000_000019_leftImg8bit_foggy_beta_0.01.png",
            "leftImg8bit/train/aachen/aachen_000000_000019_leftImg8bit_foggy_beta_0.02.png",
            "leftImg8bit/train/aachen/aachen_000000_000019_leftImg8bit_transmittance_beta_0.01.png",
            "leftImg8bit/train/aachen/aachen_000000_000019_leftImg8bit_transmittance_beta_0.02.png",
            "leftImg8bit/train/bremen/bremen_000001_000019_leftImg8bit_foggy_beta_0.01.png",
            "leftImg8bit/train/bremen/bremen_000001_000019_leftImg8bit_foggy_beta_0.02.png",
            "leftImg8bit/train/bremen/bremen_000001_000019_leftImg8bit_transmittance_beta_0.01.png",
            "leftImg8bit/train/bremen/bremen_000001_000019_leftImg8bit_transmittance_beta_0.02.png",
        ]
    );
    // One log line per output, with its parameters and timings.
    let log = std::fs::read_to_string(dir.path().join("out/brume-batch-1-of-1.jsonl")).unwrap();
    let records: Vec<serde_json::Value> = log
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(records.len(), 4);
    for r in &records {
        assert_eq!(r["status"], "ok");
        // Which build made each output, should a dataset ever mix two.
        assert_eq!(
            (&r["brume"], &r["sources"]),
            (&brume::VERSION.into(), &brume::SOURCES.into())
        );
        assert!(
            r["gpu_ms"].as_f64().unwrap() > 0.0 && r["decode_ms"].as_f64().is_some(),
            "{r}"
        );
        // Cityscapes disparity is repaired by default: the frame's refinement has a time.
        assert!(r["refine_ms"].as_f64().unwrap() > 0.0, "{r}");
    }

    // A second run finds everything complete: it writes nothing and changes nothing.
    let again = run(&["--transmittance"]);
    assert!(again.status.success(), "{}", stderr(&again));
    let summary = String::from_utf8_lossy(&again.stdout).into_owned();
    assert!(
        summary.contains("wrote 0 outputs") && summary.contains("skipped 4 already written"),
        "{summary}"
    );
    assert_eq!(outputs(&dir.path().join("out")), written);

    // A lost output is written again, and only it.
    std::fs::remove_file(
        dir.path().join(
            "out/leftImg8bit/train/bremen/bremen_000001_000019_leftImg8bit_foggy_beta_0.02.png",
        ),
    )
    .unwrap();
    let resumed = run(&["--transmittance"]);
    assert!(resumed.status.success(), "{}", stderr(&resumed));
    assert!(String::from_utf8_lossy(&resumed.stdout).contains("wrote 1 outputs"));
    assert_eq!(
        outputs(&dir.path().join("out")),
        written,
        "the same bytes again"
    );
}

#[test]
fn a_run_with_other_settings_is_refused_and_changes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    cityscapes_dataset(dir.path(), 1);
    let out = dir.path().join("out");
    let run = |extra: &[&str]| {
        let mut args = vec!["batch", "cityscapes", "--out", "out"];
        args.extend_from_slice(extra);
        brume(dir.path(), &args)
    };
    let record = || -> serde_json::Value {
        let text = std::fs::read_to_string(out.join("brume-batch-settings.json")).unwrap();
        serde_json::from_str(&text).unwrap()
    };
    let first = run(&["--beta", "0.01", "--lambda", "2"]);
    assert!(first.status.success(), "{}", stderr(&first));
    let recorded = record();
    assert_eq!(recorded["brume"], env!("CARGO_PKG_VERSION"));
    assert_eq!(recorded["sources"], brume::SOURCES);
    assert_eq!(recorded["settings"]["frame"]["fog"]["lambda"], 2.0);
    let written = common::snapshot(&out);

    // Skipping the outputs there would mix two fogs: refused, naming what differs.
    let other = run(&["--beta", "0.01,0.02", "--lambda", "4", "--albedo", "0.8"]);
    assert!(!other.status.success(), "other settings accepted");
    let err = stderr(&other);
    for expected in [
        "--out",
        "albedo 1.0 there, 0.8 here",
        "fog.lambda 2.0 there, 4.0 here",
    ] {
        assert!(err.contains(expected), "{expected}: {err}");
    }
    assert_eq!(common::snapshot(&out), written, "the folder changed");

    // The same settings, with another β and other threads: the new β's outputs only.
    let more = run(&["--beta", "0.01,0.02", "--lambda", "2", "--loaders", "2"]);
    assert!(more.status.success(), "{}", stderr(&more));
    let summary = String::from_utf8_lossy(&more.stdout).into_owned();
    assert!(
        summary.contains("wrote 1 outputs") && summary.contains("skipped 1 already written"),
        "{summary}"
    );

    // The same settings recorded by another build of this version: resumed, with a warning
    // that names both builds.
    let mut older = record();
    older["sources"] = "0123456789abcdef".into();
    let settings_file = out.join("brume-batch-settings.json");
    std::fs::write(&settings_file, older.to_string()).unwrap();
    let resumed = run(&["--beta", "0.01,0.02", "--lambda", "2"]);
    assert!(resumed.status.success(), "{}", stderr(&resumed));
    let warning = stderr(&resumed);
    assert!(
        warning.contains("another build of brume")
            && warning.contains("0123456789abcdef")
            && warning.contains(brume::SOURCES),
        "{warning}"
    );

    // The record removed (the user's choice): other settings are taken, and recorded.
    std::fs::remove_file(&settings_file).unwrap();
    let anyway = run(&["--beta", "0.03", "--lambda", "4"]);
    assert!(anyway.status.success(), "{}", stderr(&anyway));
    assert_eq!(record()["settings"]["frame"]["fog"]["lambda"], 4.0);
}

#[test]
fn a_dry_run_lists_what_a_run_writes_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let root = cityscapes_dataset(dir.path(), 3);
    std::fs::remove_file(root.join("disparity/train/aachen/aachen_000002_000019_disparity.png"))
        .unwrap();
    let run = |extra: &[&str]| {
        let mut args = vec!["batch", "cityscapes", "--out", "out", "--beta", "0.01,0.02"];
        args.extend_from_slice(extra);
        brume(dir.path(), &args)
    };
    let dry = run(&["--dry-run"]);
    assert!(dry.status.success(), "{}", stderr(&dry));
    let stdout = String::from_utf8_lossy(&dry.stdout).into_owned();
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(
        lines[..4],
        [
            "out/leftImg8bit/train/aachen/aachen_000000_000019_leftImg8bit_foggy_beta_0.01.png",
            "out/leftImg8bit/train/aachen/aachen_000000_000019_leftImg8bit_foggy_beta_0.02.png",
            "out/leftImg8bit/train/bremen/bremen_000001_000019_leftImg8bit_foggy_beta_0.01.png",
            "out/leftImg8bit/train/bremen/bremen_000001_000019_leftImg8bit_foggy_beta_0.02.png",
        ]
    );
    for expected in [
        "dry run, nothing written: 3 frames found, 4 outputs to write, 0 already written",
        "1 frames that cannot be read",
        "settings to be recorded in out/brume-batch-settings.json",
    ] {
        assert!(lines[4].contains(expected), "{expected}: {stdout}");
    }
    let err = stderr(&dry);
    let missing = "aachen_000002_000019_leftImg8bit.png";
    assert!(
        err.contains("cannot read") && err.matches(missing).count() == 1,
        "{err}"
    );
    assert!(!dir.path().join("out").exists(), "the dry run made --out");

    // After a run, nothing is left to write, and the settings are the folder's.
    assert!(
        !run(&[]).status.success(),
        "the missing frame fails the run"
    );
    let again = run(&["--dry-run"]);
    let summary = String::from_utf8_lossy(&again.stdout).into_owned();
    assert!(
        summary.starts_with("dry run") && summary.contains("0 outputs to write, 4 already written"),
        "{summary}"
    );
    assert!(summary.contains("the settings out/brume-batch-settings.json records"));
    // Other settings are refused as a run refuses them.
    let other = run(&["--dry-run", "--lambda", "3"]);
    assert!(!other.status.success() && stderr(&other).contains("fog.lambda"));
}

#[test]
fn shards_split_the_frames_with_no_overlap() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = manifest_of(&cityscapes_dataset(dir.path(), 6));
    let manifest = manifest.to_str().unwrap();
    let mut seen = BTreeMap::new();
    for k in 1..=3 {
        let out = format!("out{k}");
        let shard = format!("{k}/3");
        let run = brume(
            dir.path(),
            &[
                "batch",
                "--manifest",
                manifest,
                "--out",
                &out,
                "--beta",
                "0.01",
                "--shard",
                &shard,
            ],
        );
        assert!(run.status.success(), "{}", stderr(&run));
        for name in outputs(&dir.path().join(&out)).into_keys() {
            assert!(
                seen.insert(name.clone(), k).is_none(),
                "{name} written by two shards"
            );
        }
    }
    assert_eq!(seen.len(), 6, "every frame in exactly one shard: {seen:?}");
}

#[test]
fn a_bad_frame_is_reported_and_skipped_and_the_run_fails() {
    let dir = tempfile::tempdir().unwrap();
    let root = cityscapes_dataset(dir.path(), 3);
    let bad = "disparity/train/aachen/aachen_000000_000019_disparity.png";
    std::fs::write(root.join(bad), b"not a png").unwrap();
    // A frame without its camera file.
    std::fs::remove_file(root.join("camera/train/bremen/bremen_000001_000019_camera.json"))
        .unwrap();
    let run = brume(
        dir.path(),
        &["batch", "cityscapes", "--out", "out", "--beta", "0.01"],
    );
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    let err = stderr(&run);
    assert!(err.contains("aachen_000000_000019_disparity.png"), "{err}");
    assert!(
        err.contains("bremen_000001_000019") && err.contains("camera"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    let names: Vec<String> = outputs(&dir.path().join("out")).into_keys().collect();
    assert_eq!(
        names,
        ["leftImg8bit/train/aachen/aachen_000002_000019_leftImg8bit_foggy_beta_0.01.png"]
    );
    let log = std::fs::read_to_string(dir.path().join("out/brume-batch-1-of-1.jsonl")).unwrap();
    assert_eq!(log.matches("\"status\":\"failed\"").count(), 2, "{log}");
}

/// Three loader threads, or three writer threads, write the bytes one writes, and log the
/// outputs in the frames' order whatever the order the loaders or the writers finish in:
/// each loader takes every third frame, the GPU takes them in turn, and the writers' log
/// waits for the outputs before. A bad frame among them fails alone.
#[test]
fn several_loaders_or_writers_write_what_one_writes_in_the_same_order() {
    let dir = tempfile::tempdir().unwrap();
    let root = cityscapes_dataset(dir.path(), 5);
    let bad = "disparity/train/bremen/bremen_000003_000019_disparity.png";
    std::fs::write(root.join(bad), b"not a png").unwrap();
    let run = |threads: [&str; 2]| {
        let out = format!("out{}", threads.concat());
        let args = ["batch", "cityscapes", "--out", &out, "--beta", "0.01,0.02"];
        let extra = ["--transmittance", threads[0], threads[1]];
        let run = brume(dir.path(), &[&args[..], &extra[..]].concat());
        assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
        let log = std::fs::read_to_string(dir.path().join(&out).join("brume-batch-1-of-1.jsonl"))
            .unwrap();
        let order: Vec<(String, String, String)> = log
            .lines()
            .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
            .map(|r| {
                let field = |k: &str| r[k].to_string();
                (field("image"), field("beta"), field("status"))
            })
            .collect();
        (outputs(&dir.path().join(&out)), order)
    };
    let (one, one_order) = run(["--loaders", "1"]);
    assert_eq!(one.len(), 16, "4 frames, 2 β, each with its τ map");
    let failed = one_order.iter().filter(|(.., s)| s == "\"failed\"").count();
    assert_eq!((one_order.len(), failed), (9, 1), "{one_order:?}");
    for threads in [["--loaders", "3"], ["--writers", "3"]] {
        let (other, other_order) = run(threads);
        assert!(one == other, "{threads:?}: the outputs differ");
        assert_eq!(one_order, other_order, "{threads:?}");
    }
}

#[test]
fn bad_batch_options_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    cityscapes_dataset(dir.path(), 1);
    for (args, expect) in [
        (
            &["batch", "cityscapes", "--out", "o", "--beta", "-0.01"][..],
            "--beta",
        ),
        (
            &["batch", "cityscapes", "--out", "o", "--beta", "0.01,x"][..],
            "--beta",
        ),
        (
            &["batch", "cityscapes", "--out", "o", "--shard", "4/3"][..],
            "--shard",
        ),
        (
            &["batch", "cityscapes", "--out", "o", "--albedo", "2"][..],
            "albedo",
        ),
        (&["batch", "--out", "o"][..], "no frames"),
        (&["batch", "nowhere", "--out", "o"][..], "nowhere"),
        (
            &["batch", "--manifest", "missing.csv", "--out", "o"][..],
            "missing.csv",
        ),
        (
            &["batch", "cityscapes", "--out", "o", "--near", "3"][..],
            "--depth-kind zbuffer",
        ),
        (
            &["batch", "cityscapes", "--out", "o", "--loaders", "0"][..],
            "--loaders",
        ),
        (
            &["batch", "cityscapes", "--out", "o", "--loaders", "17"][..],
            "--loaders",
        ),
        (
            &["batch", "cityscapes", "--out", "o", "--writers", "0"][..],
            "--writers",
        ),
        (
            &["batch", "cityscapes", "--out", "o", "--writers", "17"][..],
            "--writers",
        ),
    ] {
        let run = brume(dir.path(), args);
        assert!(!run.status.success(), "{args:?} was accepted");
        let err = stderr(&run);
        assert!(err.contains(expect), "{args:?}: {err}");
        assert!(
            !dir.path().join("o").exists(),
            "{args:?} created the output folder"
        );
    }
}

#[test]
fn each_output_is_what_render_writes_with_the_same_beta() {
    batch_outputs_are_renders(&[]);
}

/// Foggy Cityscapes' conventions too: batch finds the frame's dark-channel airlight once
/// for all its β, render once for its one.
#[test]
fn each_foggy_cityscapes_output_is_what_render_writes_with_the_same_beta() {
    batch_outputs_are_renders(&["--compat", "foggy-cityscapes"]);
}

/// Batch at β 0.005 and 0.02 with `extra` writes, for each β, the bytes `brume render`
/// writes with that β and `extra`, and two different images.
fn batch_outputs_are_renders(extra: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let root = cityscapes_dataset(dir.path(), 1);
    let args = [
        "batch",
        "cityscapes",
        "--out",
        "out",
        "--beta",
        "0.005,0.02",
    ];
    let run = brume(dir.path(), &[&args[..], extra].concat());
    assert!(run.status.success(), "{}", stderr(&run));
    let frame = "train/aachen/aachen_000000_000019";
    let image = root.join(format!("leftImg8bit/{frame}_leftImg8bit.png"));
    let depth = root.join(format!("disparity/{frame}_disparity.png"));
    let mut previous: Option<Vec<u8>> = None;
    for beta in ["0.005", "0.02"] {
        let out = format!("render-{beta}.png");
        let args = [
            "render",
            "--image",
            image.to_str().unwrap(),
            "--depth",
            depth.to_str().unwrap(),
            "--beta",
            beta,
            "--out",
            &out,
        ];
        let render = brume(dir.path(), &[&args[..], extra].concat());
        assert!(render.status.success(), "{}", stderr(&render));
        let batch = std::fs::read(dir.path().join(format!(
            "out/leftImg8bit/{frame}_leftImg8bit_foggy_beta_{beta}.png"
        )))
        .unwrap();
        assert!(
            batch == std::fs::read(dir.path().join(&out)).unwrap(),
            "β {beta}: batch and render differ"
        );
        // β matters: denser fog is another image.
        assert!(
            previous.as_ref() != Some(&batch),
            "β {beta} gave the image of the β before"
        );
        previous = Some(batch);
    }
}

/// Writes the demo's Aloe as `{name}.png` with its range in metres (2,000/d: 9.5-47 m,
/// unknown where d = 0) as a KITTI depth PNG (`{name}_kitti.png`, metres·256) and a float
/// map in metres (`{name}_range.pfm`), and a manifest over each (`kitti.csv`,
/// `float.csv`).
fn metric_frames(dir: &Path, name: &str) {
    let demo = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/demo");
    image::open(demo.join("aloe-left-half.jpg"))
        .unwrap()
        .to_rgb8()
        .save(dir.join(format!("{name}.png")))
        .unwrap();
    let disparity = image::open(demo.join("aloe-disparity-half.png"))
        .unwrap()
        .to_luma8();
    let metres = |x: u32, y: u32| match disparity.get_pixel(x, y)[0] {
        0 => f32::NAN,
        d => 2000.0 / f32::from(d),
    };
    let (w, h) = disparity.dimensions();
    image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_fn(w, h, |x, y| {
        let m = metres(x, y);
        image::Luma([if m.is_nan() {
            0
        } else {
            (m * 256.0).round() as u16
        }])
    })
    .save(dir.join(format!("{name}_kitti.png")))
    .unwrap();
    let range =
        brume::raster::Grid::from_fn(w as usize, h as usize, |x, y| metres(x as u32, y as u32));
    brume::io::output::write_scalar(&dir.join(format!("{name}_range.pfm")), &range).unwrap();
    for (csv, depth) in [("kitti.csv", "kitti.png"), ("float.csv", "range.pfm")] {
        let rows = format!("image,depth\n{name}.png,{name}_{depth}\n");
        std::fs::write(dir.join(csv), rows).unwrap();
    }
}

/// An output that is a file some frame reads (a manifest listing an earlier run's output
/// beside its frame, into the same folder; an output's path that links to an input) is
/// refused before any work, and the file is left as it was.
#[test]
fn an_output_that_a_frame_reads_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    metric_frames(dir.path(), "aloe");
    let earlier = dir.path().join("aloe_foggy_beta_0.02.png");
    std::fs::copy(dir.path().join("aloe.png"), &earlier).unwrap();
    let rows = "image,depth\naloe.png,aloe_kitti.png\naloe_foggy_beta_0.02.png,aloe_kitti.png\n";
    std::fs::write(dir.path().join("both.csv"), rows).unwrap();
    let before = std::fs::read(&earlier).unwrap();
    let batch = |csv: &str, out: &str| {
        let args = [
            "batch",
            "--manifest",
            csv,
            "--out",
            out,
            "--beta",
            "0.02",
            "--depth-format",
            "kitti",
            "--fov",
            "40",
            "--transmittance",
        ];
        brume(dir.path(), &args)
    };
    let refused = batch("both.csv", ".");
    assert!(!refused.status.success(), "an input taken as an output");
    let err = stderr(&refused);
    assert!(
        err.contains("aloe.png") && err.contains("a file a frame reads"),
        "{err}"
    );
    assert_eq!(std::fs::read(&earlier).unwrap(), before);
    // An output folder made beforehand, whose output path links to the photo.
    std::fs::create_dir(dir.path().join("linked")).unwrap();
    std::os::unix::fs::symlink(
        dir.path().join("aloe.png"),
        dir.path().join("linked/aloe_foggy_beta_0.02.png"),
    )
    .unwrap();
    let linked = batch("kitti.csv", "linked");
    assert!(
        !linked.status.success(),
        "an output through a link to an input"
    );
    assert!(stderr(&linked).contains("a file a frame reads"));
}

/// A manifest of KITTI depth, or of float range in metres, is read as the depth flags
/// say for every row: each output is the bytes `brume render` writes with the same flags.
/// Without them the frames fail, each naming the flag that would read it, and a frame's
/// own camera file as its manifest column (`camera`), not as `render`'s `--camera`, and
/// none offering normalised range, which batch does not have.
#[test]
fn a_manifests_depth_is_read_as_the_depth_flags_say() {
    let dir = tempfile::tempdir().unwrap();
    metric_frames(dir.path(), "aloe");
    for (csv, depth, flags, unread) in [
        (
            "kitti.csv",
            "aloe_kitti.png",
            &["--depth-format", "kitti", "--fov", "40"][..],
            "--depth-format kitti",
        ),
        (
            "float.csv",
            "aloe_range.pfm",
            &["--depth-scale", "1", "--fov", "40"][..],
            "--depth-scale",
        ),
    ] {
        let out = format!("out-{csv}");
        let batch = ["batch", "--manifest", csv, "--out", &out, "--beta", "0.02"];
        let refused = brume(dir.path(), &batch);
        assert!(!refused.status.success(), "{csv} read without flags");
        let err = stderr(&refused);
        assert!(err.contains(unread), "{err}");
        assert!(
            err.contains("`camera`") && !err.contains("--camera"),
            "{err}"
        );
        // Batch's fog is always in metres: no normalised range to offer.
        assert!(!err.contains("`ka`") && !err.contains("--ka"), "{err}");
        let _ = std::fs::remove_dir_all(dir.path().join(&out));

        let run = brume(dir.path(), &[&batch[..], flags].concat());
        assert!(run.status.success(), "{csv}: {}", stderr(&run));
        let render = [
            "render",
            "--image",
            "aloe.png",
            "--depth",
            depth,
            "--beta",
            "0.02",
            "--out",
            "render.png",
        ];
        let render = brume(dir.path(), &[&render[..], flags].concat());
        assert!(render.status.success(), "{}", stderr(&render));
        assert!(
            std::fs::read(dir.path().join(format!("{out}/aloe_foggy_beta_0.02.png"))).unwrap()
                == std::fs::read(dir.path().join("render.png")).unwrap(),
            "{csv}: batch and render differ"
        );
    }
}

/// Depth along the axis (KITTI's) read without `--fov` or `--focal` is used as range: a
/// batch warns once with the flags to give, counts the frames in its summary and lists
/// the warning in each output's log record; with `--fov` nothing warns.
#[test]
fn depth_taken_as_range_warns_once_and_is_logged_for_each_output() {
    let dir = tempfile::tempdir().unwrap();
    metric_frames(dir.path(), "a");
    metric_frames(dir.path(), "b");
    let rows = "image,depth\na.png,a_kitti.png\nb.png,b_kitti.png\n";
    std::fs::write(dir.path().join("two.csv"), rows).unwrap();
    let batch = |out: &str, extra: &[&str]| {
        let args = [
            "batch",
            "--manifest",
            "two.csv",
            "--out",
            out,
            "--beta",
            "0.02,0.03",
        ];
        let run = brume(
            dir.path(),
            &[&args[..], &["--depth-format", "kitti"], extra].concat(),
        );
        assert!(run.status.success(), "{}", stderr(&run));
        let log = std::fs::read_to_string(dir.path().join(out).join("brume-batch-1-of-1.jsonl"));
        let records: Vec<serde_json::Value> = (log.unwrap().lines())
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        assert_eq!(records.len(), 4, "two frames, two betas");
        (
            stderr(&run),
            String::from_utf8_lossy(&run.stdout).into_owned(),
            records,
        )
    };

    let (err, summary, records) = batch("warned", &[]);
    let warning = "used as range for want of --focal or --fov";
    assert_eq!(err.matches(warning).count(), 1, "{err}");
    assert!(err.contains("a.png"), "the first frame is named: {err}");
    assert!(summary.contains("2 frames with warnings"), "{summary}");
    for r in &records {
        let warnings = r["warnings"].as_array().unwrap();
        assert!(
            warnings
                .iter()
                .any(|w| w.as_str().unwrap().contains("`focal` or `fov`")),
            "{r}"
        );
    }

    let (err, summary, records) = batch("with-fov", &["--fov", "40"]);
    assert!(!err.to_lowercase().contains("warn"), "{err}");
    assert!(!summary.contains("warnings"), "{summary}");
    assert!(records
        .iter()
        .all(|r| r["warnings"] == serde_json::json!([])));
}

#[test]
fn a_gtfine_label_image_gives_the_sky() {
    let dir = tempfile::tempdir().unwrap();
    let root = cityscapes_dataset(dir.path(), 1);
    // Cityscapes' labelIds: 23 is sky. The top 60 rows of the frame.
    let gt = root.join("gtFine/train/aachen");
    std::fs::create_dir_all(&gt).unwrap();
    let (w, h) = image::image_dimensions(
        root.join("leftImg8bit/train/aachen/aachen_000000_000019_leftImg8bit.png"),
    )
    .unwrap();
    image::GrayImage::from_fn(w, h, |_, y| image::Luma([if y < 60 { 23 } else { 7 }]))
        .save(gt.join("aachen_000000_000019_gtFine_labelIds.png"))
        .unwrap();
    let run = brume(
        dir.path(),
        &["batch", "cityscapes", "--out", "out", "--beta", "0.01"],
    );
    assert!(run.status.success(), "{}", stderr(&run));
    let log = std::fs::read_to_string(dir.path().join("out/brume-batch-1-of-1.jsonl")).unwrap();
    let record: serde_json::Value = serde_json::from_str(log.lines().next().unwrap()).unwrap();
    assert!(
        record["sky_mask"]
            .as_str()
            .unwrap()
            .ends_with("_gtFine_labelIds.png"),
        "{record}"
    );
    assert_eq!(record["airlight_source"], "sky", "{record}");
}

/// A gtFine labelIds hood (label 1, the ego vehicle) is never fogged by `brume batch`: its
/// pixels come out as they went in (no blur here) and its transmittance is 1 (before the
/// fix of 2026-12-02 the fog took the hood's range 0 as the farthest).
#[test]
fn a_gtfine_hood_is_never_fogged() {
    let dir = tempfile::tempdir().unwrap();
    let root = cityscapes_dataset(dir.path(), 1);
    let name = "aachen_000000_000019";
    let input = root.join(format!("leftImg8bit/train/aachen/{name}_leftImg8bit.png"));
    let (w, h) = image::image_dimensions(&input).unwrap();
    let hood = |x: u32, y: u32| y >= h - 40 && (w / 4..3 * w / 4).contains(&x);
    let gt = root.join("gtFine/train/aachen");
    std::fs::create_dir_all(&gt).unwrap();
    image::GrayImage::from_fn(w, h, |x, y| {
        image::Luma([match (hood(x, y), y < 30) {
            (true, _) => 1,
            (false, true) => 23,
            (false, false) => 7,
        }])
    })
    .save(gt.join(format!("{name}_gtFine_labelIds.png")))
    .unwrap();
    let args = ["batch", "cityscapes", "--out", "out", "--beta", "0.01"];
    let run = brume(
        dir.path(),
        &[&args[..], &["--transmittance", "--lambda", "0"]].concat(),
    );
    assert!(run.status.success(), "{}", stderr(&run));
    let out = dir.path().join("out/leftImg8bit/train/aachen");
    let before = image::open(&input).unwrap().to_rgb8();
    let after = image::open(out.join(format!("{name}_leftImg8bit_foggy_beta_0.01.png")))
        .unwrap()
        .to_rgb8();
    let tau = image::open(out.join(format!("{name}_leftImg8bit_transmittance_beta_0.01.png")))
        .unwrap()
        .to_luma8();
    let (mut hood_pixels, mut fogged) = (0, 0);
    for (x, y, p) in after.enumerate_pixels() {
        if hood(x, y) {
            assert_eq!(p, before.get_pixel(x, y), "hood pixel ({x}, {y})");
            assert_eq!(tau.get_pixel(x, y)[0], 255, "hood τ at ({x}, {y})");
            hood_pixels += 1;
        } else {
            fogged += usize::from(p != before.get_pixel(x, y));
        }
    }
    assert_eq!(hood_pixels, (h.min(40) * (3 * w / 4 - w / 4)) as usize);
    assert!(fogged > (w * h / 2) as usize, "only {fogged} pixels fogged");
}

/// `--no-prep` where the refinement needs the range filled (repair, the default for a
/// Cityscapes disparity, which has holes) fails each frame saying so in the flags' words,
/// writes nothing for it, and exits non-zero.
#[test]
fn no_prep_with_the_default_refinement_fails_each_frame_naming_the_flags() {
    let dir = tempfile::tempdir().unwrap();
    cityscapes_dataset(dir.path(), 2);
    let args = [
        "batch",
        "cityscapes",
        "--out",
        "out",
        "--beta",
        "0.01",
        "--no-prep",
    ];
    let run = brume(dir.path(), &args);
    let err = stderr(&run);
    assert!(!run.status.success(), "{err}");
    let said = "invalid --no-prep = given: expected pre-processing with the repair refinement";
    assert_eq!(err.matches(said).count(), 2, "{err}");
    assert!(err.contains("(or --refine none)"), "{err}");
    assert!(
        err.contains("2 frames and 0 outputs failed (0 outputs written)"),
        "{err}"
    );
    assert!(!dir.path().join("out/leftImg8bit").exists(), "{err}");
}

/// The transmittance maps hold τ = exp(−βR) of each pixel's range in metres, computed here
/// from the disparity file and the camera file alone: range = fx·B/d·|ray| with d = (p −
/// 1)/256 (they were black: the range in metres was read as normalised range).
#[test]
fn transmittance_maps_are_exp_of_minus_beta_times_range() {
    let dir = tempfile::tempdir().unwrap();
    let root = cityscapes_dataset(dir.path(), 1);
    let beta = 0.005;
    let run = brume(
        dir.path(),
        &[
            "batch",
            "cityscapes",
            "--out",
            "out",
            "--beta",
            "0.005",
            "--transmittance",
            "--no-prep",
            "--refine",
            "none",
        ],
    );
    assert!(run.status.success(), "{}", stderr(&run));
    let name = "aachen_000000_000019";
    let disparity = image::open(root.join(format!("disparity/train/aachen/{name}_disparity.png")))
        .unwrap()
        .to_luma16();
    let tau = image::open(dir.path().join(format!(
        "out/leftImg8bit/train/aachen/{name}_leftImg8bit_transmittance_beta_0.005.png"
    )))
    .unwrap()
    .to_luma8();
    assert_eq!(tau.dimensions(), disparity.dimensions());
    let camera: serde_json::Value = serde_json::from_str(CAMERA_JSON).unwrap();
    let (fx, fy) = (
        camera["intrinsic"]["fx"].as_f64().unwrap(),
        camera["intrinsic"]["fy"].as_f64().unwrap(),
    );
    let (u0, v0) = (
        camera["intrinsic"]["u0"].as_f64().unwrap(),
        camera["intrinsic"]["v0"].as_f64().unwrap(),
    );
    let baseline = camera["extrinsic"]["baseline"].as_f64().unwrap();
    let (mut checked, mut worst, mut sum) = (0usize, 0i32, 0.0f64);
    for (x, y, p) in disparity.enumerate_pixels() {
        if p[0] == 0 {
            continue; // unknown disparity
        }
        let d = (f64::from(p[0]) - 1.0) / 256.0;
        let (rx, ry) = ((f64::from(x) - u0) / fx, (f64::from(y) - v0) / fy);
        let range = fx * baseline / d * (1.0 + rx * rx + ry * ry).sqrt();
        let expected = (255.0 * (-beta * range).exp()).round() as i32;
        let got = i32::from(tau.get_pixel(x, y)[0]);
        worst = worst.max((got - expected).abs());
        sum += f64::from(got);
        checked += 1;
    }
    assert!(checked > 100_000, "{checked} pixels of known disparity");
    assert!(worst <= 1, "τ off by {worst} code values of 255");
    // Not black: the demo's range of 95-465 m at β = 0.005 gives τ from 0.62 to 0.10.
    assert!(
        sum / checked as f64 > 40.0,
        "mean τ {}",
        sum / checked as f64 / 255.0
    );
}

/// This machine's name as brume writes it into its temporaries' names.
fn host() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .unwrap_or_default()
        .trim()
        .chars()
        .filter(|c| c.is_ascii_alphanumeric() || *c == '.')
        .collect::<String>()
}

/// A batch killed with SIGKILL (no clean-up runs) has logged every output it finished,
/// each as soon as it was in place; the resumed run removes the temporaries the killed
/// one left, leaves those a live process elsewhere may still be writing, writes the rest
/// and says what it skipped; a closed stdout does not stop it.
#[cfg(unix)]
#[test]
fn a_killed_batch_has_logged_its_outputs_and_a_resumed_one_cleans_up() {
    use std::io::{BufRead, BufReader};
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    cityscapes_dataset(dir.path(), 2);
    let args = ["batch", "cityscapes", "--out", "out", "--beta", "0.01"];
    let log_path = dir.path().join("out/brume-batch-1-of-1.jsonl");
    {
        let _gl = common::gl_lock();
        let mut child = Command::new(env!("CARGO_BIN_EXE_brume"))
            .args(args)
            .current_dir(dir.path())
            // Each output waits 3 s staged: the kill lands in the second's wait.
            .env("BRUME_TEST_HOLD_OUTPUTS", "3")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut err = BufReader::new(child.stderr.take().unwrap());
        let mut holds = 0;
        let mut line = String::new();
        while holds < 2 {
            line.clear();
            assert!(err.read_line(&mut line).unwrap() > 0, "brume ended early");
            holds += usize::from(line.contains("holding 1 staged outputs"));
        }
        // The second output is staged: the first is in place and must be in the log.
        let log = std::fs::read_to_string(&log_path).unwrap();
        assert_eq!(log.lines().count(), 1, "{log}");
        assert!(
            log.contains("aachen_000000_000019") && log.contains("\"ok\""),
            "{log}"
        );
        child.kill().unwrap(); // SIGKILL
        child.wait().unwrap();
    }
    let folder = dir.path().join("out/leftImg8bit/train/bremen");
    let temporaries = |d: &Path| -> Vec<String> {
        std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with(".brume-"))
            .collect()
    };
    let left = temporaries(&folder);
    assert_eq!(left.len(), 1, "SIGKILL leaves the staged output: {left:?}");
    assert!(
        left[0].starts_with(&format!(".brume-{}-", host())),
        "{left:?}"
    );
    // One that a process on another machine sharing the folder may be writing now.
    let elsewhere = ".brume-othermachine.example-12345-AbCdEf.tmp";
    std::fs::write(folder.join(elsewhere), b"live elsewhere").unwrap();

    let resumed = {
        let _gl = common::gl_lock();
        let mut child = Command::new(env!("CARGO_BIN_EXE_brume"))
            .args(args)
            .current_dir(dir.path())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take()); // a reader that went away: `brume batch | head -c 0`
        child.wait_with_output().unwrap()
    };
    let err = stderr(&resumed);
    assert_eq!(resumed.status.code(), Some(0), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains("removed 1 temporary files"), "{err}");
    assert_eq!(temporaries(&folder), [elsewhere]);
    let names: Vec<String> = outputs(&dir.path().join("out")).into_keys().collect();
    assert_eq!(names.len(), 2, "{names:?}");
    let log = std::fs::read_to_string(&log_path).unwrap();
    assert_eq!(log.matches("\"ok\"").count(), 2, "{log}");
}

/// `brume render` of a Cityscapes frame refines with `repair` unless told otherwise, and
/// says which mode ran; a Float range gets none by default.
#[test]
fn cityscapes_disparity_is_repaired_by_default() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("cityscapes");
    cityscapes_frame(&root, "aachen", "aachen_000000_000019");
    let image = root.join("leftImg8bit/train/aachen/aachen_000000_000019_leftImg8bit.png");
    let depth = root.join("disparity/train/aachen/aachen_000000_000019_disparity.png");
    let mode = |extra: &[&str]| {
        let mut args = vec![
            "render",
            "--image",
            image.to_str().unwrap(),
            "--depth",
            depth.to_str().unwrap(),
            "--beta",
            "0.02",
            "--lambda",
            "0",
            "--out",
            "o.png",
            "--json",
        ];
        args.extend(extra);
        let o = brume(dir.path(), &args);
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let mode = v["refine"]["mode"].as_str().unwrap().to_string();
        // The step's time: 0 where nothing ran (none, at the depth's own size).
        let ms = v["refine_ms"].as_f64().unwrap();
        assert_eq!(ms > 0.0, mode != "none", "{mode}: refine_ms {ms}");
        // The depth edges are moved by `repair` alone.
        let edges = v["refine"]["edges"].as_bool().unwrap();
        assert_eq!(edges, mode == "repair", "{mode}");
        mode
    };
    assert_eq!(mode(&[]), "repair");
    assert_eq!(mode(&["--refine", "none"]), "none");
}

/// The library's per-frame loop (what `brume batch` runs: one upload, every β) gives, per
/// β, the image of a render of its own (`photo::fog`), and Foggy Cityscapes' conventions
/// give the blend in code values computed here by hand.
#[test]
fn the_library_frame_loop_fogs_each_beta_as_a_render_of_its_own() {
    use brume::photo::{self, Conventions, Frame, FrameOptions};
    let dir = tempfile::tempdir().unwrap();
    let root = cityscapes_dataset(dir.path(), 1);
    let item = brume::dataset::find_cityscapes(&root)
        .unwrap()
        .remove(0)
        .unwrap();
    let (_lock, mut headless) = common::renderer();
    let betas = [0.005, 0.02];
    let mut opts = FrameOptions::default();
    let mut frame = Frame::load(&item, &opts).unwrap();
    frame.refine(&opts, headless.renderer().unwrap()).unwrap();
    let mut fogged = Vec::new();
    frame
        .fog_each(headless.renderer().unwrap(), &opts, &betas, |beta, f| {
            fogged.push((beta, f));
            Ok(())
        })
        .unwrap();
    assert_eq!(fogged.len(), 2);
    for (beta, f) in &fogged {
        let fog = opts.fog_at(*beta).unwrap();
        let alone = photo::fog(
            headless.renderer().unwrap(),
            &frame.photo,
            &frame.prepared,
            &fog,
        )
        .unwrap();
        assert!(f.passes > 0, "β {beta}: no diffusion passes");
        assert!(
            f.image.as_slice() == alone.rendered.image.as_slice(),
            "β {beta}: the frame loop and a render of its own differ"
        );
    }
    assert!(fogged[0].1.image.as_slice() != fogged[1].1.image.as_slice());

    // Foggy Cityscapes: c' = c·τ + A·(1 − τ) in sRGB code values, τ = exp(−βR).
    opts.conventions = Conventions::FoggyCityscapes;
    opts.prepare.airlight = Some([0.5, 0.6, 0.7]);
    let metres = frame.metres().unwrap().clone();
    let beta = 0.01;
    frame
        .fog_each(headless.renderer().unwrap(), &opts, &[beta], |_, f| {
            assert_eq!(f.passes, 0);
            let encode = |v: f32| brume::io::image::linear_to_srgb(v.clamp(0.0, 1.0));
            for (i, (out, src)) in f
                .image
                .as_slice()
                .iter()
                .zip(frame.photo.image.as_slice())
                .enumerate()
                .step_by(997)
            {
                let tau = (-beta * f64::from(metres.as_slice()[i])).exp() as f32;
                for c in 0..3 {
                    let want = encode(src[c]) * tau + encode([0.5, 0.6, 0.7][c]) * (1.0 - tau);
                    assert!(
                        (encode(out[c]) - want).abs() < 1e-4,
                        "pixel {i} channel {c}"
                    );
                }
            }
            Ok(())
        })
        .unwrap();
}

/// The library's batch (`brume::dataset::Batch`), with no command line: it plans a
/// dataset's outputs, tells its observer of each as it is in place, logs each, reports
/// what it did, and a second plan of the same batch finds nothing left to write. Bad
/// options are refused by their library names before anything is made.
#[test]
fn the_library_batch_writes_logs_and_reports_each_output() {
    use brume::dataset::{Batch, BatchEvent, BatchOptions, Betas};
    use std::sync::Mutex;
    let dir = tempfile::tempdir().unwrap();
    let root = cityscapes_dataset(dir.path(), 2);
    let out = dir.path().join("foggy");
    let mut opts = BatchOptions::new(out.clone());
    opts.betas = Betas::Each(vec![0.01, 0.02]);
    opts.frame.fog.lambda = 0.0; // the blur is the other tests' concern
    let refused = |betas: Betas, name: &str| {
        let opts = BatchOptions {
            betas,
            ..opts.clone()
        };
        match Batch::plan(std::slice::from_ref(&root), None, opts) {
            Err(brume::Error::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
            other => panic!("{name}: {:?}", other.map(|b| b.outputs())),
        }
        assert!(!out.exists(), "{name}: the output folder was made");
    };
    refused(Betas::Each(vec![0.01, 0.01]), "beta");
    refused(Betas::Each(vec![1e-300]), "beta");
    refused(
        Betas::Drawn("uniform:0.001,20".parse().unwrap()),
        "beta_dist",
    );
    let with_loaders = |loaders| BatchOptions {
        loaders,
        ..opts.clone()
    };
    let with_writers = |writers| BatchOptions {
        writers,
        ..opts.clone()
    };
    let threads = [0, brume::dataset::MAX_LOADERS + 1]
        .map(|n| ("loaders", n, with_loaders(n)))
        .into_iter()
        .chain([0, brume::dataset::MAX_WRITERS + 1].map(|n| ("writers", n, with_writers(n))));
    for (field, n, opts) in threads {
        match Batch::plan(std::slice::from_ref(&root), None, opts) {
            Err(brume::Error::InvalidParameter { name, .. }) => assert_eq!(name, field),
            other => panic!("{n} {field}: {:?}", other.map(|b| b.outputs())),
        }
    }

    let batch = Batch::plan(std::slice::from_ref(&root), None, opts.clone()).unwrap();
    assert_eq!(
        (batch.frames_found(), batch.outputs(), batch.skipped()),
        (2, 4, 0)
    );
    let written = Mutex::new(Vec::new());
    let report = {
        let (_lock, mut headless) = common::renderer();
        batch
            .run(headless.renderer().unwrap(), &|event| match event {
                BatchEvent::Written { output } => {
                    assert!(output.is_file(), "{} is not in place", output.display());
                    written.lock().unwrap().push(output.to_path_buf());
                }
                BatchEvent::Staged { .. } => {}
                other => panic!("{other:?}"),
            })
            .unwrap()
    };
    report.check().unwrap();
    let written = written.into_inner().unwrap();
    assert_eq!((report.written, report.frames, written.len()), (4, 2, 4));
    assert_eq!(outputs(&out).len(), 4);
    let log = std::fs::read_to_string(&report.log).unwrap();
    for path in &written {
        let line = log.lines().find(|l| l.contains(&*path.to_string_lossy()));
        assert!(line.is_some_and(|l| l.contains("\"ok\"")), "{log}");
    }
    let again = Batch::plan(&[root], None, opts).unwrap();
    assert_eq!((again.outputs(), again.skipped()), (0, 4));
}

/// A manifest of phone portraits needs no depth column: each JPEG is its own depth file
/// (an iPhone's here, stored turned with EXIF Orientation 6), and each output is the bytes
/// `brume render --image` writes from the JPEG alone.
#[test]
fn a_manifest_of_portrait_jpegs_reads_each_ones_own_depth() {
    let dir = tempfile::tempdir().unwrap();
    let portrait = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/apple/portrait-rot6.jpg");
    std::fs::copy(&portrait, dir.path().join("p.jpg")).unwrap();
    std::fs::write(dir.path().join("phone.csv"), "image\np.jpg\n").unwrap();
    let batch = [
        "batch",
        "--manifest",
        "phone.csv",
        "--out",
        "out",
        "--beta",
        "0.3",
    ];
    let run = brume(dir.path(), &batch);
    assert!(run.status.success(), "{}", stderr(&run));
    let render = [
        "render",
        "--image",
        "p.jpg",
        "--beta",
        "0.3",
        "--out",
        "render.png",
    ];
    let render = brume(dir.path(), &render);
    assert!(render.status.success(), "{}", stderr(&render));
    assert!(
        std::fs::read(dir.path().join("out/p_foggy_beta_0.3.png")).unwrap()
            == std::fs::read(dir.path().join("render.png")).unwrap(),
        "batch and render differ"
    );
}

/// The writers by default: a quarter of the cores (1 to 4), and at least two when the
/// camera model draws noise or makes a JPEG round trip, which costs more an output than
/// the GPU's passes.
#[test]
fn the_camera_model_gets_two_writers_by_default() {
    use brume::dataset::default_writers;
    use brume::photo::CaptureOptions;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let plain = default_writers(&CaptureOptions::default());
    assert_eq!(plain, (cores / 4).clamp(1, 4));
    assert_eq!(plain, brume::dataset::default_loaders());
    let exposure = CaptureOptions::from_parts(-0.5, None, None, None, 0).unwrap();
    assert_eq!(
        default_writers(&exposure),
        plain,
        "exposure alone costs nothing"
    );
    for costly in [
        CaptureOptions::from_parts(0.0, Some(0.0005), None, None, 0).unwrap(),
        CaptureOptions::from_parts(0.0, None, None, Some(85), 0).unwrap(),
    ] {
        assert_eq!(
            default_writers(&costly),
            plain.max(cores.min(2)),
            "{costly:?}"
        );
    }
}
