//! `brume batch` end to end on datasets the tests write: outputs named as Foggy
//! Cityscapes names them, the same pixels as `brume render` with the same options, runs
//! that resume, shards that split the work with no overlap, and a bad frame that is
//! reported and skipped while the others are written.

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn brume(dir: &Path, args: &[&str]) -> Output {
    let _gl = common::gl_lock();
    Command::new(env!("CARGO_BIN_EXE_brume"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("brume runs")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A manifest dataset of `n` frames (the demo's Aloe under different names, in two
/// folders) under `dir/data`.
fn manifest_dataset(dir: &Path, n: usize) -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/demo");
    let data = dir.join("data");
    let mut csv = String::from("image,depth\n");
    for k in 0..n {
        let folder = if k % 2 == 0 { "city_a" } else { "city_b" };
        std::fs::create_dir_all(data.join(folder)).unwrap();
        let image = format!("{folder}/frame{k}.jpg");
        let depth = format!("{folder}/frame{k}_disparity.png");
        std::fs::copy(root.join("aloe-left-half.jpg"), data.join(&image)).unwrap();
        std::fs::copy(root.join("aloe-disparity-half.png"), data.join(&depth)).unwrap();
        csv.push_str(&format!("{image},{depth}\n"));
    }
    let manifest = data.join("frames.csv");
    std::fs::write(&manifest, csv).unwrap();
    manifest
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
    manifest_dataset(dir.path(), 2);
    let run = |extra: &[&str]| {
        let mut args = vec![
            "batch",
            "--manifest",
            "data/frames.csv",
            "--out",
            "out",
            "--beta",
            "0.01,0.02",
        ];
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
            "city_a/frame0_foggy_beta_0.01.png",
            "city_a/frame0_foggy_beta_0.02.png",
            "city_a/frame0_transmittance_beta_0.01.png",
            "city_a/frame0_transmittance_beta_0.02.png",
            "city_b/frame1_foggy_beta_0.01.png",
            "city_b/frame1_foggy_beta_0.02.png",
            "city_b/frame1_transmittance_beta_0.01.png",
            "city_b/frame1_transmittance_beta_0.02.png",
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
        assert!(
            r["gpu_ms"].as_f64().unwrap() > 0.0 && r["decode_ms"].as_f64().is_some(),
            "{r}"
        );
    }

    // A second run finds everything complete: it writes nothing and changes nothing.
    let again = run(&["--transmittance"]);
    assert!(again.status.success(), "{}", stderr(&again));
    assert!(String::from_utf8_lossy(&again.stdout).contains("wrote 0 outputs"));
    assert_eq!(outputs(&dir.path().join("out")), written);

    // A lost output is written again, and only it.
    std::fs::remove_file(dir.path().join("out/city_b/frame1_foggy_beta_0.02.png")).unwrap();
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
fn shards_split_the_frames_with_no_overlap() {
    let dir = tempfile::tempdir().unwrap();
    manifest_dataset(dir.path(), 6);
    let mut seen = BTreeMap::new();
    for k in 1..=3 {
        let out = format!("out{k}");
        let shard = format!("{k}/3");
        let run = brume(
            dir.path(),
            &[
                "batch",
                "--manifest",
                "data/frames.csv",
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
    let manifest = manifest_dataset(dir.path(), 2);
    std::fs::write(
        dir.path().join("data/city_a/frame0_disparity.png"),
        b"not a png",
    )
    .unwrap();
    let run = brume(
        dir.path(),
        &[
            "batch",
            "--manifest",
            manifest.to_str().unwrap(),
            "--out",
            "out",
            "--beta",
            "0.01",
        ],
    );
    assert_eq!(run.status.code(), Some(1), "{}", stderr(&run));
    let err = stderr(&run);
    assert!(err.contains("frame0_disparity.png"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let names: Vec<String> = outputs(&dir.path().join("out")).into_keys().collect();
    assert_eq!(names, ["city_b/frame1_foggy_beta_0.01.png"]);
    let log = std::fs::read_to_string(dir.path().join("out/brume-batch-1-of-1.jsonl")).unwrap();
    assert!(
        log.contains("\"status\":\"failed\"") && log.contains("frame0"),
        "{log}"
    );
}

#[test]
fn bad_batch_options_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    manifest_dataset(dir.path(), 1);
    for (args, expect) in [
        (
            &[
                "batch",
                "--manifest",
                "data/frames.csv",
                "--out",
                "o",
                "--beta",
                "-0.01",
            ][..],
            "--beta",
        ),
        (
            &[
                "batch",
                "--manifest",
                "data/frames.csv",
                "--out",
                "o",
                "--beta",
                "0.01,x",
            ][..],
            "--beta",
        ),
        (
            &[
                "batch",
                "--manifest",
                "data/frames.csv",
                "--out",
                "o",
                "--shard",
                "4/3",
            ][..],
            "--shard",
        ),
        (&["batch", "--out", "o"][..], "no frames"),
        (&["batch", "nowhere", "--out", "o"][..], "nowhere"),
        (
            &["batch", "--manifest", "data/missing.csv", "--out", "o"][..],
            "missing.csv",
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
